#!/usr/bin/env bash
# The whole test suite, from a fresh Debian 12 machine: installs what is missing, builds the
# optimised and the sanitizer configurations and runs every test. Exit status 0 only if all pass.
set -euo pipefail
cd "$(dirname "$0")/.."
jobs=$(nproc)

stage() { printf '\n==== %s ====\n' "$*"; }

stage "packages"
bash tools/setup.sh

stage "optimised build (preset default)"
cmake --preset default >/dev/null
cmake --build --preset default -j "$jobs"
stage "tests: optimised build"
ctest --preset default -j "$jobs" -LE vcan

stage "SocketCAN tests (label vcan)"
if python3 -c 'import socket; socket.socket(socket.AF_CAN, socket.SOCK_RAW, socket.CAN_RAW)' 2>/dev/null &&
   ip link show vcan0 >/dev/null 2>&1; then
  echo "AF_CAN and vcan0 present: running natively"
  ctest --preset default -L vcan
else
  echo "no AF_CAN here: running them inside Debian's kernel under QEMU (tests/vm/vcan-vm)"
  tests/vm/vcan-vm --vcan 2 -- ctest --test-dir build/default -L vcan --output-on-failure
fi

stage "ASan+UBSan build of the unit tests (preset asan)"
cmake --preset asan >/dev/null
cmake --build --preset asan -j "$jobs"
stage "tests: ASan+UBSan"
ctest --preset asan -j "$jobs" -L unit

stage "ThreadSanitizer build of the unit tests (preset tsan)"
cmake --preset tsan >/dev/null
cmake --build --preset tsan -j "$jobs"
stage "tests: ThreadSanitizer"
ctest --preset tsan -j "$jobs" -L unit

stage "libFuzzer build (preset fuzz, clang-19), corpus replay and a short fuzzing run"
cmake --preset fuzz >/dev/null
targets=()
for corpus in tests/fuzz/corpus/*/; do
  name=$(basename "$corpus")
  targets+=("${name}_fuzz" "${name}_replay")
done
cmake --build --preset fuzz -j "$jobs" --target "${targets[@]}"
ctest --test-dir build/fuzz -R '^fuzz_' -j "$jobs" --output-on-failure
