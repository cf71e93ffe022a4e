# SPDX-License-Identifier: MIT
"""mcad's pairs of every kind on DDS (mca/pair_distances), against independent truth: a 3 s run of two PA10+
arms (the left one draws a circle twice) in a cell with a table plane under both bases (their bases allowed), a
turned box and a sphere near the arms, and the left arm's self pairs. A Python subscriber takes every
PairDistances and JointState sample and, per published tick, rebuilds each link capsule from the published joint
positions (the chain's points from `mca-geom fk`, the radii read here from the URDF's <collision> shapes) and
checks:
  - one arm-arm entry (arms 0-1), one arm-body entry per body (kind arm-body, its name), one self entry (arm 0,
    kind self), nothing else;
  - each body's distance is the least over the links it does not allow of the truth: python-fcl for the sphere
    (a closed form), a golden-section search for the box (FCL's GJK, about 1e-7 m off, is printed beside), the
    plane's closed form (FCL's plane crashes, tests/segdist), within 1e-6 m, and the link it names is that least one (or ties it within 1e-6 m);
  - the self entry's distance is FCL's capsule-capsule distance of the links it names, and no self pair of the
    robot's list is closer (1e-6 m);
  - the summary on stderr carries the least distance per kind and per body with its time: never above the least
    published, and within 1 cm of what was published within 5 ticks of that time (a subscriber that matched
    after that time, on a loaded machine, says so and checks the first part only).
  - mca-monitor, watching the same run, shows the least distance per kind and each body with its closest link.
usage: test_dds_pairs.py MCAD MCA_GEOM MCA_MONITOR SOURCE_DIR [mcad flags]"""
import math
import os
import re
import subprocess
import sys
import tempfile
import time
import xml.etree.ElementTree as ET

import numpy as np

MCAD, GEOM, MONITOR, SRC = sys.argv[1:5]
EXTRA = sys.argv[5:]
sys.path.insert(0, os.path.join(SRC, "tests", "dds"))
import mca_types as m  # noqa: E402

DOMAIN = 100 + (os.getpid() + 57) % 120
os.environ["CYCLONEDDS_URI"] = "file://" + os.path.join(SRC, "config", "dds", "loopback.xml")

from cyclonedds.domain import DomainParticipant  # noqa: E402
from cyclonedds.sub import DataReader  # noqa: E402
from cyclonedds.topic import Topic  # noqa: E402

import fcl  # noqa: E402  python-fcl, tools/deps/requirements.txt

URDF = os.path.join(SRC, "config", "robots", "pa10plus.urdf")
BASES = ([0.0, -0.6, 0.0], [0.0, 0.6, 0.0])
TOL = 1e-6
BOX = dict(centre=[0.35, -0.35, 0.9], half=[0.05, 0.08, 0.1], yaw=0.4)
SPHERE = dict(centre=[0.3, 0.2, 1.1], radius=0.06)
CELL = f"""name: dds-pairs-test
task: {{duration: 3.0}}
arms:
  - name: left
    backend: sim
    urdf: {URDF}
    base_xyz: {BASES[0]}
    q0: [0.0, 0.5, 0.0, 1.0, 0.0, 0.6, 0.0, 0.0]
    path: {{kind: circle, radius: 0.15, period: 1.5, u: [0, -1, 0], v: [0, 0, 1]}}
  - name: right
    backend: sim
    urdf: {URDF}
    base_xyz: {BASES[1]}
    q0: [0.0, 0.5, 0.0, 1.0, 0.0, 0.6, 0.0, 0.0]
d1: 0.04
d2: 0.13
self_pairs: [left]
bodies:
  - {{name: table, kind: plane, point: [0, 0, 0], normal: [0, 0, 1], clearance: 0.02,
     allow: [left.base, left.1, right.base, right.1]}}
  - {{name: crate, kind: box, centre: {BOX['centre']}, half_extents: {BOX['half']}, rpy: [0, 0, {BOX['yaw']}],
     clearance: 0.01}}
  - {{name: ball, kind: sphere, centre: {SPHERE['centre']}, radius: {SPHERE['radius']}, clearance: 0.01}}
dds: {{enabled: true, domain: {DOMAIN}, config: {SRC}/config/dds/loopback.xml, publish_divisor: 5}}
rt: {{period_us: 1000, priority: 60, overrun_limit: 100000, pdnn_budget_us: 1000000}}
stop_after: 3.0
"""

failures = []


def check(cond, what):
    print(("ok   " if cond else "FAIL ") + what, flush=True)
    if not cond:
        failures.append(what)


def urdf_radii(path):
    """Capsule radius per link as mca's chain takes it: link 0 the root's (and fixed children's) largest
    collision cylinder/sphere radius, link k the k-th moving joint's child link's (and its fixed children's)."""
    root = ET.parse(path).getroot()
    rad = {}
    for ln in root.findall("link"):
        r = 0.0
        for c in ln.findall("collision/geometry/*"):
            if c.tag in ("cylinder", "sphere"):
                r = max(r, float(c.get("radius")))
        rad[ln.get("name")] = r
    children = {j.find("parent").get("link"): j for j in root.findall("joint")}
    out, link, cur = [], None, 0.0
    name = next(n for n in rad if n not in {j.find("child").get("link") for j in root.findall("joint")})
    cur = rad[name]
    while name in children:
        j = children[name]
        child = j.find("child").get("link")
        if j.get("type") == "fixed":
            cur = max(cur, rad[child])
        else:
            out.append(cur)
            cur = rad[child]
        name = child
    out.append(cur)
    return out


RADII = urdf_radii(URDF)


def chain_points(q, base):
    """root, joint origins, tool tip (world) from mca-geom fk (the chain's kinematics; no distance code)."""
    r = subprocess.run([GEOM, "fk", "--robot", URDF] + [repr(x) for x in q], capture_output=True, text=True)
    pts = []
    for line in r.stdout.splitlines():
        f = line.split()
        pts.append(np.array([float(x) for x in f[-3:]]) + np.array(base))
    return pts


def fcl_capsule(a, b, r):
    a, b = np.asarray(a, float), np.asarray(b, float)
    u = b - a
    L = float(np.linalg.norm(u))
    z = u / L if L > 0 else np.array([0.0, 0.0, 1.0])
    # a rotation taking z to the axis
    v = np.cross([0.0, 0.0, 1.0], z)
    s, c = np.linalg.norm(v), z[2]
    if s < 1e-12:
        R = np.eye(3) if c > 0 else np.diag([1.0, -1.0, -1.0])
    else:
        k = v / s
        K = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
        R = np.eye(3) + s * K + (1 - c) * K @ K
    return fcl.CollisionObject(fcl.Capsule(r, L), fcl.Transform(R, (a + b) / 2))


def fcl_distance(o1, o2):
    req = fcl.DistanceRequest(enable_nearest_points=True, gjk_solver_type=fcl.GJKSolverType.GST_INDEP)
    return fcl.distance(o1, o2, req, fcl.DistanceResult())


def box_truth(A, B, r):
    """Capsule (A, B, r) to the box: the segment's least distance to the box (a convex function of the
    segment's parameter: golden-section search to 1e-13) minus r; shares nothing with body.c or FCL."""
    R, c, h = rot_z(BOX["yaw"]), np.array(BOX["centre"]), np.array(BOX["half"])

    def f(t):
        x = R.T @ (A + t * (B - A) - c)
        return float(np.linalg.norm(x - np.clip(x, -h, h)))
    lo, hi, g = 0.0, 1.0, (math.sqrt(5) - 1) / 2
    while hi - lo > 1e-13:
        m1, m2 = hi - g * (hi - lo), lo + g * (hi - lo)
        if f(m1) <= f(m2):
            hi = m2
        else:
            lo = m1
    return min(f(0.0), f(1.0), f(0.5 * (lo + hi))) - r


def rot_z(w):
    c, s = math.cos(w), math.sin(w)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


BOX_OBJ = fcl.CollisionObject(fcl.Box(*(2 * np.array(BOX["half"]))), fcl.Transform(rot_z(BOX["yaw"]), BOX["centre"]))
SPHERE_OBJ = fcl.CollisionObject(fcl.Sphere(SPHERE["radius"]), fcl.Transform(np.eye(3), SPHERE["centre"]))
FCL_BOX_ERR = [0.0]
ALLOW_TABLE = {(0, 0), (0, 1), (1, 0), (1, 1)}


def truth_bodies(pts):
    """{body name: [(distance, arm, link)] over the links it does not allow}"""
    out = {"table": [], "crate": [], "ball": []}
    for a, p in enumerate(pts):
        for l in range(len(p) - 1):
            A, B, r = p[l], p[l + 1], RADII[l]
            cap = fcl_capsule(A, B, r)
            if (a, l) not in ALLOW_TABLE:
                out["table"].append((min(A[2], B[2]) - r, a, l))
            # the exact truth, and FCL's GJK beside it (about 1e-7 m off: FCL's own error, printed)
            d = box_truth(A, B, r)
            FCL_BOX_ERR[0] = max(FCL_BOX_ERR[0], abs(fcl_distance(cap, BOX_OBJ) - d))
            out["crate"].append((d, a, l))
            out["ball"].append((fcl_distance(cap, SPHERE_OBJ), a, l))
    return out


def self_pairs():
    pairs, path = [], os.path.join(SRC, "config", "robots", "pa10plus.self.yaml")
    for line in open(path):
        mm = re.match(r"\s*-\s*\[(\d+),\s*(\d+)\]", line)
        if mm:
            pairs.append((int(mm.group(1)), int(mm.group(2))))
    return pairs


SELF = self_pairs()

dp = DomainParticipant(DOMAIN)
rp = DataReader(dp, Topic(dp, m.TOPIC_PAIR_DISTANCES, m.PairDistances, qos=m.stream_qos()), qos=m.stream_qos())
rj = DataReader(dp, Topic(dp, m.TOPIC_JOINT_STATE, m.JointState, qos=m.stream_qos()), qos=m.stream_qos())

with tempfile.TemporaryDirectory(prefix="mca-dds-pairs-") as tmp:
    cell = os.path.join(tmp, "cell.yaml")
    with open(cell, "w") as f:
        f.write(CELL)
    mon = subprocess.Popen([MONITOR, "--domain", str(DOMAIN), "--config",
                            os.path.join(SRC, "config", "dds", "loopback.xml"), "--duration", "3.5", "--no-color"],
                           stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    proc = subprocess.Popen([MCAD] + EXTRA + [cell], stderr=subprocess.PIPE, text=True)
    pairs, js = [], []
    t_exit = None
    while True:
        pairs += [s for s in rp.take(N=1000) if isinstance(s, m.PairDistances)]
        js += [s for s in rj.take(N=1000) if isinstance(s, m.JointState)]
        if t_exit is None and proc.poll() is not None:
            t_exit = time.monotonic()
        if t_exit is not None and time.monotonic() - t_exit > 1.5:
            break
        time.sleep(0.005)
    err = proc.stderr.read()
    mon_out, mon_err = mon.communicate(timeout=60)
check(proc.returncode == 0, f"mcad exit status {proc.returncode}")
check(len(pairs) >= 200, f"{len(pairs)} PairDistances samples for ~3 s at 200 Hz (first tick "
      f"{min((p.tick for p in pairs), default=None)})")
state = {}
for s in js:
    state.setdefault(s.tick, {})[s.arm_id] = list(s.position)
both = [p for p in pairs if len(state.get(p.tick, {})) == 2]
check(len(both) >= 0.9 * len(pairs), f"{len(both)} of {len(pairs)} samples with both arms' joint states")
# every 16th matched tick against the truth (FK is a subprocess per arm: keep the test quick)
worst = {"table": 0.0, "crate": 0.0, "ball": 0.0, "self": 0.0}
least = {k: math.inf for k in ("arm-arm", "arm-body", "self", "table", "crate", "ball")}
at = {k: [] for k in least}  # (tick, least of that kind or body at that tick)
bad = []
for i, p in enumerate(both):
    kinds = sorted((e.kind, e.name) for e in p.pairs)
    want = sorted([(m.PairKind.PAIR_ARM_ARM, ""), (m.PairKind.PAIR_SELF, "")] +
                  [(m.PairKind.PAIR_ARM_BODY, n) for n in ("table", "crate", "ball")])
    if kinds != want:
        bad.append(f"tick {p.tick}: entries {kinds}")
        continue
    here = {}
    for e in p.pairs:
        key = {m.PairKind.PAIR_ARM_ARM: "arm-arm", m.PairKind.PAIR_SELF: "self"}.get(e.kind, e.name)
        here[key] = min(here.get(key, math.inf), e.distance)
        if e.kind == m.PairKind.PAIR_ARM_BODY:
            here["arm-body"] = min(here.get("arm-body", math.inf), e.distance)
    for k, d in here.items():
        least[k] = min(least[k], d)
        at[k].append((p.tick, d))
    if i % 16:
        continue
    pts = [chain_points(state[p.tick][a], BASES[a]) for a in (0, 1)]
    truth = truth_bodies(pts)
    for e in p.pairs:
        if e.kind == m.PairKind.PAIR_ARM_BODY:
            dmin = min(truth[e.name])[0]
            named = next(d for d, a, l in truth[e.name] if (a, l) == (e.arm, e.link))
            worst[e.name] = max(worst[e.name], abs(e.distance - dmin))
            if abs(e.distance - dmin) > TOL or abs(named - dmin) > TOL:
                bad.append(f"tick {p.tick} {e.name}: published {e.distance:.9f} (arm {e.arm} link {e.link}: "
                           f"truth {named:.9f}), least truth {min(truth[e.name])}")
        elif e.kind == m.PairKind.PAIR_SELF:
            P = pts[0]
            caps = [fcl_capsule(P[l], P[l + 1], RADII[l]) for l in range(len(P) - 1)]
            d = fcl_distance(caps[e.link], caps[e.other_link])
            dmin = min(fcl_distance(caps[l], caps[o]) for l, o in SELF)
            worst["self"] = max(worst["self"], abs(e.distance - d))
            if e.arm != 0 or e.other_arm != 0 or (e.link, e.other_link) not in SELF or abs(e.distance - d) > TOL \
                    or abs(e.distance - dmin) > TOL:
                bad.append(f"tick {p.tick} self: arm {e.arm} links {e.link}-{e.other_link} {e.distance:.9f}, "
                           f"FCL {d:.9f}, least of the list {dmin:.9f}")
check(not bad, f"every entry agrees with the truth within {TOL} m (largest error: "
      + ", ".join(f"{k} {v:.2e} m" for k, v in worst.items()) + f"; FCL's own box error {FCL_BOX_ERR[0]:.2e} m)" + ("; " + "; ".join(bad[:5]) if bad else ""))


def near(v, t, k):
    """The summary's least v (at t) is not above the least published, and where the subscriber has a sample
    within 5 ticks of t (it may have matched after t on a loaded machine), that sample is within 1 cm of v."""
    tick = round(t * 1000)
    seen = [d for tk, d in at[k] if abs(tk - tick) <= 5]
    if not seen:
        print(f"note: {k}: no sample within 5 ticks of t = {t} s (first tick {min(at[k])[0] if at[k] else None})")
    return v <= least[k] + 1e-4 and (not seen or min(seen) - v < 0.01)


mk = re.search(r"least distance per kind: arm-arm ([\d.-]+) m at t = ([\d.]+) s, arm-body ([\d.-]+) m at t = "
               r"([\d.]+) s, self ([\d.-]+) m at t = ([\d.]+) s, arm-track n/a", err)
check(mk is not None, "the summary's line of the least distance per kind (arm-track n/a: no streamed bodies)")
if mk:
    g = mk.groups()
    for n, k in enumerate(("arm-arm", "arm-body", "self")):
        v, t = float(g[2 * n]), float(g[2 * n + 1])
        check(near(v, t, k), f"summary {k} {v} m at t = {t} s: least published {least[k]:.5f} m")
for name in ("table", "crate", "ball"):
    mb = re.search(r"body '%s': least distance ([\d.-]+) m at t = ([\d.]+) s, arm (\d) link (\d)" % name, err)
    check(mb is not None and near(float(mb.group(1)), float(mb.group(2)), name),
          f"summary body '{name}': {mb and mb.group(1)} m at t = {mb and mb.group(2)} s: least published "
          f"{least[name]:.5f} m")
# the monitor's last view: the kinds' least, then a line per body with its closest link
view = mon_out[mon_out.rfind("least per kind:"):]
check(re.search(r"least per kind:  arm-arm [\d.]+ mm \(arm 0 link \d - arm 1 link \d\)  arm-body [\d.]+ mm \('\w+'\)"
                r"  self [\d.]+ mm \(arm 0 link \d - arm 0 link \d\)  arm-track -", view) is not None,
      "mca-monitor shows the least distance per kind: " + (view.splitlines() or [""])[0])
for name in ("table", "crate", "ball"):
    check(re.search(r"body %s +arm-body +d= +[\d.]+ mm +d-clearance= +[\d.]+ mm +closest: arm \d link \d" % name, view)
          is not None, f"mca-monitor shows body '{name}' with its closest link")
if failures:
    print(mon_out[-2000:], mon_err)
    print(err)
    print(f"{len(failures)} check(s) failed")
    sys.exit(1)
print("all checks passed")
