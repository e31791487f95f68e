#!/usr/bin/env bash
# pbppo sweep on pendulum (label sweep), 2 clip schedules x 2 seeds of 4096 steps each:
#   a. --jobs 2: every run's folder and result.json, the table against the results (Student t);
#   b. the same sweep under mpirun -np 2: every policy.blob byte-identical, the tables' numbers
#      equal (wall times aside); --jobs 2 under mpirun refused;
#   c. a restart after one run lost its result.json: only that run again (its folder cleared, the
#      others untouched), and a restart with another grid refused;
#   d. refusals before anything is written (exit 2, the message names the key or flag, no folder).
# usage: sweep.sh PBPPO MPIEXEC SOURCE_DIR WORK_DIR
set -euo pipefail
pbppo=$1 mpiexec=$2 src=$3 work=$4
source "$src/tests/support/checks.sh"  # fail, expect, fresh_dir
fresh_dir "$work"
cd "$work"
grid=(--grid schedule=fixed:0.2,pbppo --seeds 1-2)
train=(-- --steps 4096 --rollout 256 --threads 1 --no-plots)
runs=(schedule=fixed:0.2/seed=1 schedule=fixed:0.2/seed=2 schedule=pbppo/seed=1 schedule=pbppo/seed=2)
mean_return() { sed -nE 's/.*"mean_return": (.*),$/\1/p' "$1"; }

echo "== a: 2 schedules x 2 seeds, --jobs 2"
"$pbppo" sweep --out jobs "${grid[@]}" --jobs 2 "${train[@]}" >a.out 2>a.err || { cat a.err; fail "sweep --jobs 2"; }
cat a.err
expect a.err "jobs: 4 runs \(2 grid cells x 2 seeds\): 0 finished before, 4 to run"
[ "$(grep -c 'final eval return' a.err)" = 4 ] || fail "not 4 finished runs in the progress"
for run in "${runs[@]}"; do
  for f in log.csv summary.json policy.blob train.log eval.json result.json; do
    [ -s "jobs/$run/$f" ] || fail "jobs/$run/$f missing"
  done
  expect "jobs/$run/result.json" '"env_steps": 4096,'
  expect "jobs/$run/result.json" '"episodes": 10,'
  [ -n "$(mean_return "jobs/$run/result.json")" ] || fail "jobs/$run/result.json: no mean_return"
done
expect jobs/sweep.json '"train_flags": \['
expect jobs/table.csv '^schedule,seeds,eval_return_mean,eval_return_ci95,eval_return_min,eval_return_max,'
expect jobs/table.md '^\| fixed:0.2 \| 2 \| '
# The pbppo row from the two seeds' results (the table has 10 digits): mean, t(0.975, 1) x sd / sqrt(2),
# min, max.
a=$(mean_return jobs/schedule=pbppo/seed=1/result.json)
b=$(mean_return jobs/schedule=pbppo/seed=2/result.json)
row=$(grep '^pbppo,' jobs/table.csv)
awk -v a="$a" -v b="$b" -v row="$row" 'BEGIN {
  split(row, f, ",")
  m = (a + b) / 2; sd = sqrt((a - m) ^ 2 + (b - m) ^ 2); hw = 12.7062047362 * sd / sqrt(2)
  lo = a < b ? a : b; hi = a < b ? b : a
  ok = f[2] == 2 && near(f[3], m) && near(f[4], hw) && near(f[5], lo) && near(f[6], hi) && f[8] == 4096
  if (!ok) { printf "table row %s; expected mean %.10g, ci95 %.10g, min %s, max %s\n", row, m, hw, lo, hi; exit 1 }
}
function near(x, y) { return (x - y) ^ 2 <= 1e-16 * (1 + y * y) }' || fail "the table's pbppo row does not match the runs' results"

echo "== b: the same sweep under mpirun -np 2"
mpi=("$mpiexec" --allow-run-as-root --oversubscribe -np 2)
"${mpi[@]}" "$pbppo" sweep --out mpi "${grid[@]}" "${train[@]}" >b.out 2>b.err || { cat b.err; fail "sweep under mpirun"; }
cat b.err
expect b.err "rank 0: 2 of the 4 runs"
expect b.err "rank 1: 2 of the 4 runs"
for run in "${runs[@]}"; do
  cmp "jobs/$run/policy.blob" "mpi/$run/policy.blob" || fail "$run: the policy differs under mpirun"
done
diff <(cut -d, -f1-9 jobs/table.csv) <(cut -d, -f1-9 mpi/table.csv) || fail "the tables differ"
rc=0
"${mpi[@]}" "$pbppo" sweep --out mpi2 "${grid[@]}" --jobs 2 "${train[@]}" >b2.log 2>&1 || rc=$?
[ "$rc" -ne 0 ] || fail "--jobs 2 under mpirun was accepted"
expect b2.log "--jobs 2: under mpirun every rank runs one run at a time"
[ ! -e mpi2 ] || fail "mpi2 written"

echo "== c: a restart after schedule=pbppo/seed=2 lost its result.json"
lost=jobs/schedule=pbppo/seed=2
rm "$lost/result.json"
touch "$lost/stale"
before=$(for run in "${runs[@]}"; do stat -c '%n %y' "jobs/$run/result.json" 2>/dev/null || true; done)
"$pbppo" sweep --out jobs "${grid[@]}" --jobs 2 "${train[@]}" >c.out 2>c.err || { cat c.err; fail "the restart"; }
cat c.err
expect c.err "4 runs \(2 grid cells x 2 seeds\): 3 finished before, 1 to run \(1 of them folders of unfinished runs"
[ "$(grep -c 'final eval return' c.err)" = 1 ] || fail "more than the lost run ran again"
expect c.err '\[1/1\] schedule=pbppo seed=2: final eval return'
[ ! -e "$lost/stale" ] || fail "the unfinished run's folder was not cleared"
[ -s "$lost/result.json" ] || fail "the lost run has no result.json again"
after=$(for run in "${runs[@]}"; do stat -c '%n %y' "jobs/$run/result.json"; done)
[ "$(diff <(echo "$before") <(echo "$after") | grep -c '^>')" = 1 ] || fail "finished runs were touched"
cmp "$lost/policy.blob" "mpi/schedule=pbppo/seed=2/policy.blob" || fail "the redone run's policy differs"
diff <(cut -d, -f1-9 jobs/table.csv) <(cut -d, -f1-9 mpi/table.csv) || fail "the table after the restart differs"
rc=0
"$pbppo" sweep --out jobs --grid schedule=fixed:0.2 --seeds 1-2 "${train[@]}" >c2.log 2>&1 || rc=$?
[ "$rc" = 2 ] || fail "a restart with another grid: exit $rc, expected 2"
expect c2.log "jobs/sweep.json is another sweep's: its grid is .*, this command's"

echo "== d: refusals"
refused() {  # refused PATTERN SWEEP_ARGS...: exit 2, says PATTERN, writes nothing
  local pattern=$1 rc=0
  shift
  "$pbppo" sweep --out bad "$@" >d.log 2>&1 || rc=$?
  [ "$rc" -eq 2 ] || { cat d.log; fail "sweep $*: exit $rc, expected 2"; }
  expect d.log "$pattern"
  [ ! -e bad ] || fail "sweep $*: wrote bad/"
  sed 's/^/   /' d.log
}
refused "--grid clip: pbppo train has no option --clip" --grid clip=0.1,0.2 "${train[@]}"
refused "--grid schedule=fixed:7: --schedule fixed: clip bound 7 is outside \[0, 1\]" \
  --grid schedule=pbppo,fixed:7 "${train[@]}"
refused "train flags after --: --out: the sweep sets it" --grid schedule=pbppo "${train[@]}" --out elsewhere
refused "train flags after --: --seed: the sweep sets it" "${train[@]}" --seed=3
refused "train flags after --: --schedule is also a --grid key" --grid schedule=pbppo "${train[@]}" --schedule pbppo
refused "--grid schedule: the key is given twice" --grid schedule=pbppo --grid schedule=fixed:0.1
refused "--grid schedule: empty value" --grid schedule=pbppo,
refused "grid cell env=nonesuch: --env: 'nonesuch' unknown" --grid env=nonesuch
refused "grid cell lr=-1: --lr: " --grid lr=0.001,-1
refused "--seeds: '3-1' is not a range" --seeds 3-1
refused "--eval-seed: '-3' is not an integer in \[0, 2\^64\)" --eval-seed -3
echo "pbppo sweep: all checks passed"
