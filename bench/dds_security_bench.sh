#!/usr/bin/env bash
# The cost of DDS Security on the AUV's link: lock-step missions (pbppo-hil auv + pbppo-controller,
# easy layout, seed 2, 435 ticks) open and secured (tools/security/make_dds_security.sh), alternated,
# RUNS each; prints the medians of the mission's wall time and of the controller's receive and send
# stages (p50 and p99 of each run's profile), side by side, and the ratios.
# usage: bench/dds_security_bench.sh [RUNS]   (after cmake --build --preset default)
set -euo pipefail
cd "$(dirname "$0")/.."
runs=${1:-7}
hil=build/default/sim_hil/pbppo-hil ctl=build/default/firmware/pbppo-controller
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
tools/security/make_dds_security.sh "$work/sec" 'controller:pbppo/auv/command+pbppo/auv/controller_status:pbppo/auv/*' \
  'hil:pbppo/auv/sensor_state:pbppo/auv/*' >/dev/null
domain=$((150 + $$ % 80))
mission() {  # mission NAME [ARGS...]
  local name=$1
  shift
  "$hil" auv --layout easy --seed 2 --lockstep --domain "$domain" "$@" >"$work/$name.hil.log" 2>&1 &
  local pid=$!
  "$ctl" --robot models/auv/robot.yaml --policy policies/frozen/auv_nav/auv_nav.blob --lockstep --domain "$domain" \
    --quiet --profile "$work/$name.json" "$@" >/dev/null 2>&1
  wait "$pid"
  grep -q "3/3 targets" "$work/$name.hil.log" || { cat "$work/$name.hil.log"; exit 1; }
}
for i in $(seq "$runs"); do
  mission "open$i"
  mission "secured$i" --dds-security "$work/sec"
done
/usr/bin/python3 - "$work" "$runs" <<'PY'
import json, re, statistics, sys
work, runs = sys.argv[1], int(sys.argv[2])
def figures(kind):
    wall, rows = [], {"receive": ([], []), "send": ([], [])}
    for i in range(1, runs + 1):
        log = open(f"{work}/{kind}{i}.hil.log").read()
        wall.append(float(re.search(r"ticks, ([0-9.]+) s wall", log).group(1)))
        stages = json.load(open(f"{work}/{kind}{i}.json"))["stages"]
        for s, (p50, p99) in rows.items():
            p50.append(stages[s]["p50"] / 1e3)
            p99.append(stages[s]["p99"] / 1e3)
    m = statistics.median
    return {"wall_s": m(wall), "receive_p50_us": m(rows["receive"][0]), "receive_p99_us": m(rows["receive"][1]),
            "send_p50_us": m(rows["send"][0]), "send_p99_us": m(rows["send"][1])}
o, s = figures("open"), figures("secured")
print(f"AUV lock-step mission, 435 ticks, medians of {runs} runs each (open and secured alternated)")
print(f"{'':16}{'open':>10}{'secured':>10}{'ratio':>8}")
for k in o:
    print(f"{k:16}{o[k]:10.2f}{s[k]:10.2f}{s[k] / o[k]:8.2f}")
print(f"lock-step speed: {435 / o['wall_s']:.0f} ticks/s open, {435 / s['wall_s']:.0f} ticks/s secured")
PY
