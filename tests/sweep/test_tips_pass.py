#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""tools/mca-sweep/tips_pass.py, the a-priori proof that two arms' tool tips cannot pass on their paths.

Hand-built paths whose answer is known without the tool (the tips' geometry alone):
  - an arm whose path runs through the other arm's resting tip: blocked (the resting arm never moves);
  - two paths that cross, each arm free to wait at its start: they pass (one waits, the other goes);
  - a diagram only a way that backs off crosses (A forward, back, on), which a wait-only test calls blocked;
  - head-on paths side by side: 2 cm wider than d1 + both radii + slack they pass, 2 cm below d1 + both radii
    they are blocked, and in 5 cm tubes that is no proof any more;
  - the tip radius read from the URDF the way model/src/urdf_shim.cpp reads it (largest cylinder or sphere
    after the last moving joint), against the numbers in the shipped URDFs.
usage: test_tips_pass.py TOOLS_DIR ROBOTS_DIR
"""
import os
import sys

FAILS = []


def check(ok, what):
    print("%s: %s" % ("ok" if ok else "FAIL", what))
    if not ok:
        FAILS.append(what)


def arm(urdf, path):
    return dict(urdf=urdf, tip_link="tool_tip", path=path)


def main():
    sys.path.insert(0, sys.argv[1])
    import tips_pass

    jaco = os.path.join(sys.argv[2], "jaco2.urdf")
    pa10 = os.path.join(sys.argv[2], "pa10plus.urdf")
    rj, rp = tips_pass.tip_radius(jaco, "tool_tip"), tips_pass.tip_radius(pa10, "tool_tip")
    check(abs(rj - 0.045) < 1e-12, "JACO2's last segment radius from its URDF: %g (0.045: link_6's cylinder)" % rj)
    check(rp > 0.0, "PA10+'s last segment radius from its URDF: %g" % rp)
    d1 = 0.07
    # 1. A straight through B's resting tip
    a = arm(jaco, dict(kind="waypoints", relative=False, points=[[1.0, 0.0, 0.3]], durations=[5.0]))
    b = arm(jaco, dict(kind="hold"))
    got = tips_pass.blocked_pairs([a, b], [[0.0, 0.0, 0.3], [0.5, 0.0, 0.3]], d1)
    check(got == [[0, 1]], "a path through the other arm's resting tip is blocked (%s)" % got)
    # the same path 0.3 m beside the resting tip
    got = tips_pass.blocked_pairs([a, b], [[0.0, 0.0, 0.3], [0.5, 0.3, 0.3]], d1)
    check(got == [], "the same path 0.3 m beside it passes (%s)" % got)
    # 2. two crossing straight paths, both starts and ends far from the other path
    a = arm(jaco, dict(kind="waypoints", relative=False, points=[[1.0, 0.0, 0.3]], durations=[5.0]))
    b = arm(jaco, dict(kind="waypoints", relative=False, points=[[0.5, 0.5, 0.3]], durations=[5.0]))
    got = tips_pass.blocked_pairs([a, b], [[0.0, 0.0, 0.3], [0.5, -0.5, 0.3]], d1)
    check(got == [], "two crossing paths pass: one waits at its start (%s)" % got)
    # 3. backing off: a diagram whose only way goes forward in A's clock, then back, then on. B may pass its
    #    first obstacle (row 2) only with A beyond column 4, its second (row 4) only with A before column 2.
    import numpy as np
    free = np.ones((7, 7), bool)
    free[0:5, 2] = False
    free[2:7, 4] = False

    def monotone(f):
        r = np.zeros_like(f)
        for x in range(f.shape[0]):
            for y in range(f.shape[1]):
                r[x, y] = f[x, y] and ((x == 0 and y == 0) or (x > 0 and r[x - 1, y]) or (y > 0 and r[x, y - 1]))
        return bool(r[-1, -1])

    check(not monotone(free) and tips_pass.passes(free),
          "a diagram that waiting alone cannot cross passes by backing off (monotone %s)" % monotone(free))
    walled = free.copy()
    walled[5, 0:5] = False
    check(not tips_pass.passes(walled), "closing the back-off's way blocks it")
    # 4. the threshold: two parallel paths at a gap g (tip to tip) for their whole length
    for g, want in ((d1 + 2 * rj + 2 * tips_pass.SLACK + tips_pass.STEP + 0.02, []),
                    (d1 + 2 * rj - 0.02, [[0, 1]])):
        a = arm(jaco, dict(kind="waypoints", relative=False, points=[[1.0, 0.0, 0.3]], durations=[5.0]))
        b = arm(jaco, dict(kind="waypoints", relative=False, points=[[1.0, g, 0.3]], durations=[5.0]))
        # B starts where A ends and ends where A starts: they must meet somewhere side by side
        b["path"]["points"] = [[0.0, g, 0.3]]
        got = tips_pass.blocked_pairs([a, b], [[0.0, 0.0, 0.3], [1.0, g, 0.3]], d1)
        check(got == want, "head-on paths side by side at %.3f m: %s (want %s)" % (g, got, want))
    # 5. a tolerance lets the tips stray apart, so the proof needs them closer: a gap blocked at tolerance 0
    #    is no proof in 5 cm tubes
    g = d1 + 2 * rj - 0.02
    a = arm(jaco, dict(kind="waypoints", relative=False, points=[[1.0, 0.0, 0.3]], durations=[5.0], tolerance=0.05))
    b = arm(jaco, dict(kind="waypoints", relative=False, points=[[0.0, g, 0.3]], durations=[5.0], tolerance=0.05))
    got = tips_pass.blocked_pairs([a, b], [[0.0, 0.0, 0.3], [1.0, g, 0.3]], d1)
    check(got == [], "the same pair in 5 cm tubes is not proven blocked (%s)" % got)
    if FAILS:
        print("%d check(s) failed" % len(FAILS))
        return 1
    print("all checks passed")
    return 0


if __name__ == "__main__":
    sys.exit(main())
