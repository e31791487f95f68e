// From the trainer's actor to a frozen policy blob and back: the blob (the actor's mean network,
// its observation normaliser, the IO layout's action map and names), its golden vectors, and its
// provenance (trainer version, the git revision the build was configured from, environment, clip
// schedule, seed, steps, return); an --init blob loaded into the actor; and the check that the
// blob acts as the trainer does.
#pragma once

#include <cstdint>
#include <string>

#include "policies/envs/env.hpp"
#include "policies/trainer/normalizer.hpp"
#include "policies/trainer/ppo_loss.hpp"
#include "runtime/core/result.hpp"
#include "runtime/policy/policy_spec.hpp"

namespace pbppo::trainer {

// The git revision of the source tree when the build was configured (12 hex digits), "unknown"
// outside a git checkout.
const char* BuildGitRevision() noexcept;

// What the blob's provenance says beyond the build.
struct ProvenanceInfo {
  std::string clip_schedule;  // the schedule described (at most 200 characters are kept)
  std::uint64_t seed = 0;
  std::uint64_t env_steps = 0;
  double final_return = 0;
};

// The actor's deterministic policy (the Gaussian mean) as a blob for `env`'s IO layout.
policy::PolicySpec FreezeActor(const GaussianPolicy<float>& actor, const float* params,
                               const ObservationNormalizer& normalizer, const envs::Env& env,
                               const ProvenanceInfo& info);

// The blob and its golden vectors (32 rows from `seed`) beside it, written together
// (policy::WritePolicyFiles).
Status WritePolicy(const std::string& path, const policy::PolicySpec& spec, std::uint64_t seed);

// --init: the blob's network into the actor's mean parameters and its normaliser into
// `normalizer`; the blob must fit `env`'s layout and the actor's widths and activations (errors
// name --init, the file and the difference).
Status LoadActor(const std::string& path, const envs::Env& env, const GaussianPolicy<float>& actor, float* params,
                 ObservationNormalizer* normalizer);

// max |trainer's deterministic command - blob reference forward| over 16 of the `count` raw
// observations (sample-major), in units of the reference's own error bound: <= 1 when the blob
// acts like the trainer.
double CheckFrozen(const policy::PolicySpec& spec, const GaussianPolicy<float>& actor, const float* params,
                   const ObservationNormalizer& normalizer, const envs::Env& env, const float* raw_obs, long count);

}  // namespace pbppo::trainer
