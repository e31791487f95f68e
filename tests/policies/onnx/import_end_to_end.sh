#!/usr/bin/env bash
# ONNX import end to end (label onnx), on the onnx.models fixture's models:
#   1. pbppo import-onnx writes each good model's blob and golden vectors; the blob's provenance
#      names the file's SHA-256 and the producer; the blob arms (its golden vectors pass);
#   2. every bad model is refused naming the node (or input, output, initializer, file), and no
#      file is written; a mapping that does not fit the model or the robot is refused naming both;
#   3. the imported stable-baselines3-style AUV actor flies the AUV missions through
#      pbppo-controller and pbppo-hil auv over Fast DDS (lock-step) as the shipped blob does;
#   4. the imported rsl_rl-style walking actor walks the demo schedule in the quadruped HIL with
#      the shipped flat policy's figures (no code change: the same programs, another blob);
#   5. the imported walking LSTM walks the demo schedule in the quadruped HIL (the controller's
#      loop in process, its state carried tick to tick), as the shipped flat policy does; the
#      recorded run replays bit for bit, and each of its 800-odd policy steps, run by ONNX Runtime
#      on the recorded observations with the state fed back, gives the engine's action;
#   6. a policy exported with unitree_rl_lab's deploy.yaml (joints in another order, two frames of
#      history on some terms) imports with --deploy alone: the IO layout and mapping it writes,
#      put in a copy of the robot's folder, walk the demo schedule as the shipped policy does;
#      deploy files the layout cannot express are refused naming the field; the same policy's
#      Isaac Lab env.yaml (with its joint order given) gives the same layout and blob; the run's
#      rsl_rl agent.yaml beside it is checked against the graph (a normaliser left out, another
#      run's widths refused) and its clip_actions narrows the targets.
# usage: import_end_to_end.sh PBPPO HIL CONTROLLER SOURCE_DIR MODELS_DIR WORK_DIR
set -euo pipefail
pbppo=$1 hil=$2 ctl=$3 src=$4 models=$5 work=$6
source "$src/tests/support/checks.sh"  # fail, expect, fresh_dir, start_in
source "$src/tests/policies/onnx/lstm_vs_ort.sh"  # lstm_vs_ort
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
import lstm_walk "$quad"
expect "$work/lstm_walk.import.log" "128 -> 64 lstm .*state h_in\[0\] -> h_out\[0\], c_in\[0\] -> c_out\[0\]"
import gru_actor "$quad"
expect "$work/gru_actor.import.log" "45 -> 32 gru \(linear_before_reset\)"
import gru_lbr0 "$quad"
expect "$work/gru_lbr0.import.log" "normaliser: +Sub .*Div .* -> the blob's"
import lstm_stacked "$quad"
expect "$work/lstm_stacked.import.log" "24 -> 24 lstm .*state h_in\[1\] -> h_out\[1\], c_in\[1\] -> c_out\[1\]"
"$pbppo" inspect "$work/lstm_walk.blob" >"$work/lstm_walk.inspect"
expect "$work/lstm_walk.inspect" "format      v2, "
expect "$work/lstm_walk.inspect" "state       128 floats carried from one step to the next"

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
refuse "$b/recurrent.onnx" "$m" "$quad" "node '/memory_a/rnn/LSTM' \(LSTM\): no initial_h: the state would start from zero"
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
r=$b/recurrent.yaml
refuse "$b/lstm_state_not_wired.onnx" "$r" "$quad" \
  "node '/memory_a/rnn/LSTM' \(LSTM\): Y_h '/memory_a/rnn/LSTM_output_1' reaches no graph output"
refuse "$b/lstm_state_swapped.onnx" "$r" "$quad" \
  "node '/memory_a/rnn/LSTM' \(LSTM\): initial_h is read from 'h_in' but the node's next state goes to 'c_out'"
refuse "$b/lstm_hidden_mismatch.onnx" "$r" "$quad" \
  "node '/memory_a/rnn/LSTM' \(LSTM\): initial_h: state 'h_in' has size 16, the node's hidden_size is 8"
refuse "$b/lstm_bidirectional.onnx" "$r" "$quad" "node '/memory_a/rnn/LSTM' \(LSTM\): direction 'bidirectional'"
refuse "$b/lstm_peephole.onnx" "$r" "$quad" "node '/memory_a/rnn/LSTM' \(LSTM\): peepholes"
refuse "$models/gru_actor.onnx" "$models/lstm_walk.yaml" "$quad" \
  "lstm_walk.yaml: state\[1\].input: 'c_in' is not a graph input of .*gru_actor.onnx"
refuse "$models/lstm_walk.onnx" "$models/rsl_rl_walk.yaml" "$quad" \
  "lstm_walk.onnx: 3 graph inputs \('obs' used by node '/actor_in/Gemm' \(Gemm\) input 0; 'h_in' used by node"

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
# like_shipped NAME LIMIT: NAME's per-phase tracking errors within LIMIT of the shipped flat policy's.
like_shipped() {
  /usr/bin/python3 - "$work/shipped_flat.json" "$work/$1.json" "$1" "$2" <<'PY'
import json, sys
a, b = (json.load(open(p)) for p in sys.argv[1:3])
ra, rb = ({p["name"]: p for p in r["phases"]} for r in (a, b))
worst = max(abs(p["mean_abs_error"][k] - rb[n]["mean_abs_error"][k]) for n, p in ra.items() for k in range(3))
print(f"   largest per-phase tracking difference, {sys.argv[3]} vs shipped flat: {worst:.4f}")
sys.exit(0 if worst <= float(sys.argv[4]) else 1)
PY
}
# The same figures as the shipped policy's, phase by phase, within 0.02 (the two differ by float32
# rounding: a 512-wide network and folded constants).
like_shipped imported_rsl_rl 0.02 || fail "imported_rsl_rl does not walk as the shipped policy"
echo "== 5: the imported LSTM walks in the quadruped HIL, replays bit for bit, acts as ONNX Runtime"
"$hil" quadruped --in-process --policy "$work/lstm_walk.blob" --commands models/quadruped/schedules/demo.yaml \
  --report "$work/imported_lstm.json" --record "$work/lstm_run.log" >"$work/imported_lstm.log" 2>&1 ||
  { cat "$work/imported_lstm.log"; fail "imported_lstm: pbppo-hil exited $?"; }
expect "$work/imported_lstm.log" "no fall"
sed -n '2,8p' "$work/imported_lstm.log" | sed "s/^/   imported_lstm: /"
lstm_vs_ort "$models/lstm_walk.onnx" "$work/lstm_walk.blob" "$work/lstm_run.log" "$work" lstm
[ "$lstm_steps" -ge 800 ] || fail "only $lstm_steps policy steps recorded"
# A rotated recording: each file begins with the loop's state, the LSTM's h and c among it, and
# replays alone from there (mid-walk).
"$hil" quadruped --in-process --policy "$work/lstm_walk.blob" --commands models/quadruped/schedules/demo.yaml \
  --record "$work/lstm_rot.log" --record-max-mb 0.5 --record-rotate 3 >"$work/lstm_rot_hil.txt" 2>&1 ||
  { cat "$work/lstm_rot_hil.txt"; fail "rotated recording: pbppo-hil exited $?"; }
kept=$(ls "$work"/lstm_rot.*.log | wc -l)
[ "$kept" -eq 3 ] || fail "rotated recording: $kept files kept, expected 3"
for f in "$work"/lstm_rot.*.log; do
  "$pbppo" replay "$f" --robot "$quad" --policy "$work/lstm_walk.blob" >"$work/lstm_rot_replay.txt" 2>&1 ||
    { cat "$work/lstm_rot_replay.txt"; fail "$f: replay"; }
  expect "$work/lstm_rot_replay.txt" "commands compared, 0 different$"
  expect "$work/lstm_rot_replay.txt" "replayed from its snapshot at tick"
  sed -n 2p "$work/lstm_rot_replay.txt" | sed 's/^/   /'
done
# As the shipped flat policy walks (the LSTM is built from it), phase by phase within 0.03.
like_shipped imported_lstm 0.03 || fail "the imported LSTM does not walk as the shipped policy"
echo "== 6: a unitree_rl_lab deploy.yaml in place of a mapping"
"$pbppo" import-onnx "$models/unitree_walk.onnx" --robot "$quad" --deploy "$models/unitree_walk.deploy.yaml" \
  --out "$work/unitree_walk.blob" >"$work/unitree_walk.import.log" 2>&1 ||
  { cat "$work/unitree_walk.import.log"; fail "unitree_walk: import-onnx --deploy exited $?"; }
sed 's/^/   /' "$work/unitree_walk.import.log"
expect "$work/unitree_walk.import.log" "6 observation terms, 45 layout observations, 12 joint position actions"
expect "$work/unitree_walk.import.log" "history: +2 frames, term-major, oldest first"
expect "$work/unitree_walk.map.yaml" "q_LF_HAA, q_RF_HAA, q_LH_HAA, q_RH_HAA, q_LF_HFE"
expect "$work/unitree_walk.io_layout.yaml" "name: base_ang_vel_x, signal: base_ang_vel_x, scale: 0.25, clip: 25, history: 2"
# The robot's folder with the deploy file's layout in place of its own (the blob carries its hash).
rm -rf "$work/models" && mkdir -p "$work/models" && cp models/dds_profile.xml "$work/models/"
cp -r models/quadruped "$work/models/unitree_quadruped"
cp "$work/unitree_walk.io_layout.yaml" "$work/models/unitree_quadruped/io_layout.yaml"
"$hil" quadruped --robot "$work/models/unitree_quadruped/robot.yaml" --in-process --policy "$work/unitree_walk.blob" \
  --commands models/quadruped/schedules/demo.yaml --report "$work/unitree_walk.json" >"$work/unitree_walk.log" 2>&1 ||
  { cat "$work/unitree_walk.log"; fail "unitree_walk: pbppo-hil exited $?"; }
expect "$work/unitree_walk.log" "no fall"
sed -n '2,8p' "$work/unitree_walk.log" | sed "s/^/   unitree_walk: /"
like_shipped unitree_walk 0.02 || fail "the deploy-file import does not walk as the shipped policy"
# On the shipped layout the blob is refused: its layout is the deploy file's.
"$hil" quadruped --in-process --policy "$work/unitree_walk.blob" --commands models/quadruped/schedules/demo.yaml \
  >"$work/unitree_wrong_layout.log" 2>&1 && fail "the deploy file's blob ran on the shipped layout"
expect "$work/unitree_wrong_layout.log" "policy does not fit robot layout 'quadruped'"
d=$work/bad_deploy.yaml
sed 's/stiffness: \[20.0,/stiffness: [40.0,/' "$models/unitree_walk.deploy.yaml" >"$d"
refuse_deploy() {  # refuse_deploy PATTERN [ARGS...]: $d (with ARGS) refused, nothing written
  local rc=0 pattern=$1
  shift
  rm -f "$work/refused".*
  "$pbppo" import-onnx "$models/unitree_walk.onnx" --robot "$quad" --deploy "$d" --out "$work/refused.blob" "$@" \
    >"$work/refused.log" 2>&1 || rc=$?
  [ "$rc" -eq 1 ] || { cat "$work/refused.log"; fail "$d: exit $rc, expected 1"; }
  [ -z "$(ls "$work"/refused.* 2>/dev/null | grep -v refused.log)" ] || fail "a refused deploy import wrote a file"
  expect "$work/refused.log" "$pattern"
  sed 's/^/   /' "$work/refused.log"
}
refuse_deploy "bad_deploy.yaml: stiffness\[0\]: 40 for joint LF_HAA, but robot 'quadruped' tracks a policy's targets with kp 20"
sed 's/  joint_vel_rel:/  height_scan:/' "$models/unitree_walk.deploy.yaml" >"$d"
refuse_deploy "bad_deploy.yaml: observations.height_scan: an observation term no signal of robot 'quadruped' gives"
sed 's/^joint_ids_map: .*/joint_ids_map: [0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11]/' "$models/unitree_walk.deploy.yaml" >"$d"
refuse_deploy "bad_deploy.yaml: default_joint_pos\[1\]: 0 rad for policy joint 1 \(motor 1, LF_HFE\)"
# The same policy's Isaac Lab env.yaml, with the articulation's joint order it does not hold: the
# same layout and the same blob, byte for byte.
isaac_joints=LF_HAA,RF_HAA,LH_HAA,RH_HAA,LF_HFE,RF_HFE,LH_HFE,RH_HFE,LF_KFE,RF_KFE,LH_KFE,RH_KFE
"$pbppo" import-onnx "$models/unitree_walk.onnx" --robot "$quad" --deploy "$models/unitree_walk.env.yaml" \
  --joints "$isaac_joints" --out "$work/isaac_walk.blob" >"$work/isaac_walk.import.log" 2>&1 ||
  { cat "$work/isaac_walk.import.log"; fail "isaac_walk: import-onnx --deploy env.yaml exited $?"; }
expect "$work/isaac_walk.import.log" "\(Isaac Lab env.yaml\): 6 observation terms, 45 layout observations"
cmp "$work/isaac_walk.blob" "$work/unitree_walk.blob" || fail "the env.yaml import differs from the deploy.yaml import"
echo "   Isaac Lab env.yaml + --joints: the same blob, byte for byte (its layout's hash among the bytes), as the deploy.yaml gives"
d=$models/unitree_walk.env.yaml
refuse_deploy "unitree_walk.env.yaml: top level: an Isaac Lab env.yaml does not hold the articulation's joint order"
# The run's rsl_rl agent.yaml beside its env.yaml (Isaac Lab's params/ folder) is read with it: the
# graph's actor checked against what was trained; the same blob.
params=$work/params
mkdir -p "$params"
cp "$models/unitree_walk.env.yaml" "$params/env.yaml"
cp "$models/unitree_walk.agent.yaml" "$params/agent.yaml"
"$pbppo" import-onnx "$models/unitree_walk.onnx" --robot "$quad" --deploy "$params/env.yaml" \
  --joints "$isaac_joints" --out "$work/isaac_agent.blob" >"$work/isaac_agent.import.log" 2>&1 ||
  { cat "$work/isaac_agent.import.log"; fail "isaac_agent: import-onnx with agent.yaml beside env.yaml exited $?"; }
expect "$work/isaac_agent.import.log" "agent: +.*params/agent.yaml \(policy\)"
expect "$work/isaac_agent.import.log" "agent.yaml: +hidden layers \[128, 64, 32\] elu: the graph's"
cmp "$work/isaac_agent.blob" "$work/isaac_walk.blob" || fail "the import with agent.yaml differs from the one without"
grep "agent" "$work/isaac_agent.import.log" | sed 's/^/   /'
# Trained on normalised observations but exported without the normaliser, and another run's
# widths (given with --agent): refused naming the field, nothing written.
d=$params/env.yaml
sed 's/actor_obs_normalization: false/actor_obs_normalization: true/' "$models/unitree_walk.agent.yaml" >"$params/agent.yaml"
refuse_deploy "agent.yaml: policy.actor_obs_normalization: true: the policy was trained on normalised observations, but the graph holds no normaliser" \
  --joints "$isaac_joints"
cp "$models/unitree_walk.agent.yaml" "$params/agent.yaml"
sed '0,/^  - 128$/s//  - 256/' "$models/unitree_walk.agent.yaml" >"$work/other_agent.yaml"
refuse_deploy "other_agent.yaml: policy.actor_hidden_dims: \[256, 64, 32\], but the graph's actor has hidden layers \[128, 64, 32\]" \
  --joints "$isaac_joints" --agent "$work/other_agent.yaml"
# Its clip_actions: each target within offset -+ clip x scale.
sed 's/^clip_actions: null/clip_actions: 1.0/' "$models/unitree_walk.agent.yaml" >"$params/agent.yaml"
"$pbppo" import-onnx "$models/unitree_walk.onnx" --robot "$quad" --deploy "$params/env.yaml" \
  --joints "$isaac_joints" --out "$work/isaac_clip.blob" >"$work/isaac_clip.import.log" 2>&1 ||
  { cat "$work/isaac_clip.import.log"; fail "isaac_clip: import-onnx with clip_actions exited $?"; }
expect "$work/isaac_clip.import.log" "clip_actions 1: each raw action within \[-1, 1\] before its scale"
expect "$work/isaac_clip.io_layout.yaml" "name: LF_HFE, command: q_des_LF_HFE, unit: rad, scale: 0.25, offset: 0.4.*, low: 0.15.*, high: 0.65"
echo "import end to end: ok"
