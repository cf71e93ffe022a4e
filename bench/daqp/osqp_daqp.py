#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""The answers of `bench_pdnn daqp --csv F` against OSQP at tight tolerance (tools/qp-check/osqp_check.py's
loader and OSQP call: rows scaled to unit norm, eps 1e-10, polishing on), and each answer's own KKT residual.

usage: osqp_daqp.py CSV [--every K] [--tol 1e-6]

OSQP is a reference only where it says "solved" and its answer violates no row by more than 1e-9 (rows of unit
norm): on the pick-and-place QPs it reports "primal infeasible" or stops at max_iter on some, and on others
its answer violates rows by 1e-8..1e-2 while the PDNN's and DAQP's, which agree to 1e-12, violate none by
more than 1e-14. So every answer is also checked on its own: the KKT residual, max over
    primal violation (unit rows)  and  |phi + G' y + U_A' mu + bounds_A' nu|_inf with mu, nu >= 0
(y, mu, nu by bounded least squares over the rows within 1e-9 of binding; the QP's minimizer is unique, and a
point with KKT residual r is its minimizer up to O(r) times the active rows' conditioning).
Exit 1 when a converged PDNN answer has a KKT residual above --tol, or is more than --tol off OSQP where
OSQP is a reference and has the lower objective; else 0. Where the PDNN's and OSQP's answers differ and both violate no row by more
than 1e-9, the lower objective 1/2 |phi|^2 is the nearer to the minimizer: counted as "PDNN objective above
OSQP's" (by more than 1e-9 relative) when OSQP's is the lower.
"""
import argparse
import csv
import os
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "tools", "qp-check"))
from osqp_check import _unit_rows, load_qp, solve_osqp  # noqa: E402


def _mx(z):
    return float(np.max(z)) if z.size else 0.0


def violation(qp, x):
    G, al = _unit_rows(qp["G"], qp["alpha"])
    U, be = _unit_rows(qp["U"], qp["beta"])
    return max(_mx(np.abs(G @ x - al)), _mx(U @ x - be), _mx(qp["lb"] - x), _mx(x - qp["ub"]))


def kkt(qp, x, act=1e-9):
    from scipy.optimize import lsq_linear

    n = qp["n"]
    G, al = _unit_rows(qp["G"], qp["alpha"])
    U, be = _unit_rows(qp["U"], qp["beta"])
    rows, lo = [G], [np.full(len(al), -np.inf)]
    A = U[U @ x - be >= -act]
    rows.append(A)
    lo.append(np.zeros(len(A)))
    e = np.eye(n)
    up, dn = x - qp["ub"] >= -act, qp["lb"] - x >= -act
    rows += [e[up], -e[dn]]
    lo += [np.zeros(int(up.sum())), np.zeros(int(dn.sum()))]
    M = np.vstack(rows)
    if len(M):
        r = lsq_linear(M.T, -x, bounds=(np.concatenate(lo), np.inf), method="bvls", tol=1e-14)
        stat = _mx(np.abs(x + M.T @ r.x))
    else:
        stat = _mx(np.abs(x))
    return max(stat, violation(qp, x))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("csv")
    ap.add_argument("--every", type=int, default=1, help="check every K-th QP")
    ap.add_argument("--tol", type=float, default=1e-6)
    a = ap.parse_args()
    dp = dd = pd = kp = kd = 0.0
    n = nref = pdnn_unconv = over = kover = fworse = 0
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
            ref = res.info.status == "solved" and violation(qp, np.asarray(res.x)) <= 1e-9
            nref += ref
            x = np.asarray(res.x)
            if p_ok:
                k = kkt(qp, phi_p)
                kp = max(kp, k)
                kover += k > a.tol
                if ref:
                    e = float(np.max(np.abs(phi_p - x)))
                    if e > dp:
                        dp, worst = e, path
                    over += e > a.tol
                    fp, fo = phi_p @ phi_p / 2, x @ x / 2
                    fworse += e > a.tol and violation(qp, phi_p) <= 1e-9 and fp > fo + 1e-9 * max(1.0, fo)
            else:
                pdnn_unconv += 1
            if d_flag > 0:
                kd = max(kd, kkt(qp, phi_d))
                if ref:
                    dd = max(dd, float(np.max(np.abs(phi_d - x))))
                if p_ok:
                    pd = max(pd, float(np.max(np.abs(phi_p - phi_d))))
    print(f"osqp (eps 1e-10) on {n} QPs (every {a.every}), a reference on {nref} (solved, rows violated <= 1e-9): "
          f"max |phi_pdnn - phi_osqp| {dp:.2g} ({over} over {a.tol:g}, PDNN objective above OSQP's on {fworse} of "
          f"them), max |phi_daqp - phi_osqp| {dd:.2g}; "
          f"KKT residual on all {n}: PDNN {kp:.2g} ({kover} over {a.tol:g}; {pdnn_unconv} not converged, not "
          f"checked), DAQP {kd:.2g}; max |phi_pdnn - phi_daqp| {pd:.2g}"
          + (f"; worst PDNN vs OSQP {worst}" if dp > a.tol else ""))
    return 1 if fworse or kover else 0


if __name__ == "__main__":
    sys.exit(main())
