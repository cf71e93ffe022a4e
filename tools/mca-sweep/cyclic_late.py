# SPDX-License-Identifier: MIT
"""The one correlator of mcad's late ticks with cyclictest (sweep_rt.py, tests/dds/test_bridge_crash.py).

This VM's host stalls its vCPUs (1-15 ms a few times a minute, ~100 ms when both are busy): a tick of mcad that
is late or long then says nothing about mcad. cyclictest runs beside mcad on the loop's CPU at the loop's
priority, 1 ms interval, aligned a quarter period before mcad's grid (mcad wakes at whole ms + 500 us of
CLOCK_MONOTONIC, cyclictest --secaligned=250 at whole seconds + 250 us: both clear of each other), and -v
gives every wake-up's latency. A tick of mcad is explained (the machine's, not mcad's) when a cyclictest
wake-up due within CYC_WINDOW_NS of the tick's wake-up was at least CYC_LATE_US late.

    cyc, launch_ns, f = launch(n_ms, cpu, prio, path)   # then start mcad (after ~1.2 s: past its first wake-up)
    ...
    stop(cyc, f)
    wk = wakeups(path, launch_ns)                       # [(due ns, latency us)]
    late = late_dues(wk)
    explained(wake_ns, late)                            # for each tick to judge (span_ns: a gap before it)
"""
import re
import signal
import subprocess
import time

CYC_LATE_US = 100  # a tick is explained by a cyclictest wake-up this late ...
CYC_WINDOW_NS = 2000000  # ... due within this of the tick's wake-up


def launch(n_ms, cpu, prio, path):
    """cyclictest launched between whole seconds (its first wake-up due at the next whole second + 250 us of
    CLOCK_MONOTONIC), writing -v to path; returns (process, launch ns, the file to close)."""
    time.sleep((1.1 - time.clock_gettime(time.CLOCK_MONOTONIC) % 1) % 1)
    launch_ns = time.clock_gettime_ns(time.CLOCK_MONOTONIC)
    f = open(path, "w")
    p = subprocess.Popen(["cyclictest", "-m", "-p", str(prio), "-a", str(cpu), "-i", "1000", "-d", "0",
                          "--secaligned=250", "-l", str(n_ms), "-q", "-v"], stdout=f, stderr=subprocess.STDOUT)
    return p, launch_ns, f


def stop(p, f):
    """End cyclictest (SIGINT), close its file; its exit status."""
    if p.poll() is None:
        p.send_signal(signal.SIGINT)
    try:
        p.wait(timeout=10)
    except subprocess.TimeoutExpired:
        p.kill()
        p.wait()
    f.close()
    return p.returncode


def wakeups(path, launch_ns):
    """[(due ns, latency us)] of cyclictest -v. Its thread starts at t0 (the aligned second + 250 us) and is first
    due one interval later; each wake-up is due one interval after the last, except after a wake-up later than
    that: then cyclictest skips the periods already past (its "while (now > next) next += interval") and logs
    nothing for them. So the dues are rebuilt in order from the latencies, not taken as t0 + i * interval: that
    placed every wake-up after a cyclictest overrun one interval too early per skipped period (seen in a sched
    trace of the loop's CPU: a 1.1 ms stall both saw, which the index put 3 ms away). The interval is the
    "Thread 0 Interval:" line; cyclictest 2.40 prints thread 0's interval plus -d's distance, default 500 us,
    under -v though it runs at the given one: -d 0 is passed so that the printed interval is the real one."""
    t0 = (launch_ns // 10**9 + 1) * 10**9 + 250000
    out, step, due = [], 10**6, None
    with open(path, errors="replace") as f:
        for line in f:
            m = re.match(r"^Thread 0 Interval:\s*(\d+)", line)
            if m:
                step = int(m.group(1)) * 1000
            m = re.match(r"^\s*0:\s*(\d+):\s*(\d+)\s*$", line)
            if m:
                due = t0 + step if due is None else due
                lat = int(m.group(2))
                out.append((due, lat))
                now = due + lat * 1000
                due += step
                while now > due:
                    due += step
    return out


def late_dues(wk, late_us=CYC_LATE_US):
    """The wake-ups at least late_us late, as (due ns, latency ns): cyclictest was held up over [due, due + latency]."""
    return [(d, us * 1000) for d, us in wk if us >= late_us]


def explained(wake_ns, late, window_ns=CYC_WINDOW_NS, span_ns=0):
    """A tick woken at wake_ns (CLOCK_MONOTONIC) after span_ns without one (an overrun's gap; 0: the tick alone) is
    the machine's: cyclictest was held up (a late wake-up's [due, due + latency]) within window_ns of
    [wake_ns - span_ns, wake_ns]. The span matters for stalls longer than the window: cyclictest logs one late
    wake-up at a stall's start and none for the periods it skips, so the tick at the stall's end is far from it."""
    return any(d - window_ns <= wake_ns and d + lat + window_ns >= wake_ns - span_ns for d, lat in late)


def covers(wk, t0_ns, t1_ns):
    """cyclictest's wake-ups span [t0_ns, t1_ns]."""
    return bool(wk) and wk[0][0] <= t0_ns and wk[-1][0] >= t1_ns
