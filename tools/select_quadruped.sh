#!/usr/bin/env bash
# Chooses a walking policy among a training run's candidates in MuJoCo, the training simulator, on
# development episodes that neither training nor the recipe's tests use: the run's policy.blob and
# every blob in snapshots/ (pbppo train --snapshots N) walk
#   - the demo schedule (SCHEDULE: stand, forward, sideways, turn in place, stop) from the starts
#     of DEMO_SEEDS, scored by its worst phase: the largest mean |error| of vx, vy or yaw rate of
#     any phase after the settling time, averaged over the starts (the HIL's figure, here in MuJoCo);
#   - the paper's test (20 s, seed DEV_SEED) on flat ground (FLAT_ROBOTS robots) and on the mix of
#     flat ground and blocks (MIXED_ROBOTS), counting falls. Falls on the mix are rare events that
#     vary from one snapshot to the next by a few in 50: 200 robots separate a 2 % rate (issue 17's
#     2 in 50) from 4 %, where 50 robots do not. MIXED_ROBOTS=0 leaves the mix out (a robot trained
#     on flat ground alone).
# A candidate qualifies with no fall in the demo, at most MAX_FALLS_FLAT falls on flat ground and
# MAX_FALLS_MIXED on the mix (4 of 200: 2 %), and, where MAX_ERROR_FLAT is set, a mean |error| of
# vx, vy and yaw rate each at most that on flat ground (the paper's figure, on the development seed);
# of those the one with the smallest worst phase is copied to
# RUN_DIR/selected.blob with its golden vectors (none qualifying: the fewest falls, then the
# smallest worst phase, and the script says so). The Simbody HIL is not used: it stays the test.
# Writes RUN_DIR/select.csv (one row per candidate) and prints the table.
# Usage: tools/select_quadruped.sh RUN_DIR
#   (PBPPO=path/to/pbppo, ROBOT=quadruped (the run's --robot: a folder of models/ or its robot.yaml),
#    DEMO_SEEDS="101 102 103 104", DEV_SEED=101, FLAT_ROBOTS=50, MIXED_ROBOTS=200, MAX_FALLS_FLAT=0,
#    MAX_FALLS_MIXED=4, MAX_ERROR_FLAT= (no bound), SCHEDULE=models/ROBOT/schedules/demo.yaml, JOBS=2)
set -euo pipefail
source "$(dirname "$0")/common.sh"
run_dir_argument "tools/select_quadruped.sh RUN_DIR (a pbppo train --env quadruped-walk --out folder)" "$@"
pbppo="$(program PBPPO build/default/policies/pbppo)"
demo_seeds="${DEMO_SEEDS:-101 102 103 104}"
seed="${DEV_SEED:-101}"
flat_robots="${FLAT_ROBOTS:-50}"
mixed_robots="${MIXED_ROBOTS:-200}"
max_flat="${MAX_FALLS_FLAT:-0}"
max_mixed="${MAX_FALLS_MIXED:-4}"
max_error="${MAX_ERROR_FLAT:-}"
robot="${ROBOT:-quadruped}"
[ -n "$robot" ] || fail "ROBOT: empty (a folder of models/, e.g. quadruped or go2, or a robot.yaml)"
robot_dir="$root/models/$robot"
[ -f "$robot" ] && robot_dir="$(dirname "$robot")"
schedule="${SCHEDULE:-$robot_dir/schedules/demo.yaml}"
jobs="${JOBS:-2}"
[ -n "${demo_seeds// /}" ] || fail "DEMO_SEEDS: empty (one or more non-negative integers)"
for s in $demo_seeds; do
  non_negative_int DEMO_SEEDS "$s"
done
non_negative_int DEV_SEED "$seed"
positive_int FLAT_ROBOTS "$flat_robots"
non_negative_int MIXED_ROBOTS "$mixed_robots"
non_negative_int MAX_FALLS_FLAT "$max_flat"
non_negative_int MAX_FALLS_MIXED "$max_mixed"
positive_int JOBS "$jobs"
if [ -n "$max_error" ]; then
  python3 -c 'import math, sys; v = float(sys.argv[1]); sys.exit(0 if math.isfinite(v) and v > 0 else 1)' \
    "$max_error" 2>/dev/null || fail "MAX_ERROR_FLAT: '$max_error' is not a positive number (m/s and rad/s)"
fi
[ -f "$schedule" ] || fail "SCHEDULE: '$schedule' is not a file"
run_candidates "$run" policy.blob
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
# One job per evaluation; each writes one JSON file named by the candidate's index and the test. A
# schedule on which the robot fell exits 1 with its figures written: that is a result, not an error.
i=0
for b in "${candidates[@]}"; do
  for s in $demo_seeds; do echo "$i demo$s $b --schedule $schedule --seed $s"; done
  echo "$i flat $b --terrain flat --episodes $flat_robots --seed $seed"
  [ "$mixed_robots" -gt 0 ] && echo "$i mixed $b --terrain mixed --episodes $mixed_robots --seed $seed"
  i=$((i + 1))
done > "$work/jobs"
export pbppo work robot
xargs -P "$jobs" -L 1 bash -c '
  f="$work/$0.$1.json"
  "$pbppo" eval "$2" --env quadruped-walk --robot "$robot" "${@:3}" --json > "$f" && exit 0
  rc=$?
  [ "$rc" -eq 1 ] && grep -q "\"fell\": true" "$f" && exit 0
  echo "select_quadruped: pbppo eval $2 ${*:3} failed (exit $rc)" >&2
  exit 1
' < "$work/jobs" || fail "an evaluation failed (above)"
python3 - "$root/tools" "$work" "$run" "$max_flat" "$max_mixed" "$demo_seeds" "$flat_robots" "$mixed_robots" \
  "${max_error:-inf}" "${candidates[@]}" <<'PY'
import json, os, sys
sys.dont_write_bytecode = True  # no __pycache__ in the source tree
sys.path.insert(0, sys.argv.pop(1))
from selection import write_choice
work, run, max_flat, max_mixed, seeds = sys.argv[1], sys.argv[2], int(sys.argv[3]), int(sys.argv[4]), sys.argv[5].split()
robots = {"flat": int(sys.argv[6]), "mixed": int(sys.argv[7])}
max_error = float(sys.argv[8])
cands = sys.argv[9:]
terrains = ("flat", "mixed") if robots["mixed"] > 0 else ("flat",)
axes = ("vx", "vy", "yaw")
rows = []
for i, blob in enumerate(cands):
    row = {"candidate": os.path.relpath(blob, run)}
    demo_falls = 0
    per_phase = {}  # phase name -> summed |error| per axis over the starts
    for s in seeds:
        e = json.load(open(os.path.join(work, "%d.demo%s.json" % (i, s))))
        demo_falls += int(e["fell"])
        for p in e["phases"]:
            acc = per_phase.setdefault(p["name"], [0.0, 0.0, 0.0])
            for k in range(3):
                acc[k] += p["mean_abs_error"][k]
    worst, worst_at = 0.0, ""
    for name, acc in per_phase.items():
        for k in range(3):
            m = acc[k] / len(seeds)
            row["%s_%s" % (name, axes[k])] = round(m, 4)
            if m > worst:
                worst, worst_at = m, "%s %s" % (name, axes[k])
    row["demo_falls"] = demo_falls
    row["worst_phase"] = round(worst, 4)
    row["worst_at"] = worst_at
    row["falls_mixed"] = 0
    for terrain in terrains:
        e = json.load(open(os.path.join(work, "%d.%s.json" % (i, terrain))))
        row["falls_" + terrain] = e["falls"]
        if terrain == "flat":
            m = e["mean_abs_error"]
            for k, key in zip(axes, ("vx_mps", "vy_mps", "yaw_rate_radps")):
                row["flat_" + k] = round(m[key], 4)
    row["flat_worst"] = max(row["flat_" + k] for k in axes)
    row["qualifies"] = int(demo_falls == 0 and row["falls_flat"] <= max_flat and row["falls_mixed"] <= max_mixed
                           and row["flat_worst"] <= max_error)
    rows.append(row)
qualified = [i for i, r in enumerate(rows) if r["qualifies"]]
if qualified:
    best = min(qualified, key=lambda i: (rows[i]["worst_phase"], i))
else:
    best = min(range(len(rows)), key=lambda i: (rows[i]["demo_falls"], rows[i]["falls_flat"] + rows[i]["falls_mixed"],
                                                rows[i]["flat_worst"] > max_error,
                                                rows[i]["worst_phase"], i))
write_choice(run, rows, best, cands)
flat_h, mixed_h = "flat falls/%d" % robots["flat"], "mixed falls/%d" % robots["mixed"]
print("%-28s %11s %-16s %10s %14s %15s %18s" % ("candidate", "worst phase", "(where)", "demo falls", flat_h, mixed_h,
                                                "flat |e| vx/vy/yaw"))
for i, r in enumerate(rows):
    print("%-28s %11.3f %-16s %10d %14d %15s %18s%s" % (
        r["candidate"], r["worst_phase"], r["worst_at"], r["demo_falls"], r["falls_flat"],
        r["falls_mixed"] if robots["mixed"] > 0 else "-", "%.3f/%.3f/%.3f" % (r["flat_vx"], r["flat_vy"], r["flat_yaw"]),
        "  <- selected" if i == best else ""))
if not qualified:
    print("select_quadruped: no candidate met the limits (no demo fall, flat <= %d of %d, mixed <= %d of %d falls%s); "
          "chose the fewest falls" % (max_flat, robots["flat"], max_mixed, robots["mixed"],
                                      ", flat |error| <= %g per axis" % max_error if max_error < float("inf") else ""))
print("select_quadruped: %s -> %s/selected.blob (worst demo phase %.3f in MuJoCo, %s)" %
      (rows[best]["candidate"], run, rows[best]["worst_phase"], rows[best]["worst_at"]))
PY
