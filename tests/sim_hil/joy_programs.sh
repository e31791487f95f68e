#!/usr/bin/env bash
# The quadruped driven through ROS 2's sensor_msgs/Joy (label dds): a joy node's side written
# against Cyclone DDS (tests/interop/cyclone_joy.c, its C type from models/ros2/idl through idlc:
# a string and two sequences as Cyclone lays them out) publishes a gamepad session on rt/joy, and
# pbppo-hil quadruped --in-process --operator robot runs models/quadruped_joy at real time.
#   1. the session: START stands the robot up, A with LB held walks it on the left stick (0.5 m/s
#      tracked within 0.2 m/s), releasing LB stands it and, LB not held again, 3 s into the hold it
#      sits down (passive); START stands it up again, R3 sits it down, BACK e-stops, GUIDE re-arms
#      it and leaves it passive (rearm_to: passive); every request taken, no fall; the recording
#      replays bit for bit;
#   2. a pad with fewer buttons than the robot file names: every Joy refused as malformed (the
#      link degraded, named), the robot never arms, and waiting disarmed stops nothing;
#   3. the AUV (models/auv_joy: a robot without motors) with pbppo-controller and pbppo-hil auv at
#      real time: waiting for START, then the mission; BACK e-stops it, GUIDE re-arms it (the
#      recovery rule) and it runs on, B ends the run; the recording replays bit for bit.
# usage: joy_programs.sh HIL PBPPO CONTROLLER CYCLONE_JOY SOURCE_DIR WORK_DIR
set -euo pipefail
hil=$1 pbppo=$2 ctl=$3 joy=$4 src=$5 work=$6
source "$src/tests/support/checks.sh"  # fail, expect, fresh_dir, start_in, dds_domain
start_in "$src" "$work"
blob=policies/frozen/quadruped_walk/flat.blob
dds_domain  # sets domain: one no other test holds
export CYCLONEDDS_URI='<CycloneDDS><Domain id="any"><General><Interfaces><NetworkInterface address="127.0.0.1"/></Interfaces><AllowMulticast>false</AllowMulticast></General><Discovery><ParticipantIndex>auto</ParticipantIndex><Peers><Peer address="127.0.0.1"/></Peers></Discovery></Domain></CycloneDDS>'

echo "== 1: a gamepad session over ROS 2's Joy"
"$hil" quadruped --robot quadruped_joy --in-process --operator robot --policy "$blob" --domain "$domain" \
  --duration 26 --report "$work/joy.json" --record "$work/joy.pbppolog" >"$work/hil.log" 2>&1 &
hpid=$!
rc=0; "$joy" "$domain" >"$work/joy.log" 2>&1 || rc=$?
hrc=0; wait $hpid || hrc=$?
[ "$rc" -eq 0 ] || { cat "$work/joy.log"; fail "cyclone_joy exited $rc"; }
[ "$hrc" -eq 0 ] || { cat "$work/hil.log"; fail "pbppo-hil exited $hrc"; }
expect "$work/joy.log" "published [0-9]+"
expect "$work/hil.log" "transport ros \(dds\): received [1-9][0-9]* \(malformed 0\)"
expect "$work/hil.log" "operator: 6 requests, 0 refused"
expect "$work/hil.log" "mode change: tick [0-9]+: e-stop: e-stop request"
expect "$work/hil.log" "mode change: tick [0-9]+: nominal: re-armed on request"
expect "$work/hil.log" "no fall"
/usr/bin/python3 - "$work/joy.json" "$work/hil.log" <<'PY'
import json, re, sys
r = json.load(open(sys.argv[1]))
log = open(sys.argv[2]).read()
assert not r["fell"], "fell at %s s" % r["fell_at_s"]
fwd = [p for p in r["phases"] if abs(p["command"][0] - 0.5) < 1e-9]
assert len(fwd) == 1, r["phases"]
e = fwd[0]["mean_abs_error"]
moves = [(int(t), a + " -> " + b) for t, a, b in re.findall(r"phase: tick (\d+): (\S+) -> (\S+)", log)]
want = ["disarmed -> arming", "arming -> stand-up", "stand-up -> hold", "hold -> run", "run -> stand-up",
        "stand-up -> hold", "hold -> sit-down", "sit-down -> passive", "passive -> stand-up", "stand-up -> hold",
        "hold -> sit-down", "sit-down -> passive", "passive -> disarmed", "disarmed -> arming", "arming -> passive"]
assert [m for _, m in moves] == want, moves
t = [tick for tick, _ in moves]
estop = int(re.search(r"mode change: tick (\d+): e-stop", log).group(1))
armed = t[0]
print("Joy: armed at tick %d, walking +%d (|e| vx %.3f vy %.3f, measured vx %.3f), standing +%d, sitting (released) "
      "+%d, up again +%d, sitting (R3) +%d, e-stop +%d, re-armed to passive +%d" % (
          armed, t[3] - armed, e[0], e[1], fwd[0]["mean_measured"][0], t[4] - armed, t[6] - armed, t[8] - armed,
          t[10] - armed, estop - armed, t[14] - armed))
assert e[0] <= 0.2 and e[1] <= 0.2, e
# The session's times on the node's clock (from START): A 3.5 s, LB released 9.0 (a 1 s stand-up,
# then 3 s in hold: 13.0), START 15.0, R3 16.5, BACK 18.5.
for k, when in ((3, 3500), (4, 9000), (6, 13000), (8, 15000), (10, 16500)):
    assert abs(t[k] - armed - when) <= 150, (k, t[k] - armed, when)
assert abs(estop - armed - 18500) <= 150, estop - armed
assert abs(t[12] - armed - 19600) <= 150, t[12] - armed  # re-armed at GUIDE, then passive
PY
"$pbppo" replay --robot quadruped_joy --policy "$blob" "$work/joy.pbppolog" >"$work/replay.log" 2>&1 ||
  { cat "$work/replay.log"; fail "pbppo replay"; }
expect "$work/replay.log" "[1-9][0-9]* commands compared, 0 different"

echo "== 2: a pad with fewer buttons than the robot file names"
"$hil" quadruped --robot quadruped_joy --in-process --operator robot --policy "$blob" --domain "$domain" \
  --duration 5 >"$work/hil2.log" 2>&1 &
hpid=$!
"$joy" "$domain" walk 6 8 >"$work/joy2.log" 2>&1 &
jpid=$!
hrc=0; wait $hpid || hrc=$?
kill "$jpid" 2>/dev/null || true
wait "$jpid" 2>/dev/null || true
[ "$hrc" -eq 0 ] || { cat "$work/hil2.log"; fail "pbppo-hil exited $hrc"; }
expect "$work/hil2.log" "transport ros \(dds\): received ([1-9][0-9]*) \(malformed \1\)"
expect "$work/hil2.log" "controller: phase disarmed, mode degraded"
expect "$work/hil2.log" "mode change: tick [0-9]+: degraded: transport degraded: 'ros'"
if grep -Eq "mode change: .*(safe-stop|e-stop)" "$work/hil2.log"; then cat "$work/hil2.log"; fail "stopped while waiting disarmed"; fi

echo "== 3: the AUV's mission run, e-stopped, re-armed and stopped from the pad"
auv_blob=policies/frozen/auv_nav/auv_nav.blob
"$hil" auv --robot auv_joy --layout easy --seed 2 --realtime --domain "$domain" --max-time 25 >"$work/auv.hil.log" 2>&1 &
hpid=$!
"$ctl" --robot auv_joy --policy "$auv_blob" --lockstep --domain "$domain" --quiet --record "$work/auv.pbppolog" \
  >"$work/auv.ctl.log" 2>&1 &
cpid=$!
rc=0; "$joy" "$domain" run >"$work/joy3.log" 2>&1 || rc=$?
crc=0; wait $cpid || crc=$?
hrc=0; wait $hpid || hrc=$?
[ "$rc" -eq 0 ] || { cat "$work/joy3.log"; fail "cyclone_joy exited $rc"; }
[ "$crc" -eq 0 ] || { cat "$work/auv.ctl.log"; fail "pbppo-controller exited $crc"; }
[ "$hrc" -eq 0 ] || { cat "$work/auv.hil.log"; fail "pbppo-hil auv exited $hrc"; }
expect "$work/auv.ctl.log" "waiting for the operator to arm \(field 'arm'\)"
expect "$work/auv.ctl.log" "phase: tick [0-9]+: disarmed -> run"
expect "$work/auv.ctl.log" "mode change: tick [0-9]+: e-stop: e-stop request"
expect "$work/auv.ctl.log" "mode change: tick [0-9]+: nominal: re-armed on request"
expect "$work/auv.ctl.log" "phase: tick [0-9]+: run -> done"
expect "$work/auv.ctl.log" "operator: 4 requests, 0 refused"
expect "$work/auv.ctl.log" "recovery: stopped 1 times, re-armed 1 \(0 automatically, 1 on request\)"
expect "$work/auv.ctl.log" "stopped by its stop done"
expect "$work/auv.ctl.log" "control thread heap allocations during the loop: 0"
/usr/bin/python3 - "$work/auv.ctl.log" <<'PY'
import re, sys
log = open(sys.argv[1]).read()
run = [int(t) for t in re.findall(r"phase: tick (\d+): disarmed -> run", log)]
estop = int(re.search(r"mode change: tick (\d+): e-stop", log).group(1))
rearm = int(re.search(r"mode change: tick (\d+): nominal: re-armed", log).group(1))
done = int(re.search(r"phase: tick (\d+): run -> done", log).group(1))
print("AUV on the pad: running at tick %s, e-stop at %d, re-armed at %d, done at %d (0.1 s ticks)" % (run, estop, rearm, done))
# The session's times on the node's clock: BACK 6 s after START, GUIDE at 9, B at 13.
assert len(run) == 2 and abs(estop - run[0] - 60) <= 3 and abs(rearm - run[0] - 90) <= 3 and abs(done - run[0] - 130) <= 3, log
PY
"$pbppo" replay --robot auv_joy --policy "$auv_blob" "$work/auv.pbppolog" >"$work/auv.replay.log" 2>&1 ||
  { cat "$work/auv.replay.log"; fail "pbppo replay (AUV)"; }
expect "$work/auv.replay.log" "[1-9][0-9]* commands compared, 0 different"
echo "joy programs: ok"
