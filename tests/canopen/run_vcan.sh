#!/bin/sh
# ctest entry of the CANopen vcan suite: natively when this kernel has vcan and we may create
# interfaces, otherwise in one QEMU guest boot (tools/vcan-guest). Never a silent pass: if neither works,
# exit 77 (ctest: skipped) and say why.
# Usage: run_vcan.sh BUILD_DIR SOURCE_DIR PYTHON
set -u
B=$(cd "$1" && pwd) S=$(cd "$2" && pwd) PY=$3
OUT=$B/tests/canopen/vcan-out
rm -rf "$OUT" && mkdir -p "$OUT"
"$PY" -c "import canopen" 2>/dev/null || { echo "run_vcan: FAIL: python-canopen missing in $PY (make deps)"; exit 1; }
if [ "$(id -u)" = 0 ] && ip link add dev mcacotest type vcan 2>/dev/null; then
    ip link del dev mcacotest
    echo "run_vcan: native vcan available: running the suite on this kernel"
    MCA_VCAN_IF=mcacovcan0 sh "$S/tests/canopen/suite.sh" run "$B" "$S" "$OUT"
    sh "$S/tests/canopen/suite.sh" check "$S" "$PY" "$OUT"
    rc=$?
    ip link del dev mcacovcan0 2>/dev/null
    exit $rc
fi
if ! command -v qemu-system-x86_64 >/dev/null 2>&1; then
    echo "run_vcan: SKIP: this kernel has no vcan and qemu-system-x86_64 is missing (apt-get install qemu-system-x86)"
    exit 77
fi
echo "run_vcan: this kernel has no vcan (or we may not create interfaces): booting the QEMU guest"
job=$B/tests/canopen/vcan-job.sh
cat >"$job" <<JOB
#!/bin/sh
export MCA_IN_GUEST=1 PATH=/usr/local/sbin:/usr/local/bin:/usr/sbin:/usr/bin:/sbin:/bin HOME=/root
exec sh "$S/tests/canopen/suite.sh" run "$B" "$S" "$OUT"
JOB
# One vCPU, as the CAN suite: controller and emulator starve together on a busy host.
MCA_GUEST_SMP=1 MCA_GUEST_LOG=$OUT/console.log sh "$S/tools/vcan-guest/run.sh" "$B/vcan-guest-cache" "$job" 900 >/dev/null
grc=$?
grep -a 'CANOPEN-SUITE\|MCA-GUEST' "$OUT/console.log" | tr -d '\r'
if [ $grc -ne 0 ]; then
    echo "run_vcan: FAIL: the guest run failed (exit $grc; console: $OUT/console.log)"
    exit 1
fi
sh "$S/tests/canopen/suite.sh" check "$S" "$PY" "$OUT"
