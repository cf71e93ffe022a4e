#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""The answers of `bench_pdnn daqp --csv F` against OSQP at tight tolerance (tools/qp-check/osqp_check.py's
loader and OSQP call: rows scaled to unit norm, eps 1e-10, polishing on).

usage: osqp_daqp.py CSV [--every K] [--tol 1e-6]
Prints max |phi_pdnn - phi_osqp| (PDNN converged), max |phi_daqp - phi_osqp| (DAQP solved) and
max |phi_pdnn - phi_daqp|; exit 1 when the PDNN's is above --tol (or OSQP fails on a QP), else 0.
"""
import argparse
import csv
import os
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "tools", "qp-check"))
from osqp_check import load_qp, solve_osqp  # noqa: E402


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("csv")
    ap.add_argument("--every", type=int, default=1, help="check every K-th QP")
    ap.add_argument("--tol", type=float, default=1e-6)
    a = ap.parse_args()
    dp = dd = pd = 0.0
    n = bad = osqp_bad = over = 0
    worst = ""
    with open(a.csv) as f:
        for i, r in enumerate(csv.reader(f)):
            if i % a.every:
                continue
            path, p_ok, d_flag = r[0], int(r[3]), int(r[4])
            v = np.array([float(x) for x in r[6:]])
            m = len(v) // 2
            phi_p, phi_d = v[:m], v[m:]
            qp = load_qp(path)
            res = solve_osqp(qp, 1e-10)
            n += 1
            if res.info.status != "solved":
                osqp_bad += 1
                continue
            x = np.asarray(res.x)
            if p_ok:
                e = float(np.max(np.abs(phi_p - x)))
                if e > dp:
                    dp, worst = e, path
                over += e > a.tol
            else:
                bad += 1
            if d_flag > 0:
                dd = max(dd, float(np.max(np.abs(phi_d - x))))
                if p_ok:
                    pd = max(pd, float(np.max(np.abs(phi_p - phi_d))))
    print(f"osqp (eps 1e-10) on {n} QPs (every {a.every}): max |phi_pdnn - phi_osqp| {dp:.2g} "
          f"({over} over {a.tol:g}; {bad} PDNN not converged), max |phi_daqp - phi_osqp| {dd:.2g}, "
          f"max |phi_pdnn - phi_daqp| {pd:.2g}; OSQP failed {osqp_bad}" + (f"; worst PDNN {worst}" if dp > a.tol else ""))
    return 1 if over or osqp_bad else 0


if __name__ == "__main__":
    sys.exit(main())
