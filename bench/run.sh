#!/bin/bash
# SPDX-License-Identifier: MIT
# `make bench`: every benchmark of the project in one run, then ONE table (bench/report.py).
# usage: bench/run.sh BUILD_DIR [--quick]
#   env MCA_BENCH_OUT   output folder (default <repo>/out/bench): raw/ (each program's own output),
#                       bench.json, table.md, scaling.png
#   env MCA_BENCH_VCAN  cached (default): reuse OUT/vcan.json from an earlier guest boot if there is one,
#                       else boot; boot: always boot the QEMU guest; skip: no vcan figure
#   env MCA_BENCH_JITTER_S  seconds of mcad and of cyclictest each (default 20; --quick 3)
#   env MCA_BENCH_SWEEP=1   also the random-task sweep (tools/mca-sweep/run_full.sh): OUT/sweep.txt, sweep-{two,three,pnp}.json
# Takes about 2 minutes on 2 cores (plus a guest boot when no vcan figure is cached); needs root for
# SCHED_FIFO / mlockall / cpu_dma_latency (without it the jitter rows say SCHED_OTHER).
set -u
ROOT=$(cd "$(dirname "$0")/.." && pwd)
B=${1:?usage: bench/run.sh BUILD_DIR [--quick]}
B=$(cd "$B" && pwd) || exit 1
QUICK=0
[ "${2:-}" = "--quick" ] && QUICK=1
OUT=${MCA_BENCH_OUT:-$ROOT/out/bench}
RAW=$OUT/raw
PY=${PY:-$ROOT/.venv/bin/python3}
[ -x "$PY" ] || PY=python3
VCAN=${MCA_BENCH_VCAN:-cached}
if [ $QUICK = 1 ]; then
    # QP_EVERY_CS below the 8000 ticks of the short cup-stacking run, so that it dumps QP blocks too
    JIT=${MCA_BENCH_JITTER_S:-3} DDS_TICKS=1000 LAT_N=1000 QP_EVERY=2000 QP_EVERY_CS=2000 SCALE="--quick"
    TICKS_CS="--ticks 8000" TICKS_CELL="--ticks 2000"
else
    JIT=${MCA_BENCH_JITTER_S:-20} DDS_TICKS=3000 LAT_N=3000 QP_EVERY=1000 QP_EVERY_CS=4000 SCALE="" TICKS_CS=""
    TICKS_CELL=""
fi
# a DDS domain of our own so that other runs on this host do not mix in
DOMAIN=${MCA_BENCH_DOMAIN:-97}
FIFO=80
rm -rf "$RAW"
mkdir -p "$RAW"
t_start=$(date +%s)
step() { echo "bench: [$(($(date +%s) - t_start)) s] $*" >&2; }
have() { [ -x "$1" ] || { echo "bench: $1 not built: row skipped" >&2; return 1; }; }

{
    echo "date: $(date -u +%Y-%m-%dT%H:%M:%SZ)"
    echo "git: $(git -C "$ROOT" rev-parse --short HEAD 2>/dev/null)$(git -C "$ROOT" diff --quiet 2>/dev/null || echo +dirty)"
    echo "kernel: $(uname -r)"
    echo "mode: $([ $QUICK = 1 ] && echo quick || echo full)"
    echo "uptime: $(uptime)"
    lscpu
} >"$RAW/machine.txt"

# 1 + 2. controller tick over the tasks (virtual time), per-stage split, QP blocks for OSQP
TICK=$B/bench/scaling/bench_tick
if have "$TICK"; then
    step "tick: task 1 (dual PA10+), task 3 (JACO2 + MICO2) and task 3 with two JACO2, SCHED_FIFO $FIFO"
    "$TICK" task --scenario "$ROOT/config/scenarios/cross_circles.yaml" --fifo $FIFO --qp-dir "$RAW/qp_cross_circles" \
        --qp-every $QP_EVERY --qp-block 10 --out "$RAW/tick_cross_circles.json" 2>"$RAW/tick_cross_circles.err"
    # shellcheck disable=SC2086
    "$TICK" task --scenario "$ROOT/config/scenarios/cup_stacking.yaml" --fifo $FIFO --qp-dir "$RAW/qp_cup_stacking" \
        --qp-every $QP_EVERY_CS --qp-block 10 $TICKS_CS --out "$RAW/tick_cup_stacking.json" \
        2>"$RAW/tick_cup_stacking.err"
    # dual JACO2: task 3 with the MICO2 replaced by a second JACO2 (same waypoints, bases, q0)
    sed -e "s#urdf: \.\./robots/[a-z0-9]*\.urdf#urdf: $ROOT/config/robots/jaco2.urdf#" \
        -e "s/^name: .*/name: cup_stacking_dual_jaco2/" "$ROOT/config/scenarios/cup_stacking.yaml" \
        >"$RAW/cup_stacking_dual_jaco2.yaml"
    # shellcheck disable=SC2086
    "$TICK" task --scenario "$RAW/cup_stacking_dual_jaco2.yaml" --fifo $FIFO $TICKS_CS \
        --out "$RAW/tick_cup_stacking_dual_jaco2.json" 2>"$RAW/tick_cup_stacking_dual_jaco2.err"
    # 1d. the whole cell: task 1 with 8 fixed bodies and both arms' self pairs against task 1 alone, five pairs
    #     of whole runs alternating plain / cell, then instructions per tick (callgrind, the tick alone)
    step "tick: task 1 plain vs whole cell (8 bodies, self pairs), 5 alternating pairs, SCHED_FIFO $FIFO"
    # shellcheck disable=SC2086
    "$TICK" pair --scenario "$ROOT/config/scenarios/cross_circles.yaml" \
        --scenario-b "$ROOT/config/scenarios/cross_circles_cell.yaml" --pairs 5 --fifo $FIFO $TICKS_CELL \
        --out "$RAW/tick_cell_pairs.json" 2>"$RAW/tick_cell_pairs.err"
    if command -v valgrind >/dev/null; then
        for k in cross_circles cross_circles_cell; do
            step "tick: callgrind, instructions in mca_controller_tick over $k"
            # shellcheck disable=SC2086
            valgrind --tool=callgrind --toggle-collect=mca_controller_tick --callgrind-out-file="$RAW/callgrind_$k.out" \
                "$TICK" task --no-split --scenario "$ROOT/config/scenarios/$k.yaml" $TICKS_CELL \
                --out "$RAW/tick_callgrind_$k.json" 2>"$RAW/callgrind_$k.err"
        done
    else
        echo "valgrind missing (apt-get install valgrind): no instruction counts" >"$RAW/callgrind_cross_circles.err"
    fi
    step "scaling: 2-4 arms x 4-8 joints, d2 sweep"
    # shellcheck disable=SC2086
    "$TICK" scaling --urdf-dir "$ROOT/config/robots" --fifo $FIFO $SCALE --out "$RAW/scaling.json" \
        2>"$RAW/scaling.err"
    step "osqp: the same QPs, OSQP's own timers (SCHED_FIFO $FIFO like the PDNN's timing)"
    for k in cross_circles cup_stacking; do
        chrt -f $FIFO "$PY" "$ROOT/bench/report.py" osqp "$RAW/qp_$k" "$RAW/osqp_$k.json" 2>"$RAW/osqp_$k.err" ||
            "$PY" "$ROOT/bench/report.py" osqp "$RAW/qp_$k" "$RAW/osqp_$k.json" 2>>"$RAW/osqp_$k.err"
    done
    if [ -f "$ROOT/tools/qp-check/osqp_check.py" ]; then
        step "qp-check: PDNN answers against OSQP (tools/qp-check)"
        "$PY" "$ROOT/tools/qp-check/osqp_check.py" "$RAW/qp_cross_circles" "$RAW/qp_cup_stacking" \
            >"$RAW/qpcheck.txt" 2>&1
        echo "exit $?" >>"$RAW/qpcheck.txt"
    fi
fi

# 2c. PDNN (polish on) against DAQP on every tick of the hardest sweep tasks (bench/daqp/run.sh:
#     DAQP built from its PyPI sdist outside the repository; "skipped: daqp not available" without it)
if have "$B/bench/pdnn/bench_pdnn" && have "$B/tools/mca-sim/mca-sim"; then
    step "daqp: PDNN vs DAQP on consecutive ticks of 3 sweep tasks, then OSQP on every 50th"
    PY=$PY bash "$ROOT/bench/daqp/run.sh" "$B" "$RAW" >"$RAW/daqp_run.err" 2>&1
fi

# 3. segment distances (bench/segdist of the dist engineer)
SEG=$B/bench/segdist/segdist_bench
if have "$SEG"; then
    step "segdist: closed form, LSDM, libccd GJK (SCHED_FIFO $FIFO)"
    # shellcheck disable=SC2046
    chrt -f $FIFO "$SEG" $([ $QUICK = 1 ] && echo "--n 20000 --reps 3") >"$RAW/segdist.txt" 2>&1 ||
        "$SEG" $([ $QUICK = 1 ] && echo "--n 20000 --reps 3") >"$RAW/segdist.txt" 2>&1
fi

# 4. wake-up jitter: mcad's loop and cyclictest, same settings, one after the other. cyclictest's histogram
#    spans 0-200 ms in 1 us bins (mcad's own histogram reaches further), so that the VM stalls seen here
#    (~100 ms) land in a bin instead of an overflow count.
CYC_HIST=200000
MCAD=$B/daemon/mcad
CELL=$ROOT/config/cells/cross_circles_sim.yaml
if have "$MCAD"; then
    step "jitter: mcad $JIT s (cell cross_circles_sim, no DDS: the loop alone)"
    "$MCAD" --no-dds --stop-after "$JIT" "$CELL" >"$RAW/mcad_jitter.out" 2>"$RAW/mcad_jitter.log"
    echo "exit $?" >>"$RAW/mcad_jitter.log"
fi
if command -v cyclictest >/dev/null; then
    step "jitter: cyclictest $JIT s (-m -p $FIFO -i 1000, histogram 1 us bins to $CYC_HIST us)"
    cyclictest -m -p $FIFO -i 1000 -l $((JIT * 1000)) -q -h $CYC_HIST >"$RAW/cyclictest.txt" 2>&1
else
    echo "cyclictest missing (apt-get install rt-tests)" >"$RAW/cyclictest.txt"
fi

# 4b. both at once: the same host disturbances hit both (each wakes for < 50 us of a 1 ms period)
if have "$MCAD" && command -v cyclictest >/dev/null; then
    step "jitter: mcad and cyclictest at the same time, $JIT s"
    cyclictest -m -p $FIFO -i 1000 -l $((JIT * 1000)) -q -h $CYC_HIST >"$RAW/cyclictest_concurrent.txt" 2>&1 &
    cyc=$!
    "$MCAD" --no-dds --stop-after "$JIT" "$CELL" >"$RAW/mcad_concurrent.out" 2>"$RAW/mcad_concurrent.log"
    echo "exit $?" >>"$RAW/mcad_concurrent.log"
    wait $cyc
fi

# 4c. mca-ts against mca in mcad's real 1 kHz loop, same task (the target: tick p99 within 1.3x). The two run
#     at the same time, one per CPU (rt.cpu), so the host's disturbances hit both; five pairs, the CPUs
#     swapped in every other one. One pair at a time, one after the other, gave p99 ratios from 1.2 to 1.6
#     on the same build (the host's load moves between runs); the report gives each pair's and the median.
if have "$MCAD"; then
    ncpu=$(nproc)
    for pass in 1 2 3 4 5; do
        ca=0 cb=1
        [ $((pass % 2)) = 0 ] && ca=1 cb=0
        [ "$ncpu" -lt 2 ] && ca=-1 cb=-1
        step "scheme: mcad $JIT s, cell cross_circles_sim, mca on CPU $ca and mca-ts on CPU $cb at once (no DDS), pair $pass of 5"
        for sch in mca mca-ts; do
            c=$ca
            [ $sch = mca-ts ] && c=$cb
            sed -e "s#scenario: \.\./#scenario: $ROOT/config/#" -e "s#config: \.\./#config: $ROOT/config/#" \
                -e "s#^\( *\)scheme: .*#\1scheme: $sch#" -e "s#^\( *\)cpu: .*#\1cpu: $c#" "$CELL" \
                >"$RAW/cell_scheme_${sch}_$pass.yaml"
        done
        "$MCAD" --no-dds --stop-after "$JIT" "$RAW/cell_scheme_mca_$pass.yaml" >/dev/null 2>"$RAW/mcad_scheme_mca_$pass.log" &
        pa=$!
        [ "$ncpu" -lt 2 ] && wait $pa
        "$MCAD" --no-dds --stop-after "$JIT" "$RAW/cell_scheme_mca-ts_$pass.yaml" >/dev/null \
            2>"$RAW/mcad_scheme_mca-ts_$pass.log"
        echo "exit $?" >>"$RAW/mcad_scheme_mca-ts_$pass.log"
        wait $pa
    done
fi

# 5. DDS publishing on vs off
MON=$B/tools/mca-monitor/mca-monitor
if have "$MCAD" && have "$MON"; then
    # one run, publishing every tick in every other block of 500 ticks (mcad --dds-ab): the whole tick's
    # time with and without publishing under the same host load
    step "dds: mcad $JIT s, publishing on/off in alternate blocks of 500 ticks (domain $DOMAIN, mca-monitor subscribed)"
    cell_on=$RAW/cell_dds_on.yaml
    sed -e "s#scenario: \.\./#scenario: $ROOT/config/#" -e "s#config: \.\./#config: $ROOT/config/#" \
        -e "s#domain: .*#domain: $DOMAIN#" -e "s#publish_divisor: .*#publish_divisor: 1#" "$CELL" >"$cell_on"
    "$MON" --domain $DOMAIN --config "$ROOT/config/dds/loopback.xml" --duration $((JIT + 6)) >/dev/null \
        2>"$RAW/mcad_dds_on.monitor" &
    mon=$!
    sleep 1
    "$MCAD" --dds-ab 500 --stop-after "$JIT" "$cell_on" >"$RAW/mcad_dds_on.out" 2>"$RAW/mcad_dds_on.log"
    echo "exit $?" >>"$RAW/mcad_dds_on.log"
    kill -INT $mon 2>/dev/null
    wait $mon 2>/dev/null
fi
BDDS=$B/bench/dds/bench_dds
if have "$BDDS" && have "$MON"; then
    step "dds: bench_dds ($DDS_TICKS ticks per mode)"
    "$BDDS" --ticks $DDS_TICKS --config "$ROOT/config/dds/loopback.xml" --domain $((DOMAIN + 1)) --monitor "$MON" \
        --fifo $FIFO >"$RAW/bench_dds.txt" 2>&1
fi
SYNTH=$B/tools/mca-dds-synth/mca-dds-synth
if have "$SYNTH" && have "$MON"; then
    step "dds: latency, $LAT_N samples at 1 kHz"
    "$SYNTH" --domain $((DOMAIN + 2)) --config "$ROOT/config/dds/loopback.xml" --ticks $LAT_N --wait-readers 1 \
        --wait-topic mca/distances --linger 500 >"$RAW/dds_synth.txt" 2>&1 &
    syn=$!
    "$MON" --domain $((DOMAIN + 2)) --config "$ROOT/config/dds/loopback.xml" --count $LAT_N \
        --duration $((LAT_N / 1000 + 15)) >/dev/null 2>"$RAW/dds_latency.txt"
    wait $syn
fi

# 5d. ROS 2: tick wake-up -> rclpy callback (JointState), in a network namespace of its own (root)
if have "$MCAD" && [ -x "$ROOT/.venv/bin/python3" ]; then
    step "ros2: latency tick -> rclpy, ${JIT} s of mcad at 100 Hz"
    "$ROOT/tests/ros2/netns.sh" "$ROOT/.venv/bin/python3" "$ROOT/bench/ros2/latency.py" "$MCAD" "$ROOT" "$JIT" \
        >"$RAW/ros2_latency.txt" 2>&1 || true
fi

# 6. vcan round trip: SocketCAN lockstep between mca-can-ctl and mca-armsim (engineer "can"'s tools);
#    this kernel has no vcan, so inside the QEMU guest of tools/vcan-guest
ARMSIM=$B/sim_backend/armsim_can/mca-armsim
CTL=$B/tests/can/mca-can-ctl
vcan_from_log() { # guest log -> OUT/vcan.json; a failed boot keeps an earlier figure, saying so
    "$PY" - "$1" "$OUT/vcan.json" "$2" <<'PYEOF'
import json, os, re, sys
txt = open(sys.argv[1], encoding="utf-8", errors="replace").read().replace("\r", "") if os.path.exists(sys.argv[1]) else ""
m = re.search(r"rtt_us p50=([0-9.]+) p99=([0-9.]+) max=([0-9.]+) n=(\d+)", txt)
k = re.search(r"(?:BENCH-VCAN|CAN-SUITE) kernel (\S+)", txt)
d = {"source": sys.argv[3], "kernel": k.group(1) if k else None}
if m:
    d.update(p50_us=float(m.group(1)), p99_us=float(m.group(2)), max_us=float(m.group(3)), n=int(m.group(4)))
else:
    why = "the guest printed no rtt_us line (see " + sys.argv[1] + ")"
    try:
        old = json.load(open(sys.argv[2]))
    except (OSError, ValueError):
        old = {}
    if old.get("p50_us") is not None:
        d = old
        d["source"] = "cached figure (" + old.get("source", "?").replace("cached figure from ", "") + "); this run's boot failed: " + why
    else:
        d["error"] = why
json.dump(d, open(sys.argv[2], "w"))
PYEOF
}
if [ "$VCAN" = skip ]; then
    echo '{"error": "skipped (MCA_BENCH_VCAN=skip)"}' >"$OUT/vcan.json"
elif [ "$VCAN" = cached ] && [ -s "$OUT/vcan.json" ] && grep -q p50_us "$OUT/vcan.json"; then
    step "vcan: reusing the cached guest figure $OUT/vcan.json (MCA_BENCH_VCAN=boot to measure again)"
    "$PY" - "$OUT/vcan.json" <<'PYEOF'
import json, sys
d = json.load(open(sys.argv[1]))
if not d.get("source", "").startswith("cached"):
    d["source"] = "cached figure from " + d.get("source", "an earlier run")
json.dump(d, open(sys.argv[1], "w"))
PYEOF
elif [ $QUICK = 1 ] && grep -qs "CAN-SUITE g:.*rtt_us" "$B/tests/can/vcan-out/results.txt"; then
    step "vcan: --quick: taking the figure of the can engineer's last suite run (ctest, $B/tests/can/vcan-out)"
    rm -f "$OUT/vcan.json"
    vcan_from_log "$B/tests/can/vcan-out/results.txt" \
        "the can engineer's vcan suite (tests/can/suite.sh, case g) as last run by ctest, $(date -u -r "$B/tests/can/vcan-out/results.txt" +%Y-%m-%dT%H:%MZ)"
elif [ $QUICK = 1 ]; then
    echo '{"error": "no cached figure; --quick does not boot the guest"}' >"$OUT/vcan.json"
elif have "$ARMSIM" && have "$CTL"; then
    step "vcan: booting the QEMU guest (TCG; up to 240 s)"
    mkdir -p "$RAW/vcan"
    job=$RAW/vcan/job.sh
    cat >"$job" <<JOB
#!/bin/sh
export PATH=/usr/local/sbin:/usr/local/bin:/usr/sbin:/usr/bin:/sbin:/bin HOME=/root
ip link add dev vcan0 type vcan 2>/dev/null; ip link set vcan0 mtu 72; ip link set up vcan0
echo "BENCH-VCAN kernel \$(uname -r)"
"$ARMSIM" --iface vcan0 --robot "$ROOT/config/robots/jaco2.urdf" --q0 0,3.14,3.14,0,0,0 --lockstep \
    2>"$RAW/vcan/armsim.err" & ARM=\$!
# the emulated guest is slow to start the emulator: retry the controller until it gets feedback
sleep 1
for try in 1 2 3 4; do
    "$CTL" --iface vcan0 --joints 6 --mode lockstep --cycles 1000 >"$RAW/vcan/ctl.out" 2>"$RAW/vcan/ctl.err"
    sed 's/^/BENCH-VCAN /' "$RAW/vcan/ctl.out"
    grep -q rtt_us "$RAW/vcan/ctl.out" && break
    echo "BENCH-VCAN try \$try: \$(cat "$RAW/vcan/ctl.err")"
    sleep 1
done
kill \$ARM; wait \$ARM
JOB
    # 1 vCPU as in the can engineer's suite: under TCG a wake-up across emulated CPUs costs milliseconds
    MCA_GUEST_SMP=1 MCA_GUEST_LOG=$RAW/vcan/console.log sh "$ROOT/tools/vcan-guest/run.sh" "$B/vcan-guest-cache" "$job" 240 \
        >/dev/null 2>"$RAW/vcan/run.err"
    vcan_from_log "$RAW/vcan/console.log" "measured $(date -u +%Y-%m-%dT%H:%MZ) by bench/run.sh in the guest"
fi

# 7. optional (MCA_BENCH_SWEEP=1, or `make sweep` alone): the seeded random-task sweep,
#    1000 two-arm tasks (500 two PA10+, 500 JACO2 + MICO2) and 200 three-arm tasks, and the 400
#    pick-and-place tasks (200 pnp-jaco-mico, 200 pnp-pa10), every scheme mca-sim has of mvn,mca,mca-ts, each
#    task again with a stop request; ~15 min on 2 cores, plus the pick-and-place part (not yet timed in full)
if [ "${MCA_BENCH_SWEEP:-0}" = 1 ] && have "$B/tools/mca-sim/mca-sim"; then
    step "sweep: 500 pa10 + 500 jaco-mico + 200 three-arm + 400 pick-and-place random tasks (seed ${MCA_SWEEP_SEED:-1})"
    bash "$ROOT/tools/mca-sweep/run_full.sh" "$B" "$OUT" >"$RAW/sweep.out" 2>"$RAW/sweep.err"
    echo "exit $?" >>"$RAW/sweep.out"
fi

step "report"
"$PY" "$ROOT/bench/report.py" "$OUT"
rc=$?
step "done: $OUT/table.md, $OUT/bench.json, $OUT/scaling.png"
exit $rc
