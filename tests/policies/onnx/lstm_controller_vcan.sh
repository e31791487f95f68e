#!/usr/bin/env bash
# An imported LSTM walking actor through pbppo-controller as its own process (label vcan: inside
# tests/vm/vcan-vm, or on a host with vcan0/vcan1): pbppo-hil quadruped on flat ground in
# lock-step over SocketCAN, the controller running tools/onnx/make_models.py's lstm_walk.onnx
# (imported here with its mapping) on a short schedule (stand, then 0.5 m/s forward: the VM's
# emulated CPU is about 90 times slower than the host; the schedule's end stops the run, and its
# silence while the robot shuts down is no stale sample: mode nominal at the end) and recording
# the run. The robot walks
# forward upright; the recording replays bit for bit, the LSTM's state carried tick to tick; and
# ONNX Runtime, run on the recorded observations with the state fed back, gives the engine's action
# at every policy step of the run (tests/policies/onnx/lstm_vs_ort.sh).
# usage: lstm_controller_vcan.sh PBPPO HIL CONTROLLER SOURCE_DIR MODELS_DIR WORK_DIR
set -euo pipefail
pbppo=$1 hil=$2 ctl=$3 src=$4 models=$5 work=$6
source "$src/tests/support/checks.sh"  # fail, expect, fresh_dir, start_in
source "$src/tests/policies/onnx/lstm_vs_ort.sh"  # lstm_vs_ort
start_in "$src" "$work"
can=${PBPPO_VCAN0:-vcan0},${PBPPO_VCAN1:-vcan1}
"$pbppo" import-onnx "$models/lstm_walk.onnx" --robot models/quadruped/robot.yaml --map "$models/lstm_walk.yaml" \
  --out "$work/lstm_walk.blob" >"$work/import.log" 2>&1 || { cat "$work/import.log"; fail "import-onnx exited $?"; }
cat >"$work/schedule.yaml" <<'YAML'
stream: velocity_command
phases:
  - {name: stand, duration_s: 1.5}
  - {name: forward, duration_s: 3.0, command_vx: 0.5}
YAML
"$hil" quadruped --can "$can" --lockstep >"$work/hil.log" 2>&1 &
hil_pid=$!
sleep 1
rc=0
"$ctl" --robot quadruped --can "$can" --policy "$work/lstm_walk.blob" --commands "$work/schedule.yaml" \
  --duration 4.5 --lockstep-wait-ms 2000 --record "$work/run.log" --quiet >"$work/ctl.log" 2>&1 || rc=$?
kill -INT "$hil_pid"
wait "$hil_pid" || { cat "$work/hil.log"; fail "pbppo-hil exited $?"; }
cat "$work/ctl.log"
[ "$rc" -eq 0 ] || fail "pbppo-controller exited $rc"
expect "$work/ctl.log" "hold -> run"
# Upright throughout: the supervisor's tilt limit (models/quadruped: 60 degrees) never tripped.
expect "$work/ctl.log" "final mode nominal"
expect "$work/ctl.log" "signal limit 0,"
# Walked forward: the base 0.5 m or more ahead of its start (where it lay down after the stop).
grep "base at" "$work/hil.log" | sed 's/^/   hil:/'
awk '/base at/ { gsub(/[(),]/, " "); if ($3 >= 0.5) ok = 1 } END { exit ok ? 0 : 1 }' "$work/hil.log" ||
  fail "the LSTM did not walk forward over vcan"
lstm_vs_ort "$models/lstm_walk.onnx" "$work/lstm_walk.blob" "$work/run.log" "$work" lstm_vcan
[ "$lstm_steps" -ge 100 ] || fail "only $lstm_steps policy steps recorded"
echo "lstm_controller_vcan: OK"
