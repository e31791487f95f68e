#!/usr/bin/env bash
# The paper's fixed clip bounds at two budgets: fixed:0.02, fixed:0.15 and fixed:0.23 x 5 seeds on
# hopper, walker2d and half-cheetah, and on the ant with its contact forces left at zero (as the
# paper's software ran it), with the paper's PPO settings (tools/mujoco_table.sh). Each run trains
# STEPS=2e6 steps (the released script's default budget) and keeps SNAPSHOTS=2 snapshots (the first
# at 10^6 steps, the paper's table's budget); every snapshot is evaluated on 10 deterministic
# episodes as episodes end and through episode ends (the released script's way). Runs through
# `pbppo sweep` and caches every evaluation, so it resumes: nothing finished is done again. Writes
# REPORT (default docs/results/mujoco_budget.md) and its plots beside it.
#
# Usage: tools/mujoco_budget.sh [OUT_DIR=runs/mujoco_budget]
#   TASKS="hopper walker2d half-cheetah"   the tasks without contact forces
#   ANT=zero       the ant's contact forces: zero, computed, or none (no ant)
#   STEPS=2e6, SNAPSHOTS=2, SEEDS=1-5, JOBS=2, MPIRUN=..., PBPPO=...: as tools/mujoco_table.sh
# All of it: 60 runs, 11,349 CPU seconds of training (about 95 minutes on this 2-core machine), the
# ant half of it.
set -euo pipefail
source "$(dirname "$0")/common.sh"
out="${1:-$root/runs/mujoco_budget}"
pbppo="$(program PBPPO build/default/policies/pbppo)"
tasks="${TASKS-hopper walker2d half-cheetah}"
ant="${ANT:-zero}"
steps="${STEPS:-2e6}"
snapshots="${SNAPSHOTS:-2}"
seeds="${SEEDS:-1-5}"
report="${REPORT:-$root/docs/results/mujoco_budget.md}"
case "$ant" in zero | computed | none) ;; *) fail "ANT: '$ant' is not zero, computed or none" ;; esac
positive_int SNAPSHOTS "$snapshots"
read -r -a task_list <<< "$tasks"
for t in "${task_list[@]}"; do
  case "$t" in hopper | walker2d | half-cheetah) ;; *) fail "TASKS: '$t' is not hopper, walker2d or half-cheetah (the ant: ANT)" ;; esac
done
[ ${#task_list[@]} -gt 0 ] || [ "$ant" != none ] || fail "TASKS is empty and ANT=none: nothing to run"
sweep_launcher
paper_mujoco_settings "$steps"
settings+=(--snapshots "$snapshots")
bounds=(--grid "schedule=fixed:0.02,fixed:0.15,fixed:0.23" --seeds "$seeds" --jobs "$jobs" --final-episodes 10)
sweeps=()
if [ ${#task_list[@]} -gt 0 ]; then
  "${launcher[@]}" "$pbppo" sweep --out "$out/tasks" --grid "env=$(IFS=,; echo "${task_list[*]}")" "${bounds[@]}" \
    -- "${settings[@]}"
  sweeps+=("$out/tasks")
fi
if [ "$ant" != none ]; then
  "${launcher[@]}" "$pbppo" sweep --out "$out/ant_$ant" --grid env=ant --grid "contact-forces=$ant" "${bounds[@]}" \
    -- "${settings[@]}"
  sweeps+=("$out/ant_$ant")
fi
PBPPO="$pbppo" python3 "$root/tools/summarise_mujoco_budget.py" "${sweeps[@]}" "$report"
