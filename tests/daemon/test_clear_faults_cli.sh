#!/bin/sh
# mcad --clear-faults: an arm that reports FAULT at start-up (the cell's test hook
# debug_start_in_fault: the sim firmware latches a fault in its first cycle, as one left from an earlier
# run) stops the start (exit 1, the arm and the fault named) unless --clear-faults is given; then the
# clearing is logged and the task runs (here 0.3 s, exit 0).
# usage: test_clear_faults_cli.sh MCAD_TEST SOURCE_DIR (the test build: the FAULT comes from a test hook)
MCAD=$1
SRC=$2
T=$(mktemp -d /tmp/mca-clear-faults-XXXXXX)
trap 'rm -rf "$T"' EXIT
sed -e "s#\.\./#$SRC/config/#g" -e 's/^stop_after:.*$/stop_after: 0.3/' "$SRC/config/cells/cross_circles_sim.yaml" > "$T/cell.yaml"
echo "debug_start_in_fault: true" >> "$T/cell.yaml"
f=0
"$MCAD" --no-dds --no-rt "$T/cell.yaml" > "$T/out1" 2> "$T/err1"
rc=$?
[ $rc -eq 1 ] || { echo "FAIL: without --clear-faults: exit $rc, want 1"; f=1; }
grep -q "start-up failed: arm 'left' reports FAULT INJECTED at start.*--clear-faults" "$T/err1" ||
    { echo "FAIL: without --clear-faults: no message naming the arm and the fault"; f=1; }
! grep -q "running\|ready" "$T/err1" || { echo "FAIL: without --clear-faults: something ran"; f=1; }
"$MCAD" --no-dds --no-rt --clear-faults "$T/cell.yaml" > "$T/out2" 2> "$T/err2"
rc=$?
[ $rc -eq 0 ] || { echo "FAIL: with --clear-faults: exit $rc, want 0"; f=1; }
grep -q "arm 'left' reports FAULT (INJECTED) at start: clearing it (--clear-faults: the operator asked)" "$T/err2" ||
    { echo "FAIL: with --clear-faults: the clearing is not logged"; f=1; }
grep -q "summary: state stopped" "$T/err2" || { echo "FAIL: with --clear-faults: did not run and stop"; f=1; }
cat "$T/err1"
[ $f -eq 0 ] && echo "ok: refused without --clear-faults (exit 1), cleared (logged) and ran with it (exit 0)"
exit $f
