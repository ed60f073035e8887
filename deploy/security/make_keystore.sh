#!/usr/bin/env bash
# A DDS-Security keystore for handshare sessions (docs/security.md), in the shape of ROS 2's
# sros2 keystores: one certificate authority, one enclave folder per process identity.
#
#   make_keystore.sh [--session PATTERN] [--days N] DIR USER...
#       Creates DIR (or adds what is missing to an existing one): an ECDSA P-256 CA, the
#       governance, and one enclave per role and station: world_server, haptic/USER for each
#       USER, spectator, audio_guide, recorder, player, web_console. Every enclave gets its key,
#       its certificate and its permissions (least privilege, see below), signed (S/MIME) by the CA.
#       --session: the sessions (DDS partitions, fnmatch pattern) the grants allow; default *.
#       --days: how long certificates and grants are valid; default 365.
#   make_keystore.sh --revoke DIR ENCLAVE
#       Revokes ENCLAVE's certificate: DIR/public/crl.pem is re-issued with it listed. Every
#       participant reads the CRL at start, and then refuses the revoked station's handshake.
#       Copy the new crl.pem to every station and restart its nodes.
#
# Layout (the nodes' --security DIR reads exactly these):
#   DIR/public/ca.cert.pem       identity and permissions CA
#   DIR/public/governance.p7s    governance (protection kinds), signed by the CA
#   DIR/public/crl.pem           revoked certificates, signed by the CA
#   DIR/enclaves/E/cert.pem, key.pem, permissions.p7s   (and permissions.xml, readable)
#   DIR/private/                 the CA's key and database: keep it off the stations
# A station needs public/ and its own enclave folder only.
set -euo pipefail

usage() {
  sed -n '2,23p' "$0" | sed 's/^# \{0,1\}//' >&2
  exit 2
}
die() { echo "make_keystore: $*" >&2; exit 1; }
command -v openssl >/dev/null || die "openssl not found (Debian: apt-get install openssl)"

# Topics (core/dds/include/handshare/dds/topics.hpp).
T_MEMBER=handshare/member_info
T_SCENE=handshare/scene_state
T_BOARD=handshare/message_board
T_DEVICE=handshare/device_state
T_CONTACT=handshare/contact_set
T_OBJECT=handshare/object_state
T_DEFORM=handshare/deformation
T_EVENT=handshare/control_event
T_CONTROL=handshare/control_state
T_STATS=handshare/loop_statistics
T_ROSTER=handshare/session_roster
T_VISIT=handshare/visit_answers
T_OPCMD=handshare/operator_command
ALL_TOPICS="$T_MEMBER $T_SCENE $T_BOARD $T_DEVICE $T_CONTACT $T_OBJECT $T_DEFORM $T_EVENT $T_STATS $T_CONTROL"

# Least privilege, from who creates which writer and reader (grep MakeWriter / MakeReader):
# publish topics | subscribe topics of each role.
role_publish() {
  case "$1" in
    world_server) echo "$T_SCENE $T_BOARD $T_OBJECT $T_DEFORM $T_CONTROL $T_ROSTER $T_STATS" ;;  # stats: its tick
    haptic) echo "$T_MEMBER $T_DEVICE $T_CONTACT $T_EVENT $T_STATS" ;;
    spectator | audio_guide) echo "$T_MEMBER $T_STATS" ;;  # stats: their frames' and board loop's
    recorder) echo "" ;;
    player) echo "$ALL_TOPICS" ;;
    # The web console (docs/web_console.md): its member entry, and the operator's actions only.
    web_console) echo "$T_MEMBER $T_EVENT $T_VISIT $T_OPCMD" ;;
  esac
}
role_subscribe() {
  case "$1" in
    world_server) echo "$T_MEMBER $T_CONTACT $T_EVENT $T_VISIT $T_OPCMD $T_STATS" ;;  # stats: for the session log
    haptic) echo "$T_MEMBER $T_SCENE $T_CONTACT $T_OBJECT $T_CONTROL" ;;
    spectator) echo "$T_MEMBER $T_SCENE $T_BOARD $T_DEVICE $T_OBJECT $T_DEFORM $T_CONTROL $T_ROSTER" ;;  # roster: to rejoin
    audio_guide) echo "$T_BOARD $T_SCENE $T_CONTROL" ;;  # scene, controls: the sound cues
    recorder) echo "$ALL_TOPICS $T_ROSTER" ;;  # the roster: to rejoin (not recorded)
    player) echo "" ;;
    web_console) echo "$T_MEMBER $T_SCENE $T_BOARD $T_STATS $T_DEVICE $T_OBJECT $T_DEFORM $T_CONTROL $T_EVENT" ;;  # events: Table 4 live
  esac
}

ca_config() {  # $1 = DIR/private
  cat <<EOF
[ ca ]
default_ca = handshare_ca
[ handshare_ca ]
dir = $1
database = \$dir/index.txt
new_certs_dir = \$dir/issued
serial = \$dir/serial
crlnumber = \$dir/crlnumber
certificate = \$dir/../public/ca.cert.pem
private_key = \$dir/ca.key.pem
default_md = sha256
default_crl_days = 3650
unique_subject = no
policy = policy_any
copy_extensions = none
[ policy_any ]
organizationName = supplied
organizationalUnitName = optional
commonName = supplied
[ station ]
basicConstraints = critical, CA:FALSE
keyUsage = critical, digitalSignature, keyAgreement
EOF
}

# A grant's topic list in permissions XML.
topics_xml() {
  local t
  for t in $1; do printf '              <topic>%s</topic>\n' "$t"; done
}

# Certificates and grants start a day early: a station whose clock is a little behind still
# accepts them.
START_S=$(($(date -u +%s) - 86400))
valid_from() { date -u -d "@$START_S" "$1"; }
valid_until() { date -u -d "@$((START_S + 86400 * (DAYS + 1)))" "$1"; }

permissions_xml() {  # $1 subject (RFC 2253)  $2 role  $3 grant name
  local not_before not_after pub sub
  not_before=$(valid_from +%Y-%m-%dT%H:%M:%S)
  not_after=$(valid_until +%Y-%m-%dT%H:%M:%S)
  pub=$(role_publish "$2")
  sub=$(role_subscribe "$2")
  cat <<EOF
<?xml version="1.0" encoding="UTF-8"?>
<dds xmlns:xsi="http://www.w3.org/2001/XMLSchema-instance"
     xsi:noNamespaceSchemaLocation="http://www.omg.org/spec/DDS-SECURITY/20170901/omg_shared_ca_permissions.xsd">
  <permissions>
    <grant name="$3">
      <subject_name>$1</subject_name>
      <validity>
        <not_before>$not_before</not_before>
        <not_after>$not_after</not_after>
      </validity>
EOF
  if [ -n "$pub$sub" ]; then
    cat <<EOF
      <allow_rule>
        <domains><id_range><min>0</min><max>232</max></id_range></domains>
EOF
    if [ -n "$pub" ]; then
      printf '        <publish>\n          <topics>\n%s\n          </topics>\n' "$(topics_xml "$pub")"
      printf '          <partitions><partition>%s</partition></partitions>\n        </publish>\n' "$SESSION"
    fi
    if [ -n "$sub" ]; then
      printf '        <subscribe>\n          <topics>\n%s\n          </topics>\n' "$(topics_xml "$sub")"
      printf '          <partitions><partition>%s</partition></partitions>\n        </subscribe>\n' "$SESSION"
    fi
    echo "      </allow_rule>"
  fi
  cat <<EOF
      <default>DENY</default>
    </grant>
  </permissions>
</dds>
EOF
}

# Protection kinds (docs/security.md, "Protection kinds"): discovery, liveliness, and every
# topic's metadata (keys: user names) and payload encrypted; everything authenticated.
governance_xml() {
  cat <<'EOF'
<?xml version="1.0" encoding="UTF-8"?>
<dds xmlns:xsi="http://www.w3.org/2001/XMLSchema-instance"
     xsi:noNamespaceSchemaLocation="http://www.omg.org/spec/DDS-SECURITY/20170901/omg_shared_ca_governance.xsd">
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
          <topic_expression>handshare/*</topic_expression>
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
EOF
}

sign() {  # $1 in.xml  $2 out.p7s
  openssl smime -sign -in "$1" -text -out "$2" -signer "$DIR/public/ca.cert.pem" \
    -inkey "$DIR/private/ca.key.pem" 2>/dev/null || die "signing $1 failed"
}

make_ca() {
  mkdir -p "$DIR/public" "$DIR/private/issued" "$DIR/enclaves"
  chmod 700 "$DIR/private"
  ca_config "$(cd "$DIR/private" && pwd)" >"$DIR/private/ca.cnf"
  : >"$DIR/private/index.txt"
  echo 1000 >"$DIR/private/serial"
  echo 1000 >"$DIR/private/crlnumber"
  openssl req -x509 -nodes -days 3650 -newkey ec -pkeyopt ec_paramgen_curve:prime256v1 -sha256 \
    -keyout "$DIR/private/ca.key.pem" -out "$DIR/public/ca.cert.pem" \
    -subj "/O=handshare/CN=handshare CA" 2>/dev/null || die "creating the CA failed"
  chmod 600 "$DIR/private/ca.key.pem"
  governance_xml >"$DIR/public/governance.xml"
  sign "$DIR/public/governance.xml" "$DIR/public/governance.p7s"
  make_crl
  echo "make_keystore: CA and governance in $DIR/public"
}

make_crl() {
  openssl ca -config "$DIR/private/ca.cnf" -gencrl -out "$DIR/public/crl.pem" 2>/dev/null ||
    die "issuing the CRL failed"
}

# One enclave: key, certificate (subject O=handshare, OU=role, CN=station), permissions.
make_enclave() {  # $1 enclave path  $2 role  $3 station
  local e="$DIR/enclaves/$1" subject
  [ -f "$e/permissions.p7s" ] && return 0
  mkdir -p "$e"
  openssl req -nodes -new -newkey ec -pkeyopt ec_paramgen_curve:prime256v1 -sha256 \
    -keyout "$e/key.pem" -out "$e/cert.csr" -subj "/O=handshare/OU=$2/CN=$3" 2>/dev/null ||
    die "key for $1 failed"
  chmod 600 "$e/key.pem"
  openssl ca -config "$DIR/private/ca.cnf" -batch -notext -extensions station \
    -startdate "$(valid_from +%Y%m%d%H%M%SZ)" -enddate "$(valid_until +%Y%m%d%H%M%SZ)" \
    -in "$e/cert.csr" -out "$e/cert.pem" 2>/dev/null || die "certificate for $1 failed"
  rm -f "$e/cert.csr"
  # The grant's subject must equal the certificate's, as OpenSSL writes it in RFC 2253.
  subject=$(openssl x509 -in "$e/cert.pem" -noout -subject -nameopt RFC2253 | sed 's/^subject=//')
  permissions_xml "$subject" "$2" "$2_$3" >"$e/permissions.xml"
  sign "$e/permissions.xml" "$e/permissions.p7s"
  echo "make_keystore: enclave $1 ($subject)"
}

revoke() {  # $1 enclave path
  local cert="$DIR/enclaves/$1/cert.pem"
  [ -f "$DIR/private/ca.cnf" ] || die "$DIR is not a keystore (no $DIR/private/ca.cnf)"
  [ -f "$cert" ] || die "no enclave '$1' in $DIR (no $cert)"
  openssl ca -config "$DIR/private/ca.cnf" -revoke "$cert" 2>/dev/null || die "revoking $cert failed"
  make_crl
  echo "make_keystore: revoked $1; copy $DIR/public/crl.pem to every station and restart its nodes"
}

SESSION='*'
DAYS=365
REVOKE=""
while [ $# -gt 0 ]; do
  case "$1" in
    --session) SESSION=${2:?--session needs a pattern}; shift 2 ;;
    --days) DAYS=${2:?--days needs a number}; shift 2 ;;
    --revoke) REVOKE=1; shift ;;
    -h | --help) usage ;;
    -*) echo "make_keystore: unknown option $1" >&2; usage ;;
    *) break ;;
  esac
done
[ $# -ge 1 ] || usage
DIR=$1
shift
[[ "$DAYS" =~ ^[1-9][0-9]*$ ]] || die "--days must be a positive whole number, not '$DAYS'"
[[ "$SESSION" =~ ^[A-Za-z0-9_.*?-]+$ ]] || die "--session '$SESSION': letters, digits, _ . - * ? only"

if [ -n "$REVOKE" ]; then
  [ $# -eq 1 ] || die "--revoke takes DIR and one ENCLAVE (e.g. haptic/bob)"
  revoke "$1"
  exit 0
fi
for user in "$@"; do
  [[ "$user" =~ ^[A-Za-z0-9_.-]+$ ]] || die "user name '$user': letters, digits, _ . - only"
done

mkdir -p "$DIR"
if [ ! -f "$DIR/private/ca.key.pem" ]; then
  [ -z "$(ls -A "$DIR")" ] || die "$DIR is not empty and holds no keystore"
  make_ca
fi
make_enclave world_server world_server server
for user in "$@"; do make_enclave "haptic/$user" haptic "$user"; done
make_enclave spectator spectator spectator
make_enclave audio_guide audio_guide audio_guide
make_enclave recorder recorder recorder
make_enclave player player player
make_enclave web_console web_console web_console
