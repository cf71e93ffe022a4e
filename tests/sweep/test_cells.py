#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""The sweep's random cells (tools/mca-sweep/cells.py, `mca_sweep.py --cells`).

1. cells.point_distance (what keeps the drawn obstacles off the tool-tip paths) against the library's own body
   distances (`mca-geom body`, core/src/body.c, with a capsule of length and radius 0): 2000 random points
   against random boxes turned about z and posts, outside and inside, within 1e-9 m.
2. One task with its cell, pnp-pa10:1 of seed 1: a table and 1-3 obstacles, every obstacle clear of both tool-tip
   paths by its clearance + PATH_ROOM, the start inside no clearance; MVN (no rows) comes below an obstacle's
   clearance, mca-ts keeps every clearance on every tick and completes the task; and the same scenario through
   `mca-sim --no-body-rows` comes below a clearance (so the rows, not the draw, keep it).
usage: test_cells.py TOOLS_DIR MCA_SIM MCA_GEOM WORK
"""
import json
import math
import os
import random
import subprocess
import sys

FAILS = []


def check(ok, what):
    print("%s: %s" % ("ok" if ok else "FAIL", what))
    if not ok:
        FAILS.append(what)


def geom_line(b, p):
    cap = "%r %r %r %r %r %r 0" % (p[0], p[1], p[2], p[0], p[1], p[2])
    c = b["centre"]
    if b["kind"] == "cylinder":
        return "cylinder %s %r %r %r 0 0 1 %r %r" % (cap, c[0], c[1], c[2], b["half_length"], b["radius"])
    y = b["rpy"][2]
    R = [math.cos(y), -math.sin(y), 0.0, math.sin(y), math.cos(y), 0.0, 0.0, 0.0, 1.0]
    h = b["half_extents"]
    return "box %s %r %r %r %r %r %r %s" % (cap, c[0], c[1], c[2], h[0], h[1], h[2], " ".join(repr(x) for x in R))


def main():
    tools, sim, geom, work = sys.argv[1:5]
    sys.path.insert(0, tools)
    import cells

    rng = random.Random(7)
    bodies, pts = [], []
    for _ in range(2000):
        b = cells.draw_obstacle(rng, [-0.5, -0.5], [0.5, 0.5])
        c = b["centre"]
        pts.append([c[k] + rng.uniform(-0.3, 0.3) for k in range(3)])
        bodies.append(b)
    p = subprocess.run([geom, "body"], input="\n".join(geom_line(b, q) for b, q in zip(bodies, pts)) + "\n",
                       capture_output=True, text=True, timeout=60)
    got = [float(line.split()[0]) for line in p.stdout.split("\n") if line.strip()]
    check(p.returncode == 0 and len(got) == len(pts), "mca-geom body answered %d of %d (exit %d %s)" % (
        len(got), len(pts), p.returncode, p.stderr[-200:]))
    if len(got) == len(pts):
        err = max(abs(cells.point_distance(b, q) - d) for b, q, d in zip(bodies, pts, got))
        inside = sum(1 for d in got if d < 0)
        check(err <= 1e-9, "cells.point_distance against core/src/body.c: max |difference| %.3g m over %d points "
              "(%d inside)" % (err, len(pts), inside))
        check(inside > 0, "some points inside a body (%d)" % inside)

    os.makedirs(work, exist_ok=True)
    out = os.path.join(work, "cells.json")
    cmd = [sys.executable, os.path.join(tools, "mca_sweep.py"), "--sim", sim, "--kind", "pnp-pa10", "--n", "2",
           "--seed", "1", "--only", "pnp-pa10:1", "--schemes", "mca-ts", "--no-stop", "--jobs", "1", "--cells",
           "--work", os.path.join(work, "tasks"), "--keep", "--json", out]
    print(" ".join(cmd))
    p = subprocess.run(cmd, capture_output=True, text=True, timeout=600)
    print(p.stdout[-3000:])
    if p.returncode != 0:
        print(p.stderr[-2000:])
        sys.exit("mca_sweep.py failed (exit %d)" % p.returncode)
    t = json.load(open(out))["tasks"][0]
    bs = t.get("bodies") or []
    check(bs and bs[0]["kind"] == "plane" and 1 <= len(bs) - 1 <= 3,
          "a table and 1-3 obstacles (%s)" % [b["kind"] for b in bs])
    scn = t["scenario"]
    import yaml
    import tips_pass
    sc = yaml.safe_load(open(scn))
    import csv
    row = next(csv.DictReader(open(os.path.join(os.path.dirname(scn), "probe.csv"))))
    for a, arm in enumerate(sc["arms"]):
        tip = [float(row["ee%d_%s" % (a, c)]) for c in "xyz"]
        path = tips_pass.sample(tips_pass.polyline(arm["path"], tip), 0.005)
        r = tips_pass.tip_radius(arm["urdf"], "tool_tip")
        for b in bs[1:]:
            gap = min(cells.point_distance(b, q) for q in path) - r
            check(gap >= b["clearance"] + cells.PATH_ROOM - 0.005,
                  "%s: %s's tool-tip path %.3f m from it (>= clearance + room)" % (b["name"], arm["name"], gap))
    check(t.get("mvn_body_ticks_below", 0) > 0, "MVN (no rows) comes below a clearance on %s ticks"
          % t.get("mvn_body_ticks_below"))
    r = t["runs"]["mca-ts"]["task"]
    check(r.get("body_ticks_below") == 0 and r.get("body_min_margin", -1) >= 0.0,
          "mca-ts keeps every clearance (ticks below %s, least margin %s m)" % (r.get("body_ticks_below"),
                                                                              r.get("body_min_margin")))
    check(r["cls"] in ("completed", "late"), "mca-ts completes it (%s %s)" % (r["cls"], r.get("reason")))
    sj = os.path.join(work, "norows.json")
    subprocess.run([sim, "--scenario", scn, "--scheme", "mca-ts", "--no-body-rows", "--summary", sj],
                   capture_output=True, text=True, timeout=600)
    nr = [x for x in json.load(open(sj))["runs"] if x["scheme"] == "mca-ts"][0]
    check(nr.get("body_ticks_below", 0) > 0, "without the body rows mca-ts comes below a clearance (%s ticks, "
          "margin %s m)" % (nr.get("body_ticks_below"), nr.get("body_min_margin")))
    if FAILS:
        print("%d check(s) failed" % len(FAILS))
        return 1
    print("all checks passed")
    return 0


if __name__ == "__main__":
    sys.exit(main())
