#!/usr/bin/env bash
# Trains the shipped AUV navigation policy and writes its report: Pb-PPO (our `pbppo` schedule,
# arms 0.05:0.4:6, rollout feedback) on the hard layout (LAYOUT=mixed trains on all three), then
# 200 deterministic evaluation episodes per layout from seeds that training never uses, with the
# trajectory plots. Copies the blob, its golden vectors and the report to policies/frozen/auv_nav/.
# Usage: tools/train_auv.sh [OUT_DIR=runs/train_auv]   (PBPPO=path/to/pbppo, STEPS, SEED, THREADS)
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
out="${1:-$root/runs/train_auv}"
pbppo="${PBPPO:-$root/build/default/policies/pbppo}"
steps="${STEPS:-2.5e6}"
layout="${LAYOUT:-hard}"
seed="${SEED:-1}"
threads="${THREADS:-2}"
frozen="$root/policies/frozen/auv_nav"
if [ ! -x "$pbppo" ]; then
  echo "train_auv: $pbppo not found; build first (cmake --preset default && cmake --build build/default -j2)" >&2
  exit 2
fi
mkdir -p "$out"
"$pbppo" train --env auv-nav --layout "$layout" --schedule pbppo --arms 0.05:0.4:6 --feedback rollout \
  --steps "$steps" --seed "$seed" --threads "$threads" --envs 16 --rollout 256 --minibatch 512 --epochs 10 \
  --lr 3e-4 --gamma 0.99 --normalize-obs --scale-rewards --hidden 64-64 --keep-best --out "$out"
# PPO on this task is not monotonic: ship the policy of the best last-100-episode return.
"$root/tools/eval_auv.sh" "$out/best.blob" "$out" || echo "train_auv: the policy misses the evaluation targets (shipped anyway, see the report)"
mkdir -p "$frozen/report"
cp "$out/best.blob" "$frozen/auv_nav.blob"
cp "$out/best.golden" "$frozen/auv_nav.golden"
cp "$out"/{summary.json,log.csv,return.png,success.png,epsilon.png,arms.png} "$frozen/report/"
cp "$out"/eval_{easy,medium,hard}.{json,png} "$frozen/report/"
echo "shipped: $frozen"
