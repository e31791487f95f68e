#!/usr/bin/env bash
# The AUV's soak over DDS, two processes (labels dds, soak): one pbppo-controller in lock-step
# (--lockstep-through-ends) with the shipped policy, its robot file's recovery rule automatic for
# stale samples, lost peers and invalid samples, and VEHICLES vehicles (pbppo-hil auv) one after
# another, each a new process and a new DDS participant: the controller loses its peer at each
# change and runs again when the next one is healthy. Drawn from SEED, each vehicle gets a layout
# and a seed, and one of: no fault, a burst of NaN samples (nan@S+D), a burst of out-of-range
# samples (range@S+D), or SIGKILL in the middle of its run. Checked: the controller runs through
# them all and ends cleanly (exit 0 at SIGTERM); no allocation in its ticks; every stop recovered
# (stops = re-arms + 1: the last vehicle's end is the last stop), no request refused; every
# vehicle that ran to its end was driven by the policy after its re-arm; every command the
# vehicles received inside the robot's limits; the controller's resident memory flat (less than 1
# MiB of growth after the first quarter of the run; five samples a second, at least 40). The
# controller records the run (rotated in files of 64 MiB); pbppo replay replays every file bit for
# bit and traces each tick's mode and samples, from which every burst of NaN or out-of-range
# samples that began while the vehicle was driven must reach safe-stop within 3 ticks (the robot
# file's invalid_safe_stop: the third invalid sample in a row).
# usage: auv_soak.sh HIL CONTROLLER PBPPO SOURCE_DIR WORK_DIR [VEHICLES] [SEED]
set -euo pipefail
hil=$1 ctl=$2 pbppo=$3 src=$4 work=$5 vehicles=${6:-40} seed=${7:-1}
source "$src/tests/support/checks.sh"  # fail, expect, fresh_dir, start_in
start_in "$src" "$work"
blob=policies/frozen/auv_nav/auv_nav.blob
dds_domain  # sets domain: one no other test holds
mkdir -p "$work/robot" "$work/log"
cp -r models/auv "$work/robot/auv"
cp models/dds_profile.xml "$work/robot/"
robot=$work/robot/auv/robot.yaml
sed -i 's/recovery: {rule: request, healthy_s: 2.0}/recovery: {rule: automatic, healthy_s: 1.0, causes: [stale sample, lost peer, invalid sample], max_automatic: 1000000}/' "$robot"
grep -q "rule: automatic" "$robot" || fail "the AUV's recovery line is not the one this soak edits"

RANDOM=$seed
layouts=(easy medium hard)
echo "== the AUV's soak: $vehicles vehicles, seed $seed, domain $domain"
# The first vehicle starts first: the controller waits for its peer before arming.
start_vehicle() {  # start_vehicle I: starts vehicle I in the background; sets vpid and vdesc
  local i=$1 layout=${layouts[$((RANDOM % 3))]} vseed=$((RANDOM % 100)) fault_args=()
  case $((i % 4)) in
    1) fault_args=(--fault "nan@$((3 + RANDOM % 5)).0+$((5 + RANDOM % 10))e-1") ;;
    2) fault_args=(--fault "range@$((3 + RANDOM % 5)).0+$((5 + RANDOM % 10))e-1") ;;
  esac
  vdesc="$layout seed $vseed ${fault_args[*]:-no fault}"
  "$hil" auv --layout "$layout" --seed "$vseed" --lockstep --domain "$domain" --trajectory "$work/v$i.csv" \
    --command-timeout 30 "${fault_args[@]}" >"$work/v$i.log" 2>&1 &
  vpid=$!
}
start_vehicle 1
"$ctl" --robot "$robot" --policy "$blob" --lockstep --lockstep-through-ends --lockstep-timeout-ms 100 \
  --domain "$domain" --quiet --record "$work/log/run.log" --record-max-mb 64 >"$work/ctl.log" 2>&1 &
cpid=$!
# The controller's resident memory, five times a second.
(
  echo "sample,rss_kib"
  s=0
  while kill -0 "$cpid" 2>/dev/null; do
    rss=$(awk '/^VmRSS:/ { print $2 }' "/proc/$cpid/status" 2>/dev/null || true)
    [ -n "$rss" ] && echo "$s,$rss"
    sleep 0.2
    s=$((s + 1))
  done
) >"$work/rss.csv" &
rss_pid=$!
killed=()
for i in $(seq 1 "$vehicles"); do
  [ "$i" -gt 1 ] && start_vehicle "$i"
  if [ $((i % 4)) -eq 3 ]; then
    sleep "0.$((2 + RANDOM % 7))"
    kill -KILL "$vpid" 2>/dev/null || true
    wait "$vpid" 2>/dev/null || true
    killed+=("$i")
    echo "   vehicle $i ($vdesc): killed"
  else
    wait "$vpid" || fail "vehicle $i ($vdesc): pbppo-hil exited $?: $(cat "$work/v$i.log")"
    outcome=$(sed -nE 's/^pbppo-hil auv: ([a-z ]+ after [0-9.]+ s simulated) \(([0-9]+) ticks.*: ([0-9]\/3 targets).*/\1, \2 ticks, \3/p' "$work/v$i.log")
    [ -n "$outcome" ] || fail "vehicle $i ($vdesc): no outcome: $(cat "$work/v$i.log")"
    echo "   vehicle $i ($vdesc): $outcome"
  fi
  kill -0 "$cpid" 2>/dev/null || fail "the controller ended during vehicle $i: $(cat "$work/ctl.log")"
done
sleep 1.5  # the last vehicle's end: lost, the last stop
kill -TERM "$cpid"
rc=0
wait "$cpid" || rc=$?
wait "$rss_pid" 2>/dev/null || true
[ "$rc" -eq 0 ] || fail "the controller exited $rc: $(cat "$work/ctl.log")"
grep -E "^controller:|^recovery:|allocations|^supervisor:" "$work/ctl.log" | sed 's/^/   /'
expect "$work/ctl.log" "control thread heap allocations during the loop: 0$"
read -r stops rearms refused < <(sed -nE 's/^recovery: stopped ([0-9]+) times, re-armed ([0-9]+) .*, ([0-9]+) requests refused$/\1 \2 \3/p' "$work/ctl.log")
[ -n "${stops:-}" ] || fail "no recovery line in the controller's summary"
[ "$rearms" -eq $((stops - 1)) ] || fail "stopped $stops times, re-armed $rearms: every stop but the last must be recovered"
[ "$stops" -ge "$vehicles" ] || fail "stopped $stops times for $vehicles vehicles: each vehicle's end is a stop"
[ "$refused" -eq 0 ] || fail "$refused re-arm requests refused"
# Every vehicle that ran to its end was driven (a forward command) after its re-arm; every command
# any vehicle received inside the robot's limits (surge [0, 1.5] m/s, yaw rate [-0.5, 0.5] rad/s).
for i in $(seq 1 "$vehicles"); do
  case " ${killed[*]:-} " in *" $i "*) continue ;; esac
  awk -F, -v v="$i" 'NR > 1 { if ($5 > 0) d++; if ($5 < 0 || $5 > 1.5 || $6 < -0.5 || $6 > 0.5) bad++ }
    END { if (d < 10 || bad > 0) { printf "vehicle %d: driven %d rows, %d commands out of limits\n", v, d, bad; exit 1 } }' \
    "$work/v$i.csv" || fail "vehicle $i was not driven within the limits"
done
# Resident memory flat after the first quarter of the samples (the start: the participant, the
# memory locked and touched at arming).
awk -F, 'NR > 1 { r[n++] = $2 } END { if (n < 40) { printf "   only %d samples of resident memory\n", n; exit 1 }
  a = r[int(n / 4)]; b = r[n - 1];
  printf "   controller resident memory: %d KiB after the first quarter, %d KiB at the end (%+d KiB, %d samples)\n", a, b, b - a, n;
  exit !(b <= a + 1024) }' "$work/rss.csv" || fail "the controller's resident memory: too few samples (a short run) or it grew"
# Every burst of NaN or out-of-range samples (surge NaN or 99: sim_hil/auv_hil.cpp) that began while
# the vehicle was driven (run phase, below safe-stop): safe-stop within 3 ticks of its first sample.
mapfile -t logs < <(ls -v "$work/log"/run*.log)
"$pbppo" replay "${logs[@]}" --robot "$robot" --policy "$blob" --trace "$work/trace.csv" \
  --trace-fields surge_mps >"$work/replay.log" 2>&1 || fail "the recording does not replay: $(cat "$work/replay.log")"
[ "$(grep -cE ": [0-9]+ ticks, [0-9]+ commands compared, 0 different$" "$work/replay.log")" -eq "${#logs[@]}" ] ||
  fail "the recording does not replay bit for bit: $(cat "$work/replay.log")"
faulty=0  # vehicles with a burst (start_vehicle: the first and second of every four)
for i in $(seq 1 "$vehicles"); do case $((i % 4)) in 1 | 2) faulty=$((faulty + 1)) ;; esac; done
awk -F, -v want="$faulty" '
  function stopped(m) { return m == "safe-stop" || m == "e-stop" }
  NR == 1 { next }
  { bad = ($4 == "nan" || $4 == 99) }
  bad && !was_bad && $2 == "run" && !stopped(prev_mode) { open_at = $1; bursts++ }
  open_at != "" && stopped($3) { d = $1 - open_at; if (d > worst) worst = d; if (d > 2) late++; open_at = "" }
  open_at != "" && !bad { late++; printf "   burst at tick %d ended without a stop\n", open_at; open_at = "" }
  { was_bad = bad; prev_mode = $3 }
  END {
    printf "   %d bursts of invalid samples while driven (%d vehicles with a fault): safe-stop within %d ticks of the first at worst, %d late\n", bursts, want, worst + 1, late
    exit !(late == 0 && bursts >= 0.9 * want)
  }' "$work/trace.csv" || fail "a burst of invalid samples did not reach safe-stop within 3 ticks, or too few bursts were seen"
echo "auv soak: all checks passed"
