#!/usr/bin/env bash
# Soak runs, the long ones (the test command runs test_soak, 150,000 ticks):
#  1. the walking quadruped in lock-step for TICKS ticks (default 10^6: 1000 s of walking) under a
#     seeded schedule of velocity commands and of faults that end (a silent motor, the IMU lost, a
#     bus off and restarted, out-of-range replies, the operator silent, frame drops, pushes), the
#     robot file's recovery rule automatic: the report (every promise of
#     sim_hil/quadruped_soak.hpp, resident memory, the controller's tick per tenth of the run) and
#     plots: resident memory over the run, the tick's p50/p99/max per tenth, the mode per second;
#  2. the same in real time for REALTIME_S seconds (default 3600; 0: skip): the controller on its
#     own 1 kHz clock, deadline misses acted on as on the robot;
#  3. the AUV over DDS, two processes: one pbppo-controller in lock-step through VEHICLES vehicles
#     (default 1600: about 10^6 ticks) that come and go, with NaN and out-of-range bursts and
#     vehicles killed mid-run (tests/soak/auv_soak.sh), and a plot of the controller's resident
#     memory.
# Both quadruped runs are recorded as pbppo-controller records (--record), rotated in files of
# RECORD_MB MiB (default 64; 0: no recording), the newest 4 kept; the newest is replayed on its own.
# Quiet the machine first: other load shows up in the latency figures. Writes into OUT_DIR
# (default build/results/soak). Exit 1 when a promise broke or the latency tail drifted.
# Usage: bench/soak.sh [OUT_DIR]   (TICKS=1000000, SEED=1, REALTIME_S=3600, VEHICLES=1600 (0: skip),
#                                   RECORD_MB=64 (0: none))
set -euo pipefail
source "$(dirname "$0")/../tools/common.sh"
out="${1:-$root/build/results/soak}"
ticks="${TICKS:-1000000}"
seed="${SEED:-1}"
realtime_s="${REALTIME_S:-3600}"
vehicles="${VEHICLES:-1600}"
record_mb="${RECORD_MB:-64}"
positive_int TICKS "$ticks"
non_negative_int SEED "$seed"
non_negative_int REALTIME_S "$realtime_s"
non_negative_int VEHICLES "$vehicles"
non_negative_int RECORD_MB "$record_mb"
record() {  # record DIR: the soak's recording flags
  [ "$record_mb" -gt 0 ] || return 0
  rm -rf "$1/log" && mkdir -p "$1/log"
  echo --record "$1/log/soak.log" --record-max-mb "$record_mb" --record-rotate 4
}
hil="$(program PBPPO_HIL build/default/sim_hil/pbppo-hil)"
ctl="$(program PBPPO_CONTROLLER build/default/firmware/pbppo-controller)"
soak="$(program PBPPO_BENCH_SOAK build/default/bench/pbppo_bench_soak)"
pbppo="$(program PBPPO build/default/policies/pbppo)"
command -v gnuplot >/dev/null || fail "gnuplot not found (apt-get install gnuplot-nox)"
cd "$root"
mkdir -p "$out"

plots() {  # plots DIR TITLE
  local dir=$1 title=$2
  gnuplot <<GP
set datafile separator ","
set terminal pngcairo size 900,420
set key autotitle columnhead
set grid
set output "$dir/rss.png"
set title "$title: resident memory"
set xlabel "tick"
set ylabel "KiB"
plot "$dir/rss.csv" using 1:2 with linespoints title "resident"
set output "$dir/latency.png"
set title "$title: the controller's tick, per tenth of the run"
set xlabel "tenth of the run"
set ylabel "us"
set logscale y
plot "$dir/latency.csv" using 1:2 with linespoints title "p50", "" using 1:3 with linespoints title "p99", \
     "" using 1:4 with linespoints title "p99.9", "" using 1:5 with linespoints title "max"
unset logscale y
set output "$dir/modes.png"
set title "$title: the highest mode in each second (0 nominal, 1 degraded, 2 safe-stop, 3 e-stop)"
set xlabel "s"
set ylabel "mode"
set yrange [-0.2:3.2]
plot "$dir/modes.csv" using 1:2 with steps title "mode"
GP
}

rc=0
echo "== 1: the walking quadruped, lock-step, $ticks ticks, seed $seed"
mkdir -p "$out/lockstep" "$out/realtime"
# shellcheck disable=SC2046
"$soak" --ticks "$ticks" --seed "$seed" --out "$out/lockstep" $(record "$out/lockstep") || rc=1
plots "$out/lockstep" "soak, lock-step"
echo "   plots: $out/lockstep/{rss,latency,modes}.png"
if [ "$realtime_s" -gt 0 ]; then
  echo "== 2: the walking quadruped, real time at 1 kHz, $realtime_s s, seed $seed"
  # shellcheck disable=SC2046
  "$soak" --ticks $((realtime_s * 1000)) --seed "$seed" --realtime --out "$out/realtime" $(record "$out/realtime") ||
    rc=1
  plots "$out/realtime" "soak, real time"
  echo "   plots: $out/realtime/{rss,latency,modes}.png"
fi
if [ "$vehicles" -gt 0 ]; then
  echo "== 3: the AUV over DDS, lock-step, $vehicles vehicles that come and go, seed $seed"
  bash tests/soak/auv_soak.sh "$hil" "$ctl" "$pbppo" "$root" "$out/auv" "$vehicles" "$seed" |
    tee "$out/auv_report.txt" || rc=1
  gnuplot <<GP || rc=1
set datafile separator ","
set terminal pngcairo size 900,420
set grid
set output "$out/auv/rss.png"
set title "AUV soak: the controller's resident memory (5 samples a second)"
set xlabel "sample"
set ylabel "KiB"
plot "$out/auv/rss.csv" using 1:2 with lines title "resident"
GP
  echo "   plot: $out/auv/rss.png"
fi
exit "$rc"
