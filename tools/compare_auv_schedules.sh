#!/usr/bin/env bash
# Clip-schedule comparison on auv-nav (hard layout): fixed:0.2 against the three Pb-PPO schedules
# (pbppo-paper wi-ad, pbppo-reference: the released script's default wo-ad, pbppo), 5 seeds each,
# equal total environment steps: the bandits take `rollout` feedback (mean return of the episodes
# finished in the next rollout), which costs no extra steps, so every run uses exactly STEPS
# environment steps. After training, each policy is evaluated deterministically on 100 hard
# episodes from seed 900001 (not a training seed).
# The reward is the shipped policy's training reward (PROGRESS=geodesic, MARGIN=2:4: the geodesic
# progress term with its margin; PROGRESS=euclidean MARGIN= for the paper's).
# Writes docs/results/auv_hard_schedules.md (means with 95% t-intervals over seeds) and a plot of
# the training curves (pbppo curves: mean over seeds with a one-sd band).
# Usage: tools/compare_auv_schedules.sh [OUT_DIR=runs/compare_auv]
#   (PBPPO=path/to/pbppo, STEPS=1e6, SEEDS="1 2 3 4 5", THREADS=2, EPISODES=100, PROGRESS, MARGIN and
#   SCHEDULES="fixed:0.2 pbppo-paper:wi-ad pbppo-reference pbppo" may be set)
set -euo pipefail
source "$(dirname "$0")/common.sh"
out="${1:-$root/runs/compare_auv}"
pbppo="$(program PBPPO build/default/policies/pbppo)"
steps="${STEPS:-1e6}"
progress="${PROGRESS:-geodesic}"
margin="${MARGIN-2:4}"
seeds="${SEEDS:-1 2 3 4 5}"
threads="${THREADS:-2}"
episodes="${EPISODES:-100}"
read -r -a schedules <<<"${SCHEDULES:-fixed:0.2 pbppo-paper:wi-ad pbppo-reference pbppo}"
common=(--env auv-nav --layout hard --threads "$threads" --envs 16 --rollout 256 --minibatch 512 --epochs 10
  --lr 3e-4 --gamma 0.99 --normalize-obs --scale-rewards --arms 0.05:0.4:6 --feedback rollout --steps "$steps"
  --progress "$progress" ${margin:+--geodesic-margin "$margin"})
train_and_eval() {
  local run="$1" schedule="$2" seed="$3"
  "$pbppo" train "${common[@]}" --schedule "$schedule" --seed "$seed" --quiet --out "$run" > "$run.txt" 2>&1
  # eval.json marks a finished run: written whole or not at all.
  "$pbppo" eval "$run/policy.blob" --env auv-nav --layout hard --episodes "$episodes" --seed 900001 --json \
    > "$run/eval.json.part"
  mv "$run/eval.json.part" "$run/eval.json"
  python3 -c 'import json,sys; e=json.load(open(sys.argv[1])); s=json.load(open(sys.argv[2]));
print("  last-100 return %.1f, eval success %.0f%%, eval return %.1f, steps %d" % (s["final_return_last100"],
 100*e["success_rate"], e["mean_return"], s["env_steps"] + s["eval_steps"]))' "$run/eval.json" "$run/summary.json"
}
schedule_runs "$out" "$steps" "$seeds" "${schedules[@]}"
PBPPO="$pbppo" python3 "$root/tools/summarise_schedules.py" "$out" "$root/docs/results/auv_hard_schedules.md" \
  "${schedules[@]}"
