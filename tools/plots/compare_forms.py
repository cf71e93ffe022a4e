#!/usr/bin/env python3
"""Compare the collision-row forms on the tasks (docs/scheme.md table).

usage: compare_forms.py MCA_SIM SCENARIO_DIR
Runs mca-sim (sim backend) per task with: the paper's componentwise rows (v_floor 0), componentwise with a
floor of 0.02 m/s, and the normal form (v_normal 0.5 m/s, the default); prints a Markdown table of the
minimum distance, the maximum tracking error (overall / while no collision row binds), the PDNN steps
(max / mean), ticks at the PDNN step cap and the fault, if any.
"""
import json
import os
import subprocess
import sys
import tempfile

VARIANTS = [("componentwise, v_floor 0 (paper)", ["--form", "componentwise", "--v-floor", "0"]),
            ("componentwise, v_floor 0.02", ["--form", "componentwise", "--v-floor", "0.02"]),
            ("normal, v_normal 0.5 (default)", ["--form", "normal", "--v-normal", "0.5"])]
TASKS = ["cross_circles", "hui", "cup_stacking", "negative"]


def main():
    sim, sdir = sys.argv[1:3]
    print("| task | form | min d [m] | max err [m] (no binding row) | PDNN steps max / mean | capped ticks | "
          "fault |")
    print("|---|---|---|---|---|---|---|")
    with tempfile.TemporaryDirectory() as tmp:
        for t in TASKS:
            for label, extra in VARIANTS:
                summ = os.path.join(tmp, "s.json")
                subprocess.run([sim, "--scenario", os.path.join(sdir, t + ".yaml"), "--scheme", "mca", "--summary",
                                summ] + extra, check=True, capture_output=True)
                s = json.load(open(summ))
                r = s["runs"][0]
                fault = "none" if not r["fault"] else "%s at %.2f s (d %.4f)" % (r["fault_name"], r["fault_t"],
                                                                                r["fault_distance"])
                print("| %s | %s | %.4f | %.2e (%.2e) | %d / %.1f | %d | %s |" % (
                    t, label, r["min_distance"], r["max_err"], r["max_err_free"], r["pdnn_steps_max"],
                    r["pdnn_steps_mean"], r["pdnn_capped"], fault), flush=True)


if __name__ == "__main__":
    main()
