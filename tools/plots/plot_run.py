#!/usr/bin/env python3
"""Figures from mca-sim CSV files (matplotlib; PNG).

usage: plot_run.py --out PREFIX [--d1 D1 --d2 D2] [--title T] LABEL=run.csv [LABEL=run.csv ...]
Writes
  PREFIX-distance.png  minimum distance vs time with d1, d2 (paper Fig. 10), one curve per run; with three
                       or more arms (CSV columns d_<a>_<b>) one curve per pair of arms instead;
  PREFIX-error.png     end-effector tracking error |r_d - r| per arm vs time (paper Fig. 11), per run;
  PREFIX-paths.png     both arms' end-effector paths in 3-D, desired dashed (paper Fig. 8), per run.
Example:
  mca-sim --scenario config/scenarios/cross_circles.yaml --scheme mvn,mca --csv /tmp/cc.csv
  plot_run.py --out /tmp/cc --d1 0.05 --d2 0.12 mvn=/tmp/cc-mvn.csv mca=/tmp/cc-mca.csv
"""
import argparse
import csv
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402


def load(path):
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    if len(rows) < 2:
        sys.exit("%s: no data rows" % path)
    head = rows[0]
    data = np.array([[float(x) for x in r] for r in rows[1:]])
    return {h: data[:, i] for i, h in enumerate(head)}


def n_arms(d):
    a = 0
    while "err%d" % a in d:
        a += 1
    return a


def pairs(d):
    """(a, b) of every per-pair distance column d_<a>_<b> (mca-sim writes them for three or more arms)."""
    return sorted(tuple(int(x) for x in h[2:].split("_")) for h in d
                  if h.startswith("d_") and h[2:].replace("_", "").isdigit())


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--out", required=True)
    ap.add_argument("--d1", type=float)
    ap.add_argument("--d2", type=float)
    ap.add_argument("--title", default="")
    ap.add_argument("runs", nargs="+")
    a = ap.parse_args()
    runs = []
    for spec in a.runs:
        if "=" not in spec:
            sys.exit("run '%s' is not LABEL=file.csv" % spec)
        label, path = spec.split("=", 1)
        runs.append((label, load(path)))

    fig, ax = plt.subplots(figsize=(8, 4))
    for label, d in runs:
        pp = pairs(d)
        if pp:
            for a_, b_ in pp:
                ax.plot(d["t"], d["d_%d_%d" % (a_, b_)], lw=1, label="%s: arms %d-%d" % (label, a_, b_))
        else:
            ax.plot(d["t"], d["min_d"], label=label)
        if "fault" in d and np.any(d["fault"] > 0):
            k = int(np.argmax(d["fault"] > 0))
            ax.axvline(d["t"][k], color="k", ls=":", lw=0.8)
            ax.annotate("%s fault" % label, (d["t"][k], d["min_d"][k]), fontsize=8)
    if a.d1 is not None:
        ax.axhline(a.d1, color="r", ls="--", lw=1, label="d1 = %.3f m" % a.d1)
    if a.d2 is not None:
        ax.axhline(a.d2, color="orange", ls="--", lw=1, label="d2 = %.3f m" % a.d2)
    ax.set_xlabel("t [s]")
    ax.set_ylabel("minimum distance [m]")
    ax.set_title((a.title + ": " if a.title else "") + "minimum distance between the arms" +
                 (" (per pair)" if any(pairs(d) for _, d in runs) else ""))
    ax.grid(True, alpha=0.3)
    ax.legend()
    fig.tight_layout()
    fig.savefig(a.out + "-distance.png", dpi=110)
    plt.close(fig)

    fig, axes = plt.subplots(len(runs), 1, figsize=(8, 2.6 * len(runs)), squeeze=False)
    for (label, d), ax in zip(runs, axes[:, 0]):
        ok = d["fault"] == 0 if "fault" in d else np.ones_like(d["t"], bool)
        for arm in range(n_arms(d)):
            ax.semilogy(d["t"][ok], np.maximum(d["err%d" % arm][ok], 1e-12), label="arm %d" % arm, lw=0.8)
        ax.set_ylabel("|r_d - r| [m]")
        ax.set_title("%s: end-effector tracking error%s" % (label, " (until the fault)" if not ok.all() else ""))
        ax.grid(True, alpha=0.3, which="both")
        ax.legend()
    axes[-1, 0].set_xlabel("t [s]")
    fig.tight_layout()
    fig.savefig(a.out + "-error.png", dpi=110)
    plt.close(fig)

    fig = plt.figure(figsize=(5.5 * len(runs), 5))
    for i, (label, d) in enumerate(runs):
        ax = fig.add_subplot(1, len(runs), i + 1, projection="3d")
        for arm in range(n_arms(d)):
            ax.plot(d["ee%d_x" % arm], d["ee%d_y" % arm], d["ee%d_z" % arm], label="arm %d" % arm)
            ax.plot(d["rd%d_x" % arm], d["rd%d_y" % arm], d["rd%d_z" % arm], "k--", lw=0.6)
        k = int(np.argmin(d["min_d"]))
        ax.plot([d["p_x"][k], d["e_x"][k]], [d["p_y"][k], d["e_y"][k]], [d["p_z"][k], d["e_z"][k]], "r-o", ms=3,
                label="closest pair, d = %.3f m" % d["min_d"][k])
        ax.set_title("%s: end-effector paths" % label)
        ax.set_xlabel("x [m]")
        ax.set_ylabel("y [m]")
        ax.set_zlabel("z [m]")
        ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(a.out + "-paths.png", dpi=110)
    plt.close(fig)
    print("wrote %s-distance.png %s-error.png %s-paths.png" % (a.out, a.out, a.out))


if __name__ == "__main__":
    main()
