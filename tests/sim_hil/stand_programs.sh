#!/usr/bin/env bash
# The two programs over vcan (label vcan): pbppo-hil in lock-step and pbppo-controller
# (--robot models/quadruped/robot.yaml) waiting for each tick's replies.
# 1) --duration: arming, stand-up, hold, damping, motor off -> exit 0.
# 2) SIGINT during the trajectory -> damping -> motor off -> exit 0.
# 3) the controller killed (SIGKILL) while standing up, its motors left enabled; then
#    --safe-stop (what the service runs after any end): damping -> motor off -> exit 0.
# 4) the gamepad robot (--robot quadruped_gamepad, a recorded session as --gamepad): the
#    controller waits for START, stands up, walks on A with LB held, and says the requests.
# usage: stand_programs.sh HIL CONTROLLER SOURCE_DIR WORK_DIR
set -euo pipefail
hil=$1 ctl=$2 src=$3 work=$4
can=${PBPPO_VCAN0:-vcan0},${PBPPO_VCAN1:-vcan1}
mkdir -p "$work"
cd "$src"

run_hil() {
  "$hil" quadruped --stand --can "$can" --lockstep >"$work/hil.$1.log" 2>&1 &
  hil_pid=$!
  sleep 1
}
stop_hil() {
  kill -INT "$hil_pid"
  wait "$hil_pid" || { echo "pbppo-hil exited with $?"; cat "$work/hil.$1.log"; exit 1; }
  cat "$work/hil.$1.log"
}

# start_trajectory N PHASE: the controller on the stand trajectory (ctl_pid), 1 s into PHASE.
start_trajectory() {
  "$ctl" --robot models/quadruped/robot.yaml --can "$can" --trajectory models/quadruped/stand_trajectory.yaml \
    --lockstep-wait-ms 2000 >"$work/ctl.$1.log" 2>&1 &
  ctl_pid=$!
  for _ in $(seq 1 3000); do
    grep -q -- "now $2" "$work/ctl.$1.log" 2>/dev/null && break
    sleep 0.1
  done
  sleep 1
}

echo "== 1: --duration 1.3"
run_hil 1
rc=0
"$ctl" --robot models/quadruped/robot.yaml --can "$can" --duration 1.3 --lockstep-wait-ms 2000 >"$work/ctl.1.log" 2>&1 || rc=$?
cat "$work/ctl.1.log"
stop_hil 1
[ "$rc" -eq 0 ] || { echo "controller exited with $rc"; exit 1; }
grep -q "hold -> damping" "$work/ctl.1.log"
grep -q "motor-off -> done" "$work/ctl.1.log"
grep -q "final mode nominal" "$work/ctl.1.log"
grep -Eq "LF_HAA .* motor_mode 0" "$work/hil.1.log"

echo "== 2: SIGINT during the trajectory"
run_hil 2
start_trajectory 2 run
kill -INT "$ctl_pid"
rc=0
wait "$ctl_pid" || rc=$?
cat "$work/ctl.2.log"
stop_hil 2
[ "$rc" -eq 0 ] || { echo "controller exited with $rc"; exit 1; }
grep -q "run -> damping" "$work/ctl.2.log"
grep -q "motor-off -> done" "$work/ctl.2.log"

echo "== 3: killed while standing up, then --safe-stop"
run_hil 3
start_trajectory 3 stand-up  # the motors are on from here
kill -KILL "$ctl_pid"
wait "$ctl_pid" 2>/dev/null || true
rc=0
"$ctl" --robot quadruped --can "$can" --safe-stop --lockstep-wait-ms 2000 >"$work/ctl.3s.log" 2>&1 || rc=$?
cat "$work/ctl.3s.log"
stop_hil 3
[ "$rc" -eq 0 ] || { echo "--safe-stop exited with $rc"; exit 1; }
grep -q "quadruped: safe stop" "$work/ctl.3s.log"
grep -q "disarmed -> damping" "$work/ctl.3s.log"
grep -q "motor-off -> done" "$work/ctl.3s.log"
grep -q "stopped by --safe-stop, its stop done" "$work/ctl.3s.log"
[ "$(grep -Ec "motor_mode 0" "$work/hil.3.log")" -eq 12 ] || { echo "not every motor off after --safe-stop"; exit 1; }
echo "== 4: the gamepad robot: waiting for START, then the session's requests"
run_hil 4
rc=0
"$ctl" --robot quadruped_gamepad --can "$can" --policy policies/frozen/quadruped_walk/flat.blob \
  --gamepad models/quadruped_gamepad/sessions/demo.ev --duration 3 --lockstep-wait-ms 2000 >"$work/ctl.4.log" 2>&1 ||
  rc=$?
cat "$work/ctl.4.log"
stop_hil 4
[ "$rc" -eq 0 ] || { echo "controller exited with $rc"; exit 1; }
grep -q "waiting for the operator to arm (field 'arm')" "$work/ctl.4.log"
grep -q "disarmed -> arming" "$work/ctl.4.log"
grep -q "hold -> run" "$work/ctl.4.log"
grep -q "operator: 2 requests, 0 refused" "$work/ctl.4.log"
grep -q "motor-off -> done" "$work/ctl.4.log"
echo "stand_programs: OK"
