#!/usr/bin/env bash
# The paper's table on our trainer: hopper, walker2d, half-cheetah and ant (docs/mujoco_tasks.md),
# six clip schedules (fixed:0.02, fixed:0.15, fixed:0.23, pbppo-paper:wi-ad, pbppo-reference, pbppo;
# pbppo-reference is the released script's rule as it runs by default, wo-ad)
# x 5 seeds, 10^6 environment steps each with the paper's PPO settings (its released script's: one
# environment, 2048-step rollouts, minibatch 64, 10 epochs, lr 3e-4, 64-64 tanh, gamma 0.99,
# lambda 0.95; bandit arms 0.02:0.5:6 and 2 evaluation episodes per iteration, counted), every final
# policy evaluated on 10 deterministic episodes. Runs through `pbppo sweep`, so it resumes: a
# finished run is never repeated. Then writes docs/results/mujoco_table.md and its plots.
#
# Usage: tools/mujoco_table.sh [OUT_DIR=runs/mujoco_table]
#   JOBS=2         runs at once on this machine
#   MPIRUN="mpirun -np 16 --hostfile hosts"   run the sweep across machines instead (OUT_DIR on a
#                  folder every host shares; JOBS is then 1 per rank)
#   TASKS="hopper walker2d half-cheetah ant", SEEDS=1-5, STEPS=1e6, SCHEDULES="..." narrow or widen it
#   PBPPO=path/to/pbppo
# The whole table is 120 runs: about 14,000 CPU seconds, 2 hours on this 2-core machine (docs/results/README.md).
set -euo pipefail
source "$(dirname "$0")/common.sh"
out="${1:-$root/runs/mujoco_table}"
pbppo="$(program PBPPO build/default/policies/pbppo)"
tasks="${TASKS:-hopper walker2d half-cheetah ant}"
schedules="${SCHEDULES:-fixed:0.02 fixed:0.15 fixed:0.23 pbppo-paper:wi-ad pbppo-reference pbppo}"
seeds="${SEEDS:-1-5}"
steps="${STEPS:-1e6}"
sweep_launcher
paper_mujoco_settings "$steps"
"${launcher[@]}" "$pbppo" sweep --out "$out" --grid "env=${tasks// /,}" --grid "schedule=${schedules// /,}" \
  --seeds "$seeds" --jobs "$jobs" --final-episodes 10 -- "${settings[@]}"
python3 "$root/tools/summarise_mujoco_table.py" "$out" "$root/docs/results/mujoco_table.md"
