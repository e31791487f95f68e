#!/usr/bin/env bash
# ONNX import end to end (label onnx), on the onnx.models fixture's models:
#   1. pbppo import-onnx writes each good model's blob and golden vectors; the blob's provenance
#      names the file's SHA-256 and the producer; the blob arms (its golden vectors pass);
#   2. every bad model is refused naming the node (or input, output, initializer, file), and no
#      file is written; a mapping that does not fit the model or the robot is refused naming both;
#   3. the imported stable-baselines3-style AUV actor flies the AUV missions through
#      pbppo-controller and pbppo-hil auv over Fast DDS (lock-step) as the shipped blob does;
#   4. the imported rsl_rl-style walking actor walks the demo schedule in the quadruped HIL with
#      the shipped flat policy's figures (no code change: the same programs, another blob).
# usage: import_end_to_end.sh PBPPO HIL CONTROLLER SOURCE_DIR MODELS_DIR WORK_DIR
set -euo pipefail
pbppo=$1 hil=$2 ctl=$3 src=$4 models=$5 work=$6
source "$src/tests/support/checks.sh"  # fail, expect, fresh_dir, start_in
start_in "$src" "$work"
quad=models/quadruped/robot.yaml auv=models/auv/robot.yaml
dds_domain  # sets domain: one no other test holds

echo "== 1: the good models import"
import() {  # import NAME ROBOT
  "$pbppo" import-onnx "$models/$1.onnx" --robot "$2" --map "$models/$1.yaml" --out "$work/$1.blob" \
    >"$work/$1.import.log" 2>&1 || { cat "$work/$1.import.log"; fail "$1: import-onnx exited $?"; }
  [ -s "$work/$1.blob" ] && [ -s "$work/$1.golden" ] || fail "$1: blob or golden vectors missing"
  local sha
  sha=$(sha256sum "$models/$1.onnx" | cut -d' ' -f1)
  "$pbppo" inspect --json "$work/$1.blob" >"$work/$1.json"
  expect "$work/$1.json" "\"environment\": \"onnx $1.onnx sha256 $sha opset 17 ir 8\""
  expect "$work/$1.json" "\"trainer_version\": \"pytorch 2.1.0 via ONNX\""
  sed 's/^/   /' "$work/$1.import.log"
}
import rsl_rl_walk "$quad"
expect "$work/rsl_rl_walk.import.log" "45 layout observations, 3 constants folded"
import normalised_walk "$quad"
expect "$work/normalised_walk.import.log" "normaliser: +Sub .*Div .*Clip .*clip at 100 -> the blob's"
import sb3_auv "$auv"
expect "$work/sb3_auv.import.log" "output map: +Clip"

echo "== 2: refusals"
refuse() {  # refuse MODEL MAP ROBOT PATTERN
  local rc=0 log="$work/refused.log"
  rm -f "$work/refused.blob"
  "$pbppo" import-onnx "$1" --robot "$3" --map "$2" --out "$work/refused.blob" >"$log" 2>&1 || rc=$?
  [ "$rc" -eq 1 ] || { cat "$log"; fail "$1: exit $rc, expected 1"; }
  [ ! -e "$work/refused.blob" ] && [ ! -e "$work/refused.golden" ] || fail "$1: a refused import wrote a file"
  expect "$log" "$4"
  sed 's/^/   /' "$log"
}
m=$models/rsl_rl_walk.yaml b=$models/bad
refuse "$b/truncated.onnx" "$m" "$quad" "truncated.onnx: not an ONNX model"
refuse "$b/garbage.onnx" "$m" "$quad" "garbage.onnx: not an ONNX model"
refuse "$b/unsupported_op.onnx" "$m" "$quad" "node 'actor.softmax' \(Softmax\): operator not supported"
refuse "$b/recurrent.onnx" "$m" "$quad" "node '/memory_a/rnn/LSTM' \(LSTM\): a recurrent"
refuse "$b/dynamic_dim.onnx" "$m" "$quad" "input 'obs' dimension 1 is symbolic \('n_obs'\)"
refuse "$b/float16.onnx" "$m" "$quad" "node '/actor/actor.2/Gemm' \(Gemm\): constant 'actor.2.weight' is float16"
refuse "$b/elu_alpha.onnx" "$m" "$quad" "node '/actor/actor.1/Elu' \(Elu\): alpha 0.5"
refuse "$b/weight_as_input.onnx" "$m" "$quad" "'actor.0.weight' used by node '/actor/actor.0/Gemm' \(Gemm\) input 1"
refuse "$b/gemm_transA.onnx" "$m" "$quad" "node '/actor/actor.2/Gemm' \(Gemm\): transA 1"
refuse "$b/two_outputs.onnx" "$m" "$quad" "2 graph outputs \('actions', 'values'\)"
refuse "$b/external_data.onnx" "$m" "$quad" "tensor 'actor.0.weight' keeps its data in an external file"
refuse "$b/branching.onnx" "$m" "$quad" "value '/actor/actor.1/Elu_output_0' feeds 2 nodes"
refuse "$b/shape_mismatch.onnx" "$m" "$quad" "node '/actor/actor.2/Gemm' \(Gemm\): weight 'actor.2.weight' \[2, 6\]"
refuse "$models/rsl_rl_walk.onnx" "$models/normalised_walk.yaml" "$quad" \
  "normalised_walk.yaml: input: 'obs' of 45 elements, but .*rsl_rl_walk.onnx takes 'obs' of 48"
refuse "$models/sb3_auv.onnx" "$models/sb3_auv.yaml" "$quad" \
  "sb3_auv.yaml: robot: 'auv', but the robot's IO layout is for 'quadruped'"
refuse "$work/none.onnx" "$m" "$quad" "none.onnx: cannot open"

echo "== 3: the imported AUV actor flies the missions through pbppo-controller (lock-step, Fast DDS)"
mission() {  # mission NAME BLOB LAYOUT SEED
  "$hil" auv --layout "$3" --seed "$4" --lockstep --domain "$domain" --trajectory "$work/$1.csv" \
    >"$work/$1.hil.log" 2>&1 &
  local pid=$! rc=0
  "$ctl" --robot "$auv" --policy "$2" --lockstep --domain "$domain" --quiet >"$work/$1.ctl.log" 2>&1 || rc=$?
  wait "$pid" || fail "$1: pbppo-hil exited $?: $(cat "$work/$1.hil.log")"
  [ "$rc" -eq 0 ] || fail "$1: pbppo-controller exited $rc: $(cat "$work/$1.ctl.log")"
  expect "$work/$1.ctl.log" "final mode nominal"
}
for m in easy:2 hard:3; do
  layout=${m%%:*} seed=${m##*:}
  mission "shipped_$layout" policies/frozen/auv_nav/auv_nav.blob "$layout" "$seed"
  mission "imported_$layout" "$work/sb3_auv.blob" "$layout" "$seed"
  expect "$work/imported_$layout.hil.log" "success after .* 3/3 targets"
  printf '   %s seed %s: shipped: %s\n   %s seed %s: imported: %s\n' "$layout" "$seed" \
    "$(sed -n 2p "$work/shipped_$layout.hil.log")" "$layout" "$seed" "$(sed -n 2p "$work/imported_$layout.hil.log")"
done

echo "== 4: the imported rsl_rl actor walks in the quadruped HIL"
walk() {  # walk NAME BLOB
  "$hil" quadruped --in-process --policy "$2" --commands models/quadruped/schedules/demo.yaml \
    --report "$work/$1.json" >"$work/$1.log" 2>&1 || { cat "$work/$1.log"; fail "$1: pbppo-hil exited $?"; }
  expect "$work/$1.log" "no fall"
  sed -n '2,8p' "$work/$1.log" | sed "s/^/   $1: /"
}
walk shipped_flat policies/frozen/quadruped_walk/flat.blob
walk imported_rsl_rl "$work/rsl_rl_walk.blob"
# The same figures as the shipped policy's, phase by phase, within 0.02 (the two differ by float32
# rounding: a 512-wide network and folded constants).
/usr/bin/python3 - "$work/shipped_flat.json" "$work/imported_rsl_rl.json" <<'PY'
import json, sys
a, b = (json.load(open(p)) for p in sys.argv[1:3])
def rows(r):
    return {p["name"]: p for p in r["phases"]}
ra, rb = rows(a), rows(b)
worst = 0.0
for name, p in ra.items():
    for k in range(3):
        worst = max(worst, abs(p["mean_abs_error"][k] - rb[name]["mean_abs_error"][k]))
print(f"   largest per-phase tracking difference, imported vs shipped: {worst:.4f}")
sys.exit(0 if worst <= 0.02 else 1)
PY
echo "import end to end: ok"
