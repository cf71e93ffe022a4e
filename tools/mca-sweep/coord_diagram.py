#!/usr/bin/env python3
"""Is a two-arm task feasible on its paths? A constructive test: a schedule that keeps both tool tips on their
paths and both arms >= d1, found in a coordination diagram (O'Donnell and Lozano-Perez, 1989).

Each arm alone follows its path under plain MVN (its own QP, no avoidance): that records one joint trajectory
q_a(s) per arm, exact on its path (path error ~1e-5 m). Any schedule that moves each arm forwards or backwards
along its own recorded trajectory keeps its tip on the path; the pair's distance at (s_a, s_b) is then a fixed
number. The diagram samples it every N ticks (mca-geom armgrid: the same capsules and closed-form distance as the
controller) and joins neighbour samples where one arm moves while the other waits, if the move stays >= d1:
  d(i, j) >= d1 + eps at both ends, and max(d(i, j), d(i+1, j)) - travel_a(i) >= d1 + eps,
travel_a(i) bounding how far any point of arm a moves between its samples (so no state in between is closer).
eps covers the CSV's rounding of q. If (start, start) and (end, end) are connected, the task is feasible: the
connecting walk is a schedule (timing is free: an arm may wait or back off as slowly as its limits need).
Distances of at least d1 + 0.05 m are not refined (mca-geom armgrid --cap): they are free whatever the travel.

A witness proves feasibility; no witness proves nothing (the arms' redundancy could move elbows aside, and a
path tolerance allows more). tips_pass.py proves infeasibility for the tips alone; between the two a task is
undecided. usage: coord_diagram.py --sim MCA_SIM --geom MCA_GEOM WORKDIR... (a sweep task's folder, --keep)
"""
import argparse
import csv
import json
import os
import subprocess
import sys

import numpy as np
import yaml
from scipy import ndimage

EPS = 2e-4  # [m] q in the CSV has 6 significant digits: |dq| <= 5e-6 rad per joint, arms <= 1.3 m long


def read_grid(path):
    with open(path, "rb") as f:
        n = int(np.frombuffer(f.read(4), np.int32)[0])
        ta = np.frombuffer(f.read(8 * n), np.float64)
        tb = np.frombuffer(f.read(8 * n), np.float64)
        d = np.frombuffer(f.read(4 * n * n), np.float32).reshape(n, n).astype(np.float64)
    return d, ta, tb


def connected(d, ta, tb, d1):
    """Do the diagram's safe samples and moves join (0, 0) to (n-1, n-1)? Samples at even indices of a doubled
    grid, moves at the odd ones between them; one label pass (4-neighbours)."""
    n = d.shape[0]
    ok = d >= d1 + EPS
    g = np.zeros((2 * n - 1, 2 * n - 1), bool)
    g[::2, ::2] = ok
    # arm a moves (i -> i+1) while b waits at j
    ma = (np.maximum(d[:-1, :], d[1:, :]) - ta[:-1, None] >= d1 + EPS) & ok[:-1, :] & ok[1:, :]
    g[1::2, ::2] = ma
    mb = (np.maximum(d[:, :-1], d[:, 1:]) - tb[None, :-1] >= d1 + EPS) & ok[:, :-1] & ok[:, 1:]
    g[::2, 1::2] = mb
    if not (g[0, 0] and g[-1, -1]):
        return False
    lab, _ = ndimage.label(g)
    return bool(lab[0, 0] == lab[-1, -1])


def monotone(d, ta, tb, d1):
    """Is there a schedule that never backs off (each step moves one arm forwards, the other waits)? The same
    samples and moves as connected(), searched forwards only (mca-ts's start-up plan looks for such ones)."""
    n = d.shape[0]
    ok = d >= d1 + EPS
    ma = np.maximum(d[:-1, :], d[1:, :]) - ta[:-1, None] >= d1 + EPS
    mb = np.maximum(d[:, :-1], d[:, 1:]) - tb[None, :-1] >= d1 + EPS
    reach = np.zeros(n, bool)
    for i in range(n):
        row = (reach & ma[i - 1] & ok[i]) if i > 0 else np.zeros(n, bool)
        if i == 0:
            row[0] = ok[0, 0]
        for j in range(1, n):  # b moves forwards along the row
            row[j] = row[j] or (row[j - 1] and mb[i, j - 1] and ok[i, j])
        reach = row
    return bool(reach[-1])


def witness(sim, geom, scn_path, wd, every=20):
    """{'feasible': True/False, 'samples': n, 'start_d', 'min_d_alone'} for a two-arm scenario; None when it has
    another number of arms or a run failed (with 'error')."""
    scn = yaml.safe_load(open(scn_path))
    arms = scn["arms"]
    if len(arms) != 2:
        return dict(feasible=None, error="%d arms: the diagram is for two" % len(arms))
    d1 = float(scn["d1"])
    out_csv = os.path.join(wd, "witness_mvn.csv")
    summ = os.path.join(wd, "witness_mvn.json")
    p = subprocess.run([sim, "--scenario", scn_path, "--scheme", "mvn", "--summary", summ, "--csv", out_csv],
                       capture_output=True, text=True, timeout=900)
    if p.returncode != 0:
        return dict(feasible=None, error="mca-sim exit %d: %s" % (p.returncode, p.stderr.strip()[-300:]))
    qtext = []
    with open(out_csv, newline="") as f:
        rd = csv.DictReader(f)
        cols = [c for c in rd.fieldnames if c.startswith("q0_")] + [c for c in rd.fieldnames if c.startswith("q1_")]
        for row in rd:
            qtext.append(" ".join(row[c] for c in cols))
    grid = os.path.join(wd, "witness.grid")
    cmd = [geom, "armgrid", "--every", str(every), "--cap", str(d1 + 0.05), "--out", grid]
    for lab, arm in zip("ab", arms):
        base = list(arm.get("base_xyz", [0, 0, 0])) + list(arm.get("base_rpy", [0, 0, 0]))
        cmd += ["--robot-" + lab, arm["urdf"], "--base-" + lab, ",".join(str(x) for x in base)]
    p = subprocess.run(cmd, input="\n".join(qtext) + "\n", capture_output=True, text=True, timeout=1800)
    if p.returncode != 0:
        return dict(feasible=None, error="mca-geom armgrid exit %d: %s" % (p.returncode, p.stderr.strip()[-300:]))
    d, ta, tb = read_grid(grid)
    feasible = connected(d, ta, tb, d1)
    res = dict(feasible=feasible, monotone=monotone(d, ta, tb, d1) if feasible else False,
               samples=int(d.shape[0]), every=every, travel_max=round(float(max(ta.max(), tb.max())), 5))
    for f in (out_csv, grid):
        os.remove(f)
    return res


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--sim", required=True)
    ap.add_argument("--geom", required=True)
    ap.add_argument("--every", type=int, default=20, help="ticks per sample")
    ap.add_argument("workdirs", nargs="+")
    a = ap.parse_args()
    for wd in a.workdirs:
        print(wd, json.dumps(witness(a.sim, a.geom, os.path.join(wd, "scenario.yaml"), wd, a.every)))
    return 0


if __name__ == "__main__":
    sys.exit(main())
