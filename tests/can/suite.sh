#!/bin/sh
# The vcan suite, in two phases so the slow part (python) need not run inside the emulated guest:
#   suite.sh run   BUILD_DIR SOURCE_DIR OUT_DIR   scenarios on vcan (root, kernel with vcan): captures,
#                                                 program stats and exit codes into OUT_DIR
#   suite.sh check SOURCE_DIR PYTHON OUT_DIR      verdicts from OUT_DIR (cantools + the DBC); prints
#                                                 "CAN-SUITE ok|FAIL|SKIP <case>" lines, exit 0 only if all
#                                                 pass, 77 (skipped) if none failed but one could not be
#                                                 judged because the guest was starved (it says so)
set -u
phase=$1
if [ "$phase" = check ]; then
    S=$2 PY=$3 OUT=$4
    RES=$OUT/results.txt
    CHECK="$PY $S/tests/can/check_bus.py $S/config/can/mca.dbc"
    fails=0 skips=0
    note() { echo "$*" | tee -a "$RES"; }
    verdict() { # case rc
        if [ "$2" -eq 0 ]; then note "CAN-SUITE ok   $1"; else note "CAN-SUITE FAIL $1"; fails=$((fails + 1)); fi
    }
    [ -s "$OUT/status.env" ] || { note "CAN-SUITE FAIL the scenario phase wrote no status (did it run?)"; exit 1; }
    . "$OUT/status.env"
    cat "$OUT/run.txt" >>"$RES" 2>/dev/null
    chk() { # case args...: check_bus.py's own exit status (a crash is a failure too)
        $CHECK "$@" >"$OUT/check.$1.txt" 2>&1
        r=$?
        cat "$OUT/check.$1.txt" | tee -a "$RES"
        return $r
    }
    [ "$A_RC$A_ARC" = 00 ] && chk a "$OUT/a.candump" "$OUT/a.log" "$OUT/a.ctl" "$OUT/a.armsim" "$OUT/a.armlog"
    verdict "a: 2 s sine run, bus decoded with the DBC = logged values: commands, feedback, state, fault (ctl rc $A_RC, armsim rc $A_ARC)" $?
    [ "$B_ALIVE$B_RC" = 13 ] && chk b "$OUT/b.candump" "$OUT/b.ctl" "$B_LOST"
    verdict "b: emulator killed -> lost feedback reported within $B_LOST cycles, commanding stopped (alive $B_ALIVE, ctl rc $B_RC, want 1 3)" $?
    if [ "${C_TRIPS:-1}" = 1 ]; then
        chk c "$OUT/c.candump" "$C_WD" "$C_DEC" "$OUT/c.armsim" "$OUT/c.armlog"
        verdict "c: controller killed -> watchdog BRAKING after $C_WD cycles, ramp within $C_DEC rad/s^2, FAULT" $?
    else
        # every attempt had a watchdog trip before the kill: the test controller (SCHED_FIFO, alone on the
        # guest's vCPU with the emulator) sent nothing for >= C_WD firmware cycles while alive, which only a
        # vCPU the host did not run does; the arm's watchdog did its job, but the kill then found it outside
        # SERVOING, so the case cannot be judged
        note "CAN-SUITE SKIP c: not judged: the guest was starved on all $C_TRIES attempts (watchdog trips before the kill: $C_TRIPS in the last; the host did not run the guest's vCPU for >= $C_WD ms)"
        skips=$((skips + 1))
    fi
    [ "$D_RC$D_ARC" = 00 ] && chk d "$OUT/d.candump" "$OUT/d.ctl" "$OUT/d.armsim" && ! grep -q '^rx .* 3.0000000' "$OUT/d.log"
    drc=$?
    [ "$D_RC$D_ARC" = 00 ] || note "d: what the programs said: $(tail -n 3 "$OUT/d.err" 2>/dev/null | tr '\n' ' ')"
    verdict "d: injected malformed frames counted by the receiving side, not applied (ctl rc $D_RC, armsim rc $D_ARC)" $drc
    [ "$D_RC$D_ARC" = 00 ] && chk e "$OUT/d.candump" "$OUT/d.ctl" "$OUT/d.log"
    verdict "e: error frames counted by the first read after each, MCA_EIO in the cycles the read contract gives, bus-off held until the next feedback" $?
    cat "$OUT/f.out" >>"$RES" 2>/dev/null
    verdict "f: same trajectory via in-process sim and SocketCAN + mca-armsim ($(grep compare "$OUT/f.out"))" "$F_RC"
    [ "$F_RC" = 0 ] && chk g "$OUT/f.out"
    verdict "g: command->feedback round trip over vcan (lockstep, kernel rx stamp - write time): $(grep rtt_us "$OUT/f.out")" $?
    verdict "h: the kernel's drops from a full receive queue reach the reader (SO_RXQ_OVFL): $(cat "$OUT/h.out" 2>/dev/null)" "${H_RC:-1}"
    note "CAN-SUITE done: $fails failing, $skips not judged (guest starved)"
    [ $fails -eq 0 ] || exit 1
    [ $skips -eq 0 ] || exit 77
    exit 0
fi

[ "$phase" = run ] || { echo "usage: suite.sh run BUILD SOURCE OUT | suite.sh check SOURCE PYTHON OUT" >&2; exit 2; }
B=$2 S=$3 OUT=$4
ARMSIM=$B/sim_backend/armsim_can/mca-armsim
CTL=$B/tests/can/mca-can-ctl
URDF=$S/config/robots/jaco2.urdf
Q0=0,3.14,3.14,0,0,0
IF=${MCA_VCAN_IF:-vcan0}
mkdir -p "$OUT"
ST=$OUT/status.env
: >"$ST"
note() { echo "$*" | tee -a "$OUT/run.txt"; }
for t in "$ARMSIM" "$CTL"; do
    [ -x "$t" ] || { note "CAN-SUITE FAIL setup: $t not built"; exit 1; }
done
command -v candump >/dev/null && command -v cansend >/dev/null || { note "CAN-SUITE FAIL setup: can-utils missing"; exit 1; }
if ! ip link show "$IF" >/dev/null 2>&1; then
    ip link add dev "$IF" type vcan || { note "CAN-SUITE FAIL setup: cannot create $IF"; exit 1; }
fi
ip link set "$IF" mtu 72 2>/dev/null
ip link set up "$IF"
# Inside the guest: big socket buffers and backlog (processes can be starved for 100s of ms under TCG).
if [ "${MCA_IN_GUEST:-0}" = 1 ]; then
    echo 67108864 >/proc/sys/net/core/rmem_max
    echo 16777216 >/proc/sys/net/core/rmem_default
    echo 100000 >/proc/sys/net/core/netdev_max_backlog
    # frames are delivered in softirq context; deferred to ksoftirqd (SCHED_OTHER) they wait behind the
    # FIFO programs (an error frame counted 5 reads late): ksoftirqd above them, as vcan_e2e.sh does
    for k in $(pgrep '^ksoftirqd/'); do chrt -f -p 95 "$k" >/dev/null 2>&1; done
fi
note "CAN-SUITE kernel $(uname -r), $IF mtu $(cat /sys/class/net/$IF/mtu), $(nproc) cpu"
# Controller and emulator at real-time priority when allowed (root): the shell and candump do not
# delay their cycles.
RT=""
RT_HI=""
chrt -f 50 true 2>/dev/null && RT="chrt -f 50" && RT_HI="chrt -f 60"

# candump writes to a tmpfs (the shared tree is 9p in the guest: slow), copied out afterwards.
TMPD=$(mktemp -d /dev/shm/mca-can.XXXXXX 2>/dev/null || mktemp -d)
# the arm's id block, the end marker (candump_stop) and every error frame (#FFFFFFFF: error mask). candump may
# not run at all while the real-time programs do (one vCPU): its socket must hold the whole case. 32 MB held
# ~45 800 frames and case d sends ~50 000 (seen failing twice, "capture incomplete"): 128 MB here and in the
# other captures (canopen suite, vcan_e2e)
dump_start() { DUMPF=$1; candump -r 134217728 -L "$IF,100:7F0,7FF:7FF,#FFFFFFFF" >"$TMPD/dump" 2>/dev/null & DUMP=$!; sleep 0.2; }
# candump runs below the real-time programs and may lag far behind: let it drain (up to 120 s), stop it
. "$S/tests/can/candump_stop.sh"
dump_stop() { candump_stop "$TMPD/dump" "$DUMP" 240 "$IF"; cp "$TMPD/dump" "$DUMPF"; }
# wait until N frames of an id were seen (programs start slowly in the guest); fails after 60 s
seen() { timeout 60 candump -n "$2" "$IF,$1:7FF" >/dev/null; }
# one current frame of an id, payload hex (bounded: never hang the suite)
grab() { timeout 5 candump -n 1 -L "$IF,$1:7FF" | sed 's/.*##.//'; }
T="timeout 300"
# Runs that are not about the watchdog or lost feedback use long limits (1000 cycles), so a preempted
# cycle in the emulated guest is not a fault there.
WD_LONG=1000

# (a) controller and emulator run 2 s of sinusoidal joint velocities; the bus, decoded with the DBC,
#     carries exactly what the controller logged as sent (flags, velocities, position refs) and received,
#     and the state and fault frames the emulator logged as sent. Joint 0 is commanded 1 rad/s (above
#     its 0.63 rad/s limit) in cycles 800..829: the arm flags VEL_SAT, so fault frames are on the bus.
dump_start "$OUT/a.candump"
$RT "$ARMSIM" --iface "$IF" --robot "$URDF" --q0 $Q0 --watchdog-cycles $WD_LONG --stats "$OUT/a.armsim" --log "$OUT/a.armlog" 2>>"$OUT/a.err" & ARM=$!
seen 101 1
$T $RT "$CTL" --iface "$IF" --joints 6 --mode sine --duration 2 --lost-cycles $WD_LONG --sat-from 800 --sat-len 30 \
    --sat-vel 1.0 --log "$OUT/a.log" --stats "$OUT/a.ctl" 2>>"$OUT/a.err"
echo "A_RC=$?" >>"$ST"
sleep 0.05; kill "$ARM"; wait "$ARM"; echo "A_ARC=$?" >>"$ST"
dump_stop

# (b) the emulator dies mid-run: the controller reports lost feedback within 5 cycles and stops commanding.
#     If the controller already reported lost feedback before the kill (both programs preempted unevenly
#     in the emulated guest), the run is repeated, at most 3 times (the check reports it if it stays so).
try=1
while :; do
    dump_start "$OUT/b.candump"
    $RT "$ARMSIM" --iface "$IF" --robot "$URDF" --q0 $Q0 --watchdog-cycles $WD_LONG 2>>"$OUT/b.err" & ARM=$!
    seen 101 1
    $T $RT "$CTL" --iface "$IF" --joints 6 --mode sine --duration 60 --lost-cycles 5 --stats "$OUT/b.ctl" 2>>"$OUT/b.err" & C=$!
    seen 100 300
    alive=0; kill -0 "$C" 2>/dev/null && alive=1
    kill -9 "$ARM"; wait "$ARM" 2>/dev/null
    wait "$C"; brc=$?
    dump_stop
    [ $alive = 1 ] || [ $try -ge 3 ] && break
    note "b: attempt $try: the controller reported lost feedback before the kill: repeating"
    try=$((try + 1))
done
echo "B_RC=$brc B_ALIVE=$alive B_LOST=5" >>"$ST"

# (c) the controller dies mid-run: the emulator's watchdog (MCA_CAN_WD cycles, default 3 as the PA-10
#     firmware) brakes within its decel limit, then FAULT.
#     A watchdog trip before the kill (controller preempted >= WD cycles in the emulated guest; the test
#     controller clears it and goes on) could leave the arm outside SERVOING at the kill: then the run is
#     repeated, at most 5 times (if it still happens, the check says the guest was starved and does not judge c).
WD=${MCA_CAN_WD:-3}
try=1
while :; do
    dump_start "$OUT/c.candump"
    $RT "$ARMSIM" --iface "$IF" --robot "$URDF" --q0 $Q0 --watchdog-cycles $WD --dec-limit 5 --stats "$OUT/c.armsim" --log "$OUT/c.armlog" 2>>"$OUT/c.err" & ARM=$!
    seen 101 1
    # (no `timeout` wrapper here: kill -9 must hit the controller itself; --duration bounds it)
    $RT "$CTL" --iface "$IF" --joints 6 --mode sine --duration 60 --lost-cycles $WD_LONG --amp 0.4 2>>"$OUT/c.err" & C=$!
    seen 100 300
    kill -9 "$C"; wait "$C" 2>/dev/null
    seen 102 20                                          # >= 190 firmware cycles after the kill (braking <= 100)
    kill "$ARM"; wait "$ARM"
    dump_stop
    trips=$(sed -n 's/.*watchdog_trips=\([0-9]*\).*/\1/p' "$OUT/c.armsim")
    [ "$trips" = 1 ] || [ $try -ge 5 ] && break
    note "c: attempt $try had $trips watchdog trips (an early one while the controller was preempted): repeating"
    try=$((try + 1))
done
echo "C_WD=$WD C_DEC=5 C_TRIPS=${trips:-0} C_TRIES=$try" >>"$ST"

# (d)+(e) malformed frames (wrong length, replayed counter, unknown ids) and error frames injected with
#     cansend during a run: counted by the side that receives them, never applied; (e) also checks, cycle
#     by cycle, when the controller saw MCA_EIO and bus_off (mca-can-ctl logs "er" lines).
dump_start "$OUT/d.candump"
$RT "$ARMSIM" --iface "$IF" --robot "$URDF" --q0 $Q0 --watchdog-cycles $WD_LONG --stats "$OUT/d.armsim" 2>>"$OUT/d.err" & ARM=$!
seen 101 1
$T $RT "$CTL" --iface "$IF" --joints 6 --mode sine --duration 60 --lost-cycles 10000 --log "$OUT/d.log" --stats "$OUT/d.ctl" 2>>"$OUT/d.err" & C=$!
seen 100 300
zeros64=$(printf '%0128d' 0)
cansend "$IF" 100#1122334455667788                       # command id, classic 8 bytes: wrong length
cansend "$IF" 100##1$(printf '%096d' 0)                  # command id, CAN FD 48 bytes: wrong length
# replay of a genuine command frame (stale counter) with every flag cleared and -0.6 rad/s on all joints:
# if applied, the arm would leave SERVOING (flags 0 = braking request)
hex=$(grab 100)
vel=$(printf '40D8F6FF%.0s' 1 2 3 4 5 6)0000000000000000
cansend "$IF" 100##1$(echo "$hex" | cut -c1-8)00000000$vel$(echo "$hex" | cut -c81-128)
cansend "$IF" 105##1$zeros64                             # unknown id in the arm's block
cansend "$IF" 10F#00                                     # unknown id in the arm's block
cansend "$IF" 101#0102                                   # feedback id, wrong length
hex=$(grab 101)                                          # replayed feedback (stale counter), Pos0 = 3 rad
cansend "$IF" 101##1$(echo "$hex" | cut -c1-8)C0C62D00$(echo "$hex" | cut -c17-128)
# (e) error frames. The bus-off frame goes out while the emulator is stopped (SIGSTOP), as on a real
#     bus-off where no feedback gets through: the controller must hold bus_off (EIO every read) until the
#     first feedback after it. 50 ms = ~50 cycles, far below the long watchdog / lost-feedback limits.
#     The stop window runs above the real-time programs' priority: as a normal shell on a starved guest
#     (1 vCPU shared with two 1 kHz FIFO programs under TCG) it once stretched past the lost-feedback
#     limit (CI: ctl rc 3). The controller's limit here is 10 s, far beyond the window.
$RT_HI sh -c "kill -STOP $ARM; cansend $IF 20000040#0000000000000000; sleep 0.05; kill -CONT $ARM" # bus-off
cansend "$IF" 20000004#0004000000000000                  # error frame: controller problem (rx warning)
seen 100 100                                             # the run goes on after the injections
kill -TERM "$C"; wait "$C"; echo "D_RC=$?" >>"$ST"
sleep 0.05; kill "$ARM"; wait "$ARM"; echo "D_ARC=$?" >>"$ST"
dump_stop

# (f) same trajectory: 1000 lockstep commands through SocketCAN + mca-armsim and through the in-process
#     sim backend give the same joint trajectory within the fixed-point resolution; (g) round trip times.
$RT "$ARMSIM" --iface "$IF" --robot "$URDF" --q0 $Q0 --lockstep 2>>"$OUT/f.err" & ARM=$!
sleep 1
$T $RT "$CTL" --iface "$IF" --joints 6 --mode lockstep --cycles 1000 --compare-robot "$URDF" --q0 $Q0 \
    --stats "$OUT/f.ctl" >"$OUT/f.out" 2>>"$OUT/f.err"
echo "F_RC=$?" >>"$ST"
kill "$ARM"; wait "$ARM"
# (h) frames the kernel dropped from a full receive queue are counted where the backend reads them
#     (SO_RXQ_OVFL): read + dropped = sent (N + 1), dropped > 0
"$B/tests/can/mca-can-drops" "$IF" 500 >"$OUT/h.out" 2>&1
echo "H_RC=$?" >>"$ST"
note "softnet_stat (processed dropped ...): $(cut -d' ' -f1-2 /proc/net/softnet_stat | tr '\n' ' ')"
rm -rf "$TMPD"
note "CAN-SUITE scenarios done"
