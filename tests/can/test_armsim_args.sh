#!/bin/sh
# mca-armsim refuses bad arguments with a message naming the option and exit status 2, and a missing
# interface / SocketCAN with exit status 1 (never a crash, never a silent start).
# Usage: test_armsim_args.sh MCA_ARMSIM URDF
A=$1 U=$2
fails=0
expect() { # want_rc want_text args...
    want=$1 text=$2
    shift 2
    out=$("$A" "$@" 2>&1)
    rc=$?
    if [ $rc -ne "$want" ] || ! echo "$out" | grep -q -- "$text"; then
        echo "FAIL: mca-armsim $*: rc $rc (want $want), output: $out"
        fails=$((fails + 1))
    else
        echo "ok: mca-armsim $* -> $rc: $out" | head -n 1
    fi
}
expect 2 "--iface is required" --robot "$U"
expect 2 "exactly one of --robot and --joints" --iface vcan0
expect 2 "exactly one of --robot and --joints" --iface vcan0 --robot "$U" --joints 6
expect 2 "--joints '9'" --iface vcan0 --joints 9
expect 2 "--id-base 0x105" --iface vcan0 --joints 6 --id-base 0x105
expect 2 "--id-base 'zz'" --iface vcan0 --joints 6 --id-base zz
expect 2 "--watchdog-cycles '0'" --iface vcan0 --joints 6 --watchdog-cycles 0
expect 2 "--dec-limit '-1'" --iface vcan0 --joints 6 --dec-limit -1
expect 2 "--q0" --iface vcan0 --joints 3 --q0 1,2
expect 2 "--q0" --iface vcan0 --joints 3 --q0 1,2,3,4
expect 2 "--q0" --iface vcan0 --joints 3 --q0 1,x,3
expect 2 "/nonexistent.urdf" --iface vcan0 --robot /nonexistent.urdf
expect 2 "unexpected argument" --iface vcan0 --joints 6 extra
expect 1 "nosuchcan7" --iface nosuchcan7 --joints 6
[ $fails -eq 0 ]
