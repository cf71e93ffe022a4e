#!/usr/bin/env python3
"""Issue 11 checks (ctest -L sweep).

usage: test_sweep.py pa10|pa10-simarm MCA_SIM MCA_SWEEP_PY WORK_DIR
         50 seeded random two-PA10+ tasks through tools/mca-sweep (seed 11): the tasks exercise the scheme
         (>= 70 % reachable, MVN below d1 on >= 5 of them) and mca-ts completes, on its paths (path first),
         >= 90 % of the reachable tasks and >= 95 % of those whose paths clear the other arm at rest. pa10: arms that realise each command exactly (mca-sim --euler): no mca-ts run below d1 (task,
         and with a stop request). pa10-simarm: the sim backend's rate-limited firmware model: the stop runs
         have none below d1, the task runs at most KNOWN_SIMARM_UNSAFE (1) (a known gap, see
         docs/scheme.md "What is not yet shown"; the bound makes a regression fail);
       test_sweep.py regress MCA_SIM MCA_SWEEP_PY WORK_DIR [MCA_STOPCHECK]
         tasks of the full sweep (seed 1) that once went below d1 under mca-ts: MVN goes below d1 on each,
         mca-ts keeps d1 (task and with a stop request). jaco-mico:411: the tool links nearly parallel, the
         closest points jumped from one end to the other (a row on the closest points only, 2 mm below d1);
       test_sweep.py three MCA_SIM THREE_ARMS_YAML WORK_DIR
         the three-arm task: MVN goes below d1; mca-ts keeps every pair (CSV d_<a>_<b>) >= d1 at every tick,
         braking included, and completes;
       test_sweep.py pnp MCA_SIM MCA_SWEEP_PY WORK_DIR
         pick and place, 4 pnp-jaco-mico + 4 pnp-pa10 tasks (seed 3): every task reachable (MVN
         tracks it alone), each arm's picks in its own pick area on its side of the zone, every place point in
         the shared zone and >= sep from the other arm's, the exact indices exactly the grasp/release dwell
         pairs, timetables 25-45 s, the pick-and-place keys written iff this mca-sim takes them; MVN below d1 on some
         task of each kind (the arms meet), mca-ts never; one task drawn again alone is the same scenario.
Exit 77 (ctest SKIP) when this mca-sim has no scheme mca-ts.
"""
import csv
import json
import math
import os
import re
import subprocess
import sys

FAILS = []
KNOWN_SIMARM_UNSAFE = 1  # measured 0 of 49 at the commit setting this (1 of 49 before the capped-answer repair)


def check(cond, msg):
    print(("ok   " if cond else "FAIL ") + msg)
    if not cond:
        FAILS.append(msg)


def has_ts(sim):
    h = subprocess.run([sim, "--help"], capture_output=True, text=True).stdout
    m = re.search(r"--scheme ([a-z|\-]+)", h)
    return bool(m) and "mca-ts" in m.group(1).split("|")


def sweep(sim, tool, work, ideal):
    os.makedirs(work, exist_ok=True)
    out = os.path.join(work, "sweep.json")
    cmd = [sys.executable, tool, "--sim", sim, "--kind", "pa10", "--n", "50", "--seed", "11", "--jobs", "2",
           "--schemes", "mvn,mca,mca-ts", "--work", os.path.join(work, "tasks"), "--json", out] + \
        (["--ideal-arms"] if ideal else [])
    print(" ".join(cmd))
    p = subprocess.run(cmd, capture_output=True, text=True, timeout=400)
    print(p.stdout)
    if p.returncode != 0:
        print(p.stderr)
        sys.exit("mca_sweep.py failed (exit %d)" % p.returncode)
    d = json.load(open(out))
    nr = d["reachable"]
    n = len(d["tasks"])
    check(n == 50, "50 tasks drawn (%d)" % n)
    check(nr >= 35, "reachable tasks %d >= 35 of %d" % (nr, n))
    mvn = d["summary"]["mvn/task"]
    check(mvn is not None and mvn["unsafe"] >= 5, "MVN goes below d1 on %s >= 5 tasks (the sweep exercises the "
          "scheme)" % (mvn and mvn["unsafe"]))
    ts = d["summary"]["mca-ts/task"]
    check(ts is not None, "mca-ts ran")
    if ts:
        bad = [t["id"] for t in d["tasks"] if t.get("reachable") and t["runs"]["mca-ts"]["task"]["cls"] == "unsafe"]
        allowed = 0 if ideal else KNOWN_SIMARM_UNSAFE
        check(ts["unsafe"] <= allowed, "mca-ts: %d runs below d1 (want <= %d) %s" % (ts["unsafe"], allowed,
                                                                                     " ".join(bad)))
        # completed = on the path (path first, tolerance 0: the default; the elastic tracking
        # "completed" 49 of 50 here by leaving its paths by up to 10 cm). A task whose path runs into the other
        # arm standing at its start (= end) cannot be completed by any path rate: the bar of 95 % is on the
        # others (mca_sweep.py's a-priori rest probe), 90 % on all.
        done = ts["completed"] + ts["late"]
        cl = d["summary"].get("clear/mca-ts") or {}
        check(done >= 0.90 * nr, "mca-ts completes %d of %d reachable tasks (%.1f %%, want >= 90 %%; %d within "
              "%.2f s of path time)" % (done, nr, 100.0 * done / max(nr, 1), ts["completed"], d["lost_threshold"]))
        check(cl.get("clear", 0) >= 0.7 * nr and cl["done"] >= 0.95 * cl["clear"],
              "mca-ts completes %s of the %s reachable tasks whose paths clear the other arm at rest (want >= 95 %%)"
              % (cl.get("done"), cl.get("clear")))
    st = d["summary"].get("mca-ts/stop")
    if d["features"]["stop_at"] and st:
        check(st["unsafe"] == 0, "mca-ts with a stop request: %d runs below d1 (want 0)" % st["unsafe"])
    else:
        print("note: this mca-sim has no --stop-at: no stop runs checked")


REGRESSIONS = ["jaco-mico:411"]
# tasks whose stops along the way (mca-stopcheck: every 20 ms, dec 0.5, 2, 5) must all keep d1: jaco-mico:19
# at dec 0.5 went below d1 at c828870 (20 stops) and again at f1ca96b (39 stops, the task itself faulted at
# 9.716 s: a capped PDNN's answer outside the acceleration box, where pruned rows do not hold)
STOP_REGRESSIONS = ["jaco-mico:19"]


def run_sweep(tool, sim, work, name, args, timeout, seed=1, kind="jaco-mico"):
    """mca_sweep.py on `kind` tasks (jaco-mico) with args, its work files under work/name; (the JSON it wrote, what
    it printed)."""
    out = os.path.join(work, name + ".json")
    cmd = [sys.executable, tool, "--sim", sim, "--kind", kind, "--seed", str(seed), "--jobs", "2", "--work",
           os.path.join(work, name), "--json", out] + args
    print(" ".join(cmd))
    p = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout)
    print(p.stdout)
    if p.returncode != 0:
        print(p.stderr)
        sys.exit("mca_sweep.py failed (exit %d)" % p.returncode)
    return json.load(open(out)), p.stdout


def regress(sim, tool, work, stopcheck=None):
    os.makedirs(work, exist_ok=True)
    d, _ = run_sweep(tool, sim, work, "tasks", ["--n", "500", "--only", ",".join(REGRESSIONS), "--schemes", "mvn,mca-ts"],
                  400)
    check(len(d["tasks"]) == len(REGRESSIONS), "%d tasks run" % len(d["tasks"]))
    for t in d["tasks"]:
        runs = t["runs"]
        check(runs["mvn"]["task"]["cls"] == "unsafe", "%s: MVN goes below d1 (%s)" % (t["id"],
                                                                                   runs["mvn"]["task"]["cls"]))
        for r in ("task", "stop"):
            cls = runs["mca-ts"][r]["cls"]
            check(cls != "unsafe", "%s: mca-ts %s run keeps d1 (%s)" % (t["id"], r, cls))
    # jaco-mico:132 at tolerance 0: two arms at rest, one backing off through a dwell; standing still sat on three
    # of the tube's edges at once, and the PDNN left 24306 of 30541 ticks unconverged (MCA_TUBE_FLOOR since)
    d, _ = run_sweep(tool, sim, work, "vertex", ["--n", "500", "--only", "jaco-mico:132", "--schemes", "mca-ts",
                                               "--no-stop"], 400)
    r = d["tasks"][0]["runs"]["mca-ts"]["task"]
    if r.get("solves"):
        check(r["solves_unconverged"] <= 0.01 * r["solves"] and r["min_d"] >= d["tasks"][0]["d1"],
              "jaco-mico:132: %d of %d solves unconverged (want <= 1 %%), least distance %.4f m" %
              (r["solves_unconverged"], r["solves"], r["min_d"]))
    else:
        print("note: this mca-sim reports no solver counts: jaco-mico:132 not judged")
    if not stopcheck:
        return
    d, _ = run_sweep(tool, sim, work, "stop-tasks", ["--n", "50", "--only", ",".join(STOP_REGRESSIONS), "--schemes",
                                                  "mca-ts", "--no-stop", "--stopcheck", stopcheck], 600)
    check(len(d["tasks"]) == len(STOP_REGRESSIONS), "%d stop-check tasks run" % len(d["tasks"]))
    for t in d["tasks"]:
        runs = t.get("stopcheck") or []
        check(len(runs) == 3, "%s: stops at 3 deceleration limits" % t["id"])
        for r in runs:
            check(r["below_d1"] == 0 and r["task_fault"] == "none" and r["stops"] > 400,
                  "%s: dec %g: %d stops, %d below d1 (least %.4f m, d1 %.3f), task fault %s" %
                  (t["id"], r["dec"], r["stops"], r["below_d1"], min(r["min_distance_task"], r["min_distance_brake"]),
                   t["d1"], r["task_fault"]))


def path_first(sim, tool, work):
    """Issue 29: crossing tasks with a 5 cm tube (seed 501). The tube holds (path_error_max <= 5 cm), d1 holds,
    the tasks whose paths clear the other arm at rest complete, and one whose path runs into the other arm
    standing at home (jaco-mico:0, found by the a-priori rest probe) ends named: blocked by that arm at its
    path's end (before the averaged hold it crawled unnamed; before the tube's edge rule its error reached 8.3 cm)."""
    os.makedirs(work, exist_ok=True)
    d, printed = run_sweep(tool, sim, work, "pf", ["--n", "16", "--only", "0,3,6,7", "--schemes", "mca-ts",
                                                   "--no-stop", "--tolerance", "0.05"], 300, seed=501)
    tasks = {t["id"]: t for t in d["tasks"]}
    check(len(tasks) == 4, "4 tasks run")
    for tid, t in sorted(tasks.items()):
        r = t["runs"]["mca-ts"]["task"]
        check(r["min_d"] >= t["d1"], "%s: least distance %.4f m >= d1 %.3f" % (tid, r["min_d"], t["d1"]))
        check(r["path_error_max"] <= 0.05, "%s: path error max %.4f m within the 5 cm tube" % (tid, r["path_error_max"]))
        if tid != "jaco-mico:0":
            check(not t["rest_conflicts"] and r["cls"] in ("completed", "late"),
                  "%s: paths clear of the other arm at rest (%s), done (%s)" % (tid, t["rest_conflicts"], r["cls"]))
    t0 = tasks["jaco-mico:0"]
    check([1, 0] in [c[:2] for c in t0["rest_conflicts"]],
          "jaco-mico:0: arm 1's path runs into arm 0 at rest (%s)" % t0["rest_conflicts"])
    check(t0["runs"]["mca-ts"]["task"]["cls"] == "safe-stop" and
          "jaco-mico:0 " in printed and "blocked by arm0 at its path's end" in printed,
          "jaco-mico:0: unfinished, named as blocked by arm0 standing at its path's end")


def coordinate(sim, tool, work):
    """Issue 29: who passes first, planned at start-up (mca/coord.h). Three pick-and-place tasks (seed 1) that
    deadlocked in the shared place zone without the plan (backing off put one arm back into the other's way)
    complete with it, on their paths, exact points met, d1 kept; without it (--no-coordinate) they deadlock
    again, so this test fails when the plan is taken out. A crossing task whose fixed paths meet whoever goes first
    (jaco-mico:7) ends named: no schedule."""
    os.makedirs(work, exist_ok=True)
    ids = ["pnp-jaco-mico:1", "pnp-jaco-mico:8", "pnp-jaco-mico:10"]
    args = ["--n", "30", "--only", ",".join(ids), "--schemes", "mca-ts", "--no-stop"]
    on, _ = run_sweep(tool, sim, work, "on", args, 300, kind="pnp-jaco-mico")
    off, _ = run_sweep(tool, sim, work, "off", args + ["--no-coordinate"], 300, kind="pnp-jaco-mico")
    check(len(on["tasks"]) == 3 and len(off["tasks"]) == 3, "3 + 3 tasks run")
    for t in on["tasks"]:
        r = t["runs"]["mca-ts"]["task"]
        check(r["cls"] in ("completed", "late") and r["exact_missed"] == 0 and r["coord_pairs"] == 1,
              "%s: done with the plan (%s, %s exact points missed, %s pair planned)" %
              (t["id"], r["cls"], r["exact_missed"], r["coord_pairs"]))
        check(r["min_d"] >= t["d1"] and r["path_error_max"] <= 0.02,
              "%s: least distance %.4f m >= d1 %.3f, path error max %.4f m" %
              (t["id"], r["min_d"], t["d1"], r["path_error_max"]))
    stuck = [t["id"] for t in off["tasks"] if t["runs"]["mca-ts"]["task"]["cls"] not in ("completed", "late")]
    check(len(stuck) >= 2, "without the plan at least 2 of the 3 deadlock for good (%s)" % stuck)
    d, printed = run_sweep(tool, sim, work, "cross", ["--n", "10", "--only", "7", "--schemes", "mca-ts", "--no-stop"],
                           300)
    r = d["tasks"][0]["runs"]["mca-ts"]["task"]
    check(r["coord_unplanned"] == 1 and r["min_d"] >= d["tasks"][0]["d1"] and
          "no schedule: the predicted arms meet on every order of passing" in printed,
          "jaco-mico:7: no schedule exists, the task is named so, d1 kept (%s unplanned, least %.4f m)" %
          (r["coord_unplanned"], r["min_d"]))


def three(sim, scn, work):
    os.makedirs(work, exist_ok=True)
    summ = os.path.join(work, "three.json")
    base = os.path.join(work, "three")
    cmd = [sim, "--scenario", scn, "--scheme", "mvn,mca-ts", "--summary", summ, "--csv", base]
    p = subprocess.run(cmd, capture_output=True, text=True, timeout=100)
    print(p.stdout)
    if p.returncode != 0:
        print(p.stderr)
        sys.exit("mca-sim failed")
    s = json.load(open(summ))
    d1 = s["d1"]
    r = {x["scheme"]: x for x in s["runs"]}
    check(r["mvn"]["min_distance"] < d1, "three arms: MVN min distance %.5f m < d1 %.3f (at %.3f s)" %
          (r["mvn"]["min_distance"], d1, r["mvn"]["min_distance_t"]))
    ts = r["mca-ts"]
    with open(base + "-mca-ts.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    pairs = [k for k in rows[0] if re.fullmatch(r"d_\d+_\d+", k)]
    check(pairs == ["d_0_1", "d_0_2", "d_1_2"], "the CSV has the three pair distances (%s)" % ",".join(pairs))
    for k in pairs:
        m = min(float(x[k]) for x in rows)
        check(m >= d1, "three arms: mca-ts pair %s min %.5f m >= d1 at every tick" % (k[2:], m))
    mins = [ts["min_distance"]] + [v for k, v in ts.items() if k.startswith("min_distance") and not k.endswith("_t")
                                   and k != "min_distance" and not (k == "min_distance_after_fault" and v == -1)]
    check(min(mins) >= d1, "three arms: mca-ts min distance over the task and any braking %.5f m >= d1" % min(mins))
    check(ts.get("completed") == 1, "three arms: mca-ts completes (completed %s, fault %s, %s s path time lost, "
          "%s deadlocks)" % (ts.get("completed"), ts["fault_name"], ts.get("path_time_lost_s"), ts.get("deadlocks")))


def pnp(sim, tool, work):
    os.makedirs(work, exist_ok=True)
    out = os.path.join(work, "pnp.json")
    n = 4
    cmd = [sys.executable, tool, "--sim", sim, "--kind", "pnp-jaco-mico,pnp-pa10", "--n", str(n), "--seed", "3",
           "--jobs", "2", "--schemes", "mvn,mca-ts", "--no-stop", "--work", os.path.join(work, "tasks"), "--json", out]
    print(" ".join(cmd))
    p = subprocess.run(cmd, capture_output=True, text=True, timeout=400)
    print(p.stdout)
    if p.returncode != 0:
        print(p.stderr)
        sys.exit("mca_sweep.py failed (exit %d)" % p.returncode)
    d = json.load(open(out))
    keys = d["features"]["scenario_keys"]
    tasks = d["tasks"]
    check(len(tasks) == 2 * n, "%d tasks drawn (%d)" % (2 * n, len(tasks)))
    bad = ["%s (%s)" % (t["id"], t.get("unreachable")) for t in tasks if not t.get("reachable")]
    check(not bad, "every pick-and-place task reachable: MVN tracks each arm's path alone %s" % " ".join(bad))
    for t in tasks:
        if "pnp" not in t:
            continue
        g = t["pnp"]
        o, e, nn = g["frame"]

        def afz(pt):
            dd = [a - b for a, b in zip(pt, o)]
            return [sum(a * b for a, b in zip(dd, e)), sum(a * b for a, b in zip(dd, nn)), dd[2]]

        def inside(c, box):
            return all(lo - 1e-3 <= x <= hi + 1e-3 for x, (lo, hi) in zip(c, box))

        zone = g["zone"]
        arms = g["arms"]
        check(len(arms) == 2 and all(2 <= a["rounds"] <= 3 for a in arms),
              "%s: two arms, 2-3 rounds each (%s)" % (t["id"], [a["rounds"] for a in arms]))
        for k, a in enumerate(arms):
            cp = [afz(x) for x in a["picks"]]
            cq = [afz(x) for x in a["places"]]
            side = all(c[0] < zone[0][0] for c in cp) if k == 0 else all(c[0] > zone[0][1] for c in cp)
            check(all(inside(c, g["pick_areas"][k]) for c in cp) and side,
                  "%s %s: picks in its own pick area, on its side of the zone (along %s, zone %s)" % (
                      t["id"], a["arm"], ["%.3f" % c[0] for c in cp], zone[0]))
            check(all(inside(c, zone) for c in cq), "%s %s: every place point in the shared zone" % (t["id"], a["arm"]))
            pts, ex = a["points"], a["exact"]
            pairs = [(ex[j], ex[j + 1]) for j in range(0, len(ex), 2)]
            dwell = [(j, j + 1) for j in range(len(pts) - 1) if pts[j] == pts[j + 1] and
                     any(pts[j] == q for q in a["picks"] + a["places"])]
            check(len(ex) == 4 * a["rounds"] and pairs == dwell,
                  "%s %s: the exact indices are the %d grasp/release dwell pairs (%s)" % (
                      t["id"], a["arm"], 2 * a["rounds"], ex))
            check(25.0 - 0.05 <= a["total"] <= 45.0 + 0.05, "%s %s: timetable %.2f s in 25-45 s" % (
                t["id"], a["arm"], a["total"]))
        sep = min(math.hypot(p[0] - q[0], p[1] - q[1]) for p in arms[0]["places"] for q in arms[1]["places"])
        check(sep >= g["sep"] - 1e-3, "%s: the arms' place points %.3f m >= %.2f m apart" % (t["id"], sep, g["sep"]))
        txt = open(t["scenario"]).read()
        check(("exact:" in txt) == keys["exact"] and ("exact_tolerance:" in txt) == keys["exact_tolerance"] and
              "relative: false" in txt, "%s: scenario with absolute waypoints, exact keys iff mca-sim takes them (%s)"
              % (t["id"], keys))
    for kind in ("pnp-jaco-mico", "pnp-pa10"):
        kt = [t for t in tasks if t["id"].startswith(kind + ":") and t.get("reachable")]
        mvn = [t["runs"]["mvn"]["task"]["min_d"] for t in kt]
        ts = [t["runs"]["mca-ts"]["task"] for t in kt]
        check(sum(1 for t, m in zip(kt, mvn) if m < t["d1"]) >= 1,
              "%s: MVN below d1 on %d of %d tasks (least %s m): the arms meet" % (
                  kind, sum(1 for t, m in zip(kt, mvn) if m < t["d1"]), len(kt), min(mvn) if mvn else None))
        check(all(r["cls"] != "unsafe" for r in ts), "%s: mca-ts keeps d1 on every task (least %.4f m; %s)" % (
            kind, min(r["min_d"] for r in ts), [r["cls"] for r in ts]))
    # task 1 of pnp-pa10 again, alone: the same scenario (drawn from "3:pnp-pa10:1" only)
    again = os.path.join(work, "again")
    p = subprocess.run([sys.executable, tool, "--sim", sim, "--kind", "pnp-pa10", "--n", "1", "--seed", "3", "--only",
                        "pnp-pa10:1", "--schemes", "mvn", "--no-stop", "--work", again, "--json",
                        os.path.join(work, "again.json")], capture_output=True, text=True, timeout=200)
    first = [t for t in tasks if t["id"] == "pnp-pa10:1"][0]
    same = p.returncode == 0 and open(os.path.join(again, "sweep_pnp_pa10_1", "scenario.yaml")).read() == \
        open(first["scenario"]).read()
    check(same, "pnp-pa10:1 drawn again alone: the same scenario")


def main():
    mode, sim = sys.argv[1], sys.argv[2]
    if not has_ts(sim):
        print("SKIP: %s has no scheme mca-ts (mca-sim --help lists the schemes)" % sim)
        return 77
    if mode in ("pa10", "pa10-simarm"):
        sweep(sim, sys.argv[3], sys.argv[4], mode == "pa10")
    elif mode == "regress":
        regress(sim, sys.argv[3], sys.argv[4], sys.argv[5] if len(sys.argv) > 5 else None)
    elif mode == "path-first":
        path_first(sim, sys.argv[3], sys.argv[4])
    elif mode == "coordinate":
        coordinate(sim, sys.argv[3], sys.argv[4])
    elif mode == "three":
        three(sim, sys.argv[3], sys.argv[4])
    elif mode == "pnp":
        pnp(sim, sys.argv[3], sys.argv[4])
    else:
        sys.exit("unknown mode " + mode)
    if FAILS:
        print("%d check(s) failed" % len(FAILS))
        return 1
    print("all checks passed")
    return 0


if __name__ == "__main__":
    sys.exit(main())
