#!/usr/bin/env bash
# A CAN robot that exists only as data (tests/data/diffbot: two continuous, velocity-commanded
# wheels, a pan head, an IMU) through the real programs over vcan (label vcan): pbppo-hil rotors
# (the generic rotor plant) in lock-step and pbppo-controller with a policy that pbppo synth made
# for the robot's io_layout, recording every input and command; then pbppo replay of the log
# (bit for bit) and another policy refused.
# usage: diffbot_programs.sh HIL CONTROLLER PBPPO SOURCE_DIR WORK_DIR
set -euo pipefail
hil=$1 ctl=$2 pbppo=$3 src=$4 work=$5
can=${PBPPO_VCAN0:-vcan0}
robot=tests/data/diffbot/robot.yaml
mkdir -p "$work"
rm -f "$work"/*.log
cd "$src"

"$pbppo" synth --layout tests/data/diffbot/io_layout.yaml --widths 10-16-3 --activation tanh --seed 7 \
  --out "$work/diffbot.blob"

"$hil" rotors --robot "$robot" --can "$can" --lockstep >"$work/hil.log" 2>&1 &
hil_pid=$!
sleep 1
rc=0
# 500 ticks: arming, stand-up (100), hold (50), the policy, then damping (50) and motor off.
"$ctl" --robot "$robot" --can "$can" --policy "$work/diffbot.blob" --ticks 500 --lockstep-wait-ms 2000 \
  --record "$work/diffbot.log" >"$work/ctl.log" 2>&1 || rc=$?
cat "$work/ctl.log"
kill -INT "$hil_pid"
wait "$hil_pid" || { echo "pbppo-hil exited with $?"; cat "$work/hil.log"; exit 1; }
cat "$work/hil.log"
[ "$rc" -eq 0 ] || { echo "controller exited with $rc"; exit 1; }
grep -q "diffbot on $can, with a policy" "$work/ctl.log"
grep -q "stand-up -> hold" "$work/ctl.log"
grep -q "hold -> run" "$work/ctl.log"
grep -q "run -> damping" "$work/ctl.log"
grep -q "motor-off -> done" "$work/ctl.log"
grep -q "final mode nominal" "$work/ctl.log"
grep -q "control thread heap allocations during the loop: 0" "$work/ctl.log"
grep -Eq "log: .*, [0-9]+ records, 0 dropped" "$work/ctl.log"
for joint in left_wheel right_wheel head_pan; do
  grep -Eq "$joint +frames [1-9][0-9]* replies [1-9][0-9]* dropped 0 watchdog 0 motor_mode 0" "$work/hil.log"
done
# The wheels (a cruise of 10 rad/s) turned past their drivers' range end (pi): the controller
# stayed nominal on the unwrapped angle.
for joint in left_wheel right_wheel; do
  awk -v j="$joint" '$1 == j { for (i = 1; i < NF; ++i) if ($i == "q") q = $(i + 1) } END { exit !(q > 3.2) }' \
    "$work/hil.log" || { echo "$joint did not turn past pi"; exit 1; }
done

# The recorded run replays to the same commands, bit for bit.
"$pbppo" replay "$work/diffbot.log" --robot "$robot" --policy "$work/diffbot.blob" | tee "$work/replay.txt"
grep -Eq "replay: .*: [1-9][0-9]* ticks, [1-9][0-9]* commands compared, 0 different" "$work/replay.txt"
# Another policy is refused, naming what differs.
"$pbppo" synth --layout tests/data/diffbot/io_layout.yaml --widths 10-16-3 --activation tanh --seed 8 \
  --out "$work/other.blob" >/dev/null
rc=0
"$pbppo" replay "$work/diffbot.log" --robot "$robot" --policy "$work/other.blob" >"$work/replay_other.txt" 2>&1 ||
  rc=$?
cat "$work/replay_other.txt"
[ "$rc" -eq 1 ] || { echo "replay with another policy exited with $rc"; exit 1; }
grep -q "another policy or trajectory" "$work/replay_other.txt"
echo "diffbot_programs: OK"
