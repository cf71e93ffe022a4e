#!/usr/bin/env python3
"""Search a schedule for Task 3 (cup stacking, JACO2 left at the origin, MICO2 right at x = 0.78 m).

Wanted: a real pick-and-place task in which both arms work in the shared target area at the same time, the
plain MVN scheme drives the minimum distance below d1 and the MCA scheme keeps it above d1 with collision
rows binding, without a fault, tracking within 1e-4 m.

Layout: two stacks in the target area between the arms, one per arm: the JACO2's at (x, ysj), the MICO2's
at (x + dxm, ysm), farther out in -y, so the MICO2's hand comes down over the JACO2's tool while both place;
each arm fetches two cups from its own side (grasp at z = 0.10 m) and builds its stack of two (place at
z = 0.10 and 0.10 + dz). Timing: the MICO2 waits w1 s holding its first cup and w2 s holding its second;
the JACO2's release dwell lasts 1 + hj s at its first place and 1 + hj2 s at its second.
What makes a schedule MCA can finish (see docs/scheme.md, task 3): a tool tip (prescribed) must not move
towards the other arm inside the band (each arm's rows limit only its own approach; the other arm does
not yield): the JACO2 waits at its stack (hj) until the MICO2 has left, and in the second round the MICO2
waits (w2) until the JACO2 has gone.

Usage (negative values as --ysj=-0.25):
  search_cups.py MCA_SIM [--x a:b:s|v,v] [--dxm ..] [--ysj ..] [--ysm ..] [--w1 ..] [--w2 ..] [--hj ..]
                 [--hj2 ..] [--dz D] [--jobs N] [--trapezoid]
      runs mvn,mca for every candidate (mca-sim --euler; --trapezoid: the sim backend, as the tests), one
      line each (MVN/MCA minimum, binding ticks, PDNN steps, fault), the best (largest of the smaller of
      the MVN violation and the MCA margin) last;
  search_cups.py --emit --x X --ysj Y --ysm Y --w1 W --w2 W --hj H [--out FILE]
      prints (or writes) the scenario YAML of one candidate. config/scenarios/cup_stacking.yaml is
      --x 0.36 --ysj=-0.25 --ysm=-0.45 --w1 3 --w2 11 --hj 6; its neighbourhood:
      search_cups.py build/tools/mca-sim/mca-sim --trapezoid --x 0.36 --ysj=-0.25 --ysm=-0.45 \
          --w1 2,3,4 --w2 9,10,11 --hj 6
"""
import argparse
import concurrent.futures
import json
import os
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
ROBOTS = os.path.normpath(os.path.join(HERE, "..", "..", "config", "robots"))

JACO_Q0 = "[4.7997, 2.9234, 1.0036, 4.1888, 1.4399, 1.3090]"
MICO_Q0 = "[6.4228, 2.9234, 1.0036, 4.1888, 1.4399, 1.3090]"
JACO_HOME = (0.214, -0.258, 0.511)
MICO_REST = (0.66, -0.40, 0.25)  # back above its first pick-up place, clear of the target area
Z_GRASP = 0.10  # grasp / first place height of the tool tip [m]
Z_UP = 0.25     # carry height above cups on the table


def frange(spec):
    """"a:b:step" (inclusive), "v1,v2,..." or one value."""
    if ":" not in spec:
        return [float(v) for v in spec.split(",")]
    a, b, s = (float(v) for v in spec.split(":"))
    out, v = [], a
    while v <= b + 1e-9:
        out.append(round(v, 6))
        v += s
    return out


def pick(cup, up=Z_UP):
    """above, down, grasp (dwell), up: 4 points, durations 3, 2, 1, 2."""
    x, y = cup
    return ([(x, y, up, "above cup"), (x, y, Z_GRASP, "cup"), (x, y, Z_GRASP, "grasp"), (x, y, up, "")],
            [3, 2, 1, 2])


def place(stack, z, what, above=0.15, release=1.0):
    x, y = stack
    return ([(x, y, z + above, "above the stack"), (x, y, z, what), (x, y, z, "release"),
             (x, y, z + above, "")], [3, 2, release, 2])


def schedule(p):
    """Both arms' waypoint lists [(x, y, z, comment)] and durations from the parameters."""
    sj, sm = (p["x"], p["ysj"]), (p["x"] + p["dxm"], p["ysm"])
    dz = p["dz"]
    jaco_pts, jaco_dur = [], []
    mico_pts, mico_dur = [], []

    def add(pts, dur, seg):
        pts.extend(seg[0])
        dur.extend(seg[1])

    # JACO2: cup 1 -> its stack, cup 2 -> on top, home
    add(jaco_pts, jaco_dur, pick(p["cj1"]))
    add(jaco_pts, jaco_dur, place(sj, Z_GRASP, "place cup 1 (JACO2 stack)", release=1 + p["hj"]))
    add(jaco_pts, jaco_dur, pick(p["cj2"]))
    add(jaco_pts, jaco_dur, place(sj, Z_GRASP + dz, "place cup 2 on cup 1", release=1 + p["hj2"]))
    jaco_pts.append(JACO_HOME + ("home",))
    jaco_dur.append(3)
    # MICO2: cup 3, wait w1, -> its stack, cup 4, wait w2, -> on top, home
    add(mico_pts, mico_dur, pick(p["cm1"]))
    if p["w1"] > 0:
        mico_pts.append(mico_pts[-1][:3] + ("wait",))
        mico_dur.append(p["w1"])
    add(mico_pts, mico_dur, place(sm, Z_GRASP, "place cup 3 (MICO2 stack)"))
    add(mico_pts, mico_dur, pick(p["cm2"]))
    if p["w2"] > 0:
        mico_pts.append(mico_pts[-1][:3] + ("wait",))
        mico_dur.append(p["w2"])
    add(mico_pts, mico_dur, place(sm, Z_GRASP + dz, "place cup 4 on cup 3"))
    mico_pts.append(p.get("mico_end", MICO_REST) + ("rest: back above cup 3's place, clear of the target area",))
    mico_dur.append(3)
    return (jaco_pts, jaco_dur), (mico_pts, mico_dur)


def fmt_points(pts, indent):
    out = []
    for x, y, z, c in pts:
        line = "%s- [%.3f, %.3f, %.3f]" % (indent, x, y, z)
        if c:
            line = "%-40s # %s" % (line, c)
        out.append(line.rstrip())
    return "\n".join(out)


def make_yaml(p, absolute=False):
    """The scenario text; URDF paths relative to config/scenarios/ (absolute: for files elsewhere)."""
    (jp, jd), (mp, md) = schedule(p)
    dur = max(sum(jd), sum(md)) + 1.0
    rdir = ROBOTS if absolute else "../robots"
    jaco_urdf, mico_urdf = rdir + "/jaco2.urdf", rdir + "/mico2.urdf"
    args = " ".join("--%s %s" % (k, p[k]) for k in ("x", "dxm", "ysj", "ysm", "w1", "w2", "hj", "hj2"))
    return """# Task 3 (paper Section VI-D): JACO2 (left, base at the origin) and MICO2 (right, base at x = 0.78 m) stack
# cups in the target area between them at the same time. Each arm fetches two cups from its own side and
# builds its own stack of two: the JACO2's stack at (%.3f, %.3f), the MICO2's at (%.3f, %.3f),
# farther out. First round: the MICO2 lowers its cup onto its stack while the JACO2 releases its cup on the nearer
# stack; the MICO2's hand (pointing back towards its base) comes down over the JACO2's tool tip: plain MVN
# goes below d1 (0.040 m at 16 s), MCA turns the MICO2's hand about its tool tip through the null space
# (3 redundant DOF for a 3-D position task) and keeps 0.071 m while both tool tips track. The JACO2 holds
# still at its stack until the MICO2 has gone (a tool tip moving towards the other arm inside the band could
# only be stopped, not steered). Second round: the MICO2 waits with its cup until the JACO2 has placed its
# second cup and left. The MICO2 ends above its first pick-up place (after the avoidance manoeuvre its
# home pose lies close to a wrist singularity).
# Waypoints with quintic rest-to-rest timing per segment; a dwell (same point twice) stands for
# grasp/release, "wait" for an arm holding until its turn.
# Generated by: tools/plots/search_cups.py --emit %s
# Start: Kinova's home position (deg [275, 167.5, 57.5, 240, 82.5, 75]); the MICO2 turned by joint 1 to
# face the JACO2 (q1 = 368 deg).
name: cup_stacking
duration: %.1f
dt: 0.001
d1: 0.07
d2: 0.12
K: 20
epsilon: 5
sample_times: %s
arms:
  - name: jaco2
    urdf: %s
    tip_link: tool_tip
    base_xyz: [0.0, 0.0, 0.0]
    q0: %s
    path:
      kind: waypoints
      relative: false
      points:
%s
      durations: [%s]
  - name: mico2
    urdf: %s
    tip_link: tool_tip
    base_xyz: [0.78, 0.0, 0.0]
    q0: %s
    path:
      kind: waypoints
      relative: false
      points:
%s
      durations: [%s]
""" % (p["x"], p["ysj"], p["x"] + p["dxm"], p["ysm"], args, dur,
       "[" + ", ".join("%g" % t for t in p.get("samples", [0, 10, 13, 14, 15, 16, 17, 18, 19, 20, 25, 30, 35, 40, 45, dur])) + "]",
       jaco_urdf, JACO_Q0, fmt_points(jp, "        "), ", ".join("%g" % d for d in jd),
       mico_urdf, MICO_Q0, fmt_points(mp, "        "), ", ".join("%g" % d for d in md))


def evaluate(sim, p, tmp, euler=True):
    tag = "_".join("%s%g" % (k, p[k]) for k in ("x", "dxm", "ysj", "ysm", "w1", "w2", "hj", "hj2"))
    path = os.path.join(tmp, tag + ".yaml")
    with open(path, "w") as f:
        f.write(make_yaml(p, absolute=True))
    summ = os.path.join(tmp, tag + ".json")
    cmd = [sim, "--scenario", path, "--scheme", "mvn,mca", "--summary", summ] + (["--euler"] if euler else [])
    r = subprocess.run(cmd, capture_output=True, text=True)
    if r.returncode != 0:
        return p, None, r.stderr.strip()
    s = json.load(open(summ))
    return p, s, ""


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("mca_sim", nargs="?")
    ap.add_argument("--emit", action="store_true")
    ap.add_argument("--out")
    ap.add_argument("--x", default="0.36:0.42:0.03")
    ap.add_argument("--dxm", default="0.0")
    ap.add_argument("--ysj", default="-0.30:-0.20:0.05")
    ap.add_argument("--ysm", default="-0.50:-0.40:0.05")
    ap.add_argument("--w1", default="0:4:1")
    ap.add_argument("--w2", default="0")
    ap.add_argument("--hj", default="0")
    ap.add_argument("--hj2", default="0")
    ap.add_argument("--dz", type=float, default=0.04)
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--trapezoid", action="store_true", help="sim backend instead of --euler")
    a = ap.parse_args()
    base = dict(cj1=(0.12, -0.45), cj2=(0.22, -0.55), cm1=(0.66, -0.40), cm2=(0.58, -0.52), dz=a.dz)
    grid = []
    for x in frange(a.x):
        for dxm in frange(a.dxm):
            for ysj in frange(a.ysj):
                for ysm in frange(a.ysm):
                    for w1 in frange(a.w1):
                        for w2 in frange(a.w2):
                            for hj in frange(a.hj):
                                for hj2 in frange(a.hj2):
                                    grid.append(dict(base, x=x, dxm=dxm, ysj=ysj, ysm=ysm, w1=w1, w2=w2, hj=hj,
                                                     hj2=hj2))
    if a.emit:
        if len(grid) != 1:
            sys.exit("--emit needs exactly one candidate (single values for --x --ysj --ysm --w1 --w2)")
        text = make_yaml(grid[0])
        if a.out:
            with open(a.out, "w") as f:
                f.write(text)
        else:
            sys.stdout.write(text)
        return 0
    if not a.mca_sim:
        sys.exit("usage: search_cups.py MCA_SIM [options]  (or --emit)")
    results = []
    with tempfile.TemporaryDirectory() as tmp, concurrent.futures.ThreadPoolExecutor(a.jobs) as ex:
        futs = [ex.submit(evaluate, a.mca_sim, p, tmp, not a.trapezoid) for p in grid]
        for fu in concurrent.futures.as_completed(futs):
            p, s, err = fu.result()
            key = "x %.2f dxm %.2f ysj %.2f ysm %.2f w1 %g w2 %g hj %g hj2 %g" % (
                p["x"], p["dxm"], p["ysj"], p["ysm"], p["w1"], p["w2"], p["hj"], p["hj2"])
            if s is None:
                print("   %s: error %s" % (key, err), flush=True)
                continue
            runs = {r["scheme"]: r for r in s["runs"]}
            mvn, mca = runs["mvn"], runs["mca"]
            d1 = s["d1"]
            ok = (mvn["min_distance"] < d1 and mca["min_distance"] > d1 and mca["fault"] == 0
                  and mca["binding_ticks"] > 0 and mca["max_err_free"] <= 1e-4)
            # score: the MVN violation depth and the MCA margin, the smaller of the two counts
            score = min(d1 - mvn["min_distance"], mca["min_distance"] - d1) if ok else -1
            results.append((score, key, mvn, mca))
            fault = mca["fault_name"] if mca["fault"] == 0 else "%s at %.2f s (d %.4f)" % (
                mca["fault_name"], mca["fault_t"], mca["fault_distance"])
            print("%s %s  mvn min %.4f at %5.2f s  mca min %.4f bind %5d pdnn max %4d capped %3d err %.1e/%.1e "
                  "fault %s" % ("OK " if ok else "   ", key, mvn["min_distance"], mvn["min_distance_t"],
                                mca["min_distance"], mca["binding_ticks"], mca["pdnn_steps_max"], mca["pdnn_capped"],
                                mca["max_err_free"], mca["max_err"], fault), flush=True)
    good = sorted([r for r in results if r[0] > 0], key=lambda r: r[0])
    print("\n%d of %d candidates meet the goal" % (len(good), len(results)))
    for score, key, mvn, mca in good[-5:]:
        print("best: %s  mvn min %.4f  mca min %.4f  (score %.4f)" % (key, mvn["min_distance"],
                                                                     mca["min_distance"], score))
    return 0


if __name__ == "__main__":
    sys.exit(main())
