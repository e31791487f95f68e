#!/usr/bin/env bash
# Trains the shipped quadruped walking policies and writes their report:
#   flat   from scratch on flat ground (FLAT_STEPS, Pb-PPO: our `pbppo` schedule with rollout
#          feedback), the policy the 30-minute target is about; the recipe prints its wall time;
#   mixed  from the flat policy (--init) on the paper's 1:1 mix of flat ground and blocks
#          (MIXED_STEPS; the fresh value network learns alone for CRITIC_WARMUP iterations, the
#          exploration noise starts at the flat run's last).
# Then the paper's test for each (50 robots x 20 s, commands vx, vy in [-1, 1] m/s and a heading
# in [-pi, pi]; `pbppo eval --env quadruped-walk`) on flat and mixed terrain, on two seeds, with
# the velocity plots, and copies the blobs, their golden vectors and the report to
# policies/frozen/quadruped_walk/. Same build, same seed and thread count: the same blobs.
# A stage whose folder holds a finished run (summary.json, not interrupted) is kept, so a stopped
# recipe resumes; delete OUT_DIR to train afresh.
# Usage: tools/train_quadruped.sh [OUT_DIR=runs/train_quadruped]
#   PBPPO=path/to/pbppo  THREADS=2  SEED=1  FLAT_STEPS=2.5e7  MIXED_STEPS=2e7  CRITIC_WARMUP=20
#   SCHEDULE=pbppo  SHIP=1 (0: train and evaluate, do not copy into policies/frozen)
set -euo pipefail
source "$(dirname "$0")/common.sh"
out="${1:-$root/runs/train_quadruped}"
pbppo="$(program PBPPO build/default/policies/pbppo)"
threads="${THREADS:-2}"
seed="${SEED:-1}"
flat_steps="${FLAT_STEPS:-2.5e7}"
mixed_steps="${MIXED_STEPS:-2e7}"
warmup="${CRITIC_WARMUP:-20}"
schedule="${SCHEDULE:-pbppo}"
ship="${SHIP:-1}"
frozen="$root/policies/frozen/quadruped_walk"
# legged_gym's PPO for flat terrain (rsl_rl: 5 epochs, 4 minibatches, KL-adaptive rate, entropy
# 0.01, value loss 1.0 clipped at 0.2, gradient norm 1.0, 128-64-32 ELU) on 512 environments x 24
# steps (docs/quadruped_walk.md).
common=(--env quadruped-walk --schedule "$schedule" --arms 0.1:0.3:5 --feedback rollout --threads "$threads"
  --envs 512 --rollout 24 --minibatch 3072 --epochs 5 --lr 1e-3 --lr-schedule adaptive:0.01 --ent-coef 0.01
  --vf-coef 1.0 --clip-vf 0.2 --max-grad-norm 1.0 --hidden 128-64-32 --activation elu --seed "$seed")
finished() { [ -f "$1/summary.json" ] && grep -q '"interrupted": false' "$1/summary.json"; }
mkdir -p "$out"

if finished "$out/flat"; then
  echo "flat: finished before, kept ($out/flat)"
else
  echo "flat: training from scratch, $flat_steps steps"
  start=$(date +%s)
  "$pbppo" train "${common[@]}" --terrain flat --steps "$flat_steps" --out "$out/flat"
  echo "flat: wall time $(( $(date +%s) - start )) s" | tee "$out/flat/wall_time.txt"
fi
if finished "$out/mixed"; then
  echo "mixed: finished before, kept ($out/mixed)"
else
  echo "mixed: training from the flat policy on flat ground and blocks, $mixed_steps steps"
  # The blob holds the actor's mean only: the exploration noise starts where the flat run ended
  # (its last mean log-std), not at the default 1.0, which makes the walking policy fall.
  log_std=$(python3 -c 'import csv, sys; print(list(csv.DictReader(open(sys.argv[1])))[-1]["log_std_mean"])' \
    "$out/flat/log.csv")
  echo "mixed: exploration log-std $log_std (the flat run's last)"
  start=$(date +%s)
  "$pbppo" train "${common[@]}" --terrain mixed --steps "$mixed_steps" --init "$out/flat/policy.blob" \
    --log-std-init "$log_std" --critic-warmup "$warmup" --out "$out/mixed"
  echo "mixed: wall time $(( $(date +%s) - start )) s" | tee "$out/mixed/wall_time.txt"
fi

report="$out/report"
mkdir -p "$report"
# The tracking errors of the last 100 training episodes over the run, per stage.
for stage in flat mixed; do
  for axis in vx vy yaw_rate; do
    "$pbppo" curves --out "$out/$stage/tracking_$axis.png" --column "tracking_${axis}_100" \
      --title "quadruped-walk, $stage: mean |error| of $axis, last 100 training episodes" "$stage=$out/$stage" > /dev/null
  done
done
for policy in flat mixed; do
  for terrain in flat mixed; do
    for s in 7 8; do
      name="${policy}_on_${terrain}_seed$s"
      "$pbppo" eval "$out/$policy/policy.blob" --env quadruped-walk --terrain "$terrain" --seed "$s" --json \
        --plot "$report/$name.png" > "$report/$name.json"
      python3 - "$report/$name.json" "$name" <<'PY'
import json, sys
r = json.load(open(sys.argv[1]))
e = r["mean_abs_error"]
print("%-24s vx %.3f  vy %.3f  yaw %.3f  falls %d/%d (blocks %d/%d)" % (sys.argv[2], e["vx_mps"], e["vy_mps"],
      e["yaw_rate_radps"], r["falls"], r["robots"], r["falls_on_blocks"], r["robots_on_blocks"]))
PY
    done
  done
done
if [ "$ship" = "1" ]; then
  mkdir -p "$frozen/report"
  cp "$out/flat/policy.blob" "$frozen/flat.blob"
  cp "$out/flat/policy.golden" "$frozen/flat.golden"
  cp "$out/mixed/policy.blob" "$frozen/mixed.blob"
  cp "$out/mixed/policy.golden" "$frozen/mixed.golden"
  for stage in flat mixed; do
    mkdir -p "$frozen/report/$stage"
    cp "$out/$stage/log.csv" "$out/$stage/summary.json" "$out/$stage/wall_time.txt" "$frozen/report/$stage/"
    cp "$out/$stage"/*.png "$frozen/report/$stage/" 2>/dev/null || true
  done
  cp "$report"/*.json "$report"/*.png "$frozen/report/"
  echo "shipped: $frozen"
fi
