#!/usr/bin/env bash
# The arm64 packages (run by tools/test.sh after the arm64 build's tests; docs/arm64.md):
#   1. cpack writes pbppo-controller, pbppo-tools and pbppo-rt-dev for arm64: aarch64 programs, the
#      robots, the policies and the unit; every library they load is in the arm64 root and comes
#      from a package their Depends name; the packaged pbppo runs under qemu-aarch64;
#   2. the package unpacked like an installation, its controller run under qemu-aarch64 finds the
#      AUV by name in the package's own files and completes the AUV mission, lock-step over DDS
#      with the x86-64 simulator, with the portable kernel and with its own (neon): the same
#      outcome and number of steps as the x86-64 controller's with the same kernel choice, and the
#      row where float rounding first makes the trajectories differ, if it does.
# usage: arm64_package.sh ARM64_BUILD ARM64_ROOT HOST_BUILD SOURCE_DIR WORK_DIR
set -euo pipefail
abuild=$(realpath "$1") aroot=$(realpath "$2") hbuild=$(realpath "$3") src=$(realpath "$4") work=$(realpath -m "$5")
source "$src/tests/support/checks.sh"  # fail, expect, fresh_dir, trace_difference
source "$src/tests/packages/common.sh"  # make_packages
fresh_dir "$work"
[ -f "$aroot/.files" ] || fail "$aroot/.files missing: make the root with tools/arm64/make_root.sh"
dds_domain  # sets domain: one no other test holds

echo "== 1: the arm64 packages"
make_packages "$abuild" "$work/out"
deb=$(ls "$work"/out/pbppo-controller_*_arm64.deb)
ls "$work"/out/pbppo-rt-dev_*_arm64.deb >/dev/null || fail "no pbppo-rt-dev arm64 package"
[ "$(dpkg-deb -f "$deb" Architecture)" = arm64 ] || fail "$(basename "$deb"): Architecture $(dpkg-deb -f "$deb" Architecture)"
echo "   $(basename "$deb"): $(($(stat -c %s "$deb") / 1024)) KiB"
pkg=$work/pkg
dpkg-deb -x "$deb" "$pkg"
ctl=$pkg/usr/bin/pbppo-controller
readelf -h "$ctl" | grep 'Machine:.*AArch64' >/dev/null || fail "pbppo-controller is not an aarch64 program"
for f in usr/share/pbppo-rt/robots/auv/robot.yaml usr/share/pbppo-rt/policies/auv_nav/auv_nav.blob \
  usr/lib/systemd/system/pbppo-controller@.service; do
  [ -f "$pkg/$f" ] || fail "pbppo-controller (arm64) lacks $f"
done
# check_depends DEB DIR: DEB unpacked in DIR; every library its programs load comes from a package
# its Depends name (or, for pbppo-tools, the pbppo-controller package it depends on names).
check_depends() {
  local deb=$1 dir=$2 name exe so owner
  name=$(dpkg-deb -f "$deb" Package)
  { dpkg-deb -f "$deb" Depends; [ "$name" = pbppo-controller ] || dpkg-deb -f "$controller_deb" Depends; } |
    tr ',' '\n' | sed 's/^ *//; s/ .*//' >"$work/$name.depends"
  for exe in "$dir"/usr/bin/*; do
    readelf -h "$exe" | grep 'Machine:.*AArch64' >/dev/null || fail "$name: $(basename "$exe") is not an aarch64 program"
    for so in $(readelf -d "$exe" | sed -n 's/.*(NEEDED).*\[\(.*\)\]/\1/p'); do
      owner=$(awk -v so="$so" '{n = split($2, p, "/")} p[n] == so {print $1; exit}' "$aroot/.files")
      [ -n "$owner" ] || fail "$(basename "$exe") needs $so, which no arm64 package of the root holds"
      grep -qxF "$owner" "$work/$name.depends" || fail "$(basename "$exe") needs $so from $owner, which $name's Depends do not name"
    done
  done
  echo "   $name ($(cd "$dir/usr/bin" && echo *)): Depends $(dpkg-deb -f "$deb" Depends)"
}
controller_deb=$deb
check_depends "$deb" "$pkg"
tools_deb=$(ls "$work"/out/pbppo-tools_*_arm64.deb) || fail "no pbppo-tools arm64 package"
tools=$work/tools
dpkg-deb -x "$tools_deb" "$tools"
check_depends "$tools_deb" "$tools"
# The packaged pbppo runs on aarch64 with the root's libraries: it reads the packaged blob as the
# x86-64 pbppo does, line for line.
blob=$pkg/usr/share/pbppo-rt/policies/auv_nav/auv_nav.blob
qemu-aarch64 -L "$aroot" "$tools/usr/bin/pbppo" inspect "$blob" >"$work/inspect.arm64" 2>&1 ||
  fail "the packaged arm64 pbppo: $(cat "$work/inspect.arm64")"
"$hbuild/policies/pbppo" inspect "$blob" >"$work/inspect.amd64" 2>&1 || fail "pbppo inspect: $(cat "$work/inspect.amd64")"
cmp -s "$work/inspect.arm64" "$work/inspect.amd64" ||
  fail "pbppo inspect differs on aarch64: $(diff "$work/inspect.arm64" "$work/inspect.amd64" | head -5)"
echo "   the packaged arm64 pbppo reads the AUV's blob as x86-64's does ($(wc -l <"$work/inspect.arm64") lines): $(sed -n 3p "$work/inspect.arm64" | sed 's/^ *//')"

echo "== 2: the packaged arm64 controller under qemu-aarch64: the AUV mission"
shim=$abuild/tests/libpbppo_qemu_setsockopt.so  # qemu-user 7.2 and IP_MULTICAST_IF (docs/arm64.md)
[ -f "$shim" ] || fail "$shim missing (the arm64 build's tests make it)"
cd "$work"  # no models/ here: the robot is found in the package's files
mission() {  # mission NAME CONTROLLER...: the x86-64 vehicle and a controller, lock-step, seed easy:2
  local name=$1
  shift
  "$hbuild/sim_hil/pbppo-hil" auv --robot "$pkg/usr/share/pbppo-rt/robots/auv" --layout easy --seed 2 --lockstep \
    --domain "$domain" --trajectory "$name.csv" --events "$name.json" >"$name.hil.log" 2>&1 &
  local pid=$!
  "$@" --robot auv --policy "$pkg/usr/share/pbppo-rt/policies/auv_nav/auv_nav.blob" --lockstep \
    --lockstep-timeout-ms 60000 --domain "$domain" --quiet --no-mlock --rt-priority 0 >"$name.ctl.log" 2>&1 ||
    fail "$name: controller: $(cat "$name.ctl.log")"
  wait "$pid" || fail "$name: pbppo-hil exited $?: $(cat "$name.hil.log")"
  expect "$name.json" '"outcome": "success"'
  echo "   $name: $(grep -o 'on the [a-z0-9]* kernel' "$name.ctl.log"), $(grep -o '[0-9]/[0-9] targets' "$name.hil.log"), $(($(wc -l <"$name.csv") - 1)) steps"
}
arm64=(qemu-aarch64 -L "$aroot" -E LD_PRELOAD="$shim" "$ctl")
amd64=(env PBPPO_ROBOT_PATH="$pkg/usr/share/pbppo-rt/robots" "$hbuild/firmware/pbppo-controller")
# compare KERNEL: the two machines' missions with that kernel: the same outcome and steps; whether
# the trajectories are identical, else where float rounding first differs.
compare() {
  local a=arm64_$1 b=amd64_$1
  [ "$(grep -o '[0-9]/[0-9] targets' "$a.hil.log")" = "$(grep -o '[0-9]/[0-9] targets' "$b.hil.log")" ] &&
    [ "$(wc -l <"$a.csv")" = "$(wc -l <"$b.csv")" ] || fail "$1 kernel: the missions on aarch64 and x86-64 differ"
  echo "   $1 kernel: the same mission"
  trace_difference aarch64 "$a.csv" "x86-64 " "$b.csv" 2 3  # the vehicle's x, y
}
mission arm64_portable "${arm64[@]}" --kernel portable
mission amd64_portable "${amd64[@]}" --kernel portable
compare portable
# Each machine's own kernel (neon on aarch64).
mission arm64_auto "${arm64[@]}"
expect arm64_auto.ctl.log "on the neon kernel, its golden vectors passed"
mission amd64_auto "${amd64[@]}"
compare auto
echo "PASS"
