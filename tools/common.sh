# Sourced by the scripts in tools/: sets `root` (the repository root) and `tool` (the script's
# name, for messages) and gives `program`, the one place that finds a built program.
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
tool="$(basename "${BASH_SOURCE[1]}" .sh)"

# program VAR PATH: prints PATH (the value of the environment variable VAR when set) or, when that
# is not an executable, says which and how to build it and exits 2.
program() {
  local path="${!1:-$root/$2}"
  if [ ! -x "$path" ]; then
    echo "$tool: $path not found (set $1 or build first: cmake --preset default && cmake --build build/default -j2)" >&2
    exit 2
  fi
  printf '%s\n' "$path"
}

# fail MESSAGE: prints "<script>: MESSAGE" to stderr and exits 2.
fail() {
  echo "$tool: $*" >&2
  exit 2
}

# positive_int NAME VALUE, non_negative_int NAME VALUE: fail naming the setting and its value unless
# VALUE is such an integer (digits only).
positive_int() {
  case "$2" in '' | *[!0-9]* | 0) fail "$1: '$2' is not a positive integer" ;; esac
}
non_negative_int() {
  case "$2" in '' | *[!0-9]*) fail "$1: '$2' is not a non-negative integer" ;; esac
}
# number_in NAME VALUE LOW HIGH WHAT: fail with "NAME: 'VALUE' is not WHAT" unless VALUE is a number
# in [LOW, HIGH] (nan and inf are not).
number_in() {
  python3 -c 'import sys; v = float(sys.argv[1]); sys.exit(0 if float(sys.argv[2]) <= v <= float(sys.argv[3]) else 1)' \
    "$2" "$3" "$4" 2>/dev/null || fail "$1: '$2' is not $5"
}

# schedule_runs OUT_DIR STEPS "SEEDS" SCHEDULE...: for every seed and schedule calls the script's
# own `train_and_eval RUN SCHEDULE SEED`, RUN being OUT_DIR/<schedule>_seed<seed> (':' as '_'),
# except where RUN already holds eval.json: a finished run is kept, so a stopped script resumes.
schedule_runs() {
  local out="$1" steps="$2" seeds="$3" seed s name
  shift 3
  mkdir -p "$out"
  for seed in $seeds; do
    for s in "$@"; do
      name="${s//:/_}_seed$seed"
      if [ -f "$out/$name/eval.json" ]; then
        echo "$name: done before, kept"
        continue
      fi
      echo "$name: training ($steps steps)"
      train_and_eval "$out/$name" "$s" "$seed"
    done
  done
}

# run_dir_argument USAGE ARGS...: sets `run` to the script's one argument, a folder (a training
# run's --out); fails with "usage: USAGE" otherwise.
run_dir_argument() {
  local usage="$1"
  shift
  if [ $# -ne 1 ] || [ ! -d "$1" ]; then
    fail "usage: $usage"
  fi
  run="$1"
}

# run_candidates RUN_DIR FIRST: sets the array `candidates` to RUN_DIR/FIRST (when it exists) and
# every RUN_DIR/snapshots/*.blob (pbppo train --snapshots), the blobs a selection script chooses
# among; fails naming both when there is none.
run_candidates() {
  local b
  candidates=()
  [ -f "$1/$2" ] && candidates+=("$1/$2")
  for b in "$1"/snapshots/*.blob; do [ -f "$b" ] && candidates+=("$b"); done
  if [ ${#candidates[@]} -eq 0 ]; then
    fail "$1 holds no $2 and no snapshots/*.blob"
  fi
}

# paper_mujoco_settings STEPS: sets the array `settings` to the paper's PPO settings for the MuJoCo
# tasks (those of its released script; its text differs in places) for STEPS training steps: the
# train flags of tools/mujoco_table.sh and tools/mujoco_budget.sh.
paper_mujoco_settings() {
  settings=(--steps "$1" --envs 1 --rollout 2048 --minibatch 64 --epochs 10 --lr 3e-4 --hidden 64-64
    --activation tanh --gamma 0.99 --gae-lambda 0.95 --ent-coef 0 --vf-coef 0.5 --max-grad-norm 0.5
    --arms 0.02:0.5:6 --feedback eval --eval-episodes 2 --threads 1 --no-plots)
}

# sweep_launcher: sets the array `launcher` from MPIRUN (e.g. "mpirun -np 16 --hostfile hosts": the
# sweep runs across machines; unset: on this one) and `jobs`, the runs at once per process: JOBS
# (default 2), 1 under MPIRUN.
sweep_launcher() {
  launcher=()
  jobs="${JOBS:-2}"
  if [ -n "${MPIRUN:-}" ]; then
    read -r -a launcher <<< "$MPIRUN"
    jobs=1
  fi
}

# train_run PBPPO DIR ARGS...: `pbppo train ARGS --out DIR`, or, where DIR holds a stopped run's
# resume.bin, that run continued with its own options (`pbppo train --resume DIR`: the weights the
# run would have given uninterrupted). Delete DIR to train afresh.
train_run() {
  local pbppo=$1 dir=$2
  shift 2
  if [ -f "$dir/resume.bin" ]; then
    echo "$dir: continuing the stopped run there (its own options; delete the folder to start afresh)" >&2
    "$pbppo" train --resume "$dir"
  else
    "$pbppo" train "$@" --out "$dir"
  fi
}
