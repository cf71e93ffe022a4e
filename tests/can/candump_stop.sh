# SPDX-License-Identifier: MIT
# Sourced by tests/can/suite.sh, tests/canopen/suite.sh and tests/daemon/vcan_e2e.sh (POSIX sh).
# candump_stop FILE PID MAX IFACE...: the candump PID writing FILE runs below the real-time programs and may
# lag far behind them; on a starved guest it can make no progress for seconds. So the end is marked, not
# guessed from a pause: a marker frame (id 0x7FF, no data; every capture's filter passes it, the checkers
# skip it) goes out on each IFACE, and a CAN socket delivers in order, so once FILE holds every marker it
# holds every frame sent before them. Waits at most MAX half-second polls, then stops candump; says so on
# stderr (and returns 1) when a marker is missing, and the checker then finds the capture incomplete.
CANDUMP_MARKER=7FF
candump_stop() {
    cs_file=$1 cs_pid=$2 cs_max=$3
    shift 3
    for cs_if in "$@"; do cansend "$cs_if" "$CANDUMP_MARKER#"; done
    cs_i=0 cs_n=0
    while [ $cs_i -lt "$cs_max" ]; do
        cs_n=$(grep -c " $CANDUMP_MARKER#\$" "$cs_file")
        [ "$cs_n" -ge $# ] && break
        sleep 0.5
        cs_i=$((cs_i + 1))
    done
    kill "$cs_pid" 2>/dev/null
    wait "$cs_pid" 2>/dev/null
    [ "$cs_n" -ge $# ] && return 0
    echo "candump_stop: $cs_n of $# end markers in $cs_file after $((cs_max / 2)) s: candump starved, capture cut" >&2
    return 1
}
