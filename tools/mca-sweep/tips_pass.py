#!/usr/bin/env python3
"""Can the tool tips pass each other on their paths at all? An a-priori test of a drawn task (no controller).

Two arms that keep their tool tips on fixed paths can only choose how their path clocks advance: forwards,
waiting, backing off. The pair's tool tips at clocks (s_a, s_b) are fixed points whatever the arms' joints do
(redundancy moves elbows, never tips), and the tips are the ends of the last links' capsules (model: link dof
is the segment from the last joint to the tool tip, radius r). So where

    |p_a(s_a) - p_b(s_b)| + tol_a + tol_b - r_a - r_b < d1

every configuration of both arms is below d1 there: the cell is blocked for any controller that keeps its
tips within tol of their paths. If the free cells do not connect both starts to both ends (any path through
the diagram, not only monotone ones: backing off is allowed), no path rate, order or back-off completes the
task on its paths: it is infeasible as drawn, not a failure of the scheme.

The diagram is built on arclength (timing does not matter: a clock can wait anywhere), sampled every h; a cell
is blocked only if it is blocked at every point inside it (h added to the distance: each tip moves at most h/2
inside its cell), so the test is conservative: it calls a task infeasible only with a proof, and misses
the infeasible tasks where whole arms, not tips, meet. tol is the path's `tolerance` plus a slack of 5 mm
(the exact points' 1 mm, the tube's floor and the running path error mca-ts shows, <= 2.6 mm in the sweep).

usage: tips_pass.py WORKDIR [...]   (a sweep task's directory, kept with --keep: scenario.yaml and probe.csv)
"""
import csv
import math
import os
import sys
import xml.etree.ElementTree as ET

import numpy as np
import yaml
from scipy import ndimage

SLACK = 0.005  # [m] see above
STEP = 0.002   # [m] arclength between samples


def tip_radius(urdf, tip_link):
    """The capsule radius of the segment that ends at the tool tip, as model/src/urdf_shim.cpp builds it: the
    largest <collision> cylinder or sphere radius of the links after the last moving joint."""
    root = ET.parse(urdf).getroot()
    radius = {}
    for link in root.iter("link"):
        r = 0.0
        for geo in link.iter("geometry"):
            for kind in ("cylinder", "sphere"):
                e = geo.find(kind)
                if e is not None:
                    r = max(r, float(e.get("radius")))
        radius[link.get("name")] = r
    by_child = {j.find("child").get("link"): j for j in root.iter("joint")}
    chain, cur = [], tip_link
    while cur in by_child:
        chain.append(by_child[cur])
        cur = by_child[cur].find("parent").get("link")
    chain.reverse()
    last = max(i for i, j in enumerate(chain) if j.get("type") != "fixed")
    return max(radius[j.find("child").get("link")] for j in chain[last:])


def polyline(path, start):
    """The tip's path as a polyline from its start tip (mca/path.h geometry; timing left out)."""
    kind = path.get("kind", "hold")
    if kind == "waypoints":
        rel = path.get("relative", True)
        return [list(start)] + [[s + x for s, x in zip(start, q)] if rel else list(q) for q in path["points"]]
    if kind == "circle":
        R, u, v = float(path["radius"]), path["u"], path["v"]
        turns = float(path.get("turns", 1))
        c = [s - R * a for s, a in zip(start, u)]
        n = max(8, int(math.ceil(2 * math.pi * R * turns / (STEP / 2))))
        return [[c[i] + R * (math.cos(f) * u[i] + math.sin(f) * v[i]) for i in range(3)]
                for f in np.linspace(0.0, 2 * math.pi * turns, n + 1)]
    return [list(start)]


def sample(pts, h):
    out = [np.asarray(pts[0], float)]
    for a, b in zip(pts[:-1], pts[1:]):
        a, b = np.asarray(a, float), np.asarray(b, float)
        n = int(math.ceil(np.linalg.norm(b - a) / h))
        out += [a + (b - a) * k / n for k in range(1, n + 1)]
    return np.array(out)


def passes(free):
    """Do the free cells of a diagram connect (0, 0) to its far corner, by any way (8-neighbours: both clocks
    may move in one step; backwards too)?"""
    label, _ = ndimage.label(free, structure=np.ones((3, 3)))
    return bool(free[0, 0] and free[-1, -1] and label[0, 0] == label[-1, -1])


def blocked_pairs(arms, tips, d1, slack=SLACK, h=STEP):
    """[[a, b], ...]: the arm pairs whose tool tips cannot pass on their paths (see above). arms: the scenario's
    arm dicts (urdf, tip_link, path), tips: each arm's tool tip at the start."""
    P, R, T = [], [], []
    for arm, tip in zip(arms, tips):
        P.append(sample(polyline(arm["path"], tip), h))
        R.append(tip_radius(arm["urdf"], arm.get("tip_link", "tool_tip")))
        T.append(float(arm["path"].get("tolerance", 0.0) or 0.0) + slack)
    out = []
    for a in range(len(arms)):
        for b in range(a + 1, len(arms)):
            D = np.linalg.norm(P[a][:, None, :] - P[b][None, :, :], axis=2)
            if not passes(~(D + h + T[a] + T[b] - R[a] - R[b] < d1)):
                out.append([a, b])
    return out


def scenario_blocked(scn_path, tips):
    scn = yaml.safe_load(open(scn_path))
    return blocked_pairs(scn["arms"], tips, float(scn["d1"]))


def main():
    for wd in sys.argv[1:]:
        row = next(csv.DictReader(open(os.path.join(wd, "probe.csv"))))
        scn = yaml.safe_load(open(os.path.join(wd, "scenario.yaml")))
        tips = [[float(row["ee%d_%s" % (i, c)]) for c in "xyz"] for i in range(len(scn["arms"]))]
        print(wd, blocked_pairs(scn["arms"], tips, float(scn["d1"])))


if __name__ == "__main__":
    main()
