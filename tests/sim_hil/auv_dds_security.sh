#!/usr/bin/env bash
# The AUV over DDS Security (label dds): pbppo-hil auv and pbppo-controller with certificates from
# tools/security/make_dds_security.sh (authenticated, access-controlled, encrypted).
#   1. the secured lock-step mission ends as the open one does, trajectory identical;
#   2. participants without a certificate on the same domain (an open pbppo-controller and an open
#      pbppo-hil auv, publishing commands and sensor samples) are never seen: the secured pair's
#      trajectory is identical again, and the open pair runs its own mission;
#   3. a participant with a valid certificate but no permission to publish commands is refused
#      its command writer; an expired certificate, altered permissions, a certificate of another
#      CA and a missing identity are refused at start, naming the file.
# The cost, open against secured: bench/dds_security_bench.sh.
# usage: auv_dds_security.sh HIL CONTROLLER SOURCE_DIR WORK_DIR
set -euo pipefail
hil=$1 ctl=$2 src=$3 work=$4
source "$src/tests/support/checks.sh"  # fail, expect, fresh_dir, start_in
start_in "$src" "$work"
blob=policies/frozen/auv_nav/auv_nav.blob
robot=models/auv/robot.yaml
dds_domain  # sets domain: one no other test holds
# The trajectories are compared byte for byte, so no tick may run without its sample: the
# controller's lock-step timeout (500 ms, for a vanished vehicle) is raised past any pause of a
# loaded machine (sanitizer builds, encryption, the open pair beside the secured one).
wait_ms=(--lockstep-timeout-ms 20000)
sec=$work/sec
tools/security/make_dds_security.sh "$sec" \
  'controller:pbppo/auv/command+pbppo/auv/controller_status:pbppo/auv/*' \
  'hil:pbppo/auv/sensor_state:pbppo/auv/*' \
  'rogue:pbppo/auv/controller_status:pbppo/auv/*' >/dev/null
tools/security/make_dds_security.sh "$sec" --days -30 'expired:*:*' >/dev/null
tools/security/make_dds_security.sh "$work/other_ca" 'controller:*:*' >/dev/null

pair() {  # pair NAME [ARGS for both...]: a lock-step mission, easy layout, seed 2
  local name=$1
  shift
  "$hil" auv --layout easy --seed 2 --lockstep --domain "$domain" --trajectory "$work/$name.csv" "$@" \
    >"$work/$name.hil.log" 2>&1 &
  local pid=$! rc=0
  "$ctl" --robot "$robot" --policy "$blob" --lockstep "${wait_ms[@]}" --domain "$domain" "$@" \
    >"$work/$name.ctl.log" 2>&1 || rc=$?
  wait "$pid" || fail "$name: pbppo-hil exited $?: $(cat "$work/$name.hil.log")"
  [ "$rc" -eq 0 ] || fail "$name: pbppo-controller exited $rc: $(cat "$work/$name.ctl.log")"
  expect "$work/$name.hil.log" "success after .* 3/3 targets"
  expect "$work/$name.hil.log" "commands: applied [0-9]+, ignored 0"
  expect "$work/$name.ctl.log" "final mode nominal"
}

echo "== 1: the secured mission ends as the open one"
pair open
pair secured --dds-security "$sec"
cmp "$work/open.csv" "$work/secured.csv" || fail "the secured mission's trajectory differs from the open one's"
sed -n 2p "$work/open.hil.log" | sed 's/^/   open:    /'
sed -n 2p "$work/secured.hil.log" | sed 's/^/   secured: /'

echo "== 2: participants without a certificate are never seen"
"$hil" auv --layout medium --seed 1 --lockstep --domain "$domain" --trajectory "$work/intruder.csv" \
  >"$work/intruder.hil.log" 2>&1 &
ipid=$!
"$ctl" --robot "$robot" --policy "$blob" --lockstep --domain "$domain" --quiet >"$work/intruder.ctl.log" 2>&1 &
cpid=$!
sleep 1  # the open pair is publishing before the secured one starts
pair guarded --dds-security "$sec"
wait "$ipid" || fail "the open pbppo-hil exited $?: $(cat "$work/intruder.hil.log")"
wait "$cpid" || fail "the open pbppo-controller exited $?: $(cat "$work/intruder.ctl.log")"
cmp "$work/secured.csv" "$work/guarded.csv" || fail "the open participants changed the secured mission"
expect "$work/intruder.hil.log" "layout medium"  # the open pair ran its own mission, unseen
sed -n 2p "$work/guarded.hil.log" | sed 's/^/   secured, beside an open pair: /'
sed -n 2p "$work/intruder.hil.log" | sed 's/^/   the open pair, on its own:    /'

echo "== 3: refusals"
refused() {  # refused NAME PATTERN ARGS...: the controller exits non-zero at start, saying PATTERN
  local name=$1 pattern=$2 rc=0
  shift 2
  timeout 60 "$ctl" --robot "$robot" --policy "$blob" --lockstep --domain "$domain" "$@" >"$work/$name.log" 2>&1 || rc=$?
  [ "$rc" -ne 0 ] && [ "$rc" -ne 124 ] || fail "$name: exit $rc"
  expect "$work/$name.log" "$pattern"
  grep -v "^.\[" "$work/$name.log" | tail -1 | sed 's/^/   /'
}
refused rogue "dds: cannot create a writer of topic 'pbppo/auv/command'" --dds-security "$sec" --dds-identity rogue
refused expired "dds security: identity certificate '.*expired.pem' expired on " --dds-security "$sec" \
  --dds-identity expired
cp -r "$sec" "$work/altered"
sed -i 's|<default>DENY|<default>ALLOW|' "$work/altered/controller_permissions.p7s"
refused altered "dds security: permissions '.*altered/controller_permissions.p7s' does not verify against the CA" \
  --dds-security "$work/altered"
cp -r "$sec" "$work/mixed_ca"
cp "$work/other_ca/controller.pem" "$work/other_ca/controller_key.pem" "$work/mixed_ca/"
refused other_ca "dds security: identity certificate '.*mixed_ca/controller.pem' is not signed by the CA" \
  --dds-security "$work/mixed_ca"
refused nobody "dds security: '.*nobody.pem' is missing" --dds-security "$sec" --dds-identity nobody

echo "auv dds security: ok"
