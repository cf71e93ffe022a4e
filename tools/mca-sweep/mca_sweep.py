#!/usr/bin/env python3
"""Seeded random-task sweep through mca-sim ("yield instead of fault"; pick and place; docs/sweep.md).

usage: mca_sweep.py --sim MCA_SIM [--kind pa10|jaco-mico|three|pnp-jaco-mico|pnp-pa10[,...]] [--n N] [--seed S]
                    [--only ID[,ID...]] [--schemes mvn,mca,mca-ts] [--jobs 2] [--work DIR] [--json OUT]
                    [--table OUT] [--lost-threshold 0.1] [--no-stop] [--dec-limit X] [--max-err 0.005]
                    [--tolerance X] [--cells [--sphere]] [--self-pairs] [--keep]

For each kind (pa10: two PA10+ as in cross_circles.yaml; jaco-mico: JACO2 + MICO2 as in cup_stacking.yaml;
three: JACO2, MICO2, JACO2 as in three_arms.yaml; pnp-jaco-mico, pnp-pa10: pick and place at cup_stacking's and
cross_circles' placements) N tasks are drawn, task i of kind K from the random generator seeded with "S:K:i"
alone, so `--seed S --kind K --only K:i` repeats one task whatever N is (and whatever this mca-sim takes: the
draws never depend on it, only which keys are written).
A crossing task: base placements and initial configurations jittered around the shipped scenario's; a first
short mca-sim run (hold paths, 2 ticks) gives the tool tips and the start distance (redrawn while < d2); then
every arm gets a tool-tip path (a circle through its start, or relative waypoints out and back) whose far
point lies towards another arm's tool tip (closer to it than the start).
A pick-and-place task (PNP): the shipped placement, q0 jittered by 0.1 rad (redrawn while < d2 apart); each
arm does 2-3 rounds from its own pick area (on its side of the cell) to its slot in the place zone between
the bases (the two slots >= 0.10 m apart): above the pick point, down, grasp dwell, up, [wait], over the place
point, down, release dwell, up; at the end back above its last pick point. Absolute waypoints; each arm's
timetable drawn on its own (moves no faster than the kind's vmax, 25-45 s, a start delay t0); the grasp and
release dwells' points are the path's exact points (`exact: [...]`, with `exact_tolerance: 0.001` at the top)
when this mca-sim takes those keys. A round one arm alone cannot track under MVN (a single-arm run) is redrawn.
Reachable: plain MVN (each arm's QP is its own: every arm alone) tracks every path with error < --max-err and
no fault; the others are counted apart as unreachable (with MVN's fault name).
--cells gives every task a table and 1-3 boxes or posts, with --sphere every odd task a streamed sphere crossing
between the arms (cells.py; mca-sim's simulated_sphere); --self-pairs every arm's self pairs (docs/sweep.md, "Random cells").
Every reachable task runs under each scheme, and again with a stop request at a random instant
(mca-sim --stop-at, when this mca-sim has it). Each run is classified:
  unsafe        some tick below d1, during the task or while braking (for mvn the expected collision);
  completed     every path clock reached its end (summary `completed`) with <= --lost-threshold s lost, and
                every exact point met (summary exact_missed 0, where mca-sim writes it);
  late          completed, more path time lost;
  exact-missed  ran to its end without fault or stop, but missed an exact point;
  safe-stop     a named fault, the stop request or an unresolved deadlock, and >= d1 all the way.
Prints one table (rows scheme x {task, with stop}; counts and % of the reachable tasks, path_error_max p50/max
over the runs), the unreachable count, the deadlock count and the fault names, the start and least distances,
for pick and place the target (>= 95 % completed with every exact point met and path_error_max <=
0.02 m), and writes --json OUT with every task's details. --tolerance X writes `tolerance: X` into every
generated path (when this mca-sim takes the key). Summary fields this mca-sim does not write (completed,
path_time_lost_s, deadlocks, path_error_max, exact_missed, ...) are reported "n/a"; without `completed` a run
"completes" when it ran its duration without fault.
"""
import argparse
import concurrent.futures as cf
import csv
import json
import math
import os
import random
import re
import shutil
import subprocess
import sys
import time
import xml.etree.ElementTree as ET

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import cells  # noqa: E402
import coord_diagram  # noqa: E402
import tips_pass  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
ROBOTS = os.path.join(ROOT, "config", "robots")
CLASSES = ("completed", "late", "exact-missed", "safe-stop", "unsafe")
PNP_PATH_ERROR = 0.02  # the bound on path_error_max for pick and place [m]

# Kinova home (deg [275, 167.5, 57.5, 240, 82.5, 75]); joint 1 turns the arm about its base
KINOVA_HOME = [4.7997, 2.9234, 1.0036, 4.1888, 1.4399, 1.3090]
PA10_LEFT = [0.0, math.pi / 4, 0.0, -math.pi / 2, 0.0, math.pi / 4, 0.0, math.pi / 4]
PA10_RIGHT = [-math.pi / 2, -math.pi / 4, 0.0, math.pi / 2, 0.0, -math.pi / 4, 0.0, -math.pi / 4]

# vmax: peak tool-tip speed of the drawn paths [m/s] (the Kinova arms' joints are slower: 0.63-0.84 rad/s)
KINDS = {
    "pa10": dict(d1=0.05, d2=0.12, vmax=0.25, reach=0.40),
    "jaco-mico": dict(d1=0.07, d2=0.12, vmax=0.12, reach=0.30),
    "three": dict(d1=0.05, d2=0.12, vmax=0.12, reach=0.30),
    # pick and place (PNP below): vmax of the moves; the Kinova pair's moves as fast as cup_stacking.yaml's
    "pnp-jaco-mico": dict(d1=0.07, d2=0.12, vmax=0.18),
    "pnp-pa10": dict(d1=0.05, d2=0.12, vmax=0.25),
}


def joint_limits(urdf):
    """[(lower, upper)] of the moving joints in file order (continuous: None)."""
    lims = []
    for j in ET.parse(urdf).getroot().iter("joint"):
        if j.get("type") in ("revolute", "continuous", "prismatic"):
            lim = j.find("limit")
            if j.get("type") == "continuous" or lim is None or lim.get("lower") is None:
                lims.append(None)
            else:
                lims.append((float(lim.get("lower")), float(lim.get("upper"))))
    return lims


_LIMITS = {}


def jitter_q(rng, urdf, q, sigma):
    if urdf not in _LIMITS:
        _LIMITS[urdf] = joint_limits(os.path.join(ROBOTS, urdf))
    lims = _LIMITS[urdf]
    out = []
    for j, x in enumerate(q):
        y = x + rng.gauss(0.0, sigma)
        if j < len(lims) and lims[j] is not None:
            lo, hi = lims[j]
            margin = 0.1 * (hi - lo)
            y = min(max(y, lo + margin), hi - margin)
        out.append(round(y, 5))
    return out


def draw_arms(kind, rng):
    """Bases and initial configurations around the shipped scenario's."""
    if kind == "pa10":
        return [
            dict(name="left", urdf="pa10plus.urdf", base=[0.0, 0.0, 0.0], q0=jitter_q(rng, "pa10plus.urdf", PA10_LEFT, 0.2)),
            dict(name="right", urdf="pa10plus.urdf",
                 base=[round(0.45 + rng.uniform(-0.1, 0.1), 4), round(-0.5 + rng.uniform(-0.1, 0.1), 4), 0.0],
                 q0=jitter_q(rng, "pa10plus.urdf", PA10_RIGHT, 0.2)),
        ]
    if kind == "jaco-mico":
        mico = list(KINOVA_HOME)
        mico[0] = 6.4228  # turned by joint 1 to face the JACO2 (cup_stacking.yaml)
        return [
            dict(name="jaco2", urdf="jaco2.urdf", base=[0.0, 0.0, 0.0], q0=jitter_q(rng, "jaco2.urdf", KINOVA_HOME, 0.15)),
            dict(name="mico2", urdf="mico2.urdf",
                 base=[round(0.78 + rng.uniform(-0.1, 0.05), 4), round(rng.uniform(-0.1, 0.1), 4), 0.0],
                 q0=jitter_q(rng, "mico2.urdf", mico, 0.15)),
        ]
    if kind == "pnp-pa10":  # cross_circles.yaml's placement, q0 jittered by 0.1 rad
        return [
            dict(name="left", urdf="pa10plus.urdf", base=[0.0, 0.0, 0.0],
                 q0=jitter_q(rng, "pa10plus.urdf", PA10_LEFT, 0.1)),
            dict(name="right", urdf="pa10plus.urdf", base=[0.45, -0.5, 0.0],
                 q0=jitter_q(rng, "pa10plus.urdf", PA10_RIGHT, 0.1)),
        ]
    if kind == "pnp-jaco-mico":  # cup_stacking.yaml's placement, q0 jittered by 0.1 rad
        mico = list(KINOVA_HOME)
        mico[0] = 6.4228
        return [
            dict(name="jaco2", urdf="jaco2.urdf", base=[0.0, 0.0, 0.0],
                 q0=jitter_q(rng, "jaco2.urdf", KINOVA_HOME, 0.1)),
            dict(name="mico2", urdf="mico2.urdf", base=[0.78, 0.0, 0.0], q0=jitter_q(rng, "mico2.urdf", mico, 0.1)),
        ]
    if kind == "three":
        arms = []
        for i, (name, urdf) in enumerate((("jaco2_a", "jaco2.urdf"), ("mico2", "mico2.urdf"), ("jaco2_b", "jaco2.urdf"))):
            th = math.radians(90 + 120 * i + rng.uniform(-10, 10))
            r = rng.uniform(0.5, 0.6)
            q = list(KINOVA_HOME)
            # joint 1: the tool tip towards the table's centre (three_arms.yaml)
            q[0] = math.radians((45 - math.degrees(th)) % 360)
            arms.append(dict(name=name, urdf=urdf, base=[round(r * math.cos(th), 4), round(r * math.sin(th), 4), 0.0],
                             q0=jitter_q(rng, urdf, q, 0.12)))
        return arms
    raise ValueError("unknown kind " + kind)


def fmt(v):
    return "[" + ", ".join("%.6g" % x for x in v) + "]"


SELF_PAIRS = False  # --self-pairs: every arm's robot list of self pairs in every task (docs/scheme.md section 15)
SPHERE = False  # --sphere (with --cells): a streamed sphere in every odd task (cells.draw_sphere)


def self_pairs(sim, wd, name, kind, arms):
    """--self-pairs: the `self_pairs:` entries of a task, each arm's robot list less the pairs below d1 + 5 mm at
    the start configuration (as cup_stacking_self.yaml takes mico2's 5-2 and 6-2 out at the Kinova home), found
    by 2-tick probes; None without --self-pairs."""
    if not SELF_PAIRS:
        return None
    out = [a["name"] for a in arms]
    for _ in range(12):
        scn = os.path.join(wd, "self_probe.yaml")
        with open(scn, "w") as f:
            f.write(scenario_yaml(name + "_self_probe", kind, arms, 0.002, selfp=out))
        r = sim.run(scn, os.path.join(wd, "self_probe.json"), ["mvn"])[0].get("mvn")
        if r is None or r.get("self_min_distance", 1.0) >= KINDS[kind]["d1"] + 0.005:
            break
        a, link, other = r["self_min_pair"]
        out.append("-%s.%d-%d" % (arms[a]["name"], link, other))
    return out


def scenario_yaml(name, kind, arms, duration, paths=None, exact_tolerance=None, bodies=None, sphere=None,
                  selfp=None):
    """The scenario text. A path dict: kind, its keys, and optionally t0, relative (waypoints; default true),
    tolerance and exact (written only when present: the caller leaves them out for an mca-sim without them)."""
    d = KINDS[kind]
    s = ["# generated by tools/mca-sweep/mca_sweep.py", "name: %s" % name, "duration: %.3f" % duration,
         "dt: 0.001", "d1: %g" % d["d1"], "d2: %g" % d["d2"], "K: 20", "epsilon: 5"]
    if exact_tolerance is not None:
        s.append("exact_tolerance: %g" % exact_tolerance)
    if bodies:
        s += cells.bodies_yaml(bodies)
    if sphere:
        s += cells.sphere_yaml(sphere)
    if selfp:
        s.append("self_pairs: [%s]" % ", ".join(selfp))
    s.append("arms:")
    for i, a in enumerate(arms):
        s += ["  - name: %s" % a["name"], "    urdf: %s" % os.path.join(ROBOTS, a["urdf"]), "    tip_link: tool_tip",
              "    base_xyz: %s" % fmt(a["base"]), "    q0: %s" % fmt(a["q0"]), "    path:"]
        p = paths[i] if paths else {"kind": "hold"}
        s.append("      kind: %s" % p["kind"])
        if p.get("t0"):
            s.append("      t0: %.3f" % p["t0"])
        if p["kind"] == "circle":
            s += ["      radius: %.4f" % p["radius"], "      period: %.3f" % p["period"], "      u: %s" % fmt(p["u"]),
                  "      v: %s" % fmt(p["v"])]
        elif p["kind"] == "waypoints":
            s += ["      relative: %s" % ("true" if p.get("relative", True) else "false"), "      points:"]
            s += ["        - %s" % fmt(pt) for pt in p["points"]]
            s.append("      durations: %s" % fmt(p["durations"]))
        if p.get("tolerance") is not None:
            s.append("      tolerance: %g" % p["tolerance"])
        if p.get("tracking"):
            s.append("      tracking: %s" % p["tracking"])
        if p.get("exact"):
            s.append("      exact: [%s]" % ", ".join(str(x) for x in p["exact"]))
    return "\n".join(s) + "\n"


def norm(v):
    n = math.sqrt(sum(x * x for x in v))
    return [x / n for x in v] if n > 0 else v


def sub(a, b):
    return [x - y for x, y in zip(a, b)]


def dist(a, b):
    return math.sqrt(sum((x - y) ** 2 for x, y in zip(a, b)))


def draw_path(rng, start, other_tip, vmax, max_reach):
    """A path from start whose far point is closer to other_tip than start is; (path, far point, time)."""
    to = sub(other_tip, start)
    gap = math.sqrt(sum(x * x for x in to))
    for _ in range(50):
        u = norm([x / gap + rng.gauss(0.0, 0.35) for x in to])
        reach = rng.uniform(0.45, 0.95) * gap
        reach = min(max(reach, 0.08), max_reach)
        far = [s + reach * x for s, x in zip(start, u)]
        if dist(far, other_tip) < gap and far[2] > 0.08:
            break
    else:
        return None
    if rng.random() < 0.4:
        # circle through the start: centre = start - R u_c, far point = start - 2 R u_c
        r = reach / 2.0
        w = norm([rng.gauss(0, 1) for _ in range(3)])
        v = norm(sub(w, [sum(a * b for a, b in zip(w, u)) * x for x in u]))
        period = round(max(3.0, 2 * 2 * math.pi * r / vmax), 2)  # sin^2 phase: peak = 2 x mean speed
        return dict(kind="circle", radius=r, period=period, u=[-x for x in u], v=v), far, period
    # waypoints (relative): optional start delay, out (optionally through a side point), dwell, back
    pts, durs = [], []
    delay = round(rng.uniform(0.0, 1.0), 2)
    if delay > 0.05:
        pts.append([0.0, 0.0, 0.0])
        durs.append(delay)
    off = [reach * x for x in u]
    seg = lambda d: round(max(1.0, 1.875 * d / vmax), 2)  # quintic peak speed 1.875 d / T <= vmax
    if rng.random() < 0.5:
        side = norm([rng.gauss(0, 1) for _ in range(3)])
        mid = [0.5 * o + 0.3 * reach * s for o, s in zip(off, side)]
        pts += [mid, off]
        durs += [seg(dist(mid, [0, 0, 0])), seg(dist(mid, off))]
    else:
        pts.append(off)
        durs.append(seg(reach))
    pts += [off, [0.0, 0.0, 0.0]]
    durs += [round(rng.uniform(0.2, 1.0), 2), seg(reach)]
    return dict(kind="waypoints", points=[[round(x, 4) for x in p] for p in pts], durations=durs), far, sum(durs)


# summary fields that not every mca-sim writes (completion; path error and exact points)
SUMMARY_FIELDS = ("completed", "path_time_lost_s", "deadlocks", "path_error_max", "path_error_p99", "exact_points",
                  "exact_missed", "exact_error_max")


def load_summary(path):
    """mca-sim's JSON summary (a run without a second arm writes min_distance inf: read as Infinity)."""
    with open(path) as f:
        txt = f.read()
    fix = {"inf": "Infinity", "nan": "NaN"}
    return json.loads(re.sub(r'(?<=[:\[,])(-?)(inf|nan)\b', lambda m: m.group(1) + fix[m.group(2)], txt))


# ---------------------------------------------------------------- pick and place

# Boxes in the cell's frame: origin at arm 0's base, `along` the base line towards arm 1's base, `front` across
# it to the side the arms work on, z up: ranges [m] of (along, front, z). The place zone lies between the bases
# (both arms reach it), each arm's pick area on its own side. lift: height above a pick/place point of the
# approach points; each arm places within `spread` (horizontally) of its own slot in the zone (a stack, a tray
# cell), the two slots sep + 2 spread apart: every place point of one arm at least sep from the other's (the
# zone is shared, its slots are not: two place points closer than d1 could never be served at once, and an arm
# waiting above the other's slot would block it, a deadlock by construction); front: which normal of the base
# line is the working side (the one the start tool tips lean to: -y for the Kinova pair, +x+y for the PA10+
# pair). PNP_*: for every pnp kind.
PNP = {
    "pnp-jaco-mico": dict(zone=((0.26, 0.52), (0.24, 0.46), (0.08, 0.14)), sep=0.10, spread=0.03,
                          pick=(((0.05, 0.25), (0.35, 0.58), (0.06, 0.14)), ((0.55, 0.72), (0.32, 0.52), (0.06, 0.14))),
                          lift=(0.10, 0.16), front=1.0),
    "pnp-pa10": dict(zone=((0.20, 0.48), (0.20, 0.48), (0.45, 0.65)), sep=0.10, spread=0.03,
                     pick=(((-0.35, 0.0), (0.30, 0.60), (0.40, 0.65)), ((0.67, 1.02), (0.30, 0.60), (0.40, 0.65))),
                     lift=(0.12, 0.20), front=-1.0),
}
PNP_ROUNDS = (2, 3)
PNP_TOTAL = (25.0, 45.0)
PNP_DWELL = (0.5, 1.5)
PNP_TMIN = 1.0  # shortest move [s]
PNP_EXACT_TOL = 0.001  # exact_tolerance written into the pnp scenarios (mca-sim's default: 1 mm)


def pnp_frame(kind, arms):
    """(origin, e, n) of kind's pick-and-place boxes: e along the base line, n its horizontal normal on the
    working side."""
    b0, b1 = arms[0]["base"], arms[1]["base"]
    e = norm([b1[0] - b0[0], b1[1] - b0[1], 0.0])
    f = PNP[kind]["front"]
    return list(b0), e, [f * e[1], -f * e[0], 0.0]


def pnp_point(frame, afz):
    o, e, n = frame
    return [round(o[k] + afz[0] * e[k] + afz[1] * n[k] + (afz[2] if k == 2 else 0.0), 4) for k in range(3)]


def pnp_coords(frame, p):
    """(along, front, z) of a world point."""
    o, e, n = frame
    d = sub(p, o)
    return [sum(a * b for a, b in zip(d, e)), sum(a * b for a, b in zip(d, n)), d[2]]


def in_box(afz, box, tol=1e-3):
    return all(lo - tol <= x <= hi + tol for x, (lo, hi) in zip(afz, box))


def draw_in(rng, box):
    return [rng.uniform(lo, hi) for lo, hi in box]


def hdist(p, q):
    return math.hypot(p[0] - q[0], p[1] - q[1])


def pnp_slots(rng, kind, frame):
    """The two arms' slots in the place zone: (along, front) each, sep + 2 spread apart (None: none found)."""
    g = PNP[kind]
    box = [(lo + g["spread"], hi - g["spread"]) for lo, hi in g["zone"][:2]]
    for _ in range(200):
        c = [draw_in(rng, box), draw_in(rng, box)]
        if math.hypot(c[0][0] - c[1][0], c[0][1] - c[1][1]) >= g["sep"] + 2 * g["spread"]:
            return c
    return None


def pnp_round(rng, kind, a, frame, slot):
    """One round's pick point (arm a's pick area), place point (within spread of slot, at a height in the zone)
    and their approach points (above, by lift)."""
    g = PNP[kind]
    pick = pnp_point(frame, draw_in(rng, g["pick"][a]))
    r, th = g["spread"] * math.sqrt(rng.random()), rng.uniform(0.0, 2.0 * math.pi)
    place = pnp_point(frame, [slot[0] + r * math.cos(th), slot[1] + r * math.sin(th), rng.uniform(*g["zone"][2])])
    hp, hq = rng.uniform(*g["lift"]), rng.uniform(*g["lift"])
    return dict(pick=pick, pick_above=[pick[0], pick[1], round(pick[2] + hp, 4)],
                place=place, place_above=[place[0], place[1], round(place[2] + hq, 4)])


def pnp_timetable(rng, start, rounds, vmax):
    """The waypoint path through the rounds: above the pick point, down, grasp dwell, up, [wait holding it],
    over the place point, down, release dwell, up; at the end back above the last pick point (clear of the
    zone). Each move lasts at least max(PNP_TMIN, 1.875 d / vmax) (quintic peak speed <= vmax); the time
    left to a total drawn in PNP_TOTAL goes to longer moves, a start delay (t0) and waits holding the part.
    Returns dict(points, durations, t0, exact, segs: [(round, what)], total) or None when the rounds need
    more than PNP_TOTAL's upper end."""
    segs = []  # (point, what, round): what in move/dwell/wait
    for r, rd in enumerate(rounds):
        segs += [(rd["pick_above"], "move", r), (rd["pick"], "move", r), (rd["pick"], "dwell", r),
                 (rd["pick_above"], "move", r), (rd["pick_above"], "wait", r), (rd["place_above"], "move", r),
                 (rd["place"], "move", r), (rd["place"], "dwell", r), (rd["place_above"], "move", r)]
    segs.append((rounds[-1]["pick_above"], "move", len(rounds) - 1))
    mins, prev = [], start
    for pt, what, _ in segs:
        if what == "move":
            mins.append(max(PNP_TMIN, 1.875 * dist(prev, pt) / vmax))
        elif what == "dwell":
            mins.append(rng.uniform(*PNP_DWELL))
        else:
            mins.append(0.0)
        prev = pt
    base = sum(mins)
    hi = PNP_TOTAL[1] - 0.01 * len(segs)  # room for rounding every duration up to 10 ms
    if base > hi:
        return None
    total = rng.uniform(max(base, PNP_TOTAL[0] + 0.01), hi)
    slack = total - base
    stretch = rng.uniform(0.3, 0.8) * slack
    moves = [k for k, (_, w, _) in enumerate(segs) if w == "move"]
    waits = [k for k, (_, w, _) in enumerate(segs) if w == "wait"] + [-1]  # -1: the start delay
    wm = [rng.expovariate(1.0) for _ in moves]
    ww = [rng.expovariate(1.0) for _ in waits]
    durs = list(mins)
    for k, w in zip(moves, wm):
        durs[k] += stretch * w / sum(wm)
    t0 = 0.0
    for k, w in zip(waits, ww):
        x = (slack - stretch) * w / sum(ww)
        if x < 0.3:
            durs[k + 1] += x  # too short a wait or delay: the next move (a wait is followed by one) takes it
        elif k < 0:
            t0 = math.floor(x * 100) / 100.0
        else:
            durs[k] = x
    pts, out, exact, what = [], [], [], []
    for (pt, w, r), d in zip(segs, durs):
        if w == "wait" and d < 0.3:
            continue  # left out (its time went to the next move)
        if w == "dwell":
            exact += [len(pts) - 1, len(pts)]  # the point reached (grasp/release) and the dwell's end
        pts.append(list(pt))
        out.append(math.ceil(d * 100 - 1e-9) / 100.0)
        what.append((r, w))
    return dict(points=pts, durations=out, t0=t0, exact=exact, segs=what, total=round(t0 + sum(out), 2))


def first_failure(sim, wd, name, kind, arm, path, max_err):
    """MVN alone on one arm along its path: None when it tracks (error < max_err everywhere, no fault), else
    the task time of the first tick off by max_err or more (or of the fault)."""
    scn = os.path.join(wd, "arm.yaml")
    end = path.get("t0", 0.0) + sum(path["durations"])
    with open(scn, "w") as f:
        f.write(scenario_yaml(name + "_arm", kind, [arm], round(end + 0.3, 3), [{k: v for k, v in path.items() if k in (
            "kind", "relative", "t0", "points", "durations")}]))
    out = os.path.join(wd, "arm.csv")
    runs, errs = sim.run(scn, os.path.join(wd, "arm.json"), ["mvn"], csv_out=out)
    if errs or "mvn" not in runs:
        return 0.0
    r = runs["mvn"]
    if not r.get("fault") and r["max_err"] < max_err:
        return None
    t = r["fault_t"] if r.get("fault") else end
    with open(out, newline="") as f:
        for row in csv.DictReader(f):
            if float(row["err0"]) >= max_err:
                t = min(t, float(row["t"]))
                break
    return t


def seg_at(path, t):
    """(round, what) of the segment the path is in at task time t."""
    tt = path.get("t0", 0.0)
    if t < tt:
        return path["segs"][0]
    for sg, d in zip(path["segs"], path["durations"]):
        tt += d
        if t < tt:
            return sg
    return path["segs"][-1]


def task_start(kind, seed, i, work):
    """Task i of kind: its random generator (seeded by 'seed:kind:i' alone), id, name and work folder."""
    name = "sweep_%s_%d" % (kind.replace("-", "_"), i)
    wd = os.path.join(work, name)
    os.makedirs(wd, exist_ok=True)
    return random.Random("%d:%s:%d" % (seed, kind, i)), "%s:%d" % (kind, i), name, wd


def draw_cell(sim, kind, seed, i, wd, name, arms, tips, paths, duration, selfp=None):
    """A random cell for the task (cells.py; its own generator, so the task's own draws do not change): bodies
    whose clearances the start configurations keep (a 2-tick probe with them), and with --sphere in every odd task
    a streamed sphere (its own generator too) that starts outside S_p of the arms (a 50 ms probe: its first samples);
    (bodies, sphere or None), or (None, None) after 20 draws."""
    rng = random.Random("%d:%s:%d:cell" % (seed, kind, i))
    srng = random.Random("%d:%s:%d:sphere" % (seed, kind, i)) if SPHERE and i % 2 == 1 else None
    full = [dict(a, urdf=os.path.join(ROBOTS, a["urdf"])) for a in arms]
    for _ in range(20):
        bodies = cells.draw_cell(rng, full, tips, paths)
        if bodies is None:
            continue
        sphere = cells.draw_sphere(srng, arms, tips, duration) if srng else None
        scn = os.path.join(wd, "cell_probe.yaml")
        with open(scn, "w") as f:
            f.write(scenario_yaml(name + "_cell_probe", kind, arms, 0.05 if sphere else 0.002, bodies=bodies,
                                  sphere=sphere, selfp=selfp))
        r = sim.run(scn, os.path.join(wd, "cell_probe.json"), ["mvn"])[0].get("mvn")
        if r is not None and r.get("body_min_margin", -1.0) >= 0.005 and (
                not sphere or r.get("track_min_margin", -1.0) >= 0.005):
            return bodies, sphere
    return None, None


def make_pnp_task(sim, kind, seed, i, work, max_err, tol=None, with_cell=False):
    """Pick-and-place task i of kind (seeded by 'seed:kind:i'): both arms at the shipped scenario's placement
    (q0 jittered), each with 2-3 rounds from its own pick area to the shared place zone. Rounds an arm alone
    cannot track under MVN are redrawn (a single-arm run: with MVN every arm's QP is its own)."""
    rng, tid, name, wd = task_start(kind, seed, i, work)
    d2 = KINDS[kind]["d2"]
    vmax = KINDS[kind]["vmax"]
    for tries in range(1, 51):  # the PA10+ pair starts 0.085 m apart at cross_circles' q0: often < d2
        arms = draw_arms(kind, rng)
        tips, d0, err = probe(sim, wd, name, kind, arms)
        if err:
            if tries == 50:
                return dict(id=tid, error="probe failed: " + err)
            continue
        if d0 >= d2 or tries == 50:
            break
    frame = pnp_frame(kind, arms)
    slots = pnp_slots(rng, kind, frame)
    if slots is None:
        return dict(id=tid, error="no two slots in the place zone")
    paths, info = [], []
    for a, arm in enumerate(arms):
        rounds = [pnp_round(rng, kind, a, frame, slots[a]) for _ in range(rng.choice(PNP_ROUNDS))]
        fails = 0
        for attempt in range(40):
            tt = pnp_timetable(rng, tips[a], rounds, vmax)
            if tt is None:  # too many rounds for PNP_TOTAL
                rounds = rounds[:-1] if len(rounds) > PNP_ROUNDS[0] else \
                    [pnp_round(rng, kind, a, frame, slots[a]) for _ in rounds]
                continue
            path = dict(kind="waypoints", relative=False, **tt)
            t = first_failure(sim, wd, name, kind, arm, path, max_err)
            if t is None:
                break
            fails += 1
            if fails % 10 == 0:
                rounds = [pnp_round(rng, kind, a, frame, slots[a]) for _ in rounds]  # all new now and then
            else:
                rounds[seg_at(path, t)[0]] = pnp_round(rng, kind, a, frame, slots[a])
        else:
            return dict(id=tid, error="%s: no pick-and-place path MVN tracks alone in 40 draws" % arm["name"])
        paths.append(path)
        info.append(dict(arm=arm["name"], rounds=len(rounds), redraws=fails, t0=path["t0"], total=path["total"],
                         picks=[r["pick"] for r in rounds], places=[r["place"] for r in rounds],
                         points=path["points"], exact=path["exact"]))
    duration = round(max(p["total"] for p in paths) + 0.5, 2)
    selfp = self_pairs(sim, wd, name, kind, arms)
    bodies, sphere = draw_cell(sim, kind, seed, i, wd, name, arms, tips, paths, duration,
                               selfp) if with_cell else (None, None)
    if with_cell and bodies is None:
        return dict(id=tid, error="no random cell clear of the paths and the start in 20 draws")
    out = []
    for p in paths:
        q = {k: v for k, v in p.items() if k in ("kind", "relative", "t0", "points", "durations")}
        if tol is not None:
            q["tolerance"] = tol
        if sim.keys["exact"]:
            q["exact"] = p["exact"]
        out.append(q)
    scn = os.path.join(wd, "scenario.yaml")
    with open(scn, "w") as f:
        f.write(scenario_yaml(name, kind, arms, duration, out,
                              exact_tolerance=PNP_EXACT_TOL if sim.keys["exact_tolerance"] else None, bodies=bodies,
                              sphere=sphere, selfp=selfp))
    stop_t = round(rng.uniform(0.15, 0.85) * duration, 3)
    g = PNP[kind]
    return dict(id=tid, kind=kind, index=i, scenario=scn, duration=duration, start_distance=round(d0, 5),
                draws=tries, stop_at=stop_t, d1=KINDS[kind]["d1"], d2=d2, paths=["pick-and-place"] * len(arms),
                pnp=dict(frame=[[round(x, 6) for x in v] for v in frame], zone=g["zone"], sep=g["sep"],
                         slots=[[round(x, 4) for x in c] for c in slots],
                         pick_areas=list(g["pick"]), arms=info),
                tips_blocked=tips_pass.scenario_blocked(scn, tips), bodies=bodies, sphere=sphere, self_pairs=selfp)


class Sim:
    def __init__(self, path):
        self.path = path
        h = subprocess.run([path, "--help"], capture_output=True, text=True).stdout
        self.help = h
        m = re.search(r"--scheme ([a-z|\-]+)", h)
        self.schemes = m.group(1).split("|") if m else ["mca", "mvn", "apf"]
        self.stop_at = "--stop-at" in h
        self.fault_at = "--fault-at" in h
        self.dec_limit = "--dec-limit" in h
        self.fields = set()  # the newer summary fields (mca-ts, pick and place) this mca-sim writes
        # the pick-and-place scenario keys, each accepted or not by a 2-tick run of a tiny scenario: per path
        # `tolerance: X` and `exact: [i, ...]`, top level `exact_tolerance: X`
        self.keys = self.probe_keys()

    def probe_keys(self):
        import tempfile
        wd = tempfile.mkdtemp(prefix="mca-sweep-keys-")
        arm = dict(name="a", urdf="jaco2.urdf", base=[0.0, 0.0, 0.0], q0=KINOVA_HOME)

        def accepts(path_keys, top=None):
            scn = os.path.join(wd, "keys.yaml")
            path = dict(kind="waypoints", points=[[0.0, 0.0, 0.0], [0.0, 0.0, 0.0]], durations=[1.0, 1.0])
            path.update(path_keys)
            with open(scn, "w") as f:
                f.write(scenario_yaml("keys_probe", "jaco-mico", [arm], 0.002, [path], exact_tolerance=top))
            p = subprocess.run([self.path, "--scenario", scn, "--scheme", "mvn"], capture_output=True, text=True,
                               timeout=60)
            return p.returncode == 0

        try:
            if not accepts({}):
                return dict(tolerance=False, exact=False, exact_tolerance=False)
            return dict(tolerance=accepts(dict(tolerance=0.01)), exact=accepts(dict(exact=[0, 1])),
                        exact_tolerance=accepts({}, top=0.001))
        finally:
            shutil.rmtree(wd, ignore_errors=True)

    def run(self, scn, summary, schemes, extra=(), csv_out=None):
        """mca-sim on schemes (in groups of 3); {scheme: run dict}, plus the error text of a failed run."""
        runs, errs = {}, []
        for i in range(0, len(schemes), 3):
            part = schemes[i:i + 3]
            cmd = [self.path, "--scenario", scn, "--scheme", ",".join(part), "--summary", summary] + list(extra)
            if csv_out:
                cmd += ["--csv", csv_out]
            p = subprocess.run(cmd, capture_output=True, text=True, timeout=600)
            if p.returncode != 0:
                errs.append("%s: exit %d: %s" % (" ".join(cmd[-6:]), p.returncode, p.stderr.strip()[-300:]))
                continue
            s = load_summary(summary)
            for r in s["runs"]:
                runs[r["scheme"]] = r
                self.fields.update(k for k in SUMMARY_FIELDS if k in r)
        return runs, errs


def min_distance_all(r):
    """Minimum over the task and the braking: every min_distance* field of the summary."""
    vals = [r["min_distance"]]
    for k, v in r.items():
        if k.startswith("min_distance") and not k.endswith("_t") and k != "min_distance" and isinstance(v, (int, float)):
            if k == "min_distance_after_fault" and (not r.get("fault") or v == -1):
                continue
            vals.append(v)
    return min(vals)


def classify(r, d1, duration, lost_thr, stop_t=None):
    """(class, reason, details) of one run's summary. With the pick-and-place fields a run completes only when every
    exact point was met too (exact_missed 0); one that ran to its end without fault or stop but missed an exact
    point is `exact-missed`."""
    dmin = min_distance_all(r)
    has_c = "completed" in r
    if has_c:
        completed = bool(r["completed"])
    else:
        completed = not r.get("fault") and r.get("ticks", 0) >= int(round(duration / 0.001))
    missed = r.get("exact_missed")
    lost = r.get("path_time_lost_s")
    fault = r.get("fault_name", "none")
    det = dict(min_d=round(dmin, 6), fault=fault, fault_t=r.get("fault_t"), completed=int(completed) if has_c else None,
               lost=lost, deadlocks=r.get("deadlocks"), stopped=r.get("stopped"), ticks=r.get("ticks"),
               max_err=r.get("max_err"))
    det.update({k: r.get(k) for k in ("path_error_max", "path_error_p99", "path_error_brake_max", "exact_points", "exact_missed",
                                      "exact_error_max", "end_pair", "end_distance", "end_ee", "end_tau", "end_done", "coord_pairs", "coord_unplanned",
                                      "solves", "solves_unconverged", "solve_steps", "exact_solves",
                                      "bodies", "body_min_margin", "body_min_name", "body_min_pair", "body_ticks_below",
                                      "arm_ticks_below", "self_ticks_below", "sphere_sent", "sphere_lost",
                                      "track_min_margin", "track_sp_max", "track_ticks_rest", "track_ticks_moving",
                                      "track_ticks_braking",
                                      "sphere_true_min_d")})
    if dmin < d1:
        return "unsafe", fault if fault != "none" else "below-d1", det
    if r.get("body_ticks_below"):
        return "unsafe", "below-clearance", det
    if r.get("self_ticks_below"):
        return "unsafe", "self-below-d1", det
    if r.get("track_ticks_moving"):
        return "unsafe", "below-S_p-moving", det
    if completed and not missed:
        if lost is not None and lost > lost_thr:
            return "late", "lost %.2f s" % lost, det
        return "completed", "", det
    if fault != "none":
        return "safe-stop", fault, det
    if stop_t is not None:
        return "safe-stop", "stop", det
    if r.get("deadlocks"):
        return "safe-stop", "deadlock-unresolved", det
    if missed:
        return "exact-missed", "exact-missed", det
    return "safe-stop", "not-completed", det


def probe(sim, wd, name, kind, arms):
    """Tool tips and start distance: two ticks with hold paths."""
    scn = os.path.join(wd, "probe.yaml")
    with open(scn, "w") as f:
        f.write(scenario_yaml(name + "_probe", kind, arms, 0.002))
    out = os.path.join(wd, "probe.csv")
    runs, errs = sim.run(scn, os.path.join(wd, "probe.json"), ["mvn"], csv_out=out)
    if errs:
        return None, None, errs[0]
    with open(out, newline="") as f:
        row = next(csv.DictReader(f))
    tips = [[float(row["ee%d_%s" % (a, c)]) for c in "xyz"] for a in range(len(arms))]
    return tips, float(row["min_d"]), None


def rest_conflicts(sim, wd, name, kind, arms, paths, duration):
    """Each arm on its path (MVN: no avoidance) with every other arm standing at its start: the pairs that come
    below d1, as [arm on its path, arm at rest, least distance]. No path rate can complete such a task while
    the arm at rest stays there (the crossing kinds' paths return home, so an arm's start is also its end);
    the sweep reports completion with and without them. An a-priori test: it does not look at mca-ts. Not for
    pick and place: there an arm's start is not its end, and leaving its start is what makes room."""
    out = []
    for a in range(len(arms)):
        scn = os.path.join(wd, "rest%d.yaml" % a)
        solo = [{"kind": "hold"} if b != a else {k: v for k, v in paths[a].items() if k not in ("tolerance", "exact")}
                for b in range(len(arms))]
        with open(scn, "w") as f:
            f.write(scenario_yaml(name + "_rest%d" % a, kind, arms, duration, solo))
        r = sim.run(scn, os.path.join(wd, "rest%d.json" % a), ["mvn"])[0].get("mvn")
        if r is None:
            continue
        if r["min_distance"] < KINDS[kind]["d1"]:
            other = [b for b in range(len(arms)) if b != a]
            out.append([a, other[0] if len(other) == 1 else -1, round(r["min_distance"], 4)])
    return out


def make_task(sim, kind, seed, i, work, tol=None, elastic=False, with_cell=False):
    """Draw task i of kind (seeded by 'seed:kind:i'), write its scenario; a dict describing it."""
    rng, tid, name, wd = task_start(kind, seed, i, work)
    d2 = KINDS[kind]["d2"]
    tries = 0
    while True:
        tries += 1
        arms = draw_arms(kind, rng)
        tips, d0, err = probe(sim, wd, name, kind, arms)
        if err:
            if tries >= 20:
                return dict(id=tid, error="probe failed: " + err)
            continue
        if d0 < d2 and tries < 20:
            continue
        paths, fars, times, ok = [], [], [], True
        for a in range(len(arms)):
            others = [b for b in range(len(arms)) if b != a]
            b = others[rng.randrange(len(others))]
            p = draw_path(rng, tips[a], tips[b], KINDS[kind]["vmax"], KINDS[kind]["reach"])
            if p is None:
                ok = False
                break
            paths.append(p[0])
            fars.append(dict(towards=b, start_gap=round(dist(tips[a], tips[b]), 4),
                             far_gap=round(dist(p[1], tips[b]), 4)))
            times.append(p[2])
        if ok or tries >= 20:
            break
    if not ok:
        return dict(id=tid, error="no path towards the other arm in 20 draws")
    duration = round(max(times) + 0.5, 2)
    for p in paths:
        if elastic:
            p["tracking"] = "elastic"  # the L2 slack of docs/scheme.md section 10 (no tube)
        elif tol is not None:
            p["tolerance"] = tol
    selfp = self_pairs(sim, wd, name, kind, arms)
    bodies, sphere = draw_cell(sim, kind, seed, i, wd, name, arms, tips, paths, duration,
                               selfp) if with_cell else (None, None)
    if with_cell and bodies is None:
        return dict(id=tid, error="no random cell clear of the paths and the start in 20 draws")
    scn = os.path.join(wd, "scenario.yaml")
    with open(scn, "w") as f:
        f.write(scenario_yaml(name, kind, arms, duration, paths, bodies=bodies, sphere=sphere, selfp=selfp))
    stop_t = round(rng.uniform(0.15, 0.85) * duration, 3)
    return dict(id=tid, kind=kind, index=i, scenario=scn, duration=duration, start_distance=round(d0, 5),
                draws=tries, stop_at=stop_t, d1=KINDS[kind]["d1"], d2=d2,
                paths=[p["kind"] for p in paths], towards=fars,
                rest_conflicts=rest_conflicts(sim, wd, name, kind, arms, paths, duration),
                tips_blocked=tips_pass.scenario_blocked(scn, tips), bodies=bodies, sphere=sphere, self_pairs=selfp)


def run_task(sim, kind, seed, i, a):
    t0 = time.time()
    tol = a.tolerance if sim.keys["tolerance"] else None
    if kind in PNP:
        task = make_pnp_task(sim, kind, seed, i, a.work, a.max_err, tol, a.cells)
    else:
        task = make_task(sim, kind, seed, i, a.work, tol, a.elastic, a.cells)
    if "error" in task:
        task.update(reachable=False, unreachable="generation: " + task["error"], runs={}, seconds=time.time() - t0)
        return task
    wd = os.path.dirname(task["scenario"])
    schemes = ["mvn"] + [s for s in a.schemes if s != "mvn"]
    extra = ["--dec-limit", str(a.dec_limit)] if a.dec_limit and sim.dec_limit else []
    if a.ideal_arms:
        extra.append("--euler")  # arms that realise every command exactly (no rate limit)
    if a.no_coordinate:
        extra.append("--no-coordinate")
    runs, errs = sim.run(task["scenario"], os.path.join(wd, "task.json"), schemes, extra)
    task["errors"] = errs
    mvn = runs.get("mvn")
    if mvn is None:
        task.update(reachable=False, unreachable="mvn run failed", runs={}, seconds=time.time() - t0)
        return task
    reach = mvn.get("fault", 0) == 0 and mvn["max_err"] < a.max_err
    task["mvn_max_err"] = mvn["max_err"]
    if mvn.get("bodies"):
        task["mvn_body_ticks_below"] = mvn.get("body_ticks_below", 0)
    task["reachable"] = reach
    if not reach:
        task["unreachable"] = mvn.get("fault_name") if mvn.get("fault") else "max err %.3g m" % mvn["max_err"]
        task["runs"] = {}
        task["seconds"] = round(time.time() - t0, 3)
        return task
    res = {}
    for s in a.schemes:
        if s in runs:
            c, why, det = classify(runs[s], task["d1"], task["duration"], a.lost_threshold)
            res[s] = {"task": dict(det, cls=c, reason=why)}
        else:
            res[s] = {"task": dict(cls="n/a", reason="scheme not run")}
    if sim.stop_at and not a.no_stop:
        sruns, serrs = sim.run(task["scenario"], os.path.join(wd, "stop.json"), list(a.schemes),
                               extra + ["--stop-at", "%.3f" % task["stop_at"]])
        task["errors"] += serrs
        for s in a.schemes:
            if s in sruns:
                c, why, det = classify(sruns[s], task["d1"], task["duration"], a.lost_threshold, task["stop_at"])
                res[s]["stop"] = dict(det, cls=c, reason=why)
            else:
                res[s]["stop"] = dict(cls="n/a", reason="scheme not run")
    task["runs"] = res
    if a.witness:
        task["witness"] = coord_diagram.witness(sim.path, a.witness, task["scenario"], wd)
    if a.stopcheck:
        # stops branched off the task every 20 ms at each dec limit (tools/mca-stopcheck, mca-ts)
        sj = os.path.join(wd, "stopcheck.json")
        p = subprocess.run([a.stopcheck, "--scenario", task["scenario"], "--scheme", "mca-ts", "--every", "0.02",
                            "--dec", a.stop_decs, "--json", sj], capture_output=True, text=True, timeout=1800)
        try:
            task["stopcheck"] = json.load(open(sj))["runs"]
        except (OSError, ValueError, KeyError):
            task["stopcheck"] = None
            task["errors"].append("mca-stopcheck exit %d: %s" % (p.returncode, p.stderr[-300:]))
    task["seconds"] = round(time.time() - t0, 3)
    if not a.keep and reach:
        for f in ("probe.csv", "arm.csv"):
            try:
                os.remove(os.path.join(wd, f))
            except OSError:
                pass
    return task


def pnp_target(tasks, schemes, lines):
    """The target for pick and place, per scheme over the task runs: >= 95 % completed (late included)
    with every exact point met, and path_error_max <= PNP_PATH_ERROR; a line each and a dict."""
    out = {}
    for s in schemes:
        rs = [t["runs"][s]["task"] for t in tasks if t["runs"].get(s, {}).get("task", {}).get("cls", "n/a") != "n/a"]
        if not rs:
            continue
        n = len(rs)
        done = [r for r in rs if r["cls"] in ("completed", "late")]
        have_pe = all(r.get("path_error_max") is not None for r in rs)
        have_ex = all(r.get("exact_missed") is not None for r in rs)
        pe_ok = sum(1 for r in rs if r.get("path_error_max") is not None and r["path_error_max"] <= PNP_PATH_ERROR)
        both = sum(1 for r in done if r.get("path_error_max") is not None and r["path_error_max"] <= PNP_PATH_ERROR)
        met = have_pe and have_ex and both >= 0.95 * n
        # until mca-sim writes path_error_max: max_err, the distance to the path's current point (>= the distance
        # to the path's curve), so an upper bound
        me_ok = sum(1 for r in rs if r.get("max_err") is not None and r["max_err"] <= PNP_PATH_ERROR)
        out[s] = dict(n=n, done=len(done), exact_fields=have_ex, path_error_fields=have_pe,
                      path_error_ok=pe_ok if have_pe else None,
                      path_error_ok_every_task=(pe_ok == n) if have_pe else None,
                      done_and_path_error_ok=both if have_pe else None, target_met=met if have_pe and have_ex else None,
                      max_err_ok=me_ok)
        lines.append("pick and place, %s: %d of %d done (completed or late%s) = %.1f %%; path_error_max <= %.2f m: %s; "
                     "both: %s -> target (>= 95 %%): %s" % (
                         s, len(done), n, ", every exact point met" if have_ex else "; exact points: n/a",
                         100.0 * len(done) / n, PNP_PATH_ERROR,
                         ("%d of %d (every task: %s)" % (pe_ok, n, "yes" if pe_ok == n else "no")) if have_pe else "n/a",
                         ("%d (%.1f %%)" % (both, 100.0 * both / n)) if have_pe else "n/a",
                         ("met" if met else "not met") if have_pe and have_ex else
                         "n/a (this mca-sim writes no path_error_max / exact_missed)"))
        # tasks whose predicted arms meet on every order of passing (mca-ts's start-up plan found no schedule):
        # the pick-and-place analogue of the crossing kinds' rest conflicts, counted apart, never dropped
        plan = [t["runs"].get("mca-ts", {}).get("task", {}).get("coord_unplanned") for t in tasks
                if t["runs"].get(s, {}).get("task", {}).get("cls", "n/a") != "n/a"]
        if all(u is not None for u in plan):
            sched = [r for r, u in zip(rs, plan) if u == 0]
            sdone = sum(1 for r in sched if r["cls"] in ("completed", "late"))
            out[s].update(with_schedule=len(sched), with_schedule_done=sdone)
            lines.append("pick and place, %s: of the %d tasks with a coordination schedule %d done (%.1f %%); the other "
                         "%d have none (fixed paths whose predicted arms meet on every order of passing)" % (
                             s, len(sched), sdone, 100.0 * sdone / max(1, len(sched)), n - len(sched)))
        blk = [t.get("tips_blocked") for t in tasks if t["runs"].get(s, {}).get("task", {}).get("cls", "n/a") != "n/a"]
        if all(b is not None for b in blk):
            ok = [r for r, b in zip(rs, blk) if not b]
            okd = sum(1 for r in ok if r["cls"] in ("completed", "late"))
            okb = sum(1 for r in ok if r["cls"] in ("completed", "late") and r.get("path_error_max") is not None
                      and r["path_error_max"] <= PNP_PATH_ERROR)
            out[s].update(tips_pass=len(ok), tips_pass_done=okd, tips_pass_done_and_path_error_ok=okb)
            lines.append("pick and place, %s: of the %d tasks whose tool tips can pass on their paths %d done (%.1f %%), "
                         "%d with path_error_max <= %.2f m; the other %d cannot be done on their paths by any "
                         "controller (tips_pass.py proves it), %d of them done anyway" % (
                             s, len(ok), okd, 100.0 * okd / max(1, len(ok)), okb, PNP_PATH_ERROR, n - len(ok),
                             sum(1 for r, b in zip(rs, blk) if b and r["cls"] in ("completed", "late"))))
        if not have_pe:
            lines.append("pick and place, %s: max_err (to the path's current point, an upper bound on the path "
                         "error) <= %.2f m on %d of %d" % (s, PNP_PATH_ERROR, me_ok, n))
    return out


def table(tasks, schemes, sim, a):
    reach = [t for t in tasks if t.get("reachable")]
    nr = len(reach)
    lines = []
    kinds = sorted({t["id"].split(":")[0] for t in tasks})
    lines.append("mca-sweep: seed %d, kinds %s, %d tasks, %d reachable, %d unreachable%s" % (
        a.seed, ",".join(kinds), len(tasks), nr, len(tasks) - nr,
        "" if sim.stop_at else "; this mca-sim has no --stop-at: the stop rows are n/a"))
    hdr = "%-8s %-9s" % ("scheme", "run") + "".join(" %15s" % c for c in CLASSES) + " %10s %9s %17s" % (
        "deadlocks", "lost p50", "path err p50/max")
    lines.append(hdr)
    lines.append("-" * len(hdr))
    summary = {}
    for s in schemes:
        for mode in ("task", "stop"):
            rs = [t["runs"][s][mode] for t in reach if mode in t["runs"].get(s, {}) and t["runs"][s][mode]["cls"] != "n/a"]
            if not rs:
                lines.append("%-8s %-9s" % (s, "task" if mode == "task" else "with stop") +
                             "".join(" %15s" % "n/a" for _ in CLASSES) + " %10s %9s %17s" % ("n/a", "n/a", "n/a"))
                summary["%s/%s" % (s, mode)] = None
                continue
            cnt = {c: sum(1 for r in rs if r["cls"] == c) for c in CLASSES}
            dl = [r.get("deadlocks") for r in rs]
            dls = "n/a" if all(x is None for x in dl) else str(sum(1 for x in dl if x))
            lost = sorted(r["lost"] for r in rs if r.get("lost") is not None)
            lp = "n/a" if not lost else "%.2f s" % lost[len(lost) // 2]
            pe = sorted(r["path_error_max"] for r in rs if r.get("path_error_max") is not None)
            pes = "n/a" if not pe else "%.4f/%.4f m" % (pe[len(pe) // 2], pe[-1])
            lines.append("%-8s %-9s" % (s, "task" if mode == "task" else "with stop") +
                         "".join(" %6d (%5.1f%%)" % (cnt[c], 100.0 * cnt[c] / nr) for c in CLASSES) +
                         " %10s %9s %17s" % (dls, lp, pes))
            faults = {}
            for r in rs:
                if r["cls"] in ("exact-missed", "safe-stop", "unsafe") and r.get("reason"):
                    faults[r["reason"]] = faults.get(r["reason"], 0) + 1
            summary["%s/%s" % (s, mode)] = dict(cnt, n=len(rs), reachable=nr, tasks_with_deadlocks=None if dls == "n/a" else int(dls),
                                                reasons=faults, path_error_max_p50=pe[len(pe) // 2] if pe else None,
                                                path_error_max_max=pe[-1] if pe else None)
    lines.append("")
    un = {}
    for t in tasks:
        if not t.get("reachable"):
            un[t.get("unreachable", "?")] = un.get(t.get("unreachable", "?"), 0) + 1
    lines.append("unreachable (MVN cannot track alone): %d %s" % (len(tasks) - nr, json.dumps(un, sort_keys=True)))
    # paths that run into another arm standing at its start (rest_conflicts): reported apart, never dropped
    clear = [t for t in reach if not t.get("rest_conflicts")]
    rest = [t for t in reach if t.get("rest_conflicts")]
    if any("rest_conflicts" in t for t in reach):
        for s in schemes:
            dc, dr = [sum(1 for t in ts if t["runs"].get(s, {}).get("task", {}).get("cls") in ("completed", "late"))
                      for ts in (clear, rest)]
            lines.append("paths clear of the other arms at rest: %d of %d reachable; %s done (completed or late) on "
                         "them %d (%.1f %%), on the %d others %d" % (
                             len(clear), nr, s, dc, 100.0 * dc / max(1, len(clear)), len(rest), dr))
            summary["clear/%s" % s] = dict(clear=len(clear), done=dc, rest=len(rest), rest_done=dr)
    # tool tips that cannot pass on their paths whatever the arms do (tips_pass.py): reported apart, never dropped
    if reach and all("tips_blocked" in t for t in reach):
        passable = [t for t in reach if not t["tips_blocked"]]
        for s in schemes:
            dp, db = [sum(1 for t in ts if t["runs"].get(s, {}).get("task", {}).get("cls") in ("completed", "late"))
                      for ts in (passable, [t for t in reach if t["tips_blocked"]])]
            lines.append("tool tips that can pass on their paths: %d of %d reachable; %s done on them %d (%.1f %%), on "
                         "the %d others (no controller completes them on their paths above d1) %d" % (
                             len(passable), nr, s, dp, 100.0 * dp / max(1, len(passable)), nr - len(passable), db))
            summary["tips_pass/%s" % s] = dict(passable=len(passable), done=dp, blocked=nr - len(passable),
                                               blocked_done=db)
    # a schedule on the paths found in the coordination diagram (--witness): a proof that the task can be done
    if reach and any(t.get("witness", {}).get("feasible") is not None for t in reach):
        wit = [t for t in reach if t.get("witness", {}).get("feasible")]
        nowit = [t for t in reach if not t.get("witness", {}).get("feasible")]
        for s in schemes:
            dw, dn = [sum(1 for t in ts if t["runs"].get(s, {}).get("task", {}).get("cls") in ("completed", "late"))
                      for ts in (wit, nowit)]
            mono = sum(1 for t in wit if t["witness"].get("monotone"))
            lines.append("tasks with a schedule on their paths (coord_diagram.py: a proof they can be done): %d of %d "
                         "reachable (%d without backing off); %s done on them %d (%.1f %%), on the %d without one "
                         "(undecided or infeasible) %d"
                         % (len(wit), nr, mono, s, dw, 100.0 * dw / max(1, len(wit)), len(nowit), dn))
            summary["witness/%s" % s] = dict(witnessed=len(wit), done=dw, others=len(nowit), others_done=dn)
            for t in wit:
                r = t["runs"].get(s, {}).get("task", {})
                if r.get("cls") not in ("completed", "late", None):
                    lines.append("  witnessed, not done: %s %s %s (%s)" % (
                        s, t["id"], r.get("reason", ""),
                        "a schedule without backing off exists" if t["witness"].get("monotone") else
                        "only by backing off"))
    # random cells (--cells): every link keeps each fixed body's clearance (the table, the obstacles)
    if any(t.get("bodies") for t in reach):
        mb = [t for t in reach if t.get("mvn_body_ticks_below")]
        lines.append("cells: %d reachable tasks with a table and 1-3 obstacles; under MVN (no rows) %d of them come "
                     "below a body's clearance" % (sum(1 for t in reach if t.get("bodies")), len(mb)))
        for s in schemes:
            for mode in ("task", "stop"):
                rs = [t["runs"][s][mode] for t in reach if t["runs"].get(s, {}).get(mode, {}).get("bodies")]
                if not rs:
                    continue
                below = [r for r in rs if r.get("body_ticks_below")]
                mm = sorted(r["body_min_margin"] for r in rs)
                lines.append("cells %-6s %-9s %d runs with bodies: %d with ticks below a clearance (%d ticks); least "
                             "margin p50 %.4f m, min %.4f m" % (
                                 s, "task" if mode == "task" else "with stop", len(rs), len(below),
                                 sum(r["body_ticks_below"] for r in below), mm[len(mm) // 2], mm[0]))
                summary["cells/%s/%s" % (s, mode)] = dict(runs=len(rs), below=len(below), min_margin=mm[0])
    # the streamed sphere (--cells, odd tasks): ticks below clearance per pair kind; arm-sphere apart by whether
    # that arm was at rest (the sphere walked into it) or moving (must be 0)
    sph = [t for t in reach if t.get("sphere")]
    if sph:
        lines.append("sphere: %d reachable tasks with a streamed sphere crossing between the arms (%.1f-%.1f m/s, "
                     "%g ms latency, %g %% of samples lost), %d without" % (
                         len(sph), min(t["sphere"]["speed"] for t in sph), max(t["sphere"]["speed"] for t in sph),
                         1e3 * cells.SPHERE_LATENCY, 100 * cells.SPHERE_LOSS, nr - len(sph)))
        for s in schemes:
            for mode in ("task", "stop"):
                for label, ts in (("sphere", sph), ("no sphere", [t for t in reach if not t.get("sphere")])):
                    rs = [t["runs"][s][mode] for t in ts if t["runs"].get(s, {}).get(mode, {}).get("cls", "n/a") != "n/a"]
                    if not rs:
                        continue

                    def tot(k):
                        return sum(r.get(k) or 0 for r in rs)
                    done = sum(1 for r in rs if r["cls"] in ("completed", "late"))
                    pe = sorted(r["path_error_max"] for r in rs if r.get("path_error_max") is not None)
                    row = dict(runs=len(rs), arm_arm=tot("arm_ticks_below"), arm_body=tot("body_ticks_below"),
                               self=tot("self_ticks_below"), done=done,
                               path_error_max_p50=pe[len(pe) // 2] if pe else None,
                               path_error_max_max=pe[-1] if pe else None)
                    txt = ("sphere %-6s %-9s %-9s %3d runs: ticks below clearance arm-arm %d, arm-body %d, self %d" % (
                        s, "task" if mode == "task" else "with stop", label, len(rs), row["arm_arm"], row["arm_body"],
                        row["self"]))
                    if label == "sphere":
                        within = [r for r in rs if (r.get("track_min_margin") or 1e9) < 0]
                        row.update(track_rest=tot("track_ticks_rest"), track_moving=tot("track_ticks_moving"),
                                   track_braking=tot("track_ticks_braking"),
                                   within_sp=len(within),
                                   true_min_d=min(r.get("sphere_true_min_d", 1e9) for r in rs),
                                   sp_max=max(r.get("track_sp_max") or 0 for r in rs))
                        txt += (", arm-sphere at rest %d / moving %d (%d braking) (sphere inside S_p in %d runs, S_p up "
                                "to %.3f m, least distance to it %.3f m)" % (
                                    row["track_rest"], row["track_moving"], row["track_braking"], len(within),
                                    row["sp_max"], row["true_min_d"]))
                    txt += "; done %d (%.1f %%), path err p50/max %s" % (
                        done, 100.0 * done / len(rs), "n/a" if not pe else "%.4f/%.4f m" % (pe[len(pe) // 2], pe[-1]))
                    lines.append(txt)
                    summary["sphere/%s/%s/%s" % (s, mode, label.replace(" ", "_"))] = row
    for s in schemes:
        for mode in ("task", "stop"):
            v = summary.get("%s/%s" % (s, mode))
            if v and v["reasons"]:
                lines.append("reasons %-6s %-9s %s" % (s, "task" if mode == "task" else "with stop",
                                                     json.dumps(v["reasons"], sort_keys=True)))
    # the solver's work per tick, running and braking, task and stop runs
    for s in schemes:
        rs = [t["runs"][s][m] for t in reach for m in ("task", "stop") if t["runs"].get(s, {}).get(m, {}).get("solves")]
        if rs:
            n = sum(r["solves"] for r in rs)
            un = sum(r["solves_unconverged"] for r in rs)
            lines.append("solver %-6s %d solves (running and braking): steps p50 <= %d, p99.9 <= %d, max %d; exact "
                         "solves p50 <= %d, p99.9 <= %d, max %d (per-run percentiles, their largest); unconverged %d "
                         "(%.3f %%)" % (s, n, max(r["solve_steps"][0] for r in rs), max(r["solve_steps"][1] for r in rs),
                                        max(r["solve_steps"][2] for r in rs), max(r["exact_solves"][0] for r in rs),
                                        max(r["exact_solves"][1] for r in rs), max(r["exact_solves"][2] for r in rs),
                                        un, 100.0 * un / n))
            summary["solver/%s" % s] = dict(solves=n, unconverged=un)
    # the path error while braking after the stop request (the stop keeps the rows, not the path: docs/scheme.md
    # section 11): the stop runs' largest, per scheme
    for s in schemes:
        pe = sorted(t["runs"][s]["stop"]["path_error_brake_max"] for t in reach
                    if t["runs"].get(s, {}).get("stop", {}).get("path_error_brake_max") is not None)
        if pe:
            lines.append("braking  %-6s path error after the stop request over %d stop runs: p50 %.4f m, p99 %.4f m, "
                         "max %.4f m" % (s, len(pe), pe[len(pe) // 2], pe[int(0.99 * (len(pe) - 1))], pe[-1]))
    # every unfinished task named: where it ended (the closest pair, its distance, the tool tips, the clocks),
    # and whether an arm that had finished was in the way (no path rate can move it: the paths conflict at rest)
    blocked_by_done, no_schedule = {}, {}
    for t in reach:
        for s in schemes:
            r = t["runs"].get(s, {}).get("task", {})
            if r.get("cls") in ("safe-stop", "exact-missed") and r.get("end_pair") is not None:
                p = r["end_pair"]
                done = [a for a, x in enumerate(r.get("end_done") or []) if x]
                lines.append("unfinished %-6s %-16s %-20s pair arm%d.link%d-arm%d.link%d d %.4f m, tips %s, clocks %s s%s" % (
                    s, t["id"], r.get("reason", ""), p[0], p[1], p[2], p[3], r["end_distance"],
                    " ".join("[%.3f %.3f %.3f]" % tuple(e) for e in r["end_ee"]),
                    "/".join("%.2f" % x for x in r["end_tau"]),
                    ("; blocked by %s at its path's end" % ", ".join("arm%d" % a for a in done) if done else "") +
                    ("; no schedule: the predicted arms meet on every order of passing" if r.get("coord_unplanned")
                     else "")))
                if done:
                    blocked_by_done[s] = blocked_by_done.get(s, 0) + 1
                if r.get("coord_unplanned"):
                    no_schedule[s] = no_schedule.get(s, 0) + 1
    for s, n in sorted(blocked_by_done.items()):
        lines.append("unfinished %s: %d blocked by an arm standing at its path's end" % (s, n))
        summary["blocked_by_done/%s" % s] = n
    for s, n in sorted(no_schedule.items()):
        lines.append("unfinished %s: %d without a coordination schedule (fixed paths that meet whoever goes first)"
                     % (s, n))
        summary["no_schedule/%s" % s] = n
    # distances: where the tasks start and how near the arms come (does avoidance matter?)
    d0 = sorted(t["start_distance"] for t in reach)
    if d0:
        parts = []
        for s in schemes:
            md = sorted(t["runs"][s]["task"]["min_d"] for t in reach if "min_d" in t["runs"].get(s, {}).get("task", {}))
            if md:
                below = sum(1 for t in reach if t["runs"][s]["task"].get("min_d", 1e9) < t["d1"])
                parts.append("%s p50 %.4f min %.4f (%d below d1)" % (s, md[len(md) // 2], md[0], below))
        lines.append("distance [m]: start p50 %.4f min %.4f; least in the task runs: %s" % (
            d0[len(d0) // 2], d0[0], "; ".join(parts)))
    pnp = [t for t in reach if t["id"].rsplit(":", 1)[0] in PNP]
    if pnp:
        summary["pnp_target"] = pnp_target(pnp, schemes, lines)
    sc = [r for t in tasks if t.get("reachable") and t.get("stopcheck") for r in t["stopcheck"]]
    if a.stopcheck:
        for dec in sorted({r["dec"] for r in sc}):
            rs = [r for r in sc if r["dec"] == dec]
            lines.append("stops every 20 ms, mca-ts, dec %.3g rad/s^2: %d tasks, %d stops, %d below d1 (%d tasks), "
                         "least distance %.4f m over task and brakes, max |dv|/(dec dt) %.4f, longest stop %.3f s, "
                         "fallback ticks %d of %d"
                         % (dec, len(rs), sum(r["stops"] for r in rs), sum(r["below_d1"] for r in rs),
                            sum(1 for r in rs if r["below_d1"] or r["min_distance_task"] < 0),
                            min(min(r["min_distance_task"], r["min_distance_brake"]) for r in rs),
                            max(r["max_dv_ratio"] for r in rs), max(r["longest_stop_s"] for r in rs),
                            sum(r["fallback_ticks"] for r in rs), sum(r["brake_ticks"] for r in rs)))
        summary["stopcheck"] = sc and {"stops": sum(r["stops"] for r in sc), "below_d1": sum(r["below_d1"] for r in sc)}
    secs = sorted(t.get("seconds", 0) for t in tasks)
    if secs:
        lines.append("runtime per task (all its mca-sim runs): median %.2f s, max %.2f s" % (secs[len(secs) // 2], secs[-1]))
    return "\n".join(lines), summary


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--sim", default=os.path.join(ROOT, "build", "tools", "mca-sim", "mca-sim"))
    ap.add_argument("--kind", default="pa10", help="pa10, jaco-mico, three, pnp-jaco-mico, pnp-pa10, comma-separated")
    ap.add_argument("--n", default="50", help="tasks per kind (one number, or one per kind: 500,500,200)")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--only", default="", help="task ids KIND:I[,KIND:I...] (or plain I for the first kind)")
    ap.add_argument("--schemes", default="mvn,mca,mca-ts")
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--work", default="")
    ap.add_argument("--json", default="")
    ap.add_argument("--table", default="", help="also write the table to this file")
    ap.add_argument("--lost-threshold", type=float, default=0.1, help="s of path time lost that still count as completed")
    ap.add_argument("--max-err", type=float, default=0.005, help="MVN tracking error that makes a task unreachable [m]")
    ap.add_argument("--no-stop", action="store_true", help="no second run with a stop request")
    ap.add_argument("--dec-limit", type=float, default=0.0, help="pass --dec-limit X to mca-sim (when it has it)")
    ap.add_argument("--stopcheck", default="", help="path of mca-stopcheck: also branch stops off every "
                    "reachable task every 20 ms (mca-ts, arms integrated as commanded)")
    ap.add_argument("--stop-decs", default="0.5,2,5", help="dec limits for --stopcheck [rad/s^2]")
    ap.add_argument("--ideal-arms", action="store_true",
                    help="mca-sim --euler: arms realise each command exactly (default: the sim backend's "
                         "rate-limited firmware model)")
    ap.add_argument("--tolerance", type=float, default=None,
                    help="write `tolerance: X` (path error allowed outside exact points [m]) into every generated "
                    "path, when this mca-sim takes the key")
    ap.add_argument("--elastic", action="store_true",
                    help="crossing kinds: write `tracking: elastic` into every generated path (the L2 slack that "
                    "passes by leaving the path; default: path first)")
    ap.add_argument("--no-coordinate", action="store_true",
                    help="mca-sim --no-coordinate: mca-ts without the start-up plan of who passes first")
    ap.add_argument("--cells", action="store_true",
                    help="random cells: a table and 1-3 boxes or posts in every task (cells.py; the same tasks)")
    ap.add_argument("--witness", default="", help="path of mca-geom: also look for a schedule on the paths in "
                    "each two-arm task's coordination diagram (coord_diagram.py; ~5-20 s a task)")
    ap.add_argument("--sphere", action="store_true",
                    help="with --cells: a streamed sphere crossing between the arms in every odd task (mca-sim's "
                    "simulated_sphere, 0.3-2.0 m/s, 30 ms latency, 1 %% of samples lost)")
    ap.add_argument("--self-pairs", action="store_true",
                    help="every arm's self pairs (its robot's list, ROBOT.self.yaml) in every task: self rows, and "
                    "their ticks below d1 counted")
    ap.add_argument("--keep", action="store_true", help="keep the work dir (default: removed unless --work is given)")
    a = ap.parse_args()
    global SELF_PAIRS, SPHERE
    SELF_PAIRS = a.self_pairs
    SPHERE = a.sphere
    if a.sphere and not a.cells:
        sys.exit("mca-sweep: --sphere needs --cells")
    if not os.access(a.sim, os.X_OK):
        sys.exit("mca-sweep: %s: no mca-sim there (--sim)" % a.sim)
    sim = Sim(a.sim)
    kinds = [k for k in a.kind.split(",") if k]
    for k in kinds:
        if k not in KINDS:
            sys.exit("mca-sweep: unknown kind '%s' (%s)" % (k, ", ".join(KINDS)))
    ns = [int(x) for x in a.n.split(",")]
    if len(ns) == 1:
        ns = ns * len(kinds)
    if len(ns) != len(kinds):
        sys.exit("mca-sweep: --n: one count, or one per kind")
    schemes = [s for s in a.schemes.split(",") if s]
    missing = [s for s in schemes if s not in sim.schemes]
    if missing:
        print("mca-sweep: this mca-sim has no scheme %s (it has %s): left out" % (",".join(missing), "|".join(sim.schemes)))
        schemes = [s for s in schemes if s in sim.schemes]
    a.schemes = schemes
    if a.tolerance is not None and not sim.keys["tolerance"]:
        print("mca-sweep: this mca-sim takes no path key `tolerance`: --tolerance %g left out" % a.tolerance)
    todo = []
    if a.only:
        for x in a.only.split(","):
            k, _, i = x.rpartition(":")
            todo.append((k or kinds[0], int(i)))
    else:
        for k, n in zip(kinds, ns):
            todo += [(k, i) for i in range(n)]
    tmp = not a.work
    if tmp:
        import tempfile
        a.work = tempfile.mkdtemp(prefix="mca-sweep-")
    os.makedirs(a.work, exist_ok=True)
    t0 = time.time()
    tasks = []
    with cf.ThreadPoolExecutor(max_workers=max(1, a.jobs)) as ex:
        futs = {ex.submit(run_task, sim, k, a.seed, i, a): (k, i) for k, i in todo}
        for n, f in enumerate(cf.as_completed(futs)):
            tasks.append(f.result())
            if (n + 1) % 50 == 0:
                print("mca-sweep: %d/%d tasks, %.0f s" % (n + 1, len(todo), time.time() - t0), file=sys.stderr)
    order = {kd: i for i, kd in enumerate(todo)}
    tasks.sort(key=lambda t: order[(t["id"].rsplit(":", 1)[0], int(t["id"].rsplit(":", 1)[1]))])
    txt, summ = table(tasks, schemes, sim, a)
    by_kind = {}
    if len(kinds) > 1:
        for k in kinds:
            kt = [t for t in tasks if t["id"].rsplit(":", 1)[0] == k]
            if kt:
                ktxt, by_kind[k] = table(kt, schemes, sim, a)
                txt += "\n\n" + ktxt
    txt += "\nwall time %.1f s with --jobs %d; repeat one task: --seed %d --kind K --only K:I" % (time.time() - t0, a.jobs, a.seed)
    print(txt)
    if a.table:
        with open(a.table, "w") as f:
            f.write(txt + "\n")
    if a.json:
        out = dict(seed=a.seed, kinds=kinds, n=ns, only=a.only, schemes=schemes, sim=a.sim,
                   features=dict(stop_at=sim.stop_at, fault_at=sim.fault_at, dec_limit=sim.dec_limit,
                                 summary_fields=sorted(sim.fields), scenario_keys=sim.keys),
                   tolerance=a.tolerance if sim.keys["tolerance"] else None,
                   lost_threshold=a.lost_threshold, max_err=a.max_err, summary=summ, summary_by_kind=by_kind,
                   reachable=sum(1 for t in tasks if t.get("reachable")), tasks=tasks, wall_s=round(time.time() - t0, 2))
        with open(a.json, "w") as f:
            json.dump(out, f, indent=1)
    if tmp and not a.keep:
        shutil.rmtree(a.work, ignore_errors=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
