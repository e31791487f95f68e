#!/usr/bin/env bash
# Pb-PPO against PPO on quadruped-walk (flat terrain): our `pbppo` schedule (arms 0.1:0.3:5, rollout
# feedback: the mean return of the episodes finished in the next rollout, no extra environment
# steps) against fixed:0.2, 3 seeds each, equal environment steps and the shipped recipe's PPO
# settings (tools/train_quadruped.sh). After training, each policy takes the paper's test (50
# robots x 20 s, `pbppo eval --env quadruped-walk`) on seed 900001 (no training seed).
# Writes docs/results/quadruped_schedules.md (means over seeds with 95% t-intervals) and the
# training curves with bands (return, tracking errors). Finished runs are kept: the script resumes.
# Usage: tools/compare_quadruped_schedules.sh [OUT_DIR=runs/compare_quadruped]
#   (PBPPO=path/to/pbppo, STEPS=2e7, SEEDS="1 2 3", THREADS=2 may be set)
set -euo pipefail
source "$(dirname "$0")/common.sh"
out="${1:-$root/runs/compare_quadruped}"
pbppo="$(program PBPPO build/default/policies/pbppo)"
steps="${STEPS:-2e7}"
seeds="${SEEDS:-1 2 3}"
threads="${THREADS:-2}"
schedules=("fixed:0.2" "pbppo")
# The shipped recipe's settings (tools/train_quadruped.sh).
common=(--env quadruped-walk --terrain flat --arms 0.1:0.3:5 --feedback rollout --threads "$threads" --envs 512
  --rollout 24 --minibatch 3072 --epochs 5 --lr 1e-3 --lr-schedule adaptive:0.01 --ent-coef 0.01 --vf-coef 1.0
  --clip-vf 0.2 --max-grad-norm 1.0 --hidden 128-64-32 --activation elu --steps "$steps" --no-plots)
train_and_eval() {
  local run="$1" schedule="$2" seed="$3"
  "$pbppo" train "${common[@]}" --schedule "$schedule" --seed "$seed" --quiet --out "$run" > "$run.txt" 2>&1
  # eval.json marks a finished run: written whole or not at all.
  "$pbppo" eval "$run/policy.blob" --env quadruped-walk --terrain flat --seed 900001 --json > "$run/eval.json.part"
  mv "$run/eval.json.part" "$run/eval.json"
  python3 -c 'import json,sys; e=json.load(open(sys.argv[1])); s=json.load(open(sys.argv[2])); m=e["mean_abs_error"]
print("  last-100 return %.1f; test: |error| vx %.3f vy %.3f yaw %.3f, falls %d/%d; %d steps in %.0f s" % (
 s["final_return_last100"], m["vx_mps"], m["vy_mps"], m["yaw_rate_radps"], e["falls"], e["robots"],
 s["env_steps"] + s["eval_steps"], s["wall_seconds"]))' "$run/eval.json" "$run/summary.json"
}
schedule_runs "$out" "$steps" "$seeds" "${schedules[@]}"
python3 "$root/tools/summarise_quadruped_schedules.py" "$out" "$root/docs/results/quadruped_schedules.md" \
  "${schedules[@]}"
