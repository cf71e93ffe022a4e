#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Plots of the LSDM study (docs/segdist.md).
usage: segdist_study --n 40000 --csv /tmp/study.csv && plot_study.py /tmp/study.csv docs/img"""
import csv
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

src, outdir = sys.argv[1], sys.argv[2]
os.makedirs(outdir, exist_ok=True)
rows = list(csv.DictReader(open(src)))
classes = ["generic", "near-parallel", "intersecting", "collinear-overlap", "degenerate"]

# 1. iterations (paper rule, tol 1e-12, cap 10000) as a CDF per class
fig, ax = plt.subplots(figsize=(7, 4))
for c in classes:
    it = np.sort(np.array([int(r["iters1"]) for r in rows if r["class"] == c]))
    ax.step(it, np.arange(1, len(it) + 1) / len(it), where="post", label=c)
ax.set_xscale("log")
ax.set_xlabel("projections until the distance stops declining by 1e-12 m (cap 10000)")
ax.set_ylabel("fraction of pairs")
ax.set_title("LSDM iterations per segment pair")
ax.grid(True, which="both", alpha=0.3)
ax.legend()
fig.tight_layout()
fig.savefig(os.path.join(outdir, "segdist_lsdm_iterations.png"), dpi=110)

# 2. near-parallel: error vs tilt for the paper's tol and for 1e-12
fig, ax = plt.subplots(figsize=(7, 4))
npr = [r for r in rows if r["class"] == "near-parallel"]
tilt = np.array([float(r["tilt"]) for r in npr])
for k, lab, mk in ((0, "paper rule, tol 1e-5", "."), (1, "paper rule, tol 1e-12 (cap 10000)", "x")):
    err = np.array([float(r[f"err{k}"]) for r in npr])
    ax.scatter(tilt, np.maximum(err, 1e-17), s=3, marker=mk, alpha=0.4, label=lab)
ax.axhline(1e-9, color="k", lw=1, ls="--", label="1e-9 m requirement")
ax.set_xscale("log")
ax.set_yscale("log")
ax.set_xlabel("tilt between the segments [rad]")
ax.set_ylabel("d_LSDM - d_true [m] (floored at 1e-17)")
ax.set_title("LSDM error on near-parallel pairs")
ax.grid(True, which="both", alpha=0.3)
ax.legend(markerscale=4)
fig.tight_layout()
fig.savefig(os.path.join(outdir, "segdist_lsdm_nearparallel.png"), dpi=110)
print("wrote", outdir)
