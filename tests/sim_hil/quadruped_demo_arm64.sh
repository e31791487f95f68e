#!/usr/bin/env bash
# The quadruped's demo schedule on aarch64 (run by tools/test.sh after the arm64 build's tests;
# docs/arm64.md): pbppo-hil quadruped --in-process of the arm64 build (the controller's loop, the
# walking policy on the neon kernel after its golden vectors, the Simbody plant and the emulated
# CAN devices in one process) under qemu-aarch64, beside the same schedule on x86-64 (portable
# kernel). Both walk the whole schedule without a fall, in phase run and mode nominal; each phase's
# mean velocities and the distance walked agree within bounds float rounding stays inside (contact
# makes a walk chaotic: the trajectories part from the first rounding difference); the script says
# where the traces first differ and how far apart the two robots end.
# usage: quadruped_demo_arm64.sh ARM64_BUILD ARM64_ROOT HOST_BUILD SOURCE_DIR WORK_DIR
set -euo pipefail
abuild=$(realpath "$1") aroot=$(realpath "$2") hbuild=$(realpath "$3") src=$(realpath "$4") work=$(realpath -m "$5")
source "$src/tests/support/checks.sh"  # fail, expect, fresh_dir, trace_difference
fresh_dir "$work"
cd "$work"
args=(quadruped --in-process --robot "$src/models/quadruped" --policy "$src/policies/frozen/quadruped_walk/flat.blob"
  --commands "$src/models/quadruped/schedules/demo.yaml")
walk() {  # walk NAME KERNEL PROGRAM...: the demo schedule, its log, report and trace
  local name=$1 kernel=$2
  shift 2
  "$@" "${args[@]}" --kernel "$kernel" --report "$name.json" --trace "$name.csv" >"$name.log" 2>&1 ||
    fail "$name: pbppo-hil exited $?: $(tail -20 "$name.log")"
  expect "$name.log" "controller: phase run, mode nominal"
  expect "$name.json" '"fell": false'
  echo "   $name: $(grep -o 'on the [a-z0-9]* kernel, its golden vectors passed' "$name.log"); $(grep '^walked' "$name.log")"
}
hil=$abuild/sim_hil/pbppo-hil
readelf -h "$hil" | grep 'Machine:.*AArch64' >/dev/null || fail "$hil is not an aarch64 program"
t0=$SECONDS
walk aarch64 auto qemu-aarch64 -L "$aroot" "$hil"
expect aarch64.log "on the neon kernel, its golden vectors passed"
echo "   (under qemu-aarch64: $((SECONDS - t0)) s for 18 s of schedule; emulated timings are not figures)"
walk x86-64 portable "$hbuild/sim_hil/pbppo-hil"

# Each phase's mean velocities within 0.01 m/s or rad/s, the distance within 0.02 m (on this machine:
# 0.0007 and 0.002).
/usr/bin/python3 - aarch64.json x86-64.json <<'EOF' || fail "the demo schedule on aarch64 and x86-64 differ beyond float rounding"
import json, sys
a, b = (json.load(open(p)) for p in sys.argv[1:3])
bad = []
worst = 0.0
if len(a["phases"]) != len(b["phases"]):
    bad.append(f"{len(a['phases'])} phases against {len(b['phases'])}")
for pa, pb in zip(a["phases"], b["phases"]):
    for k, (u, v) in enumerate(zip(pa["mean_measured"], pb["mean_measured"])):
        worst = max(worst, abs(u - v))
        if abs(u - v) > 0.01:
            bad.append(f"phase {pa['name']}, velocity {k}: {u:.4f} on aarch64, {v:.4f} on x86-64")
dd = abs(a["distance_m"] - b["distance_m"])
if dd > 0.02:
    bad.append(f"walked {a['distance_m']:.3f} m on aarch64, {b['distance_m']:.3f} m on x86-64")
print(f"   every phase's mean velocities within {worst:.4f} of each other (bound 0.01); distances walked "
      f"{a['distance_m']:.3f} m and {b['distance_m']:.3f} m")
for line in bad:
    print("   " + line, file=sys.stderr)
sys.exit(1 if bad else 0)
EOF
trace_difference aarch64 aarch64.csv "x86-64 " x86-64.csv 2 3  # the base's x, y
echo "PASS"
