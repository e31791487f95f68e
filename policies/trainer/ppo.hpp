// The PPO algorithm (rsl_rl's algorithms/ppo): the actor (a Gaussian policy: MLP mean,
// state-independent log-std) and the critic (an MLP value network on the critic's inputs), their
// Adam optimisers, the values and GAE returns of a rollout, and the clipped-surrogate update with
// the clip bound the clip schedule chose (clip_schedule.hpp) and the learning rate the
// learning-rate schedule sets (lr_schedule.hpp). Losses and gradients: ppo_loss.hpp.
//
// Deterministic: the same rollout and bound give bit-identical parameters for any thread and rank
// count, on every machine the build runs on (PinEigenBlocking).
#pragma once

#include <cstddef>
#include <vector>

#include "policies/trainer/adam.hpp"
#include "policies/trainer/collective.hpp"
#include "policies/trainer/mlp.hpp"
#include "policies/trainer/options.hpp"
#include "policies/trainer/ppo_loss.hpp"
#include "policies/trainer/rollout_storage.hpp"
#include "policies/trainer/worker_pool.hpp"
#include "runtime/core/random.hpp"

namespace pbppo::trainer {

// Means over the iteration's minibatches.
struct UpdateStats {
  double approx_kl = 0, clip_fraction = 0, explained_variance = 0, entropy = 0;
  double policy_loss = 0, value_loss = 0, grad_norm = 0, log_std_mean = 0;
  double kl = 0;  // the Gaussian KL divergence from the rollout's policy (SumGaussianKl), before each step
  double exchange_seconds = 0;  // ranks exchanging chunk gradients (and waiting for each other there)
};

// Eigen cuts a matrix product into blocks sized from the CPU's cache sizes, which it reads at run
// time, and a product that sums over more than about 256 columns (the weight gradient of a
// minibatch chunk of 768 samples, for example) then adds in another order on a CPU with another L1
// size: the same build trained another policy on another machine. This pins Eigen's cache sizes
// to kEigenCacheSizes, the ones it read on the machine that trained the shipped policies, so that
// the blocking, and every sum, is the same everywhere. Ppo's constructor calls it.
inline constexpr std::ptrdiff_t kEigenCacheSizes[3] = {48 * 1024, 1024 * 1024, 384 * 1024 * 1024};
void PinEigenBlocking();

class Ppo {
 public:
  // Networks from the options' widths and activation, orthogonally initialised from the seed.
  Ppo(const TrainOptions& options, int obs_size, int value_input_size, int action_size);

  const GaussianPolicy<float>& actor() const noexcept { return actor_; }
  const float* actor_params() const noexcept { return actor_params_.data(); }
  float* actor_params() noexcept { return actor_params_.data(); }
  const float* log_std() const noexcept { return actor_params_.data() + actor_.log_std_offset(); }
  const Mlp<float>& critic() const noexcept { return critic_; }

  // The networks, optimisers, rate and minibatch generator (a resumed run's).
  void Save(ByteWriter& w) const;
  void Load(ByteReader& r);

  double learning_rate() const noexcept { return lr_; }
  void set_learning_rate(double lr) noexcept { lr_ = lr; }

  // V of every stored state (in fixed 256-column chunks: the same arithmetic for any thread count),
  // of the truncation and last inputs; then advantages and returns by GAE.
  void ComputeReturns(RolloutStorage& rollout, WorkerPool& pool) const;
  // The fraction of the returns' variance the values explain (NaN when the returns are constant).
  static double ExplainedVariance(const RolloutStorage& rollout);

  // `epochs` passes over the rollout in minibatches with clip bound `eps`. critic_only: the actor
  // is held (its loss is still computed for the log). With the adaptive learning-rate schedule
  // each minibatch's KL divergence sets the rate of its step (and of the steps after it).
  // With ranks (`group`), every rank calls it with the same rollout and gets the same parameters;
  // each computes its share of the chunks (below).
  UpdateStats Update(const RolloutStorage& rollout, double eps, bool critic_only, WorkerPool& pool,
                     const Collective* group = nullptr);

  // How the update divides a minibatch, whatever the thread count: minibatches of kChunkedFrom
  // samples or more in kChunks column chunks (chunks are the faster from about there:
  // pbppo_bench_trainer update), smaller ones in one; each chunk's gradient of the minibatch's mean
  // loss computed on its own per network, the chunks' gradients summed in chunk order, and the
  // squared gradient norm summed over Segments(chunks) parameter segments per network, in segment
  // order. The threads share the chunk and segment tasks (Update says how); the arithmetic is the
  // same for any share.
  static constexpr long kChunkedFrom = 2048;
  static constexpr int kChunks = 4;
  static constexpr int kSegments = 8;
  static int Chunks(long minibatch) noexcept { return minibatch >= kChunkedFrom ? kChunks : 1; }
  static int Segments(int chunks) noexcept { return chunks == 1 ? 1 : kSegments; }

 private:
  const TrainOptions& o_;
  GaussianPolicy<float> actor_;
  Mlp<float> critic_;
  // Eigen-aligned storage: vectorised code then sees the same alignment on every run.
  Vec<float> actor_params_, critic_params_, actor_grad_, critic_grad_;
  Adam<float> actor_adam_, critic_adam_;
  double lr_ = 0;
  Rng rng_;  // minibatch order
};

}  // namespace pbppo::trainer
