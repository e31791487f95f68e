#!/usr/bin/env bash
# Chooses an AUV policy among a training run's candidates on development episodes: best.blob and
# every blob in snapshots/ (pbppo train --snapshots N) are evaluated deterministically on each
# layout (EPISODES from seed DEV_SEED: a stream that neither training nor tools/eval_auv.sh uses),
# and the candidate closest to the targets (95 / 95 / 90 % on easy / medium / hard: the least total
# shortfall, ties by the higher total success) is copied to RUN_DIR/selected.blob with its golden
# vectors. Writes RUN_DIR/select.csv (one row per candidate) and prints the table. The best of many
# candidates on the same episodes is flattered by chance (at 100 episodes and 65 % one standard
# error is 5 points), so the choice is evaluated again on as many episodes from CONFIRM_SEED (a
# second development stream; empty: skip) and both results are printed.
# Usage: tools/select_auv.sh RUN_DIR
#   (PBPPO=path/to/pbppo, EPISODES=100, DEV_SEED=777, CONFIRM_SEED=888, JOBS=2)
set -euo pipefail
source "$(dirname "$0")/common.sh"
run_dir_argument "tools/select_auv.sh RUN_DIR (a pbppo train --out folder)" "$@"
pbppo="$(program PBPPO build/default/policies/pbppo)"
episodes="${EPISODES:-100}"
seed="${DEV_SEED:-777}"
confirm="${CONFIRM_SEED-888}"
jobs="${JOBS:-2}"
positive_int EPISODES "$episodes"
non_negative_int DEV_SEED "$seed"
positive_int JOBS "$jobs"
case "$confirm" in *[!0-9]*) fail "CONFIRM_SEED: '$confirm' is not a non-negative integer (or empty: skip)" ;; esac
if [ -n "$confirm" ] && [ "$confirm" = "$seed" ]; then
  fail "CONFIRM_SEED must differ from DEV_SEED ($seed)"
fi
run_candidates "$run" best.blob
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
# One job per (candidate, layout); each writes one line "index layout success collisions timeouts".
i=0
for b in "${candidates[@]}"; do
  for layout in easy medium hard; do echo "$i $layout $b"; done
  i=$((i + 1))
done > "$work/jobs"
export pbppo episodes seed work
xargs -P "$jobs" -L 1 bash -c '
  "$pbppo" eval "$2" --env auv-nav --layout "$1" --episodes "$episodes" --seed "$seed" --json > "$work/$0.$1.json"
' < "$work/jobs"
python3 - "$root/tools" "$work" "$run" "${candidates[@]}" <<'PY'
import json, os, sys
sys.dont_write_bytecode = True  # no __pycache__ in the source tree
sys.path.insert(0, sys.argv.pop(1))
from selection import write_choice
work, run, cands = sys.argv[1], sys.argv[2], sys.argv[3:]
targets = {"easy": 95.0, "medium": 95.0, "hard": 90.0}
rows = []
for i, blob in enumerate(cands):
    row = {"candidate": os.path.relpath(blob, run)}
    shortfall = total = 0.0
    for layout, t in targets.items():
        e = json.load(open(os.path.join(work, "%d.%s.json" % (i, layout))))
        s = 100.0 * e["success_rate"]
        row[layout] = round(s, 2)
        row[layout + "_collisions"] = e["collisions"]
        row[layout + "_timeouts"] = e["timeouts"]
        shortfall += max(0.0, t - s)
        total += s
    row["shortfall"] = shortfall
    row["total"] = total
    rows.append(row)
best = min(range(len(rows)), key=lambda i: (rows[i]["shortfall"], -rows[i]["total"], i))
write_choice(run, rows, best, cands)
print("%-28s %7s %7s %7s  %s" % ("candidate", "easy", "medium", "hard", "shortfall"))
for i, r in enumerate(rows):
    print("%-28s %6.1f%% %6.1f%% %6.1f%%  %5.1f%s" % (r["candidate"], r["easy"], r["medium"], r["hard"], r["shortfall"],
                                                    "  <- selected" if i == best else ""))
print("select_auv: %s -> %s/selected.blob" % (rows[best]["candidate"], run))
PY
if [ -n "$confirm" ]; then
  line=""
  for layout in easy medium hard; do
    r=$("$pbppo" eval "$run/selected.blob" --env auv-nav --layout "$layout" --episodes "$episodes" --seed "$confirm" --json |
      python3 -c 'import json,sys; e=json.load(sys.stdin); print("%.1f%%" % (100 * e["success_rate"]))')
    line="$line $layout $r"
  done
  echo "select_auv: the choice on $episodes other episodes per layout (seed $confirm):$line"
fi
