#!/bin/sh
# SPDX-License-Identifier: MIT
# Runs inside the QEMU guest whose PID 1 is the host's own systemd (tests/daemon/systemd_guest.sh), as the
# oneshot unit mca-guest-test.service, with mca installed into the guest's overlay root (/usr/local, as
# `cmake --install` puts it): a shipped sim cell through the installed mcad@.service and through the README's
# systemd-run line (config/systemd/mcad-run.sh). One line per check, "ok   ..." or "FAIL ...".
# usage: systemd_guest_checks.sh SOURCE_DIR     (exit 0: every check passed)
S=$1
CELL=cross_circles_sim
U=mcad@$CELL.service
fail=0
ok() { echo "ok   $1"; }
bad() { echo "FAIL $1"; fail=1; }
prop() { systemctl show -P "$2" "$1" 2>/dev/null; }
# wait_for UNIT PROPERTY VALUE SECONDS: poll until the property has the value
wait_for() {
    n=0
    while [ "$(prop "$1" "$2")" != "$3" ]; do
        n=$((n + 1))
        [ $n -gt $(($4 * 5)) ] && return 1
        sleep 0.2
    done
}
# priorities UNIT SINCE: mcad's journal lines of the unit as "PRIORITY MESSAGE" (journald's PRIORITY field)
priorities() {
    journalctl -q --no-pager -o json -u "$1" --since "$2" _COMM=mcad | python3 -c '
import json, sys
for line in sys.stdin:
    e = json.loads(line)
    m = e.get("MESSAGE")
    if isinstance(m, list):  # journald gives non-UTF-8 messages as byte arrays
        m = bytes(m).decode("utf-8", "replace")
    print(e.get("PRIORITY"), m)'
}
# stop_exit UNIT SINCE: systemctl stop, then how its main process ended, from systemd's own line (logged at
# debug level when the exit is clean: raised for the stop; a stopped unit may be unloaded at once, so
# `systemctl show -p ExecMainStatus` cannot be relied on, and a transient unit is always gone)
stop_exit() {
    systemd-analyze log-level debug
    systemctl stop "$1"
    r=$?
    systemd-analyze log-level info
    journalctl -q --no-pager -u "$1" --since "$2" -o cat | sed -n 's/.*: Main process exited, //p' | tail -n 1
    return $r
}
echo "guest: $(systemctl --version | head -n 1); PID 1 is $(cat /proc/1/comm); system state $(systemctl is-system-running 2>/dev/null)"
echo "guest uptime at the start: $(cut -d' ' -f1 /proc/uptime) s (systemd's boot: boot.txt in the results)"
journalctl -b -q --no-pager -o short-monotonic >/mca-results/boot.txt 2>&1; dmesg >/mca-results/dmesg.txt
echo "installed unit: $(systemctl show -P FragmentPath $U): $(grep '^ExecStart=' /usr/local/lib/systemd/system/mcad@.service)"

# 1. the installed unit: start (Type=notify: returns once mcad sent READY=1), status, journal, stop
t0=$(date '+%Y-%m-%d %H:%M:%S')
if systemctl start $U; then ok "systemctl start $U returned (READY=1 reached)"; else bad "systemctl start $U"; fi
state="$(prop $U ActiveState)/$(prop $U SubState)"
if [ "$state" = active/running ]; then ok "$U: $state"; else bad "$U: $state, not active/running"; fi
sleep 2 # STATUS= every second
systemctl status --no-pager -l $U >/tmp/status.txt 2>&1
status=$(sed -n 's/^ *Status: //p' /tmp/status.txt)
if echo "$status" | grep -q 'running'; then ok "systemctl status $U shows mcad's STATUS=: $status"; else
    cat /tmp/status.txt
    bad "systemctl status $U: no STATUS= line with the state"
fi
main=$(stop_exit $U "$t0") && ok "systemctl stop $U returned" || bad "systemctl stop $U"
if [ "${main%% (success)}" = "code=exited, status=0/SUCCESS" ]; then ok "$U: main process exited, $main"; else
    bad "$U: main process: '$main', not exited 0"
fi
priorities $U "$t0" >/tmp/prio.txt
sed 's/^/  journal: /' /tmp/prio.txt | grep -v ' summary: \| loop stall at ' | head -n 12
if grep -q '^6 mcad: ready' /tmp/prio.txt && grep -q '^5 mcad: SIGTERM: braking to zero and stopping' /tmp/prio.txt &&
    grep -q '^6 mcad: summary: state stopped' /tmp/prio.txt; then
    ok "journald kept the priorities: ready at 6 (info), SIGTERM braking at 5 (notice), summary state stopped at 6"
else
    bad "journal: the ready (6), SIGTERM braking (5) and summary state stopped (6) lines at their priorities"
fi
if grep -q '^[0-9]* <[0-7]>' /tmp/prio.txt; then bad "journal: a <N> prefix left in a message"; else
    ok "journal: no <N> prefix left in any of mcad's $(wc -l </tmp/prio.txt) messages"
fi
grep -q '^[0-9]* mcad: summary: faults: none' /tmp/prio.txt && ok "summary: faults: none" || bad "summary: faults"

# 2. SIGSTOP: no WATCHDOG=1 any more, systemd's WatchdogSec (2 s) kills mcad; Restart=no: it stays down
systemctl reset-failed $U 2>/dev/null
t0=$(date '+%Y-%m-%d %H:%M:%S')
if systemctl start $U && [ "$(prop $U ActiveState)" = active ]; then ok "$U started again"; else bad "$U start again"; fi
pid=$(prop $U MainPID)
sleep 1
kill -STOP "$pid"
ts=$(date +%s.%N)
if wait_for $U ActiveState failed 30; then
    te=$(date +%s.%N)
    ok "SIGSTOP on mcad (pid $pid): unit failed after $(echo "$te $ts" | awk '{printf "%.1f", $1 - $2}') s"
else
    bad "SIGSTOP on mcad (pid $pid): unit not failed within 30 s ($(prop $U ActiveState)/$(prop $U SubState))"
fi
res="$(prop $U Result) $(prop $U ExecMainCode) $(prop $U ExecMainStatus)"
# ExecMainCode 2 = CLD_KILLED, 3 = CLD_DUMPED; status 6 = SIGABRT (WatchdogSignal), 9 = SIGKILL (after TimeoutAbortSec)
case "$res" in
"watchdog 2 6" | "watchdog 3 6" | "watchdog 2 9") ok "Result=watchdog, main process killed by signal $(prop $U ExecMainStatus) (ExecMainCode $(prop $U ExecMainCode))" ;;
*) bad "after SIGSTOP: Result ExecMainCode ExecMainStatus = $res, not watchdog and a kill" ;;
esac
journalctl -q --no-pager -u $U --since "$t0" | grep -i 'watchdog' | sed 's/^/  journal: /'
journalctl -q --no-pager -u $U --since "$t0" | grep -q 'Watchdog timeout' && ok "systemd logged the watchdog timeout" ||
    bad "no 'Watchdog timeout' in the journal"
if kill -0 "$pid" 2>/dev/null; then bad "mcad pid $pid still there"; else ok "mcad pid $pid gone"; fi
sleep 3
n=$(prop $U NRestarts)
if [ "$n" = 0 ] && [ "$(prop $U ActiveState)" = failed ] && ! pgrep -x mcad >/dev/null; then
    ok "Restart=$(prop $U Restart): not restarted (NRestarts=0, still failed 3 s later, no mcad running): nothing moves until an operator starts it"
else
    bad "after the watchdog kill: NRestarts=$n, $(prop $U ActiveState), mcad: $(pgrep -x mcad)"
fi
systemctl reset-failed $U 2>/dev/null

# 3. the README's systemd-run line (the installed copy of config/systemd/mcad-run.sh)
R=mcad-cross-circles-sim
t0=$(date '+%Y-%m-%d %H:%M:%S')
if sh /usr/local/share/mca/mcad-run.sh /usr/local/sbin/mcad /usr/local/etc/mca/cells/$CELL.yaml >/tmp/run.txt 2>&1; then
    ok "mcad-run.sh: $(cat /tmp/run.txt)"
else
    cat /tmp/run.txt
    bad "mcad-run.sh (systemd-run) failed"
fi
state="$(prop $R ActiveState)/$(prop $R SubState)"
if [ "$state" = active/running ]; then ok "$R (transient): $state after systemd-run returned"; else bad "$R: $state"; fi
sleep 2
status=$(systemctl status --no-pager -l $R 2>&1 | sed -n 's/^ *Status: //p')
if echo "$status" | grep -q 'running'; then ok "systemctl status $R shows STATUS=: $status"; else bad "systemctl status $R: no STATUS="; fi
main=$(stop_exit $R.service "$t0") && ok "systemctl stop $R returned" || bad "systemctl stop $R"
if [ "${main%% (success)}" = "code=exited, status=0/SUCCESS" ]; then ok "$R: main process exited, $main"; else
    bad "$R: main process: '$main', not exited 0"
fi
priorities $R.service "$t0" >/tmp/prio-run.txt
if grep -q '^5 mcad: SIGTERM: braking to zero and stopping' /tmp/prio-run.txt &&
    grep -q '^6 mcad: summary: state stopped' /tmp/prio-run.txt; then
    ok "$R: SIGTERM braking (5) and summary state stopped (6) in the journal"
else
    sed 's/^/  journal: /' /tmp/prio-run.txt
    bad "$R: SIGTERM braking and summary state stopped"
fi
journalctl -q --no-pager -u $R.service --since "$t0" -o cat | grep 'Start\|Stop\|exited\|Deactivated\|Failed' |
    sed 's/^/  journal: /'
echo "guest uptime at the end: $(cut -d' ' -f1 /proc/uptime) s"

[ $fail -eq 0 ] && echo PASSED || echo FAILED
exit $fail
