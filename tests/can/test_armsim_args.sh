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
# the in-process backend's model options reach the firmware model's configuration (--print-config: no bus)
expect 0 "lag_tau=0.005 latency_cycles=2 noise_pos=0.0001 noise_vel=0.001 seed=42 injections=2" \
    --joints 3 --print-config --lag-ms 5 --latency-cycles 2 --noise-pos 1e-4 --noise-vel 1e-3 --seed 42 \
    --inject actuator@100:1 --inject silent@200+50
expect 0 "inject 0: kind=actuator at_cycle=100 duration=0 joint=1" --joints 3 --print-config --inject actuator@100:1
expect 0 "inject 0: kind=drop-rx at_cycle=7 duration=30 joint=0" --joints 3 --print-config --inject drop-rx@7+30
expect 0 "joint 5: q0=0 acc_limit" --robot "$U" --print-config
expect 2 "--inject 'actuator@100'" --joints 3 --print-config --inject actuator@100
expect 2 "--inject 'actuator@1:3'" --joints 3 --print-config --inject actuator@1:3
expect 2 "--inject 'bogus@1'" --joints 3 --print-config --inject bogus@1
expect 2 "--inject 'freeze@-3'" --joints 3 --print-config --inject freeze@-3
expect 2 "--inject 'silent'" --joints 3 --print-config --inject silent
expect 2 "--latency-cycles '65'" --joints 3 --print-config --latency-cycles 65
expect 2 "--noise-pos '-1'" --joints 3 --print-config --noise-pos -1
expect 2 "--lag-ms 'x'" --joints 3 --print-config --lag-ms x
expect 2 "--inject: at most 8" --joints 3 --print-config --inject silent@1 --inject silent@2 --inject silent@3 \
    --inject silent@4 --inject silent@5 --inject silent@6 --inject silent@7 --inject silent@8 --inject silent@9
[ $fails -eq 0 ]
