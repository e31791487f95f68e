# Sourced by the ONNX import tests (needs fail and expect from tests/support/checks.sh, and $pbppo):
# lstm_vs_ort MODEL.onnx BLOB LOG WORK NAME: the recorded run LOG of the imported LSTM BLOB replays
# bit for bit (pbppo replay, every command), and each recorded policy step, run by ONNX Runtime
# (tools/onnx/ort_eval.js) on the recorded observations with the state fed back from the start,
# gives the engine's action within 1e-5 relative (the import check's tolerance is at least that).
# Sets lstm_steps: the number of policy steps compared.
# The model's inputs are the layout's observations in order and its outputs the actions in order
# (lstm_walk.yaml), so the recorded observation is the model's input and the engine's action the
# blob's action map of its output.
lstm_vs_ort() {
  local model=$1 blob=$2 log=$3 work=$4 name=$5 steps
  "$pbppo" replay "$log" --robot models/quadruped/robot.yaml --policy "$blob" --policy-io "$work/${name}_io" \
    >"$work/${name}_replay.log" 2>&1 || { cat "$work/${name}_replay.log"; fail "$name: pbppo replay exited $?"; }
  expect "$work/${name}_replay.log" "commands compared, 0 different$"
  sed 's/^/   /' "$work/${name}_replay.log"
  steps=$(($(stat -c %s "$work/${name}_io.obs.f32") / (45 * 4)))
  node tools/onnx/ort_eval.js "$model" "$work/${name}_io.obs.f32" "$steps" "$work/${name}_ort.f32" \
    h_in=h_out c_in=c_out || fail "$name: ort_eval.js exited $?"
  "$pbppo" inspect --json "$blob" >"$work/${name}_blob.json"
  /usr/bin/python3 - "$work" "$name" "$steps" <<'PY' || fail "$name: the engine's actions are not ONNX Runtime's"
import json, sys
import numpy as np
work, name, steps = sys.argv[1], sys.argv[2], int(sys.argv[3])
m = json.load(open(f"{work}/{name}_blob.json"))["action_map"]
y = np.fromfile(f"{work}/{name}_ort.f32", "<f4").reshape(steps, 12).astype(np.float64)
engine = np.fromfile(f"{work}/{name}_io.act.f32", "<f4").reshape(steps, 12).astype(np.float64)
ort = np.clip(y * np.array(m["scale"]) + np.array(m["offset"]), m["low"], m["high"])
rel = np.abs(engine - ort) / np.maximum(1.0, np.abs(ort))
print(f"   {steps} policy steps: engine vs ONNX Runtime max |diff| {np.abs(engine - ort).max():.3g} "
      f"(relative {rel.max():.3g}; the import check's tolerance is at least 1e-5 relative)")
sys.exit(0 if rel.max() <= 1e-5 else 1)
PY
  lstm_steps=$steps
}
