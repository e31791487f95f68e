// The Pb-PPO trainer: PPO whose clip bound a clip schedule (a bandit fed by task return) chooses
// each iteration, on N environments stepped in parallel, ending in a frozen policy blob with golden
// vectors. The same seed and number of environments give a bit-identical run on any threads and
// ranks (runner.hpp), and a resumed run the same as one uninterrupted (checkpoint.hpp).
//
// Train(options) is the entry point. The parts, each its own file, read in this order:
//   options.hpp          TrainOptions: every option of a run in one struct (the command line's)
//   runner.hpp           the learning loop: rollouts on worker threads and ranks, evaluation,
//                        checkpoints (runner.cpp); its resumable state (runner_state.cpp)
//   collective.hpp       what the ranks of one run exchange
//   state_io.hpp         the state as bytes (the ranks' exchange, resume.bin: checkpoint.hpp)
//   rollout_storage.hpp  one iteration's rollout, time-major
//   ppo.hpp              the algorithm: actor and critic, values and GAE, the clipped update
//   ppo_loss.hpp         the losses and their hand-written gradients (mlp.hpp: the networks)
//   clip_schedule.hpp    what sets the clip bound (fixed, the paper's bandit, ours)
//   lr_schedule.hpp      what sets the learning rate (constant, anneal, KL-adaptive)
//   normalizer.hpp       observation normalisation (the actor's goes into the blob)
//   logger.hpp           log.csv, the progress figures, summary.json, the curves (report/)
//   exporter.hpp         the blob: freezing, golden vectors, provenance, --init
#pragma once

#include "policies/trainer/logger.hpp"
#include "policies/trainer/options.hpp"
#include "policies/trainer/runner.hpp"
