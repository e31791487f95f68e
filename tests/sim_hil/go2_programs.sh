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
#      naming the cause.
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

echo "== 2: the HIL in lock-step: stand up and hold, recorded and replayed"
# Without a policy the controller holds until told to stop (--ticks); the HIL ends when it leaves.
"$hil" go2 --domain "$domain" --report "$work/hil2.json" >"$work/hil2.log" 2>&1 &
hil_pid=$!
"$ctl" --robot "$robot" --domain "$domain" --lockstep --lockstep-timeout-ms 100 --no-mlock --ticks 2000 \
  --record "$work/run2.log" >"$work/ctl2b.log" 2>&1 || true
rc=0; wait "$hil_pid" || rc=$?
cat "$work/hil2.log"
[ "$rc" -eq 0 ] || { cat "$work/ctl2b.log"; fail "pbppo-hil go2 exit $rc"; }
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
echo "go2 programs: ok"
