#!/usr/bin/env bash
# The AUV end to end (label dds): pbppo-hil auv and pbppo-controller as two processes over Fast DDS
# on loopback with the shipped policy.
#   1. start-up refusals: corrupted blob, a blob for another IO layout, a blob for a layout that
#      differs only in a scale, unreadable files, bad flags;
#   2. lock-step: two runs with the same seed give identical trajectories; the controller's tick
#      makes no heap allocation over the whole run;
#   3. the shipped policy completes the mission on fixed seeds of the layouts in MISSIONS;
#   4. NaN and out-of-range samples (the simulator's fault injection): the supervisor degrades,
#      then holds a safe-stop, and its counters show it;
#   5. the simulator is killed mid-run (real time): safe-stop within 3 periods, naming the cause;
#   6. record and replay: a lock-step run recorded (--record) replays (pbppo replay) to
#      bit-identical commands (and traces each tick with --trace); a log cut short replays up to
#      its last whole record and says where it ends; a log cut inside its header or corrupted is
#      refused naming the offset;
#   6b. a rotated recording (--record-max-mb, --record-rotate): the newest files kept, each no
#      larger than the size, replaying on its own from its snapshot and in order with the others;
#      files out of order and bad rotation flags refused;
#   7. recording onto a file system that fills: the mission goes on, the failure is told at once and
#      in the summary (exit 1), the log holds its whole records and an end record naming the error,
#      and replays; onto a read-only one: refused at once, before the wait for a peer;
#   8. the vehicle restarts mid-run (real time): the controller stops (e-stop, the peer lost), and
#      runs again by the robot file's recovery rule: by itself once healthy (rule automatic), or
#      only when a person asks (rule request, SIGUSR1), the new vehicle then driven by the policy.
# usage: auv_end_to_end.sh HIL CONTROLLER PBPPO SOURCE_DIR WORK_DIR
set -euo pipefail
hil=$1 ctl=$2 pbppo=$3 src=$4 work=$5
source "$src/tests/support/checks.sh"  # fail, expect, fresh_dir, start_in
start_in "$src" "$work"
blob=policies/frozen/auv_nav/auv_nav.blob
robot=models/auv/robot.yaml
# Missions the shipped policy must complete: "layout:seed ...".
missions=${PBPPO_AUV_MISSIONS:-$(cat policies/frozen/auv_nav/test_missions.txt)}
dds_domain  # sets domain: one no other test holds

echo "== 1: start-up refusals"
cp "$blob" "$work/corrupt.blob"
printf '\x55' | dd of="$work/corrupt.blob" bs=1 seek=200 conv=notrunc status=none
rc=0
"$ctl" --robot "$robot" --policy "$work/corrupt.blob" --domain "$domain" >"$work/r1.log" 2>&1 || rc=$?
[ "$rc" -ne 0 ] || fail "a corrupted blob was accepted"
expect "$work/r1.log" "corrupt.blob"
rc=0
"$ctl" --robot "$robot" --policy tests/data/blobs/p3.blob --domain "$domain" >"$work/r2.log" 2>&1 || rc=$?
[ "$rc" -ne 0 ] || fail "a blob for another layout was accepted"
expect "$work/r2.log" "does not fit robot layout 'auv'"
# Same names, one scale changed: only the layout hash differs.
cp -r models "$work/models"
sed -i 's/name: yaw_rate, signal: yaw_rate, unit: rad\/s, scale: 1.66666667/name: yaw_rate, signal: yaw_rate, unit: rad\/s, scale: 1.5/' \
  "$work/models/auv/io_layout.yaml"
"$pbppo" train --models "$work/models" --env auv-nav --layout easy --steps 2048 --envs 2 --rollout 1024 --epochs 1 \
  --no-plots --quiet --out "$work/other" >/dev/null
rc=0
"$ctl" --robot "$robot" --policy "$work/other/policy.blob" --domain "$domain" >"$work/r3.log" 2>&1 || rc=$?
[ "$rc" -ne 0 ] || fail "a blob trained for another layout hash was accepted"
expect "$work/r3.log" "layout hash"
rc=0
"$ctl" --robot "$work/none.yaml" --policy "$blob" >"$work/r4.log" 2>&1 || rc=$?
[ "$rc" -ne 0 ] || fail "a missing robot file was accepted"
expect "$work/r4.log" "none.yaml"
rc=0
"$ctl" --robot "$robot" --policy "$blob" --period-ms 0 >"$work/r5.log" 2>&1 || rc=$?
[ "$rc" -eq 2 ] || fail "--period-ms 0: exit $rc"
expect "$work/r5.log" "--period-ms: Value 0 not in range"
rc=0
"$ctl" --robot "$robot" --policy "$blob" --ticks -1 >"$work/r6.log" 2>&1 || rc=$?
[ "$rc" -eq 2 ] || fail "--ticks -1: exit $rc"
expect "$work/r6.log" "--ticks: '-1' is not an integer in \[0, 2\^64\)"
cat "$work"/r[1-6].log | sed 's/^/   /'

run_pair() {  # run_pair NAME LAYOUT SEED [HIL ARGS...] ; lock-step, both to completion
  local name=$1 layout=$2 seed=$3
  shift 3
  "$hil" auv --layout "$layout" --seed "$seed" --lockstep --domain "$domain" --trajectory "$work/$name.csv" \
    --events "$work/$name.json" "$@" >"$work/$name.hil.log" 2>&1 &
  local pid=$!
  local rc=0
  # Compared byte for byte: no tick may run without its sample, however loaded the machine (the
  # lock-step timeout, 500 ms by default, is there for a vanished vehicle).
  "$ctl" --robot "$robot" --policy "$blob" --lockstep --lockstep-timeout-ms 20000 --domain "$domain" --quiet \
    >"$work/$name.ctl.log" 2>&1 || rc=$?
  wait "$pid" || fail "$name: pbppo-hil exited $?: $(cat "$work/$name.hil.log")"
  [ "$rc" -eq 0 ] || fail "$name: pbppo-controller exited $rc: $(cat "$work/$name.ctl.log")"
}

echo "== 2: lock-step determinism, no allocation in the tick"
run_pair det1 hard 4 --max-time 40
run_pair det2 hard 4 --max-time 40
cmp "$work/det1.csv" "$work/det2.csv" || fail "two lock-step runs with the same seed differ"
[ "$(wc -l <"$work/det1.csv")" -gt 300 ] || fail "det1: short trajectory"
expect "$work/det1.ctl.log" "control thread heap allocations during the loop: 0$"
expect "$work/det1.ctl.log" "final mode nominal"
echo "   identical trajectories ($(wc -l <"$work/det1.csv") rows), 0 allocations in the control thread"

echo "== 3: missions of the shipped policy: $missions"
for m in $missions; do
  layout=${m%%:*} seed=${m##*:}
  run_pair "mission_${layout}_$seed" "$layout" "$seed"
  expect "$work/mission_${layout}_$seed.hil.log" "success after .* 3/3 targets"
  expect "$work/mission_${layout}_$seed.ctl.log" "final mode nominal"
  sed -n 2p "$work/mission_${layout}_$seed.hil.log" | sed "s/^/   $layout seed $seed: /"
  head -1 "$work/mission_${layout}_$seed.hil.log" >/dev/null
done

echo "== 4: NaN and out-of-range samples"
run_pair nan easy 5 --fault nan@3 --max-time 12
expect "$work/nan.ctl.log" "mode change: tick 30: degraded: invalid sample: (yaw_rad|surge_mps) = nan"
expect "$work/nan.ctl.log" "mode change: tick 32: safe-stop: invalid sample"
expect "$work/nan.ctl.log" "invalid sample [1-9][0-9]"
# Holding: the commands the simulator applied after the fault ramp to zero and stay there.
awk -F, 'NR > 1 && $1 >= 4.0 && ($5 != 0 || $6 != 0) {bad = 1} END {exit bad}' "$work/nan.csv" ||
  fail "commands after the safe-stop were not zero"
run_pair range easy 5 --fault range@3 --max-time 6
expect "$work/range.ctl.log" "degraded: invalid sample: surge_mps = 99"
expect "$work/range.ctl.log" "safe-stop: invalid sample"
grep -E "mode change|supervisor:" "$work/nan.ctl.log" "$work/range.ctl.log" | sed 's/^/   /'

echo "== 5: the simulator is killed mid-run (real time, 10 Hz)"
"$hil" auv --layout hard --seed 2 --realtime --domain "$domain" >"$work/kill.hil.log" 2>&1 &
hpid=$!
"$ctl" --robot "$robot" --policy "$blob" --domain "$domain" --quiet >"$work/kill.ctl.log" 2>&1 &
cpid=$!
sleep 3
kill -KILL "$hpid"
wait "$hpid" 2>/dev/null || true
sleep 1.5
kill -TERM "$cpid"
rc=0
wait "$cpid" || rc=$?
[ "$rc" -eq 0 ] || fail "controller exited $rc after SIGTERM: $(cat "$work/kill.ctl.log")"
expect "$work/kill.ctl.log" "degraded: stale sample: sensor: age 2 ticks > 1"
expect "$work/kill.ctl.log" "safe-stop: stale sample: sensor: age 3 ticks > 2"
grep -E "mode change|final mode" "$work/kill.ctl.log" | sed 's/^/   /'
echo "== 6: record and replay"
"$hil" auv --layout hard --seed 3 --lockstep --domain "$domain" --max-time 30 >"$work/rec.hil.log" 2>&1 &
hpid=$!
"$ctl" --robot "$robot" --policy "$blob" --lockstep --domain "$domain" --quiet --record "$work/run.log" \
  >"$work/rec.ctl.log" 2>&1 || fail "recording: $(cat "$work/rec.ctl.log")"
wait "$hpid" || fail "recording: pbppo-hil exited $?"
expect "$work/rec.ctl.log" "log: .*run.log, [0-9]+ records, 0 dropped"
"$pbppo" replay "$work/run.log" --robot "$robot" --policy "$blob" --out "$work/replayed.txt" >"$work/replay.log" 2>&1 ||
  fail "replay: $(cat "$work/replay.log")"
expect "$work/replay.log" "replay: .*run.log: [0-9]+ ticks, [0-9]+ commands compared, 0 different$"
[ "$(wc -l <"$work/replayed.txt")" -gt 290 ] || fail "replay: short output"
# A trace of what each tick saw: one row per tick, the fields named; an unknown field refused.
"$pbppo" replay "$work/run.log" --robot "$robot" --policy "$blob" --trace "$work/trace.csv" \
  --trace-fields tick,yaw_rad >/dev/null 2>&1 || fail "replay --trace failed"
[ "$(head -1 "$work/trace.csv")" = "tick,phase,mode,tick,yaw_rad" ] || fail "trace header: $(head -1 "$work/trace.csv")"
[ "$(wc -l <"$work/trace.csv")" -gt 290 ] || fail "replay --trace: short trace"
rc=0
"$pbppo" replay "$work/run.log" --robot "$robot" --policy "$blob" --trace "$work/trace.csv" \
  --trace-fields yaw >"$work/trace_bad.log" 2>&1 || rc=$?
[ "$rc" -eq 1 ] || fail "an unknown trace field: exit $rc"
expect "$work/trace_bad.log" "--trace-fields: 'yaw' is not a field of robot 'auv'"
# A recording cut short (a full disk): its whole records replay, and the replay says where it ends.
head -c 20000 "$work/run.log" >"$work/cut.log"
"$pbppo" replay "$work/cut.log" --robot "$robot" --policy "$blob" >"$work/replay_cut.log" 2>&1 ||
  fail "a log cut short: $(cat "$work/replay_cut.log")"
expect "$work/replay_cut.log" "replay: .*cut.log: [0-9]+ ticks, [0-9]+ commands compared, 0 different$"
expect "$work/replay_cut.log" "cut.log ends early, at offset [0-9]+: the file ends inside record [0-9]+"
# One cut inside its header has nothing to replay: refused.
head -c 40 "$work/run.log" >"$work/truncated.log"
rc=0
"$pbppo" replay "$work/truncated.log" --robot "$robot" --policy "$blob" >"$work/replay2.log" 2>&1 || rc=$?
[ "$rc" -eq 1 ] || fail "a truncated log: exit $rc"
expect "$work/replay2.log" "truncated.log: offset [0-9]+: header"
cp "$work/run.log" "$work/corrupt.log"
printf '\x55' | dd of="$work/corrupt.log" bs=1 seek=3000 conv=notrunc status=none
rc=0
"$pbppo" replay "$work/corrupt.log" --robot "$robot" --policy "$blob" >"$work/replay3.log" 2>&1 || rc=$?
[ "$rc" -eq 1 ] || fail "a corrupted log: exit $rc"
expect "$work/replay3.log" "corrupt.log: offset [0-9]+: record [0-9]+"
cat "$work/replay.log" "$work/replay_cut.log" "$work/replay2.log" "$work/replay3.log" | sed 's/^/   /'
echo "== 6b: a rotated recording (files of 30 KiB, the newest 3 kept): each file replays on its own"
"$hil" auv --layout hard --seed 3 --lockstep --domain "$domain" --max-time 30 >"$work/rot.hil.log" 2>&1 &
hpid=$!
mkdir -p "$work/rot"
"$ctl" --robot "$robot" --policy "$blob" --lockstep --domain "$domain" --quiet --record "$work/rot/run.log" \
  --record-max-mb 0.03 --record-rotate 3 >"$work/rot.ctl.log" 2>&1 || fail "rotated recording: $(cat "$work/rot.ctl.log")"
wait "$hpid" || fail "rotated recording: pbppo-hil exited $?"
expect "$work/rot.ctl.log" "log: .*run.log, [0-9]+ records, in [0-9]+ files \(.*run.log to .*run.[0-9]+.log; the [0-9]+ oldest deleted\), 0 dropped"
files=$(grep -oE "in [0-9]+ files" "$work/rot.ctl.log" | grep -oE "[0-9]+")
[ "$files" -ge 4 ] || fail "rotated recording: $files files (4 or more expected)"
kept=("$work/rot/run.$((files - 3)).log" "$work/rot/run.$((files - 2)).log" "$work/rot/run.$((files - 1)).log")
[ "$(ls "$work/rot" | wc -l)" -eq 3 ] || fail "rotated recording: $(ls "$work/rot") (the newest 3 expected)"
for f in "${kept[@]}"; do
  [ "$(stat -c %s "$f")" -le 31457 ] || fail "rotated recording: $f is larger than 0.03 MiB"
done
"$pbppo" replay "${kept[@]}" --robot "$robot" --policy "$blob" >"$work/replay_rot.log" 2>&1 ||
  fail "rotated recording: $(cat "$work/replay_rot.log")"
[ "$(grep -cE "replay: .*: [0-9]+ ticks, [0-9]+ commands compared, 0 different$" "$work/replay_rot.log")" -eq 3 ] ||
  fail "rotated recording: $(cat "$work/replay_rot.log")"
expect "$work/replay_rot.log" "run.$((files - 2)).log is file $((files - 2)) of a rotated recording: replayed from its snapshot at tick [0-9]+"
expect "$work/replay_rot.log" "run.$((files - 3)).log ends where the recording went on in the next file \(run.$((files - 2)).log\)"
# Out of order: refused, naming the file.
rc=0
"$pbppo" replay "${kept[1]}" "${kept[0]}" --robot "$robot" --policy "$blob" >"$work/replay_order.log" 2>&1 || rc=$?
[ "$rc" -eq 1 ] || fail "files out of order: exit $rc"
expect "$work/replay_order.log" "run.$((files - 3)).log: file $((files - 3)) of the recording does not follow file $((files - 2))"
# Bad rotation flags: refused before anything runs (a file too small for the loop's state is
# refused too, naming the size it needs: tests/runtime/loop/test_log.cpp).
for flags in "--record-max-mb 0.001" "--record-rotate 3" "--record-max-mb 1 --record-rotate 0"; do
  rc=0
  # shellcheck disable=SC2086
  "$ctl" --robot "$robot" --policy "$blob" --record "$work/bad.log" $flags >"$work/bad.ctl.log" 2>&1 || rc=$?
  [ "$rc" -eq 2 ] || fail "$flags: exit $rc: $(cat "$work/bad.ctl.log")"
  [ ! -e "$work/bad.log" ] || fail "$flags: a log was written"
done
rc=0
"$ctl" --robot "$robot" --policy "$blob" --record-max-mb 1 >"$work/bad.ctl.log" 2>&1 || rc=$?
[ "$rc" -eq 2 ] || fail "--record-max-mb without --record: exit $rc"
expect "$work/bad.ctl.log" "--record-max-mb requires --record"
sed 's/^/   /' "$work/replay_rot.log"
echo "== 7: recording onto a disk that fills (a 64 KiB file system; the log takes about 116 KiB)"
# The controller runs in a mount namespace of its own with a small tmpfs on the log's directory
# (mounting needs root, which the test command has); the log is copied out before it ends.
[ "$(id -u)" = 0 ] || fail "step 7 mounts a small file system: run it as root (the test command does)"
mkdir -p "$work/small"
cat >"$work/on_small_fs.sh" <<'SH'
dir=$1 out=$2
shift 2
mount -t tmpfs -o size=64k pbppo-small "$dir" || exit 97
rc=0
"$@" || rc=$?
cp "$dir"/run*.log "$out" || exit 98
exit "$rc"
SH
"$hil" auv --layout hard --seed 3 --lockstep --domain "$domain" --max-time 30 >"$work/full.hil.log" 2>&1 &
hpid=$!
rc=0
unshare --mount --propagation private bash "$work/on_small_fs.sh" "$work/small" "$work/full.log" \
  "$ctl" --robot "$robot" --policy "$blob" --lockstep --domain "$domain" --quiet --record "$work/small/run.log" \
  >"$work/full.ctl.log" 2>&1 || rc=$?
wait "$hpid" || fail "disk full: pbppo-hil exited $?: $(cat "$work/full.hil.log")"
# The run goes on to its end as step 6's did (lock-step: the same outcome, to the digit); the failure
# is told at once, in the summary, and by the exit status.
outcome() { grep -oE "[0-9]+/3 targets, return [-0-9.]+, min clearance [0-9.]+ m" "$1"; }
[ -n "$(outcome "$work/rec.hil.log")" ] && [ "$(outcome "$work/full.hil.log")" = "$(outcome "$work/rec.hil.log")" ] ||
  fail "disk full: the run differs from step 6's: '$(outcome "$work/full.hil.log")' against '$(outcome "$work/rec.hil.log")'"
[ "$rc" -eq 1 ] || fail "disk full: the controller exited $rc (1 expected): $(cat "$work/full.ctl.log")"
expect "$work/full.ctl.log" "tick [0-9]+: log .*small/run.log: write failed after [0-9]+ records: No space left on device; recording stopped, the control loop goes on"
expect "$work/full.ctl.log" "log: .*run.log, [0-9]+ records, 0 dropped, recording stopped: write failed after [0-9]+ records: No space left on device, [0-9]+ records not written"
expect "$work/full.ctl.log" "final mode nominal"
[ "$(stat -c %s "$work/full.log")" -le 65536 ] || fail "disk full: the log is larger than its file system"
# The log is whole up to where recording stopped: it replays, and says why it ends.
"$pbppo" replay "$work/full.log" --robot "$robot" --policy "$blob" >"$work/replay_full.log" 2>&1 ||
  fail "the log of a full disk: $(cat "$work/replay_full.log")"
expect "$work/replay_full.log" "replay: .*full.log: [0-9]+ ticks, [0-9]+ commands compared, 0 different$"
expect "$work/replay_full.log" "full.log ends where its recording stopped: a write failed: No space left on device \(28\); [0-9]+ records not written after it"
grep -E "write failed|recording stopped" "$work/full.ctl.log" | sed 's/^/   /'
sed 's/^/   /' "$work/replay_full.log"
# The same small file system with rotation (files of 20 KiB, the newest 2 kept): the disk never
# fills, the recording goes on to the end, and the newest files replay.
mkdir -p "$work/small_rot"
"$hil" auv --layout hard --seed 3 --lockstep --domain "$domain" --max-time 30 >"$work/keep.hil.log" 2>&1 &
hpid=$!
rc=0
unshare --mount --propagation private bash "$work/on_small_fs.sh" "$work/small" "$work/small_rot" \
  "$ctl" --robot "$robot" --policy "$blob" --lockstep --domain "$domain" --quiet --record "$work/small/run.log" \
  --record-max-mb 0.02 --record-rotate 2 >"$work/keep.ctl.log" 2>&1 || rc=$?
wait "$hpid" || fail "disk full, rotated: pbppo-hil exited $?: $(cat "$work/keep.hil.log")"
[ "$rc" -eq 0 ] || fail "disk full, rotated: the controller exited $rc: $(cat "$work/keep.ctl.log")"
expect "$work/keep.ctl.log" "log: .*run.log, [0-9]+ records, in [0-9]+ files \(.*; the [0-9]+ oldest deleted\), 0 dropped$"
mapfile -t kept < <(ls -v "$work/small_rot"/run.*.log)
[ "${#kept[@]}" -eq 2 ] || fail "disk full, rotated: ${kept[*]} (2 files expected)"
"$pbppo" replay "${kept[@]}" --robot "$robot" --policy "$blob" >"$work/replay_keep.log" 2>&1 ||
  fail "disk full, rotated: $(cat "$work/replay_keep.log")"
grep -E "^log: " "$work/keep.ctl.log" | sed 's/^/   /'
# A read-only file system: refused before anything else (no vehicle runs: it is not waited for).
mkdir -p "$work/ro"
cat >"$work/on_ro_fs.sh" <<'SH'
dir=$1
shift
mount -t tmpfs -o ro,size=64k pbppo-ro "$dir" || exit 97
"$@"
SH
rc=0
SECONDS=0
unshare --mount --propagation private bash "$work/on_ro_fs.sh" "$work/ro" \
  "$ctl" --robot "$robot" --policy "$blob" --domain "$domain" --quiet --record "$work/ro/run.log" \
  --peer-timeout-s 20 >"$work/ro.ctl.log" 2>&1 || rc=$?
[ "$rc" -eq 1 ] || fail "read-only: the controller exited $rc (1 expected): $(cat "$work/ro.ctl.log")"
expect "$work/ro.ctl.log" "log .*ro/run.log: cannot write: Read-only file system"
[ "$SECONDS" -lt 15 ] || fail "read-only: refused only after ${SECONDS} s (the wait for the peer came first)"
sed 's/^/   /' "$work/ro.ctl.log"
echo "== 8: the vehicle restarts mid-run (real time): the robot file's recovery rule, both ways"
mkdir -p "$work/rearm"
cp -r models/auv "$work/rearm/auv"
cp models/dds_profile.xml "$work/rearm/"
sed -i 's/recovery: {rule: request, healthy_s: 2.0}/recovery: {rule: automatic, healthy_s: 1.0, causes: [stale sample, lost peer]}/' \
  "$work/rearm/auv/robot.yaml"
grep -q "rule: automatic" "$work/rearm/auv/robot.yaml" || fail "step 8: the AUV's recovery line is not the one this step edits"
# A vehicle killed after 3 s; 3 s later (the peer lost after 2 s: e-stop) a new one, for 8 s of real
# time; with `request`, a person's SIGUSR1 to the controller 4 s after the new vehicle started.
vehicle_restarts() {  # vehicle_restarts NAME ROBOT_FILE [request]
  local name=$1 robot_file=$2 request=${3:-}
  "$hil" auv --layout hard --seed 2 --realtime --domain "$domain" >"$work/$name.hil1.log" 2>&1 &
  local h1=$!
  "$ctl" --robot "$robot_file" --policy "$blob" --domain "$domain" --quiet >"$work/$name.ctl.log" 2>&1 &
  local c=$!
  sleep 3
  kill -KILL "$h1"
  wait "$h1" 2>/dev/null || true
  sleep 3
  "$hil" auv --layout easy --seed 1 --realtime --domain "$domain" --max-time 8 --trajectory "$work/$name.csv" \
    >"$work/$name.hil2.log" 2>&1 &
  local h2=$!
  if [ -n "$request" ]; then
    sleep 4
    kill -USR1 "$c"
  fi
  wait "$h2" || fail "$name: the second pbppo-hil exited $?: $(cat "$work/$name.hil2.log")"
  kill -TERM "$c"
  local rc=0
  wait "$c" || rc=$?
  [ "$rc" -eq 0 ] || fail "$name: the controller exited $rc: $(cat "$work/$name.ctl.log")"
  grep -E "pbppo-controller: tick|mode change|recovery:|final mode" "$work/$name.ctl.log" | sed 's/^/   /'
}
# Seconds of the new vehicle's run with a forward speed command, and the first of them.
driven() { awk -F, 'NR > 1 && $5 > 0 { n++; if (!t) t = $1 } END { printf "%d %.1f\n", n / 10, t }' "$1"; }
vehicle_restarts automatic "$work/rearm/auv/robot.yaml"
expect "$work/automatic.ctl.log" "tick [0-9]+: safe-stop: stale sample; runs again by itself"
expect "$work/automatic.ctl.log" "tick [0-9]+: re-armed automatically after 10 healthy ticks \(stopped by: stale sample, lost peer\)"
expect "$work/automatic.ctl.log" "recovery: stopped 2 times, re-armed 1 \(1 automatically, 0 on request\), 0 requests refused"
read -r secs first <<<"$(driven "$work/automatic.csv")"
echo "   the new vehicle driven for ${secs} s of its 8 s, from ${first} s"
[ "$secs" -ge 4 ] || fail "automatic: the new vehicle was driven for only $secs s"
vehicle_restarts request "$robot" request
expect "$work/request.ctl.log" "tick [0-9]+: safe-stop: stale sample; runs again on request \(SIGUSR1; supervisor.recovery: request\)"
expect "$work/request.ctl.log" "tick [0-9]+: re-armed on request after [0-9]+ healthy ticks \(stopped by: stale sample, lost peer\)"
expect "$work/request.ctl.log" "recovery: stopped 2 times, re-armed 1 \(0 automatically, 1 on request\), 0 requests refused"
read -r secs first <<<"$(driven "$work/request.csv")"
echo "   the new vehicle driven for ${secs} s of its 8 s, from ${first} s"
[ "$secs" -ge 2 ] || fail "request: the new vehicle was driven for only $secs s"
awk "BEGIN { exit !($first >= 3.0) }" || fail "request: the new vehicle was driven from $first s, before the request"
echo "auv end to end: all checks passed"
