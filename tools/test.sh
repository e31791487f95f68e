#!/usr/bin/env bash
# The whole test suite, from a fresh Debian 12 machine: installs what is missing, builds the
# optimised and the sanitizer configurations and runs every test. Exit status 0 only if all pass.
set -euo pipefail
cd "$(dirname "$0")/.."
jobs=$(nproc)

stage() { printf '\n==== %s ====\n' "$*"; }
# preset NAME TITLE [CTEST_ARGS...]: configures and builds the preset, then runs its tests
# (none when no CTEST_ARGS are given).
preset() {
  local name="$1" title="$2"
  shift 2
  stage "$title (preset $name)"
  cmake --preset "$name" >/dev/null
  cmake --build --preset "$name" -j "$jobs"
  if [ $# -gt 0 ]; then
    stage "tests: $title"
    ctest --preset "$name" -j "$jobs" "$@"
  fi
}

stage "packages"
bash tools/setup.sh

preset default "optimised build" -LE vcan

stage "SocketCAN tests (label vcan)"
if python3 -c 'import socket; socket.socket(socket.AF_CAN, socket.SOCK_RAW, socket.CAN_RAW)' 2>/dev/null &&
   ip link show vcan0 >/dev/null 2>&1; then
  echo "AF_CAN and vcan0 present: running natively"
  ctest --preset default -L vcan
else
  echo "no AF_CAN here: running them inside Debian's kernel under QEMU (tests/vm/vcan-vm)"
  tests/vm/vcan-vm --vcan 2 -- ctest --test-dir build/default -L vcan --output-on-failure
fi

# The DDS tests run under ASan too (Fast DDS over loopback, within one process and across two).
preset asan "ASan+UBSan build" -L 'unit|dds'

preset tsan "ThreadSanitizer build" -L unit

# What a robot controller is built with: the runtime, the firmware and the report, without
# Simbody, MuJoCo or the trainer; it must configure and build on its own.
preset runtime-only "runtime-only configuration"

stage "libFuzzer build (preset fuzz, clang-19), corpus replay and a short fuzzing run"
cmake --preset fuzz >/dev/null
targets=()
for corpus in tests/fuzz/corpus/*/; do
  name=$(basename "$corpus")
  targets+=("${name}_fuzz" "${name}_replay")
done
cmake --build --preset fuzz -j "$jobs" --target "${targets[@]}"
ctest --test-dir build/fuzz -R '^fuzz_' -j "$jobs" --output-on-failure
