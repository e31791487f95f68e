#!/usr/bin/env bash
# The main job: installs what is missing, builds the optimised configuration, then measures the
# policy inference latency on the three reference shapes and prints the table.
set -euo pipefail
cd "$(dirname "$0")/.."
bash tools/setup.sh >/dev/null
cmake --preset default >/dev/null
cmake --build --preset default -j "$(nproc)" --target pbppo_bench_inference pbppo >/dev/null
mkdir -p build/results
build/default/bench/pbppo_bench_inference --kernel all --calls 1000000 --json build/results/inference.json
echo "JSON: build/results/inference.json"
