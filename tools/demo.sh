#!/usr/bin/env bash
# The main job: installs what is missing, builds, then runs the AUV end to end: the Simbody HIL
# simulator (pbppo-hil auv, hard layout, lock-step) and the controller (pbppo-controller) with the
# shipped policy as two processes over Fast DDS on loopback. Prints the mission result (targets,
# collisions, time), the controller's supervisor counts and its latency table; writes the
# trajectory plot, the events and the latency profile (JSON + PNG) into build/results/demo/.
# DEMO_LAYOUT=easy|medium|hard and DEMO_SEED=N choose the scenario. Then the quadruped walks its
# demo schedule (stand, forward, sideways, turn, stop) with the shipped walking policy: pbppo-hil
# quadruped --in-process runs the controller (runtime/loop over the CAN transport) and the Simbody
# plant behind the emulated drivers in lock-step; per-phase tracking, plots and the trace. Last the
# Unitree Go2 walks the same schedule with its shipped policy over its own low-level DDS messages:
# pbppo-hil go2 plays the robot (rt/lowstate with its CRC, every rt/lowcmd checked) around a Simbody
# plant, pbppo-controller --robot go2 runs the policy, two processes in lock-step.
set -euo pipefail
cd "$(dirname "$0")/.."
layout="${DEMO_LAYOUT:-hard}"
seed="${DEMO_SEED:-3}"
out=build/results/demo
bash tools/setup.sh >/dev/null
cmake --preset default >/dev/null
cmake --build --preset default -j "$(nproc)" --target pbppo-hil pbppo-controller pbppo >/dev/null
mkdir -p "$out"
rm -f "$out"/*
domain=$((20 + $$ % 200))
blob=policies/frozen/auv_nav/auv_nav.blob
echo "== AUV HIL demo: layout $layout, seed $seed, policy $blob, DDS domain $domain (loopback, lock-step)"
build/default/sim_hil/pbppo-hil auv --layout "$layout" --seed "$seed" --lockstep --domain "$domain" \
  --trajectory "$out/trajectory.csv" --plot "$out/trajectory.png" --events "$out/events.json" \
  > "$out/hil.txt" 2> "$out/hil.err" &
hil=$!
trap 'kill $hil 2>/dev/null || true' EXIT
set +e
build/default/firmware/pbppo-controller --robot models/auv/robot.yaml --policy "$blob" --lockstep \
  --domain "$domain" --profile "$out/profile.json" --profile-plot "$out/profile.png" --quiet \
  > "$out/controller.txt" 2> "$out/controller.err"
crc=$?
wait $hil
hrc=$?
set -e
trap - EXIT
echo
echo "-- vehicle (pbppo-hil auv) --"
cat "$out/hil.txt"
echo
echo "-- controller (pbppo-controller) --"
cat "$out/controller.txt"
grep -v '^$' "$out/controller.err" "$out/hil.err" 2>/dev/null | sed 's/^/   /' || true
echo
echo "files: $out/trajectory.png (trajectory over the map), $out/profile.png (latency histograms),"
echo "       $out/profile.json, $out/events.json, $out/trajectory.csv"
echo
qblob=policies/frozen/quadruped_walk/flat.blob
echo "== Quadruped HIL demo: policy $qblob walking models/quadruped/schedules/demo.yaml on flat ground"
echo "   (controller and Simbody plant in one process, lock-step over the in-process CAN network)"
set +e
build/default/sim_hil/pbppo-hil quadruped --in-process --policy "$qblob" \
  --commands models/quadruped/schedules/demo.yaml --scenario models/quadruped/scenarios/flat.yaml \
  --trace "$out/quadruped_trace.csv" --report "$out/quadruped.json" --plot "$out/quadruped.png"
qrc=$?
set -e
echo "files: $out/quadruped.png (commanded vs measured velocity), $out/quadruped_path.png (base path),"
echo "       $out/quadruped_latency.png (controller tick latency), $out/quadruped.json (per-phase tracking),"
echo "       $out/quadruped_trace.csv"
echo
gblob=policies/frozen/go2_walk/flat.blob
gdomain=$((domain + 1))
echo "== Go2 HIL demo: policy $gblob walking models/go2/schedules/demo.yaml on flat ground"
echo "   (pbppo-hil go2 and pbppo-controller --robot go2 over the robot's rt/lowstate and rt/lowcmd, DDS domain $gdomain, lock-step)"
build/default/sim_hil/pbppo-hil go2 --domain "$gdomain" --commands models/go2/schedules/demo.yaml \
  --trace "$out/go2_trace.csv" --report "$out/go2.json" --plot "$out/go2.png" > "$out/go2_hil.txt" 2>&1 &
ghil=$!
trap 'kill $ghil 2>/dev/null || true' EXIT
set +e
build/default/firmware/pbppo-controller --robot models/go2/robot.yaml --policy "$gblob" \
  --commands models/go2/schedules/demo.yaml --lockstep --domain "$gdomain" --no-mlock \
  --profile "$out/go2_profile.json" --quiet > "$out/go2_controller.txt" 2>&1
gcrc=$?
wait $ghil
ghrc=$?
set -e
trap - EXIT
cat "$out/go2_hil.txt"
grep -q "; no fall" "$out/go2_hil.txt" || ghrc=1  # the Go2 fell (or its run did not finish)
grep -E "^(controller|supervisor|mode change):" "$out/go2_controller.txt" || true
echo "files: $out/go2.png (commanded vs measured velocity), $out/go2_path.png (base path), $out/go2.json,"
echo "       $out/go2_trace.csv, $out/go2_profile.json (controller tick latency), $out/go2_controller.txt"
if [ "$crc" -ne 0 ] || [ "$hrc" -ne 0 ] || [ "$qrc" -ne 0 ] || [ "$gcrc" -ne 0 ] || [ "$ghrc" -ne 0 ]; then
  echo "demo: AUV controller exited $crc, AUV simulator exited $hrc, quadruped HIL exited $qrc," \
    "Go2 controller exited $gcrc, Go2 simulator exited $ghrc" >&2
  exit 1
fi
