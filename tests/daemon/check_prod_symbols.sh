#!/bin/sh
# SPDX-License-Identifier: MIT
# daemon.prod_symbols: the production mcad holds no test-only code and none of the virtual-time driver.
#   1. mcad defines no function of the driver (mca/daemon_drive.h: mca_drive_*) nor of the test build's
#      hooks (mca/daemon_test.h: mca_daemon_request_stall, mca_daemon_swap_arm), and
#      has none of the test build's texts (its start-up banner, the SIGUSR1 stall, the debug stall's log line);
#   2. the controls, so the check can fail: mcad-test defines the hooks and has the texts, mca-sim defines
#      the driver's functions;
#   3. no public header of the daemon depends on MCA_TEST_HOOKS, so every struct they declare (mca_cell_t
#      among them) has one layout in mcad, mcad-test, mca-sim and the tests; where gdb is installed, the
#      debug information of the three binaries agrees on mca_cell_t's size and its last field's offset.
# usage: check_prod_symbols.sh NM MCAD MCAD_TEST MCA_SIM DAEMON_INCLUDE_DIR
set -eu
NM=$1
MCAD=$2
MCAD_TEST=$3
MCA_SIM=$4
INC=$5
fail=0

DRIVER='^(mca_drive_[a-z_]+)$'
HOOKS='^(mca_daemon_request_stall|mca_daemon_swap_arm)$'
TEXTS='test build (mcad-test): test hooks on|SIGUSR1: stalling the loop (test hook)|debug stall after %g ticks'

# defined functions (text symbols) of binary $1 that match $2
defined() {
    "$NM" --defined-only "$1" | awk -v re="$2" '($(NF - 1) == "T" || $(NF - 1) == "t") && $NF ~ re { print $NF }' | sort -u
}
# how many of the test build's texts binary $1 holds
texts() {
    n=0
    for t in "test build (mcad-test): test hooks on" "SIGUSR1: stalling the loop (test hook)" \
             "debug stall after %g ticks"; do
        if grep -aqF "$t" "$1"; then
            n=$((n + 1))
        fi
    done
    echo $n
}

bad=$(defined "$MCAD" "$DRIVER|$HOOKS")
if [ -n "$bad" ]; then
    echo "FAIL mcad defines driver or test-hook functions:"
    echo "$bad" | sed 's/^/  /'
    fail=1
else
    echo "ok   mcad: no mca_drive_* function, no test hook"
fi
n=$(texts "$MCAD")
if [ "$n" -ne 0 ]; then
    echo "FAIL mcad holds $n of the test build's 3 texts ($TEXTS)"
    fail=1
else
    echo "ok   mcad: none of the test build's 3 texts"
fi

hooks=$(defined "$MCAD_TEST" "$HOOKS" | wc -l)
n=$(texts "$MCAD_TEST")
if [ "$hooks" -ne 2 ] || [ "$n" -ne 3 ]; then
    echo "FAIL control: mcad-test defines $hooks of the 2 hooks and holds $n of the 3 texts (the check sees nothing)"
    fail=1
else
    echo "ok   control: mcad-test defines the 2 hooks and holds the 3 texts"
fi
drv=$(defined "$MCA_SIM" "$DRIVER" | wc -l)
if [ "$drv" -lt 3 ]; then
    echo "FAIL control: mca-sim defines $drv mca_drive_* functions (the check sees nothing)"
    fail=1
else
    echo "ok   control: mca-sim defines $drv mca_drive_* functions"
fi

hdr=$(grep -rl 'MCA_TEST_HOOKS' "$INC" || true)
if [ -n "$hdr" ]; then
    echo "FAIL public headers that change with MCA_TEST_HOOKS (two layouts):"
    echo "$hdr" | sed 's/^/  /'
    fail=1
else
    echo "ok   no public header of the daemon depends on MCA_TEST_HOOKS: one layout in every binary"
fi
if command -v gdb >/dev/null 2>&1; then
    layouts=""
    for b in "$MCAD" "$MCAD_TEST" "$MCA_SIM"; do
        l=$(gdb -nx -batch -ex 'print sizeof(mca_cell_t)' \
                -ex 'print (long)&((mca_cell_t *)0)->debug_kill_after_ticks' "$b" 2>/dev/null |
            sed -n 's/^\$[0-9]* = //p' | tr '\n' ' ')
        layouts="$layouts$(basename "$b"): $l
"
    done
    if [ "$(printf '%s' "$layouts" | sed 's/^[^:]*: //' | sort -u | wc -l)" -ne 1 ] ||
        [ -z "$(printf '%s' "$layouts" | head -1 | sed 's/^[^:]*: *//')" ]; then
        echo "FAIL mca_cell_t (size, offset of its last field) differs or is unreadable:"
        printf '%s' "$layouts" | sed 's/^/  /'
        fail=1
    else
        echo "ok   mca_cell_t in mcad, mcad-test and mca-sim: size, last field's offset $(printf '%s' "$layouts" | head -1 | sed 's/^[^:]*: //')"
    fi
else
    echo "skip gdb not installed: the binaries' mca_cell_t layouts not compared (the header check above stands)"
fi
exit $fail
