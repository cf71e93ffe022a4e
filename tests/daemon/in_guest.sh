#!/bin/sh
# Run one test command inside one QEMU guest boot (tools/vcan-guest: this kernel has no SocketCAN) and
# pass its output and exit status out. Never a silent skip: no guest, no pass.
# usage: in_guest.sh BUILD_DIR SOURCE_DIR NAME VCPUS COMMAND [ARG...]   (output kept in BUILD_DIR/tests/daemon/NAME)
set -u
B=$(cd "$1" && pwd) S=$(cd "$2" && pwd) NAME=$3 SMP=$4
shift 4
OUT=$B/tests/daemon/$NAME
rm -rf "$OUT" && mkdir -p "$OUT"
if ! command -v qemu-system-x86_64 >/dev/null 2>&1; then
    echo "$NAME: FAIL: this kernel has no vcan and qemu-system-x86_64 is missing (apt-get install qemu-system-x86)"
    exit 1
fi
job=$OUT/job.sh
{
    echo '#!/bin/sh'
    echo 'export MCA_IN_GUEST=1 PATH=/usr/local/sbin:/usr/local/bin:/usr/sbin:/usr/bin:/sbin:/bin HOME=/root'
    # CAN frames are delivered in softirq context; deferred to ksoftirqd (SCHED_OTHER) they wait behind the
    # FIFO programs: ksoftirqd above them, as tests/daemon/vcan_e2e.sh does
    echo 'for k in $(pgrep "^ksoftirqd/"); do chrt -f -p 95 "$k" >/dev/null 2>&1; done'
    printf '%s' 'exec'
    for a in "$@"; do printf ' %s' "'$a'"; done
    printf ' >"%s" 2>&1\n' "$OUT/result.txt"
} >"$job"
MCA_GUEST_SMP=$SMP MCA_GUEST_LOG=$OUT/console.log sh "$S/tools/vcan-guest/run.sh" "$B/vcan-guest-cache" "$job" 900 >/dev/null
rc=$?
cat "$OUT/result.txt" 2>/dev/null
if [ ! -s "$OUT/result.txt" ]; then
    echo "$NAME: FAIL: the guest run left no result (exit $rc; console: $OUT/console.log)"
    exit 1
fi
exit $rc
