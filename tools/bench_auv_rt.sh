#!/usr/bin/env bash
# AUV controller latency in native real-time mode and lock-step HIL speed.
#  1. pbppo-hil auv --realtime (10 Hz samples) and pbppo-controller free-running at 1000 Hz for
#     DURATION s (default 60) over DDS on loopback: per-stage latency, tick (receive -> send),
#     wake-up jitter, deadline misses; JSON + PNG profile.
#  2. A lock-step run (hard layout) to the end of its episode: simulated seconds per wall second.
# Quiet the machine first: other load shows up as jitter. Writes into OUT_DIR (build/results/rt).
# Usage: tools/bench_auv_rt.sh [OUT_DIR]   (DURATION=60, POLL_US=200 (0: the tick wakes the DDS writer),
#   BLOB=policies/frozen/auv_nav/auv_nav.blob)
set -euo pipefail
source "$(dirname "$0")/common.sh"
out="${1:-$root/build/results/rt}"
duration="${DURATION:-60}"
blob="${BLOB:-$root/policies/frozen/auv_nav/auv_nav.blob}"
hil="$(program PBPPO_HIL build/default/sim_hil/pbppo-hil)"
ctl="$(program PBPPO_CONTROLLER build/default/firmware/pbppo-controller)"
cd "$root"
mkdir -p "$out"
domain=$((20 + $$ % 200))
echo "== 1: real time, controller at 1000 Hz for ${duration} s (vehicle at 10 Hz)"
"$hil" auv --layout hard --seed 3 --realtime --domain "$domain" --max-time $((duration + 30)) >"$out/rt.hil.log" 2>&1 &
hpid=$!
"$ctl" --robot models/auv/robot.yaml --policy "$blob" --domain "$domain" --period-ms 1 \
  --duration "$duration" --writer-poll-us "${POLL_US:-200}" --quiet --profile "$out/rt_profile.json" --profile-plot "$out/rt_profile.png" | tee "$out/rt.ctl.log"
kill -INT "$hpid" 2>/dev/null || true
wait "$hpid" || true
echo
echo "== 2: lock-step HIL speed (hard, seed 3, whole episode)"
"$hil" auv --layout hard --seed 3 --lockstep --domain "$domain" >"$out/ls.hil.log" 2>&1 &
hpid=$!
"$ctl" --robot models/auv/robot.yaml --policy "$blob" --lockstep --domain "$domain" --quiet >"$out/ls.ctl.log"
wait "$hpid"
sed -n 2p "$out/ls.hil.log"
python3 - "$out/ls.hil.log" <<'PY'
import re, sys
t = open(sys.argv[1]).read()
m = re.search(r"after ([0-9.]+) s simulated \(([0-9]+) ticks, ([0-9.]+) s wall\)", t)
sim, ticks, wall = float(m.group(1)), int(m.group(2)), float(m.group(3))
print("lock-step: %.1f simulated s in %.2f wall s = %.0f simulated s per wall s (%.0f ticks/s)" % (sim, wall, sim / wall, ticks / wall))
PY
echo "files: $out/rt_profile.json $out/rt_profile.png"
