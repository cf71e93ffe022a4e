#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""tools/mca-sweep/coord_diagram.py and `mca-geom armgrid`, the constructive proof that a two-arm task can be
done on its paths.

  - connected() on hand-built diagrams: a way that only exists by backing off is found (monotone() says there is
    no forward-only one, and finds one without the second obstacle); a wall is a wall; a
    move between two safe samples is refused when the arm's travel between them could reach below d1;
  - armgrid's distances against `mca-geom armdist` (mca_arm_distances, the per-pair table) at sampled pairs of
    two recorded trajectories, and its travel bound against the link points `mca-geom fk` gives at every tick
    in between;
  - end to end on mca-sim: the JACO2 driven through the MICO2's resting tool tip (the MICO2 holds: no schedule
    can exist) has no witness; a third of the way there and back has one (mca-sim's least distance agrees).
usage: test_coord_diagram.py TOOLS_DIR MCA_SIM MCA_GEOM WORK_DIR
"""
import math
import os
import random
import shutil
import subprocess
import sys

import numpy as np

FAILS = []


def check(ok, what):
    print("%s: %s" % ("ok" if ok else "FAIL", what))
    if not ok:
        FAILS.append(what)


def fk_points(geom, urdf, base, q):
    out = subprocess.run([geom, "fk", "--robot", urdf] + ["%.17g" % x for x in q], capture_output=True, text=True,
                         check=True).stdout.split("\n")
    pts = [[float(x) for x in ln.split()[-3:]] for ln in out if ln.split()[:1] in (["root"], ["joint"], ["ee"])]
    return np.array(pts) + np.array(base)


def main():
    tools, sim, geom, work = sys.argv[1:5]
    sys.path.insert(0, tools)
    import coord_diagram as cd
    import mca_sweep

    shutil.rmtree(work, ignore_errors=True)
    os.makedirs(work)
    d1 = 0.05
    # 1. hand-built diagrams (travel 0 unless said)
    n = 7
    z = np.zeros(n)
    d = np.full((n, n), 1.0)
    d[0:5, 2] = 0.0  # b's first obstacle: passable only with a beyond sample 4
    d[2:7, 4] = 0.0  # b's second: only with a before sample 2 -> a must go forward, then back
    check(cd.connected(d, z, z, d1), "a diagram whose only way backs off is connected")
    check(not cd.monotone(d, z, z, d1), "... and has no schedule that never backs off")
    d2 = d.copy()
    d2[2:7, 4] = 1.0
    check(cd.monotone(d2, z, z, d1), "without b's second obstacle a schedule that never backs off exists")
    d[:, 3] = 0.0
    check(not cd.connected(d, z, z, d1), "a full wall across b's clock: not connected")
    d = np.full((3, 3), 0.06)
    check(cd.connected(d, z[:3], z[:3], d1), "samples 1 cm above d1, arms that do not move between them: connected")
    check(not cd.connected(d, np.full(3, 0.011), np.full(3, 0.011), d1),
          "the same samples with 11 mm of travel between them: not connected (a move could reach below d1)")
    check(cd.connected(d, np.full(3, 0.009), np.full(3, 0.009), d1), "... with 9 mm of travel: connected")

    # 2. armgrid against armdist and fk on two recorded random trajectories
    robots = os.path.join(os.path.dirname(os.path.dirname(tools)), "config", "robots")
    ja, mi = os.path.join(robots, "jaco2.urdf"), os.path.join(robots, "mico2.urdf")
    base_b = [0.6, 0.05, 0.0]
    rng = random.Random(7)
    qa0 = [4.8, 2.9, 1.0, 4.2, 1.4, 1.3]
    qb0 = [6.42, 2.9, 1.0, 4.2, 1.4, 1.3]
    wa = [rng.uniform(-0.6, 0.6) for _ in qa0]
    wb = [rng.uniform(-0.6, 0.6) for _ in qb0]
    ticks = 400
    qs = []
    for k in range(ticks):
        t = k * 0.001 * 5
        qs.append([q + w * math.sin(1.3 * t + i) for i, (q, w) in enumerate(zip(qa0, wa))] +
                  [q + w * math.sin(0.9 * t + 2 * i) for i, (q, w) in enumerate(zip(qb0, wb))])
    grid = os.path.join(work, "g.bin")
    p = subprocess.run([geom, "armgrid", "--every", "40", "--cap", "5", "--out", grid, "--robot-a", ja,
                        "--robot-b", mi, "--base-b", ",".join(str(x) for x in base_b + [0, 0, 0])],
                       input="".join(" ".join("%.17g" % x for x in q) + "\n" for q in qs), capture_output=True,
                       text=True)
    check(p.returncode == 0, "mca-geom armgrid runs (%s)" % p.stderr.strip())
    d, ta, tb = cd.read_grid(grid)
    check(d.shape == (10, 10), "400 ticks every 40: 10 x 10 samples (%s)" % (d.shape,))
    worst = 0.0
    for i, j in [(0, 0), (3, 7), (9, 9), (5, 2), (8, 1)]:
        out = subprocess.run([geom, "armdist", "--robot-a", ja, "--qa", ",".join("%.17g" % x for x in qs[40 * i][:6]),
                              "--robot-b", mi, "--base-b", ",".join(str(x) for x in base_b + [0, 0, 0]), "--qb",
                              ",".join("%.17g" % x for x in qs[40 * j][6:])], capture_output=True, text=True,
                             check=True).stdout.split("\n")
        # armdist's per-pair minimum over every pair but the two fixed bases (armgrid leaves that one out)
        dmin = min(float(ln.split()[3]) for ln in out if ln.startswith(("a_to_b", "b_to_a"))
                   and not (ln.split()[1] == "0" and ln.split()[2] == "0"))
        worst = max(worst, abs(dmin - d[i, j]))
    check(worst < 1e-6, "armgrid's distances = armdist's at 5 sampled pairs (largest difference %.2g m)" % worst)
    # travel: the largest move of any link point from sample 1 to any tick up to sample 2 is within travel[1]
    p1 = fk_points(geom, ja, [0, 0, 0], qs[40][:6])
    far = max(np.linalg.norm(fk_points(geom, ja, [0, 0, 0], qs[k][:6]) - p1, axis=1).max() for k in range(41, 81, 4))
    check(0 < far <= ta[1] + 1e-12, "arm a's travel bound from sample 1 to 2: %.5f m >= the points' largest move "
          "%.5f m" % (ta[1], far))
    check(ta[-1] == 0.0 and tb[-1] == 0.0, "no travel after the last sample")

    # 3. end to end: the JACO2 through the resting MICO2's tool tip, and 0.3 m aside
    arms = mca_sweep.draw_arms("jaco-mico", random.Random(3))
    sw = mca_sweep.Sim(sim)
    tips, d0, err = mca_sweep.probe(sw, work, "cd", "jaco-mico", arms)
    check(err is None, "probe of the arms' tool tips (%s)" % err)
    res = {}
    for name, share in (("through", 1.0), ("short", 0.3)):
        goal = [a + share * (b - a) for a, b in zip(tips[0], tips[1])]
        mid_pt = [0.5 * (a + b) for a, b in zip(tips[0], goal)]
        path = dict(kind="waypoints", relative=False, points=[mid_pt, goal, mid_pt, tips[0]], durations=[3, 3, 3, 3])
        scn = os.path.join(work, name + ".yaml")
        with open(scn, "w") as f:
            f.write(mca_sweep.scenario_yaml(name, "jaco-mico", arms, 12.5, [path, {"kind": "hold"}]))
        res[name] = cd.witness(sim, geom, scn, work)
        # the other arm holds: a schedule exists exactly when the moving arm alone keeps d1 (mca-sim's own least
        # distance of that MVN run, with the diagram's sampling margin)
        runs, errs = sw.run(scn, os.path.join(work, name + ".json"), ["mvn"])
        res[name]["mvn_min_distance"] = runs["mvn"]["min_distance"] if "mvn" in runs else errs
    check(res["through"].get("feasible") is False and res["through"]["mvn_min_distance"] < d1,
          "the JACO2 through the resting MICO2's tool tip: no witness (%s)" % res["through"])
    check(res["short"].get("feasible") is True and res["short"]["mvn_min_distance"] > 0.07 + 0.01,
          "a third of the way there and back: a witness (%s)" % res["short"])
    if FAILS:
        print("%d check(s) failed" % len(FAILS))
        return 1
    print("all checks passed")
    return 0


if __name__ == "__main__":
    sys.exit(main())
