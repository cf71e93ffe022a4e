#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Runs the mca-geom tool on good and bad input and checks numbers (known answers) and exit codes.
usage: test_mca_geom.py MCA_GEOM ROBOTS_DIR EXACT_CASES_TXT"""
from fractions import Fraction
import math
import os
import subprocess
import sys
import tempfile

TOOL = sys.argv[1]
ROBOTS = sys.argv[2]
EXACT_CASES = sys.argv[3]
MIN_EXACT_CASES = 21  # as many as exact_cases.txt holds today (segdist.unit checks the same count)
failures = 0


def run(args, stdin=""):
    p = subprocess.run([TOOL] + args, input=stdin, capture_output=True, text=True, timeout=30)
    return p.returncode, p.stdout, p.stderr


def check(cond, what):
    global failures
    if not cond:
        failures += 1
        print("FAIL:", what)
    else:
        print("ok:  ", what)


def close(a, b, tol):
    return all(abs(x - y) <= tol for x, y in zip(a, b)) and len(a) == len(b)


def rows(out):
    return [[float(x) for x in ln.split()] for ln in out.splitlines() if ln.strip()]


# --- segdist: known answers ---
GOOD = """# crossing perpendicular segments 0.3 apart
-1 0 0 1 0 0 0 -1 0.3 0 1 0.3

   # collinear disjoint: P = B, E = C, d = 2
0 0 0 1 0 0 3 0 0 5 0 0
0 0 0 1 0 0 1 -1 0 1 1 0
1 2 3 1 2 3 4 6 3 4 6 3
"""
EXPECT = [
    [0.3, 0, 0, 0, 0, 0, 0.3],
    [2, 1, 0, 0, 3, 0, 0],
    [0, 1, 0, 0, 1, 0, 0],
    [5, 1, 2, 3, 4, 6, 3],
]
for method, tol in (("closed", 1e-15), ("lsdm", 1e-9), ("lsdm-cert", 1e-9)):
    rc, out, err = run(["segdist", "--method", method], GOOD)
    r = rows(out)
    check(rc == 0 and len(r) == 4, f"segdist {method}: exit 0, 4 answers (comments/blank skipped) [{rc} {err}]")
    for i, exp in enumerate(EXPECT):
        check(i < len(r) and close(r[i][:7], exp, tol), f"segdist {method}: line {i} = {exp}")
    iters = [int(x[7]) for x in r]
    if method == "closed":
        check(all(i == 0 for i in iters), "closed form reports 0 iterations")
    else:
        # the paper's rule needs two projections to see a decline; the certificate may stop after one
        least = 2 if method == "lsdm" else 1
        check(all(i >= least for i in iters), f"{method} reports >= {least} projections {iters}")
# default method is the closed form, output is %.17g (round-trips)
rc, out, _ = run(["segdist"], "0 0 0 1 0 0 0.1 0.2 0 0.1 0.2 1\n")
check(rc == 0 and float(out.split()[0]) == 0.2 and float(out.split()[1]) == 0.1 and len(out.split()[0]) >= 17,
      "default closed, %.17g output: " + out.strip())

# paper's tolerance on a near-parallel pair stops early (documented behaviour), closed form does not
NEARPAR = "0 0 0 1 0 0 -1 0.1 -1e-3 1 0.1 1e-3\n"
rc, out, _ = run(["segdist", "--method", "lsdm", "--tol", "1e-5"], NEARPAR)
d_lsdm = float(out.split()[0])
rc2, out2, _ = run(["segdist"], NEARPAR)
check(rc == 0 and abs(float(out2.split()[0]) - 0.1) < 1e-15, "closed: near-parallel d = 0.1")
# B -> H1 = (x', 0.1, 1e-3 x') with x' = 1 / (1 + 1e-6); H1 -> (x', 0, 0): d = sqrt(0.01 + 1e-6 x'^2)
check(abs(d_lsdm - math.sqrt(0.01 + 1e-6 / (1 + 1e-6) ** 2)) < 1e-14, f"lsdm tol 1e-5 stops early at {d_lsdm}")
rc, out, err = run(["segdist", "--method", "lsdm-cert", "--tol", "1e-9", "--max-iter", "50"], NEARPAR)
check(rc == 0 and "cap" in err and len(rows(out)) == 1, "lsdm-cert at its cap: answer printed + warning")

# --- segdist: the hand-derived exact hard cases of exact_cases.txt (also checked on the library by
# segdist.unit), through the tool, in both orders (D C B A swaps P and E) ---
def load_exact_cases(path):
    cases = []
    with open(path) as f:
        for lineno, ln in enumerate(f, 1):
            ln = ln.strip()
            if not ln or ln.startswith("#"):
                continue
            name, seg, d, pe = (x.strip() for x in ln.split("|"))  # exactly 4 fields, else ValueError
            seg = [float(x) for x in seg.split()]
            pe = None if pe == "-" else [float(x) for x in pe.split()]
            assert len(seg) == 12 and (pe is None or len(pe) == 6), f"{path}:{lineno}: bad case"
            cases.append((name, seg, float(d), pe))
    return cases


def seg_point_dist_exact(x, a, b):
    """Distance from x to segment ab, in exact rational arithmetic on the given doubles."""
    x, a, b = ([Fraction(v) for v in p] for p in (x, a, b))
    u = [bi - ai for ai, bi in zip(a, b)]
    w = [xi - ai for ai, xi in zip(a, x)]
    uu = sum(c * c for c in u)
    t = min(max(sum(p * q for p, q in zip(w, u)) / uu, Fraction(0)), Fraction(1)) if uu else Fraction(0)
    return math.sqrt(sum((wi - t * ui) ** 2 for wi, ui in zip(w, u)))


cases = load_exact_cases(EXACT_CASES)
check(len(cases) >= MIN_EXACT_CASES, f"exact cases: {len(cases)} read from {EXACT_CASES}")
swapped = [seg[9:12] + seg[6:9] + seg[3:6] + seg[0:3] for _, seg, _, _ in cases]
stdin = "".join(" ".join(repr(v) for v in seg) + "\n" for seg in [c[1] for c in cases] + swapped)
rc, out, err = run(["segdist", "--method", "closed"], stdin)
r = rows(out)
check(rc == 0 and len(r) == 2 * len(cases), f"exact cases: exit 0, {2 * len(cases)} answers [{rc} {err.strip()}]")
TOL = 1e-12
worst_d = worst_pe = 0.0
for i, (name, seg, d, pe) in enumerate(cases):
    for order, row in (("", i), (" (swapped)", len(cases) + i)):
        if row >= len(r):
            check(False, f"exact case {name}{order}: no answer")
            continue
        got = r[row]
        segs = seg if not order else swapped[i]
        P, E = got[1:4], got[4:7]
        err_d = abs(got[0] - d)
        worst_d = max(worst_d, err_d) if err_d == err_d else math.inf  # a NaN counts as a failure
        ok = err_d <= TOL and len(got) == 8 and got[7] == 0
        # P on the first segment, E on the second, |P - E| = d (all that is defined when P, E are not unique)
        ok = ok and seg_point_dist_exact(P, segs[0:3], segs[3:6]) <= TOL
        ok = ok and seg_point_dist_exact(E, segs[6:9], segs[9:12]) <= TOL
        ok = ok and abs(math.dist(P, E) - d) <= TOL
        what = "d, P on AB, E on CD"
        if pe is not None:
            expP, expE = (pe[0:3], pe[3:6]) if not order else (pe[3:6], pe[0:3])
            e_pe = max(abs(x - y) for x, y in zip(P + E, expP + expE))
            worst_pe = max(worst_pe, e_pe) if e_pe == e_pe else math.inf
            ok = ok and e_pe <= TOL
            what = "d, P, E"
        check(ok, f"exact case {name}{order}: {what} within {TOL:g}: {got}")
print(f"exact cases through the tool: max |d - exact| = {worst_d:.3g}, max |P, E - exact| = {worst_pe:.3g}")

# --- segdist: bad input ---
for bad, lineno, answered, what in (
    ("0 0 0 1 0 0 0 -1 0.3 0 1 0.3\n\n1 2 3\n", 3, 1, "wrong count"),
    ("0 0 0 1 0 0 0 -1 0.3 0 1 0.3\n0 0 0 1 0 0 0 -1 0.3 0 1 0.3 7\n", 2, 1, "too many"),
    ("0 0 0 1 0 0 0 -1 0.3 0 1 0.3\n0 0 0 1 0 0 0 -1 abc 0 1 0.3\n", 2, 1, "non-number"),
    ("0 0 0 1 0 0 0 -1 0.3 0 1 0.3\n#\n0 0 0 1 0 0 0 -1 nan 0 1 0.3\n", 3, 1, "NaN"),
    ("0 0 0 1 0 0 0 -1 0.3 0 1 inf\n", 1, 0, "inf"),
    ("0 0 0 1 0 0 0 -1 0.3 0 1 1e999\n", 1, 0, "overflow"),
    ("0 0 0 1 0 0 0 -1 0.3 0 1 0.3x\n", 1, 0, "trailing junk"),
    ("0 0 0 1 0 0 0 -1 0.3 0 1 0.3\n1e200 0 0 -1e200 0 0 0 -1 0.3 0 1 0.3\n", 2, 1, "beyond 1e100"),
):
    rc, out, err = run(["segdist"], bad)
    r = rows(out)
    check(rc == 2 and f"line {lineno}:" in err and len(r) == answered and all(abs(x[0] - 0.3) < 1e-15 for x in r),
          f"segdist {what}: exit 2, 'line {lineno}' on stderr, {answered} earlier answer(s) [{rc} {err.strip()}]")
rc, _, err = run(["segdist", "--method", "dpsl"], "")
check(rc == 2 and "dpsl" in err, "unknown method: exit 2")
rc, _, err = run(["segdist", "--tol", "-1"], "")
check(rc == 2, "negative tol: exit 2")

# --- fk ---
pa10 = os.path.join(ROBOTS, "pa10plus.urdf")
jaco = os.path.join(ROBOTS, "jaco2.urdf")


def fk(urdf, q):
    rc, out, err = run(["fk", "--robot", urdf] + [repr(x) for x in q])
    pts = {}
    joints = []
    for ln in out.splitlines():
        f = ln.split()
        if f[0] == "joint":
            joints.append([float(x) for x in f[3:6]])
        else:
            pts[f[0]] = [float(x) for x in f[1:4]]
    return rc, pts, joints, err


# PA10+ at zero stands straight up: 0.317 + 0.45 + 0.48 + 0.07 (flange) + 0.25 (tool) = 1.567 m
rc, pts, joints, err = fk(pa10, [0.0] * 8)
check(rc == 0 and len(joints) == 8, f"fk pa10plus: exit 0, 8 joints [{err}]")
check(close(pts.get("ee", []), [0, 0, 1.567], 1e-12), f"fk pa10plus zero: ee = (0, 0, 1.567): {pts.get('ee')}")
# Only the shoulder pitch S2 moved by pi/2: the straight arm lies horizontal at the shoulder height 0.317 m,
# 1.25 m from the shoulder
rc, pts, joints, err = fk(pa10, [0, math.pi / 2, 0, 0, 0, 0, 0, 0])
ee = pts["ee"]
check(rc == 0 and abs(ee[2] - 0.317) < 1e-12 and abs(math.hypot(ee[0], ee[1]) - 1.25) < 1e-12,
      f"fk pa10plus S2 = pi/2: ee horizontal at z = 0.317, 1.25 m out: {ee}")
# JACO2: base yaw q1 rotates the end effector about z: z and |xy| unchanged
q = [0.3, 2.9, 1.1, -0.4, 0.7, 1.3]
rc, p0, _, _ = fk(jaco, q)
rc1, p1, _, _ = fk(jaco, [q[0] + 0.9] + q[1:])
check(rc == 0 and rc1 == 0 and abs(p0["ee"][2] - p1["ee"][2]) < 1e-12
      and abs(math.hypot(*p0["ee"][:2]) - math.hypot(*p1["ee"][:2])) < 1e-12, "fk jaco2: q1 is a yaw about z")

rc, _, _, err = fk(pa10, [0.0] * 7)
check(rc == 2 and "8 joints" in err, f"fk wrong number of q: exit 2 [{err.strip()}]")
rc, _, _, err = fk(pa10, [0.0] * 9)
check(rc == 2, f"fk too many q: exit 2 [{err.strip()}]")
rc, out, err = run(["fk", "--robot", pa10, "0", "0", "zero", "0", "0", "0", "0", "0"])
check(rc == 2 and "zero" in err, f"fk non-numeric q: exit 2 [{err.strip()}]")
with tempfile.TemporaryDirectory() as td:
    bad = os.path.join(td, "broken.urdf")
    with open(bad, "w") as f:
        f.write("<robot name='x'><link name='a'/><joint name='j' type='revolute'><parent link='a'/>")
    rc, out, err = run(["fk", "--robot", bad, "0"])
    check(rc == 2 and "broken.urdf" in err, f"fk malformed URDF: exit 2, names the file [{err.strip()}]")
rc, _, err = run(["fk", "--robot", "/nonexistent/robot.urdf", "0"])
check(rc == 2 and "/nonexistent/robot.urdf" in err, "fk missing file: exit 2")
rc, _, err = run(["fk", "0", "0"])
check(rc == 2, "fk without --robot: exit 2")

# --- armdist ---
# two PA10+ straight up, 1 m apart (B yawed about its own vertical axis): the axes are parallel vertical
# lines 1 m apart; the closest capsules are the two base spheres (radius 0.08 in the URDF): 1 - 0.16
zero8 = ",".join(["0"] * 8)
rc, out, err = run(["armdist", "--robot-a", pa10, "--qa", zero8, "--robot-b", pa10, "--base-b", "1,0,0,0,0,2",
                    "--qb", zero8])
lines = {ln.split()[0]: ln.split() for ln in out.splitlines()}
m = [float(x) for x in lines.get("min", ["min"] + ["nan"] * 10)[1:]]
check(rc == 0 and abs(m[2] - 0.84) < 1e-12 and abs(m[3] - 1.0) < 1e-12 and abs(m[7] - m[4] - 1.0) < 1e-12,
      f"armdist two PA10+ 1 m apart: min 0.84, axis 1, E - P = +x [{err.strip()}] {m}")
check(sum(1 for ln in out.splitlines() if ln.startswith("a_to_b")) == 9, "armdist: 9 a_to_b rows for 8 DOF")
rc, out2, _ = run(["armdist", "--robot-a", pa10, "--qa", zero8, "--robot-b", pa10, "--base-b", "1,0,0,0,0,2",
                   "--qb", zero8, "--method", "lsdm"])
check(rc == 0 and out2.splitlines()[0] == out.splitlines()[0] and int(out2.split()[-1]) > 0,
      "armdist --method lsdm: same minimum here (parallel axes, endpoint answers), counts iterations")
rc, _, err = run(["armdist", "--robot-a", pa10, "--qa", "0,0,0", "--robot-b", pa10, "--qb", zero8])
check(rc == 2 and "8 joints" in err, f"armdist wrong q count: exit 2 [{err.strip()}]")
rc, _, err = run(["armdist", "--robot-a", pa10, "--qa", zero8, "--robot-b", pa10, "--qb", zero8, "--base-b", "1,2"])
check(rc == 2 and "base-b" in err, f"armdist bad base: exit 2 [{err.strip()}]")

# --- help / usage ---
rc, out, _ = run(["--help"])
check(rc == 0 and "segdist" in out and "fk --robot" in out, "--help: exit 0, lists commands")
rc, _, err = run(["frobnicate"])
check(rc == 2 and "frobnicate" in err, "unknown command: exit 2")

print(f"{failures} failure(s)")
sys.exit(1 if failures else 0)
