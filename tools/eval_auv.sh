#!/usr/bin/env bash
# Evaluates an AUV policy blob on the three layouts: 200 deterministic episodes each from seed
# 424242 (training draws its episode seeds from other streams), success rate with 95% interval,
# collisions, timeouts, mean time and what the failures were nearest to (a wall, a layout obstacle
# or a random one); writes eval_<layout>.json, eval_<layout>.png (trajectories) and
# outcomes_<layout>.csv (one row per episode: pbppo eval --outcomes) into OUT_DIR and checks the
# shipped-policy targets (>= 95% easy and medium, >= 90% hard).
# Usage: tools/eval_auv.sh BLOB [OUT_DIR=.]   (PBPPO=path/to/pbppo, EPISODES=200, SEED=424242)
set -euo pipefail
source "$(dirname "$0")/common.sh"
blob="$1"
out="${2:-.}"
pbppo="$(program PBPPO build/default/policies/pbppo)"
episodes="${EPISODES:-200}"
seed="${SEED:-424242}"
mkdir -p "$out"
ok=1
for layout in easy medium hard; do
  "$pbppo" eval "$blob" --env auv-nav --layout "$layout" --episodes "$episodes" --seed "$seed" --json \
    --plot "$out/eval_$layout.png" --outcomes "$out/outcomes_$layout.csv" > "$out/eval_$layout.json"
  rm -rf "$out/eval_$layout.png.d"
  target=95
  [ "$layout" = hard ] && target=90
  line=$(python3 -c 'import json,sys; e=json.load(open(sys.argv[1])); t=float(sys.argv[2]);
r=100*e["success_rate"]; lo,hi=e["success_rate_ci95"]
print("%-6s success %5.1f%% (95%% CI %.1f-%.1f)  collisions %3d  timeouts %3d  mean time %.1f s  target %g%%: %s" % (
 sys.argv[3], r, 100*lo, 100*hi, e["collisions"], e["timeouts"], e["mean_success_time_s"] or float("nan"), t,
 "met" if r >= t else "NOT met"))' "$out/eval_$layout.json" "$target" "$layout")
  echo "$line"
  python3 -c 'import csv,collections,sys
c=collections.Counter((r["outcome"],r["nearest"]) for r in csv.DictReader(open(sys.argv[1])))
for o in ("collision","timeout"):
  n=sum(v for (k,_),v in c.items() if k==o)
  if n: print("         %ss near: %s" % (o, ", ".join("%s %d" % (w, c[(o,w)]) for w in ("random","layout","wall") if c[(o,w)])))
' "$out/outcomes_$layout.csv"
  case "$line" in *"NOT met"*) ok=0 ;; esac
done
[ "$ok" = 1 ] && echo "all targets met" || { echo "targets not met"; exit 1; }
