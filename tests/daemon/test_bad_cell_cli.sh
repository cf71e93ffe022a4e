#!/bin/bash
# SPDX-License-Identifier: MIT
# mcad with a bad cell file: "<3>mcad: bad cell file: FILE:LINE: FIELD: ..." on stderr, exit status 2,
# and no arm opened (no "ready" line). usage: test_bad_cell_cli.sh MCAD SOURCE_DIR
set -u
MCAD=$1 SRC=$2
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fail=0
sed "s#\.\./\.\./\.\./config#$SRC/config#" "$SRC/tests/daemon/data/hold_sim.yaml" > "$tmp/good.yaml"
expect() { # name, sed expression, expected message regex
    sed "$2" "$tmp/good.yaml" > "$tmp/$1.yaml"
    "$MCAD" --no-dds --stop-after 0.1 "$tmp/$1.yaml" 2> "$tmp/$1.err"
    local rc=$?
    if [ $rc -ne 2 ] || ! grep -Eq "^<3>mcad: bad cell file: $tmp/$1.yaml:$3" "$tmp/$1.err" || grep -q "ready" "$tmp/$1.err"; then
        echo "FAIL $1: exit $rc, stderr:"; cat "$tmp/$1.err"; fail=1
    else
        echo "ok   $1: $(cat "$tmp/$1.err")"
    fi
}
expect d1d2 's/^d1: 0.05/d1: 0.3/' '6: d1/d2: need 0 <= d1 < d2'
expect badtype 's/priority: 80/priority: urgent/' "2[0-9]:13: rt.priority: Invalid INT value: 'urgent'"
expect backend '0,/backend: sim/s//backend: profibus/' "10: arms\[0\].backend: unknown backend 'profibus'"
expect period 's/period_us: 1000/period_us: 0/' '2[0-9]: rt.period_us: must be in 1..1000000'
"$MCAD" --no-dds "$tmp/none.yaml" 2> "$tmp/none.err"
rc=$?
if [ $rc -ne 2 ] || ! grep -q "none.yaml:0: cannot open cell file" "$tmp/none.err"; then
    echo "FAIL missing file: exit $rc"; cat "$tmp/none.err"; fail=1
else
    echo "ok   missing: $(cat "$tmp/none.err")"
fi
"$MCAD" --check "$tmp/good.yaml" > /dev/null || { echo "FAIL: good cell rejected"; fail=1; }
exit $fail
