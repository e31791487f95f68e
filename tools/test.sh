#!/usr/bin/env bash
# The whole test suite, from a fresh Debian 12 machine: installs what is missing, builds the
# optimised and the sanitizer configurations and runs every test. Exit status 0 only if all pass.
#
# On a 2-core machine the stages take about an hour together. The SocketCAN tests run inside a
# one-vCPU VM (no AF_CAN here), which leaves a core free: the ASan+UBSan build uses it meanwhile,
# at the lowest CPU priority so that the VM keeps its core. Every stage's duration is printed
# when the script ends, passing or not.
set -euo pipefail
cd "$(dirname "$0")/.."
jobs=$(nproc)
t0=$SECONDS
stages=()
stage_name=""
stage_start=$SECONDS

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
summary() {
  local rc=$?
  end_stage
  printf '\n==== stage durations (exit status %d) ====\n' "$rc"
  printf '%s\n' "${stages[@]}"
  printf '%5d s  in all\n' $((SECONDS - t0))
}
trap summary EXIT

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

stage "packages"
bash tools/setup.sh

stage "optimised build (preset default)"
build default
stage "tests: optimised build"
ctest --preset default -j "$jobs" -LE vcan

stage "SocketCAN tests (label vcan), beside the ASan+UBSan build"
# The ASan configuration is generated first, so that its build starts from a configured tree.
cmake --preset asan >/dev/null
if python3 -c 'import socket; socket.socket(socket.AF_CAN, socket.SOCK_RAW, socket.CAN_RAW)' 2>/dev/null &&
   ip link show vcan0 >/dev/null 2>&1; then
  echo "AF_CAN and vcan0 present: running natively"
  ctest --preset default -L vcan
else
  echo "no AF_CAN here: running them inside Debian's kernel under QEMU (tests/vm/vcan-vm);"
  echo "the ASan+UBSan build runs meanwhile at nice 19 (its output: build/asan-build.log)"
  nice -n 19 cmake --build --preset asan -j "$jobs" >build/asan-build.log 2>&1 &
  asan_pid=$!
  vm_rc=0
  tests/vm/vcan-vm --vcan 2 --timeout 1800 -- ctest --test-dir build/default -L vcan --output-on-failure || vm_rc=$?
  asan_rc=0
  wait "$asan_pid" || asan_rc=$?
  tail -n 5 build/asan-build.log
  if [ "$vm_rc" -ne 0 ]; then
    echo "the vcan tests failed (exit status $vm_rc)"
    exit "$vm_rc"
  fi
  if [ "$asan_rc" -ne 0 ]; then
    echo "the ASan+UBSan build failed (exit status $asan_rc); its log:"
    cat build/asan-build.log
    exit "$asan_rc"
  fi
fi

# The DDS tests run under ASan too (Fast DDS over loopback, within one process and across two).
stage "ASan+UBSan build (preset asan)"
build asan
stage "tests: ASan+UBSan build"
ctest --preset asan -j "$jobs" -L 'unit|dds'

# ThreadSanitizer on the tests that run more than one thread (label threads): the trainer's
# workers, the recorder's writer, the mailbox, the lock-step pacer, plants on two threads.
stage "ThreadSanitizer build of the threaded tests (preset tsan)"
build tsan pbppo_tests_threads
stage "tests: ThreadSanitizer build"
ctest --preset tsan -j "$jobs" -L threads

# What a robot controller is built with: the runtime, the firmware and the report, without
# Simbody, MuJoCo or the trainer; it must configure and build on its own.
stage "runtime-only configuration (preset runtime-only)"
build runtime-only

stage "libFuzzer build (preset fuzz, clang-19) and a short fuzzing run of each target"
# The corpora are replayed as tests of the optimised and the ASan builds (fuzz_replay.*); here
# each libFuzzer binary runs from its corpus.
targets=()
for corpus in tests/fuzz/corpus/*/; do
  targets+=("$(basename "$corpus")_fuzz")
done
build fuzz "${targets[@]}"
ctest --test-dir build/fuzz -R '^fuzz_run[.]' -j "$jobs" --output-on-failure
