#!/usr/bin/env bash
# Installs every Debian package pbppo-rt needs on a Debian 12 machine, then the ONNX Runtime
# reference evaluator's npm packages (tools/onnx, pinned by its package-lock.json).
# Idempotent: packages already present are skipped; apt runs only when something is missing, npm
# only when tools/onnx/node_modules is missing or older than the lock.
# The one place where the project's system dependencies are listed.
set -euo pipefail

PACKAGES=(
  # toolchain
  build-essential cmake ninja-build git pkg-config
  clang-19 libclang-rt-19-dev clang-format-19
  # libraries
  libeigen3-dev doctest-dev libbenchmark-dev libcli11-dev nlohmann-json3-dev libyaml-cpp-dev
  libsimbody-dev
  # signed policy blobs (SHA-256, Ed25519) and the key-making script (tools/security)
  libssl-dev openssl
  # MuJoCo 2.2.2 (the quadruped's training physics); its CMake package needs qhull
  libmujoco-dev libqhull-dev
  # plots
  gnuplot-nox
  # pbppo sweep under mpirun (Open MPI: the library pbppo links, and mpirun)
  libopenmpi-dev openmpi-bin
  # DDS: Fast DDS 2.9 with its CDR library, and the IDL code generator (a Java program)
  libfastrtps-dev libfastcdr-dev fastddsgen default-jre-headless
  # a second DDS implementation (and its IDL compiler) for the ROS 2 naming interop test
  cyclonedds-dev cyclonedds-tools
  # CAN: tools, DBC decoding (python3-yaml: tools/gen_can_dbc.py), and the QEMU runner for the vcan tests (kernel has no AF_CAN)
  can-utils python3-can python3-canmatrix python3-yaml
  qemu-system-x86 busybox-static kmod cpio xz-utils
  # arm64: the cross compiler, and qemu-aarch64 for the arm64 build's tests (tools/arm64/make_root.sh
  # unpacks the arm64 libraries beside the machine's own)
  g++-aarch64-linux-gnu qemu-user
  # the service test (tests/packages): systemd as the first process of a PID namespace
  systemd
  # ONNX import (pbppo import-onnx): the ONNX library and protobuf, the test-model generator
  # (tools/onnx/make_models.py) and the ONNX Runtime reference it is checked against (tools/onnx)
  libonnx-dev libprotobuf-dev protobuf-compiler python3-onnx python3-numpy nodejs npm
)

# installed PACKAGE: dpkg has it, or (npm) another installed nodejs package provides its command:
# NodeSource's nodejs ships npm and conflicts with Debian's npm package.
installed() {
  dpkg-query -W -f='${Status}' "$1" 2>/dev/null | grep 'install ok installed' >/dev/null && return 0
  [ "$1" = npm ] && command -v npm >/dev/null
}

missing=()
for p in "${PACKAGES[@]}"; do
  if ! installed "$p"; then
    missing+=("$p")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "setup: all ${#PACKAGES[@]} packages present"
else
  echo "setup: installing ${#missing[@]} packages: ${missing[*]}"
  SUDO=""
  if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
  export DEBIAN_FRONTEND=noninteractive
  $SUDO apt-get update -qq
  $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi

# onnxruntime-node for tools/onnx/ort_eval.js, exactly as the lock pins it. --ignore-scripts: its
# install script would download CUDA binaries; the CPU binaries are in the npm package itself.
# npm ci writes node_modules/.package-lock.json last, so that file's age is node_modules' age.
onnx_tools="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)/onnx"
if [ ! -f "$onnx_tools/node_modules/.package-lock.json" ] ||
  [ "$onnx_tools/package-lock.json" -nt "$onnx_tools/node_modules/.package-lock.json" ]; then
  echo "setup: installing tools/onnx's npm packages (npm ci)"
  (cd "$onnx_tools" && npm ci --ignore-scripts --no-audit --no-fund --loglevel=error)
else
  echo "setup: tools/onnx's npm packages present"
fi
echo "setup: done"
