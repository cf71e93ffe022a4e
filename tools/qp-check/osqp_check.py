#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Check LVI-PDNN answers against OSQP, the independent second solver.

usage: osqp_check.py [--min-count N] [--tol T] [--eps E] [--no-row-scale] [--verbose] DIR [DIR ...]

Loads every *.json file under each DIR (recursively) written by mca_qp_dump_json (format in
model/include/mca/qp_dump.h: n, n_eq, n_ineq, G, alpha, U, beta, lb, ub with null for infinities, and the
PDNN answer phi, steps, residual, tag), solves
    minimize 1/2 phi^T phi  s.t.  G phi = alpha,  U phi <= beta,  lb <= phi <= ub
with OSQP (eps_abs = eps_rel = 1e-10, polishing on, max_iter 1e6; where OSQP does not converge, DAQP) and asserts
max |phi_pdnn - phi_osqp| <= T (default 1e-6) on every file.

Rows of G and U are scaled to unit norm first (alpha, beta with them: the same QP). OSQP's tolerances are
absolute per row, so a row of norm 1e-7 (mca_scheme's componentwise rows when a component of r_PE is ~0)
would be allowed a violation of 1e-3 in phi units, or trip OSQP's infeasibility test; measured on
mca-sim dumps: without scaling 2.6e-4 differences and false 'primal infeasible', with it 1e-9 agreement.
--no-row-scale hands OSQP the rows as dumped.

Exit status: 0 all files agree; 1 at least one mismatch (or OSQP could not solve a QP the PDNN answered);
2 bad input (unreadable/malformed file, a file without a PDNN answer, fewer than --min-count files).
"""
import argparse
import glob
import json
import math
import os
import sys

import numpy as np


class BadInput(Exception):
    pass


def _vec(d, key, length, path, allow_null=False, fill=None):
    v = d.get(key)
    if not isinstance(v, list) or len(v) != length:
        raise BadInput(f"{path}: field '{key}' must be a list of {length} numbers")
    out = np.empty(length)
    for i, x in enumerate(v):
        if x is None and allow_null:
            out[i] = fill
        elif isinstance(x, (int, float)) and not isinstance(x, bool) and math.isfinite(x):
            out[i] = x
        else:
            raise BadInput(f"{path}: field '{key}'[{i}] is {x!r}, not a finite number")
    return out


def _mat(d, key, rows, cols, path):
    v = d.get(key)
    if not isinstance(v, list) or len(v) != rows:
        raise BadInput(f"{path}: field '{key}' must be a list of {rows} rows")
    out = np.zeros((rows, cols))
    for i, row in enumerate(v):
        out[i] = _vec({key: row}, key, cols, f"{path} row {i}")
    return out


def load_qp(path):
    try:
        with open(path, encoding="utf-8") as f:
            d = json.load(f)
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as e:
        raise BadInput(f"{path}: cannot read JSON: {e}") from e
    if not isinstance(d, dict):
        raise BadInput(f"{path}: top level must be an object")
    sizes = []
    for key in ("n", "n_eq", "n_ineq"):
        v = d.get(key)
        if not isinstance(v, int) or isinstance(v, bool) or v < 0:
            raise BadInput(f"{path}: field '{key}' must be a non-negative integer, got {v!r}")
        sizes.append(v)
    n, n_eq, n_ineq = sizes
    if n < 1:
        raise BadInput(f"{path}: field 'n' must be >= 1")
    qp = {
        "n": n,
        "G": _mat(d, "G", n_eq, n, path),
        "alpha": _vec(d, "alpha", n_eq, path),
        "U": _mat(d, "U", n_ineq, n, path),
        "beta": _vec(d, "beta", n_ineq, path),
        "lb": _vec(d, "lb", n, path, allow_null=True, fill=-np.inf),
        "ub": _vec(d, "ub", n, path, allow_null=True, fill=np.inf),
        "tag": d.get("tag", ""),
    }
    if "phi" not in d or d["phi"] is None:
        raise BadInput(f"{path}: no PDNN answer ('phi'); dump with a non-NULL phi")
    qp["phi"] = _vec(d, "phi", n, path)
    qp["steps"] = d.get("steps")
    qp["residual"] = d.get("residual")
    if np.any(qp["lb"] > qp["ub"]):
        raise BadInput(f"{path}: lb > ub at index {int(np.argmax(qp['lb'] > qp['ub']))}")
    return qp


def _unit_rows(M, v):
    norms = np.linalg.norm(M, axis=1) if M.size else np.zeros(0)
    s = np.where(norms > 0, 1.0 / np.where(norms > 0, norms, 1.0), 1.0)
    return M * s[:, None], v * s


def solve_osqp(qp, eps, row_scale=True):
    import osqp
    from scipy import sparse

    n = qp["n"]
    G, alpha, U, beta = qp["G"], qp["alpha"], qp["U"], qp["beta"]
    if row_scale:
        G, alpha = _unit_rows(G, alpha)
        U, beta = _unit_rows(U, beta)
    A = sparse.csc_matrix(np.vstack([G, U, np.eye(n)]))
    lo = np.concatenate([alpha, np.full(len(beta), -np.inf), qp["lb"]])
    hi = np.concatenate([alpha, beta, qp["ub"]])
    prob = osqp.OSQP()
    prob.setup(sparse.identity(n, format="csc"), np.zeros(n), A, lo, hi, eps_abs=eps, eps_rel=eps,
               polishing=True, max_iter=1000000, verbose=False)
    res = prob.solve()
    return res


def solve_daqp(qp):
    """DAQP (dual active-set, exact on its active set): the second truth where OSQP runs out of iterations (the
    path-first QPs' split slack makes some of them degenerate enough for OSQP at eps 1e-10). (x, exitflag)."""
    import daqp

    n = qp["n"]
    G, alpha, U, beta = qp["G"], qp["alpha"], qp["U"], qp["beta"]
    big = 1e30
    lb = np.where(np.isfinite(qp["lb"]), qp["lb"], -big)
    ub = np.where(np.isfinite(qp["ub"]), qp["ub"], big)
    A = np.vstack([G, U]) if U.size else G
    bu = np.concatenate([ub, alpha, beta])
    bl = np.concatenate([lb, alpha, np.full(len(beta), -big)])
    sense = np.concatenate([np.zeros(n, dtype=np.int32), np.full(len(alpha), 5, dtype=np.int32),
                            np.zeros(len(beta), dtype=np.int32)])
    x, _, exitflag, _ = daqp.solve(np.eye(n), np.zeros(n), np.ascontiguousarray(A, dtype=float), bu, bl, sense)
    return np.asarray(x), exitflag


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("dirs", nargs="+", metavar="DIR")
    ap.add_argument("--min-count", type=int, default=1, help="fail (exit 2) with fewer files (default 1)")
    ap.add_argument("--tol", type=float, default=1e-6, help="max |phi_pdnn - phi_osqp| (default 1e-6)")
    ap.add_argument("--eps", type=float, default=1e-10, help="OSQP eps_abs = eps_rel (default 1e-10)")
    ap.add_argument("--no-row-scale", action="store_true", help="do not scale G, U rows to unit norm")
    ap.add_argument("--verbose", action="store_true", help="one line per file")
    args = ap.parse_args(argv)

    files = []
    for d in args.dirs:
        if not os.path.isdir(d):
            print(f"osqp_check: {d}: not a directory", file=sys.stderr)
            return 2
        files += sorted(glob.glob(os.path.join(d, "**", "*.json"), recursive=True))
    if len(files) < args.min_count:
        print(f"osqp_check: found {len(files)} JSON files in {' '.join(args.dirs)}, need at least "
              f"{args.min_count}", file=sys.stderr)
        return 2

    bad_input = 0
    mismatch = 0
    by_daqp = 0
    worst = (0.0, "")
    osqp_times = []
    steps = []
    for path in files:
        try:
            qp = load_qp(path)
        except BadInput as e:
            print(f"osqp_check: bad input: {e}", file=sys.stderr)
            bad_input += 1
            continue
        res = solve_osqp(qp, args.eps, row_scale=not args.no_row_scale)
        status = res.info.status
        if status not in ("solved",):
            x, flag = solve_daqp(qp)
            if flag < 1:
                print(f"osqp_check: MISMATCH {path}: OSQP status '{status}', DAQP exit {flag}, but the PDNN gave "
                      "an answer", file=sys.stderr)
                mismatch += 1
                continue
            by_daqp += 1
            delta = float(np.max(np.abs(qp["phi"] - x)))
        else:
            delta = float(np.max(np.abs(qp["phi"] - res.x)))
            osqp_times.append(res.info.solve_time)
        if isinstance(qp["steps"], int):
            steps.append(qp["steps"])
        if delta > worst[0]:
            worst = (delta, path)
        if not delta <= args.tol:
            print(f"osqp_check: MISMATCH {path} ({qp['tag']}): max |phi_pdnn - phi_osqp| = {delta:.3g} "
                  f"> {args.tol:g}", file=sys.stderr)
            mismatch += 1
        elif args.verbose:
            print(f"{path}: ok, max delta {delta:.3g}, osqp {res.info.iter} iter {res.info.solve_time * 1e6:.0f} us")

    checked = len(files) - bad_input
    print(f"osqp_check: {len(files)} files, {checked} checked, {mismatch} mismatches, {bad_input} bad input; "
          f"max |delta phi| = {worst[0]:.3g} ({worst[1] or '-'}), tol {args.tol:g}; {by_daqp} decided by DAQP "
          "(OSQP out of iterations)")
    if osqp_times:
        t = np.array(osqp_times) * 1e6
        print(f"osqp_check: OSQP solve_time us p50 {np.percentile(t, 50):.1f} p99 {np.percentile(t, 99):.1f} "
              f"max {t.max():.1f}" + (f"; PDNN steps p50 {np.percentile(steps, 50):.0f} max {max(steps)}"
                                     if steps else ""))
    if bad_input:
        return 2
    return 1 if mismatch else 0


if __name__ == "__main__":
    sys.exit(main())
