#!/usr/bin/env bash
# Our latency table for the machine it runs on: a robot's own computer (a Jetson, a Raspberry Pi,
# an RK3588 board: aarch64) or any x86-64 machine. Builds the robot side and its benchmarks
# natively (Release, no Simbody, MuJoCo or trainer), then runs
#   - pbppo_bench_inference: one forward call of the reference shapes on every kernel this CPU
#     has (neon and portable on aarch64), against the time to merely read the parameters;
#   - pbppo_bench_tick: one control tick of each shipped robot (read, check, observe, infer,
#     supervise, write) over an in-memory transport, per stage;
# and writes everything to build/results/board/<host>/ with a summary (summary.txt).
# Run it on an idle board, with the CPU governor at performance if you can; numbers from an
# emulator are not figures.
#
# usage: tools/bench_board.sh [--calls N] [--ticks N] [--build-dir DIR]
#   (the build needs cmake, ninja, g++ and the robot side's -dev packages: docs/arm64.md)
set -euo pipefail
cd "$(dirname "$0")/.."
calls=1000000 ticks=200000 build=build/board
while [ $# -gt 0 ]; do
  case "$1" in
    --calls) calls=$2; shift 2 ;;
    --ticks) ticks=$2; shift 2 ;;
    --build-dir) build=$2; shift 2 ;;
    *) echo "usage: $0 [--calls N] [--ticks N] [--build-dir DIR]" >&2; exit 2 ;;
  esac
done
for v in "$calls" "$ticks"; do
  [[ "$v" =~ ^[0-9]+$ ]] || { echo "bench_board: '$v' is not a count" >&2; exit 2; }
done
host=$(hostname -s 2>/dev/null || hostname)
out=build/results/board/$host
mkdir -p "$out"

echo "== building the robot side and its benchmarks in $build"
cmake -S . -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release -DPBPPO_BUILD_SIM_HIL=OFF -DPBPPO_BUILD_TOOLS=OFF \
  -DPBPPO_BUILD_BENCH=ON -DPBPPO_BUILD_TESTS=OFF >"$out/configure.log"
cmake --build "$build" --target pbppo_bench_inference pbppo_bench_tick >"$out/build.log"

{
  echo "machine: $(uname -m), $(nproc) CPUs, kernel $(uname -r)"
  model=$(grep -m1 -E '^(model name|Model|Hardware)' /proc/cpuinfo 2>/dev/null | cut -d: -f2- | sed 's/^ *//')
  [ -n "$model" ] && echo "CPU: $model"
  gov=/sys/devices/system/cpu/cpu0/cpufreq/scaling_governor
  [ -r "$gov" ] && echo "governor: $(cat "$gov")"
  echo "date: $(date -u +%Y-%m-%dT%H:%MZ), commit $(git rev-parse --short HEAD 2>/dev/null || echo unknown)"
} | tee "$out/summary.txt"

echo "== inference ($calls calls per row)"
"$build/bench/pbppo_bench_inference" --calls "$calls" --kernel all --json "$out/inference.json" |
  tee "$out/inference.txt"
for robot in auv quadruped; do
  echo "== one control tick of the $robot ($ticks ticks)"
  "$build/bench/pbppo_bench_tick" --robot "models/$robot/robot.yaml" --ticks "$ticks" --json "$out/tick_$robot.json" |
    tee "$out/tick_$robot.txt"
done
{
  echo
  grep -E '^(shape|P[0-9])' "$out/inference.txt"
  for robot in auv quadruped; do
    echo
    echo "tick of the $robot:"
    grep -E '^(stage|tick|infer) ' "$out/tick_$robot.txt" || true
  done
} | tee -a "$out/summary.txt"
echo "bench_board: results in $out"
