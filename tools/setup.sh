#!/usr/bin/env bash
# Installs every Debian package pbppo-rt needs on a Debian 12 machine.
# Idempotent: packages already present are skipped; apt runs only when something is missing.
# The one place where the project's system dependencies are listed.
set -euo pipefail

PACKAGES=(
  # toolchain
  build-essential cmake ninja-build git pkg-config
  clang-19 libclang-rt-19-dev clang-format-19
  # libraries
  libeigen3-dev doctest-dev libbenchmark-dev libcli11-dev nlohmann-json3-dev libyaml-cpp-dev
  libsimbody-dev
  # MuJoCo 2.2.2 (the quadruped's training physics); its CMake package needs qhull
  libmujoco-dev libqhull-dev
  # plots
  gnuplot-nox
  # DDS: Fast DDS 2.9 with its CDR library, and the IDL code generator (a Java program)
  libfastrtps-dev libfastcdr-dev fastddsgen default-jre-headless
  # a second DDS implementation (and its IDL compiler) for the ROS 2 naming interop test
  cyclonedds-dev cyclonedds-tools
  # CAN: tools, DBC decoding (python3-yaml: tools/gen_can_dbc.py), and the QEMU runner for the vcan tests (kernel has no AF_CAN)
  can-utils python3-can python3-canmatrix python3-yaml
  qemu-system-x86 busybox-static kmod cpio xz-utils
)

missing=()
for p in "${PACKAGES[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q 'install ok installed'; then
    missing+=("$p")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "setup: all ${#PACKAGES[@]} packages present"
  exit 0
fi

echo "setup: installing ${#missing[@]} packages: ${missing[*]}"
SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
echo "setup: done"
