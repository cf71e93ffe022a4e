#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Plot an mca-simarm-trace CSV: joint velocities and positions over time, with the arm state
shaded (SERVOING white, BRAKING orange, FAULT red, READY grey).

Usage: plot_trace.py TRACE.csv OUT.png [--joint J] [--title TEXT]
"""
import argparse
import csv
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

COLORS = {1: "#dddddd", 3: "#ffcc88", 4: "#ff8888"}
NAMES = {1: "READY", 2: "SERVOING", 3: "BRAKING", 4: "FAULT"}


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("trace")
    ap.add_argument("out")
    ap.add_argument("--joint", type=int, default=0)
    ap.add_argument("--title", default="")
    a = ap.parse_args()
    with open(a.trace) as f:
        meta = [ln for ln in f if ln.startswith("#")]
    with open(a.trace) as f:
        rows = [r for r in csv.DictReader(ln for ln in f if not ln.startswith("#")) if r["rc"] == "0"]
    if not rows:
        sys.exit(f"{a.trace}: no feedback rows")
    dt = float(dict(t.split("=") for t in meta[0][1:].split())["dt"])
    j = a.joint
    t = [int(r["k"]) * dt for r in rows]
    fig, (ax1, ax2) = plt.subplots(2, 1, sharex=True, figsize=(8, 5))
    start = 0
    for i in range(1, len(rows) + 1):
        if i == len(rows) or rows[i]["state"] != rows[start]["state"]:
            st = int(rows[start]["state"])
            if st in COLORS:
                for ax in (ax1, ax2):
                    ax.axvspan(t[start], t[i - 1] + dt, color=COLORS[st], alpha=0.5, lw=0)
                ax1.text(t[start], 0.02, NAMES[st], transform=ax1.get_xaxis_transform(), fontsize=7)
            start = i
    u = [float(r[f"u{j}"]) if r["has_cmd"] == "1" else float("nan") for r in rows]  # gaps: none sent
    ax1.plot(t, u, "--", lw=1, label=f"command u{j}")
    ax1.plot(t, [float(r[f"v{j}"]) for r in rows], lw=1.2, label=f"feedback v{j}")
    ax1.set_ylabel("velocity [rad/s]")
    ax1.legend(loc="upper right", fontsize=8)
    ax2.plot(t, [float(r[f"q{j}"]) for r in rows], lw=1.2, label=f"q{j}")
    ax2.set_ylabel("position [rad]")
    ax2.set_xlabel("time [s]")
    fig.suptitle(a.title or meta[0][1:].strip(), fontsize=9)
    fig.tight_layout()
    fig.savefig(a.out, dpi=110)
    return 0


if __name__ == "__main__":
    sys.exit(main())
