#!/usr/bin/env python3
"""Issue 11, stops through mcad's own pipeline in virtual time (mca-sim drives mca_drive_step):
1. cross circles under mca-ts, a stop request (--stop-at, as SIGTERM) mid-task at several instants and
   dec_limit 0.5, 2 and 5 rad/s^2 (--dec-limit, the daemon's braking box and the sim arm's): the run ends
   STOPPED with the arms at rest, min_distance (task and braking) >= d1, max_dv_over_dt_dec <= 1 (every
   per-tick commanded velocity change within dec_limit dt), the stop no longer than its bound;
2. an injected controller fault (--fault-at T:pdnn-not-converged): the summary names it, the daemon brakes
   to FAULT at rest within the dec limit, >= d1;
3. bad --stop-at / --fault-at values are usage errors (exit 2).
usage: test_stop_pipeline.py MCA_SIM SOURCE_DIR"""
import json
import os
import subprocess
import sys
import tempfile

sim, src = sys.argv[1], sys.argv[2]
scn = os.path.join(src, "config/scenarios/cross_circles.yaml")
tmp = tempfile.mkdtemp(prefix="mca-stop-pipe-")
fails = 0


def run(*args):
    summ = os.path.join(tmp, "s.json")
    p = subprocess.run([sim, "--scenario", scn, "--summary", summ] + list(args), capture_output=True, text=True)
    if p.returncode != 0:
        print(p.stdout, p.stderr)
        raise SystemExit("FAIL: mca-sim %s: exit %d" % (" ".join(args), p.returncode))
    with open(summ) as f:
        s = json.load(f)
    return s, s["runs"][0], p.stderr


def check(ok, what):
    global fails
    if not ok:
        fails += 1
    print(("ok   " if ok else "FAIL ") + what)


for dec in (0.5, 2.0, 5.0):
    for t_stop in (3.0, 6.5, 7.9):
        s, r, _ = run("--scheme", "mca-ts", "--stop-at", str(t_stop), "--dec-limit", str(dec))
        d1 = s["d1"]
        # the stop's bound: max|v|/dec (1 rad/s joint speed at most) x 1.5 + 20 ticks, then the scale-down
        bound = 2.5 * 1.0 / dec + 0.05
        check(r["stop_requested"] == 1 and r["state"] == "stopped" and r["fault"] == 0 and r["stopped"] == 1
              and r["min_distance"] >= d1 and r["max_dv_over_dt_dec"] <= 1.0 + 1e-9
              and 0.0 <= r["stop_duration_s"] <= bound and abs(r["brake_t"] - t_stop) < 1.5e-3,
              "mca-ts stop at %.1f s, dec %.1f: %s, min distance %.5f m (d1 %.3f) at %.3f s, max |dv|/(dec dt) "
              "%.6f, at rest after %.3f s, fallback ticks %d"
              % (t_stop, dec, r["state"], r["min_distance"], d1, r["min_distance_t"], r["max_dv_over_dt_dec"],
                 r["stop_duration_s"], r["brake_fallback_ticks"]))

s, r, err = run("--scheme", "mca-ts", "--fault-at", "5:pdnn-not-converged", "--dec-limit", "2")
check(r["fault_name"] == "pdnn-not-converged" and "injected" in r["fault_text"] and r["state"] == "fault"
      and r["stopped"] == 1 and abs(r["fault_t"] - 5.0) < 1.5e-3 and r["min_distance"] >= s["d1"]
      and r["max_dv_over_dt_dec"] <= 1.0 + 1e-9 and r["stop_duration_s"] > 0.0
      and "fault at t = 5.000 s" in err,
      "injected fault: %s (%s) at %.3f s, state %s, at rest after %.3f s, max |dv|/(dec dt) %.6f, min %.5f m"
      % (r["fault_name"], r["fault_text"], r["fault_t"], r["state"], r["stop_duration_s"],
         r["max_dv_over_dt_dec"], r["min_distance"]))

for bad in (["--stop-at", "-1"], ["--fault-at", "5"], ["--fault-at", "5:gremlins"], ["--dec-limit", "0"]):
    p = subprocess.run([sim, "--scenario", scn] + bad, capture_output=True, text=True)
    check(p.returncode == 2 and bad[0] in p.stderr, "%s -> exit %d: %s" % (" ".join(bad), p.returncode,
                                                                           p.stderr.strip()[:120]))
print("%d failures" % fails)
sys.exit(1 if fails else 0)
