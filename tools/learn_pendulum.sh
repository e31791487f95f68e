#!/usr/bin/env bash
# Learns Pendulum with rl-zoo's PPO settings (4 envs x 1024 steps, gamma 0.9, lr 1e-3, GAE 0.95,
# 10 epochs, minibatch 64, fixed clip 0.2, 100k steps; rl-zoo's gSDE is not used) for 5 seeds
# and reports the median over seeds of the mean return of the last 100 training episodes.
# Target: a median of -210 or better.
# Usage: tools/learn_pendulum.sh [OUT_DIR=runs/learn_pendulum]   (PBPPO=path/to/pbppo, THREADS=n,
# SCHEDULE=fixed:0.2 and SEEDS="1 2 3 4 5" may be set in the environment)
set -euo pipefail
source "$(dirname "$0")/common.sh"
out="${1:-$root/runs/learn_pendulum}"
pbppo="$(program PBPPO build/default/policies/pbppo)"
threads="${THREADS:-1}"
schedule="${SCHEDULE:-fixed:0.2}"
seeds="${SEEDS:-1 2 3 4 5}"
mkdir -p "$out"
results=()
for seed in $seeds; do
  run="$out/seed$seed"
  "$pbppo" train --env pendulum --schedule "$schedule" --envs 4 --rollout 1024 --gamma 0.9 \
    --lr 1e-3 --gae-lambda 0.95 --epochs 10 --minibatch 64 --steps 1e5 --seed "$seed" --threads "$threads" \
    --quiet --out "$run" > "$run.txt" 2>&1
  r=$(sed -n 's/.*"final_return_last100": \([-0-9.eE+]*\).*/\1/p' "$run/summary.json")
  sps=$(sed -n 's/.*"steps_per_second": \([-0-9.eE+]*\).*/\1/p' "$run/summary.json")
  printf 'seed %s  last-100 return %9.2f  steps/s %.0f\n' "$seed" "$r" "$sps"
  results+=("$r")
done
median=$(printf '%s\n' "${results[@]}" | sort -g | awk '{a[NR]=$1} END {if (NR % 2) print a[(NR+1)/2]; else print (a[NR/2]+a[NR/2+1])/2}')
printf 'median over %d seeds: %.2f (target >= -210): %s\n' "${#results[@]}" "$median" \
  "$(awk -v m="$median" 'BEGIN {print (m >= -210) ? "met" : "NOT met"}')"
