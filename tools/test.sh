#!/usr/bin/env bash
# The whole test suite, from a fresh Debian 12 machine: installs what is missing, builds the
# optimised and the sanitizer configurations and runs every test. Exit status 0 only if all pass.
#
# Within the hour on a 2-core machine: once the optimised build is done, the ASan+UBSan, TSan,
# arm64, arm64 ASan+UBSan and libFuzzer builds run one after another in the background at the
# lowest CPU priority, on what the tests leave free (the SocketCAN tests run inside a one-vCPU VM,
# the long tests leave a core idle), and each test stage waits only for the build it needs. Every
# stage's duration is printed when the script ends, passing or not.
#
#   tools/test.sh               everything
#   tools/test.sh --builds ...  (internal) the background builds
set -euo pipefail
cd "$(dirname "$0")/.."
jobs=$(nproc)

# build PRESET [TARGET...]: configures the preset and builds it (all targets, or those named).
build() {
  local name="$1"
  shift
  cmake --preset "$name" >/dev/null
  if [ $# -gt 0 ]; then
    cmake --build --preset "$name" -j "$jobs" --target "$@"
  else
    cmake --build --preset "$name" -j "$jobs"
  fi
}

# The builds in the background: each writes build/NAME-build.log and, when done, its exit status
# to build/NAME-build.rc; the first that fails ends the sequence.
if [ "${1-}" = "--builds" ]; then
  shift
  # setsid gave these builds a session of their own, and with the kernel's autogroups a session
  # shares the CPU with the others whatever its processes' nice values: the group itself is niced
  # (measured without it: the compilers at 49 % of a core each, the tests beside them at 30 %).
  echo 19 >/proc/self/autogroup 2>/dev/null || true
  for spec in "asan" "tsan pbppo_tests_threads pbppo-controller pbppo-operator pbppo_report" "arm64" "arm64-asan" \
    "fuzz $*"; do
    read -r -a words <<<"$spec"
    rc=0
    # The arm64 build needs its root of arm64 libraries (downloaded once, then kept).
    root=""
    if [ "${words[0]}" = arm64 ]; then root="tools/arm64/make_root.sh build/arm64-root;"; fi
    nice -n 19 bash -c "set -euo pipefail; $(declare -f build); jobs=$jobs; $root build ${words[*]}" \
      >"build/${words[0]}-build.log" 2>&1 || rc=$?
    echo "$rc" >"build/${words[0]}-build.rc"
    [ "$rc" -eq 0 ] || exit "$rc"
  done
  exit 0
fi

t0=$SECONDS
stages=()
stage_name=""
stage_start=$SECONDS
builds_pid=""
end_stage() {
  if [ -n "$stage_name" ]; then
    stages+=("$(printf '%5d s  %s' $((SECONDS - stage_start)) "$stage_name")")
  fi
  stage_name=""
}
stage() {
  end_stage
  stage_name="$*"
  stage_start=$SECONDS
  printf '\n==== %s (at %d s) ====\n' "$*" $((SECONDS - t0))
}
finish() {
  local rc=$?
  if [ -n "$builds_pid" ]; then
    kill -- -"$builds_pid" 2>/dev/null || true
  fi
  end_stage
  printf '\n==== stage durations (exit status %d) ====\n' "$rc"
  printf '%s\n' "${stages[@]}"
  printf '%5d s  in all\n' $((SECONDS - t0))
}
trap finish EXIT

# wait_build NAME: waits for the background build of preset NAME; on failure prints its log.
wait_build() {
  local name="$1" rc
  while [ ! -f "build/$name-build.rc" ]; do
    if ! kill -0 "$builds_pid" 2>/dev/null && [ ! -f "build/$name-build.rc" ]; then
      echo "the background builds ended before the $name build; their logs:"
      tail -n 50 build/*-build.log
      exit 1
    fi
    sleep 5
  done
  rc=$(cat "build/$name-build.rc")
  if [ "$rc" -ne 0 ]; then
    cat "build/$name-build.log"
    echo "the $name build failed (exit status $rc)"
    exit "$rc"
  fi
  tail -n 2 "build/$name-build.log"
}

stage "packages"
bash tools/setup.sh

stage "optimised build (preset default)"
build default

fuzz_targets=()
for corpus in tests/fuzz/corpus/*/; do
  fuzz_targets+=("$(basename "$corpus")_fuzz")
done
rm -f build/*-build.rc
setsid bash "$PWD/tools/test.sh" --builds "${fuzz_targets[@]}" &
builds_pid=$!
echo "ASan+UBSan, TSan, arm64, arm64 ASan+UBSan and libFuzzer builds started in the background at nice 19 (logs: build/*-build.log)"

stage "tests: optimised build"
ctest --preset default -j "$jobs" -LE vcan --no-tests=error

stage "SocketCAN and uinput tests (label vcan)"
if python3 -c 'import socket; socket.socket(socket.AF_CAN, socket.SOCK_RAW, socket.CAN_RAW)' 2>/dev/null &&
   ip link show vcan0 >/dev/null 2>&1; then
  echo "AF_CAN and vcan0 present: running natively"
  ctest --preset default -L vcan --no-tests=error
else
  echo "no AF_CAN here: running them inside Debian's kernel under QEMU (tests/vm/vcan-vm)"
  tests/vm/vcan-vm --vcan 2 --timeout 1800 -- ctest --test-dir build/default -L vcan --output-on-failure \
    --no-tests=error
fi

# Under the sanitizers: the runtime, firmware, HIL and DDS tests (Fast DDS over loopback, within
# one process and across two), but the walk from many starts, whose figures the optimised build
# checks (under ASan it takes four minutes and runs the code the shorter walks run).
long_cases='from other starts'
stage "ASan+UBSan build (preset asan), then its tests"
wait_build asan
ctest --preset asan -j "$jobs" -L 'unit|dds' -E "$long_cases" --no-tests=error

# ThreadSanitizer on the tests that run more than one thread (label threads: the recorder's writer,
# the mailbox, the lock-step pacer, the real-time clocks), in the runtime-only configuration, which
# also proves it configures and builds without Simbody, MuJoCo or the trainer.
stage "ThreadSanitizer build (preset tsan, runtime-only), then its threaded tests"
wait_build tsan
ctest --preset tsan -j "$jobs" -L threads --no-tests=error

# The arm64 cross-build (runtime, firmware, report, DDS, the HIL, the pbppo tool) and its tests under
# qemu-aarch64: all but the SocketCAN tests, which need a kernel with vcan, and those
# tests/CMakeLists.txt names as x86-64 only (training runs, the walk from many starts).
stage "arm64 cross-build (preset arm64), then its tests under qemu-aarch64"
wait_build arm64
ctest --preset arm64 -j "$jobs" --no-tests=error
# Its packages: their Depends checked, pbppo and the controller from them run under qemu-aarch64 (the
# controller: the AUV mission).
bash tests/packages/arm64_package.sh build/arm64 build/arm64-root build/default "$PWD" build/arm64/scratch/arm64_package
# The quadruped's demo schedule, its controller and plant in one arm64 process, beside x86-64's.
bash tests/sim_hil/quadruped_demo_arm64.sh build/arm64 build/arm64-root build/default "$PWD" build/arm64/scratch/quadruped_demo

# The neon kernel under AddressSanitizer and UBSan (qemu-aarch64 runs them; no leak check there):
# the policy engine's tests (golden vectors of every shape and shipped blob) and the blob corpus.
stage "arm64 ASan+UBSan build (preset arm64-asan), then the policy engine's tests under qemu-aarch64"
wait_build arm64-asan
ctest --preset arm64-asan -j "$jobs" --no-tests=error

# The corpora are replayed as tests of the optimised and the ASan builds (fuzz_replay.*); here each
# libFuzzer binary runs from its corpus.
stage "libFuzzer build (preset fuzz, clang-19), then a short fuzzing run of each target"
wait_build fuzz
ctest --test-dir build/fuzz -R '^fuzz_run[.]' -j "$jobs" --output-on-failure --no-tests=error
