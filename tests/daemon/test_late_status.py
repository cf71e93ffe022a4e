#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""The transient-local ControllerStatus: a subscriber that joins late gets the current status at once.

mcad runs the negative task (task 4: ends in a braked, named fault at ~3.1 s of task time) on the sim
backend with publish_divisor 100, so the status goes out only on a state or fault change and every 10 s
(status every 100th published snapshot): after the RUNNING sample at tick 0 nothing is published until
the fault. Then:
  1. ~1 s after READY a new participant subscribes: its transient-local reader must get the RUNNING
     status of tick 0 within 1.5 s, stamped (mcad's CLOCK_MONOTONIC, the same clock as time.monotonic()
     here) before the reader existed: it came from the writer's history, not from a new publication.
     (A volatile reader is no control here: Cyclone hands the history also to a volatile reader that is
     matched before the writer's first heartbeat reaches it, as seen with the PyPI 11.x subscriber.)
  2. that transient-local reader sees BRAKING and FAULT live when the fault comes;
  3. ~0.5 s after the fault another new participant's transient-local reader gets the FAULT status with
     its code (MCA_ENOTCONV) and text at once;
  4. SIGTERM: exit status 3.
usage: test_late_status.py MCAD SOURCE_DIR DOMAIN [--no-rt]"""
import os
import queue
import signal
import subprocess
import sys
import tempfile
import threading
import time

MCAD, SRC, DOMAIN = sys.argv[1], sys.argv[2], int(sys.argv[3])
EXTRA = sys.argv[4:]
sys.path.insert(0, os.path.join(SRC, "tests", "dds"))
import mca_types as m  # noqa: E402

XML = os.path.join(SRC, "config", "dds", "loopback.xml")
os.environ["CYCLONEDDS_URI"] = "file://" + XML

from cyclonedds.domain import DomainParticipant  # noqa: E402
from cyclonedds.sub import DataReader  # noqa: E402
from cyclonedds.topic import Topic  # noqa: E402

MCA_ENOTCONV = -8
CELL = f"""name: late-status-test
task:
  scenario: {SRC}/config/scenarios/negative.yaml
scheme: mca
arms:
  - name: left
    backend: sim
  - name: right
    backend: sim
dds: {{enabled: true, domain: {DOMAIN}, config: {XML}, publish_divisor: 100}}
rt: {{period_us: 1000, priority: 60, overrun_limit: 100000, pdnn_budget_us: 1000000}}
stop_after: 0
"""

failures = []


def check(cond, what):
    print(("ok   " if cond else "FAIL ") + what, flush=True)
    if not cond:
        failures.append(what)


def subscribe(qos):
    dp = DomainParticipant(DOMAIN)
    return dp, DataReader(dp, Topic(dp, m.TOPIC_STATUS, m.ControllerStatus, qos=m.status_qos()), qos=qos)


def collect(reader, until, out):
    while time.monotonic() < until:
        out += [(time.monotonic(), s) for s in reader.take(N=16) if isinstance(s, m.ControllerStatus)]
        time.sleep(0.005)


with tempfile.TemporaryDirectory(prefix="mca-late-status-") as tmp:
    cell = os.path.join(tmp, "cell.yaml")
    with open(cell, "w") as f:
        f.write(CELL)
    proc = subprocess.Popen([MCAD] + EXTRA + [cell], stderr=subprocess.PIPE, text=True)
    lines = queue.Queue()
    err = []

    def pump():
        for ln in proc.stderr:
            err.append(ln)
            lines.put((time.monotonic(), ln))

    threading.Thread(target=pump, daemon=True).start()

    def wait_line(text, timeout):
        end = time.monotonic() + timeout
        while time.monotonic() < end:
            try:
                t, ln = lines.get(timeout=0.05)
            except queue.Empty:
                if proc.poll() is not None:
                    return None
                continue
            if text in ln:
                return t
        return None

    t_ready = wait_line("mcad: ready", 20)
    check(t_ready is not None, "mcad ready")
    if t_ready is None:
        proc.kill()
        print("".join(err))
        sys.exit(1)

    # 1. late subscriber, ~1 s into the run (the only status so far: RUNNING at tick 0)
    time.sleep(max(0.0, t_ready + 1.0 - time.monotonic()))
    t_join = time.monotonic()
    dp1, late = subscribe(m.status_qos())
    got = []
    end = t_join + 1.5
    while time.monotonic() < end and not got:
        collect(late, min(end, time.monotonic() + 0.01), got)
    collect(late, time.monotonic() + 0.2, got)
    dt = got[0][0] - t_join if got else None
    check(len(got) == 1 and got[0][1].state == m.ControllerState.STATE_RUNNING and got[0][1].tick == 0,
          f"late transient-local reader: {[(s.tick, s.state) for _, s in got]} "
          f"(want the RUNNING status of tick 0), {dt and round(dt * 1e3)} ms after joining")
    check(dt is not None and dt < 1.5, "it arrived within 1.5 s of joining")
    age = t_join - got[0][1].stamp_ns * 1e-9 if got else None
    check(age is not None and age > 0.5,
          f"it was published {age and round(age, 2)} s before the reader existed (history, not a new sample)")

    # 2. the fault, live on the late reader
    t_fault = wait_line("fault at t =", 20)
    check(t_fault is not None, "mcad faulted (negative task)")
    collect(late, time.monotonic() + 0.5, got)
    states = [s.state for _, s in got]
    check(m.ControllerState.STATE_BRAKING in states and states[-1] == m.ControllerState.STATE_FAULT,
          f"the late reader then saw the changes live: states {states}")

    # 3. another late subscriber, after the fault
    dp2, late2 = subscribe(m.status_qos())
    t_join2 = time.monotonic()
    got2 = []
    while time.monotonic() < t_join2 + 1.5 and not got2:
        collect(late2, time.monotonic() + 0.01, got2)
    s2 = got2[-1][1] if got2 else None
    age2 = t_join2 - s2.stamp_ns * 1e-9 if s2 else None
    check(age2 is not None and age2 > 0.2, f"... published {age2 and round(age2, 2)} s before that reader existed")
    check(s2 is not None and s2.state == m.ControllerState.STATE_FAULT and s2.fault_code == MCA_ENOTCONV
          and "PDNN residual" in s2.fault_text,
          f"reader joining after the fault: {s2 and (s2.tick, s2.state, s2.fault_code, s2.fault_text)}, "
          f"{got2 and round((got2[0][0] - t_join2) * 1e3)} ms after joining")

    # 4. SIGTERM in FAULT: exit 3
    proc.send_signal(signal.SIGTERM)
    try:
        rc = proc.wait(timeout=20)
    except subprocess.TimeoutExpired:
        proc.kill()
        rc = None
    check(rc == 3, f"mcad exit status {rc} after SIGTERM in FAULT (want 3)")
    if failures:
        time.sleep(0.2)
        print("".join(err))

if failures:
    print(f"{len(failures)} check(s) failed")
    sys.exit(1)
print("all checks passed")
