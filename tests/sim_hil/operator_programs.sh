#!/usr/bin/env bash
# The quadruped driven over DDS by another process (label dds): pbppo-hil quadruped --in-process
# --operator dds (controller and HIL in one process, at real time) and pbppo-operator playing a
# velocity schedule, with ROS 2's names.
#   1. pbppo-operator refuses bad arguments and files (exit 2, naming them) and reports a missing
#      controller (exit 1, naming the domain);
#   2. the robot walks the schedule sent over DDS: 0.5 m/s tracked within 0.2 m/s, no fall; the
#      operator reads the status back, and after it falls silent the controller is in safe-stop;
#   3. an operator with the native names does not reach a controller with ROS 2's;
#   4. over DDS Security (tools/security/make_dds_security.sh): the operator with its certificate
#      drives the robot; a Cyclone DDS operator without one (tests/interop/cyclone_operator.c,
#      ROS 2's names) is never seen: the robot does not move and Cyclone reads no status.
# usage: operator_programs.sh HIL OPERATOR CYCLONE_OPERATOR SOURCE_DIR WORK_DIR
set -euo pipefail
hil=$1 op=$2 cyclone=$3 src=$4 work=$5
source "$src/tests/support/checks.sh"  # fail, expect, fresh_dir, start_in
start_in "$src" "$work"
blob=policies/frozen/quadruped_walk/flat.blob
robot=models/quadruped/robot.yaml
dds_domain  # sets domain: one no other test holds
cat > "$work/short.yaml" <<'YAML'
stream: velocity_command
phases:
  - {name: stand, duration_s: 2.0}
  - {name: forward, duration_s: 4.0, command_vx: 0.5}
  - {name: stop, duration_s: 1.0}
YAML

echo "== 1: bad arguments and files"
rc=0; "$op" --robot "$robot" >"$work/a1.log" 2>&1 || rc=$?
[ "$rc" -eq 2 ] || fail "no --schedule: exit $rc"
expect "$work/a1.log" "schedule"
rc=0; "$op" --schedule "$work/short.yaml" >"$work/a0.log" 2>&1 || rc=$?
[ "$rc" -eq 2 ] || fail "no --robot: exit $rc"
expect "$work/a0.log" "--robot is required"
rc=0; "$op" --robot models/quadruped/robot.yaml --schedule models/auv/layouts/easy.yaml >"$work/a6.log" 2>&1 || rc=$?
[ "$rc" -eq 2 ] || fail "a file that is no schedule: exit $rc"
expect "$work/a6.log" "easy.yaml"
rc=0; "$op" --robot "$robot" --schedule "$work/short.yaml" --dds-naming ros >"$work/a2.log" 2>&1 || rc=$?
[ "$rc" -eq 2 ] || fail "--dds-naming ros: exit $rc"
expect "$work/a2.log" "naming 'ros'"
rc=0; "$op" --robot "$robot" --schedule "$work/none.yaml" >"$work/a3.log" 2>&1 || rc=$?
[ "$rc" -eq 2 ] || fail "a missing schedule: exit $rc"
expect "$work/a3.log" "none.yaml"
sed 's/command_vx: 0.5/command_vx: 5.0/' "$work/short.yaml" > "$work/fast.yaml"
rc=0; "$op" --robot "$robot" --schedule "$work/fast.yaml" >"$work/a4.log" 2>&1 || rc=$?
[ "$rc" -eq 2 ] || fail "a command beyond the field's bounds: exit $rc"
expect "$work/a4.log" "command_vx"
rc=0; "$op" --robot "$robot" --schedule "$work/short.yaml" --domain "$domain" --peer-timeout-s 1 >"$work/a5.log" 2>&1 || rc=$?
[ "$rc" -eq 1 ] || fail "no controller: exit $rc"
expect "$work/a5.log" "no controller on DDS domain $domain"

echo "== 2: walking on commands sent over DDS (ROS 2 names)"
"$hil" quadruped --in-process --policy "$blob" --operator dds --domain "$domain" --dds-naming ros2 --duration 9 \
  --report "$work/walk.json" >"$work/hil.log" 2>&1 &
hpid=$!
rc=0
"$op" --robot "$robot" --schedule "$work/short.yaml" --domain "$domain" --dds-naming ros2 --linger-s 3 >"$work/op.log" 2>&1 || rc=$?
hrc=0; wait $hpid || hrc=$?
[ "$rc" -eq 0 ] || { cat "$work/op.log"; fail "pbppo-operator exited $rc"; }
[ "$hrc" -eq 0 ] || { cat "$work/hil.log"; fail "pbppo-hil exited $hrc"; }
expect "$work/op.log" "status t=.*run, nominal, velocity_command [0-9]+, in force \(0\.50, 0\.00, 0\.00\)"
expect "$work/op.log" "status t=.*run, safe-stop"
expect "$work/op.log" "last status .*(safe-stop|e-stop)"
python3 - "$work/walk.json" <<'PY'
import json, sys
r = json.load(open(sys.argv[1]))
assert not r["fell"], "fell at %s s" % r["fell_at_s"]
fwd = [p for p in r["phases"] if abs(p["command"][0] - 0.5) < 1e-9]
assert len(fwd) == 1, r["phases"]
e = fwd[0]["mean_abs_error"]
print("forward over DDS: |e| vx %.3f vy %.3f yaw rate %.3f, measured vx %.3f" % (e[0], e[1], e[2], fwd[0]["mean_measured"][0]))
assert e[0] <= 0.2 and e[1] <= 0.2, e
PY

echo "== 3: native names do not reach a controller with ROS 2's"
"$hil" quadruped --in-process --policy "$blob" --operator dds --domain "$domain" --dds-naming ros2 --duration 4 \
  >"$work/hil3.log" 2>&1 &
hpid=$!
rc=0; "$op" --robot "$robot" --schedule "$work/short.yaml" --domain "$domain" --peer-timeout-s 3 >"$work/op3.log" 2>&1 || rc=$?
wait $hpid || true
[ "$rc" -eq 1 ] || { cat "$work/op3.log"; fail "a native operator reached a ROS 2 controller (exit $rc)"; }
echo "== 4: DDS Security: the operator with a certificate drives the robot, Cyclone without one is not seen"
sec=$work/sec
tools/security/make_dds_security.sh "$sec" 'controller:rt/pbppo/quadruped/status:rt/pbppo/quadruped/*' \
  'operator:rt/pbppo/quadruped/velocity_command:rt/pbppo/quadruped/*' >/dev/null
"$hil" quadruped --in-process --policy "$blob" --operator dds --domain "$domain" --dds-naming ros2 --duration 9 \
  --dds-security "$sec" --report "$work/secure.json" >"$work/hil4.log" 2>&1 &
hpid=$!
rc=0
"$op" --robot "$robot" --schedule "$work/short.yaml" --domain "$domain" --dds-naming ros2 --linger-s 3 --dds-security "$sec" \
  >"$work/op4.log" 2>&1 || rc=$?
hrc=0; wait $hpid || hrc=$?
[ "$rc" -eq 0 ] || { cat "$work/op4.log"; fail "the secured pbppo-operator exited $rc"; }
[ "$hrc" -eq 0 ] || { cat "$work/hil4.log"; fail "the secured pbppo-hil exited $hrc"; }
expect "$work/op4.log" "status t=.*run, nominal, velocity_command [0-9]+, in force \(0\.50, 0\.00, 0\.00\)"
"$hil" quadruped --in-process --policy "$blob" --operator dds --domain "$domain" --dds-naming ros2 --duration 6 \
  --dds-security "$sec" --report "$work/intruded.json" >"$work/hil5.log" 2>&1 &
hpid=$!
export CYCLONEDDS_URI='<CycloneDDS><Domain id="any"><General><Interfaces><NetworkInterface address="127.0.0.1"/></Interfaces><AllowMulticast>false</AllowMulticast></General><Discovery><ParticipantIndex>auto</ParticipantIndex><Peers><Peer address="127.0.0.1"/></Peers></Discovery></Domain></CycloneDDS>'
rc=0; "$cyclone" "$domain" 0.5 4 1 >"$work/cyclone.log" 2>&1 || rc=$?
hrc=0; wait $hpid || hrc=$?
[ "$hrc" -eq 0 ] || { cat "$work/hil5.log"; fail "the secured pbppo-hil exited $hrc"; }
[ "$rc" -ne 0 ] || { cat "$work/cyclone.log"; fail "Cyclone DDS without a certificate read the robot's status"; }
expect "$work/cyclone.log" "published [1-9][0-9]*"
python3 - "$work/secure.json" "$work/intruded.json" <<'PY'
import json, sys
walked, intruded = (json.load(open(p)) for p in sys.argv[1:3])
fwd = [p for p in walked["phases"] if abs(p["command"][0] - 0.5) < 1e-9][0]
print("secured operator: forward |e| vx %.3f, measured vx %.3f" % (fwd["mean_abs_error"][0], fwd["mean_measured"][0]))
assert fwd["mean_abs_error"][0] <= 0.2, fwd
moved = max(abs(p["mean_measured"][0]) for p in intruded["phases"])
print("Cyclone without a certificate: measured vx at most %.3f, distance %.2f m" % (moved, intruded["distance_m"]))
assert moved < 0.1 and intruded["distance_m"] < 0.3, intruded
PY
sed 's/^/   cyclone: /' "$work/cyclone.log"
echo "operator programs: all passed"
