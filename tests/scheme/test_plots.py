#!/usr/bin/env python3
"""tools/plots/plot_run.py on a short mca-sim run: the three PNG figures are written and are PNGs.
usage: test_plots.py MCA_SIM SCENARIO_DIR PLOT_RUN VENV_PYTHON WORK_DIR"""
import os
import shutil
import subprocess
import sys


def main():
    sim, sdir, plot, py, work = sys.argv[1:6]
    shutil.rmtree(work, ignore_errors=True)
    os.makedirs(work)
    csv = os.path.join(work, "neg.csv")
    subprocess.run([sim, "--scenario", os.path.join(sdir, "negative.yaml"), "--scheme", "mvn,mca", "--duration", "3.5",
                    "--csv", csv], check=True, capture_output=True, timeout=300)
    out = os.path.join(work, "neg")
    p = subprocess.run([py, plot, "--out", out, "--d1", "0.05", "--d2", "0.12", "--title", "test",
                        "mvn=" + os.path.join(work, "neg-mvn.csv"), "mca=" + os.path.join(work, "neg-mca.csv")],
                       capture_output=True, text=True, timeout=300)
    print(p.stdout, p.stderr)
    if p.returncode != 0:
        return 1
    for kind in ("distance", "error", "paths"):
        f = "%s-%s.png" % (out, kind)
        ok = os.path.exists(f) and os.path.getsize(f) > 10000 and open(f, "rb").read(8) == b"\x89PNG\r\n\x1a\n"
        print(("ok   " if ok else "FAIL ") + f)
        if not ok:
            return 1
    # a bad argument is refused with a message
    p = subprocess.run([py, plot, "--out", out, "nolabel.csv"], capture_output=True, text=True, timeout=120)
    if p.returncode == 0 or "LABEL=file.csv" not in p.stderr:
        print("FAIL: bad run spec accepted")
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
