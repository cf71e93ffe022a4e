#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Predicted stability edge of the fixed-step Euler iteration, per QP, to set beside `bench_pdnn edge`.

usage: edge_spectrum.py DIR [--precond orth|scale|none]

For every qp_*.json in DIR (from `bench_pdnn dump DIR --ticks 1 ...`, the same QPs `bench_pdnn edge` uses
with the same --seed/--runs), rebuild the iterated problem as core/src/pdnn.c does (ORTH: orthonormal G rows,
U rows projected off G, unit rows; SCALE: unit rows; NONE: as given), take the solution y* (primal from OSQP,
duals from its multipliers), and near y*, where the active set is fixed, the Euler map is
    y+ = y - kappa K (y - y*),  K = (I + M^T)(I - D + D M),  D = diag(1 where P_Omega is the identity at y*).
It is stable iff |1 - kappa lambda| < 1 for every nonzero eigenvalue lambda of K, i.e.
    kappa < kappa_loc = min 2 Re(lambda) / |lambda|^2.
Printed in units of the solver's bound 2 / ||I+M||^2 (with the Gershgorin upper estimate of ||N||^2 that
pdnn.c uses): f_loc = kappa_loc / (2 / L2_bound), and also the exact 2 / ||I+M||_2^2 in the same units.
"""
import argparse
import glob
import json
import os
import sys

import numpy as np
import osqp
from scipy import sparse


def rewrite(G, alpha, U, beta, precond):
    """N = [G; -U] and q = [-alpha; beta] rewritten as pdnn.c setup() does; returns N, q and the dual map."""
    ne = G.shape[0]
    N = np.vstack([G, -U]).astype(float)
    q = np.concatenate([-alpha, beta]).astype(float)
    R = None
    if precond == "orth" and ne > 0:
        Qf, R = np.linalg.qr(G.T)  # G^T = Qf R, rows of Q = Qf^T (signs may differ from MGS: same spectrum)
        N[:ne] = Qf.T
        q[:ne] = -np.linalg.solve(R.T, alpha)
        C = N[ne:] @ Qf
        N[ne:] -= C @ Qf.T
        q[ne:] -= C @ q[:ne]
    d = np.ones(len(q))
    if precond != "none":
        start = ne if precond == "orth" else 0
        for i in range(start, len(q)):
            nr = np.linalg.norm(N[i])
            if nr > 0:
                d[i] = 1 / nr
                N[i] *= d[i]
                q[i] *= d[i]
    return N, q, d, R


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("dir")
    ap.add_argument("--precond", choices=("orth", "scale", "none"), default="orth")
    args = ap.parse_args()
    files = sorted(glob.glob(os.path.join(args.dir, "qp_*.json")))
    if not files:
        print("no qp_*.json files", file=sys.stderr)
        return 2
    f_loc, f_exact = [], []
    for path in files:
        d = json.load(open(path, encoding="utf-8"))
        n, ne, ni = d["n"], d["n_eq"], d["n_ineq"]
        G = np.array(d["G"], float).reshape(ne, n)
        U = np.array(d["U"], float).reshape(ni, n)
        alpha, beta = np.array(d["alpha"], float), np.array(d["beta"], float)
        big = 1e10
        lb = np.array([-big if v is None else v for v in d["lb"]])
        ub = np.array([big if v is None else v for v in d["ub"]])
        prob = osqp.OSQP()
        A = np.vstack([G, U, np.eye(n)])
        prob.setup(sparse.identity(n, format="csc"), np.zeros(n), sparse.csc_matrix(A),
                   np.concatenate([alpha, np.full(ni, -np.inf), lb]), np.concatenate([alpha, beta, ub]),
                   eps_abs=1e-11, eps_rel=1e-11, polishing=True, max_iter=1000000, verbose=False)
        sol = prob.solve()
        x, ve, vi = sol.x, -sol.y[:ne], np.maximum(sol.y[ne:ne + ni], 0.0)
        N, q, dsc, R = rewrite(G, alpha, U, beta, args.precond)
        m = ne + ni
        if args.precond == "orth" and ne > 0:
            we = R @ ve + N[:ne] @ (-U.T @ vi)
        else:
            we = ve / dsc[:ne]
        y = np.concatenate([x, we, vi / dsc[ne:]])
        h = n + m
        M = np.block([[np.eye(n), -N.T], [N, np.zeros((m, m))]])
        qq = np.concatenate([np.zeros(n), q])
        lo = np.concatenate([lb, -big * np.ones(ne), np.zeros(ni)])
        hi = np.concatenate([ub, big * np.ones(m)])
        z = y - (M @ y + qq)
        tol = 1e-7
        free = ((z > lo + tol) & (z < hi - tol)).astype(float)
        D = np.diag(free)
        K = (np.eye(h) + M.T) @ (np.eye(h) - D + D @ M)
        ev = np.linalg.eigvals(K)
        ev = ev[np.abs(ev) > 1e-9]
        k_loc = np.min(2 * ev.real / np.abs(ev) ** 2)
        s2 = np.max(np.sum(np.abs(N.T @ N), axis=1))  # pdnn.c: Gershgorin bound of ||N||^2
        L2_bound = 0.5 * (5 + 2 * s2 + np.sqrt(9 + 4 * s2))
        L2_exact = np.linalg.norm(np.eye(h) + M, 2) ** 2
        f_loc.append(k_loc / (2 / L2_bound))
        f_exact.append((2 / L2_exact) / (2 / L2_bound))
    f_loc, f_exact = np.array(f_loc), np.array(f_exact)
    print(f"edge_spectrum ({args.precond}): {len(files)} QPs; in units of the bound 2/L2 (Gershgorin ||N||):")
    print(f"  exact 2/||I+M||^2        min {f_exact.min():.3f} median {np.median(f_exact):.3f} max {f_exact.max():.3f}")
    print(f"  local edge at y* (f_loc) min {f_loc.min():.3f} median {np.median(f_loc):.3f} max {f_loc.max():.3f}")
    for f in (1.0, 1.2, 1.4, 1.5, 1.6, 1.65, 1.7, 1.8, 1.9, 2.0, 2.5, 3.0):
        print(f"  f = {f:4.2f}: {int(np.sum(f_loc <= f)):3d} of {len(f_loc)} QPs predicted unstable near y*")
    return 0


if __name__ == "__main__":
    sys.exit(main())
