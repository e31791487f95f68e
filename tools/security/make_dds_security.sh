#!/usr/bin/env bash
# Provisions DDS Security (Fast DDS's builtin PKI-DH authentication, Access-Permissions and
# AES-GCM-GMAC crypto) for the robots' DDS links: a project CA, a key and a certificate per
# participant, a governance document (authenticated participants only; discovery, liveliness and
# every pbppo topic's data encrypted; read and write access control on), and a permissions
# document per participant, each signed (S/MIME) by the CA. docs/security.md explains each file.
#
# usage: make_dds_security.sh OUT_DIR [--days N] NAME:PUBLISH:SUBSCRIBE ...
#   NAME       the participant (its certificate's CN; the programs' --dds-identity)
#   PUBLISH    topics it may publish, '+'-separated DDS topic expressions ('*': any, '-': none)
#   SUBSCRIBE  topics it may subscribe to, likewise
# Example (the AUV's two programs and an operator that may only read):
#   make_dds_security.sh keys/dds controller:pbppo/auv/command+pbppo/auv/controller_status:pbppo/auv/* \
#     hil:pbppo/auv/sensor_state:pbppo/auv/* viewer:-:pbppo/auv/*
# Files: ca.pem, ca_key.pem (keep it off the robots), governance.p7s, and per NAME: NAME.pem,
# NAME_key.pem, NAME_permissions.p7s. --days (default 3650) sets the certificates' and the
# permissions' validity; a negative value makes already-expired ones (for tests).
set -euo pipefail
out=${1:?usage: make_dds_security.sh OUT_DIR [--days N] NAME:PUBLISH:SUBSCRIBE ...}
shift
days=3650
if [ "${1:-}" = --days ]; then
  days=$2
  shift 2
fi
[ $# -gt 0 ] || { echo "make_dds_security: no participant given" >&2; exit 2; }
mkdir -p "$out"
cd "$out"
umask 077
if [ ! -f ca.pem ]; then
  openssl ecparam -name prime256v1 -genkey -noout -out ca_key.pem
  openssl req -x509 -new -key ca_key.pem -out ca.pem -days 3650 -sha256 -subj "/O=pbppo-rt/CN=pbppo-rt DDS CA" 2>/dev/null
fi
# The validity window of certificates and permissions: [now, now + days] (or ending days ago).
if [ "$days" -ge 0 ]; then
  start=$(date -u +%Y-%m-%dT%H:%M:%S) end=$(date -u -d "+$days days" +%Y-%m-%dT%H:%M:%S)
else
  start=$(date -u -d "$((days * 2)) days" +%Y-%m-%dT%H:%M:%S) end=$(date -u -d "$days days" +%Y-%m-%dT%H:%M:%S)
fi
sign() {  # sign IN.xml OUT.p7s: S/MIME, clear text, signed by the CA
  openssl smime -sign -text -in "$1" -out "$2" -signer ca.pem -inkey ca_key.pem
}
cat >governance.xml <<'XML'
<?xml version="1.0" encoding="UTF-8"?>
<dds xmlns:xsi="http://www.w3.org/2001/XMLSchema-instance"
     xsi:noNamespaceSchemaLocation="http://www.omg.org/spec/DDS-Security/20170801/omg_shared_ca_governance.xsd">
  <domain_access_rules>
    <domain_rule>
      <domains><id_range><min>0</min><max>232</max></id_range></domains>
      <allow_unauthenticated_participants>false</allow_unauthenticated_participants>
      <enable_join_access_control>true</enable_join_access_control>
      <discovery_protection_kind>ENCRYPT</discovery_protection_kind>
      <liveliness_protection_kind>ENCRYPT</liveliness_protection_kind>
      <rtps_protection_kind>NONE</rtps_protection_kind>
      <topic_access_rules>
        <topic_rule>
          <topic_expression>*</topic_expression>
          <enable_discovery_protection>true</enable_discovery_protection>
          <enable_liveliness_protection>true</enable_liveliness_protection>
          <enable_read_access_control>true</enable_read_access_control>
          <enable_write_access_control>true</enable_write_access_control>
          <metadata_protection_kind>ENCRYPT</metadata_protection_kind>
          <data_protection_kind>ENCRYPT</data_protection_kind>
        </topic_rule>
      </topic_access_rules>
    </domain_rule>
  </domain_access_rules>
</dds>
XML
sign governance.xml governance.p7s
topics() {  # topics LIST: '+'-separated expressions as <topic> elements
  local IFS=+
  for t in $1; do printf '<topic>%s</topic>' "$t"; done
}
for spec in "$@"; do
  IFS=: read -r name pub sub <<<"$spec"
  [ -n "$name" ] && [ -n "$pub" ] && [ -n "$sub" ] || { echo "make_dds_security: '$spec' is not NAME:PUBLISH:SUBSCRIBE" >&2; exit 2; }
  openssl ecparam -name prime256v1 -genkey -noout -out "${name}_key.pem"
  openssl req -new -key "${name}_key.pem" -out "$name.csr" -subj "/O=pbppo-rt/CN=$name" 2>/dev/null
  if [ "$days" -ge 0 ]; then
    openssl x509 -req -in "$name.csr" -CA ca.pem -CAkey ca_key.pem -CAcreateserial -out "$name.pem" \
      -days "$days" -sha256 2>/dev/null
  else  # already expired: a CA-signed certificate whose validity ended -days ago
    faketime=$(date -u -d "$days days" +%y%m%d%H%M%SZ) first=$(date -u -d "$((days * 2)) days" +%y%m%d%H%M%SZ)
    mkdir -p ca_db && : >ca_db/index.txt && [ -f ca_db/serial ] || echo 1000 >ca_db/serial
    cat >ca_db/ca.cnf <<CNF
[ca]
default_ca = pbppo
[pbppo]
database = ca_db/index.txt
serial = ca_db/serial
new_certs_dir = ca_db
default_md = sha256
policy = any
[any]
commonName = supplied
organizationName = optional
CNF
    openssl ca -batch -config ca_db/ca.cnf -cert ca.pem -keyfile ca_key.pem -in "$name.csr" -out "$name.pem" \
      -startdate "$first" -enddate "$faketime" -notext >/dev/null 2>&1
  fi
  rm -f "$name.csr"
  publish='' subscribe=''
  [ "$pub" = - ] || publish="<publish><topics>$(topics "$pub")</topics></publish>"
  [ "$sub" = - ] || subscribe="<subscribe><topics>$(topics "$sub")</topics></subscribe>"
  cat >"${name}_permissions.xml" <<XML
<?xml version="1.0" encoding="UTF-8"?>
<dds xmlns:xsi="http://www.w3.org/2001/XMLSchema-instance"
     xsi:noNamespaceSchemaLocation="http://www.omg.org/spec/DDS-Security/20170801/omg_shared_ca_permissions.xsd">
  <permissions>
    <grant name="$name">
      <subject_name>CN=$name,O=pbppo-rt</subject_name>
      <validity><not_before>$start</not_before><not_after>$end</not_after></validity>
      <allow_rule>
        <domains><id_range><min>0</min><max>232</max></id_range></domains>
        $publish
        $subscribe
      </allow_rule>
      <default>DENY</default>
    </grant>
  </permissions>
</dds>
XML
  sign "${name}_permissions.xml" "${name}_permissions.p7s"
done
chmod 644 ca.pem governance.p7s ./*_permissions.p7s
for spec in "$@"; do chmod 644 "${spec%%:*}.pem"; done
echo "make_dds_security: $(pwd): ca.pem, governance.p7s, and for each of: $(for s in "$@"; do printf '%s ' "${s%%:*}"; done)"
