#!/usr/bin/env bash
# Makes the DDS-Security files of one mrslam run (docs/security.md) into OUT_DIR:
#   identity_ca.pem, permissions_ca.pem          the two certificate authorities (ECDSA P-256)
#   <id>_cert.pem, <id>_key.pem (mode 600)       one identity per process name given
#   governance.p7s                               the domain's rules, signed by the permissions CA
#   permissions_<id>.p7s                         what each process may publish and read
# Process names: world_sim, evaluator, monitor (the launcher's progress monitor), viewer (the live
# view, a truth reader); any other name is a robot of the team. Keys never go into git: make them into a run folder or the build tree.
# Running it again keeps the CAs and identities already in OUT_DIR and signs the documents anew.
# Usage: make_identities.sh OUT_DIR ID...
set -euo pipefail
umask 077

die() {
  echo "make_identities.sh: error: $*" >&2
  exit 1
}

[ $# -ge 2 ] || die "usage: make_identities.sh OUT_DIR ID... (e.g. world_sim evaluator monitor r1 r2)"
command -v openssl >/dev/null 2>&1 || die "openssl not found (apt-get install openssl)"
out=$1
shift
ids=("$@")
robots=()
for id in "${ids[@]}"; do
  [[ $id =~ ^[A-Za-z0-9_]+$ ]] || die "process name '$id' is not made of letters, digits and '_'"
  case $id in
    world_sim | evaluator | monitor | viewer) ;;
    *) robots+=("$id") ;;
  esac
done
mkdir -p "$out"
cd "$out"
work=$(mktemp -d "./.make_identities.XXXXXX")
trap 'rm -rf "$work"' EXIT

readonly subject_base="/C=ES/O=MRSLAM"
readonly days=3650

# quiet CMD...: runs an openssl command, printing its output only if it fails.
quiet() {
  local log="$work/openssl.log"
  "$@" >"$log" 2>&1 || {
    cat "$log" >&2
    die "'$*' failed"
  }
}

# make_ca NAME CN: a self-signed CA (NAME.pem, NAME_key.pem) unless it exists.
make_ca() {
  [ -s "$1.pem" ] && [ -s "$1_key.pem" ] && return
  quiet openssl genpkey -algorithm EC -pkeyopt ec_paramgen_curve:P-256 -out "$work/$1_key.pem"
  quiet openssl req -x509 -new -key "$work/$1_key.pem" -sha256 -days "$days" -subj "$subject_base/CN=$2" \
    -out "$work/$1.pem"
  chmod 644 "$work/$1.pem"
  mv "$work/$1_key.pem" "$1_key.pem"
  mv "$work/$1.pem" "$1.pem"
}

# make_identity ID: ID_key.pem and ID_cert.pem (CN=ID) signed by the identity CA, unless they
# exist and the CA signed them.
make_identity() {
  if [ -s "$1_cert.pem" ] && [ -s "$1_key.pem" ] &&
    openssl verify -CAfile identity_ca.pem "$1_cert.pem" >/dev/null 2>&1; then
    return
  fi
  printf 'basicConstraints=critical,CA:FALSE\nkeyUsage=critical,digitalSignature\n' >"$work/ext.cnf"
  quiet openssl genpkey -algorithm EC -pkeyopt ec_paramgen_curve:P-256 -out "$work/$1_key.pem"
  quiet openssl req -new -key "$work/$1_key.pem" -subj "$subject_base/CN=$1" -out "$work/$1.csr"
  quiet openssl x509 -req -in "$work/$1.csr" -CA identity_ca.pem -CAkey identity_ca_key.pem -CAcreateserial \
    -CAserial "$work/serial" -sha256 -days "$days" -extfile "$work/ext.cnf" -out "$work/$1_cert.pem"
  chmod 600 "$work/$1_key.pem"
  chmod 644 "$work/$1_cert.pem"
  mv "$work/$1_key.pem" "$1_key.pem"
  mv "$work/$1_cert.pem" "$1_cert.pem"
}

# sign NAME: NAME.xml (in the work folder) S/MIME-signed by the permissions CA into NAME.p7s.
sign() {
  quiet openssl smime -sign -text -in "$work/$1.xml" -out "$work/$1.p7s" -signer permissions_ca.pem \
    -inkey permissions_ca_key.pem
  chmod 644 "$work/$1.p7s"
  mv "$work/$1.p7s" "$1.p7s"
}

# topics PREFIX SUFFIX...: <topic> elements, one per robot and suffix: PREFIX<robot>SUFFIX.
topics() {
  local prefix=$1
  shift
  for suffix in "$@"; do
    for r in "${robots[@]}"; do echo "<topic>$prefix$r$suffix</topic>"; done
  done
}

# peer_topics SELF DIRECTION: a robot's peer topics, into its inbox ("in") or its peers' ("out").
peer_topics() {
  for peer in "${robots[@]}"; do
    [ "$peer" = "$1" ] && continue
    for kind in relative map moved factors; do
      if [ "$2" = in ]; then
        echo "<topic>mrslam/peer/$1/from/$peer/$kind</topic>"
      else
        echo "<topic>mrslam/peer/$peer/from/$1/$kind</topic>"
      fi
    done
  done
}

# grants ID: the <publish> and <subscribe> topics of one process (docs/dds.md).
grants() {
  case $1 in
    world_sim)
      echo "<publish><topics>$(topics mrslam/ /sensors)"
      echo "<topic>mrslam/world/truth</topic><topic>mrslam/world/clock</topic></topics></publish>"
      echo "<subscribe><topics>$(topics mrslam/ /ack)</topics></subscribe>"
      ;;
    evaluator)
      echo "<subscribe><topics><topic>mrslam/world/truth</topic>"
      echo "$(topics mrslam/ /estimate /sensors /final_trajectory)</topics></subscribe>"
      ;;
    monitor)
      echo "<subscribe><topics><topic>mrslam/world/clock</topic>$(topics mrslam/ /estimate)</topics></subscribe>"
      ;;
    viewer)
      echo "<subscribe><topics><topic>mrslam/world/clock</topic><topic>mrslam/world/truth</topic>"
      echo "$(topics mrslam/ /estimate /sensors)</topics></subscribe>"
      ;;
    *)
      echo "<publish><topics><topic>mrslam/$1/estimate</topic><topic>mrslam/$1/ack</topic>"
      echo "<topic>mrslam/$1/final_trajectory</topic>$(peer_topics "$1" out)</topics></publish>"
      echo "<subscribe><topics><topic>mrslam/$1/sensors</topic><topic>mrslam/world/clock</topic>"
      echo "$(peer_topics "$1" in)</topics></subscribe>"
      ;;
  esac
}

write_governance() {
  local rule_body='<enable_discovery_protection>true</enable_discovery_protection>
        <enable_liveliness_protection>true</enable_liveliness_protection>
        <enable_read_access_control>true</enable_read_access_control>
        <enable_write_access_control>true</enable_write_access_control>
        <metadata_protection_kind>ENCRYPT</metadata_protection_kind>
        <data_protection_kind>ENCRYPT</data_protection_kind>'
  cat >"$work/governance.xml" <<XML
<?xml version="1.0" encoding="UTF-8"?>
<dds xmlns:xsi="http://www.w3.org/2001/XMLSchema-instance"
     xsi:noNamespaceSchemaLocation="http://www.omg.org/spec/DDS-SECURITY/20170801/omg_shared_ca_governance.xsd">
  <domain_access_rules>
    <domain_rule>
      <domains><id_range><min>0</min><max>232</max></id_range></domains>
      <allow_unauthenticated_participants>false</allow_unauthenticated_participants>
      <enable_join_access_control>true</enable_join_access_control>
      <discovery_protection_kind>ENCRYPT</discovery_protection_kind>
      <liveliness_protection_kind>ENCRYPT</liveliness_protection_kind>
      <rtps_protection_kind>ENCRYPT</rtps_protection_kind>
      <topic_access_rules>
        <topic_rule>
          <topic_expression>mrslam/*</topic_expression>
        $rule_body
        </topic_rule>
        <topic_rule>
          <topic_expression>*</topic_expression>
        $rule_body
        </topic_rule>
      </topic_access_rules>
    </domain_rule>
  </domain_access_rules>
</dds>
XML
}

write_permissions() {
  local subject not_before not_after
  subject=$(openssl x509 -noout -subject -nameopt RFC2253 -in "$1_cert.pem")
  subject=${subject#subject=}
  # The grant's window is read in local time: from yesterday, so that a skewed zone cannot hide it.
  not_before=$(date -d yesterday +%Y-%m-%dT%H:%M:%S)
  not_after=$(date -d "+$days days" +%Y-%m-%dT%H:%M:%S)
  cat >"$work/permissions_$1.xml" <<XML
<?xml version="1.0" encoding="UTF-8"?>
<dds xmlns:xsi="http://www.w3.org/2001/XMLSchema-instance"
     xsi:noNamespaceSchemaLocation="http://www.omg.org/spec/DDS-SECURITY/20170801/omg_shared_ca_permissions.xsd">
  <permissions>
    <grant name="$1">
      <subject_name>$subject</subject_name>
      <validity><not_before>$not_before</not_before><not_after>$not_after</not_after></validity>
      <allow_rule>
        <domains><id_range><min>0</min><max>232</max></id_range></domains>
        $(grants "$1")
      </allow_rule>
      <default>DENY</default>
    </grant>
  </permissions>
</dds>
XML
}

make_ca identity_ca "mrslam identity ca"
make_ca permissions_ca "mrslam permissions ca"
write_governance
sign governance
for id in "${ids[@]}"; do
  make_identity "$id"
  write_permissions "$id"
  sign "permissions_$id"
done
