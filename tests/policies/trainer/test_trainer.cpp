// The trainer end to end on Pendulum: determinism, real learning on a small budget, the files
// it writes (log, summary, blob + golden vectors that the runtime loads), and its errors.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "policies/envs/env.hpp"
#include "policies/trainer/ppo.hpp"
#include "policies/trainer/trainer.hpp"
#include "runtime/policy/blob.hpp"
#include "runtime/policy/policy_model.hpp"
#include "runtime/policy/reference.hpp"
#include "tests/support/test_paths.hpp"

namespace pbppo::trainer {
namespace {

TrainOptions Small() {
  return {.seed = 3, .total_steps = 4096, .num_envs = 4, .rollout_steps = 256, .minibatch = 64, .epochs = 3};
}

void CheckSameRun(const TrainResult& a, const TrainResult& b) {
  REQUIRE(a.spec.layers.size() == b.spec.layers.size());
  for (std::size_t l = 0; l < a.spec.layers.size(); ++l) {
    CHECK(a.spec.layers[l].weight == b.spec.layers[l].weight);
    CHECK(a.spec.layers[l].bias == b.spec.layers[l].bias);
  }
  CHECK(a.spec.obs_mean == b.spec.obs_mean);
  REQUIRE(a.iterations.size() == b.iterations.size());
  for (std::size_t i = 0; i < a.iterations.size(); ++i) {
    CHECK(a.iterations[i].approx_kl == b.iterations[i].approx_kl);
    CHECK(a.iterations[i].value_loss == b.iterations[i].value_loss);
  }
}

// One thread per environment makes each forward pass a matrix-vector product, several a matrix
// product, whose sums Eigen orders otherwise: the environments' blocks keep the shapes fixed.
// (Ranks: tests/policies/train_ranks.sh under mpirun.)
TEST_CASE("same seed and environments give a bit-identical run on any number of threads") {
  for (int envs : {2, 5}) {
    CAPTURE(envs);
    TrainOptions c = Small();
    c.num_envs = envs;
    c.rollout_steps = 1024 / envs;
    c.normalize_observations = true;
    c.scale_rewards = true;
    c.threads = 1;
    auto a = Train(c);
    REQUIRE(a.ok());
    for (int threads : {1, 2, 3}) {
      CAPTURE(threads);
      c.threads = threads;
      auto b = Train(c);
      REQUIRE(b.ok());
      CheckSameRun(*a, *b);
    }
    c.seed = 4;
    auto other = Train(c);
    REQUIRE(other.ok());
    CHECK(other->spec.layers[0].weight != a->spec.layers[0].weight);
  }
}

TEST_CASE("environments per block: N/16 within [1, 32]") {
  CHECK(BlockSize(1) == 1);
  CHECK(BlockSize(31) == 1);
  CHECK(BlockSize(32) == 2);
  CHECK(BlockSize(512) == 32);
  CHECK(BlockSize(4096) == 32);
}

// rl-zoo's Pendulum settings on a small budget.
TrainOptions RlZoo() {
  TrainOptions c;
  c.num_envs = 4;
  c.rollout_steps = 1024;
  c.gamma = 0.9;
  c.learning_rate = 1e-3;
  c.total_steps = 61440;
  c.seed = 1;
  return c;
}

TEST_CASE("PPO learns Pendulum on a small budget (rl-zoo settings, fixed seed)") {
  TrainOptions c = RlZoo();
  auto r = Train(c);
  REQUIRE(r.ok());
  const double first = r->iterations.front().train_return;
  MESSAGE("first rollout return " << first << ", last-100 return " << r->final_return);
  CHECK(first < -900);            // a random policy
  CHECK(r->final_return > -600);  // real progress, far above random
}

TEST_CASE("minibatches in chunks: PPO still learns Pendulum, deterministically") {
  // rl-zoo's settings on 8 environments, in minibatches of 2048 samples (4 chunks of 512): 4
  // minibatches per epoch, a larger rate and budget.
  TrainOptions c = RlZoo();
  c.num_envs = 8;
  c.minibatch = 2048;
  c.learning_rate = 3e-3;
  c.total_steps = 245760;
  c.threads = 2;
  REQUIRE(Ppo::Chunks(c.minibatch) == 4);
  auto a = Train(c), b = Train(c);
  REQUIRE(a.ok());
  REQUIRE(b.ok());
  MESSAGE("minibatches of 2048 in 4 chunks: last-100 return " << a->final_return);
  CHECK(a->final_return > -600);  // as with whole minibatches of 64 above
  for (std::size_t l = 0; l < a->spec.layers.size(); ++l) CHECK(a->spec.layers[l].weight == b->spec.layers[l].weight);
}

// A rollout of random observations and actions the actor sampled, with random advantages and
// returns, for the update alone.
RolloutStorage RandomRollout(const Ppo& ppo, int steps, int envs, int obs, int critic, int actions) {
  RolloutStorage r(steps, envs, obs, critic, actions);
  Rng rng(3);
  for (long i = 0; i < r.size(); ++i) {
    for (int j = 0; j < obs; ++j) r.obs(j, i) = static_cast<float>(rng.Normal());
    for (int j = 0; j < critic; ++j) r.critic_obs(j, i) = static_cast<float>(rng.Normal());
    for (int j = 0; j < actions; ++j) {
      r.action_mean(j, i) = static_cast<float>(0.1 * rng.Normal());
      r.actions(j, i) = r.action_mean(j, i) + static_cast<float>(rng.Normal());
    }
    const auto u = static_cast<std::size_t>(i);
    r.log_prob[u] = static_cast<float>(-actions * 1.4 + 0.3 * rng.Normal());
    r.advantages[u] = static_cast<float>(rng.Normal());
    r.returns[u] = static_cast<float>(rng.Normal());
    r.values[u] = static_cast<float>(rng.Normal());
  }
  std::copy(ppo.log_std(), ppo.log_std() + actions, r.log_std.begin());
  return r;
}

TEST_CASE("chunks of a minibatch: 4 from 2048 samples, else 1") {
  CHECK(Ppo::Chunks(2) == 1);
  CHECK(Ppo::Chunks(64) == 1);   // tools/mujoco_table.sh, tools/learn_pendulum.sh
  CHECK(Ppo::Chunks(512) == 1);  // tools/train_auv.sh
  CHECK(Ppo::Chunks(2047) == 1);
  CHECK(Ppo::Chunks(2048) == 4);
  CHECK(Ppo::Chunks(3072) == 4);  // tools/train_quadruped.sh
  CHECK(Ppo::Segments(1) == 1);
  CHECK(Ppo::Segments(4) == Ppo::kSegments);
}

TEST_CASE("the update: the same parameters for 1, 2 and 3 threads, minibatches in one chunk or in several") {
  // 6000 samples in minibatches of 64 (one chunk; the last minibatch of each epoch 48 samples), of
  // 2048 (4 chunks; 2048, 2048 and 1904 samples) and of 3072 (3072 and 2928), with the adaptive
  // rate, the entropy term and value clipping; and with the actor held (--critic-warmup).
  for (int minibatch : {64, 2048, 3072}) {
    for (bool critic_only : {false, true}) {
      CAPTURE(minibatch);
      CAPTURE(critic_only);
      TrainOptions o;
      o.policy_hidden = {64, 32};
      o.activation = policy::Activation::kElu;
      o.minibatch = minibatch;
      o.epochs = 2;
      o.clip_vf = 0.2;
      o.ent_coef = 0.01;
      o.lr_schedule = ParseLrSchedule("adaptive").value();
      std::vector<std::vector<float>> actor, critic_out;
      std::vector<double> lr, grad_norm, value_loss;
      for (int threads : {1, 2, 3}) {
        Ppo ppo(o, 10, 14, 4);
        RolloutStorage r = RandomRollout(ppo, 25, 240, 10, 14, 4);
        const std::vector<float> actor_before(ppo.actor_params(), ppo.actor_params() + ppo.actor().size());
        WorkerPool pool(threads);
        const UpdateStats st = ppo.Update(r, 0.2, critic_only, pool);
        CHECK(std::isfinite(st.value_loss));
        CHECK(st.grad_norm > 0);
        if (!critic_only) CHECK(st.kl > 0);
        actor.emplace_back(ppo.actor_params(), ppo.actor_params() + ppo.actor().size());
        CHECK((actor.back() == actor_before) == critic_only);
        ppo.ComputeReturns(r, pool);
        critic_out.emplace_back(r.values.begin(), r.values.end());
        lr.push_back(ppo.learning_rate());
        grad_norm.push_back(st.grad_norm);
        value_loss.push_back(st.value_loss);
      }
      CHECK((lr[0] == o.learning_rate) == critic_only);  // the adaptive rate waits for a held actor
      for (std::size_t k = 1; k < 3; ++k) {
        CAPTURE(k + 1);
        CHECK(actor[k] == actor[0]);
        CHECK(critic_out[k] == critic_out[0]);
        CHECK(lr[k] == lr[0]);
        CHECK(grad_norm[k] == grad_norm[0]);
        CHECK(value_loss[k] == value_loss[0]);
      }
    }
  }
}

TEST_CASE("the same parameters whatever cache sizes the CPU reports (Eigen's blocking is pinned)") {
  // The recipe's shape: minibatches of 3072 in chunks of 768 columns, so that each weight gradient
  // sums over 768 samples, where Eigen's blocking follows the L1 size. Each pass plays another CPU
  // (Eigen reads the sizes once; setCpuCacheSizes stands in for that read) before the trainer starts.
  TrainOptions o;
  o.policy_hidden = {128, 64, 32};
  o.activation = policy::Activation::kElu;
  o.minibatch = 3072;
  o.epochs = 1;
  const std::ptrdiff_t cpus[][3] = {
      {32 * 1024, 512 * 1024, 16 << 20}, {48 * 1024, 2 << 20, 32 << 20}, {32 * 1024, 1 << 20, 32 << 20}};
  std::vector<std::vector<float>> actor;
  for (const auto& c : cpus) {
    Eigen::setCpuCacheSizes(c[0], c[1], c[2]);
    Ppo ppo(o, 48, 48, 12);
    std::ptrdiff_t l1 = 0, l2 = 0, l3 = 0;
    Eigen::internal::manage_caching_sizes(Eigen::GetAction, &l1, &l2, &l3);
    CHECK(l1 == kEigenCacheSizes[0]);
    CHECK(l2 == kEigenCacheSizes[1]);
    CHECK(l3 == kEigenCacheSizes[2]);
    RolloutStorage r = RandomRollout(ppo, 24, 128, 48, 48, 12);  // one minibatch of 3072
    WorkerPool pool(2);
    ppo.Update(r, 0.2, false, pool);
    actor.emplace_back(ppo.actor_params(), ppo.actor_params() + ppo.actor().size());
  }
  CHECK(actor[1] == actor[0]);
  CHECK(actor[2] == actor[0]);
}

TEST_CASE("--lr-schedule adaptive: the KL divergence steers the learning rate within [1e-5, 1e-2], logged") {
  auto run = [](double desired_kl) {
    TrainOptions c = RlZoo();
    c.total_steps = 16384;
    c.lr_schedule = ParseLrSchedule("adaptive:" + std::to_string(desired_kl)).value();
    auto r = Train(c);
    REQUIRE(r.ok());
    return std::move(r).value();
  };
  // Tiny KL target: the rate falls from 1e-3; generous target: it rises to the ceiling.
  const TrainResult small = run(1e-5), large = run(0.5);
  for (const auto* r : {&small, &large})
    for (const auto& it : r->iterations) {
      CHECK(it.learning_rate >= 1e-5);
      CHECK(it.learning_rate <= 1e-2);
      CHECK(it.kl >= 0);
    }
  CHECK(small.iterations.back().learning_rate < 1e-4);
  CHECK(large.iterations.back().learning_rate == doctest::Approx(1e-2));
  MESSAGE("late KL: target 1e-5 -> " << small.iterations.back().kl << ", target 0.5 -> " << large.iterations.back().kl);
  CHECK(small.iterations.back().kl < large.iterations.back().kl);
  // A constant schedule logs its rate unchanged.
  TrainOptions c = RlZoo();
  c.total_steps = 8192;
  auto constant = Train(c);
  REQUIRE(constant.ok());
  for (const auto& it : constant->iterations) CHECK(it.learning_rate == 1e-3);
}

TEST_CASE("a bandit run writes the log, summary, blob and golden vectors - the runtime loads the blob") {
  const std::string out = test::ScratchDir("trainer_files") + "/run";
  TrainOptions c = Small();
  c.schedule = ParseSchedule("pbppo", {0.1, 0.2, 0.3}).value();
  c.schedule.eval_episodes = 2;
  c.normalize_observations = true;
  c.out_dir = out;
  c.plots = false;
  auto r = Train(c);
  REQUIRE_MESSAGE(r.ok(), (r.ok() ? "" : r.error().message));
  // Evaluation steps are counted: 2 episodes of 200 steps before the first update and after each.
  CHECK(r->eval_steps == 2u * 200u * (r->iterations.size() + 1));
  CHECK(r->env_steps == 4096u);
  CHECK(r->freeze_check <= 1.0);

  std::ifstream csv(out + "/log.csv");
  std::string header, line;
  std::getline(csv, header);
  CHECK(header.find("epsilon") != std::string::npos);
  CHECK(header.find("arm2_bonus") != std::string::npos);
  CHECK(header.find("explained_variance") != std::string::npos);
  int rows = 0;
  while (std::getline(csv, line)) ++rows;
  CHECK(rows == static_cast<int>(r->iterations.size()));

  std::ifstream js(out + "/summary.json");
  const auto j = nlohmann::json::parse(js);
  CHECK(j["total_env_steps"].get<std::uint64_t>() == r->env_steps + r->eval_steps);
  CHECK(j["arm_pulls"].size() == 3);

  auto spec = policy::ReadBlobFile(out + "/policy.blob");
  REQUIRE(spec.ok());
  CHECK(spec->provenance.environment == "pendulum");
  CHECK(spec->provenance.seed == 3);
  CHECK(spec->provenance.env_steps == 4096u);
  CHECK(spec->provenance.clip_schedule.rfind("pbppo ", 0) == 0);
  CHECK(spec->action_low == std::vector<float>{-2.f});
  CHECK(spec->obs_clip == 10.f);
  CHECK(spec->obs_mean != std::vector<float>(3, 0.f));
  auto env = envs::MakeEnv(envs::EnvOptions{});
  REQUIRE(env.ok());
  CHECK(robot::CheckPolicyMatchesLayout(spec.value(), (*env)->layout()).ok());
  CHECK(std::filesystem::exists(out + "/policy.golden"));

  // The runtime forward gives the trainer's deterministic action (the Gaussian mean).
  auto model = policy::PolicyModel::FromFile(out + "/policy.blob");
  REQUIRE(model.ok());
  auto data = policy::MakePolicyData(model.value());
  REQUIRE(data.ok());
  const float obs[3] = {0.3f, -0.95f, 1.5f};
  std::copy(obs, obs + 3, data->observation().begin());
  REQUIRE(policy::Forward(model.value(), data.value()) == policy::ForwardStatus::kOk);
  const auto ref = policy::ReferenceForward(spec.value(), obs);
  CHECK(std::fabs(data->action()[0] - ref.action[0]) <= ref.error_bound[0] + 1e-6);
}

TEST_CASE("--snapshots N writes N blobs spread over the run, the last one the final policy") {
  const std::string out = test::ScratchDir("trainer_snapshots") + "/run";
  TrainOptions c = Small();  // 4 iterations of 1024 steps
  c.snapshots = 2;
  c.out_dir = out;
  c.plots = false;
  auto r = Train(c);
  REQUIRE_MESSAGE(r.ok(), (r.ok() ? "" : r.error().message));
  std::vector<std::string> names;
  for (const auto& e : std::filesystem::directory_iterator(out + "/snapshots")) names.push_back(e.path().filename());
  std::sort(names.begin(), names.end());
  CHECK(names == std::vector<std::string>{"000000002048.blob", "000000002048.golden", "000000004096.blob",
                                          "000000004096.golden"});
  auto mid = policy::ReadBlobFile(out + "/snapshots/000000002048.blob");
  auto last = policy::ReadBlobFile(out + "/snapshots/000000004096.blob");
  auto final_blob = policy::ReadBlobFile(out + "/policy.blob");
  REQUIRE(mid.ok());
  REQUIRE(last.ok());
  REQUIRE(final_blob.ok());
  CHECK(mid->provenance.env_steps == 2048u);
  const float obs[3] = {0.3f, -0.95f, 1.5f};
  CHECK(policy::ReferenceForward(last.value(), obs).action == policy::ReferenceForward(final_blob.value(), obs).action);
  CHECK(policy::ReferenceForward(mid.value(), obs).action != policy::ReferenceForward(last.value(), obs).action);
  std::ifstream js(out + "/summary.json");
  CHECK(nlohmann::json::parse(js)["snapshots"] == 2);
  c.snapshots = 1001;
  auto bad = Train(c);
  REQUIRE_FALSE(bad.ok());
  CHECK(bad.error().message.find("--snapshots: 1001 is not in [0, 1000]") != std::string::npos);
}

TEST_CASE("trainer errors name the field and value") {
  TrainOptions c = Small();
  c.env.name = "cartpole";
  CHECK(Train(c).error().message.find("'cartpole' unknown") != std::string::npos);
  c = Small();
  c.num_envs = 0;
  CHECK(Train(c).error().message.find("--envs: 0") != std::string::npos);
  c = Small();
  c.schedule.arms = {1.5};
  CHECK(Train(c).error().message.find("1.5") != std::string::npos);
  c = Small();
  c.env.flags["progress"] = "geodesic";  // Small() is pendulum
  CHECK(Train(c).error().message.find("--progress: only auv-nav has a progress term to choose, not 'pendulum'") !=
        std::string::npos);
  c.env.name = "auv-nav";
  c.env.flags["progress"] = "crow-flies";
  CHECK(Train(c).error().message.find("--progress: 'crow-flies': unknown (euclidean, geodesic, or LAYOUT=MODE,...)") !=
        std::string::npos);
  c.env.flags["progress"] = "hard=crow-flies";
  CHECK(Train(c).error().message.find("--progress: 'hard=crow-flies': 'crow-flies' for hard is not euclidean or "
                                      "geodesic") != std::string::npos);
  c.env.flags.erase("progress");
  c.env.flags["geodesic-margin"] = "2:four";
  CHECK(Train(c).error().message.find("--geodesic-margin: '2:four': cost 'four' is not a number in [0, 100]") !=
        std::string::npos);
  c = Small();
  c.env.flags["geodesic-margin"] = "2:4";  // pendulum
  CHECK(Train(c).error().message.find("--geodesic-margin: only auv-nav has one, not 'pendulum'") != std::string::npos);
  c.env.flags.erase("geodesic-margin");
  c.env.flags["clearance-penalty"] = "1.5:1";  // pendulum
  CHECK(Train(c).error().message.find("--clearance-penalty: only auv-nav has one, not 'pendulum'") !=
        std::string::npos);
  c.env.flags.erase("clearance-penalty");
  c.env.flags["extra-obstacles"] = "2";  // pendulum
  CHECK(Train(c).error().message.find("--extra-obstacles: only auv-nav has obstacles, not 'pendulum'") !=
        std::string::npos);
  c.env.flags.erase("extra-obstacles");
  c.env.name = "auv-nav";
  c.env.flags["clearance-penalty"] = "1.5:1:2";
  CHECK(Train(c).error().message.find("--clearance-penalty: '1.5:1:2': per-step cost '1:2' is not a number in "
                                      "[0, 100]") != std::string::npos);
  c = Small();
  const std::string dir = test::ScratchDir("trainer_unwritable");
  std::ofstream(dir + "/file") << "x";
  c.out_dir = dir + "/file/run";
  auto r = Train(c);
  REQUIRE_FALSE(r.ok());
  CHECK(r.error().message.find("--out") != std::string::npos);
}

TEST_CASE("a stop request ends the run cleanly with a blob") {
  const std::string out = test::ScratchDir("trainer_stop") + "/run";
  std::atomic<bool> stop{true};
  TrainOptions c = Small();
  c.out_dir = out;
  c.plots = false;
  c.stop = &stop;
  auto r = Train(c);
  REQUIRE(r.ok());
  CHECK(r->interrupted);
  CHECK(r->iterations.size() == 1);
  CHECK(policy::ReadBlobFile(out + "/policy.blob").ok());
}

TEST_CASE("--init starts from a trained blob's policy and normaliser, mismatches are refused") {
  const std::string dir = test::ScratchDir("trainer_init");
  // A learned Pendulum policy (rl-zoo settings as above), with a running normaliser.
  TrainOptions a = RlZoo();
  a.normalize_observations = true;
  auto ra = Train(a);
  REQUIRE(ra.ok());
  MESSAGE("trained last-100 return " << ra->final_return);
  REQUIRE(ra->final_return > -750);
  const std::string blob = dir + "/a.blob";
  REQUIRE(policy::WriteBlobFile(blob, ra->spec).ok());

  // Warm start with a learning rate too small to move anything: the first rollout is already
  // the learned policy's (a random one scores below -900), and the frozen result is the blob.
  TrainOptions b = Small();
  b.seed = 9;
  b.learning_rate = 1e-12;
  b.total_steps = 1024;
  b.init_blob = blob;
  b.log_std_init = -2.0;
  auto rb = Train(b);
  REQUIRE(rb.ok());
  MESSAGE("warm-started first rollout return " << rb->iterations.front().train_return);
  CHECK(rb->iterations.front().train_return > -700);
  REQUIRE(rb->spec.layers.size() == ra->spec.layers.size());
  float worst = 0;
  for (std::size_t l = 0; l < ra->spec.layers.size(); ++l) {
    for (std::size_t i = 0; i < ra->spec.layers[l].weight.size(); ++i)
      worst = std::max(worst, std::abs(rb->spec.layers[l].weight[i] - ra->spec.layers[l].weight[i]));
    for (std::size_t i = 0; i < ra->spec.layers[l].bias.size(); ++i)
      worst = std::max(worst, std::abs(rb->spec.layers[l].bias[i] - ra->spec.layers[l].bias[i]));
  }
  CHECK(worst < 1e-6f);
  CHECK(rb->spec.obs_mean == ra->spec.obs_mean);
  CHECK(rb->spec.obs_inv_std == ra->spec.obs_inv_std);

  // --critic-warmup: at a real learning rate the policy stays the blob's while only the value
  // network learns, and moves from the first iteration after the warm-up.
  auto largest_change = [&](const policy::PolicySpec& spec) {
    float d = 0;
    for (std::size_t l = 0; l < ra->spec.layers.size(); ++l)
      for (std::size_t i = 0; i < ra->spec.layers[l].weight.size(); ++i)
        d = std::max(d, std::abs(spec.layers[l].weight[i] - ra->spec.layers[l].weight[i]));
    return d;
  };
  TrainOptions w = Small();  // 1024 steps per iteration
  w.total_steps = 2048;
  w.init_blob = blob;
  w.critic_warmup = 2;
  auto held = Train(w);
  REQUIRE(held.ok());
  CHECK(largest_change(held->spec) == 0.0f);
  CHECK(held->iterations.back().value_loss < held->iterations.front().value_loss);
  // With the KL-adaptive rate the held policy's KL is 0: the rate waits for the policy's first
  // step instead of rising to its ceiling (1e-2) during the warm-up and wrecking that step.
  TrainOptions wa = w;
  wa.lr_schedule = ParseLrSchedule("adaptive:0.01").value();
  auto held_adaptive = Train(wa);
  REQUIRE(held_adaptive.ok());
  for (const auto& it : held_adaptive->iterations) CHECK(it.learning_rate == wa.learning_rate);
  w.critic_warmup = 1;
  auto moved = Train(w);
  REQUIRE(moved.ok());
  CHECK(largest_change(moved->spec) > 1e-4f);
  w.init_blob = "";
  auto no_init = Train(w);
  REQUIRE_FALSE(no_init.ok());
  CHECK(no_init.error().message.find("--critic-warmup: needs --init") != std::string::npos);

  auto error_of = [&](TrainOptions c) {
    auto r = Train(c);
    REQUIRE_FALSE(r.ok());
    return r.error().message;
  };
  TrainOptions c = b;
  c.policy_hidden = {32};
  CHECK(error_of(c).find("--init: '" + blob + "' has 3 layers, --hidden gives 2") != std::string::npos);
  c = b;
  c.policy_hidden = {64, 32};
  CHECK(error_of(c).find("layer 1 is 64x64, --hidden gives 64x32") != std::string::npos);
  c = b;
  c.activation = policy::Activation::kElu;
  CHECK(error_of(c).find("layer 0 has activation tanh") != std::string::npos);
  c = b;
  c.normalize_observations = true;
  CHECK(error_of(c).find("--init:") != std::string::npos);
  c = b;
  c.init_blob = dir + "/missing.blob";
  CHECK(error_of(c).find("--init: " + dir + "/missing.blob") != std::string::npos);
  c = b;
  c.init_blob = test::SourcePath("policies/frozen/auv_nav/auv_nav.blob");
  CHECK(error_of(c).find("does not fit robot layout 'pendulum': the policy takes 24 observations") !=
        std::string::npos);
}

}  // namespace
}  // namespace pbppo::trainer
