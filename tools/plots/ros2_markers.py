#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Draw what a ROS 2 node received from mcad: one MarkerArray of /<cell>/distance_markers as written by
tests/ros2/test_ros2.py (the tick of the smallest distance): each arm's capsules in their zone colour, the
closest-point segment and its distance. usage: ros2_markers.py MARKERS_JSON OUT_PNG"""
import json
import sys

import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

SPHERE_LIST, LINE_LIST, TEXT = 7, 5, 9

data = json.load(open(sys.argv[1]))
fig = plt.figure(figsize=(7, 6))
ax = fig.add_subplot(projection="3d")
pts_all = []
for m in data["markers"]:
    if m["type"] == SPHERE_LIST and len(m["points"]) == 2:
        (x0, y0, z0), (x1, y1, z1) = m["points"]
        # capsule: its axis drawn as wide as its diameter at this scale
        ax.plot([x0, x1], [y0, y1], [z0, z1], color=m["color"][:3], lw=max(2.0, 160 * m["scale"][0]),
                alpha=0.55, solid_capstyle="round")
        pts_all += m["points"]
    elif m["type"] == LINE_LIST:
        (x0, y0, z0), (x1, y1, z1) = m["points"]
        ax.plot([x0, x1], [y0, y1], [z0, z1], color="k", lw=2.0)
        ax.scatter([x0, x1], [y0, y1], [z0, z1], color="k", s=12)
    elif m["type"] == TEXT:
        ax.text(*m["position"], m["text"].split()[0] + f"  {float(m['text'].split()[-2]):.3f} m", fontsize=9)
xs, ys, zs = zip(*pts_all)
span = max(max(xs) - min(xs), max(ys) - min(ys), max(zs) - min(zs)) / 2
cx, cy, cz = ((max(v) + min(v)) / 2 for v in (xs, ys, zs))
ax.set_xlim(cx - span, cx + span)
ax.set_ylim(cy - span, cy + span)
ax.set_zlim(cz - span, cz + span)
ax.set_xlabel("x [m]")
ax.set_ylabel("y [m]")
ax.set_zlabel("z [m]")
ax.set_title(f"received by an rclpy node: distance_markers at tick {data['tick']}\n"
             f"capsules green > d2 = {data['d2']} m, amber d1..d2, red < d1 = {data['d1']} m; "
             "black: closest points", fontsize=9)
fig.tight_layout()
fig.savefig(sys.argv[2], dpi=110)
