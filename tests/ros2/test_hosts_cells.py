#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Every shipped plain cell with DDS on publishes the way ros2.hosts proves (docs/ros2.md "Network").

ros2.hosts runs the shipped plain sim cells with default ROS 2 nodes on the controller's host and on a second
one. The vcan and CANopen cells need SocketCAN, which this kernel lacks (their runs are QEMU guest tests under
TCG, where rclpy and Fast DDS would take minutes), so they are not run there; what makes a cell visible to a
default node is its DDS side alone (the bridge publishes the same snapshots whatever the backend), and that is
what this test pins: a cell whose DDS side drifts from the proven one fails here instead of silently hiding
from ROS 2.

For every config/cells/*.yaml, `mcad --check` (mcad's own loader: defaults applied, paths resolved) gives
its DDS side: on/off, domain, configuration file, publishing divisor, ROS 2 topics. Plain = a configuration
that is not secure*.xml (those cells are DDS Security's, docs/security.md). Asserted:
  - the cells given to ros2.hosts (the command line) are shipped plain cells with DDS on, and they share one
    configuration file (config/dds/loopback.xml) and domain 0;
  - every shipped plain sim cell with DDS on is among them (a new one is run, not assumed);
  - every other shipped plain cell with DDS on (vcan, CANopen) uses that same file (the same inode after
    resolving its relative path), domain 0, a divisor ros2.hosts ran, and publishes joint_states,
    distance_markers and diagnostics, as the proven cells do;
  - the check itself catches drift: a copy of a vcan cell pointed at config/dds/ros2.xml, one on domain 7 and
    one without markers are each refused.

usage: test_hosts_cells.py MCAD SOURCE_DIR HOSTS_CELL..."""
import glob
import os
import re
import subprocess
import sys
import tempfile

MCAD, SRC, HOSTS = sys.argv[1], sys.argv[2], [os.path.realpath(x) for x in sys.argv[3:]]
NEEDED = ("joint_states", "distance_markers", "diagnostics")  # what a user's ROS 2 tools need to see the cell
failures = []


def check(cond, what):
    print(("ok   " if cond else "FAIL ") + what, flush=True)
    if not cond:
        failures.append(what)


def dds_side(path):
    """The cell's DDS side as mcad --check reads it: dict, or None if mcad refuses the cell."""
    p = subprocess.run([MCAD, "--check", path], capture_output=True, text=True, timeout=60)
    if p.returncode != 0:
        print(f"mcad --check {path}: exit {p.returncode}: {p.stderr.strip()[-300:]}")
        return None
    out = p.stdout
    backends = re.findall(r"backend (\w+)", out)
    d = re.search(r"^  dds: (on|off)(?:, domain (\d+), config (\S*?),? publish every (\d+) ticks)?", out, re.M)
    r2 = re.search(r"^  ros2: namespace (\S+), world frame \S+, (.*)$", out, re.M)
    if d is None:
        print(f"mcad --check {path}: no dds line in:\n{out}")
        return None
    cfg = d.group(3) or ""
    return dict(on=d.group(1) == "on", domain=int(d.group(2) or -1), config=os.path.realpath(cfg) if cfg else "",
                divisor=int(d.group(4) or 0), topics=set(r2.group(2).split()) if r2 else set(),
                backends=sorted(set(backends)))


def plain(side):
    return side["on"] and not os.path.basename(side["config"]).startswith("secure")


def same_as_proven(side, proven):
    """Why a plain cell does not publish as the proven cells do ("" if it does)."""
    why = []
    cfgs = {s["config"] for s in proven.values()}
    if side["config"] not in cfgs or not os.path.exists(side["config"]):
        why.append(f"configuration {side['config']} (proven: {sorted(cfgs)})")
    if side["domain"] not in {s["domain"] for s in proven.values()}:
        why.append(f"domain {side['domain']}")
    if side["divisor"] not in {s["divisor"] for s in proven.values()}:
        why.append(f"publish every {side['divisor']} ticks")
    missing = [t for t in NEEDED if t not in side["topics"]]
    if missing:
        why.append(f"no {', '.join(missing)}")
    return "; ".join(why)


def main():
    cells = sorted(glob.glob(os.path.join(SRC, "config", "cells", "*.yaml")))
    sides = {os.path.realpath(c): dds_side(c) for c in cells}
    check(all(s is not None for s in sides.values()),
          f"mcad --check reads all {len(cells)} shipped cells: "
          + (", ".join(os.path.basename(c) for c, s in sides.items() if s is None) or "yes"))
    sides = {c: s for c, s in sides.items() if s is not None}

    proven = {c: sides.get(c) for c in HOSTS}
    bad = [os.path.basename(c) for c, s in proven.items() if s is None or not plain(s)]
    check(bool(HOSTS) and not bad, f"ros2.hosts runs {len(HOSTS)} shipped plain cells with DDS on ({bad or 'all'})")
    proven = {c: s for c, s in proven.items() if s is not None}
    loopback = os.path.realpath(os.path.join(SRC, "config", "dds", "loopback.xml"))
    check({s["config"] for s in proven.values()} == {loopback} and {s["domain"] for s in proven.values()} == {0},
          f"they share one configuration, config/dds/loopback.xml, and domain 0 "
          f"({sorted({s['config'] for s in proven.values()})}, {sorted({s['domain'] for s in proven.values()})})")

    plain_on = {c: s for c, s in sides.items() if plain(s)}
    sim_left_out = [os.path.basename(c) for c, s in plain_on.items() if s["backends"] == ["sim"] and c not in proven]
    check(not sim_left_out, f"every shipped plain sim cell with DDS on is run by ros2.hosts ({sim_left_out or 'yes'})")

    others = {c: s for c, s in plain_on.items() if c not in proven}
    for c, s in others.items():
        why = same_as_proven(s, proven)
        check(not why, f"{os.path.basename(c)} (backend {'/'.join(s['backends'])}): publishes as the proven cells "
              f"do (same loopback.xml, domain {s['domain']}, every {s['divisor']} ticks, {' '.join(NEEDED)})"
              + (f": NOT: {why}" if why else ""))
    print(f"plain cells with DDS on: {len(plain_on)}; run by ros2.hosts {len(proven)}, held to its DDS side here "
          f"{len(others)} ({', '.join(os.path.basename(c) for c in others)}); not plain: "
          + ", ".join(os.path.basename(c) for c, s in sides.items() if s["on"] and not plain(s)))

    # the check catches drift (a vcan cell edited three ways)
    vcan = next((c for c, s in others.items() if "socketcan" in s["backends"]), None)
    check(vcan is not None, "a shipped vcan cell to edit for the self-check")
    if vcan is not None:
        text = open(vcan).read().replace("../", os.path.join(SRC, "config") + "/")
        with tempfile.TemporaryDirectory(prefix="mca-hosts-cells-") as tmp:
            for what, pat, new in (("config/dds/ros2.xml", r"(?m)^  config: *\S+", "  config: "
                                    + os.path.join(SRC, "config", "dds", "ros2.xml")),
                                   ("domain 7", r"(?m)^  domain: *\d+", "  domain: 7"),
                                   ("markers off", r"(?m)^dds:\n", "dds:\n  ros2:\n    markers: false\n")):
                edited, n = re.subn(pat, new, text, count=1)
                path = os.path.join(tmp, "drift.yaml")
                with open(path, "w") as f:
                    f.write(edited)
                s = dds_side(path)
                why = same_as_proven(s, proven) if s is not None else "refused by mcad"
                check(n == 1 and bool(why), f"a copy of {os.path.basename(vcan)} with {what} is caught: {why}")
    print(f"{len(failures)} failed" if failures else "all passed")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
