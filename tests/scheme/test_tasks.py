#!/usr/bin/env python3
"""The paper's four tasks through mca-sim (the controller tick the daemon runs, arms in the sim backend).

usage: test_tasks.py MCA_SIM SCENARIO_DIR WORK_DIR
 1. cross circles: MVN goes below d1 (paper Table I), MCA stays above d1 at every tick, no fault;
 2. Hui, 3. cup stacking: MVN goes below d1, MCA stays above d1 at every tick with collision rows
    binding, no fault, the whole task;
    tasks 1-3: MCA's end-effector error <= 1e-4 m while no collision row binds, and overall;
 4. negative example: MCA ends in a braked stop with a named fault, no distance below d1 (MVN collides).
 5. path first: tasks 1-3 as shipped under mca-ts (path first, tolerance 0, the default): every
    pair >= d1, the task completed, the tool tips' distance to their paths' curves <= 2e-5 m; with
    `tracking: elastic` on every path the same tasks leave the path by more (the exact penalty holds it).
Prints the figures (min distance, tracking errors, PDNN steps, tick compute time).
"""
import json
import os
import subprocess
import sys

FAILS = []


def check(cond, msg):
    print(("ok   " if cond else "FAIL ") + msg)
    if not cond:
        FAILS.append(msg)


def run(sim, scn, work, schemes, extra=()):
    os.makedirs(work, exist_ok=True)
    base = os.path.splitext(os.path.basename(scn))[0]
    summ = os.path.join(work, "%s-%s.json" % (base, schemes.replace(",", "-")))
    cmd = [sim, "--scenario", scn, "--scheme", schemes, "--summary", summ] + list(extra)
    p = subprocess.run(cmd, capture_output=True, text=True, timeout=500)
    print(p.stdout)
    if p.returncode != 0:
        print(p.stderr)
        FAILS.append("mca-sim failed on %s" % scn)
        return None
    s = json.load(open(summ))
    return {r["scheme"]: r for r in s["runs"]}, s["d1"]


def elastic_copy(src, work):
    """The scenario with `tracking: elastic` on every path (robot paths made absolute for the copy's folder)."""
    out = []
    for line in open(src):
        stripped = line.lstrip()
        if stripped.startswith("urdf: ../"):
            line = line.replace("../", os.path.dirname(os.path.dirname(os.path.abspath(src))) + "/", 1)
        out.append(line)
        if stripped.startswith("kind: ") and stripped.split()[1] in ("circle", "waypoints"):
            out.append(line[: len(line) - len(stripped)] + "tracking: elastic\n")
    dst = os.path.join(work, "elastic-" + os.path.basename(src))
    with open(dst, "w") as f:
        f.writelines(out)
    return dst


def path_first(sim, sdir, work):
    for name in ("cross_circles", "hui", "cup_stacking"):
        pf, d1 = run(sim, os.path.join(sdir, name + ".yaml"), work, "mca-ts")
        el, _ = run(sim, elastic_copy(os.path.join(sdir, name + ".yaml"), work), work, "mca-ts")
        el, pf = el["mca-ts"], pf["mca-ts"]
        check(pf["min_distance"] >= d1 and pf["fault"] == 0 and pf["completed"] == 1,
              "%s path first: completed %d, no fault (%s), min distance %.5f m >= d1 %.3f" %
              (name, pf["completed"], pf["fault_name"], pf["min_distance"], d1))
        check(pf["path_error_max"] <= 2e-5, "%s path first: path error max %.3e m <= 2e-5 (elastic: %.3e m)" %
              (name, pf["path_error_max"], el["path_error_max"]))
        check(el["path_error_max"] > pf["path_error_max"],
              "%s: elastic tracking leaves the path by more (%.3e > %.3e m)" %
              (name, el["path_error_max"], pf["path_error_max"]))


def slow_arms(sim, sdir, work):
    """Cup stacking on arms that decelerate at 0.5 rad/s^2: the paths ask more than the arms can follow on
    their bends, so the path rate is slowed there (sigma's own stop bound, mca/path_rate.h), not the path left
    (without the bound: 4.6 cm)."""
    r, d1 = run(sim, os.path.join(sdir, "cup_stacking.yaml"), os.path.join(work, "dec05"), "mca-ts",
                ("--dec-limit", "0.5"))
    m = r["mca-ts"]
    check(m["completed"] == 1 and m["fault"] == 0 and m["min_distance"] >= d1,
          "cup stacking at dec 0.5: completed %d, no fault (%s), min distance %.5f m >= d1" %
          (m["completed"], m["fault_name"], m["min_distance"]))
    check(m["path_error_max"] <= 5e-3, "cup stacking at dec 0.5: path error max %.3e m <= 5e-3 (time lost %.2f s)" %
          (m["path_error_max"], m["path_time_lost_s"]))


def main():
    sim, sdir, work = sys.argv[1:4]
    tol = 1e-4
    # 1. cross circles
    r, d1 = run(sim, os.path.join(sdir, "cross_circles.yaml"), work, "mvn,mca")
    mvn, mca = r["mvn"], r["mca"]
    check(mvn["min_distance"] < d1, "task 1: MVN min distance %.5f m < d1 %.3f (at %.3f s)" %
          (mvn["min_distance"], d1, mvn["min_distance_t"]))
    check(mca["min_distance"] > d1, "task 1: MCA min distance %.5f m > d1" % mca["min_distance"])
    check(mca["fault"] == 0, "task 1: MCA no fault (%s)" % mca["fault_name"])
    check(mca["ticks"] >= 10000, "task 1: MCA ran the whole task (%d ticks)" % mca["ticks"])
    for name in ("hui", "cup_stacking"):
        r2, d1b = run(sim, os.path.join(sdir, name + ".yaml"), work, "mvn,mca")
        m = r2["mca"]
        # Hui and cup stacking: without MCA the arms come closer than d1; with MCA the collision rows bind
        check(r2["mvn"]["min_distance"] < d1b, "%s: MVN min distance %.5f m < d1 (at %.3f s, no MCA)" %
              (name, r2["mvn"]["min_distance"], r2["mvn"]["min_distance_t"]))
        check(r2["mvn"]["fault"] == 0, "%s: MVN ran without fault (%s)" % (name, r2["mvn"]["fault_name"]))
        check(m["binding_ticks"] > 0, "%s: collision rows did bind (%d ticks)" % (name, m["binding_ticks"]))
        check(m["ticks"] >= r2["mvn"]["ticks"], "%s: MCA ran the whole task (%d ticks)" % (name, m["ticks"]))
        check(m["min_distance"] > d1b, "%s: MCA min distance %.5f m > d1 %.3f" % (name, m["min_distance"], d1b))
        check(m["fault"] == 0, "%s: MCA no fault (%s)" % (name, m["fault_name"]))
        check(m["max_err_free"] <= tol and m["max_err"] <= tol,
              "%s: MCA max tracking error %.3e m (free of binding rows %.3e m) <= %.0e" %
              (name, m["max_err"], m["max_err_free"], tol))
    check(mca["max_err_free"] <= tol and mca["max_err"] <= tol,
          "task 1: MCA max tracking error %.3e m (free of binding rows %.3e m) <= %.0e" %
          (mca["max_err"], mca["max_err_free"], tol))
    check(mca["binding_ticks"] > 0, "task 1: collision rows did bind (%d ticks)" % mca["binding_ticks"])
    # 4. negative example
    r4, d14 = run(sim, os.path.join(sdir, "negative.yaml"), work, "mvn,mca")
    m = r4["mca"]
    check(r4["mvn"]["min_distance"] < d14, "task 4: MVN collides (%.5f m)" % r4["mvn"]["min_distance"])
    check(m["fault_name"] in ("fake-attractor", "pdnn-not-converged", "distance-below-d1"),
          "task 4: MCA fault named: %s at %.3f s (distance %.5f m)" % (m["fault_name"], m["fault_t"],
                                                                         m["fault_distance"]))
    check(m["stopped"] == 1, "task 4: arms braked to a stop (at %.3f s)" % m["stop_t"])
    check(m["min_distance"] > d14, "task 4: no distance below d1 in the whole run, braking included (%.5f m)" %
          m["min_distance"])
    path_first(sim, sdir, work)
    slow_arms(sim, sdir, work)
    if FAILS:
        print("\n%d check(s) failed" % len(FAILS))
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
