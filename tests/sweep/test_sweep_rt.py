#!/usr/bin/env python3
"""Smoke of `make sweep-rt` (tools/mca-sweep/sweep_rt.py): one jaco-mico task (seed 1, ~10 s of task) through
mcad at 1 kHz with cyclictest beside it, against mca-sim.

usage: test_sweep_rt.py SWEEP_RT_PY BUILD_DIR WORK_DIR
Checks only what a loaded machine cannot move: the run happened under SCHED_FIFO, mcad ran the task to its
end without fault, no tick below d1, cyclictest's wake-ups cover mcad's span, the table printed the checks.
The timing checks (ticks over 250 us, budget events) are reported by the tool, not asserted here.
Exit 77 (ctest SKIP) without root or cyclictest.
"""
import json
import os
import shutil
import subprocess
import sys

FAILS = []


def check(cond, msg):
    print(("ok   " if cond else "FAIL ") + msg)
    if not cond:
        FAILS.append(msg)


def main():
    tool, build, work = sys.argv[1:4]
    if os.geteuid() != 0 or not shutil.which("cyclictest"):
        print("skip: needs root (SCHED_FIFO) and cyclictest")
        return 77
    shutil.rmtree(work, ignore_errors=True)
    p = subprocess.run([sys.executable, tool, "--build", build, "--kind", "jaco-mico", "--n", "1", "--jobs", "1",
                        "--out", work], capture_output=True, text=True, timeout=240)
    print(p.stdout)
    check(p.returncode == 0, "sweep_rt.py exit 0 (got %d: %s)" % (p.returncode, p.stderr[-400:]))
    if p.returncode != 0:
        return 1
    d = json.load(open(os.path.join(work, "sweep-rt.json")))
    check(len(d["tasks"]) == 1, "one task")
    t = d["tasks"][0]
    rt = t.get("rt")
    check(rt is not None, "the task is reachable and ran through mcad")
    if rt:
        check(rt["sched_fifo"] == "yes", "mcad ran under SCHED_FIFO")
        check(rt["faults"] == 0, "mcad: faults none")
        check(rt["ticks"] >= int(t["duration"] * 1000) - 20, "mcad ran the task's duration (%d ticks)" % rt["ticks"])
        check(rt["min_d"] >= t["d1"], "rt: no tick below d1 (min_d %.4f, d1 %g)" % (rt["min_d"], t["d1"]))
        check(rt["cyc_covers"], "cyclictest's wake-ups cover mcad's span")
        check(rt["budget_clock"] is not None and rt["overruns"] is not None, "mcad's summary read")
    for s in ("check: 0 faults", "check: 0 below d1", "check: completion within 2 points",
              "check: 0 controller ticks over 250 us"):
        check(s in p.stdout, "table prints '%s'" % s)
    print("%d failed" % len(FAILS))
    return 1 if FAILS else 0


if __name__ == "__main__":
    sys.exit(main())
