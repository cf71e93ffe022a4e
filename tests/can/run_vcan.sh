#!/bin/sh
# ctest entry of the vcan suite: natively when this kernel has vcan and we may create interfaces,
# otherwise in one QEMU guest boot (tools/vcan-guest). Never a silent skip: if neither works, FAIL and say why.
# Usage: run_vcan.sh BUILD_DIR SOURCE_DIR PYTHON
set -u
B=$(cd "$1" && pwd) S=$(cd "$2" && pwd) PY=$3
OUT=$B/tests/can/vcan-out
rm -rf "$OUT" && mkdir -p "$OUT"
if [ "$(id -u)" = 0 ] && ip link add dev mcavcantest type vcan 2>/dev/null; then
    ip link del dev mcavcantest
    echo "run_vcan: native vcan available: running the suite on this kernel"
    MCA_VCAN_IF=mcavcan0 sh "$S/tests/can/suite.sh" run "$B" "$S" "$OUT"
    sh "$S/tests/can/suite.sh" check "$S" "$PY" "$OUT"
    rc=$?
    ip link del dev mcavcan0 2>/dev/null
    exit $rc
fi
echo "run_vcan: this kernel has no vcan (or we may not create interfaces): booting the QEMU guest"
if ! command -v qemu-system-x86_64 >/dev/null 2>&1; then
    echo "run_vcan: FAIL: no vcan here and qemu-system-x86_64 is missing (apt-get install qemu-system-x86)"
    exit 1
fi
case "$B$S" in
    /tmp/*) echo "run_vcan: note: paths under /tmp work (the guest sees the host / over 9p)" ;;
esac
job=$B/tests/can/vcan-job.sh
cat >"$job" <<JOB
#!/bin/sh
export MCA_IN_GUEST=1 PATH=/usr/local/sbin:/usr/local/bin:/usr/sbin:/usr/bin:/sbin:/bin HOME=/root
exec sh "$S/tests/can/suite.sh" run "$B" "$S" "$OUT"
JOB
# One vCPU: controller and emulator then starve together when the host is busy, instead of one running
# cycles while the other is stalled (which a lost-feedback check rightly reports).
MCA_GUEST_SMP=1 MCA_GUEST_LOG=$OUT/console.log sh "$S/tools/vcan-guest/run.sh" "$B/vcan-guest-cache" "$job" 600 >/dev/null
grc=$?
grep -a 'CAN-SUITE\|MCA-GUEST' "$OUT/console.log" | tr -d '\r'
if [ $grc -ne 0 ]; then
    echo "run_vcan: FAIL: the guest run failed (exit $grc; console: $OUT/console.log)"
    exit 1
fi
sh "$S/tests/can/suite.sh" check "$S" "$PY" "$OUT"
