#!/usr/bin/env bash
# pbppo train --resume (label train_resume):
#   a. a run killed (SIGKILL) after it wrote resume.bin, resumed on other threads or ranks, ends with
#      the blob and log (timings aside) of the same run uninterrupted: the pendulum (evaluation
#      feedback, normaliser, reward scaling), the walking robot (privileged critic, rollout
#      feedback, snapshots), Hopper and the AUV; a finished run leaves no resume.bin;
#   b. a run stopped by SIGINT or SIGTERM writes resume.bin at the stop and resumes to the same blob;
#   c. the recipes' train_run continues a killed run the same way;
#   d. refusals, exit 2, the message naming the flag or the file: other options with --resume, a
#      finished run, a missing folder, a damaged file, a file that is not one, no --out.
# usage: train_resume.sh PBPPO MPIEXEC SOURCE_DIR WORK_DIR
set -euo pipefail
pbppo=$1 mpiexec=$2 src=$3 work=$4
source "$src/tests/support/checks.sh"  # fail, expect, fresh_dir, log_without_timing
fresh_dir "$work"
cd "$work"
same() {  # same A B: the two runs' blobs, snapshots and logs equal
  cmp "$1/policy.blob" "$2/policy.blob" || fail "$2: the resumed run's blob differs from $1's"
  diff <(log_without_timing "$1/log.csv") <(log_without_timing "$2/log.csv") >/dev/null ||
    fail "$2: the resumed run's log differs from $1's"
  if [ -d "$1/snapshots" ]; then
    for s in "$1"/snapshots/*.blob; do cmp "$s" "$2/snapshots/$(basename "$s")" || fail "$2: snapshot $s differs"; done
  fi
  [ ! -e "$2/resume.bin" ] || fail "$2: the finished run left resume.bin"
}
# killed NAME ARGS...: starts the run in NAME, kills it once resume.bin exists (before it finishes).
killed() {
  local name=$1
  shift
  "$pbppo" "$@" --out "$name" >"$name.log" 2>&1 &
  local pid=$!
  for _ in $(seq 3000); do
    [ -s "$name/resume.bin" ] && break
    kill -0 "$pid" 2>/dev/null || fail "$name: ended before it wrote resume.bin"
    sleep 0.02
  done
  kill -9 "$pid"
  wait "$pid" 2>/dev/null || true
  [ -s "$name/resume.bin" ] || fail "$name: no resume.bin"
  [ ! -e "$name/summary.json" ] || fail "$name: finished before it was killed (make the run longer)"
  echo "   $name: killed after $(($(wc -l <"$name/log.csv") - 1)) iterations"
}

echo "== a: killed, resumed on other threads or ranks, the same run"
pend_flags=(train --env pendulum --envs 4 --rollout 256 --steps 204800 --schedule pbppo --feedback eval
  --eval-episodes 2 --normalize-obs --scale-rewards --no-plots --quiet)
pend=("${pend_flags[@]}" --resume-every 5)
"$pbppo" "${pend[@]}" --out pend >/dev/null
[ ! -e pend/resume.bin ] || fail "the finished run left resume.bin"
killed pend_killed "${pend[@]}"
"$pbppo" train --resume pend_killed --threads 2 >pend_resumed.log 2>&1 || { cat pend_resumed.log; fail "resume"; }
same pend pend_killed

walk=(train --env quadruped-walk --envs 64 --rollout 24 --steps 46080 --minibatch 768 --epochs 2 --hidden 64-32
  --activation elu --feedback rollout --snapshots 3 --resume-every 5 --no-plots --quiet)
"$pbppo" "${walk[@]}" --out walk >/dev/null
killed walk_killed "${walk[@]}"
"$mpiexec" --allow-run-as-root --oversubscribe -np 2 "$pbppo" train --resume walk_killed --threads 1 \
  >walk_resumed.log 2>&1 || { cat walk_resumed.log; fail "resume under mpirun"; }
same walk walk_killed

hopper=(train --env hopper --envs 8 --rollout 128 --steps 61440 --minibatch 512 --epochs 2 --resume-every 5
  --no-plots --quiet)
"$pbppo" "${hopper[@]}" --out hopper >/dev/null
killed hopper_killed "${hopper[@]}"
"$pbppo" train --resume hopper_killed >hopper_resumed.log 2>&1 || { cat hopper_resumed.log; fail "resume"; }
same hopper hopper_killed

auv=(train --env auv-nav --envs 8 --rollout 128 --steps 61440 --minibatch 512 --epochs 2 --resume-every 5
  --no-plots --quiet)
"$pbppo" "${auv[@]}" --out auv >/dev/null
killed auv_killed "${auv[@]}"
"$pbppo" train --resume auv_killed --threads 2 >auv_resumed.log 2>&1 || { cat auv_resumed.log; fail "resume"; }
same auv auv_killed

echo "== b: SIGINT or SIGTERM, resume.bin at the stop"
# stopped_by SIGNAL NAME: the pendulum run in NAME (no periodic state) stopped by SIGNAL after 5
# iterations exits 130 with resume.bin, and resumes to the uninterrupted run.
stopped_by() {
  local signal=$1 name=$2 rc=0 pid
  "$pbppo" "${pend_flags[@]}" --resume-every 1000 --out "$name" >"$name.log" 2>&1 &
  pid=$!
  for _ in $(seq 3000); do
    [ "$(cat "$name/log.csv" 2>/dev/null | wc -l)" -ge 6 ] && break
    sleep 0.02
  done
  kill "-$signal" "$pid"
  wait "$pid" || rc=$?
  [ "$rc" = 130 ] || { cat "$name.log"; fail "SIG$signal: exit $rc, not 130"; }
  [ -s "$name/resume.bin" ] || fail "no resume.bin after SIG$signal"
  "$pbppo" train --resume "$name" --quiet >"${name}_resumed.log" 2>&1 ||
    { cat "${name}_resumed.log"; fail "resume after SIG$signal"; }
  same pend "$name"
}
stopped_by INT stopped
stopped_by TERM termed

echo "== c: the recipes' train_run (tools/common.sh) continues a killed run"
killed recipe "${pend[@]}"
(source "$src/tools/common.sh" && train_run "$pbppo" recipe "${pend[@]}") >recipe.log 2>&1 ||
  { cat recipe.log; fail "train_run"; }
expect recipe.log "recipe: continuing the stopped run there"
same pend recipe

echo "== d: refusals"
refused() {  # refused PATTERN ARGS...: exit 2 and the message
  local pattern=$1 rc=0
  shift
  "$pbppo" "$@" >refused.log 2>&1 || rc=$?
  [ "$rc" = 2 ] || { cat refused.log; fail "'$*': exit $rc, not 2"; }
  expect refused.log "$pattern"
}
killed again "${pend[@]}"
refused "--resume: the run's options are those its resume.bin recorded; only --threads and --quiet may be given with it, not '--steps'" \
  train --resume again --steps 1000
refused "--resume: the run in 'pend' finished \(summary.json, no resume.bin\): nothing to resume" train --resume pend
refused "--resume: 'nowhere/resume.bin' does not exist" train --resume nowhere
cp again/resume.bin good.bin
/usr/bin/python3 -c 'import sys
p = sys.argv[1]; b = bytearray(open(p, "rb").read()); b[len(b) // 2] ^= 1; open(p, "wb").write(b)' again/resume.bin
refused "--resume: 'again/resume.bin': damaged \(its checksum does not match\)" train --resume again
cp pend/policy.blob again/resume.bin
refused "--resume: 'again/resume.bin': not a resume file" train --resume again
head -c 100 good.bin >again/resume.bin
refused "--resume: 'again/resume.bin': damaged" train --resume again
refused "--out is required \(or --resume DIR\)" train --env pendulum --steps 1000
cp good.bin again/resume.bin
"$pbppo" train --resume again >again.log 2>&1 || { cat again.log; fail "the undamaged file did not resume"; }
same pend again
echo "PASS"
