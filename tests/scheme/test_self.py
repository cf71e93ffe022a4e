#!/usr/bin/env python3
"""A PA10+ that folds onto itself (config/scenarios/self_fold.yaml): the self rows keep the arm's own links
d1 apart (docs/scheme.md, "Self pairs").

usage: test_self.py MCA_SIM SCENARIO_DIR WORK_DIR
 1. without the self rows (--no-self-rows: the pairs measured only) the elbow folds links 4 and 2 below d1:
    the rows are what keeps them (so this test fails when they are taken out of the tick);
 2. mca-ts and the paper's scheme (mca) with the rows: the least self distance >= d1 on every tick (the
    summary's count and, independently, the CSV's self_d column), no fault, the task completed on its path;
 3. a stop (as SIGTERM to mcad) while the elbow is at its closest: the braking keeps d1 too.
"""
import csv
import os
import sys

from simcheck import FAILS, check, sim_run


def run(sim, scn, work, scheme, tag, extra=()):
    r = sim_run(sim, scn, work, scheme, tag, extra, with_csv=True)
    if r is None:
        return None
    with open(r["csv"]) as f:
        r["csv_self_d"] = [float(row["self_d"]) for row in csv.DictReader(f)]
    # the summary's pairs per kind: no arm pair (null, as min_distance), no body, the self pairs' least the
    # least of the CSV's self_d column (every tick)
    k = r["pair_kinds"]
    check(r["min_distance"] is None and k["arm-arm"]["min"] is None and k["arm-body"]["min"] is None and
          k["arm-track"]["min"] is None and r["body_min"] == [] and
          abs(k["self"]["min"] - min(r["csv_self_d"])) < 1e-6,
          "%s: pairs per kind: arm-arm null, no bodies, self %s = least of the CSV's self_d %.6f" %
          (tag, k["self"]["min"], min(r["csv_self_d"] or [0])))
    print("%-22s completed %d, fault %s, self: least %.5f m (pair %s, %.3f s), %d ticks below d1, path error "
          "max %.3e m, tick cpu p50/p99 %.1f/%.1f us" %
          (tag, r["completed"], r["fault_name"], r["self_min_distance"], r["self_min_pair"], r["self_min_t"],
           r["self_ticks_below"], r["path_error_max"], r["cpu_p50_ns"] / 1e3, r["cpu_p99_ns"] / 1e3))
    return r


def main():
    sim, scn_dir, work = sys.argv[1:4]
    scn = os.path.join(scn_dir, "self_fold.yaml")

    for scheme in ("mca-ts", "mca"):
        n = run(sim, scn, work, scheme, scheme + "-no-self-rows", ["--no-self-rows"])
        if n:
            check(n["self_min_distance"] < n["d1"] - 0.02 and n["self_ticks_below"] > 1000 and
                  min(n["csv_self_d"]) < n["d1"] - 0.02,
                  "%s without the self rows: links %s-%s fold to %.5f m < d1 for %d ticks" %
                  (scheme, n["self_min_pair"][1], n["self_min_pair"][2], n["self_min_distance"],
                   n["self_ticks_below"]))
        r = run(sim, scn, work, scheme, scheme)
        if r:
            check(r["self_ticks_below"] == 0 and r["self_min_distance"] >= r["d1"] and
                  len(r["csv_self_d"]) >= 5000 and min(r["csv_self_d"]) >= r["d1"],
                  "%s with the self rows: >= d1 on every tick (least %.5f m, CSV %.5f m over %d ticks)" %
                  (scheme, r["self_min_distance"], min(r["csv_self_d"] or [0]), len(r["csv_self_d"])))
            check(r["fault"] == 0 and r["completed"] == 1 and r["path_error_max"] < 1e-4,
                  "%s with the self rows: completed, no fault, path error max %.3e m" %
                  (scheme, r["path_error_max"]))

    for dec in ("2", "10"):
        s = run(sim, scn, work, "mca-ts", "stop-4.3-dec" + dec, ["--stop-at", "4.3", "--dec-limit", dec])
        if s:
            check(s["self_ticks_below"] == 0 and min(s["csv_self_d"]) >= s["d1"] and s["stop_requested"] == 1,
                  "stop at 4.3 s, dec %s rad/s^2: >= d1 while braking (least %.5f m)" %
                  (dec, min(s["csv_self_d"] or [0])))

    if FAILS:
        print("%d check(s) failed" % len(FAILS))
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
