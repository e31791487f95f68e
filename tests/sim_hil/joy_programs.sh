#!/usr/bin/env bash
# The quadruped driven through ROS 2's sensor_msgs/Joy (label dds): a joy node's side written
# against Cyclone DDS (tests/interop/cyclone_joy.c, its C type from models/ros2/idl through idlc:
# a string and two sequences as Cyclone lays them out) publishes a gamepad session on rt/joy, and
# pbppo-hil quadruped --in-process --operator robot runs models/quadruped_joy at real time.
#   1. the session: START stands the robot up, A with LB held walks it on the left stick (0.5 m/s
#      tracked within 0.2 m/s), releasing LB stands it, R3 sits it down and leaves it passive,
#      BACK e-stops; every request taken, no fall; the recording replays bit for bit;
#   2. a pad with fewer buttons than the robot file names: every Joy refused as malformed (the
#      link degraded, named), the robot never arms, and waiting disarmed stops nothing.
# usage: joy_programs.sh HIL PBPPO CYCLONE_JOY SOURCE_DIR WORK_DIR
set -euo pipefail
hil=$1 pbppo=$2 joy=$3 src=$4 work=$5
source "$src/tests/support/checks.sh"  # fail, expect, fresh_dir, start_in, dds_domain
start_in "$src" "$work"
blob=policies/frozen/quadruped_walk/flat.blob
dds_domain  # sets domain: one no other test holds
export CYCLONEDDS_URI='<CycloneDDS><Domain id="any"><General><Interfaces><NetworkInterface address="127.0.0.1"/></Interfaces><AllowMulticast>false</AllowMulticast></General><Discovery><ParticipantIndex>auto</ParticipantIndex><Peers><Peer address="127.0.0.1"/></Peers></Discovery></Domain></CycloneDDS>'

echo "== 1: a gamepad session over ROS 2's Joy"
"$hil" quadruped --robot quadruped_joy --in-process --operator robot --policy "$blob" --domain "$domain" \
  --duration 19 --report "$work/joy.json" --record "$work/joy.pbppolog" >"$work/hil.log" 2>&1 &
hpid=$!
rc=0; "$joy" "$domain" >"$work/joy.log" 2>&1 || rc=$?
hrc=0; wait $hpid || hrc=$?
[ "$rc" -eq 0 ] || { cat "$work/joy.log"; fail "cyclone_joy exited $rc"; }
[ "$hrc" -eq 0 ] || { cat "$work/hil.log"; fail "pbppo-hil exited $hrc"; }
expect "$work/joy.log" "published [0-9]+"
expect "$work/hil.log" "transport ros \(dds\): received [1-9][0-9]* \(malformed 0\)"
expect "$work/hil.log" "operator: 4 requests, 0 refused"
for step in "disarmed -> arming" "hold -> run" "run -> stand-up" "stand-up -> sit-down" "sit-down -> passive"; do
  expect "$work/hil.log" "phase: tick [0-9]+: $step"
done
expect "$work/hil.log" "mode change: tick [0-9]+: e-stop: e-stop request"
expect "$work/hil.log" "no fall"
/usr/bin/python3 - "$work/joy.json" "$work/hil.log" <<'PY'
import json, re, sys
r = json.load(open(sys.argv[1]))
log = open(sys.argv[2]).read()
assert not r["fell"], "fell at %s s" % r["fell_at_s"]
fwd = [p for p in r["phases"] if abs(p["command"][0] - 0.5) < 1e-9]
assert len(fwd) == 1, r["phases"]
e = fwd[0]["mean_abs_error"]
ticks = {m.group(2): int(m.group(1)) for m in re.finditer(r"phase: tick (\d+): \S+ -> (\S+)", log)}
print("Joy: armed at tick %d, walking at %d (|e| vx %.3f vy %.3f, measured vx %.3f), standing at %d, sitting at %d, "
      "passive at %d" % (ticks["arming"], ticks["run"], e[0], e[1], fwd[0]["mean_measured"][0], ticks["stand-up"],
                         ticks["sit-down"], ticks["passive"]))
assert e[0] <= 0.2 and e[1] <= 0.2, e
# The session's times on the node's clock: A 3.5 s after START, LB released at 9.0, R3 at 10.0.
assert abs(ticks["run"] - ticks["arming"] - 3500) <= 150, ticks
assert abs(ticks["sit-down"] - ticks["arming"] - 10000) <= 150, ticks
PY
"$pbppo" replay --robot quadruped_joy --policy "$blob" "$work/joy.pbppolog" >"$work/replay.log" 2>&1 ||
  { cat "$work/replay.log"; fail "pbppo replay"; }
expect "$work/replay.log" "[1-9][0-9]* commands compared, 0 different"

echo "== 2: a pad with fewer buttons than the robot file names"
"$hil" quadruped --robot quadruped_joy --in-process --operator robot --policy "$blob" --domain "$domain" \
  --duration 5 >"$work/hil2.log" 2>&1 &
hpid=$!
"$joy" "$domain" 6 8 >"$work/joy2.log" 2>&1 &
jpid=$!
hrc=0; wait $hpid || hrc=$?
kill "$jpid" 2>/dev/null || true
wait "$jpid" 2>/dev/null || true
[ "$hrc" -eq 0 ] || { cat "$work/hil2.log"; fail "pbppo-hil exited $hrc"; }
expect "$work/hil2.log" "transport ros \(dds\): received ([1-9][0-9]*) \(malformed \1\)"
expect "$work/hil2.log" "controller: phase disarmed, mode degraded"
expect "$work/hil2.log" "mode change: tick [0-9]+: degraded: transport degraded: 'ros'"
if grep -Eq "mode change: .*(safe-stop|e-stop)" "$work/hil2.log"; then cat "$work/hil2.log"; fail "stopped while waiting disarmed"; fi
echo "joy programs: ok"
