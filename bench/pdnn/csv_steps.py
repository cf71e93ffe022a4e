#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""PDNN steps per tick pooled over mca-sim --csv files (docs/pdnn.md, "Active-set polish").

usage: csv_steps.py [--tol 1e-9] CSV [CSV ...]

Prints the tick count, pdnn_steps p50/p99/p99.9/max, ticks over 300 steps, ticks whose pdnn_residual is
above --tol (not converged) and ticks at 2000 steps (the controller's cap). Rows without a PDNN solve
(empty pdnn_steps) are skipped.
"""
import argparse
import csv
import math

import numpy as np


def pct(a, p):
    a = np.sort(a)
    i = max(0, int(math.ceil(p / 100.0 * len(a))) - 1)
    return a[min(i, len(a) - 1)]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--tol", type=float, default=1e-9)
    ap.add_argument("csv", nargs="+")
    a = ap.parse_args()
    steps, res = [], []
    for path in a.csv:
        with open(path) as f:
            for row in csv.DictReader(f):
                if row.get("pdnn_steps", "") != "":
                    steps.append(int(row["pdnn_steps"]))
                    res.append(float(row["pdnn_residual"]))
    s, r = np.array(steps), np.array(res)
    if len(s) == 0:
        raise SystemExit("no ticks with a PDNN solve")
    print("%d ticks: steps p50 %d p99 %d p99.9 %d max %d | > 300: %d | residual > %g: %d (%.2f %%) | at 2000: %d"
          % (len(s), pct(s, 50), pct(s, 99), pct(s, 99.9), s.max(), (s > 300).sum(), a.tol, (r > a.tol).sum(),
             100.0 * (r > a.tol).mean(), (s >= 2000).sum()))


if __name__ == "__main__":
    main()
