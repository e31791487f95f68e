#!/usr/bin/env bash
# Flies a policy through the deployment path on many seeds: for each layout and seed, the Simbody
# HIL simulator (pbppo-hil auv, lock-step) and the controller (pbppo-controller, supervisor on) as
# two processes over Fast DDS on loopback. Prints one line per mission and the success count per
# layout; writes missions.csv (layout, seed, result, targets, time) into OUT_DIR.
# Usage: tools/hil_missions.sh [OUT_DIR=build/results/hil_missions]
#   BLOB=policies/frozen/auv_nav/auv_nav.blob  LAYOUTS="easy medium hard"  SEEDS="1 2 ... 30"
set -euo pipefail
source "$(dirname "$0")/common.sh"
cd "$root"
out="${1:-build/results/hil_missions}"
blob="${BLOB:-policies/frozen/auv_nav/auv_nav.blob}"
[ -r "$blob" ] || fail "BLOB '$blob' not readable"
layouts="${LAYOUTS:-easy medium hard}"
for layout in $layouts; do
  [ -f "models/auv/layouts/$layout.yaml" ] || fail "LAYOUTS: '$layout' is not a file of models/auv/layouts"
done
seeds="${SEEDS:-$(seq -s ' ' 1 30)}"
[ -n "${seeds// /}" ] || fail "SEEDS: empty (one or more non-negative integers)"
for seed in $seeds; do non_negative_int SEEDS "$seed"; done
hil="$(program PBPPO_HIL build/default/sim_hil/pbppo-hil)"
ctl="$(program PBPPO_CONTROLLER build/default/firmware/pbppo-controller)"
mkdir -p "$out"
echo "layout,seed,result,targets,time_s" >"$out/missions.csv"
domain=$((120 + $$ % 100))
for layout in $layouts; do
  ok=0 n=0
  for seed in $seeds; do
    log="$out/$layout.$seed"
    "$hil" auv --layout "$layout" --seed "$seed" --lockstep --domain "$domain" >"$log.hil.log" 2>&1 &
    pid=$!
    "$ctl" --robot models/auv/robot.yaml --policy "$blob" --lockstep --domain "$domain" --quiet \
      >"$log.ctl.log" 2>&1 || true
    wait "$pid" || true
    # The simulator's second line: "pbppo-hil auv: <result> after <t> s simulated (...): <k>/3 targets, ..."
    line=$(sed -n 2p "$log.hil.log" | sed 's/^pbppo-hil auv: //')
    result=$(echo "$line" | sed -n 's/^\([a-z_ -]*\) after .*/\1/p')
    time_s=$(echo "$line" | sed -n 's/.* after \([0-9.]*\) s.*/\1/p')
    targets=$(echo "$line" | sed -n 's/.* \([0-9]\)\/3 targets.*/\1/p')
    echo "$layout,$seed,${result:-none},${targets:-},${time_s:-}" >>"$out/missions.csv"
    printf '%-6s seed %3s: %s\n' "$layout" "$seed" "${line:-no result (see $log.hil.log)}"
    n=$((n + 1))
    [ "$result" = success ] && ok=$((ok + 1))
  done
  echo "== $layout: $ok/$n missions completed"
done
