#!/usr/bin/env bash
# The Go2 over its own low-level DDS interface (label dds), with pbppo-controller --robot go2:
#   1. a Cyclone DDS program playing the robot (tests/interop/cyclone_go2_robot.c: rt/lowstate with
#      the robot's type names and its own CRC, every rt/lowcmd checked: CRC, header, bounds) and the
#      controller: every command's CRC and bounds hold, the controller reads every state sample's
#      CRC as matching; then one state sample in 200 with a wrong CRC: the controller counts them
#      and stops naming crc_ok;
#   2. the Simbody HIL (pbppo-hil go2) in lock-step: the controller stands the robot up and holds,
#      every command inside the model's limits, no fall; the recording replays bit for bit;
#   3. faults as data in the HIL (a wrong CRC, a NaN or out-of-range position, a motor losing
#      frames, a motor that stops answering, the state stopping):
#      the commands reach damping within 3 periods of the controller's detection, the controller
#      naming the cause;
#   4. the Go2's remote (models/go2_remote) played by the HIL's robot into LowState_: START stands
#      the robot up, DOWN sits it down (passive on its belly), START stands it up again, SELECT is
#      the e-stop; the trunk's heights, no fall, the recording replays bit for bit.
#   5. the shipped walking policy (policies/frozen/go2_walk/flat.blob) on the demo schedule (stand,
#      forward 0.5 m/s, sideways 0.3 m/s, turn in place 0.5 rad/s, stop) in the HIL in lock-step:
#      no fall, every command inside the limits (none clamped: the mode stays nominal), each
#      phase's commanded axis tracked within its bound; the recording replays bit for bit.
# usage: go2_programs.sh HIL CONTROLLER PBPPO CYCLONE_GO2_ROBOT SOURCE_DIR WORK_DIR
set -euo pipefail
hil=$1 ctl=$2 pbppo=$3 cyclone=$4 src=$5 work=$6
source "$src/tests/support/checks.sh"  # fail, expect, fresh_dir, start_in
start_in "$src" "$work"
robot=models/go2/robot.yaml
dds_domain  # sets domain: one no other test holds
export CYCLONEDDS_URI='<CycloneDDS><Domain id="any"><General><Interfaces><NetworkInterface address="127.0.0.1"/></Interfaces><AllowMulticast>false</AllowMulticast></General><Discovery><ParticipantIndex>auto</ParticipantIndex><Peers><Peer address="127.0.0.1"/></Peers></Discovery></Domain></CycloneDDS>'

echo "== 1: the robot's side in Cyclone DDS"
"$cyclone" "$domain" 5 >"$work/cyclone1.log" 2>&1 &
robot_pid=$!
"$ctl" --robot "$robot" --domain "$domain" --duration 3 --no-mlock >"$work/ctl1.log" 2>&1 || true
rc=0; wait "$robot_pid" || rc=$?
cat "$work/cyclone1.log"
[ "$rc" -eq 0 ] || { cat "$work/ctl1.log"; fail "the Cyclone robot refused the controller's commands (exit $rc)"; }
expect "$work/cyclone1.log" "lowcmd received [1-9][0-9]+ crc_ok [1-9][0-9]+ crc_bad 0"
expect "$work/cyclone1.log" "head_bad 0 level_flag_bad 0 bounds_bad 0"
expect "$work/ctl1.log" "transport lowlevel \(dds\): received [1-9][0-9]+ .*checksum mismatches 0"
expect "$work/ctl1.log" "invalid sample 0,"
"$cyclone" "$domain" 5 --bad-crc-every 200 >"$work/cyclone2.log" 2>&1 &
robot_pid=$!
"$ctl" --robot "$robot" --domain "$domain" --duration 3 --no-mlock >"$work/ctl2.log" 2>&1 || true
wait "$robot_pid" || true
expect "$work/ctl2.log" "checksum mismatches [1-9]"
expect "$work/ctl2.log" "mode change: tick [0-9]+: safe-stop: invalid sample: crc_ok = 0"

# The HIL and the controller of ROBOT in lock-step for TICKS, the controller recording RUN; the
# HIL's output in HIL_LOG (printed), the controller's in CTL_LOG; more HIL flags after them.
# Without a policy the controller holds until told to stop (--ticks); the HIL ends when it leaves.
hil_and_controller() {  # ROBOT TICKS RUN HIL_LOG CTL_LOG [HIL FLAGS...]
  local robot_file=$1 ticks=$2 run=$3 hil_log=$4 ctl_log=$5
  shift 5
  "$hil" go2 --robot "$robot_file" --domain "$domain" "$@" >"$hil_log" 2>&1 &
  local pid=$! status=0
  "$ctl" --robot "$robot_file" --domain "$domain" --lockstep --lockstep-timeout-ms 100 --no-mlock --ticks "$ticks" \
    --record "$run" >"$ctl_log" 2>&1 || true
  wait "$pid" || status=$?
  cat "$hil_log"
  [ "$status" -eq 0 ] || { cat "$ctl_log"; fail "pbppo-hil go2 --robot $robot_file exit $status"; }
}

echo "== 2: the HIL in lock-step: stand up and hold, recorded and replayed"
hil_and_controller "$robot" 2000 "$work/run2.log" "$work/hil2.log" "$work/ctl2b.log" --report "$work/hil2.json"
expect "$work/hil2.log" "commands [0-9]+ \(checksum mismatches 0, outside the limits 0\)"
expect "$work/hil2.log" "no fall"
expect "$work/ctl2b.log" "now hold"
"$pbppo" replay "$work/run2.log" --robot "$robot" >"$work/replay2.log" 2>&1 || { cat "$work/replay2.log"; fail "replay"; }
expect "$work/replay2.log" "commands compared, 0 different$"

echo "== 3: faults reach damping"
check_fault() {  # FAULT CAUSE MAX_PERIODS
  "$hil" go2 --domain "$domain" --fault "$1" >"$work/hil3.log" 2>&1 &
  hil_pid=$!
  "$ctl" --robot "$robot" --domain "$domain" --lockstep --lockstep-timeout-ms 100 --no-mlock --ticks 2000 \
    >"$work/ctl3.log" 2>&1 || true
  wait "$hil_pid" || { cat "$work/hil3.log"; fail "fault $1: pbppo-hil go2 failed"; }
  grep "^fault" "$work/hil3.log"
  local after
  after=$(sed -n 's/^fault .*: damping \([0-9]*\) periods after it began$/\1/p' "$work/hil3.log")
  if [ -z "$after" ] || [ "$after" -gt "$3" ]; then fail "fault $1: damping after '${after}' periods (at most $3)"; fi
  expect "$work/ctl3.log" "mode change: tick [0-9]+: $2"
}
check_fault crc@3.0 "safe-stop: invalid sample: crc_ok = 0" 3
check_fault nan@3.0:2 "safe-stop: invalid sample: q_FR_calf = nan" 3
check_fault range@3.0:4 "safe-stop: invalid sample: q_FL_thigh = 10" 3
# A motor's driver counts a lost frame (motor_state[7].lost grows by one per sample).
check_fault lost@3.0:7 "safe-stop: invalid sample: lost_RR_thigh = 1" 3
# A motor stops answering: no torque, its state frozen, its driver counting the frames it lost.
check_fault silent@3.0:11 "safe-stop: invalid sample: lost_RL_calf = 1" 3
# The state stops: detected when stale (degraded after 2 periods) or lost; damping 3 periods after.
check_fault stop@3.0+0.5 "(degraded: stale sample|e-stop: lost peer)" 8
echo "== 4: the Go2's remote (models/go2_remote) in the HIL: stand up, sit down, passive, up again, e-stop"
remote=models/go2_remote/robot.yaml
hil_and_controller "$remote" 6400 "$work/run4.log" "$work/hil4.log" "$work/ctl4.log" \
  --remote models/go2_remote/sessions/stand_sit.yaml --trace "$work/hil4.csv"
grep -E "^(phase|mode change|operator):" "$work/ctl4.log"
expect "$work/ctl4.log" "waiting for the operator to arm \(field 'arm'\)"
expect "$work/ctl4.log" "phase: tick 0: disarmed -> arming"           # START at once
expect "$work/ctl4.log" "phase: tick 2000: hold -> sit-down"           # DOWN at 4.0 s
expect "$work/ctl4.log" "phase: tick 3000: sit-down -> passive"        # 2 s later
expect "$work/ctl4.log" "phase: tick 4000: passive -> stand-up"        # START at 8.0 s
expect "$work/ctl4.log" "phase: tick 5000: stand-up -> hold"
expect "$work/ctl4.log" "mode change: tick 5750: e-stop: e-stop request"  # SELECT at 11.5 s
expect "$work/ctl4.log" "operator: 4 requests, 0 refused"
expect "$work/hil4.log" "outside the limits 0\)"
expect "$work/hil4.log" "no fall"
# The trunk's height (m) and whether it touches the ground, at a time of the trace.
at() { awk -F, -v T="$1" 'NR > 1 && $1 >= T { print $4, $17; exit }' "$work/hil4.csv"; }
check_height() {  # TIME MIN MAX CONTACT WHAT
  local z c
  read -r z c <<<"$(at "$1")"
  echo "  $5 at $1 s: trunk ${z} m, on the ground ${c}"
  awk -v z="$z" -v lo="$2" -v hi="$3" 'BEGIN { exit !(z >= lo && z <= hi) }' || fail "$5: trunk at ${z} m, not in [$2, $3]"
  [ "$c" = "$4" ] || fail "$5: body contact ${c}, expected $4"
}
check_height 3.9 0.25 0.40 0 "standing"
check_height 5.98 0.08 0.16 0 "seated (the sit pose)"
check_height 7.9 0.0 0.08 1 "passive (on its belly)"
check_height 9.9 0.25 0.40 0 "standing again"
"$pbppo" replay "$work/run4.log" --robot "$remote" >"$work/replay4.log" 2>&1 || { cat "$work/replay4.log"; fail "replay"; }
expect "$work/replay4.log" "commands compared, 0 different$"
echo "== 5: the shipped walking policy on the demo schedule, recorded and replayed"
blob=policies/frozen/go2_walk/flat.blob
demo=models/go2/schedules/demo.yaml
"$hil" go2 --domain "$domain" --commands "$demo" --report "$work/hil5.json" >"$work/hil5.log" 2>&1 &
hil_pid=$!
"$ctl" --robot "$robot" --domain "$domain" --policy "$blob" --commands "$demo" --lockstep --lockstep-timeout-ms 100 \
  --no-mlock --record "$work/run5.log" >"$work/ctl5.log" 2>&1 || { cat "$work/ctl5.log"; fail "the controller failed"; }
wait "$hil_pid" || { cat "$work/hil5.log"; fail "pbppo-hil go2 failed"; }
cat "$work/hil5.log"
grep -E "^(controller|supervisor):" "$work/ctl5.log"
expect "$work/hil5.log" "outside the limits 0\)"
expect "$work/hil5.log" "; no fall"
expect "$work/ctl5.log" "final mode nominal"
expect "$work/ctl5.log" "supervisor: command limit 0,"
# Each phase's commanded axis (vx, vy, yaw rate) within its bound, and the robot at rest standing.
python3 - "$work/hil5.json" <<'PY' || fail "tracking (above)"
import json, sys
bounds = {"stand": (0, 0.1), "forward": (0, 0.15), "sideways": (1, 0.2), "turn": (2, 0.2), "stop": (0, 0.1)}
ok = True
for p in json.load(open(sys.argv[1]))["phases"]:
    axis, bound = bounds[p["name"]]
    e = p["mean_abs_error"][axis]
    print("  %-9s |e| %s %.3f (bound %.2f)" % (p["name"], ("vx", "vy", "yaw rate")[axis], e, bound))
    ok &= e <= bound
sys.exit(0 if ok else 1)
PY
"$pbppo" replay "$work/run5.log" --robot "$robot" --policy "$blob" >"$work/replay5.log" 2>&1 ||
  { cat "$work/replay5.log"; fail "replay"; }
expect "$work/replay5.log" "commands compared, 0 different$"
echo "go2 programs: ok"
