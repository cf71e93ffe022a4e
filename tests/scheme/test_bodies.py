#!/usr/bin/env python3
"""Cup stacking in its whole cell (config/scenarios/cup_stacking_bodies.yaml): a table plane under both bases
and a cylinder per cup and per stack, each link kept clear of them by the fixed bodies' rows.

usage: test_bodies.py MCA_SIM SCENARIO_DIR WORK_DIR
 1. mca-ts with the bodies: every link not on a body's allow list keeps that body's clearance at every tick
    (running and braking: the least margin d - clearance >= 0, no tick inside a clearance), every arm pair
    >= d1, the task completed on its paths; completion and path error printed beside the run without
    bodies (cup_stacking.yaml);
 2. the same scenario with the bodies measured only (--no-body-rows) goes inside a clearance: the rows are
    what keeps it (so this test fails when they are taken out of the tick);
 3. the paper's scheme (mca) with the bodies: the same, no fault;
 4. stops (as SIGTERM to mcad) while the MICO2's hand passes the JACO2's stack, at dec 2 and 10 rad/s^2:
    the braking keeps the bodies' clearances and d1.
"""
import os
import sys

from simcheck import FAILS, check, sim_run


def run(sim, scn, work, scheme, tag, extra=()):
    r = sim_run(sim, scn, work, scheme, tag, extra)
    if r is None:
        return None
    if r.get("bodies"):
        # each body's least distance (mcad's summary, per body): the arm-body kind's least is the least of
        # them, the arm pair's is min_distance, and the body of least margin came no closer than its own least
        k, per = r["pair_kinds"], [e for e in r["body_min"] if e["min"] is not None]
        name = r["body_min_name"]
        own = next((e["min"] for e in r["body_min"] if e["name"] == name), None)
        check(len(r["body_min"]) == r["bodies"] and per and k["arm-body"]["min"] == min(e["min"] for e in per)
              and k["arm-arm"]["min"] == r["min_distance"] and own is not None
              and own <= r["body_min_distance"] + 1e-12,
              "%s: per body %s; arm-body least %s = least of them; '%s' least %s <= its least-margin pair's %s" %
              (tag, [(e["name"], e["min"] and round(e["min"], 4)) for e in r["body_min"]], k["arm-body"]["min"],
               name, own, r["body_min_distance"]))
    print("%-28s completed %d, min d %.5f m (d1 %.3f), path error max %.3e m, bodies: least margin %s m "
          "(%s '%s', arm %s link %s, %s s), %s ticks inside, binding ticks %d, tick cpu p50/p99 %.1f/%.1f us,"
          " state %s" % (tag, r["completed"], r["min_distance"], r["d1"], r["path_error_max"],
                         r.get("body_min_margin"), r.get("body_min_kind"), r.get("body_min_name"),
                         (r.get("body_min_pair") or ["-"])[0], (r.get("body_min_pair") or ["-", "-"])[1],
                         r.get("body_min_t"), r.get("body_ticks_below"), r["binding_ticks"],
                         r["cpu_p50_ns"] / 1e3, r["cpu_p99_ns"] / 1e3, r["state"]))
    return r


def main():
    sim, scn_dir, work = sys.argv[1:4]
    bodies = os.path.join(scn_dir, "cup_stacking_bodies.yaml")
    plain = os.path.join(scn_dir, "cup_stacking.yaml")

    ref = run(sim, plain, work, "mca-ts", "without-bodies")
    b = run(sim, bodies, work, "mca-ts", "mca-ts")
    if ref and b:
        check(b["bodies"] == 7, "7 bodies loaded")
        check(b["body_min_margin"] >= 0.0 and b["body_ticks_below"] == 0,
              "mca-ts: every link keeps every body's clearance (least margin %.5f m)" % b["body_min_margin"])
        check(b["min_distance"] >= b["d1"], "mca-ts: arm pair >= d1 (%.5f m)" % b["min_distance"])
        check(b["fault"] == 0 and b["completed"] == 1, "mca-ts: completed, no fault")
        check(b["path_error_max"] <= 2e-5,
              "mca-ts: path error max %.3e m (without bodies %.3e m), path time lost %.3f s (%.3f s)" %
              (b["path_error_max"], ref["path_error_max"], b["path_time_lost_s"], ref["path_time_lost_s"]))
        check(b["binding_ticks"] > 0, "mca-ts: body rows bind (%d ticks)" % b["binding_ticks"])

    n = run(sim, bodies, work, "mca-ts", "mca-ts-no-body-rows", ["--no-body-rows"])
    if n:
        check(n["body_min_margin"] < -0.005 and n["body_ticks_below"] > 100,
              "without the body rows a link goes inside a clearance (least margin %.5f m, %d ticks): the rows "
              "keep it" % (n["body_min_margin"], n["body_ticks_below"]))

    m = run(sim, bodies, work, "mca", "mca")
    if m:
        check(m["fault"] == 0 and m["body_min_margin"] >= 0.0 and m["body_ticks_below"] == 0,
              "mca: every link keeps every body's clearance, no fault (least margin %.5f m)" %
              m["body_min_margin"])
        check(m["min_distance"] >= m["d1"], "mca: arm pair >= d1 (%.5f m)" % m["min_distance"])

    for t in ("15.0", "15.4", "15.8"):
        for dec in ("2", "10"):
            s = run(sim, bodies, work, "mca-ts", "stop-%s-dec%s" % (t, dec), ["--stop-at", t, "--dec-limit", dec])
            if s:
                check(s["state"] == "stopped" and s["body_min_margin"] >= 0.0 and s["body_ticks_below"] == 0 and
                      s["min_distance"] >= s["d1"],
                      "stop at %s s, dec %s: at rest, bodies' clearances kept (least margin %.5f m), d1 kept" %
                      (t, dec, s["body_min_margin"]))

    if FAILS:
        print("%d FAILED" % len(FAILS))
        sys.exit(1)
    print("all ok")


if __name__ == "__main__":
    main()
