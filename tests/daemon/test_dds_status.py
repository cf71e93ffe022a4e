#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""mcad on DDS: a Python subscriber (PyPI cyclonedds, the IDL types of tests/dds/mca_types.py) watches a
2 s run of a sim cell (the left arm draws a circle, the right one holds) and checks that
  - the final ControllerStatus says STOPPED, no fault, and carries the SAME figures as mcad's summary on
    stderr (ticks, overruns, skipped periods, jitter p50/p99/p99.9/max, compute p50/p99/max, minimum
    distance so far); mcad is stopped (SIGSTOP) for 60 ms mid-run so that overruns and skipped periods
    are not 0 and differ (one late tick skips ~60 periods);
  - Distances samples arrive at the cell's rate (publish_divisor 10 -> ~100 Hz) with the cell's d1/d2,
    and their smallest min_distance is the summary's minimum (to the publish decimation);
  - JointCommand velocity setpoints of the last samples are zero (braked) and JointState has 8 joints.
usage: test_dds_status.py MCAD SOURCE_DIR [--no-rt]"""
import os
import re
import signal
import subprocess
import sys
import tempfile
import time

MCAD, SRC = sys.argv[1], sys.argv[2]
EXTRA = sys.argv[3:]
sys.path.insert(0, os.path.join(SRC, "tests", "dds"))
import mca_types as m  # noqa: E402

# 100..219 (the notify test publishes on 221..230; tests/dds readers use partitions of their own)
DOMAIN = 100 + os.getpid() % 120
os.environ["CYCLONEDDS_URI"] = "file://" + os.path.join(SRC, "config", "dds", "loopback.xml")

from cyclonedds.domain import DomainParticipant  # noqa: E402
from cyclonedds.sub import DataReader  # noqa: E402
from cyclonedds.topic import Topic  # noqa: E402

CELL = f"""name: dds-status-test
task: {{duration: 2.0}}
arms:
  - name: left
    backend: sim
    urdf: {SRC}/config/robots/pa10plus.urdf
    base_xyz: [0.0, -0.6, 0.0]
    q0: [0.0, 0.5, 0.0, 1.0, 0.0, 0.6, 0.0, 0.0]
    path: {{kind: circle, radius: 0.15, period: 2.0, u: [0, -1, 0], v: [0, 0, 1]}}
  - name: right
    backend: sim
    urdf: {SRC}/config/robots/pa10plus.urdf
    base_xyz: [0.0, 0.6, 0.0]
    q0: [0.0, 0.5, 0.0, 1.0, 0.0, 0.6, 0.0, 0.0]
d1: 0.04
d2: 0.13
dds: {{enabled: true, domain: {DOMAIN}, config: {SRC}/config/dds/loopback.xml, publish_divisor: 10}}
rt: {{period_us: 1000, priority: 60, overrun_limit: 100000, pdnn_budget_us: 1000000}}
stop_after: 2.0
"""

failures = []


def check(cond, what):
    print(("ok   " if cond else "FAIL ") + what, flush=True)
    if not cond:
        failures.append(what)


dp = DomainParticipant(DOMAIN)
rs = DataReader(dp, Topic(dp, m.TOPIC_STATUS, m.ControllerStatus, qos=m.status_qos()), qos=m.status_qos())
rd = DataReader(dp, Topic(dp, m.TOPIC_DISTANCES, m.Distances, qos=m.stream_qos()), qos=m.stream_qos())
rc_ = DataReader(dp, Topic(dp, m.TOPIC_JOINT_COMMAND, m.JointCommand, qos=m.stream_qos()), qos=m.stream_qos())
rj = DataReader(dp, Topic(dp, m.TOPIC_JOINT_STATE, m.JointState, qos=m.stream_qos()), qos=m.stream_qos())

with tempfile.TemporaryDirectory(prefix="mca-dds-status-") as tmp:
    cell = os.path.join(tmp, "cell.yaml")
    with open(cell, "w") as f:
        f.write(CELL)
    proc = subprocess.Popen([MCAD] + EXTRA + [cell], stderr=subprocess.PIPE, text=True)
    status, dist, cmd, js = [], [], [], []
    t_exit = None
    t_start, paused = time.monotonic(), False
    while True:
        if not paused and time.monotonic() - t_start > 1.5 and proc.poll() is None:
            # a 60 ms stall of the whole process: one overrun of ~60 skipped periods (overrun_limit is huge)
            os.kill(proc.pid, signal.SIGSTOP)
            time.sleep(0.06)
            os.kill(proc.pid, signal.SIGCONT)
            paused = True
        status += [s for s in rs.take(N=100) if isinstance(s, m.ControllerStatus)]
        dist += [s for s in rd.take(N=1000) if isinstance(s, m.Distances)]
        cmd += [s for s in rc_.take(N=1000) if isinstance(s, m.JointCommand)]
        js += [s for s in rj.take(N=1000) if isinstance(s, m.JointState)]
        if t_exit is None and proc.poll() is not None:
            t_exit = time.monotonic()
        if t_exit is not None and time.monotonic() - t_exit > 1.5:
            break
        time.sleep(0.005)
    err = proc.stderr.read()
    check(proc.returncode == 0, f"mcad exit status {proc.returncode}")

    def fig(pattern, cast=float):
        mm = re.search(pattern, err)
        return tuple(cast(x) for x in mm.groups()) if mm else None

    ticks, overruns, skipped = fig(r"ticks (\d+), overruns (\d+) \(skipped periods (\d+)\)", int) or (None,) * 3
    jit = fig(r"wake-up jitter p50 ([\d.]+) us, p99 ([\d.]+) us, p99.9 ([\d.]+) us, max ([\d.]+) us")
    comp = fig(r"compute time \(whole tick\) p50 ([\d.]+) us, p99 ([\d.]+) us, max ([\d.]+) us")
    dmin = fig(r"minimum distance ([\d.]+) m")
    budget = fig(r"PDNN out of its budget \(.*?\): (\d+) ticks by the clock, (\d+) by steps", int)
    check(None not in (ticks, jit, comp, dmin, budget), "summary figures on stderr")
    check(len(status) > 0, f"{len(status)} ControllerStatus samples")
    if status and None not in (ticks, jit, comp, dmin, budget):
        last = status[-1]
        print("final status:", last)
        check(last.state == m.ControllerState.STATE_STOPPED, f"final state {last.state} is STOPPED")
        check(last.fault_code == 0 and last.fault_text == "", "no fault in the final status")
        check(overruns is not None and 1 <= overruns < skipped and skipped >= 40,
              f"the 60 ms stop shows: {overruns} overrun(s), {skipped} skipped periods")
        check(last.ticks == ticks and last.overruns == overruns and last.skipped_periods == skipped,
              f"final status ticks/overruns/skipped periods {last.ticks}/{last.overruns}/{last.skipped_periods}"
              f" = summary {ticks}/{overruns}/{skipped}")
        check(last.pdnn_budget_hits == sum(budget),
              f"final status PDNN budget hits {last.pdnn_budget_hits} = summary {budget[0]} + {budget[1]}")
        for name, want, fields in (("jitter", jit, ("p50", "p99", "p999", "max")),
                                   ("compute", comp, ("p50", "p99", "max"))):
            got = [getattr(last, f"{name}_{f}_ns") for f in fields]
            same = all(abs(g / 1e3 - w) <= 0.051 for g, w in zip(got, want))
            check(same, f"final status {name} {'/'.join(fields)} {[g / 1e3 for g in got]} us = summary {list(want)}")
        check(abs(last.min_distance_so_far - dmin[0]) < 6e-5,
              f"final status min distance {last.min_distance_so_far:.5f} m = summary {dmin[0]} m")
    # Distances stream
    check(100 <= len(dist) <= 260, f"{len(dist)} Distances samples for ~2 s at 100 Hz")
    if dist:
        check(all(s.d1 == 0.04 and s.d2 == 0.13 for s in dist), "Distances carry the cell's d1 = 0.04, d2 = 0.13")
        ticks_seen = [s.tick for s in dist]
        check(all(b - a == 10 for a, b in zip(ticks_seen, ticks_seen[1:])) or len(set(ticks_seen)) > 0.95 * len(dist),
              "Distances every 10th tick")
        dm = min(s.min_distance for s in dist)
        check(dmin is not None and dm >= dmin[0] - 6e-5 and dm - dmin[0] < 0.01,
              f"smallest published distance {dm:.5f} m vs summary minimum {dmin and dmin[0]} m")
    if cmd:
        last_tick = max(s.tick for s in cmd)
        final = [s for s in cmd if s.tick == last_tick]
        check(all(all(v == 0.0 for v in s.velocity_setpoint) for s in final),
              f"last JointCommand samples (tick {last_tick}) command zero velocity")
    check(len(js) > 0 and all(len(s.position) == 8 for s in js), "JointState samples with 8 joints")
    if failures:
        print(err)

if failures:
    print(f"{len(failures)} check(s) failed")
    sys.exit(1)
print("all checks passed")
