#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Issue 16, "production holds no test hooks": SIGUSR1 (which many setups send for log rotation) must not
touch the production mcad's loop. Before, it stalled the loop for good (a test hook).

The production mcad runs the shipped sim cell config/cells/cross_circles_sim.yaml (--no-dds, --stop-after 3)
and gets SIGUSR1 six times, 0.3 s apart, while it runs. Checks:
  - each SIGUSR1 gives one status line ("<6>mcad: SIGUSR1: state running, ticks N, ...") and nothing else;
  - between two signals the loop ticked at its period: ticks advanced by at least half the periods that
    passed on the wall clock (a stalled loop advances by 0);
  - the task ends by itself at stop_after (no SIGTERM needed): exit 0, "state stopped", no fault, no stall;
  - the summary: ticks = 3000 + the braking ticks (3000..3600), skipped periods <= 10 % of the ticks (more
    only if cyclictest, beside mcad on every CPU at the loop's priority, lost at least half as long to late
    wake-ups: this VM freezes its vCPUs now and then, ~100 ms when busy; seen: 369 skipped periods under
    load), and the run's wall time matches its ticks + skipped periods (within 1 s);
  - every thread of mcad but the main one blocks SIGUSR1 (/proc/PID/task/*/status SigBlk): the main thread
    takes it with sigtimedwait, no thread (the loop least of all) ever runs a handler for it.
usage: test_sigusr1.py MCAD SOURCE_DIR [--no-rt]
"""
import os
import re
import signal
import subprocess
import sys
import threading
import time

MCAD, SRC = sys.argv[1], sys.argv[2]
EXTRA = sys.argv[3:]
CELL = os.path.join(SRC, "config", "cells", "cross_circles_sim.yaml")
STOP_AFTER = 3.0
N_SIG, GAP = 6, 0.3
PERIOD = 1e-3

PRIO = 80  # the cell's rt.priority

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "common"))
from cyclic_probe import CyclicProbe  # noqa: E402

failures = []


def check(cond, what):
    print(("ok   " if cond else "FAIL ") + what, flush=True)
    if not cond:
        failures.append(what)


lines = []  # (monotonic time, line)
probe = CyclicProbe(PRIO)
proc = subprocess.Popen([MCAD, "--no-dds", "--stop-after", str(STOP_AFTER)] + EXTRA + [CELL],
                        stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)


def reader():
    for ln in proc.stderr:
        lines.append((time.monotonic(), ln.rstrip("\n")))


th = threading.Thread(target=reader, daemon=True)
th.start()

deadline = time.monotonic() + 15
while time.monotonic() < deadline and proc.poll() is None and not any("mcad: ready" in ln for _, ln in lines):
    time.sleep(0.01)
t_ready = next((t for t, ln in lines if "mcad: ready" in ln), None)
check(t_ready is not None, "mcad ready")
sent = []
if t_ready is not None:
    # every other thread blocks SIGUSR1 (bit 10 of SigBlk): the main thread takes it with sigtimedwait (which
    # opens the waited-for signals in its SigBlk while it waits), no handler runs, the loop never sees it
    masks = {}
    for tid in os.listdir(f"/proc/{proc.pid}/task"):
        if int(tid) == proc.pid:
            continue
        try:
            with open(f"/proc/{proc.pid}/task/{tid}/status") as f:
                st = f.read()
            name = re.search(r"^Name:\s*(.*)$", st, re.M).group(1)
            masks[f"{name} ({tid})"] = int(re.search(r"^SigBlk:\s*([0-9a-f]+)$", st, re.M).group(1), 16)
        except (OSError, AttributeError):
            pass  # a thread that ended meanwhile
    open_to = [t for t, mk in masks.items() if not mk & (1 << (signal.SIGUSR1 - 1))]
    check(any(t.startswith("mcad-loop") for t in masks) and not open_to,
          f"every thread of mcad but the main one (sigtimedwait) blocks SIGUSR1: {', '.join(sorted(masks))}"
          + (f"; not: {', '.join(open_to)}" if open_to else ""))
    time.sleep(0.3)
    for i in range(N_SIG):
        if proc.poll() is not None:
            break
        sent.append(time.monotonic())
        proc.send_signal(signal.SIGUSR1)
        time.sleep(GAP)
try:
    rc = proc.wait(timeout=30)
except subprocess.TimeoutExpired:
    # the old mcad: stalled by the first SIGUSR1, it never reaches stop_after
    proc.send_signal(signal.SIGTERM)
    try:
        rc = proc.wait(timeout=10)
    except subprocess.TimeoutExpired:
        proc.kill()
        rc = proc.wait()
    check(False, f"mcad did not end by itself within 30 s (stalled?); after SIGTERM exit {rc}")
t_end = time.monotonic()
th.join(timeout=5)
check(probe.stop(), probe.describe())
log = "\n".join(ln for _, ln in lines)

check(len(sent) == N_SIG, f"{len(sent)} SIGUSR1 sent while mcad ran")
status = [(t, ln) for t, ln in lines if "SIGUSR1:" in ln]
pat = re.compile(r"<6>mcad: SIGUSR1: state running, ticks (\d+), overruns (\d+) \(skipped periods (\d+)\)")
parsed = [(t, *map(int, m.groups())) for t, ln in status for m in [pat.search(ln)] if m]
check(len(status) == len(sent) and len(parsed) == len(status),
      f"one status line per SIGUSR1 ({len(status)} lines, {len(parsed)} 'state running' ones, {len(sent)} sent)")
for (t0, k0, _, s0), (t1, k1, _, s1) in zip(parsed, parsed[1:]):
    periods = (t1 - t0) / PERIOD
    check(k1 - k0 >= 0.5 * periods,
          f"the loop ticked between two SIGUSR1: {k1 - k0} ticks (+ {s1 - s0} skipped periods) "
          f"in {t1 - t0:.3f} s ({periods:.0f} periods)")
# the old test hook's "debug stall" stopped the loop for good. Loop stalls (> 5 periods between two ticks'
# commands) are this VM's own vCPU stalls (1-15 ms a few times a minute), not SIGUSR1's: the tick counts
# between the signals above judge the loop; the summary's count is printed
stalls = re.search(r"summary: loop stalls \(.*\) (\d+), the longest ([0-9.]+) ms", log)
check(not re.search(r"debug stall", log, re.I) and stalls is not None,
      f"nothing stopped the loop (no 'debug stall'; the summary counts {stalls.group(1) if stalls else '?'} "
      f"loop stalls, the longest {stalls.group(2) if stalls else '?'} ms)")
check(rc == 0, f"exit status {rc} (want 0: stopped by itself at stop_after {STOP_AFTER} s)")
check("summary: state stopped" in log, "summary: state stopped")
check("summary: faults: none" in log, "summary: faults: none")
m = re.search(r"summary: state \w+, ticks (\d+), overruns (\d+) \(skipped periods (\d+)\)", log)
check(m is not None, "summary line with ticks and overruns")
if m and t_ready is not None:
    ticks, overruns, skipped = map(int, m.groups())
    want = int(STOP_AFTER / PERIOD)
    check(want <= ticks <= want + 600, f"ticks {ticks} (want {want} + the braking ticks, <= {want + 600})")
    lost_ms = probe.stalled_us() / 1e3
    if skipped > 0.1 * ticks and lost_ms >= 0.5 * skipped * PERIOD * 1e3:
        print(f"NOTE: {skipped} skipped periods (> 10 % of the ticks) are the machine's, not judged: cyclictest "
              f"lost {lost_ms:.0f} ms to late wake-ups on one CPU in the same run", flush=True)
    check(skipped <= 0.1 * ticks or lost_ms >= 0.5 * skipped * PERIOD * 1e3,
          f"overruns {overruns}, skipped periods {skipped} <= 10 % of the ticks (or the machine's: cyclictest "
          f"lost {lost_ms:.0f} ms)")
    wall = t_end - t_ready
    loop = (ticks + skipped) * PERIOD
    check(abs(wall - loop) < 1.0,
          f"wall time ready -> exit {wall:.3f} s ~ (ticks + skipped periods) x period = {loop:.3f} s")
if failures:
    print(log)
    print(f"{len(failures)} check(s) failed")
    sys.exit(1)
print("all checks passed")
