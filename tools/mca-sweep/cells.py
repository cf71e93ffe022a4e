#!/usr/bin/env python3
"""Random cells for the sweep (`mca_sweep.py --cells`): a table under the arms and 1-3 boxes or posts near them.

Each task keeps its arms, start configurations and paths (the cell's draws come from their own generator,
seeded "S:K:i:cell", so a task with and without its cell is the same task) and gets:
  - a table: the plane z = 0 under the bases, clearance TABLE_CLEARANCE, the bases, their first links and the
    tools allowed (a gripper picks from the table; what the table keeps off it is the rest of each arm);
  - 1-3 obstacles: a post (a vertical cylinder standing on the table) or a box (on the table, turned about z),
    clearance OBSTACLE_CLEARANCE, nothing allowed, placed near the arms: inside the box around both bases and
    every tool-tip path, grown by NEAR. Drawn again while it comes closer than its clearance + PATH_ROOM to
    any tool-tip path (the paths stay reachable: only the arms' other links have to give way) or than BASE_ROOM
    to a base; the caller drops a cell whose bodies are inside a clearance at the start configurations;
  - in half of the tasks (the caller picks them) a streamed sphere crossing the workspace between the arms
    (draw_sphere: mca-sim's `simulated_sphere`, fed through the daemon's track input as a tracker's samples).
"""
import math

import numpy as np

import tips_pass

TABLE_CLEARANCE = 0.02  # [m]
OBSTACLE_CLEARANCE = 0.03  # [m]
PATH_ROOM = 0.03  # [m] between an obstacle's clearance and a tool tip's capsule on its path
BASE_ROOM = 0.20  # [m] from a base's axis to an obstacle
NEAR = 0.15  # [m]


def point_distance(body, p):
    """Distance from p to the body's surface (negative inside), for the kinds this module draws."""
    c = np.asarray(body["centre"], float)
    d = np.asarray(p, float) - c
    if body["kind"] == "cylinder":  # axis z
        radial = math.hypot(d[0], d[1]) - body["radius"]
        axial = abs(d[2]) - body["half_length"]
        if radial <= 0 and axial <= 0:
            return max(radial, axial)
        return math.hypot(max(radial, 0.0), max(axial, 0.0))
    # box turned by yaw about z
    yaw = body["rpy"][2]
    x = math.cos(yaw) * d[0] + math.sin(yaw) * d[1]
    y = -math.sin(yaw) * d[0] + math.cos(yaw) * d[1]
    q = np.abs([x, y, d[2]]) - np.asarray(body["half_extents"], float)
    out = np.linalg.norm(np.maximum(q, 0.0))
    return out if out > 0 else float(np.max(q))


def draw_obstacle(rng, lo, hi):
    x, y = rng.uniform(lo[0], hi[0]), rng.uniform(lo[1], hi[1])
    if rng.random() < 0.5:
        h = rng.uniform(0.15, 0.50)
        return dict(kind="cylinder", centre=[round(x, 4), round(y, 4), round(h / 2, 4)], half_length=round(h / 2, 4),
                    radius=round(rng.uniform(0.02, 0.05), 4))
    hz = rng.uniform(0.03, 0.20)
    return dict(kind="box", centre=[round(x, 4), round(y, 4), round(hz, 4)],
                half_extents=[round(rng.uniform(0.03, 0.12), 4), round(rng.uniform(0.03, 0.12), 4), round(hz, 4)],
                rpy=[0.0, 0.0, round(rng.uniform(-math.pi, math.pi), 4)])


def draw_cell(rng, arms, tips, paths):
    """The bodies of a random cell (list of dicts with the scenario's keys), or None when 200 draws of an
    obstacle found no place. arms: name, urdf (absolute), base; tips: start tool tips; paths: the paths."""
    samples, radii = [], []
    for arm, tip, path in zip(arms, tips, paths):
        samples.append(tips_pass.sample(tips_pass.polyline(path, tip), 0.01))
        radii.append(tips_pass.tip_radius(arm["urdf"], "tool_tip"))
    pts = np.vstack(samples + [np.asarray([a["base"] for a in arms], float)])
    lo, hi = pts.min(axis=0) - NEAR, pts.max(axis=0) + NEAR
    allow = [n for a in arms for n in ("%s.base" % a["name"], "%s.1" % a["name"], "%s.tool" % a["name"])]
    bodies = [dict(name="table", kind="plane", point=[0, 0, 0], normal=[0, 0, 1], clearance=TABLE_CLEARANCE,
                   allow=allow)]
    for k in range(rng.choice((1, 2, 3))):
        for _ in range(200):
            b = draw_obstacle(rng, lo, hi)
            near_base = any(math.hypot(b["centre"][0] - a["base"][0], b["centre"][1] - a["base"][1]) < BASE_ROOM +
                            b.get("radius", max(b.get("half_extents", [0, 0])[:2])) for a in arms)
            if near_base:
                continue
            gap = min(min(point_distance(b, p) for p in s) - r for s, r in zip(samples, radii))
            if gap >= OBSTACLE_CLEARANCE + PATH_ROOM:
                b.update(name="obstacle%d" % (k + 1), clearance=OBSTACLE_CLEARANCE)
                bodies.append(b)
                break
        else:
            return None
    return bodies


SPHERE_SPEED = (0.3, 2.0)  # [m/s]
SPHERE_RADIUS = (0.10, 0.25)  # [m] a head to a torso
SPHERE_RUN = 3.0  # [m] from its start to the crossing point (beyond S_p of the arms at its speed)
SPHERE_RATE = 30.0  # [1/s] a camera
SPHERE_LATENCY = 0.03  # [s]
SPHERE_LOSS = 0.01


def draw_sphere(rng, arms, tips, duration):
    """A sphere crossing the workspace between the first two arms: through a point near the middle of their
    bases (+-0.15 m, at the tool tips' mean height +-0.15 m), horizontally, across the line of the bases
    (+-30 deg), SPHERE_RUN m before and after it, at 0.3-2.0 m/s, reaching that point at 20-80 % of the task
    (or later when it cannot start that close)."""
    b0, b1 = (np.asarray(a["base"], float) for a in arms[:2])
    mid = 0.5 * (b0 + b1)
    zt = float(np.mean([t[2] for t in tips]))
    c = [mid[0] + rng.uniform(-0.15, 0.15), mid[1] + rng.uniform(-0.15, 0.15), 0.0]
    r = rng.uniform(*SPHERE_RADIUS)
    c[2] = max(r + 0.05, zt + rng.uniform(-0.15, 0.15))
    ang = math.atan2(b1[1] - b0[1], b1[0] - b0[0]) + math.pi / 2 + math.radians(rng.uniform(-30.0, 30.0))
    u = [math.cos(ang), math.sin(ang), 0.0]
    v = rng.uniform(*SPHERE_SPEED)
    t0 = max(0.0, rng.uniform(0.2, 0.8) * duration - SPHERE_RUN / v)
    return dict(radius=round(r, 4), speed=round(v, 4), t0=round(t0, 3),
                start=[round(c[j] - SPHERE_RUN * u[j], 4) for j in range(3)],
                end=[round(c[j] + SPHERE_RUN * u[j], 4) for j in range(3)],
                rate=SPHERE_RATE, latency=SPHERE_LATENCY, loss=SPHERE_LOSS, seed=rng.randrange(1, 2 ** 31 - 1))


def sphere_yaml(s):
    """The scenario's `simulated_sphere:` lines."""
    def f(v):
        return "[%s]" % ", ".join("%g" % x for x in v)

    return ["simulated_sphere:", "  radius: %g" % s["radius"], "  start: %s" % f(s["start"]), "  end: %s" % f(s["end"]),
            "  speed: %g" % s["speed"], "  t0: %g" % s["t0"], "  rate: %g" % s["rate"], "  latency: %g" % s["latency"],
            "  loss: %g" % s["loss"], "  seed: %d" % s["seed"]]


def bodies_yaml(bodies):
    """The scenario's `bodies:` lines."""
    def f(v):
        return "[%s]" % ", ".join("%g" % x for x in v)

    out = ["bodies:"]
    for b in bodies:
        out.append("  - name: %s" % b["name"])
        out.append("    kind: %s" % b["kind"])
        if b["kind"] == "plane":
            out += ["    point: %s" % f(b["point"]), "    normal: %s" % f(b["normal"])]
        elif b["kind"] == "cylinder":
            out += ["    centre: %s" % f(b["centre"]), "    half_length: %g" % b["half_length"],
                    "    radius: %g" % b["radius"]]
        else:
            out += ["    centre: %s" % f(b["centre"]), "    half_extents: %s" % f(b["half_extents"]),
                    "    rpy: %s" % f(b["rpy"])]
        out.append("    clearance: %g" % b["clearance"])
        if b.get("allow"):
            out.append("    allow: [%s]" % ", ".join(b["allow"]))
    return out
