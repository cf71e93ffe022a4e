#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""PDNN vs OSQP time on the same QPs, at matching accuracy.

usage: osqp_vs_pdnn.py DIR [--eps 1e-9]

DIR comes from `bench_pdnn dump DIR ...`: qp_*.json (mca_qp_dump_json) and pdnn_times.csv (file, ns, steps,
warm). Each QP is solved by OSQP (eps_abs = eps_rel = --eps, polishing on) twice:
  cold: a new OSQP object per QP (setup + solve), as the PDNN's cold solves;
  warm: per run of ticks one OSQP object, then update(q, l, u, Ax) and solve warm-started from the previous
        tick, as the PDNN's warm solves.
OSQP's own C timers are reported (info.solve_time, info.run_time = setup + solve + polish), next to the PDNN's
clock_gettime per mca_pdnn_solve call, with p50/p99/max, the p50 ratio and max |phi_pdnn - phi_osqp|.
"""
import argparse
import csv
import json
import os
import sys

import numpy as np
import osqp
from scipy import sparse


def load(path):
    with open(path, encoding="utf-8") as f:
        d = json.load(f)
    n = d["n"]
    G = np.array(d["G"], float).reshape(d["n_eq"], n)
    U = np.array(d["U"], float).reshape(d["n_ineq"], n)
    lb = np.array([-np.inf if v is None else v for v in d["lb"]])
    ub = np.array([np.inf if v is None else v for v in d["ub"]])
    A = np.vstack([G, U, np.eye(n)])
    lo = np.concatenate([d["alpha"], np.full(d["n_ineq"], -np.inf), lb])
    hi = np.concatenate([d["alpha"], d["beta"], ub])
    return n, A, lo, hi, np.array(d["phi"], float)


def stats(v):
    v = np.asarray(v, float)
    return f"p50 {np.percentile(v, 50):9.1f} p99 {np.percentile(v, 99):9.1f} max {v.max():9.1f}"


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("dir")
    ap.add_argument("--eps", type=float, default=1e-9)
    args = ap.parse_args()
    rows = list(csv.DictReader(open(os.path.join(args.dir, "pdnn_times.csv"), encoding="utf-8")))
    if not rows:
        print("no rows in pdnn_times.csv", file=sys.stderr)
        return 2
    settings = dict(eps_abs=args.eps, eps_rel=args.eps, polishing=True, max_iter=1000000, verbose=False)
    res = {k: {"pdnn": [], "solve": [], "run": [], "delta": [], "iters": [], "bad": 0} for k in ("cold", "warm")}
    warm_prob = None
    pattern = None
    for r in rows:
        n, A, lo, hi, phi = load(os.path.join(args.dir, r["file"]))
        kind = "warm" if int(r["warm"]) else "cold"
        Acsc = sparse.csc_matrix(A)
        P = sparse.identity(n, format="csc")
        # cold: setup + solve from scratch
        prob = osqp.OSQP()
        prob.setup(P, np.zeros(n), Acsc, lo, hi, **settings)
        out = prob.solve()
        if kind == "cold":
            warm_prob, pattern = prob, (Acsc.indices.copy(), Acsc.indptr.copy())
            sol = out
        else:
            same = pattern is not None and np.array_equal(Acsc.indices, pattern[0]) and np.array_equal(
                Acsc.indptr, pattern[1])
            if same:
                warm_prob.update(Ax=Acsc.data, l=lo, u=hi)
                sol = warm_prob.solve()
            else:  # sparsity changed: no warm start possible
                sol = out
        d = res[kind]
        if sol.info.status != "solved":
            d["bad"] += 1
            continue
        d["pdnn"].append(float(r["ns"]) / 1e3)
        d["solve"].append(sol.info.solve_time * 1e6)
        d["run"].append(sol.info.run_time * 1e6)
        d["iters"].append(sol.info.iter)
        d["delta"].append(float(np.max(np.abs(sol.x - phi))))
    print(f"PDNN vs OSQP (eps_abs = eps_rel = {args.eps:g}, polishing), {len(rows)} QPs from {args.dir}; times in us")
    for kind in ("cold", "warm"):
        d = res[kind]
        if not d["pdnn"]:
            continue
        print(f"  {kind} ({len(d['pdnn'])} QPs, {d['bad']} not solved by OSQP):")
        print(f"    PDNN mca_pdnn_solve      {stats(d['pdnn'])}")
        print(f"    OSQP info.solve_time     {stats(d['solve'])}   iterations {stats(d['iters'])}")
        print(f"    OSQP info.run_time       {stats(d['run'])}")
        r50 = np.percentile(d["pdnn"], 50) / np.percentile(d["solve"], 50)
        r99 = np.percentile(d["pdnn"], 99) / np.percentile(d["solve"], 99)
        print(f"    ratio PDNN/OSQP solve_time: p50 {r50:.2f}  p99 {r99:.2f};  max |phi_pdnn - phi_osqp| "
              f"{max(d['delta']):.2e}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
