# SPDX-License-Identifier: MIT
"""The scheme scripts' shared pieces (test_bodies.py, test_self.py): check() with its one list of failures,
and one mca-sim run read back from its summary."""
import json
import os
import subprocess

FAILS = []


def check(cond, msg):
    print(("ok   " if cond else "FAIL ") + msg)
    if not cond:
        FAILS.append(msg)


def sim_run(sim, scn, work, scheme, tag, extra=(), with_csv=False):
    """mca-sim on scenario scn under scheme: the summary's first run with the scenario's d1 added (and with
    with_csv the path of its per-tick CSV as r["csv"]); None, counted as a failure, when mca-sim fails."""
    os.makedirs(work, exist_ok=True)
    summ = os.path.join(work, "%s.json" % tag)
    cmd = [sim, "--scenario", scn, "--scheme", scheme, "--summary", summ]
    out_csv = os.path.join(work, "%s.csv" % tag)
    if with_csv:
        cmd += ["--csv", out_csv]
    cmd += list(extra)
    p = subprocess.run(cmd, capture_output=True, text=True, timeout=300)
    if p.returncode != 0:
        print(p.stdout, p.stderr)
        FAILS.append("mca-sim failed: %s" % " ".join(cmd))
        return None
    s = json.load(open(summ))  # plain JSON: one arm has no arm pair, its distance is null
    r = s["runs"][0]
    r["d1"] = s["d1"]
    if with_csv:
        r["csv"] = out_csv
    return r
