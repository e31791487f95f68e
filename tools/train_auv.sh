#!/usr/bin/env bash
# Trains the shipped AUV navigation policy and writes its report. Pb-PPO (our `pbppo` schedule,
# arms 0.05:0.4:6, rollout feedback) in stages, each starting from the best policy of the one
# before (--init):
#   stage 1: FIRST_LAYOUT (all three layouts by default) from scratch (observation normaliser on),
#   geodesic progress with the margin FIRST_MARGIN;
#   stage 2, 3, ... (none by default): all three layouts (--layout mixed), one stage per
#   SEED:LR[@D:C][+D:W] in MIXED_STAGES (@D:C: --geodesic-margin D:C, the progress path keeps off
#   obstacles; +D:W: --clearance-penalty D:W, a cost for every step within D of l_safe).
# Then 200 deterministic evaluation episodes per layout from seeds that training never uses, with
# the trajectory plots. Copies the blob, its golden vectors and the report to
# policies/frozen/auv_nav/. Same build, same settings: the same blob (runs are bit-reproducible).
# A stage whose folder already holds a finished run (summary.json, not interrupted) is kept, so a
# stopped script resumes at the first unfinished stage; delete OUT_DIR to train afresh.
# Usage: tools/train_auv.sh [OUT_DIR=runs/train_auv]
#   PBPPO=path/to/pbppo  THREADS=2  PROGRESS=geodesic (--progress of every stage)
#   FIRST_LAYOUT=mixed  FIRST_STEPS=4e6  FIRST_SEED=1  FIRST_MARGIN=2:4 (empty: none)
#   MIXED_STEPS=6e6  MIXED_STAGES="" (e.g. "3:1e-4 5:5e-5@2:4")
set -euo pipefail
source "$(dirname "$0")/common.sh"
out="${1:-$root/runs/train_auv}"
pbppo="$(program PBPPO build/default/policies/pbppo)"
threads="${THREADS:-2}"
progress="${PROGRESS:-geodesic}"
first_layout="${FIRST_LAYOUT:-mixed}"
first_steps="${FIRST_STEPS:-4e6}"
first_seed="${FIRST_SEED:-1}"
first_margin="${FIRST_MARGIN-2:4}"
mixed_steps="${MIXED_STEPS:-6e6}"
mixed_stages="${MIXED_STAGES:-}"
frozen="$root/policies/frozen/auv_nav"
common=(--env auv-nav --schedule pbppo --arms 0.05:0.4:6 --feedback rollout --threads "$threads" --envs 16
  --rollout 256 --minibatch 512 --epochs 10 --gamma 0.99 --scale-rewards --hidden 64-64 --keep-best
  --progress "$progress")
finished() {  # finished DIR ENV SEED LR [MARGIN [CLEARANCE]]: a completed run with these settings is there (another: stop)
  [ -f "$1/best.blob" ] && [ -f "$1/summary.json" ] || return 1
  local rc=0
  python3 - "$1/summary.json" "$2" "$3" "$4" "$progress" "${5:-}" "${6:-}" <<'PY' || rc=$?
import json, sys
s = json.load(open(sys.argv[1]))
want = {"env": sys.argv[2], "seed": int(sys.argv[3]), "learning_rate": float(sys.argv[4]), "progress": sys.argv[5],
        "geodesic_margin": sys.argv[6] or None, "clearance_penalty": sys.argv[7] or None}
got = {k: s.get(k) or None if isinstance(s.get(k), str) else s.get(k) for k in want}  # "" (not set) as None
if got != want:
    print("train_auv: %s holds another run (%s, this script wants %s); delete it or choose another OUT_DIR"
          % (sys.argv[1], got, want), file=sys.stderr)
    sys.exit(3)
sys.exit(0 if s.get("interrupted") is False else 1)
PY
  [ "$rc" -ne 3 ] || exit 1
  return "$rc"
}
pair_re='^[0-9.]+:[0-9.]+$'  # DISTANCE:VALUE (a margin or a clearance term)
# SEED:LR[@D:C][+D:W] -> stage_seed, stage_lr, stage_margin, stage_clearance (empty when absent).
parse_stage() {
  local spec="$1" rest
  stage_clearance="" stage_margin=""
  case "$spec" in *+*) stage_clearance=${spec#*+} spec=${spec%%+*} ;; esac
  case "$spec" in *@*) stage_margin=${spec#*@} spec=${spec%%@*} ;; esac
  stage_seed=${spec%%:*} stage_lr=${spec#*:}
  rest="$stage_seed:$stage_lr"
  [[ "$rest" =~ ^[0-9]+:[0-9.]+(e-?[0-9]+)?$ ]] || return 1
  [ -z "$stage_margin" ] || [[ "$stage_margin" =~ $pair_re ]] || return 1
  [ -z "$stage_clearance" ] || [[ "$stage_clearance" =~ $pair_re ]] || return 1
}
for pair in $mixed_stages; do
  if ! parse_stage "$pair"; then
    fail "MIXED_STAGES: '$pair' is not SEED:LR[@DISTANCE:COST][+DISTANCE:PER_STEP] (e.g. 1:3e-4, 7:5e-5@2:4, 11:5e-5@2:4+1.5:1)"
  fi
done
if [ -n "$first_margin" ] && ! [[ "$first_margin" =~ $pair_re ]]; then
  fail "FIRST_MARGIN: '$first_margin' is not DISTANCE:COST (e.g. 2:4)"
fi
mkdir -p "$out"
if finished "$out/stage1" "auv-nav:$first_layout" "$first_seed" 3e-4 "$first_margin"; then
  echo "train_auv: stage 1: kept the finished run in $out/stage1"
else
  echo "train_auv: stage 1: $first_layout, $first_steps steps, seed $first_seed${first_margin:+, geodesic margin $first_margin} -> $out/stage1"
  train_run "$pbppo" "$out/stage1" "${common[@]}" --layout "$first_layout" --normalize-obs --lr 3e-4 \
    --steps "$first_steps" --seed "$first_seed" ${first_margin:+--geodesic-margin "$first_margin"}
fi
stage=1
for pair in $mixed_stages; do
  parse_stage "$pair"
  seed=$stage_seed lr=$stage_lr margin=$stage_margin clearance=$stage_clearance
  prev=$stage
  stage=$((stage + 1))
  if finished "$out/stage$stage" auv-nav:mixed "$seed" "$lr" "$margin" "$clearance"; then
    echo "train_auv: stage $stage: kept the finished run in $out/stage$stage"
    continue
  fi
  echo "train_auv: stage $stage: mixed, $mixed_steps steps, seed $seed, lr $lr${margin:+, geodesic margin $margin}${clearance:+, clearance penalty $clearance}, from stage $prev -> $out/stage$stage"
  # The normaliser comes with the --init blob (and keeps adapting).
  train_run "$pbppo" "$out/stage$stage" "${common[@]}" --layout mixed --init "$out/stage$prev/best.blob" \
    --lr "$lr" --steps "$mixed_steps" --seed "$seed" ${margin:+--geodesic-margin "$margin"} \
    ${clearance:+--clearance-penalty "$clearance"}
done
last="$out/stage$stage"
# PPO on this task is not monotonic: each stage hands on, and ships, its best checkpoint.
"$root/tools/eval_auv.sh" "$last/best.blob" "$out" || echo "train_auv: the policy misses the evaluation targets (shipped anyway, see the report)"
rm -rf "$frozen/report"
mkdir -p "$frozen/report"
cp "$last/best.blob" "$frozen/auv_nav.blob"
cp "$last/best.golden" "$frozen/auv_nav.golden"
for s in $(seq 1 "$stage"); do
  mkdir -p "$frozen/report/stage$s"
  cp "$out/stage$s"/{summary.json,log.csv,return.png,success.png,epsilon.png,arms.png} "$frozen/report/stage$s/"
done
cp "$out"/eval_{easy,medium,hard}.{json,png} "$out"/outcomes_{easy,medium,hard}.csv "$frozen/report/"
echo "shipped: $frozen"
