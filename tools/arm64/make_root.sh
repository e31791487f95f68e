#!/usr/bin/env bash
# An arm64 root for cross-building and running pbppo-rt's robot side (cmake/aarch64.cmake):
# the arm64 packages of the runtime's dependencies, with everything they depend on, unpacked into
# DIR, beside (never into) the machine's own amd64 installation. Debian's multiarch cannot hold
# both: libyaml-cpp-dev has no Multi-Arch field, so installing its arm64 package removes the amd64
# one. The packages come from the machine's own apt sources; apt only downloads them here, with an
# empty package status, so their whole dependency closure comes along (the C library included:
# qemu-aarch64 -L DIR runs the programs with it).
#
# usage: tools/arm64/make_root.sh DIR     (root: adds the arm64 architecture to dpkg if missing)
# Idempotent: a DIR made from the same package list is kept (DIR/.packages records it). The root
# cannot be moved once made: its packages' CMake files name it. DIR/.files says which package each
# file came from ("PACKAGE PATH" lines; tests/packages checks package dependencies with it).
set -euo pipefail
[ $# -eq 1 ] || { echo "usage: $0 DIR" >&2; exit 2; }
dir=$1
# The robot side's build and test dependencies (see docs/arm64.md), and the libraries the pbppo
# tool runs on (MuJoCo, protobuf, Open MPI), with everything they depend on.
packages=(libc6-dev libstdc++-12-dev libyaml-cpp-dev libfastrtps-dev libfastcdr-dev libssl-dev
  nlohmann-json3-dev libeigen3-dev libcli11-dev doctest-dev
  libmujoco2.2.2 libprotobuf32 libprotobuf-lite32 zlib1g-dev libopenmpi3)
# Packages taken without the dependency closure apt would bring (their libraries' own dependencies
# are above or here):
# - the HIL's Simbody: libsimbody-dev depends on freeglut, X and Mesa (LLVM included, 90 MB more) for
#   Simbody's visualizer, which pbppo-hil does not use; its libraries need only LAPACK, BLAS and
#   libgfortran;
# - the pbppo tool's development packages: libopenmpi-dev depends on an arm64 gfortran and compiler
#   (300 MB) for mpif90 and mpicc, which a cross-build does not run; libmujoco-dev's CMake package
#   looks for OpenGL (the GL headers and glvnd's libraries, not Mesa) and names qhull's headers;
#   libonnx-dev holds the ONNX schema the tool compiles with the machine's own protoc.
bare=(libsimbody-dev libsimbody3.7 liblapack3 libblas3 libgfortran5
  libopenmpi-dev libmujoco-dev libqhull-dev libprotobuf-dev libonnx-dev
  libgl-dev libglx-dev libopengl-dev libglvnd-dev libgl1 libglx0 libopengl0 libglvnd0)
want="${packages[*]} + ${bare[*]}"
if [ -f "$dir/.packages" ] && [ -f "$dir/.files" ] && [ "$(cat "$dir/.packages")" = "$want" ]; then
  echo "arm64 root: $dir (kept)"
  exit 0
fi
if ! dpkg --print-foreign-architectures | grep -x arm64 >/dev/null; then
  dpkg --add-architecture arm64
  apt-get update -q >/dev/null
elif ! apt-cache show libc6:arm64 >/dev/null 2>&1; then
  apt-get update -q >/dev/null
fi
rm -rf "$dir"
mkdir -p "$dir"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
mkdir -p "$tmp/debs/partial" "$tmp/state"
: >"$tmp/state/status"
apt-get -q -o APT::Architecture=arm64 -o 'APT::Architectures::=arm64' -o Dir::State::status="$tmp/state/status" \
  -o Dir::Cache::archives="$tmp/debs" -o Debug::NoLocking=1 \
  install --download-only -y --no-install-recommends "${packages[@]}" >"$tmp/apt.log" 2>&1 ||
  { cat "$tmp/apt.log" >&2; echo "arm64 root: apt could not download the arm64 packages" >&2; exit 1; }
(cd "$tmp/debs" && apt-get -q -o APT::Architecture=arm64 download "${bare[@]/%/:arm64}" >"$tmp/apt-bare.log" 2>&1) ||
  { cat "$tmp/apt-bare.log" >&2; echo "arm64 root: apt could not download ${bare[*]}" >&2; exit 1; }
n=0
for deb in "$tmp"/debs/*.deb; do
  dpkg-deb -x "$deb" "$dir"
  pkg=$(dpkg-deb -f "$deb" Package)
  dpkg-deb -c "$deb" | awk -v p="$pkg" '{print p, substr($6, 2)}' >>"$tmp/files"
  n=$((n + 1))
done
# LAPACK and BLAS are reached through links update-alternatives makes when they are installed.
for lib in lapack blas; do
  for name in lib$lib.so.3 lib$lib.so; do
    ln -sfn "$lib/lib$lib.so.3" "$dir/usr/lib/aarch64-linux-gnu/$name"
    echo "lib${lib}3 /usr/lib/aarch64-linux-gnu/$name" >>"$tmp/files"
  done
done
mv "$tmp/files" "$dir/.files"
# Links to absolute paths (libfoo.so -> /lib/aarch64-linux-gnu/libfoo.so.1) point into the root.
find "$dir" -type l -lname '/*' -print0 | while IFS= read -r -d '' link; do
  target=$(readlink "$link")
  ln -sfn "$(realpath -m --relative-to="$(dirname "$link")" "$dir$target")" "$link"
done
# The packages' CMake files name their libraries by absolute paths (/usr/lib/aarch64-linux-gnu/...,
# alone or in lists): they are made to name the root's (so the root stays where it was made).
abs=$(realpath "$dir")
grep -rlZE '("|;)/usr' --include='*.cmake' "$dir" | xargs -0 -r sed -i -E "s#(\"|;)/usr#\1$abs/usr#g"
echo "$want" >"$dir/.packages"
echo "arm64 root: $dir ($n packages, $(du -sh "$dir" | cut -f1))"
