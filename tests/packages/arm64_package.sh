#!/usr/bin/env bash
# The arm64 packages (run by tools/test.sh after the arm64 build's tests; docs/arm64.md):
#   1. cpack writes pbppo-controller and pbppo-rt-dev for arm64: aarch64 programs, the robots, the
#      policies and the unit; every library they load is in the arm64 root and comes from a
#      package their Depends name;
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
domain=$((200 + $$ % 30))

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
dpkg-deb -f "$deb" Depends | tr ',' '\n' | sed 's/^ *//; s/ .*//' >"$work/depends"
for exe in "$pkg"/usr/bin/*; do
  for so in $(readelf -d "$exe" | sed -n 's/.*(NEEDED).*\[\(.*\)\]/\1/p'); do
    owner=$(awk -v so="$so" '{n = split($2, p, "/")} p[n] == so {print $1; exit}' "$aroot/.files")
    [ -n "$owner" ] || fail "$(basename "$exe") needs $so, which no arm64 package of the root holds"
    grep -qxF "$owner" "$work/depends" || fail "$(basename "$exe") needs $so from $owner, which Depends do not name"
  done
done
echo "   Depends: $(tr '\n' ' ' <"$work/depends")"

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
