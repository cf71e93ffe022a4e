#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""A streamed sphere crossing random cells in virtual time (`mca_sweep.py --cells`, mca-sim's `simulated_sphere`).

1. The sweep on 4 + 4 seeded tasks (pa10, jaco-mico; seed 2), random cells (--cells --sphere) with every arm's
   self pairs, mca-ts,
   task and stop runs; tasks 1 and 3 of each kind get a sphere crossing between the arms at 0.3-2.0 m/s,
   sampled at 30 Hz, 30 ms latency, 1 % of samples lost, fed through the daemon's track input. Over every run:
   0 ticks with two arms below d1, 0 with a link inside a fixed body's clearance, 0 with a self pair below d1,
   and 0 (arm, tick) pairs with a moving arm inside the sphere's S_p; at least one sphere run has the sphere
   inside an arm's S_p (it walked into an arm at rest), so the figures cannot pass by the sphere missing the
   arms; no sphere run ends in the lost-stream fault (the samples did arrive); about 1 % of samples lost.
2. The control: one sphere task's scenario through `mca-sim --no-body-rows` (the bodies' rows, the track's
   among them, measured only): a moving arm inside S_p (the count sees what the rows prevent).
3. mcad refuses a task whose scenario declares `simulated_sphere` (FILE:LINE of the key), and mca-sim names
   a bad key by FILE:LINE: simulated_sphere.FIELD.
usage: test_sphere.py TOOLS_DIR MCA_SIM MCAD SOURCE_DIR WORK
"""
import json
import os
import re
import subprocess
import sys

FAILS = []


def check(ok, what):
    print("%s: %s" % ("ok" if ok else "FAIL", what))
    if not ok:
        FAILS.append(what)


def main():
    tools, sim, mcad, src, work = sys.argv[1:6]
    os.makedirs(work, exist_ok=True)
    out = os.path.join(work, "sphere.json")
    cmd = [sys.executable, os.path.join(tools, "mca_sweep.py"), "--sim", sim, "--kind", "pa10,jaco-mico", "--n", "4",
           "--seed", "2", "--schemes", "mca-ts", "--jobs", "2", "--cells", "--sphere", "--self-pairs",
           "--work", os.path.join(work, "tasks"), "--keep", "--json", out]
    print(" ".join(cmd))
    p = subprocess.run(cmd, capture_output=True, text=True, timeout=900)
    print(p.stdout[-4000:])
    if p.returncode != 0:
        print(p.stderr[-2000:])
        sys.exit("mca_sweep.py failed (exit %d)" % p.returncode)
    tasks = [t for t in json.load(open(out))["tasks"] if t.get("reachable")]
    runs = [(t, m, t["runs"]["mca-ts"][m]) for t in tasks for m in ("task", "stop") if m in t["runs"].get("mca-ts", {})]
    sph = [(t, m, r) for t, m, r in runs if t.get("sphere")]
    check(len(runs) >= 8, "%d mca-ts runs of %d reachable tasks (>= 8)" % (len(runs), len(tasks)))
    check(len(sph) >= 4, "%d of them with a sphere (>= 4)" % len(sph))
    check(all(t["sphere"]["radius"] > 0 and 0.3 <= t["sphere"]["speed"] <= 2.0 for t, _, _ in sph),
          "spheres at 0.3-2.0 m/s: %s" % sorted({t["sphere"]["speed"] for t, _, _ in sph}))
    for key, what in (("arm_ticks_below", "two arms below d1"), ("body_ticks_below", "a link inside a fixed body's "
                      "clearance"), ("self_ticks_below", "a self pair below d1")):
        n = sum(r.get(key) or 0 for _, _, r in runs)
        check(n == 0 and all(r.get(key) is not None for _, _, r in runs), "ticks with %s: %d" % (what, n))
    mv = [(t["id"], m, r.get("track_ticks_moving")) for t, m, r in sph if r.get("track_ticks_moving") != 0]
    check(not mv, "(arm, tick) pairs with a moving arm inside the sphere's S_p: none (%s)" % mv)
    within = [(t["id"], m, r["track_min_margin"], r["track_ticks_rest"]) for t, m, r in sph
              if r.get("track_min_margin", 1e9) < 0 and r.get("track_ticks_rest", 0) > 0]
    check(within, "the sphere inside an arm's S_p with the arm at rest in %d runs (%s)" % (len(within), within[:3]))
    lost = [(t["id"], m) for t, m, r in sph if "lost" in (r.get("fault") or "") or r.get("sphere_sent", 0) < 30]
    check(not lost, "every sphere run got its samples (no lost stream): %s" % lost)
    sent = sum(r.get("sphere_sent", 0) for _, _, r in sph)
    nlost = sum(r.get("sphere_lost", 0) for _, _, r in sph)
    check(sent > 0 and 0.002 <= nlost / (sent + nlost) <= 0.03, "samples lost %d of %d" % (nlost, sent + nlost))

    # the control: the same sphere task with the bodies' rows (the track's too) measured only
    t = sph[0][0] if sph else None
    if t:
        sj = os.path.join(work, "norows.json")
        subprocess.run([sim, "--scenario", t["scenario"], "--scheme", "mca-ts", "--no-body-rows", "--summary", sj],
                       capture_output=True, text=True, timeout=600)
        nr = [x for x in json.load(open(sj))["runs"] if x["scheme"] == "mca-ts"][0]
        check(nr.get("track_ticks_moving", 0) > 0, "%s without the bodies' rows: %s (arm, tick) pairs moving inside "
              "S_p" % (t["id"], nr.get("track_ticks_moving")))

    # mcad refuses a simulated sphere; mca-sim names a bad key
    scn = os.path.join(work, "sphere_scn.yaml")
    text = open(os.path.join(src, "config", "scenarios", "cross_circles.yaml")).read().replace(
        "../robots/", os.path.join(src, "config", "robots") + "/")
    text += ("simulated_sphere:\n  radius: 0.2\n  start: [-3, 0.6, 0.8]\n  end: [3, 0.6, 0.8]\n  speed: 1.0\n"
             "  loss: 0.7\n")
    open(scn, "w").write(text)
    line = text.split("\n").index("simulated_sphere:") + 1
    p = subprocess.run([sim, "--scenario", scn, "--scheme", "mca-ts"], capture_output=True, text=True, timeout=60)
    check(p.returncode != 0 and "%s:%d: simulated_sphere.loss: must be in [0, 0.5]" % (scn, line + 5) in p.stderr,
          "mca-sim: bad loss named at its line (%s)" % p.stderr.strip()[-160:])
    open(scn, "w").write(text.replace("  loss: 0.7\n", "  loss: 0.01\n"))
    cell = os.path.join(work, "sphere_cell.yaml")
    ctext = open(os.path.join(src, "config", "cells", "cross_circles_sim.yaml")).read()
    ctext = re.sub(r"scenario: \S+", "scenario: " + scn, ctext).replace("../dds/", os.path.join(src, "config", "dds") + "/")
    open(cell, "w").write(ctext)
    p = subprocess.run([mcad, "--check", cell], capture_output=True, text=True, timeout=60)
    check(p.returncode == 2 and "%s:%d: simulated_sphere: a simulated streamed body is for mca-sim only" % (scn, line)
          in p.stderr, "mcad refuses the simulated sphere (exit %d: %s)" % (p.returncode, p.stderr.strip()[-200:]))
    if FAILS:
        print("%d check(s) failed" % len(FAILS))
        return 1
    print("all checks passed")
    return 0


if __name__ == "__main__":
    sys.exit(main())
