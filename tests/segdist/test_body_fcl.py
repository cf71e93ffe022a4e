#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""mca_body (geom/src/body.c, through `mca-geom body`) against FCL (python-fcl) and a tighter truth.

For each body kind (plane, sphere, capsule, box, cylinder) it draws N random separated capsule-body pairs
and N touching ones (each separated pair moved along the true normal by the true distance, so it touches),
and compares mca's distance, witness points (on the capsule's surface, on the body's surface) and normal.

The truth: the surface distance is the distance from the capsule's axis point a + t u to the body's core
(the half-space, the sphere's centre, the other capsule's segment, the box, the cylinder), minus both
radii. That function of t is convex, so the truth bisects the sign of its derivative, in long double
(64-bit mantissa), to a bracket below 1e-18; every point-to-core distance is a plain clamp formula. It
shares no code and no algorithm with body.c (closed forms, piecewise quadratics, regula falsi).

FCL (python-fcl 0.7.0.x, FCL 0.7): its capsule-box and capsule-cylinder distances run GJK with FCL's
default distance_tolerance 1e-6, which python-fcl does not expose (DistanceRequest takes only
enable_nearest_points, enable_signed_distance, gjk_solver_type), and they are about 1e-7 m off: too coarse
for the 1e-9 m asked. Its sphere-capsule and capsule-capsule distances are closed forms. Its distance to a
Plane or a Halfspace crashes the process (SIGSEGV), so the plane has the truth only. mca is held to the
truth within TOL for every kind, and to FCL within TOL where FCL reaches it (sphere, capsule); FCL's own
error against the truth is printed beside for every kind.

usage: test_body_fcl.py MCA_GEOM [--n N] [--seed S] [--no-fcl]
"""
import argparse
import subprocess
import sys

import numpy as np

TOL = 1e-9  # the bound [m]
SIGNED = False
LD = np.longdouble
KINDS = ("plane", "sphere", "capsule", "box", "cylinder")


def rand_rot(rng, n):
    """n random rotations (uniform unit quaternions), as n x 3 x 3."""
    q = rng.normal(size=(n, 4))
    q /= np.linalg.norm(q, axis=1)[:, None]
    w, x, y, z = q.T
    return np.stack(
        [
            np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)], -1),
            np.stack([2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)], -1),
            np.stack([2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)], -1),
        ],
        1,
    )


def dot(a, b):
    return np.sum(a * b, axis=-1)


def clamp_seg(x, c, v):
    """closest point of segment c + s v to x (rows)"""
    vv = dot(v, v)
    s = np.where(vv > 0, dot(x - c, v) / np.where(vv > 0, vv, 1), 0)
    s = np.clip(s, 0, 1)
    return c + s[:, None] * v


def core_point(kind, body, x):
    """closest point of the body's core to the points x (long double rows)"""
    if kind == "plane":
        o, n = body["o"], body["n"]
        s = np.maximum(dot(x - o, n), 0)
        return x - s[:, None] * n
    if kind == "sphere":
        return body["c"].copy()
    if kind == "capsule":
        return clamp_seg(x, body["c"], body["v"])
    if kind == "box":
        R, c, h = body["R"], body["c"], body["h"]
        xl = np.einsum("kji,kj->ki", R, x - c)  # R^T (x - c)
        cl = np.clip(xl, -h, h)
        return c + np.einsum("kij,kj->ki", R, cl)
    # cylinder
    c, w, h, r = body["c"], body["w"], body["h"], body["r"]
    rel = x - c
    z = dot(rel, w)
    rad = rel - z[:, None] * w
    rho = np.sqrt(dot(rad, rad))
    f = np.where(rho > r, r / np.where(rho > 0, rho, 1), 1)
    return c + np.clip(z, -h, h)[:, None] * w + f[:, None] * rad


def truth(kind, body, a, b, r, R):
    """long-double bisection on the derivative of the convex axis-to-core distance"""
    u = b - a

    def grad(t):
        x = a + t[:, None] * u
        diff = x - core_point(kind, body, x)
        dist = np.sqrt(dot(diff, diff))
        return dot(diff, u) / np.where(dist > 0, dist, 1), dist

    n = len(a)
    g0, _ = grad(np.zeros(n, LD))
    g1, _ = grad(np.ones(n, LD))
    lo, hi = np.zeros(n, LD), np.ones(n, LD)
    for _ in range(72):
        m = 0.5 * (lo + hi)
        g, _ = grad(m)
        lo = np.where(g < 0, m, lo)
        hi = np.where(g < 0, hi, m)
    t = np.where(g0 >= 0, LD(0), np.where(g1 <= 0, LD(1), 0.5 * (lo + hi)))
    x = a + t[:, None] * u
    qc = core_point(kind, body, x)
    diff = x - qc
    dist = np.sqrt(dot(diff, diff))
    with np.errstate(invalid="ignore", divide="ignore"):  # penetrating draws (dist 0) are dropped later
        nrm = diff / dist[:, None]
    return {
        "d": dist - r - R,
        "p": x - r[:, None] * nrm,
        "q": qc + R[:, None] * nrm,
        "n": nrm,
        "axis": dist,
        "t": t,
    }


def draw(kind, rng, n):
    """n random capsule-body pairs, each separated (truth distance > 1e-4 m); coordinates in metres"""
    out = {k: [] for k in ("a", "b", "r", "body")}
    have = 0
    while have < n:
        m = 2 * (n - have) + 16
        a = rng.uniform(-1.2, 1.2, (m, 3))
        b = a + rng.normal(size=(m, 3)) * rng.uniform(0.05, 0.5, (m, 1))
        r = rng.uniform(0.0, 0.15, m)
        body = {}
        if kind == "plane":
            nn = rng.normal(size=(m, 3))
            body["n"] = nn / np.linalg.norm(nn, axis=1)[:, None]
            body["o"] = rng.uniform(-0.5, 0.5, (m, 3))
            R = np.zeros(m)
        elif kind == "sphere":
            body["c"] = rng.uniform(-0.3, 0.3, (m, 3))
            R = rng.uniform(0.0, 0.6, m)
        elif kind == "capsule":
            body["c"] = rng.uniform(-0.5, 0.5, (m, 3))
            body["v"] = rng.normal(size=(m, 3)) * rng.uniform(0.05, 0.6, (m, 1))
            R = rng.uniform(0.0, 0.3, m)
        elif kind == "box":
            body["c"] = rng.uniform(-0.3, 0.3, (m, 3))
            body["h"] = rng.uniform(0.02, 0.6, (m, 3))
            body["R"] = rand_rot(rng, m)
            R = np.zeros(m)
        else:
            body["c"] = rng.uniform(-0.3, 0.3, (m, 3))
            body["w"] = rand_rot(rng, m)[:, :, 2]
            body["h"] = rng.uniform(0.02, 0.6, m)
            body["r"] = rng.uniform(0.02, 0.6, m)
            R = np.zeros(m)
        body["R_surf"] = R
        ld = {k: v.astype(LD) for k, v in body.items()}
        tr = truth(kind, ld, a.astype(LD), b.astype(LD), r.astype(LD), R.astype(LD))
        keep = np.nonzero(tr["d"] > 1e-4)[0][: n - have]
        out["a"].append(a[keep])
        out["b"].append(b[keep])
        out["r"].append(r[keep])
        out["body"].append({k: v[keep] for k, v in body.items()})
        have += len(keep)
    body = {k: np.concatenate([bb[k] for bb in out["body"]]) for k in out["body"][0]}
    return np.concatenate(out["a"]), np.concatenate(out["b"]), np.concatenate(out["r"]), body


def line(kind, a, b, r, body, i):
    f = [*a[i], *b[i], r[i]]
    if kind == "plane":
        f += [*body["o"][i], *body["n"][i]]
    elif kind == "sphere":
        f += [*body["c"][i], body["R_surf"][i]]
    elif kind == "capsule":
        f += [*body["c"][i], *(body["c"][i] + body["v"][i]), body["R_surf"][i]]
    elif kind == "box":
        f += [*body["c"][i], *body["h"][i], *body["R"][i].ravel()]
    else:
        f += [*body["c"][i], *body["w"][i], body["h"][i], body["r"][i]]
    return kind + " " + " ".join(repr(float(x)) for x in f)


def run_mca(tool, kind, a, b, r, body):
    text = "\n".join(line(kind, a, b, r, body, i) for i in range(len(a))) + "\n"
    res = subprocess.run([tool, "body"], input=text, capture_output=True, text=True, check=False)
    if res.returncode != 0:
        sys.exit(f"mca-geom body failed ({res.returncode}): {res.stderr}")
    v = np.array([[float(x) for x in ln.split()] for ln in res.stdout.splitlines()])
    return {"d": v[:, 0], "p": v[:, 1:4], "q": v[:, 4:7], "n": v[:, 7:10], "axis_pt": v[:, 10:13], "exact": v[:, 13], "iters": v[:, 14]}


def fcl_rot_z(w):
    """a rotation whose third column is w"""
    w = w / np.linalg.norm(w)
    x = np.cross(w, [1.0, 0, 0]) if abs(w[0]) < 0.9 else np.cross(w, [0, 1.0, 0])
    x /= np.linalg.norm(x)
    return np.column_stack([x, np.cross(w, x), w])


def fcl_capsule(fcl, a, b, r):
    u = b - a
    L = np.linalg.norm(u)
    return fcl.CollisionObject(fcl.Capsule(r, L), fcl.Transform(fcl_rot_z(u), (a + b) / 2))


def run_fcl(fcl, kind, a, b, r, body, solver):
    """FCL's signed distance and nearest points (None for the plane: FCL crashes on it)"""
    if kind == "plane":
        return None
    n = len(a)
    d, p, q = np.zeros(n), np.zeros((n, 3)), np.zeros((n, 3))
    req = fcl.DistanceRequest(enable_nearest_points=True, enable_signed_distance=SIGNED, gjk_solver_type=solver)
    for i in range(n):
        o1 = fcl_capsule(fcl, a[i], b[i], r[i])
        if kind == "sphere":
            o2 = fcl.CollisionObject(fcl.Sphere(body["R_surf"][i]), fcl.Transform(np.eye(3), body["c"][i]))
        elif kind == "capsule":
            c = body["c"][i]
            o2 = fcl_capsule(fcl, c, c + body["v"][i], body["R_surf"][i])
        elif kind == "box":
            o2 = fcl.CollisionObject(fcl.Box(*(2 * body["h"][i])), fcl.Transform(body["R"][i], body["c"][i]))
        else:
            o2 = fcl.CollisionObject(
                fcl.Cylinder(body["r"][i], 2 * body["h"][i]), fcl.Transform(fcl_rot_z(body["w"][i]), body["c"][i])
            )
        res = fcl.DistanceResult()
        d[i] = fcl.distance(o1, o2, req, res)
        p[i], q[i] = res.nearest_points
    return {"d": d, "p": p, "q": q}


def err3(x, y):
    return np.max(np.linalg.norm(np.asarray(x, float) - np.asarray(y, float), axis=1))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("tool")
    ap.add_argument("--n", type=int, default=10000, help="separated pairs per kind (as many touching ones)")
    ap.add_argument("--seed", type=int, default=31)
    ap.add_argument("--no-fcl", action="store_true", help="truth only")
    ap.add_argument("--kinds", default=",".join(KINDS))
    args = ap.parse_args()
    fcl = None
    if not args.no_fcl:
        import fcl  # python-fcl, tools/deps/requirements.txt

    rng = np.random.default_rng(args.seed)
    failures = 0
    print(f"{args.n} separated + {args.n} touching pairs per kind; mca and FCL against the long-double truth [m]")
    print(
        "kind      set        | mca: max|dd|  max|dp|   max|dq|   max|dn|   | FCL (GST_LIBCCD): max|dd| max|dp|"
        " max|dq| over the pairs it answers"
    )
    for kind in args.kinds.split(","):
        a, b, r, body = draw(kind, rng, args.n)
        ld = {k: v.astype(LD) for k, v in body.items()}
        tr = truth(kind, ld, a.astype(LD), b.astype(LD), r.astype(LD), body["R_surf"].astype(LD))
        # touching: move each capsule by -d along the true normal; the closest pair stays the closest
        shift = -(tr["d"][:, None] * tr["n"]).astype(float)
        at, bt = a + shift, b + shift
        trt = truth(kind, ld, at.astype(LD), bt.astype(LD), r.astype(LD), body["R_surf"].astype(LD))
        for name, (aa, bb, t) in (("separated", (a, b, tr)), ("touching", (at, bt, trt))):
            m = run_mca(args.tool, kind, aa, bb, r, body)
            e = {
                "d": float(np.max(np.abs(m["d"] - t["d"].astype(float)))),
                "p": err3(m["p"], t["p"]),
                "q": err3(m["q"], t["q"]),
                "n": err3(m["n"], t["n"]),
            }
            row = f"{kind:9s} {name:10s} | {e['d']:.1e}  {e['p']:.1e}  {e['q']:.1e}  {e['n']:.1e}  |"
            if fcl is not None and kind == "plane":
                row += " n/a: FCL crashes (SIGSEGV) on Plane and Halfspace distances"
            elif fcl is not None:
                # FCL returns -1 (and no points) for shapes it finds in contact: touching pairs mostly
                f = run_fcl(fcl, kind, aa, bb, r, body, 0)
                ok = f["d"] >= 0
                fd = np.abs(f["d"] - t["d"].astype(float))[ok]
                fp = np.linalg.norm(f["p"] - t["p"].astype(float), axis=1)[ok]
                fq = np.linalg.norm(f["q"] - t["q"].astype(float), axis=1)[ok]
                if ok.any():
                    row += (
                        f" {np.max(fd):.1e} {np.max(fp):.1e} {np.max(fq):.1e} (median {np.median(fd):.1e},"
                        f" p99 {np.percentile(fd, 99):.1e})"
                    )
                row += f" contact -1: {int(np.sum(~ok))}"
                fi = run_fcl(fcl, kind, aa, bb, r, body, 1)
                same = np.array_equal(fi["d"], f["d"]) and np.array_equal(fi["p"], f["p"])
                row += "; GST_INDEP identical" if same else f"; GST_INDEP max|dd| {np.max(np.abs(fi['d'] - f['d'])):.1e}"
                if kind in ("sphere", "capsule") and ok.any():
                    # FCL's closed forms: mca must agree with FCL itself within TOL where FCL answers
                    fe = max(
                        float(np.max(np.abs(m["d"] - f["d"])[ok])),
                        float(np.max(np.linalg.norm(m["p"] - f["p"], axis=1)[ok])),
                        float(np.max(np.linalg.norm(m["q"] - f["q"], axis=1)[ok])),
                    )
                    row += f"; mca-FCL {fe:.1e}"
                    if fe > TOL:
                        failures += 1
                        row += " FAIL"
            bad = [k for k in ("d", "p", "q") if e[k] > TOL]
            if np.any(m["exact"] != 1):
                bad.append("exact flag")
            if name == "touching" and np.max(np.abs(m["d"])) > TOL:
                bad.append("touching d")
            if bad:
                failures += 1
                worst = int(np.argmax(np.abs(m["d"] - t["d"].astype(float))))
                row += f"  FAIL ({', '.join(bad)}; worst d line: {line(kind, aa, bb, r, body, worst)})"
            print(row, flush=True)
    print(f"{'FAILED' if failures else 'OK'}: {failures} failing rows (bound {TOL:g} m)")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
