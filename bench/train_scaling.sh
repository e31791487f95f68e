#!/usr/bin/env bash
# Where a training run's time goes as it gets more cores: the walking recipe
# (tools/train_quadruped.sh's settings: 512 robots x 24 steps, minibatch 3072, 5 epochs, 128-64-32
# ELU, the privileged critic) and Hopper (tools/mujoco_table.sh's PPO settings with its 2048-sample
# rollout spread over 16 environments x 128 steps, so that there is more than one environment to
# share) for a fixed number of iterations on 1, 2, 4, ... cores: as threads of one process and as
# mpirun ranks of one thread on this machine. For each: environment steps per second, the speed-up
# and scaling efficiency against one core (measured in the same run of this script), and the shares
# of the wall time in physics, the actor's forward passes (inference), the update (values and GAE
# included), the ranks' exchanges and the rest (summary.json's time_seconds). Every configuration's
# blob must equal the one-core blob (the run is the same, only faster): the script says so.
# Writes OUT_DIR/scaling.csv, scaling.md and scaling.png (steps per second against cores).
# Usage: bench/train_scaling.sh [OUT_DIR=runs/train_scaling]
#   PBPPO=path/to/pbppo  MPIRUN=mpirun  CORES="1 2" (default: 1, 2, 4, ... up to nproc)
#   WALK_ITERATIONS=10  HOPPER_ITERATIONS=10  TASKS="walk hopper"  REPEATS=1 (the median of so many)
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
source "$root/tools/common.sh"
out="${1:-$root/runs/train_scaling}"
pbppo="$(program PBPPO build/default/policies/pbppo)"
mpirun="${MPIRUN:-mpirun}"
ncpu=$(nproc)
if [ -z "${CORES:-}" ]; then
  CORES=""
  for ((c = 1; c <= ncpu; c *= 2)); do CORES="$CORES $c"; done
fi
walk_iterations="${WALK_ITERATIONS:-10}"
hopper_iterations="${HOPPER_ITERATIONS:-10}"
repeats="${REPEATS:-1}"
tasks="${TASKS:-walk hopper}"
for v in "$walk_iterations" "$hopper_iterations" "$repeats"; do positive_int ITERATIONS/REPEATS "$v"; done
for c in $CORES; do positive_int CORES "$c"; done
mkdir -p "$out"

flags() {  # flags TASK: the training flags of a task
  case "$1" in
    walk)
      echo --env quadruped-walk --envs 512 --rollout 24 --minibatch 3072 --epochs 5 --lr 1e-3 \
        --lr-schedule adaptive:0.01 --ent-coef 0.01 --vf-coef 1.0 --clip-vf 0.2 --max-grad-norm 1.0 \
        --hidden 128-64-32 --activation elu --schedule pbppo --arms 0.1:0.3:5 --feedback rollout \
        --steps $((512 * 24 * walk_iterations))
      ;;
    hopper)
      echo --env hopper --envs 16 --rollout 128 --minibatch 64 --epochs 10 --schedule pbppo --feedback rollout \
        --steps $((2048 * hopper_iterations))
      ;;
    *) echo "bench/train_scaling.sh: TASKS: unknown task '$1' (walk, hopper)" >&2 && exit 2 ;;
  esac
}

csv="$out/scaling.csv"
echo "task,mode,cores,ranks,threads,steps_per_s,speedup,efficiency,physics_s,inference_s,update_s,exchange_s,other_s,wall_s,same_blob" >"$csv"
for task in $tasks; do
  read -r -a f <<<"$(flags "$task")"
  base=""
  for c in $CORES; do
    for mode in threads ranks; do
      [ "$c" = 1 ] && [ "$mode" = ranks ] && continue
      ranks=1 threads=$c
      [ "$mode" = ranks ] && ranks=$c threads=1
      name="$task/${mode}_$c"
      rates=()
      mkdir -p "$out/$task"
      for ((k = 1; k <= repeats; k++)); do
        rm -rf "$out/$name"
        if [ "$ranks" = 1 ]; then
          "$pbppo" train "${f[@]}" --threads "$threads" --no-plots --quiet --out "$out/$name" >"$out/$name.log" 2>&1
        else
          "$mpirun" --allow-run-as-root --oversubscribe -np "$ranks" "$pbppo" train "${f[@]}" --threads 1 \
            --no-plots --quiet --out "$out/$name" >"$out/$name.log" 2>&1
        fi
        rates+=("$(/usr/bin/python3 -c 'import json,sys; print(json.load(open(sys.argv[1]))["steps_per_second"])' \
          "$out/$name/summary.json")")
      done
      same=yes
      [ -z "$base" ] && base="$out/$name/policy.blob"
      cmp -s "$base" "$out/$name/policy.blob" || same=no
      /usr/bin/python3 - "$out/$name/summary.json" "$task" "$mode" "$c" "$ranks" "$threads" "$same" "${rates[@]}" \
        >>"$csv" <<'PY'
import json, statistics, sys
s = json.load(open(sys.argv[1]))
task, mode, cores, ranks, threads, same = sys.argv[2:8]
rate = statistics.median(float(x) for x in sys.argv[8:])
t = s["time_seconds"]
split = t["rollout_env"] + t["rollout_policy"]
physics = t["rollout"] * t["rollout_env"] / split if split > 0 else t["rollout"]
inference = t["rollout"] - physics
update = t["update"] + t["returns"]
other = t["other"] + t["evaluation"]
print(f"{task},{mode},{cores},{ranks},{threads},{rate:.1f},,,{physics:.3f},{inference:.3f},{update:.3f},"
      f"{t['exchange']:.3f},{other:.3f},{s['wall_seconds']:.3f},{same}")
PY
      echo "$name: $(tail -1 "$csv" | cut -d, -f6) steps/s" >&2
    done
  done
done

/usr/bin/python3 - "$csv" "$out" <<'PY'
import csv, sys
path, out = sys.argv[1], sys.argv[2]
rows = list(csv.DictReader(open(path)))
one = {r["task"]: float(r["steps_per_s"]) for r in rows if r["cores"] == "1"}
for r in rows:
    s = float(r["steps_per_s"]) / one[r["task"]]
    r["speedup"] = f"{s:.3f}"
    r["efficiency"] = f"{s / int(r['cores']):.3f}"
with open(path, "w", newline="") as f:
    w = csv.DictWriter(f, fieldnames=list(rows[0].keys()))
    w.writeheader()
    w.writerows(rows)
lines = ["| task | cores | ranks x threads | steps/s | speed-up | efficiency | physics | inference | update | exchange | other | same blob |",
         "|---|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|---|"]
for r in rows:
    wall = float(r["wall_s"])
    share = lambda k: f"{100 * float(r[k]) / wall:.0f} %"
    lines.append(f"| {r['task']} | {r['cores']} | {r['ranks']} x {r['threads']} | {float(r['steps_per_s']):.0f} | "
                 f"{r['speedup']} | {r['efficiency']} | {share('physics_s')} | {share('inference_s')} | "
                 f"{share('update_s')} | {share('exchange_s')} | {share('other_s')} | {r['same_blob']} |")
open(f"{out}/scaling.md", "w").write("\n".join(lines) + "\n")
print("\n".join(lines))
PY
if command -v gnuplot >/dev/null; then
  plot=""
  for task in $tasks; do
    for mode in threads ranks; do
      grep -q "^$task,$mode," "$csv" || continue
      grep "^$task,$mode,\|^$task,threads,1," "$csv" | sort -t, -k3 -n | cut -d, -f3,6 | tr , ' ' >"$out/$task.$mode.dat"
      plot="$plot${plot:+, }'$out/$task.$mode.dat' using 1:2 with linespoints title '$task, $mode'"
    done
  done
  gnuplot -e "set terminal pngcairo size 800,500; set output '$out/scaling.png'; set logscale xy 2;
    set xlabel 'cores'; set ylabel 'environment steps per second'; set key top left; set grid; plot $plot"
fi
echo "bench/train_scaling.sh: $out/scaling.md, $out/scaling.csv, $out/scaling.png" >&2
