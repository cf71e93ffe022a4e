#!/bin/sh
# SPDX-License-Identifier: MIT
# End to end over CAN FD: mcad drives task 3 (cup stacking, JACO2 on vcan0,
# MICO2 on vcan1) through the SocketCAN backend, each arm answered by its own firmware emulator mca-armsim
# (lockstep: one firmware cycle per command, so the emulated guest CPU changes no trajectory), with DDS on
# and mca-monitor subscribed. Natively when this kernel has vcan and we are root, else in one QEMU guest
# boot (tools/vcan-guest, TCG). The cell is the shipped config/cells/cup_stacking_vcan.yaml with only
# rt.overrun_limit and rt.pdnn_budget_us widened (the emulated CPU misses every deadline; task time advances per tick) and the
# loop pinned to the emulators' CPU (rt.cpu); the diff is printed.
#   A: the task through A_STOP s of task time (env MCA_E2E_A_STOP; default the whole 50 s, ctest
#      daemon_vcan_e2e_long; `make test` runs the first 17 s, through the closest approach at 15.99 s): exit 0,
#      stopped, no fault, one CSV row per tick, every distance above d1, tracking error < 1 mm, (whole task
#      only) both tool tips at their last waypoints; mca-monitor got the Distances samples (>= 90 %, through
#      the end) with the distances of mcad's CSV at the same ticks, the final status.
#   B: the task again, SIGTERM while the arms move fast (from t = 12.3 s, >= 0.3 rad/s): exit 0, stopped;
#      from mcad's CSV every per-tick change of every commanded joint velocity is within dec_limit * dt
#      (+ the CSV's print precision), the ramp has the minimum length ceil(|v0|/(dec dt)) and ends at
#      exactly 0, every distance stays above d1 while braking; from the buses (candump of the emulators'
#      feedback frames) both arms end READY with zero velocity and unchanged positions, and the emulators
#      report no fault.
#   C: the MICO2's emulator is frozen (SIGSTOP) while both arms dwell: lost-feedback fault after the cell's
#      lost_feedback_cycles, both arms braked within the limits, exit 3 after SIGTERM.
# usage: vcan_e2e.sh BUILD_DIR SOURCE_DIR [--in-guest]
#   D: mcad SIGKILLed mid-task (tick 1500, arms moving), the emulators on their own 4 ms clock: from the candump
#      of both buses (tests/daemon/check_watchdog.py on the host) each arm BRAKING in the 3rd firmware cycle
#      without a command, velocity steps within dec_limit * 4 ms, a ramp of the minimum length, then FAULT
#      with fault code WATCHDOG; the emulators' counters: one watchdog trip, FAULT.
#   E: task 4, the negative example (two PA10+: 8 joints per frame) on the shipped negative_vcan cell:
#      the fault PDNN-not-converged named at the sim backend's task time (mca-sim, host; within 2 ticks),
#      the trajectory until then within DQ_MAX of it, both arms braked within the limits to 0 and never
#      below d1, exit status 3 at the cell's stop_after; from the buses both arms end READY at rest.
#   F: task 1, the paper's cross circles (two PA10+) on the shipped cross_circles_vcan cell: the whole
#      10 s above d1, exit 0 stopped at stop_after, no fault, both buses at rest, the trajectory within
#      DQ_MAX of the sim backend's.
#   G: task 2, the character "Hui" (two PA10+) on the shipped hui_vcan cell, the same checks as F over its
#      first 8 s (its closest approach is at 3.98 s), ended by the cell's stop_after set to 8 s while the arms
#      move: braked to rest, exit 0. The whole 32 s took 130-225 s of the guest (a third of this test), for
#      what A and F already show over CAN; MCA_E2E_G_STOP=33 runs the whole task.
#   Phases A, E, F and G also compare mcad's joint trajectory with the sim backend's (mca-sim, on the host
#   afterwards). env MCA_E2E_PHASES="A B C D E F G" (default) runs a subset (development).
set -u
B=$(cd "$1" && pwd) S=$(cd "$2" && pwd)
OUT=$B/tests/daemon/vcan-e2e
ARMSIM=$B/sim_backend/armsim_can/mca-armsim
MCAD=$B/daemon/mcad
# phase D's self-kill is a test hook (debug_kill_after_ticks): only the test build takes it (production holds no test hooks)
MCAD_TEST=$B/daemon/mcad-test
MON=$B/tools/mca-monitor/mca-monitor
SRC_CELL=$S/config/cells/cup_stacking_vcan.yaml
SCN=$S/config/scenarios/cup_stacking.yaml
# phases E and F: task 4 (the negative example) and task 1 (cross circles) on their shipped vcan cells
SRC_CELL_E=$S/config/cells/negative_vcan.yaml
SCN_E=$S/config/scenarios/negative.yaml
SRC_CELL_F=$S/config/cells/cross_circles_vcan.yaml
SCN_F=$S/config/scenarios/cross_circles.yaml
SRC_CELL_G=$S/config/cells/hui_vcan.yaml
SCN_G=$S/config/scenarios/hui.yaml
PHASES=${MCA_E2E_PHASES:-A B C D E F G}
PY=$S/.venv/bin/python3
[ -x "$PY" ] || PY=python3
# ---- on the host, after the guest (or the native run): the checks that need mca-sim or python cantools
# (cheap here, slow under TCG). $1 = exit status of the guest part; prints E2E lines, returns the status.
# mca-sim (the sim backend, virtual time) on scenario $2 into $OUT/sim$1.csv, then vcan_e2e_dq.awk's
# comparison with mcad's $OUT/mcad$1.csv on stdout; a failing mca-sim is reported on stderr, status 1
sim_dq() {
    "$B/tools/mca-sim/mca-sim" --scenario "$2" --scheme mca --csv "$OUT/sim$1.csv" > "$OUT/sim$1.txt" 2>&1 ||
        { cat "$OUT/sim$1.txt" >&2; echo "E2E FAIL: phase $1: mca-sim" >&2; return 1; }
    awk -F, -f "$S/tests/daemon/vcan_e2e_dq.awk" "$OUT/sim$1.csv" "$OUT/mcad$1.csv"
}
# the guest's exit status 77: every phase run passed but D, which the guest's starved loop left unjudged
SKIP_RC=77
host_checks() {
    hf=$1 skipD=0
    [ "$hf" -eq $SKIP_RC ] && hf=0 skipD=1
    if echo "$PHASES" | grep -q A && [ -s "$OUT/mcadA.csv" ]; then
        # A: the joint trajectory over SocketCAN (mcad's q columns, the feedback it used at each tick) against
        # the in-process sim backend in virtual time (mca-sim: same controller, same tick order: tick k uses
        # the feedback of command k-1), row by row at the same tick, over the running rows
        th=$(now)
        res=$(sim_dq A "$SCN") || hf=1
        sup=$(sed -n 's/.* cmd_superseded=\([0-9]*\) .*/\1/p' "$OUT/armsim0A.txt" "$OUT/armsim1A.txt" 2>/dev/null | tr '\n' ' ')
        set -- $res
        echo "E2E phase A: joint trajectory vs the sim backend (mca-sim, $2 ticks compared, $3 without a sim row): JACO2 max |dq| $4 rad at tick $5 (joint $6), MICO2 max |dq| $7 rad at tick $8 (joint $9); commands superseded at the emulators: ${sup:-?}; $(($(now) - th)) s on the host"
        # bound (docs/daemon.md, vcan e2e): the protocol rounds feedback positions to 1e-6 rad and commands
        # to 1e-6 rad/s; open loop that is 5e-7 rad (can_vcan (f)). Closed loop the controller acts on the
        # rounded positions, and in the null space (3 redundant DOF per arm) nothing pulls the two runs back
        # together: measured 0.6e-6 rad in the first 5 s growing to 1.2-1.7e-6 rad at 40-50 s. 1e-5 rad
        # (10 feedback steps) leaves room for that drift; a command the emulator skipped while the arm moved
        # (cmd_superseded: the arm one cycle behind, |qdot| dt <= 0.6 mrad) is not within the protocol's
        # resolution and fails here (a run with 45-49 superseded: 1e-3 rad)
        awk -v a="$4" -v b="$7" -v m="$DQ_MAX" -v n="$2" -v s="$A_STOP" 'BEGIN { exit !(n >= s * 1000 - 10 && a + 0 <= m && b + 0 <= m) }' ||
            { echo "E2E FAIL: phase A: joint trajectory differs from the sim backend's by more than $DQ_MAX rad"; hf=1; }
    fi
    if [ $skipD -eq 1 ]; then
        echo "E2E phase D: not judged (the guest starved mcad's loop on every attempt): no bus checks"
    elif echo "$PHASES" | grep -q D && [ -s "$OUT/d.candump" ]; then
        th=$(now)
        "$PY" "$S/tests/daemon/check_watchdog.py" "$S/config/can/mca.dbc" "$OUT/d.candump" 3 "$DEC_H" "$D_PERIOD_US" "$OUT" \
            > "$OUT/check_watchdog.txt" 2>&1
        wrc=$?
        grep '^FAIL\|^E2E\|Error\|error' "$OUT/check_watchdog.txt"
        echo "E2E phase D: bus checks (check_watchdog.py, exit $wrc): $(grep -c '^ok' "$OUT/check_watchdog.txt") ok, $(grep -c '^FAIL' "$OUT/check_watchdog.txt") failed; $(($(now) - th)) s on the host"
        if [ $wrc -eq 0 ]; then
            echo "E2E ok: phase D: mcad SIGKILLed mid-task: both emulators' watchdogs braked their arm in the 3rd cycle without a command, within the deceleration limit, to FAULT WATCHDOG"
        else
            hf=1
        fi
    elif echo "$PHASES" | grep -q D; then
        echo "E2E FAIL: phase D: no bus capture"; hf=1
    fi
    if echo "$PHASES" | grep -q E && [ -s "$OUT/mcadE.csv" ]; then
        # E: the same task on the sim backend (mca-sim: same controller and fault checks, virtual time):
        # the fault at the same tick (1 ms), the running rows within DQ_MAX (see phase A)
        th=$(now)
        res=$(sim_dq E "$SCN_E") || hf=1
        t_sim=$(sed -n 's/.*FAULT pdnn-not-converged at t = \([0-9.]*\) s.*/\1/p' "$OUT/simE.txt")
        t_can=$(sed -n 's/.*fault at t = \([0-9.]*\) s: braking both arms: PDNN residual.*/\1/p' "$OUT/mcadE.log")
        set -- $res
        echo "E2E phase E: vs the sim backend (mca-sim): PDNN-not-converged fault at t = ${t_sim:-?} s there, ${t_can:-?} s over CAN; $2 running ticks compared ($3 without a sim row): left max |dq| $4 rad at tick $5 (joint $6), right $7 rad at tick $8 (joint $9); $(($(now) - th)) s on the host"
        # the fault tick within 2 ticks of the sim backend's (seen: the same tick; the residual is 2.7e-4
        # against a fault threshold of 1e-6, but where the QP turns infeasible a 1e-6 rad difference could
        # move the onset by a tick), and mcad running up to it
        if [ -n "$t_sim" ] && [ -n "$t_can" ] &&
            awk -v a="$4" -v b="$7" -v m="$DQ_MAX" -v n="$2" -v t="$t_sim" -v c="$t_can" \
                'BEGIN { d = t - c; exit !((d < 0 ? -d : d) <= 0.0025 && n == int(c * 1000 + 0.5) && a + 0 <= m && b + 0 <= m) }'; then
            echo "E2E ok: phase E: negative task over vcan: the fault at the sim backend's task time (within 2 ticks), the same trajectory until then"
        else
            echo "E2E FAIL: phase E: fault time or trajectory differs from the sim backend's (bound $DQ_MAX rad)"; hf=1
        fi
    elif echo "$PHASES" | grep -q E; then
        echo "E2E FAIL: phase E: no mcad CSV"; hf=1
    fi
    # F, G: the whole task against the sim backend, tick by tick over the task (mcad holds the last point
    # until stop_after: those rows have no sim row); $1 = phase, $2 = scenario, $3 = task name
    for fg in "F $SCN_F cross-circles" "G $SCN_G Hui"; do
        set -- $fg
        if echo "$PHASES" | grep -q "$1" && [ -s "$OUT/mcad$1.csv" ]; then
            th=$(now) ph=$1 task=$3
            want=$(awk -v d="$(sed -n 's/^duration: *\([0-9.]*\).*/\1/p' "$2")" -v g="$G_STOP" -v p="$ph" \
                'BEGIN { if (p == "G" && g < d) d = g; print d * 1000 - 10 }')
            res=$(sim_dq "$1" "$2") || hf=1
            set -- $res
            echo "E2E phase $ph: vs the sim backend (mca-sim): $2 running ticks compared ($3 without a sim row): left max |dq| $4 rad at tick $5 (joint $6), right $7 rad at tick $8 (joint $9); $(($(now) - th)) s on the host"
            if awk -v a="$4" -v b="$7" -v m="$DQ_MAX" -v n="$2" -v w="$want" 'BEGIN { exit !(n >= w && a + 0 <= m && b + 0 <= m) }'; then
                echo "E2E ok: phase $ph: $task over vcan: the sim backend's trajectory within $DQ_MAX rad"
            else
                echo "E2E FAIL: phase $ph: joint trajectory differs from the sim backend's by more than $DQ_MAX rad (or fewer than $want ticks)"; hf=1
            fi
        elif echo "$PHASES" | grep -q "$1"; then
            echo "E2E FAIL: phase $1: no mcad CSV"; hf=1
        fi
    done
    [ $hf -eq 0 ] && [ $skipD -eq 1 ] && hf=$SKIP_RC
    return $hf
}
now() { date +%s; }
# phase A's bound on max |dq| against the sim backend (rad), phase D's deceleration limit (the cell's)
DQ_MAX=${MCA_E2E_DQ_MAX:-1e-5}
# phase D's firmware cycle (us): see there
# phase G's stop_after (s): the first 8 s of Hui, its closest approach included; 33 = the whole task
G_STOP=${MCA_E2E_G_STOP:-8}
A_STOP=${MCA_E2E_A_STOP:-$(sed -n 's/^duration: *\([0-9.]*\).*/\1/p' "$SCN")}
D_PERIOD_US=${MCA_E2E_D_PERIOD_US:-4000}
DEC_H=$(sed -n 's/^ *dec_limit: *\([0-9.]*\).*/\1/p' "$SRC_CELL" | head -n 1)
if [ "${3:-}" != "--in-guest" ]; then
    rm -rf "$OUT" && mkdir -p "$OUT"
    start=$(date +%s)
    if [ "$(id -u)" = 0 ] && ip link add dev mcae2etest type vcan 2>/dev/null; then
        ip link del dev mcae2etest
        echo "vcan_e2e: native vcan available"
        sh "$0" "$B" "$S" --in-guest
        host_checks $?
        exit $?
    fi
    echo "vcan_e2e: no vcan on this kernel: booting the QEMU guest (TCG: slow, several minutes)"
    # an image cache of our own: can_vcan may be building the shared one at the same time (ctest -j)
    job=$OUT/job.sh
    printf '#!/bin/sh\nexport MCA_IN_GUEST=1 MCA_E2E_PHASES="%s" MCA_E2E_D_PERIOD_US=%s MCA_E2E_G_STOP=%s MCA_E2E_A_STOP=%s PATH=/usr/local/sbin:/usr/local/bin:/usr/sbin:/usr/bin:/sbin:/bin HOME=/root\nexec sh %s %s %s --in-guest\n' \
        "$PHASES" "$D_PERIOD_US" "$G_STOP" "$A_STOP" "$S/tests/daemon/vcan_e2e.sh" "$B" "$S" > "$job"
    MCA_GUEST_LOG=$OUT/console.log sh "$S/tools/vcan-guest/run.sh" "$B/tests/daemon/vcan-guest-cache" "$job" 1800 >/dev/null
    rc=$?
    grep -a 'E2E\|MCA-GUEST\|mcad:\|mca-monitor:\|^[-+]  ' "$OUT/console.log" | tr -d '\r'
    echo "vcan_e2e: guest exit status $rc after $(($(date +%s) - start)) s (guest boot included)"
    host_checks $rc
    rc=$?
    echo "vcan_e2e: exit status $rc after $(($(date +%s) - start)) s in all"
    exit $rc
fi

# ---- inside the guest (or natively as root)
mkdir -p "$OUT"
for i in 0 1; do
    ip link show vcan$i >/dev/null 2>&1 || ip link add dev vcan$i type vcan || { echo "E2E FAIL: cannot create vcan$i"; exit 1; }
    ip link set vcan$i mtu 72
    ip link set up vcan$i
done
# DDS (config/dds/loopback.xml) runs on lo only
ip link set lo up 2>/dev/null
ip link show lo | grep -q 'UP' || { echo "E2E FAIL: lo is not up (DDS needs it)"; exit 1; }
if [ "${MCA_IN_GUEST:-0}" = 1 ]; then
    # big socket buffers and backlog: processes can be starved for 100s of ms under TCG (as tests/can)
    echo 67108864 >/proc/sys/net/core/rmem_max
    echo 16777216 >/proc/sys/net/core/rmem_default
    echo 100000 >/proc/sys/net/core/netdev_max_backlog
    # frames are delivered in softirq context; once that work is deferred to ksoftirqd (SCHED_OTHER) the
    # real-time loop and emulators would starve it, and a command reach its emulator a tick late
    for k in $(pgrep '^ksoftirqd/'); do chrt -f -p 95 "$k" >/dev/null 2>&1; done
fi
# CSVs and bus dumps on a tmpfs (the shared tree is 9p in the guest: slow), copied to $OUT at the end
TMPD=$(mktemp -d /dev/shm/mca-e2e.XXXXXX 2>/dev/null || mktemp -d)
trap 'cp "$TMPD"/* "$OUT/" 2>/dev/null; rm -rf "$TMPD"' EXIT
t_all=$(now)

# Lockstep needs every command answered before the next tick, or the emulator takes only the newest of
# two commands (cmd_superseded) and the arm falls behind the task. So the loop (SCHED_FIFO 80, cell) and
# both emulators (SCHED_FIFO 90: they preempt the loop the moment its command frame arrives) share one
# CPU and stall together when the host deschedules it; mcad's other threads (DDS, CSV), mca-monitor and
# candump run on the other CPU.
LOOP_CPU=0 OTHER_CPU=0
[ "$(nproc)" -gt 1 ] && OTHER_CPU=1
# this shell too (it polls the CSV to time the signals): on the loop's CPU it would be starved
taskset -p -c $OTHER_CPU $$ >/dev/null 2>&1
RTA=""
chrt -f 90 true 2>/dev/null && RTA="chrt -f 90"
PIN="taskset -c $LOOP_CPU" PIN2="taskset -c $OTHER_CPU"
$PIN true 2>/dev/null || PIN="" PIN2=""
# The shipped cell, with the real-time tolerances of an emulated CPU: deadlines are missed all the time
# under TCG (the lockstep arms do not care: task time advances per tick), and the emulator answers late.
# overrun_limit counts missed periods in a row, and when every tick overruns that run never ends: a busy
# host once gave 135301 in 27 s of task (a limit of 100000 faulted phase A), so the limit is out of reach: the
# largest a cell may give (3600000 periods, an hour at 1 kHz; the guest gives itself 1800 s in all).
CELL=$OUT/cup_stacking_vcan_e2e.yaml
sed -e "s|\.\./|$S/config/|g" \
    -e 's/^\(  overrun_limit:\).*/\1 3600000   # vcan_e2e.sh: emulated guest CPU (TCG)/' -e '/^  overrun_limit:/a\  pdnn_budget_us: 1000000   # vcan_e2e.sh: emulated guest CPU (TCG): the PDNN may take 1 s' \
    -e "s/^\(  cpu:\).*/\1 $LOOP_CPU   # vcan_e2e.sh: the loop on the emulators' CPU/" "$SRC_CELL" > "$CELL"
diff "$SRC_CELL" "$CELL" | grep '^[<>]' | sed 's/^</-  /; s/^>/+  /'
D1=$(sed -n 's/^d1: *\([0-9.]*\).*/\1/p' "$SCN")
DEC=$(sed -n 's/^ *dec_limit: *\([0-9.]*\).*/\1/p' "$SRC_CELL" | head -n 1)
DUR=$(sed -n 's/^duration: *\([0-9.]*\).*/\1/p' "$SCN")
DT=0.001
# the cell must put the JACO2 on vcan0 and the MICO2 on vcan1
"$MCAD" --check "$CELL" > "$OUT/check.txt" 2>&1 || { cat "$OUT/check.txt"; echo "E2E FAIL: mcad --check"; exit 1; }
grep -q "arm 0 'jaco2': .*jaco2.urdf, 6 joints.* socketcan vcan0 id_base 0x100" "$OUT/check.txt" &&
    grep -q "arm 1 'mico2': .*mico2.urdf, 6 joints.* socketcan vcan1 id_base 0x100" "$OUT/check.txt" ||
    { cat "$OUT/check.txt"; echo "E2E FAIL: cell: want jaco2 on vcan0, mico2 on vcan1"; exit 1; }
# arm K's (1-based) urdf and q0 as the scenario ($3, default task 3's) gives them (the emulator starts where the task starts)
arm_field() {
    awk -v k="$1" -v f="$2" '/^  - name:/ { n++ } n == k && $1 == f ":" { sub(/^[^:]*: */, ""); sub(/ *#.*/, "");
        gsub(/[][ ]/, ""); print; exit }' "${3:-$SCN}"
}
URDF0=$S/config/scenarios/$(arm_field 1 urdf) Q00=$(arm_field 1 q0)
URDF1=$S/config/scenarios/$(arm_field 2 urdf) Q01=$(arm_field 2 q0)
# each arm's last waypoint (where the task leaves its tool tip)
END0=$(awk '/^  - name:/ { n++ } n == 1 && /^ *- \[/ { gsub(/[][,]/, " "); p = $2 " " $3 " " $4 } END { print p }' "$SCN")
END1=$(awk '/^  - name:/ { n++ } n == 2 && /^ *- \[/ { gsub(/[][,]/, " "); p = $2 " " $3 " " $4 } END { print p }' "$SCN")
echo "E2E cell $SRC_CELL: task $DUR s (phase A: $A_STOP s), d1 $D1 m, dec_limit $DEC rad/s^2; JACO2 q0 $Q00 -> $END0, MICO2 q0 $Q01 -> $END1"

# start both emulators (lockstep; $2 = clocked: on their own clock of D_PERIOD_US with the 3-cycle
# watchdog, on the other CPU, sent state/fault frames logged into $TMPD/armlogX<tag>.txt), stats into
# $TMPD/armsimX<tag>.txt
armsims() {
    X0=--lockstep X1=--lockstep P=$PIN
    [ "${2:-}" = clocked ] && X0="--watchdog-cycles 3 --period-us $D_PERIOD_US --log $TMPD/armlog0$1.txt" \
        X1="--watchdog-cycles 3 --period-us $D_PERIOD_US --log $TMPD/armlog1$1.txt" P=$PIN2
    $RTA $P "$ARMSIM" --iface vcan0 --robot "$URDF0" --id-base 0x100 --dec-limit "$DEC" --acc-limit 10 --q0 "$Q00" \
        $X0 --stats "$TMPD/armsim0$1.txt" > "$OUT/armsim0$1.log" 2>&1 &
    A0=$!
    $RTA $P "$ARMSIM" --iface vcan1 --robot "$URDF1" --id-base 0x100 --dec-limit "$DEC" --acc-limit 10 --q0 "$Q01" \
        $X1 --stats "$TMPD/armsim1$1.txt" > "$OUT/armsim1$1.log" 2>&1 &
    A1=$!
    sleep 0.5
}
stop_armsims() {
    kill -TERM $A0 $A1 2>/dev/null
    wait $A0 $A1 2>/dev/null
    for i in 0 1; do
        echo "E2E phase $1: emulator vcan$i: $(sed -n 's/^\(cycles=[0-9]*\) .*\(cmd_accepted=[0-9]*\) \(cmd_superseded=[0-9]*\) .*\(state=[A-Z]*\) \(fault_code=[0-9]*\).*/\1 \2 \3 \4 \5/p' "$TMPD/armsim$i$1.txt" 2>/dev/null)"
    done
}
# task time of the newest row of a CSV being written (a partly flushed last line only reads lower)
csv_t() { tail -n 1 "$1" 2>/dev/null | cut -d, -f1; }

# candump_stop FILE PID MAX IFACE...: candump drained up to end markers (at most 30 s), then stopped
. "$S/tests/can/candump_stop.sh"
# The end of an arm's feedback on vcan$2 in the candump capture $1, for an arm of $3 joints (payload hex:
# byte 1 = fault << 4 | state, bytes 4.. positions int32 x N, bytes 36.. velocities int16 x N). Prints:
# frames_captured, frames_looked_at (the last two), state/fault byte of the last, its velocities all zero,
# its positions equal to the frame before.
last_feedback() {
    nfb=$(grep -c " vcan$2 101##" "$1")
    grep " vcan$2 101##" "$1" | tail -n 2 | sed 's/.*##.//' | awk -v nj="$3" -v total="$nfb" '
        { n++; p[n] = substr($0, 9, 8 * nj); s = substr($0, 3, 2); vel = substr($0, 73, 4 * nj) }
        END { print total, n + 0, (s == "" ? "-" : s), (length(vel) == 4 * nj && vel !~ /[^0]/),
                    (n == 2 && p[1] == p[2]) }'
}
# mcad's log: exit 0, stopped, no fault, no CSV rows dropped; $1 = phase name, $2 = rc, $3 = log
check_stopped() {
    f=0
    [ "$2" -eq 0 ] || { echo "E2E FAIL: $1: mcad exit status $2"; f=1; }
    grep -q "summary: state stopped" "$3" || { echo "E2E FAIL: $1: not stopped"; f=1; }
    grep -q "summary: faults: none" "$3" || { echo "E2E FAIL: $1: fault"; f=1; }
    ! grep -q "summary: dropped" "$3" || { echo "E2E FAIL: $1: $(grep 'summary: dropped' "$3")"; f=1; }
    return $f
}
# The braking ramp in mcad's CSV $1, ending in state $2 (4 stopped, 5 fault): from the last running row on,
# every commanded qdot changes by at most dec * dt per tick (+ 2e-6: the CSV prints 6 significant digits),
# all reach exactly 0 in the minimum number of ticks ceil(max |v0| / (dec dt)) (the print precision of v0
# may make that one more or less), and stay 0 in state $2. Prints: ok t_stop t_zero ticks max_change
# violations max|v0| its_joint min_ticks
STEP=$(awk -v d="$DEC" -v t="$DT" 'BEGIN { print d * t }')
ramp() {
    awk -F, -v step="$STEP" -v fin="$2" '
        NR == 1 { for (i = 1; i <= NF; i++) if ($i ~ /^qdot/) q[++nq] = i; else if ($i == "state") cs = i; next }
        { st = $cs
          if (st == 2) { t_stop = $1; r0 = NR; nb = 0; z = 0; bad = 0; dmax = 0; vmax = 0
                         for (j = 1; j <= nq; j++) { v[j] = $q[j]; x = v[j] < 0 ? -v[j] : v[j]; if (x > vmax) { vmax = x; jm = j } }
                         next }
          if (!r0) next
          if (st != 3 && st != fin) bad++
          allz = 1
          for (j = 1; j <= nq; j++) {
              x = $q[j] - v[j]; if (x < 0) x = -x; if (x > dmax) dmax = x
              if (x > step + 2e-6) bad++
              if ($q[j] + 0 != 0) allz = 0
              v[j] = $q[j]
          }
          if (!z) { nb++; if (allz) { z = 1; t_zero = $1 } } else if (!allz) bad++
          if (z && st != fin) bad++ }
        END { lo = vmax / step - 1e-3; hi = vmax / step + 1e-3
              lo = lo == int(lo) ? lo : int(lo) + 1; hi = hi == int(hi) ? hi : int(hi) + 1
              ok = r0 && z && !bad && nb >= lo && nb <= hi
              printf "%d %.4f %.4f %d %.6f %d %.4f %d %d\n", ok, t_stop, t_zero, nb, dmax, bad + 0, vmax, jm, lo }' "$1"
}
fail=0

# ---- phase A: the whole task with DDS and mca-monitor
if echo "$PHASES" | grep -q A; then
    t0=$(now)
    armsims A
    $PIN2 "$MON" --config "$S/config/dds/loopback.xml" --domain 0 --no-color --csv "$TMPD/monitor.csv" \
        > "$OUT/monitor.log" 2> "$OUT/monitor.err" &
    M=$!
    sleep 2
    t1=$(now)
    $PIN2 "$MCAD" --stop-after "$A_STOP" --csv "$TMPD/mcadA.csv" "$CELL" 2> "$OUT/mcadA.log"
    rc=$?
    t2=$(now)
    # the reader drains what reached it, then exits cleanly on SIGTERM
    sleep 3
    kill -TERM $M 2>/dev/null
    wait $M
    mrc=$?
    stop_armsims A
    cat "$OUT/mcadA.log" "$OUT/monitor.err"
    fA=0
    check_stopped "phase A" $rc "$OUT/mcadA.log" || fA=1
    [ $mrc -eq 0 ] || { echo "E2E FAIL: phase A: mca-monitor exit status $mrc"; fA=1; }
    # mcad's CSV: one row per tick from t = 0 through A_STOP, running until then, every distance above d1
    # while running, tool tips tracking and (whole task) at their last waypoints at the end
    res=$(awk -F, -v d1="$D1" -v dur="$A_STOP" -v whole="$(awk -v a="$A_STOP" -v d="$DUR" 'BEGIN { print a + 0 >= d + 0 }')" \
              -v e0="$END0" -v e1="$END1" '
        NR == 1 { for (i = 1; i <= NF; i++) c[$i] = i; next }
        { n++; t = $1 + 0
          if (n == 1) t_first = t; else if (t - pt < 0.0009 || t - pt > 0.0011) gaps++
          pt = t
          d = $c["min_d"] + 0
          if (!(d > d1)) below++
          if ($c["state"] == 2) {
              run++; t_run = t
              if (run == 1 || d < dmin) { dmin = d; tmin = t }
              for (a = 0; a < 2; a++) { e = $c["err" a] + 0; if (e > emax) emax = e }
              split(e0, p0, " "); split(e1, p1, " "); fin = 0
              for (k = 1; k <= 3; k++) {
                  x = substr("xyz", k, 1)
                  u = $c["ee0_" x] - p0[k]; v = $c["ee1_" x] - p1[k]; fin += u * u > v * v ? u * u : v * v
              }
          } else if ($c["state"] != 3 && $c["state"] != 4) other++
        }
        END { ok = n > 0 && t_first == 0 && !gaps && t_run >= dur - 0.0015 && !below && !other && \
                  emax < 1e-3 && (!whole || sqrt(fin) < 1e-3)
              printf "%d %d %d %.4f %.5f %.3f %d %.2e %.2e %d\n", ok, n, run, t_run, dmin, tmin, below + 0,
                  emax, sqrt(fin), gaps + 0 }' "$TMPD/mcadA.csv")
    set -- $res
    echo "E2E phase A: mcad CSV $2 rows ($3 running, to t = $4 s, ${10} gaps), minimum distance $5 m at t = $6 s, rows at or below d1: $7, max tracking error $8 m, tool tips $9 m from their last waypoints"
    [ "$1" = 1 ] || { echo "E2E FAIL: phase A: mcad CSV (want rows from t = 0 every 1 ms through $A_STOP s, all distances > $D1 m, tracking < 1 mm, last waypoints reached at the task's end)"; fA=1; }
    dA=$5 tA=$6 rowsA=$2
    # mca-monitor's samples against mcad's rows of the same tick
    res=$(awk -F, -v d1="$D1" '
        FNR == 1 { if (NR == 1) for (i = 1; i <= NF; i++) c[$i] = i; next }
        NR == FNR { k = int($1 * 1000 + 0.5); d[k] = $c["min_d"]; if (k > kmax) kmax = k; next }
        { m++; k = $2 + 0; if (m == 1) first = k; last = k
          # the final snapshot (sent at exit) carries the tick count: the last row again
          if (!(k in d) && k == kmax + 1) k = kmax
          if (!(k in d)) { nomatch++; next }
          x = $7 - d[k]; if (x < 0) x = -x; if (x > dx) dx = x
          if (x > 1e-7) diff++
          if (!($7 > d1)) below++
          if (m == 1 || $7 < dmin) { dmin = $7; tmin = k } }
        END { ok = m > 0 && !nomatch && !diff && !below
              printf "%d %d %d %d %d %d %.2e %.5f %.3f\n", ok, m, first, last,
                  nomatch + diff, below + 0, dx, dmin, tmin / 1000 }' "$TMPD/mcadA.csv" "$TMPD/monitor.csv")
    set -- $res
    want=$(awk -v r="$rowsA" 'BEGIN { printf "%d", r / 10 }')
    echo "E2E phase A: mca-monitor $2 Distances samples (of $want published at 100 Hz), ticks $3..$4, mismatching mcad's CSV: $5 (max |difference| $7 m), at or below d1: $6, minimum $8 m at t = $9 s"
    # the reader may miss the first samples (discovery) but must see the task through to its end
    awk -v m="$2" -v w="$want" -v f="$3" -v l="$4" -v r="$rowsA" \
        'BEGIN { exit !(m >= 0.9 * w && f < 5000 && l >= r - 1000) }' && [ "$1" = 1 ] ||
        { echo "E2E FAIL: phase A: mca-monitor's samples (want >= 90 % of them, through the end, equal to mcad's, above d1)"; fA=1; }
    grep -q "controller STOPPED, bridge dropped 0" "$OUT/monitor.err" ||
        { echo "E2E FAIL: phase A: mca-monitor did not get the final status STOPPED (or the bridge dropped snapshots)"; fA=1; }
    echo "E2E phase A: $(($(now) - t0)) s (mcad $((t2 - t1)) s for $A_STOP s of task time)"
    [ $fA -eq 0 ] && echo "E2E ok: phase A: cup stacking over vcan0/vcan1 with DDS and mca-monitor: $A_STOP of $DUR s, minimum distance $dA m at $tA s (d1 $D1 m), stopped, no fault"
    [ $fA -eq 0 ] || fail=1
fi

# ---- phase B: SIGTERM while the arms move fast
if echo "$PHASES" | grep -q B; then
    t0=$(now)
    # 12.3-13.2 s: joint speeds 0.42-0.53 rad/s, the arms 0.10-0.15 m apart (the window is wide: mcad's CSV,
    # which times the signal, is written by a non-rt thread and lags the loop by up to ~0.6 s of task here).
    # Not 14.5-15.5 s (0.58 rad/s): the ramp is not collision-aware and there, 2-7 mm above d1, coasting
    # along brought the distance from 0.0722 to 0.0712 m once (stop at 15.37 s).
    T_SIG=12.3
    armsims B
    $PIN2 "$MCAD" --csv "$TMPD/mcadB.csv" "$CELL" 2> "$OUT/mcadB.log" &
    M=$!
    n=0
    while awk -v t="$(csv_t "$TMPD/mcadB.csv")" -v s="$T_SIG" 'BEGIN { exit !(t + 0 < s - 2) }' && [ $n -lt 6000 ]; do
        sleep 0.1; n=$((n + 1))
    done
    # the emulators' feedback frames (id base + 1) on both buses, from before the stop. candump is slow to
    # start in the emulated guest and the lockstep emulators fall silent once mcad has stopped: wait until
    # its capture has frames (1 kHz on each bus) before the signal can be sent (seen: an empty capture when
    # it was started 0.3 s of task time before the signal).
    $PIN2 candump -r 134217728 -L vcan0,101:7FF,7FF:7FF vcan1,101:7FF,7FF:7FF > "$TMPD/b.candump" 2>/dev/null &
    CD=$!
    k=0
    while [ ! -s "$TMPD/b.candump" ] && [ $k -lt 600 ]; do
        sleep 0.05; k=$((k + 1))
    done
    while awk -v t="$(csv_t "$TMPD/mcadB.csv")" -v s="$T_SIG" 'BEGIN { exit !(t + 0 < s) }' && [ $n -lt 6000 ]; do
        sleep 0.05; n=$((n + 1))
    done
    t_seen=$(csv_t "$TMPD/mcadB.csv")
    kill -TERM $M
    wait $M
    rc=$?
    candump_stop "$TMPD/b.candump" $CD 60 vcan0 vcan1
    stop_armsims B
    cat "$OUT/mcadB.log"
    fB=0
    check_stopped "phase B" $rc "$OUT/mcadB.log" || fB=1
    grep -q "SIGTERM: braking to zero" "$OUT/mcadB.log" || { echo "E2E FAIL: phase B: no SIGTERM braking"; fB=1; }
    set -- $(ramp "$TMPD/mcadB.csv" 4)
    echo "E2E phase B: SIGTERM (sent when the CSV showed t = $t_seen s) at t = $2 s with max |commanded qdot| $7 rad/s (joint $8 of 12); all commands 0 at t = $3 s after $4 ticks (minimum $9), max per-tick change $5 rad/s (limit dec_limit * dt = $STEP rad/s), violations $6"
    [ "$1" = 1 ] || { echo "E2E FAIL: phase B: braking ramp outside the deceleration limit, longer than needed or not ending at 0"; fB=1; }
    # the ramp is not collision-aware (the arms coast along their last direction): distances while braking
    dB=$(awk -F, -v d1="$D1" 'NR == 1 { for (i = 1; i <= NF; i++) c[$i] = i; next }
        { d = $c["min_d"] + 0; if (!(d > d1)) below++
          if ($c["state"] == 2) d0 = d; else if (!n++ || d < dm) dm = d }
        END { printf "%d %.5f %.5f\n", below + 0, d0, dm }' "$TMPD/mcadB.csv")
    set -- $dB
    echo "E2E phase B: distance $2 m when the braking began, minimum $3 m while braking, rows at or below d1: $1"
    [ "$1" = 0 ] || { echo "E2E FAIL: phase B: distance at or below d1 ($D1 m)"; fB=1; }
    set -- $(ramp "$TMPD/mcadB.csv" 4)
    # the stop must have come while the arms moved fast (12.3-13.3 s), else this phase proved little
    awk -v v="$7" -v t="$2" -v s="$T_SIG" 'BEGIN { exit !(v > 0.3 && t >= s) }' ||
        { echo "E2E FAIL: phase B: want the stop after $T_SIG s with the arms moving fast (> 0.3 rad/s)"; fB=1; }
    # the emulators' side: the last feedback frame of each bus says READY, no fault, every joint velocity 0,
    # and the same positions as the frame before (last_feedback, 6 joints); the emulators' counters: state
    # READY, no fault
    for i in 0 1; do
        set -- $(last_feedback "$TMPD/b.candump" $i 6)
        st=$(cat "$TMPD/armsim$i""B.txt" 2>/dev/null | sed -n 's/.* watchdog_trips=\([0-9]*\) state=\([A-Z]*\) fault_code=\([0-9]*\).*/\2 fault \3 watchdog trips \1/p')
        echo "E2E phase B: vcan$i: $1 feedback frames captured, last: state/fault byte 0x$3, velocities zero: $4, positions unchanged: $5; emulator: ${st:-?}"
        [ "$2" = 2 ] && [ "$3" = 01 ] && [ "$4" = 1 ] && [ "$5" = 1 ] && [ "$st" = "READY fault 0 watchdog trips 0" ] ||
            { echo "E2E FAIL: phase B: arm on vcan$i not at rest (READY, zero velocity) after the stop"; fB=1; }
    done
    echo "E2E phase B: $(($(now) - t0)) s"
    [ $fB -eq 0 ] && echo "E2E ok: phase B: SIGTERM mid-task: both arms braked within the deceleration limits to 0, at rest, exit 0"
    [ $fB -eq 0 ] || fail=1
fi

# ---- phase C: the MICO2's firmware freezes (SIGSTOP) while both arms dwell (5.0-6.0 s: a moving arm whose
# feedback stops would first make the QP fail, a fault too but not this one): no feedback for the cell's
# lost_feedback_cycles -> fault, both arms braked within the limits, zero commands with the servo released;
# SIGTERM then ends mcad with exit status 3.
if echo "$PHASES" | grep -q C; then
    t0=$(now)
    LOST=$(sed -n 's/^ *lost_feedback_cycles: *\([0-9]*\).*/\1/p' "$CELL")
    armsims C
    $PIN2 "$MCAD" --no-dds --csv "$TMPD/mcadC.csv" "$CELL" 2> "$OUT/mcadC.log" &
    M=$!
    n=0
    while awk -v t="$(csv_t "$TMPD/mcadC.csv")" 'BEGIN { exit !(t + 0 < 5.2) }' && [ $n -lt 6000 ]; do
        sleep 0.1; n=$((n + 1))
    done
    kill -STOP $A1
    n=0
    while ! grep -q "state fault" "$OUT/mcadC.log" && [ $n -lt 300 ]; do sleep 0.2; n=$((n + 1)); done
    kill -TERM $M
    wait $M
    rc=$?
    kill -CONT $A1
    stop_armsims C
    cat "$OUT/mcadC.log"
    fC=0
    [ $rc -eq 3 ] || { echo "E2E FAIL: phase C: mcad exit status $rc, want 3 (fault)"; fC=1; }
    grep -q "arm 1: no feedback for $LOST cycles" "$OUT/mcadC.log" || { echo "E2E FAIL: phase C: no lost-feedback report"; fC=1; }
    grep -q "braking both arms: lost feedback" "$OUT/mcadC.log" || { echo "E2E FAIL: phase C: no braking"; fC=1; }
    grep -q "all joints commanded to zero at .* state fault" "$OUT/mcadC.log" || { echo "E2E FAIL: phase C: not braked"; fC=1; }
    grep -q "summary: faults: 1 .*lost feedback" "$OUT/mcadC.log" || { echo "E2E FAIL: phase C: the fault is not lost feedback"; fC=1; }
    set -- $(ramp "$TMPD/mcadC.csv" 5)
    echo "E2E phase C: fault at t = $2 s with max |commanded qdot| $7 rad/s; all commands 0 at t = $3 s after $4 ticks (minimum $9), max per-tick change $5 rad/s, violations $6"
    [ "$1" = 1 ] || { echo "E2E FAIL: phase C: braking ramp outside the deceleration limit or not ending at 0"; fC=1; }
    echo "E2E phase C: $(($(now) - t0)) s"
    [ $fC -eq 0 ] && echo "E2E ok: phase C: frozen firmware on vcan1: lost feedback fault after $LOST cycles, both arms braked, exit 3"
    [ $fC -eq 0 ] || fail=1
fi
# ---- phase D: mcad SIGKILLed mid-task while the arms move: nothing brakes them but each emulator's own
# watchdog (3 cycles). So the emulators run on their own clock here (lockstep has no watchdog: without
# commands it runs no cycle), on the other CPU than the loop. Not at 1 ms: two 1 kHz emulators slow the
# TCG guest so much that mcad managed one tick per ~5 firmware cycles and the watchdog tripped at
# t = 0.06-0.08 s (both placements tried). With a 4 ms firmware cycle (D_PERIOD_US; dt 4 ms, the watchdog
# 12 ms, the deceleration step dec_limit * 4 ms) mcad's ~3-4 commands per cycle are taken newest first
# and the arm follows the task. An early trip shows in mcad's log ("reports FAULT"): see below.
# candump records every frame of both id blocks from before the start; the host checks the capture
# (check_watchdog.py: tests/can/check_bus.py's watchdog case per bus) against the emulators' --log.
if echo "$PHASES" | grep -q D; then
    t0=$(now)
    # the first segment's quintic (3 s to above the first cup): joint speeds > 0.15 rad/s from 0.5 to 2.5 s,
    # 0.59 at 1.5 s. mcad kills itself (SIGKILL: nothing brakes, nothing is flushed) at tick K_KILL, the
    # cell's test hook debug_kill_after_ticks (so phase D runs the test build, mcad-test): a kill from this
    # shell, timed by polling the CSV, landed at 2.1-3 s of task time when the host was busy (the arms at
    # < 0.1 rad/s). The arm's speed at the kill is checked from the bus (>= 0.1 rad/s).
    K_KILL=1500
    CELL_D=$OUT/cup_stacking_vcan_e2e_D.yaml
    { cat "$CELL"; echo "debug_kill_after_ticks: $K_KILL   # vcan_e2e.sh phase D: mcad dies at tick $K_KILL"; } > "$CELL_D"
    # A trip before the kill needs 3 firmware cycles (>= 2 D_PERIOD_US apart) without a command. mcad's CSV
    # has each tick's time since the last tick's commands (cmd_gap_us; the CSV is flushed at every drain, so
    # a SIGKILL leaves it nearly whole). A trip with a gap of >= 2 firmware cycles in the 50 ms of task time
    # before mcad saw it is the guest starving the loop (SCHED_FIFO alone on its CPU: only a vCPU the host
    # did not run, or ran slowly, holds it that long), and the arm's watchdog did right: the phase runs
    # again, at most 3 times; when the guest starved the loop every time, phase D is not judged (SKIP, and
    # the test shows as skipped). A trip without such a gap is a failure.
    D_GAP_MS=$(awk -v p="$D_PERIOD_US" 'BEGIN { print 2 * p / 1000 }')
    skipD=0
    unexplained=0
    for attempt in 1 2 3; do
        $PIN2 candump -r 134217728 -L vcan0,100:7F0,7FF:7FF vcan1,100:7F0,7FF:7FF > "$TMPD/d.candump" 2>/dev/null &
        CD=$!
        sleep 0.3
        armsims D clocked
        $PIN2 "$MCAD_TEST" --no-dds --csv "$TMPD/mcadD.csv" "$CELL_D" 2> "$OUT/mcadD.log"
        rc=$?
        t_seen=$(csv_t "$TMPD/mcadD.csv")
        # the watchdog, the ramp (<= 0.1 s at 5 rad/s^2 from <= 0.5 rad/s) and a few WATCHDOG heartbeats
        sleep 2
        stop_armsims D
        candump_stop "$TMPD/d.candump" $CD 60 vcan0 vcan1
        cat "$OUT/mcadD.log"
        fD=0
        [ $rc -eq 137 ] || { echo "E2E FAIL: phase D: mcad exit status $rc, want 137 (SIGKILL)"; fD=1; }
        early=0
        ! grep -q "fault at\|brakes on its own\|reports FAULT" "$OUT/mcadD.log" || early=1
        if [ $early -eq 1 ]; then
            t_f=$(sed -n 's/.*fault at t = \([0-9.]*\) s.*/\1/p' "$OUT/mcadD.log" | head -n 1)
            # the longest gap between two ticks' commands in the 50 ms of task time before mcad saw the fault
            stall=$(awk -F, -v tf="${t_f:-0}" 'NR == 1 { for (i = 1; i <= NF; i++) c[$i] = i; next }
                $1 + 0 <= tf + 0.0005 && $1 + 0 >= tf - 0.05 && $c["cmd_gap_us"] > g { g = $c["cmd_gap_us"] + 0; at = $1 }
                END { if (g > 0) printf "%s %.1f\n", at, g / 1000 }' "$TMPD/mcadD.csv")
            set -- $stall
            if [ -n "$stall" ] && awk -v g="$2" -v m="$D_GAP_MS" 'BEGIN { exit !(g >= m) }'; then
                echo "E2E phase D: attempt $attempt: the guest starved mcad's loop: $2 ms without a command before t = $1 s (the firmware's watchdog is 3 cycles of $((D_PERIOD_US / 1000)) ms), and the arm's watchdog braked it as it should (mcad: fault at t = $t_f s; $(grep -c 'loop stall at' "$OUT/mcadD.log") loop stalls logged; host load $(cut -d' ' -f1 /proc/loadavg) in the guest)"
                if [ $attempt -lt 3 ]; then
                    echo "E2E phase D: running phase D once more"
                    continue
                fi
                echo "E2E SKIP: phase D: the guest starved mcad's loop on all 3 attempts: not judged (the host is too busy for a 12 ms watchdog under TCG)"
                skipD=1
                break
            fi
            # No loop gap explains it. Seen once per few runs under TCG: "lost feedback ... for 20 cycles"
            # while the bus capture shows the emulator's feedback every 4-6 ms and the emulator reports
            # missed cycles of its own (overruns). Not yet explained (docs/daemon.md, "Open"): one such attempt
            # is reported and the phase runs again; a fault of this kind on every attempt fails the test.
            ovr=$(sed -n 's/.* overruns=\([0-9]*\) .*/\1/p' "$TMPD/armsim0D.txt" "$TMPD/armsim1D.txt" 2>/dev/null | tr '\n' '/')
            why="a fault before the kill without a gap of $D_GAP_MS ms or more between mcad's commands in the 50 ms before it (the longest: ${2:-?} ms at t = ${1:-?} s): $(grep -m1 'fault at' "$OUT/mcadD.log" | sed 's/^<[0-9]>//'); emulator overruns ${ovr:-?}; $(grep -c 'loop stall at' "$OUT/mcadD.log") loop stalls logged"
            if [ $attempt -lt 3 ]; then
                echo "E2E NOTE: phase D: attempt $attempt: $why: not explained by a starved loop; running phase D once more (a fault like it on every attempt fails)"
                unexplained=$((unexplained + 1))
                continue
            fi
            echo "E2E FAIL: phase D: $why (unexplained early faults on all 3 attempts: $((unexplained + 1)))"
            fD=1
        fi
        [ "${unexplained:-0}" -eq 0 ] || echo "E2E NOTE: phase D: $unexplained earlier attempt(s) ended in an unexplained early fault (above); this attempt is judged"
        for i in 0 1; do
            st=$(sed -n 's/.* watchdog_trips=\([0-9]*\) state=\([A-Z]*\) fault_code=\([0-9]*\).*/\2 fault \3 watchdog trips \1/p' "$TMPD/armsim$i""D.txt" 2>/dev/null)
            echo "E2E phase D: vcan$i: $(grep -c " vcan$i 10[0-3]##" "$TMPD/d.candump") frames captured; emulator: ${st:-?}"
            [ "$st" = "FAULT fault 1 watchdog trips 1" ] || { echo "E2E FAIL: phase D: emulator on vcan$i not in FAULT WATCHDOG after one trip"; fD=1; }
        done
        break
    done
    echo "E2E phase D: mcad SIGKILLed itself at tick $K_KILL (its CSV, as far as the last drain, reached t = ${t_seen:-?} s); $(($(now) - t0)) s"
    [ $fD -eq 0 ] || fail=1
fi
# ---- phases E and F: a shipped two-PA10+ cell (8 joints in every command and feedback frame) run whole
# over vcan0/vcan1 with lockstep emulators; the host then compares the trajectory (and E's fault tick) with
# the sim backend's (host_checks).
#   E: task 4, the negative example (negative_vcan). Tracking and avoidance contradict; once the tools are
#      close the QP has no solution and the PDNN does not converge: mcad must name that fault, brake both
#      arms within the limits, keep every distance above d1, send zero commands with the servo released,
#      and exit 3 at stop_after (9 s).
#   F: task 1, the paper's cross circles (cross_circles_vcan): the whole 10 s, every distance above d1,
#      exit 0 stopped at stop_after (11 s) with no fault.
#   G: task 2, the character "Hui" (hui_vcan): the same over its first $G_STOP s (stop_after; default 8).
# $1 = phase letter, $2 = shipped cell, $3 = its scenario, $4 = fault | stopped (how the run must end)
pa10_phase() {
    t0=$(now)
    tag=$1 want=$4 stop_at=${5:-}
    cell=$OUT/$(basename "$2" .yaml)_e2e.yaml
    sed -e "s|\.\./|$S/config/|g" \
        -e "${stop_at:+s/^stop_after:.*/stop_after: $stop_at   # vcan_e2e.sh: the first $stop_at s of the task/}" \
        -e 's/^\(  overrun_limit:\).*/\1 3600000   # vcan_e2e.sh: emulated guest CPU (TCG)/' -e '/^  overrun_limit:/a\  pdnn_budget_us: 1000000   # vcan_e2e.sh: emulated guest CPU (TCG): the PDNN may take 1 s' \
        -e "s/^\(  cpu:\).*/\1 $LOOP_CPU   # vcan_e2e.sh: the loop on the emulators' CPU/" "$2" > "$cell"
    diff "$2" "$cell" | grep '^[<>]' | sed 's/^</-  /; s/^>/+  /'
    fp=0
    "$MCAD" --check "$cell" > "$OUT/check$tag.txt" 2>&1 || { cat "$OUT/check$tag.txt"; echo "E2E FAIL: phase $tag: mcad --check"; fp=1; }
    grep -q "arm 0 'left': .*pa10plus.urdf, 8 joints.* socketcan vcan0 id_base 0x100" "$OUT/check$tag.txt" &&
        grep -q "arm 1 'right': .*pa10plus.urdf, 8 joints.* socketcan vcan1 id_base 0x100" "$OUT/check$tag.txt" ||
        { cat "$OUT/check$tag.txt"; echo "E2E FAIL: phase $tag: cell: want the two PA10+ on vcan0 and vcan1"; fp=1; }
    D1=$(sed -n 's/^d1: *\([0-9.]*\).*/\1/p' "$3")
    DEC=$(sed -n 's/^ *dec_limit: *\([0-9.]*\).*/\1/p' "$2" | head -n 1)
    STEP=$(awk -v d="$DEC" -v t="$DT" 'BEGIN { print d * t }')
    stop_t=$(sed -n 's/^stop_after: *\([0-9.]*\).*/\1/p' "$cell")
    URDF0=$S/config/scenarios/$(arm_field 1 urdf "$3") Q00=$(arm_field 1 q0 "$3")
    URDF1=$S/config/scenarios/$(arm_field 2 urdf "$3") Q01=$(arm_field 2 q0 "$3")
    # the emulators' feedback frames on both buses, from before the start (the lockstep emulators answer
    # every tick until mcad exits)
    $PIN2 candump -r 134217728 -L vcan0,101:7FF,7FF:7FF vcan1,101:7FF,7FF:7FF > "$TMPD/$tag.candump" 2>/dev/null &
    CD=$!
    sleep 0.3
    armsims "$tag"
    $PIN2 "$MCAD" --no-dds --csv "$TMPD/mcad$tag.csv" "$cell" 2> "$OUT/mcad$tag.log"
    rc=$?
    candump_stop "$TMPD/$tag.candump" $CD 60 vcan0 vcan1
    stop_armsims "$tag"
    cat "$OUT/mcad$tag.log"
    if [ "$want" = fault ]; then
        [ $rc -eq 3 ] || { echo "E2E FAIL: phase $tag: mcad exit status $rc, want 3 (fault)"; fp=1; }
        grep -q "fault at t = .* s: braking both arms: PDNN residual" "$OUT/mcad$tag.log" ||
            { echo "E2E FAIL: phase $tag: no PDNN-not-converged fault"; fp=1; }
        grep -q "all joints commanded to zero at .* state fault" "$OUT/mcad$tag.log" || { echo "E2E FAIL: phase $tag: not braked"; fp=1; }
        grep -q "summary: faults: 1 " "$OUT/mcad$tag.log" || { echo "E2E FAIL: phase $tag: want exactly one fault"; fp=1; }
        set -- $(ramp "$TMPD/mcad$tag.csv" 5)
        echo "E2E phase $tag: fault at t = $2 s with max |commanded qdot| $7 rad/s (joint $8 of 16); all commands 0 at t = $3 s after $4 ticks (minimum $9), max per-tick change $5 rad/s (limit $STEP), violations $6"
        [ "$1" = 1 ] || { echo "E2E FAIL: phase $tag: braking ramp outside the deceleration limit, longer than needed or not ending at 0"; fp=1; }
    else
        check_stopped "phase $tag" $rc "$OUT/mcad$tag.log" || fp=1
        if [ -n "$stop_at" ]; then
            # stopped mid-task by stop_after: the same braking checks as phase B's SIGTERM
            set -- $(ramp "$TMPD/mcad$tag.csv" 4)
            echo "E2E phase $tag: stop_after at t = $2 s with max |commanded qdot| $7 rad/s (joint $8 of 16); all commands 0 at t = $3 s after $4 ticks (minimum $9), max per-tick change $5 rad/s (limit $STEP), violations $6"
            [ "$1" = 1 ] || { echo "E2E FAIL: phase $tag: braking ramp outside the deceleration limit, longer than needed or not ending at 0"; fp=1; }
        fi
    fi
    set -- $(awk -F, -v d1="$D1" 'NR == 1 { for (i = 1; i <= NF; i++) c[$i] = i; next }
        { d = $c["min_d"] + 0; if (!(d > d1)) below++; if (!n++ || d < dm) { dm = d; tm = $1 } }
        END { printf "%d %.5f %.3f %d %.4f\n", below + 0, dm, tm, n, $1 }' "$TMPD/mcad$tag.csv")
    echo "E2E phase $tag: $4 CSV rows to t = $5 s, minimum distance $2 m at t = $3 s (d1 $D1 m), rows at or below d1: $1"
    awk -v n="$4" -v s="$stop_t" 'BEGIN { exit !(n >= s * 1000) }' && [ "$1" = 0 ] ||
        { echo "E2E FAIL: phase $tag: a distance at or below d1, or the run ended before stop_after ($stop_t s)"; fp=1; }
    # the buses: each arm's last two feedback frames READY, no fault, all 8 velocities 0, positions unchanged
    for i in 0 1; do
        set -- $(last_feedback "$TMPD/$tag.candump" $i 8)
        echo "E2E phase $tag: vcan$i: $1 feedback frames captured, last: state/fault byte 0x$3, velocities zero: $4, positions unchanged: $5"
        [ "$2" = 2 ] && [ "$3" = 01 ] && [ "$4" = 1 ] && [ "$5" = 1 ] ||
            { echo "E2E FAIL: phase $tag: arm on vcan$i not at rest (READY, zero velocity) at the end"; fp=1; }
    done
    echo "E2E phase $tag: $(($(now) - t0)) s"
    return $fp
}
if echo "$PHASES" | grep -q E; then
    pa10_phase E "$SRC_CELL_E" "$SCN_E" fault &&
        echo "E2E ok: phase E: negative task over vcan0/vcan1 (8 joints): PDNN-not-converged fault named, both arms braked within the limits to rest above d1, exit 3" ||
        fail=1
fi
if echo "$PHASES" | grep -q F; then
    pa10_phase F "$SRC_CELL_F" "$SCN_F" stopped &&
        echo "E2E ok: phase F: cross circles over vcan0/vcan1 (8 joints): the whole task above d1, stopped, no fault, both arms at rest" ||
        fail=1
fi
if echo "$PHASES" | grep -q G; then
    pa10_phase G "$SRC_CELL_G" "$SCN_G" stopped "$G_STOP" &&
        echo "E2E ok: phase G: Hui over vcan0/vcan1 (8 joints): its first $G_STOP s above d1, stopped (braked from motion), no fault, both arms at rest" ||
        fail=1
fi
[ $fail -eq 0 ] && [ "${skipD:-0}" -eq 1 ] && fail=$SKIP_RC
echo "E2E phases $PHASES: $(($(now) - t_all)) s in the guest, exit status $fail"
exit $fail
