#!/bin/sh
# SPDX-License-Identifier: MIT
# Make the DDS Security files of an mca cell (docs/security.md) in OUTDIR:
#
#   identity_ca.pem         the CA that signs identities (its key: private/identity_ca.key)
#   permissions_ca.pem      the CA that signs governance and permissions (private/permissions_ca.key)
#   governance_protected.p7s, governance_open.p7s   the two governance variants (monitoring protected / open)
#   permissions.p7s         the grants of config/security/permissions.xml
#   <identity>/cert.pem, <identity>/key.pem, <identity>/identity_ca.pem   one per participant:
#       mcad        the controller: reads targets, writes everything else
#       commander   may write targets (command the arms) and watch
#       monitor     may watch, never command (a valid identity without write permission on targets)
#       expired     CN=commander, signed by the identity CA, valid 2021-01-01 to 2021-01-02 only
#       rogue       CN=commander, signed by ANOTHER CA (rogue/rogue_ca.pem), which its identity_ca.pem names:
#                   a participant that trusts its own forger
#   forged/permissions_ca.pem, forged/permissions.p7s, forged/governance_protected.p7s: a forger's own
#       permissions CA and, signed by it, permissions that also let CN=monitor write targets (a valid
#       identity that forges its permissions: the forger's own Cyclone accepts them, the cell must not)
#
# Keys are EC P-256 (Cyclone's authentication plugin takes P-256 and RSA-2048), made here and never
# committed. The CAs are valid from 2020-01-01 to 2040-01-01 (the expired certificate must chain to a CA
# that was valid when it was). For a real cell: keep private/ off the machines, give each machine only its
# own <identity>/ and the three signed documents.
#
# usage: make_security.sh OUTDIR [SOURCE_DIR]    (SOURCE_DIR: where the XML templates are, default: this
#        script's folder). Needs openssl. Existing OUTDIR contents are replaced.
#        make_security.sh OUTDIR --add NAME CN [NOT_AFTER [NOT_BEFORE]]   one more identity OUTDIR/NAME
#        (subject CN=<CN>,O=mca) from OUTDIR's identity CA, valid from NOT_BEFORE (default now) to NOT_AFTER
#        (YYYYMMDDHHMMSSZ, UTC; default 20400101000000Z); it may write targets only if permissions.xml has a
#        grant for its subject.
set -eu
out=${1:?usage: make_security.sh OUTDIR [SOURCE_DIR] | OUTDIR --add NAME CN [NOT_AFTER [NOT_BEFORE]]}
command -v openssl >/dev/null || { echo "make_security.sh: openssl not found (apt-get install openssl)" >&2; exit 2; }

NOT_BEFORE=2020-01-01T00:00:00
NOT_AFTER=2040-01-01T00:00:00

q() { "$@" >/dev/null 2>&1 || { echo "make_security.sh: failed: $*" >&2; "$@" >&2 || true; exit 1; }; }

# A minimal 'openssl ca' set-up per CA: only 'openssl ca' sets both validity dates of a certificate
# (openssl 3.0's 'x509 -req' has only -days), and the expired certificate needs dates in the past.
ca_setup() { # NAME
    d="$out/private/$1.ca"
    mkdir -p "$d/new"
    : >"$d/index.txt"
    echo 1000 >"$d/serial"
    cat >"$d/ca.cnf" <<EOF
[ca]
default_ca = this
[this]
dir = $d
database = \$dir/index.txt
new_certs_dir = \$dir/new
serial = \$dir/serial
default_md = sha256
policy = any
unique_subject = no
copy_extensions = none
[any]
commonName = supplied
organizationName = optional
countryName = optional
[v3_ca]
basicConstraints = critical, CA:true
keyUsage = critical, keyCertSign, cRLSign, digitalSignature, nonRepudiation
subjectKeyIdentifier = hash
[v3_id]
basicConstraints = critical, CA:false
keyUsage = critical, digitalSignature, keyAgreement
subjectKeyIdentifier = hash
authorityKeyIdentifier = keyid
EOF
}

key() { q openssl genpkey -algorithm EC -pkeyopt ec_paramgen_curve:P-256 -out "$1"; }

make_ca() { # NAME SUBJECT CERT_OUT
    ca_setup "$1"
    key "$out/private/$1.key"
    q openssl req -new -key "$out/private/$1.key" -subj "$2" -out "$out/private/$1.csr"
    q openssl ca -batch -config "$out/private/$1.ca/ca.cnf" -selfsign -keyfile "$out/private/$1.key" \
        -extensions v3_ca -startdate 20200101000000Z -enddate 20400101000000Z \
        -in "$out/private/$1.csr" -out "$3" -notext
}

make_id() { # IDENTITY SUBJECT CA START END
    mkdir -p "$out/$1"
    key "$out/$1/key.pem"
    q openssl req -new -key "$out/$1/key.pem" -subj "$2" -out "$out/private/$1.csr"
    q openssl ca -batch -config "$out/private/$3.ca/ca.cnf" -cert "$out/private/$3.pem" \
        -keyfile "$out/private/$3.key" -extensions v3_id -startdate "$4" -enddate "$5" \
        -in "$out/private/$1.csr" -out "$out/$1/cert.pem" -notext
    cp "$out/private/$3.pem" "$out/$1/identity_ca.pem"
}

if [ "${2:-}" = "--add" ]; then
    name=${3:?--add NAME CN [NOT_AFTER]}
    cn=${4:?--add NAME CN [NOT_AFTER]}
    [ -r "$out/private/identity_ca.key" ] || { echo "make_security.sh: no identity CA in $out/private" >&2; exit 2; }
    umask 077
    rm -rf "${out:?}/$name"
    make_id "$name" "/O=mca/CN=$cn" identity_ca "${6:-$(date -u +%Y%m%d%H%M%SZ)}" "${5:-20400101000000Z}"
    chmod 755 "$out/$name"
    chmod 644 "$out/$name/cert.pem" "$out/$name/identity_ca.pem"
    echo "make_security.sh: identity $name (CN=$cn,O=mca) in $out/$name"
    exit 0
fi

src=${2:-$(dirname "$0")}
for f in governance_protected.xml governance_open.xml permissions.xml; do
    [ -r "$src/$f" ] || { echo "make_security.sh: $src/$f not found" >&2; exit 2; }
done
rm -rf "$out"
mkdir -p "$out/private"
chmod 700 "$out/private"
umask 077

make_ca identity_ca "/O=mca/CN=mca identity CA" "$out/private/identity_ca.pem"
make_ca permissions_ca "/O=mca/CN=mca permissions CA" "$out/private/permissions_ca.pem"
make_ca rogue_ca "/O=mca/CN=mca identity CA" "$out/private/rogue_ca.pem" # same name, another key
make_ca forger_ca "/O=mca/CN=mca permissions CA" "$out/private/forger_ca.pem"
cp "$out/private/identity_ca.pem" "$out/private/permissions_ca.pem" "$out/"

now=$(date -u +%Y%m%d%H%M%SZ)
make_id mcad "/O=mca/CN=mcad" identity_ca "$now" 20400101000000Z
make_id commander "/O=mca/CN=commander" identity_ca "$now" 20400101000000Z
make_id monitor "/O=mca/CN=monitor" identity_ca "$now" 20400101000000Z
make_id expired "/O=mca/CN=commander" identity_ca 20210101000000Z 20210102000000Z
make_id rogue "/O=mca/CN=commander" rogue_ca "$now" 20400101000000Z

umask 022
sign() { # TEMPLATE OUT.p7s [CA]   (the signed XML is kept in private/)
    x="$out/private/$(echo "$2" | tr / _ | sed 's/\.p7s$//').xml"
    sed -e "s/@NOT_BEFORE@/$NOT_BEFORE/g" -e "s/@NOT_AFTER@/$NOT_AFTER/g" "$1" >"$x"
    q openssl smime -sign -text -in "$x" -out "$out/$2" -signer "$out/private/${3:-permissions_ca}.pem" \
        -inkey "$out/private/${3:-permissions_ca}.key"
}
sign "$src/governance_protected.xml" governance_protected.p7s
sign "$src/governance_open.xml" governance_open.p7s
sign "$src/permissions.xml" permissions.p7s
# the forger: the cell's permissions with CN=monitor also allowed to publish targets, signed by its own CA
mkdir -p "$out/forged"
cp "$out/private/forger_ca.pem" "$out/forged/permissions_ca.pem"
sign "$src/governance_protected.xml" forged/governance_protected.p7s forger_ca
sed -e 's#<subscribe><topics><topic>\*</topic></topics></subscribe>#&<publish><topics><topic>rt/*/target_twist</topic><topic>rt/*/target_pose</topic></topics></publish>#' \
    "$src/permissions.xml" >"$out/private/permissions_forged.in"
grep -q '</subscribe><publish>' "$out/private/permissions_forged.in" || { echo "make_security.sh: forging failed" >&2; exit 1; }
sign "$out/private/permissions_forged.in" forged/permissions.p7s forger_ca
chmod 644 "$out"/*.pem "$out"/*.p7s "$out"/*/cert.pem "$out"/*/identity_ca.pem "$out"/forged/*
chmod 755 "$out"/mcad "$out"/commander "$out"/monitor "$out"/expired "$out"/rogue "$out"/forged
echo "make_security.sh: DDS Security files in $out"
