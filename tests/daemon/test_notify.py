#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Plays systemd's side of the sd_notify protocol against mcad (sd_notify(3), sd_watchdog_enabled(3)).

A unix datagram socket stands in for systemd: NOTIFY_SOCKET points at it and WATCHDOG_USEC asks for
keep-alives. Four runs of a short sim cell (two PA10+, hold task, DDS on the loopback config):
  1. READY=1 arrives, WATCHDOG=1 keep-alives arrive at about WATCHDOG_USEC/4 and never more than WatchdogSec apart, SIGTERM gives STOPPING=1,
     the summary, exit 0.
  2. debug_stall_after_ticks: the loop stalls after 400 ticks; the keep-alives must STOP (none later than
     one check interval after the stall), while the process still runs; SIGTERM ends it (exit 4).
  3. same with SIGUSR1 as the stall trigger.
  4. as 1 with SIGINT (Ctrl-C) instead of SIGTERM: STOPPING=1, braking, stopped, exit 0.
Runs 1 and 4 use the production mcad; 2 and 3 need the test hooks, so they run the test build mcad-test
(production holds no test hooks; daemon_sigusr1 shows that SIGUSR1 does not stall mcad).
usage: test_notify.py MCAD MCAD_TEST SOURCE_DIR [--no-rt]
"""
import os
import signal
import socket
import subprocess
import sys
import tempfile
import time

MCAD, MCAD_TEST, SRC = sys.argv[1], sys.argv[2], sys.argv[3]
EXTRA = sys.argv[4:]
WATCHDOG_USEC = 1000000  # 1 s: pings every 250 ms while healthy
INTERVAL = WATCHDOG_USEC * 1e-6 / 4

CELL = """name: notify-test
task: {{duration: 30.0}}
arms:
  - name: left
    backend: sim
    urdf: {src}/config/robots/pa10plus.urdf
    base_xyz: [0.0, -0.6, 0.0]
    q0: [0.0, 0.3, 0.0, 0.8, 0.0, 0.5, 0.0, 0.0]
  - name: right
    backend: sim
    urdf: {src}/config/robots/pa10plus.urdf
    base_xyz: [0.0, 0.6, 0.0]
    q0: [0.0, 0.3, 0.0, 0.8, 0.0, 0.5, 0.0, 0.0]
dds: {{enabled: true, domain: {domain}, config: {src}/config/dds/loopback.xml, publish_divisor: 10}}
rt: {{period_us: 1000, priority: 60, overrun_limit: 1000, pdnn_budget_us: 1000000}}
{extra}
"""

failures = []


def check(cond, what):
    print(("ok   " if cond else "FAIL ") + what, flush=True)
    if not cond:
        failures.append(what)


def check_rt_setup(pid):
    """What the loop claims, seen from /proc: a thread "mcad-loop" SCHED_FIFO at the cell's priority (60),
    the other threads SCHED_OTHER, memory locked, /dev/cpu_dma_latency held open."""
    threads = {}
    for tid in os.listdir(f"/proc/{pid}/task"):
        with open(f"/proc/{pid}/task/{tid}/comm") as f:
            comm = f.read().strip()
        with open(f"/proc/{pid}/task/{tid}/stat") as f:
            fields = f.read().rsplit(")", 1)[1].split()
        # after "pid (comm)": field 3 is fields[0]; rt_priority is field 40, policy field 41
        threads[tid] = (comm, int(fields[37]), int(fields[38]))
    loops = [t for t in threads.values() if t[0] == "mcad-loop"]
    check(len(loops) == 1 and loops[0][1:] == (60, 1),
          f"loop thread mcad-loop SCHED_FIFO priority 60 ({loops})")
    others = [t for t in threads.values() if t[0] != "mcad-loop"]
    check(others and all(t[2] == 0 for t in others), f"{len(others)} other threads SCHED_OTHER")
    with open(f"/proc/{pid}/status") as f:
        lck = next((int(ln.split()[1]) for ln in f if ln.startswith("VmLck:")), 0)
    check(lck > 4096, f"memory locked: VmLck {lck} kB")
    fds = [os.readlink(f"/proc/{pid}/fd/{fd}") for fd in os.listdir(f"/proc/{pid}/fd")]
    check("/dev/cpu_dma_latency" in fds, "/dev/cpu_dma_latency held open")


def run(tmp, name, extra_yaml, stall_by_signal, stop_sig=signal.SIGTERM):
    cell = os.path.join(tmp, name + ".yaml")
    with open(cell, "w") as f:
        f.write(CELL.format(src=SRC, extra=extra_yaml, domain=221 + os.getpid() % 10))  # not the DDS-status test's
    sock_path = os.path.join(tmp, name + ".sock")
    sock = socket.socket(socket.AF_UNIX, socket.SOCK_DGRAM)
    sock.bind(sock_path)
    sock.settimeout(0.05)
    env = dict(os.environ, NOTIFY_SOCKET=sock_path, WATCHDOG_USEC=str(WATCHDOG_USEC))
    env.pop("WATCHDOG_PID", None)
    t0 = time.monotonic()
    # the stall runs need the test hooks (debug_stall_after_ticks, SIGUSR1 stalls): the test build
    binary = MCAD_TEST if (extra_yaml or stall_by_signal) else MCAD
    proc = subprocess.Popen([binary] + EXTRA + [cell], env=env, stderr=subprocess.PIPE, text=True)
    msgs = []  # (time since start, field)

    def pump(until):
        while time.monotonic() < until:
            try:
                data = sock.recv(4096).decode()
            except socket.timeout:
                if proc.poll() is not None:
                    return
                continue
            for field in data.split("\n"):
                if field:
                    msgs.append((time.monotonic() - t0, field))

    def first(field):
        return next((t for t, m in msgs if m == field), None)

    # wait for READY=1 (arms answered, DDS up)
    deadline = time.monotonic() + 15
    while first("READY=1") is None and time.monotonic() < deadline and proc.poll() is None:
        pump(time.monotonic() + 0.1)
    t_ready = first("READY=1")
    check(t_ready is not None, f"{name}: READY=1 received ({t_ready and round(t_ready, 2)} s after start)")
    if t_ready is None:
        proc.kill()
        print(proc.stderr.read())
        return
    check(any(m.startswith("STATUS=") for _, m in msgs), f"{name}: STATUS= line before READY")
    if name == "healthy" and "--no-rt" not in EXTRA:
        check_rt_setup(proc.pid)
    t_stall = None
    if stall_by_signal:
        pump(time.monotonic() + 1.0)
        t_stall = time.monotonic() - t0
        proc.send_signal(signal.SIGUSR1)
        pump(time.monotonic() + 2.0)
    elif extra_yaml:
        pump(time.monotonic() + 3.0)
    else:
        pump(time.monotonic() + 2.0)
    pings = [t for t, m in msgs if m == "WATCHDOG=1"]
    if not extra_yaml and not stall_by_signal:
        gaps = [b - a for a, b in zip(pings, pings[1:])]
        check(len(pings) >= 6, f"{name}: {len(pings)} WATCHDOG=1 keep-alives in 2 s (>= 6)")
        check(gaps and max(gaps) < WATCHDOG_USEC * 1e-6,
              f"{name}: largest gap between keep-alives {max(gaps) if gaps else 0:.3f} s < WatchdogSec")
    else:
        t_now = time.monotonic() - t0
        if t_stall is None:
            # debug_stall_after_ticks: the loop stops after 400 ticks (0.4 s at 1 kHz, longer when ticks
            # overrun, e.g. under sanitizers): the pings must have stopped for the last second
            t_stall = t_now - 1.4 - INTERVAL
            before = [t for t in pings if t < t_ready + 0.4]
        else:
            before = [t for t in pings if t < t_stall]
        # one ping may still go out within a check interval of the stall (the ticks had advanced)
        late = [t for t in pings if t > t_stall + INTERVAL + 0.1]
        check(len(before) >= 1, f"{name}: keep-alives before the stall ({len(before)})")
        check(not late, f"{name}: no WATCHDOG=1 after the stall (last ping {pings[-1] if pings else 0:.3f} s, "
                        f"stall at {t_stall:.3f} s)")
        check(proc.poll() is None, f"{name}: mcad still running while stalled (systemd would kill it)")
    sig_name = "SIGINT" if stop_sig == signal.SIGINT else "SIGTERM"
    proc.send_signal(stop_sig)
    t_term = time.monotonic() - t0
    pump(time.monotonic() + 10)
    try:
        rc = proc.wait(timeout=10)
    except subprocess.TimeoutExpired:
        proc.kill()
        rc = None
    err = proc.stderr.read()
    t_stop = next((t for t, m in msgs if m == "STOPPING=1" and t >= t_term), None)
    check(t_stop is not None, f"{name}: STOPPING=1 after {sig_name}")
    check(f"<5>mcad: {sig_name}: braking to zero and stopping" in err, f"{name}: '{sig_name}: braking' logged")
    want = 0 if not (extra_yaml or stall_by_signal) else 4
    check(rc == want, f"{name}: exit status {rc} (want {want})")
    check("summary: wake-up jitter p50" in err and "summary: compute time" in err, f"{name}: summary printed")
    if want == 0:
        check("state stopped" in err, f"{name}: ended in state stopped")
    if rc != want:
        print(err)
    sock.close()


with tempfile.TemporaryDirectory(prefix="mca-notify-") as tmp:
    run(tmp, "healthy", "", False)
    run(tmp, "stall-config", "debug_stall_after_ticks: 400", False)
    run(tmp, "stall-signal", "", True)
    run(tmp, "sigint", "", False, signal.SIGINT)

if failures:
    print(f"{len(failures)} check(s) failed")
    sys.exit(1)
print("all checks passed")
