#!/bin/bash
# SPDX-License-Identifier: MIT
# Real-time run of mcad on the sim backend: DURATION seconds at 1 kHz (SCHED_FIFO, mlockall, cpu_dma_latency),
# then the daemon's own summary (ticks, overruns, wake-up jitter p50/p99/p99.9/max, compute time).
# usage: rt_run.sh MCAD CELL DURATION [--strict]
#   Checks: exit 0, state stopped, ticks = DURATION * 1000 +- 1 %, every summary figure printed.
#   --strict also requires zero overruns (the figure reported in docs/daemon.md; a loaded machine can
#   miss a deadline, so the ctest smoke run does not demand it).
set -u
MCAD=$1 CELL=$2 DUR=$3 STRICT=${4:-}
log=$(mktemp)
trap 'rm -f "$log"' EXIT
"$MCAD" --no-dds --stop-after "$DUR" "$CELL" 2>"$log"
rc=$?
grep -E "summary|warn|<[34]>" "$log"
fail=0
[ $rc -eq 0 ] || { echo "FAIL: exit status $rc"; fail=1; }
grep -q "summary: state stopped" "$log" || { echo "FAIL: not stopped"; fail=1; }
ticks=$(sed -n 's/.*ticks \([0-9]*\), overruns.*/\1/p' "$log")
overruns=$(sed -n 's/.*overruns \([0-9]*\) .*/\1/p' "$log")
want=$(awk -v d="$DUR" 'BEGIN{printf "%d", d*1000}')
awk -v t="${ticks:-0}" -v w="$want" 'BEGIN{exit !(t >= w*0.99 && t <= w*1.01 + 2)}' ||
    { echo "FAIL: ticks ${ticks:-?}, expected about $want"; fail=1; }
grep -Eq "jitter p50 [0-9.]+ us, p99 [0-9.]+ us, p99.9 [0-9.]+ us, max [0-9.]+ us" "$log" ||
    { echo "FAIL: jitter figures missing"; fail=1; }
grep -Eq "compute time \(whole tick\) p50 [0-9.]+ us, p99 [0-9.]+ us, max [0-9.]+ us" "$log" ||
    { echo "FAIL: compute figures missing"; fail=1; }
if [ "$STRICT" = "--strict" ] && [ "${overruns:-1}" != 0 ]; then
    echo "FAIL: $overruns overruns"; fail=1
fi
echo "rt_run: ticks $ticks (want $want), overruns $overruns"
exit $fail
