#!/usr/bin/env bash
# The checklist for a new robot (docs/architecture.md), followed by a robot that exists only as
# data: the slider (tests/data/slider: robot file, IO layout, two messages' IDL) over DDS,
# with its tiny plant (slider_plant, the only C++ it has). Label dds.
#   1. a test policy for its layout (pbppo synth --layout);
#   2. pbppo-controller runs it in lock-step against the plant until the plant's end field, with
#      no allocation, nominal, recording; run twice, the plant's trajectories are the same;
#   3. pbppo replay reproduces every command of the recording bit for bit;
#   4. a bad robot file is refused naming the file, the field and the value.
# usage: checklist.sh PBPPO CONTROLLER SLIDER_PLANT SOURCE_DIR WORK_DIR
set -euo pipefail
pbppo=$1 ctl=$2 plant=$3 src=$4 work=$5
source "$src/tests/support/checks.sh"  # fail, expect, fresh_dir, start_in
start_in "$src" "$work"
robot=tests/data/slider/robot.yaml
dds_domain  # sets domain: one no other test holds

echo "== 1: a test policy for the slider's layout"
"$pbppo" synth --layout tests/data/slider/io_layout.yaml --widths 3-16-1 --activation tanh --seed 5 \
  --out "$work/slider.blob" >"$work/synth.log"
"$pbppo" inspect "$work/slider.blob" >"$work/inspect.log"
expect "$work/inspect.log" "position"
expect "$work/inspect.log" "force .*range \[-2, 2\]"

echo "== 2: lock-step through pbppo-controller, recorded, twice"
for run in 1 2; do
  "$plant" "$robot" "$domain" 300 "$work/plant$run.csv" >"$work/plant$run.log" 2>&1 &
  ppid=$!
  # Compared byte for byte: no tick without its sample, however loaded the machine.
  "$ctl" --robot "$robot" --policy "$work/slider.blob" --lockstep --lockstep-timeout-ms 20000 --domain "$domain" --quiet \
    --record "$work/run$run.log" >"$work/ctl$run.log" 2>&1 || { cat "$work/ctl$run.log"; fail "pbppo-controller"; }
  wait "$ppid" || { cat "$work/plant$run.log"; fail "slider_plant exited $?"; }
  expect "$work/ctl$run.log" "controller: 301 ticks \(lock-step\), final mode nominal"
  expect "$work/ctl$run.log" "stopped by the end field done"
  expect "$work/ctl$run.log" "control thread heap allocations during the loop: 0$"
  expect "$work/ctl$run.log" "transport link \(dds\): received 301 \(malformed 0\)"
  expect "$work/ctl$run.log" "log: .*run$run.log, [0-9]+ records, 0 dropped"
  expect "$work/plant$run.log" "slider_plant: 300 ticks"
done
cmp "$work/plant1.csv" "$work/plant2.csv" || fail "two runs of the same policy moved the cart differently"
# The policy pushed the cart: its forces are not all zero and within the robot file's range.
/usr/bin/python3 - "$work/plant1.csv" <<'PY'
import csv, sys
rows = list(csv.DictReader(open(sys.argv[1])))
forces = [float(r["force_n"]) for r in rows]
assert len(rows) == 300, len(rows)
assert max(abs(f) for f in forces) > 0.01, "no force"
assert all(abs(f) <= 2.0 for f in forces), max(forces)
assert all(abs(float(r["x_m"])) < 1.0 for r in rows)
print("slider: 300 ticks, force in [%.3f, %.3f] N" % (min(forces), max(forces)))
PY

echo "== 3: replay"
"$pbppo" replay "$work/run1.log" --robot "$robot" --policy "$work/slider.blob" >"$work/replay.log" 2>&1 ||
  { cat "$work/replay.log"; fail "replay"; }
expect "$work/replay.log" "replay: .*run1.log: 301 ticks, [0-9]+ commands compared, 0 different$"

echo "== 4: a bad robot file"
mkdir -p "$work/bad"
cp -r tests/data/slider/idl tests/data/slider/io_layout.yaml "$work/bad/"
sed -e 's|force_n: command.force|force_n: command.thrust|' -e 's|\.\./\.\./\.\./models|'"$src"'/models|' \
  "$robot" >"$work/bad/robot.yaml"
rc=0; "$ctl" --robot "$work/bad/robot.yaml" --policy "$work/slider.blob" >"$work/bad.log" 2>&1 || rc=$?
[ "$rc" -eq 2 ] || fail "a bad robot file: exit $rc"
expect "$work/bad.log" "robot.yaml: transports\[0\].messages\[1\].values.force_n: 'command.thrust' is not a value"
echo "checklist: all checks passed"
