#!/usr/bin/env bash
# One data-parallel training run over mpirun's ranks (label train_ranks):
#   a. the same seed and number of environments give byte-identical blobs and the same log (timings
#      aside) on 1 rank x 1 thread, 1 x 2, 2 x 1, 3 x 1 and 2 x 2: the walking robot (its privileged
#      critic, minibatches in chunks, the adaptive rate, rollout feedback) and the pendulum (two
#      environments, one per rank, evaluation feedback with episodes split over ranks, the
#      observation normaliser and reward scaling);
#   b. rank 0 alone prints and writes (one result, summary.json says 2 ranks);
#   c. a rank killed mid-run ends the job with an error, and the output holds no half-written blob;
#   d. refused before anything is written: fewer blocks of environments than ranks (exit 2, said once).
# usage: train_ranks.sh PBPPO MPIEXEC SOURCE_DIR WORK_DIR
set -euo pipefail
pbppo=$1 mpiexec=$2 src=$3 work=$4
source "$src/tests/support/checks.sh"  # fail, expect, fresh_dir, log_without_timing
fresh_dir "$work"
cd "$work"
mpi() {
  local np=$1
  shift
  "$mpiexec" --allow-run-as-root --oversubscribe -np "$np" "$@"
}
# same NAME RUN...: every run's blob and log equal the first's.
same() {
  local name=$1 first=$2
  shift 2
  for run in "$@"; do
    cmp "$first/policy.blob" "$run/policy.blob" || fail "$name: $run's blob differs from $first's"
    diff <(log_without_timing "$first/log.csv") <(log_without_timing "$run/log.csv") >/dev/null ||
      fail "$name: $run's log differs from $first's"
  done
  echo "   $name: $first and $* byte-identical"
}

echo "== a: ranks x threads, the same weights"
walk=(train --env quadruped-walk --envs 70 --rollout 48 --steps 13440 --minibatch 3000 --epochs 2 --hidden 128-64-32
  --activation elu --schedule pbppo --feedback rollout --lr-schedule adaptive:0.01 --clip-vf 0.2 --ent-coef 0.01
  --no-plots --quiet --seed 3)
"$pbppo" "${walk[@]}" --threads 1 --out walk_1x1 >walk_1x1.log
"$pbppo" "${walk[@]}" --threads 2 --out walk_1x2 >walk_1x2.log
mpi 2 "$pbppo" "${walk[@]}" --threads 1 --out walk_2x1 >walk_2x1.log
mpi 3 "$pbppo" "${walk[@]}" --threads 1 --out walk_3x1 >walk_3x1.log
mpi 2 "$pbppo" "${walk[@]}" --threads 2 --out walk_2x2 >walk_2x2.log
same walk walk_1x1 walk_1x2 walk_2x1 walk_3x1 walk_2x2
pend=(train --env pendulum --envs 2 --rollout 512 --steps 8192 --minibatch 256 --schedule pbppo --feedback eval
  --eval-episodes 3 --normalize-obs --scale-rewards --no-plots --quiet)
"$pbppo" "${pend[@]}" --threads 1 --out pend_1x1 >pend_1x1.log
"$pbppo" "${pend[@]}" --threads 2 --out pend_1x2 >pend_1x2.log
mpi 2 "$pbppo" "${pend[@]}" --threads 1 --out pend_2x1 >pend_2x1.log 2>pend_2x1.err
same pendulum pend_1x1 pend_1x2 pend_2x1

echo "== b: rank 0 prints and writes"
[ "$(grep -c '^blob ' walk_2x1.log)" = 1 ] || fail "not one result printed by 2 ranks"
expect pend_2x1.err "seed 1, 2 ranks x 1 thread -> pend_2x1"
[ "$(grep -c 'pbppo train: pendulum' pend_2x1.err)" = 1 ] || fail "the start line printed more than once"
expect walk_2x1/summary.json '"ranks": 2,'
expect walk_1x1/summary.json '"ranks": 1,'
expect walk_2x1.log '^time: rollout .* ranks exchanging'

echo "== c: a rank killed mid-run"
mpi 2 "$pbppo" train --env pendulum --envs 4 --rollout 256 --steps 100000000 --checkpoint-seconds 0 --no-plots \
  --quiet --out killed >killed.log 2>killed.err &
job=$!
# Rank 1, once the run has logged two iterations and written a checkpoint.
victim=""
for _ in $(seq 600); do
  if [ -s killed/policy.blob ] && [ "$(wc -l <killed/log.csv 2>/dev/null || echo 0)" -ge 3 ]; then
    for p in $(pgrep -f "pbppo train --env pendulum --envs 4" || true); do
      if tr '\0' '\n' <"/proc/$p/environ" 2>/dev/null | grep -qx 'OMPI_COMM_WORLD_RANK=1'; then victim=$p; fi
    done
    [ -n "$victim" ] && break
  fi
  sleep 0.1
done
[ -n "$victim" ] || { kill "$job" || true; fail "rank 1 not found running"; }
kill -9 "$victim"
rc=0
timeout 60 tail --pid="$job" -f /dev/null || fail "the job did not end within 60 s of rank 1's death"
wait "$job" || rc=$?
[ "$rc" -ne 0 ] || fail "the job exited 0 after rank 1 was killed"
cat killed.err
expect killed.err "(rank 1|process rank 1).*(signal 9|Killed)|exited on signal 9"
# The checkpoint is whole (written by rank 0 before the death, or not replaced since) and nothing
# temporary is left.
"$pbppo" inspect killed/policy.blob >/dev/null || fail "the checkpoint left behind does not load"
leftovers=$(find killed -name '*.tmp*' -o -name '.*' -type f)
[ -z "$leftovers" ] || fail "temporary files left: $leftovers"

echo "== d: refusals"
rc=0
mpi 2 "$pbppo" train --env pendulum --envs 1 --steps 1000 --out refused >refused.log 2>&1 || rc=$?
[ "$rc" = 2 ] || { cat refused.log; fail "--envs 1 on 2 ranks: exit $rc, not 2"; }
expect refused.log "--envs: 1 gives 1 block\(s\) of 1, fewer than the run's 2 ranks \(each rank steps whole blocks"
[ "$(grep -c 'fewer than' refused.log)" = 1 ] || fail "the refusal printed more than once"
[ ! -e refused ] || fail "refused: the output folder was written"
echo "PASS"
