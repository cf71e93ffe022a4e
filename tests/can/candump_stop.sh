# SPDX-License-Identifier: MIT
# Sourced by tests/can/suite.sh and tests/daemon/vcan_e2e.sh (POSIX sh).
# candump_stop FILE PID [MAX]: the candump PID writing FILE runs below the real-time programs and may lag
# far behind them: let it drain its socket (FILE stops growing once the bus is quiet; at most MAX half-second
# polls, default 60), then stop it.
candump_stop() {
    prev=-1 i=0
    while [ $i -lt "${3:-60}" ]; do
        sleep 0.5
        cur=$(stat -c %s "$1")
        [ "$cur" = "$prev" ] && break
        prev=$cur i=$((i + 1))
    done
    kill "$2" 2>/dev/null
    wait "$2" 2>/dev/null
}
