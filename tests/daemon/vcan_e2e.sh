#!/bin/sh
# SPDX-License-Identifier: MIT
# End to end over CAN FD: mcad drives task 1 (cross circles, dual PA10+) through the SocketCAN backend,
# each arm on its own virtual bus (vcan0, vcan1) answered by the firmware emulator mca-armsim.
# Natively when this kernel has vcan and we are root, else in one QEMU guest boot (tools/vcan-guest, the
# can engineer's harness). Checks: mcad exits 0 in state stopped with no fault, ran the whole task, and
# its minimum distance is the one of the same task on the in-process sim backend (mca-sim, 0.0514 m).
# Then the right arm's emulator is frozen mid-task: lost-feedback fault, both arms braked, exit status 3.
# usage: vcan_e2e.sh BUILD_DIR SOURCE_DIR [--in-guest]
set -u
B=$(cd "$1" && pwd) S=$(cd "$2" && pwd)
OUT=$B/tests/daemon/vcan-e2e
ARMSIM=$B/sim_backend/armsim_can/mca-armsim
MCAD=$B/daemon/mcad
CELL=$S/tests/daemon/data/cross_circles_vcan_e2e.yaml
if [ "${3:-}" != "--in-guest" ]; then
    rm -rf "$OUT" && mkdir -p "$OUT"
    if [ "$(id -u)" = 0 ] && ip link add dev mcae2etest type vcan 2>/dev/null; then
        ip link del dev mcae2etest
        echo "vcan_e2e: native vcan available"
        exec sh "$0" "$B" "$S" --in-guest
    fi
    echo "vcan_e2e: no vcan on this kernel: booting the QEMU guest (TCG: slow)"
    # an image cache of our own: can_vcan may be building the shared one at the same time (ctest -j)
    job=$OUT/job.sh
    printf '#!/bin/sh\nexport PATH=/usr/local/sbin:/usr/local/bin:/usr/sbin:/usr/bin:/sbin:/bin HOME=/root\nexec sh %s %s %s --in-guest\n' \
        "$S/tests/daemon/vcan_e2e.sh" "$B" "$S" > "$job"
    MCA_GUEST_LOG=$OUT/console.log sh "$S/tools/vcan-guest/run.sh" "$B/tests/daemon/vcan-guest-cache" "$job" 840 >/dev/null
    rc=$?
    grep -a 'E2E\|MCA-GUEST\|mcad:' "$OUT/console.log" | tr -d '\r'
    exit $rc
fi

# ---- inside the guest (or natively as root)
mkdir -p "$OUT"
for i in 0 1; do
    ip link show vcan$i >/dev/null 2>&1 || ip link add dev vcan$i type vcan || { echo "E2E FAIL: cannot create vcan$i"; exit 1; }
    ip link set vcan$i mtu 72
    ip link set up vcan$i
done
URDF=$S/config/robots/pa10plus.urdf
# the scenario's initial joints (config/scenarios/cross_circles.yaml)
Q0L=0,0.7853981633974483,0,-1.5707963267948966,0,0.7853981633974483,0,0.7853981633974483
Q0R=-1.5707963267948966,-0.7853981633974483,0,1.5707963267948966,0,-0.7853981633974483,0,-0.7853981633974483
# lockstep: one firmware cycle per command (virtual time), so a slow (emulated) CPU changes nothing
"$ARMSIM" --iface vcan0 --robot "$URDF" --id-base 0x100 --dec-limit 5 --acc-limit 10 --q0 "$Q0L" --lockstep \
    --stats "$OUT/armsim0.txt" > "$OUT/armsim0.log" 2>&1 &
A0=$!
"$ARMSIM" --iface vcan1 --robot "$URDF" --id-base 0x100 --dec-limit 5 --acc-limit 10 --q0 "$Q0R" --lockstep \
    --stats "$OUT/armsim1.txt" > "$OUT/armsim1.log" 2>&1 &
A1=$!
sleep 0.5
# 8.6 s of the 10 s task: past the closest approach (8.03 s), saves emulated time
"$MCAD" --no-dds --stop-after 8.6 --csv "$OUT/mcad.csv" "$CELL" 2> "$OUT/mcad.log"
rc=$?
kill -TERM $A0 $A1 2>/dev/null
wait $A0 $A1 2>/dev/null
cat "$OUT/mcad.log"
fail=0
[ $rc -eq 0 ] || { echo "E2E FAIL: mcad exit status $rc"; fail=1; }
grep -q "summary: state stopped" "$OUT/mcad.log" || { echo "E2E FAIL: not stopped"; fail=1; }
grep -q "summary: faults: none" "$OUT/mcad.log" || { echo "E2E FAIL: fault"; fail=1; }
d=$(sed -n 's/.*minimum distance \([0-9.]*\) m at t = \([0-9.]*\) s.*/\1/p' "$OUT/mcad.log")
t=$(sed -n 's/.*minimum distance \([0-9.]*\) m at t = \([0-9.]*\) s.*/\2/p' "$OUT/mcad.log")
# same task on the in-process sim backend: 0.0514 m at 8.03 s (mca-sim and mcad, docs/daemon.md); over CAN in
# the emulated guest feedback is sometimes a tick older (0.0517-0.0523 m at 8.05-8.10 s seen): up to 0.056 m, 8.3 s
awk -v d="${d:-0}" -v t="${t:-0}" 'BEGIN{exit !(d > 0.050 && d < 0.056 && t > 7.9 && t < 8.3)}' ||
    { echo "E2E FAIL: minimum distance ${d:-?} m at ${t:-?} s, expected (0.050, 0.056) m at 7.9-8.3 s"; fail=1; }
[ $fail -eq 0 ] && echo "E2E ok: cross circles over vcan0/vcan1: minimum distance $d m at $t s, stopped, no fault"

# ---- phase 2: the right arm's firmware freezes mid-task (SIGSTOP): lost feedback -> fault, both arms
# braked to zero, zero commands with the servo released; SIGTERM then ends mcad with exit status 3.
"$ARMSIM" --iface vcan0 --robot "$URDF" --id-base 0x100 --dec-limit 5 --acc-limit 10 --q0 "$Q0L" --lockstep \
    > "$OUT/armsim0b.log" 2>&1 &
A0=$!
"$ARMSIM" --iface vcan1 --robot "$URDF" --id-base 0x100 --dec-limit 5 --acc-limit 10 --q0 "$Q0R" --lockstep \
    > "$OUT/armsim1b.log" 2>&1 &
A1=$!
sleep 0.5
"$MCAD" --no-dds --stop-after 30 "$CELL" 2> "$OUT/mcad-fault.log" &
M=$!
# let it run: wait for 1000 ticks of task time (CSV-free: watch the log for "running", then time)
n=0
while ! grep -q "running" "$OUT/mcad-fault.log" && [ $n -lt 100 ]; do sleep 0.2; n=$((n + 1)); done
sleep 2
kill -STOP $A1
n=0
while ! grep -q "state fault" "$OUT/mcad-fault.log" && [ $n -lt 300 ]; do sleep 0.2; n=$((n + 1)); done
kill -TERM $M
wait $M
rc=$?
kill -CONT $A1
kill -TERM $A0 $A1 2>/dev/null
wait $A0 $A1 2>/dev/null
cat "$OUT/mcad-fault.log"
f2=0
[ $rc -eq 3 ] || { echo "E2E FAIL: phase 2: mcad exit status $rc, want 3 (fault)"; f2=1; }
grep -q "no feedback for 200 cycles" "$OUT/mcad-fault.log" || { echo "E2E FAIL: phase 2: no lost-feedback report"; f2=1; }
grep -q "braking both arms: lost feedback" "$OUT/mcad-fault.log" || { echo "E2E FAIL: phase 2: no braking"; f2=1; }
grep -q "all joints commanded to zero at .* state fault" "$OUT/mcad-fault.log" || { echo "E2E FAIL: phase 2: not braked"; f2=1; }
[ $f2 -eq 0 ] && echo "E2E ok: frozen firmware on vcan1: lost feedback fault, both arms braked, exit 3"
[ $f2 -eq 0 ] || fail=1
exit $fail
