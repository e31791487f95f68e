#!/usr/bin/env bash
# The Debian packages and the service (label packages; root: it installs them with dpkg -i and
# removes them at its end).
#   1. cpack writes pbppo-controller, pbppo-tools and pbppo-rt-dev; the controller package holds
#      the controller, the robots, the shipped policies and the unit, and nothing of the HIL,
#      Simbody, MuJoCo or the trainer; every shared library an installed program loads comes from
#      a package its package depends on;
#   2. dpkg -i installs them; from an empty folder, with the installed files only: robots found by
#      name (an unknown name lists the installed ones), the AUV mission (pbppo-hil and the
#      controller over DDS, lock-step), the quadruped's demo schedule (pbppo-hil --in-process);
#   3. systemd as the first process of a PID namespace runs pbppo-controller@auv.service: not
#      ready while the vehicle is missing, ready once it runs (its status line), `systemctl stop`
#      stops it and the safe stop runs; a loop made to stall (--inject-stall-at-tick) is killed by
#      the watchdog, the safe stop that follows sets the vehicle's command to 0 and records the
#      failure, and the service's restart does not arm (exit status 3, the unit stays failed); a
#      person's start arms; with a robot file that says service.rearm_after_failure: true the
#      restart after the watchdog arms and runs again.
# usage: packages.sh BUILD_DIR SOURCE_DIR WORK_DIR
set -euo pipefail
build=$(realpath "$1") src=$(realpath "$2") work=$(realpath -m "$3")
source "$src/tests/support/checks.sh"  # fail, expect, fresh_dir
source "$src/tests/packages/common.sh"  # make_packages
fresh_dir "$work"
[ "$(id -u)" -eq 0 ] || fail "this test installs packages (dpkg -i): run it as root"
dds_domain  # sets domain: one no other test holds

echo "== 1: the packages"
make_packages "$build" "$work/out"
ctl_deb=$(ls "$work"/out/pbppo-controller_*_amd64.deb)
tools_deb=$(ls "$work"/out/pbppo-tools_*_amd64.deb)
dev_deb=$(ls "$work"/out/pbppo-rt-dev_*_amd64.deb)
for d in "$ctl_deb" "$tools_deb" "$dev_deb"; do
  echo "   $(basename "$d"): $(($(stat -c %s "$d") / 1024)) KiB"
done
dpkg-deb -c "$ctl_deb" | awk '{print $6}' >"$work/controller.files"
for f in ./usr/bin/pbppo-controller ./usr/bin/pbppo-operator ./usr/share/pbppo-rt/robots/auv/robot.yaml \
  ./usr/share/pbppo-rt/robots/quadruped/robot.yaml ./usr/share/pbppo-rt/robots/dds_profile.xml \
  ./usr/share/pbppo-rt/robots/ros2/idl/Twist_.idl \
  ./usr/share/pbppo-rt/policies/auv_nav/auv_nav.blob ./usr/share/pbppo-rt/policies/quadruped_walk/mixed.blob \
  ./usr/lib/systemd/system/pbppo-controller@.service ./usr/share/pbppo-rt/service/auv.conf \
  ./usr/share/doc/pbppo-rt/service.md; do
  grep -qxF "$f" "$work/controller.files" || fail "pbppo-controller lacks $f"
done
if grep -E 'pbppo-hil|/pbppo$|\.so|/include/|/report/' "$work/controller.files"; then
  fail "pbppo-controller holds what a robot does not need (above)"
fi
dpkg-deb -c "$tools_deb" | awk '{print $6}' | grep -xF ./usr/bin/pbppo-hil >/dev/null || fail "pbppo-tools lacks pbppo-hil"

# Every NEEDED library of every program comes from a package named in Depends (the controller's
# Depends count for the tools, which depend on it).
# (No `| grep -q` under pipefail: grep -q quits at its first match and the writer's SIGPIPE fails
# the pipeline.)
listed() {  # listed WORD LIST...: WORD is one of LIST
  local w=$1 x
  shift
  for x in "$@"; do [ "$x" = "$w" ] && return 0; done
  return 1
}
depends_of() { dpkg-deb -f "$1" Depends | tr ',' '\n' | sed 's/^ *//; s/ .*//'; }
check_needed() {  # check_needed DEB ALLOWED_PACKAGES...
  local deb=$1 root
  shift
  root=$work/x/$(basename "$deb" .deb)
  fresh_dir "$root"
  dpkg-deb -x "$deb" "$root"
  for exe in "$root"/usr/bin/*; do
    for so in $(objdump -p "$exe" | awk '/NEEDED/ {print $2}'); do
      local path pkg
      path=$(ldconfig -p | awk -v so="$so" '$1 == so && /x86-64/ && !f {print $NF; f = 1}')
      [ -n "$path" ] || fail "$(basename "$exe") needs $so, which this machine does not have"
      pkg=$(dpkg -S "$(readlink -f "$path")" 2>/dev/null | awk -F: 'NR == 1 {print $1}' || true)
      [ -n "$pkg" ] || pkg=$(dpkg -S "$path" 2>/dev/null | awk -F: 'NR == 1 {print $1}' || true)
      listed "$pkg" "$@" ||
        fail "$(basename "$deb"): $(basename "$exe") needs $so from $pkg, which its Depends do not name"
    done
  done
}
mapfile -t ctl_depends < <(depends_of "$ctl_deb")
mapfile -t tools_depends < <(depends_of "$tools_deb")
check_needed "$ctl_deb" "${ctl_depends[@]}"
check_needed "$tools_deb" "${tools_depends[@]}" "${ctl_depends[@]}"
if objdump -p "$work/x/$(basename "$ctl_deb" .deb)/usr/bin/pbppo-controller" | grep -Ei 'NEEDED.*(simbody|mujoco|mpi|onnx)'; then
  fail "pbppo-controller links what the HIL or the trainer need"
fi
echo "   Depends (controller): ${ctl_depends[*]}"

echo "== 2: installed: robots by name, the AUV mission, the quadruped's schedule"
cleanup() {
  [ -n "${ns_pid:-}" ] && kill -9 "$ns_pid" 2>/dev/null || true
  [ -n "${hil_pid:-}" ] && kill "$hil_pid" 2>/dev/null || true
  dpkg -r pbppo-rt-dev pbppo-tools pbppo-controller >/dev/null 2>&1 || true
}
trap cleanup EXIT
dpkg -i "$ctl_deb" "$tools_deb" "$dev_deb" >"$work/dpkg.log" 2>&1 || {
  cat "$work/dpkg.log"
  fail "dpkg -i failed"
}
[ "$(command -v pbppo-controller)" = /usr/bin/pbppo-controller ] || fail "pbppo-controller is not /usr/bin's"
share=/usr/share/pbppo-rt
fresh_dir "$work/run"
cd "$work/run"  # no models/ here: only the installed robots
rc=0
pbppo-controller --robot go3 --policy "$share/policies/auv_nav/auv_nav.blob" >unknown.log 2>&1 || rc=$?
[ "$rc" -eq 2 ] || fail "an unknown robot's name: exit $rc"
expect unknown.log "robot 'go3': no robot of that name in .*/usr/share/pbppo-rt/robots.*\(robots there: auv, auv_joy, go2, go2_remote, quadruped, quadruped_gamepad, quadruped_joy\)"
rc=0
pbppo-controller --robot 'auv;rm' >badname.log 2>&1 || rc=$?
[ "$rc" -eq 2 ] || fail "a malformed robot name: exit $rc"
expect badname.log "neither a robot file, a folder, nor a robot's name"
sed 's/^/   /' unknown.log badname.log

pbppo-hil auv --layout easy --seed 2 --lockstep --domain "$domain" --events mission.json >mission.hil.log 2>&1 &
hil_pid=$!
pbppo-controller --robot auv --policy "$share/policies/auv_nav/auv_nav.blob" --lockstep --lockstep-timeout-ms 20000 \
  --domain "$domain" --quiet --no-mlock >mission.ctl.log 2>&1 || fail "controller: $(cat mission.ctl.log)"
wait "$hil_pid" || fail "pbppo-hil auv exited $?: $(cat mission.hil.log)"
hil_pid=
expect mission.json '"outcome": "success"'
grep -E "targets|outcome|reached" mission.hil.log | sed 's/^/   /'

pbppo-hil quadruped --in-process --policy "$share/policies/quadruped_walk/flat.blob" \
  --commands "$share/robots/quadruped/schedules/demo.yaml" --scenario "$share/robots/quadruped/scenarios/flat.yaml" \
  --report quadruped.json >quadruped.log 2>&1 || fail "pbppo-hil quadruped: $(tail -20 quadruped.log)"
expect quadruped.log "controller: phase [a-z-]+, mode nominal"
expect quadruped.json '"fell": false'
grep -E "^walked|^controller:" quadruped.log | sed 's/^/   /'
# The installed gamepad robot (its files beside the quadruped's) driven by its recorded session.
pbppo-hil quadruped --robot quadruped_gamepad --in-process --operator robot --duration 20 \
  --policy "$share/policies/quadruped_walk/flat.blob" --gamepad "$share/robots/quadruped_gamepad/sessions/demo.ev" \
  --report gamepad.json >gamepad.log 2>&1 || fail "pbppo-hil quadruped (gamepad): $(tail -20 gamepad.log)"
expect gamepad.log "operator: evdev .*demo.ev: 26 events in 26 reports, 0 unmapped"
expect gamepad.log "controller: phase hold, mode nominal"
expect gamepad.json '"fell": false'
grep -E "^walked|^operator:" gamepad.log | sed 's/^/   /'

echo "== 3: pbppo-controller@auv.service under systemd"
[ -x /lib/systemd/systemd ] || fail "systemd is not installed (tools/setup.sh installs it)"
mkdir -p "$work/units"
cat >"$work/units/pbppo-test.target" <<EOF
[Unit]
Description=pbppo-rt service test
DefaultDependencies=no
Wants=systemd-journald.socket systemd-journald.service
EOF
# The namespace is a container for systemd: /run, /tmp, /var/tmp, the journal, systemd's state and
# the unit folder of its own,
# /sys and /proc/sys read-only, so that nothing it starts acts on the test machine. The unit runs as
# shipped but for a drop-in: its settings file, and no default dependencies (they would start the
# machine's early-boot services: tmpfiles, udev, sysctl, which are not under test).
cat >"$work/boot.sh" <<EOF
set -e
for d in /run /tmp /var/tmp /etc/systemd/system /var/lib/systemd /var/log/journal; do
  if [ -d "\$d" ]; then mount -t tmpfs tmpfs "\$d"; fi
done
# (/sys's cgroup mounts beneath it stay writable: systemd runs its services in cgroups)
for d in /sys /proc/sys; do mount --rbind "\$d" "\$d"; mount -o remount,bind,ro "\$d"; done
cp "$work/units/pbppo-test.target" /etc/systemd/system/
mkdir -p /etc/systemd/system/pbppo-controller@auv.service.d /run/pbppo-test
printf '[Unit]\nDefaultDependencies=no\n[Service]\nEnvironmentFile=/run/pbppo-test/auv.conf\n' \
  >/etc/systemd/system/pbppo-controller@auv.service.d/test.conf
exec env container=pbppo-test /lib/systemd/systemd --system --unit=pbppo-test.target --log-target=console \
  >"$work/systemd.log" 2>&1
EOF
unshare --pid --fork --mount --mount-proc --propagation private sh "$work/boot.sh" 2>"$work/unshare.log" &
unshare_pid=$!
ns_pid=
for _ in $(seq 100); do
  ns_pid=$(pgrep -P "$unshare_pid" || true)
  [ -n "$ns_pid" ] && nsenter -t "$ns_pid" -m -p systemctl is-system-running >/dev/null 2>&1 && break
  sleep 0.2
done
[ -n "$ns_pid" ] || fail "systemd did not start: $(cat "$work/systemd.log")"
in_ns() { nsenter -t "$ns_pid" -m -p "$@"; }
prop() { in_ns systemctl show -p "$1" --value pbppo-controller@auv; }
unit_fail() {  # unit_fail MESSAGE: the unit's status and journal, then fail
  in_ns systemctl status --no-pager -l pbppo-controller@auv | sed 's/^/   | /' || true
  in_ns journalctl --no-pager -n 60 | sed 's/^/   | /' || true
  fail "$*"
}
conf() {  # conf ARGS [ROBOT_PATH]: the settings file
  { printf 'PBPPO_ARGS="--policy %s --no-mlock --peer-timeout-s 60 %s"\nPBPPO_TRANSPORT="--domain %s"\n' \
    "$share/policies/auv_nav/auv_nav.blob" "$1" "$domain"
    [ -z "${2-}" ] || printf 'PBPPO_ROBOT_PATH=%s\n' "$2"; } | in_ns tee /run/pbppo-test/auv.conf >/dev/null
}
jlines=0
journal_new() {  # journal_new FILE: the unit's journal since the last call
  in_ns journalctl -q -u pbppo-controller@auv --no-pager >"$1.all"
  tail -n +$((jlines + 1)) "$1.all" >"$1"
  jlines=$(wc -l <"$1.all")
}
wait_state() {  # wait_state STATE SECONDS
  for _ in $(seq $(($2 * 10))); do
    [ "$(prop ActiveState)" = "$1" ] && return 0
    sleep 0.1
  done
  unit_fail "pbppo-controller@auv: $(prop ActiveState), not $1, after $2 s"
}
vehicle() {  # vehicle NAME: the AUV in real time, its trajectory in NAME.csv
  pbppo-hil auv --layout easy --seed 2 --realtime --domain "$domain" --max-time 300 --trajectory "$1.csv" \
    >"$1.hil.log" 2>&1 &
  hil_pid=$!
}
stop_vehicle() {
  kill -INT "$hil_pid"
  wait "$hil_pid" || true
  hil_pid=
}

# Start with no vehicle: the controller waits for its peer, so the unit is not ready.
conf ""
in_ns systemctl start --no-block pbppo-controller@auv
sleep 3
[ "$(prop ActiveState)" = activating ] || unit_fail "ready without its vehicle: $(prop ActiveState)"
echo "   no vehicle: $(prop ActiveState) after 3 s"
vehicle svc
wait_state active 60
status=$(prop StatusText)
echo "   vehicle there: active, status '$status'"
[[ "$status" == *"phase run"* ]] || unit_fail "status line: '$status'"
sleep 3  # three watchdog periods, fed
in_ns systemctl stop pbppo-controller@auv
[ "$(prop Result)" = success ] || unit_fail "stop: Result=$(prop Result)"
journal_new svc.journal
expect svc.journal "stopped by a signal"
expect svc.journal "pbppo-controller: auv: safe stop"
stop_vehicle

# A loop that stalls: the watchdog ends it, the safe stop sets the vehicle's command to zero and
# records the failure; the service starts the controller again, which does not arm (the AUV's robot
# file does not allow it): exit status 3, and the unit stays failed.
conf "--inject-stall-at-tick 60"
vehicle stall
in_ns systemctl start pbppo-controller@auv
echo "   stalling at tick 60: $(prop ActiveState), status '$(prop StatusText)'"
wait_state failed 40
[ "$(prop NRestarts)" = 1 ] && [ "$(prop ExecMainStatus)" = 3 ] ||
  unit_fail "after the stall: $(prop NRestarts) restarts, last exit status $(prop ExecMainStatus) (not 1 and 3)"
journal_new stall.journal
expect stall.journal "pbppo-controller: auv: safe stop"
expect stall.journal "stopped by --safe-stop, its stop done"
expect stall.journal "the run ended in failure \(result watchdog, exit (killed|dumped) ABRT, at .*\): recorded in /run/pbppo/auv/failed"
expect stall.journal "not arming: the last run ended in failure \(result watchdog.*service.rearm_after_failure"
[ "$(grep -c 'policy .* on the .* kernel' stall.journal)" = 1 ] || unit_fail "the restarted controller loaded its policy"
sleep 1
stop_vehicle
# The vehicle's commanded speed: non-zero while the stalled controller's last command held, zero at the end.
awk -F, 'NR > 1 {v = $5} NR > 1 && $5 + 0 > 0.05 {moving = 1} END {exit !(moving && v + 0 == 0)}' stall.csv ||
  fail "the vehicle's last commanded speed is $(tail -1 stall.csv | cut -d, -f5), not 0 after the safe stop"
echo "   stalled loop: watchdog, safe stop sent (commanded speed $(tail -1 stall.csv | cut -d, -f5)), restarted once:"
grep -o 'not arming: the last run ended in failure ([^)]*)' stall.journal | sed 's/^/     /'

# A person starts it again: the failure record went with the failed unit, so it arms.
conf ""
vehicle again
in_ns systemctl start pbppo-controller@auv
wait_state active 60
in_ns systemctl stop pbppo-controller@auv
[ "$(prop Result)" = success ] || unit_fail "started by a person: Result=$(prop Result)"
stop_vehicle
journal_new again.journal
if grep -E "arming again|not arming" again.journal; then fail "a person's start found a failure record"; fi
echo "   started again by a person: active, then stopped: Result=success"

# A robot file that allows it (a copy of the AUV with service.rearm_after_failure: true): after
# the watchdog the service's restart arms the robot again.
rm -rf "$work/robots" && cp -r "$share/robots" "$work/robots"  # (the robots share dds_profile.xml)
printf '\nservice:\n  rearm_after_failure: true\n' >>"$work/robots/auv/robot.yaml"
conf "--inject-stall-at-tick 60" "$work/robots"
vehicle rearm
restarts=$(prop NRestarts)  # (systemd 252 keeps counting across a person's starts)
in_ns systemctl start pbppo-controller@auv
for _ in $(seq 300); do
  [ "$(prop NRestarts)" = $((restarts + 1)) ] && [ "$(prop ActiveState)" = active ] && break
  sleep 0.1
done
[ "$(prop NRestarts)" = $((restarts + 1)) ] && [ "$(prop ActiveState)" = active ] ||
  unit_fail "rearm_after_failure: $(prop NRestarts) restarts (before: $restarts), $(prop ActiveState), not active again"
in_ns systemctl stop pbppo-controller@auv
stop_vehicle
journal_new rearm.journal
expect rearm.journal "arming again after a failure \(result watchdog.*allows it \(service.rearm_after_failure\)"
echo "   rearm_after_failure: true: restarted after the watchdog and running again, then stopped"
in_ns systemctl poweroff -f >/dev/null 2>&1 || true
wait "$unshare_pid" 2>/dev/null || true
ns_pid=
echo "PASS"
