#!/usr/bin/env bash
# tools/mujoco_budget.sh on a small sweep (label sweep): half-cheetah, the three fixed bounds x 2
# seeds of 4096 steps with 2 snapshots each:
#   a. every snapshot evaluated both ways, the report's cells the means of `pbppo eval` run by hand
#      on the snapshots, its plots written, no __pycache__ left in the source tree;
#   b. a second call trains nothing (every run finished before) and evaluates nothing again;
#   c. bad settings refused before anything is written (exit 2, the message names the variable).
# usage: mujoco_budget.sh PBPPO SOURCE_DIR WORK_DIR
set -euo pipefail
pbppo=$1 src=$2 work=$3
source "$src/tests/support/checks.sh"  # fail, expect, fresh_dir
fresh_dir "$work"
cd "$work"
export PBPPO="$pbppo" TASKS=half-cheetah ANT=none STEPS=4096 SNAPSHOTS=2 SEEDS=1-2 JOBS=2 REPORT="$work/report/budget.md"
tool="$src/tools/mujoco_budget.sh"

echo "== a: 6 runs, 2 snapshots each"
"$tool" runs >a.out 2>&1 || { cat a.out; fail "mujoco_budget.sh"; }
expect a.out "6 runs \(3 grid cells x 2 seeds\): 0 finished before, 6 to run"
expect a.out "wrote $work/report/budget.md \(6 runs\)"
for png in returns returns_through_ends; do
  [ -s "report/mujoco_budget/$png.png" ] || fail "report/mujoco_budget/$png.png missing"
done
[ -z "$(ls report/mujoco_budget | grep -v '\.png$')" ] || fail "more than the plots beside the report"
[ ! -e "$src/tools/__pycache__" ] || fail "tools/__pycache__ written"
# The fixed:0.15 row at each snapshot, both readings, from pbppo eval by hand (the report rounds to
# whole numbers: mean ± interval, min and max over the two seeds; n=2 is said where n is not 5).
row() {  # row THROUGH_FLAG: "| HalfCheetah | 0.15 | <2048 cell> | <4096 cell> |" computed by hand
  local cells=() steps s blob
  for steps in 000000002048 000000004096; do
    local xs=()
    for s in 1 2; do
      blob="runs/tasks/env=half-cheetah/schedule=fixed:0.15/seed=$s/snapshots/$steps.blob"
      [ -s "$blob" ] || fail "$blob missing"
      xs+=("$("$pbppo" eval "$blob" --env half-cheetah --episodes 10 --seed 7 --json "$@" |
        sed -nE 's/.*"mean_return": (.*),$/\1/p')")
    done
    cells+=("$(awk -v a="${xs[0]}" -v b="${xs[1]}" 'BEGIN {
      m = (a + b) / 2; sd = sqrt((a - m) ^ 2 + (b - m) ^ 2); hw = 12.7062047362 * sd / sqrt(2)
      printf "%.0f ± %.0f (n=2) [%.0f, %.0f]", m, hw, (a < b ? a : b), (a < b ? b : a) }')")
  done
  echo "| HalfCheetah | 0.15 | ${cells[0]} | ${cells[1]} | 1608 |"
}
plain=$(row)
through=$(row --through-ends)
grep -qF -- "$plain" report/budget.md || { cat report/budget.md; fail "no row '$plain'"; }
grep -qF -- "$through" report/budget.md || { cat report/budget.md; fail "no row '$through'"; }
[ "$(grep -c '^| HalfCheetah | 0\.' report/budget.md)" = 6 ] || fail "not 3 rows in each reading"
expect report/budget.md "three rows hold the paper's figure on [01] of the 1 tasks with all three measured"
[ "$(find runs -name '*.eval.json' | wc -l)" = 12 ] || fail "not 12 cached evaluations as episodes end"
[ "$(find runs -name '*.eval_through_ends.json' | wc -l)" = 12 ] || fail "not 12 cached evaluations through ends"

echo "== b: again: nothing trained, nothing evaluated again"
before=$(find runs -name '*.json' -printf '%p %T@\n' | sort)
"$tool" runs >b.out 2>&1 || { cat b.out; fail "the second call"; }
expect b.out "6 runs \(3 grid cells x 2 seeds\): 6 finished before, 0 to run"
after=$(find runs -name '*.json' -not -name sweep.json -printf '%p %T@\n' | sort)
[ "$(echo "$before" | grep -v sweep.json)" = "$after" ] || fail "files of finished runs or evaluations rewritten"
grep -qF -- "$plain" report/budget.md || fail "the report changed"

echo "== c: refusals"
refused() {  # refused PATTERN VAR=VALUE...: exit 2, says PATTERN, writes nothing
  local pattern=$1 rc=0
  shift
  env "$@" "$tool" bad >c.log 2>&1 || rc=$?
  [ "$rc" -eq 2 ] || { cat c.log; fail "$*: exit $rc, expected 2"; }
  expect c.log "$pattern"
  [ ! -e bad ] || fail "$*: wrote bad/"
  sed 's/^/   /' c.log
}
refused "ANT: 'some' is not zero, computed or none" ANT=some
refused "SNAPSHOTS: '0' is not a positive integer" SNAPSHOTS=0
refused "SNAPSHOTS: 'two' is not a positive integer" SNAPSHOTS=two
refused "TASKS: 'ant' is not hopper, walker2d or half-cheetah" TASKS=ant
refused "TASKS is empty and ANT=none: nothing to run" TASKS=
refused "--seeds: '3-1' is not a range" SEEDS=3-1
echo "tools/mujoco_budget.sh: all checks passed"
