#!/usr/bin/env bash
# Signed policy blobs through the programs (label signing):
#   1. keys from tools/security/make_signing_key.sh; pbppo sign writes the signature beside the
#      blob; pbppo verify accepts it and refuses, each with its own message: a key it does not
#      trust, no signature, a blob changed after signing, the signature of another blob; pbppo sign
#      refuses an RSA key and a missing one;
#   2. a robot file that trusts the key: pbppo-controller and pbppo-hil refuse to arm on the
#      unsigned blob; the signed blob walks in the quadruped HIL.
# usage: sign_programs.sh PBPPO HIL CONTROLLER SOURCE_DIR WORK_DIR
set -euo pipefail
pbppo=$1 hil=$2 ctl=$3 src=$4 work=$5
source "$src/tests/support/checks.sh"  # fail, expect, fresh_dir, start_in
start_in "$src" "$work"
refused() {  # refused LOG PATTERN CMD...: exits 1, says PATTERN
  local log=$1 pattern=$2 rc=0
  shift 2
  "$@" >"$log" 2>&1 || rc=$?
  [ "$rc" -eq 1 ] || { cat "$log"; fail "$*: exit $rc, expected 1"; }
  expect "$log" "$pattern"
  sed 's/^/   /' "$log"
}

echo "== 1: pbppo sign and verify"
tools/security/make_signing_key.sh release "$work/keys" >/dev/null
tools/security/make_signing_key.sh other "$work/keys" >/dev/null
[ "$(stat -c %a "$work/keys/release.pem")" = 600 ] || fail "the private key is not mode 600"
openssl genpkey -algorithm rsa -pkeyopt rsa_keygen_bits:2048 -out "$work/keys/rsa.pem" 2>/dev/null
cp policies/frozen/quadruped_walk/flat.blob policies/frozen/quadruped_walk/flat.golden "$work/"
cp policies/frozen/quadruped_walk/mixed.blob "$work/"
"$pbppo" sign "$work/flat.blob" --key "$work/keys/release.pem" >"$work/sign.log"
expect "$work/sign.log" "signed .*flat.blob \(sha256 [0-9a-f]{64}\) with key [0-9a-f]{16}: .*flat.sig"
expect "$work/flat.sig" "^policy: io_layout 0x45b7f39b788bf22a, [0-9]+ bytes, "
"$pbppo" verify "$work/flat.blob" --key "$work/keys/release.pub" >"$work/verify.log"
expect "$work/verify.log" "verified .*flat.blob"
refused "$work/v1.log" "signed by key [0-9a-f]{16}, which the robot does not trust \(trusted: other.pub " \
  "$pbppo" verify "$work/flat.blob" --key "$work/keys/other.pub"
refused "$work/v2.log" "mixed.blob is not signed \(no .*mixed.sig\)" \
  "$pbppo" verify "$work/mixed.blob" --key "$work/keys/release.pub"
cp "$work/flat.sig" "$work/mixed.sig"
refused "$work/v3.log" "mixed.sig is the signature of another blob \(io_layout .*\), not of .*mixed.blob \(io_layout" \
  "$pbppo" verify "$work/mixed.blob" --key "$work/keys/release.pub"
cp "$work/flat.blob" "$work/changed.blob"
cp "$work/flat.sig" "$work/changed.sig"
printf '\x55' | dd of="$work/changed.blob" bs=1 seek=300 conv=notrunc status=none
refused "$work/v4.log" "changed.blob changed after it was signed \(sha256 [0-9a-f]{16} signed, [0-9a-f]{16} now" \
  "$pbppo" verify "$work/changed.blob" --key "$work/keys/release.pub"
refused "$work/s1.log" "rsa.pem: not an Ed25519 key" "$pbppo" sign "$work/flat.blob" --key "$work/keys/rsa.pem"
refused "$work/s2.log" "none.pem: cannot open" "$pbppo" sign "$work/flat.blob" --key "$work/keys/none.pem"
refused "$work/s3.log" "not an unencrypted PEM private key" \
  "$pbppo" sign "$work/flat.blob" --key "$work/keys/release.pub"

echo "== 2: a robot that trusts the key"
cp -r models "$work/models"
mkdir -p "$work/models/quadruped/keys" "$work/models/auv/keys"
cp "$work/keys/release.pub" "$work/models/quadruped/keys/"
cp "$work/keys/release.pub" "$work/models/auv/keys/"
for r in quadruped auv; do
  sed -i 's|^files:$|files:\n  trusted_keys: {release: keys/release.pub}|' "$work/models/$r/robot.yaml"
  expect "$work/models/$r/robot.yaml" "trusted_keys: \{release: keys/release.pub\}"
done
"$pbppo" verify "$work/flat.blob" --robot "$work/models/quadruped/robot.yaml" >/dev/null
rc=0
"$ctl" --robot "$work/models/auv/robot.yaml" --policy policies/frozen/auv_nav/auv_nav.blob --lockstep \
  >"$work/c1.log" 2>&1 || rc=$?
[ "$rc" -ne 0 ] || fail "pbppo-controller armed on an unsigned blob"
expect "$work/c1.log" "refusing to arm: .*auv_nav.blob is not signed \(no .*auv_nav.sig\): .* \(release [0-9a-f]{16}\)"
sed 's/^/   /' "$work/c1.log"
cat >"$work/short.yaml" <<'YAML'
stream: velocity_command
phases:
  - {name: stand, duration_s: 1.5}
  - {name: forward, duration_s: 1.5, command_vx: 0.5}
YAML
rm -f "$work/mixed.sig"
rc=0
"$hil" quadruped --robot "$work/models/quadruped/robot.yaml" --in-process --policy "$work/mixed.blob" \
  --commands "$work/short.yaml" >"$work/h1.log" 2>&1 || rc=$?
[ "$rc" -ne 0 ] || fail "pbppo-hil armed on an unsigned blob"
expect "$work/h1.log" "refusing to arm: .*mixed.blob is not signed"
sed 's/^/   /' "$work/h1.log"
"$hil" quadruped --robot "$work/models/quadruped/robot.yaml" --in-process --policy "$work/flat.blob" \
  --commands "$work/short.yaml" >"$work/h2.log" 2>&1 || { cat "$work/h2.log"; fail "the signed blob did not run"; }
expect "$work/h2.log" "no fall"
sed -n 2,5p "$work/h2.log" | sed 's/^/   signed flat.blob: /'
echo "sign programs: ok"
