#!/bin/sh
# ctest entry of daemon_rt_syscalls_can: test_rt_syscalls.py --can (mcad on the CAN backend under strace,
# the loop thread's system calls against the allow-list of docs/daemon.md) in one QEMU guest boot
# (tools/vcan-guest: this kernel has no SocketCAN). Never a silent skip: no guest, no pass.
# Usage: rt_syscalls_can.sh BUILD_DIR SOURCE_DIR PYTHON
set -u
B=$(cd "$1" && pwd) S=$(cd "$2" && pwd) PY=$3
OUT=$B/tests/daemon/rt-syscalls-can
rm -rf "$OUT" && mkdir -p "$OUT"
if ! command -v qemu-system-x86_64 >/dev/null 2>&1; then
    echo "rt_syscalls_can: FAIL: this kernel has no vcan and qemu-system-x86_64 is missing (apt-get install qemu-system-x86)"
    exit 1
fi
job=$OUT/job.sh
cat >"$job" <<JOB
#!/bin/sh
export MCA_IN_GUEST=1 PATH=/usr/local/sbin:/usr/local/bin:/usr/sbin:/usr/bin:/sbin:/bin HOME=/root
"$PY" "$S/tests/daemon/test_rt_syscalls.py" "$B/daemon/mcad" "$S" 0 --can "$B/sim_backend/armsim_can/mca-armsim" \
    >"$OUT/result.txt" 2>&1
exit \$?
JOB
MCA_GUEST_SMP=1 MCA_GUEST_LOG=$OUT/console.log sh "$S/tools/vcan-guest/run.sh" "$B/vcan-guest-cache" "$job" 900 >/dev/null
rc=$?
cat "$OUT/result.txt" 2>/dev/null
if [ ! -s "$OUT/result.txt" ]; then
    echo "rt_syscalls_can: FAIL: the guest run left no result (exit $rc; console: $OUT/console.log)"
    exit 1
fi
exit $rc
