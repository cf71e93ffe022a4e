#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""The OSQP checker's exit status on known input: 0 for a right answer, 1 for a wrong one or an infeasible
QP, 2 for malformed files, a missing answer and too few files. usage: test_osqp_check.py OSQP_CHECK_PY"""
import importlib.util
import json
import os
import subprocess
import sys
import tempfile

CHECK = sys.argv[1]
# Most cases call main() in this process (one scipy/osqp import instead of one per case); two cases run
# the command itself to see the exit status reach the shell.
_spec = importlib.util.spec_from_file_location("osqp_check", CHECK)
osqp_check = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(osqp_check)

# min |phi|^2/2 s.t. phi1 + phi2 + phi3 = 3, 2 phi1 <= 0, phi3 <= 1.2 (box): by KKT phi = (0, 1.8, 1.2).
GOOD = {"n": 3, "n_eq": 1, "n_ineq": 1, "G": [[1, 1, 1]], "alpha": [3], "U": [[2, 0, 0]], "beta": [0],
        "lb": [None, None, -1], "ub": [None, None, 1.2], "phi": [0, 1.8, 1.2], "steps": 10,
        "residual": 1e-10, "tag": "hand"}


def run(files, *extra, subprocess_run=False):
    with tempfile.TemporaryDirectory() as d:
        for name, content in files.items():
            with open(os.path.join(d, name), "w", encoding="utf-8") as f:
                f.write(content if isinstance(content, str) else json.dumps(content))
        if not subprocess_run:
            return osqp_check.main([*extra, d])
        p = subprocess.run([sys.executable, CHECK, *extra, d], capture_output=True, text=True)
        sys.stdout.write(p.stdout + p.stderr)
        return p.returncode


def variant(**kw):
    d = dict(GOOD)
    d.update(kw)
    return d


failures = 0


def expect(name, rc, want):
    global failures
    print(f"--- {name}: exit {rc}, expected {want}")
    if rc != want:
        failures += 1


expect("right answer (command)", run({"a.json": GOOD}, subprocess_run=True), 0)
expect("wrong answer (command)", run({"a.json": variant(phi=[0, 1.8 + 1e-5, 1.2 - 1e-5])}, subprocess_run=True), 1)
expect("right answer", run({"a.json": GOOD}), 0)
expect("two right answers, --min-count 2", run({"a.json": GOOD, "b.json": GOOD}, "--min-count", "2"), 0)
expect("wrong answer by 1e-5", run({"a.json": variant(phi=[0, 1.8 + 1e-5, 1.2 - 1e-5])}), 1)
expect("wrong answer, looser --tol passes", run({"a.json": variant(phi=[0, 1.8 + 1e-5, 1.2 - 1e-5])},
                                                "--tol", "1e-4"), 0)
expect("infeasible QP with an answer", run({"a.json": variant(beta=[-10], lb=[-1, -1, -1], ub=[1, 1, 1])}), 1)
expect("not JSON", run({"a.json": "{nope"}), 2)
expect("no phi", run({"a.json": {k: v for k, v in GOOD.items() if k != "phi"}}), 2)
expect("wrong row length", run({"a.json": variant(G=[[1, 1]])}), 2)
expect("NaN-like string in beta", run({"a.json": variant(beta=["x"])}), 2)
expect("too few files", run({"a.json": GOOD}, "--min-count", "2"), 2)
expect("empty folder", run({}), 2)
# A QP dumped by mca-sim (componentwise form) with collision rows of norm ~1e-7: the PDNN answer is exact
# (unit-row violation 6e-16); OSQP on the raw rows lets the tiny rows slip by 2.6e-4 (its tolerances are
# absolute per row), on unit rows it agrees to 1e-13. Default: scaled rows.
with open(os.path.join(os.path.dirname(os.path.abspath(__file__)), "data", "scheme_tiny_rows.json"),
          encoding="utf-8") as f:
    TINY = json.load(f)
expect("mca-sim QP with tiny rows", run({"a.json": TINY}), 0)
expect("the same, --no-row-scale", run({"a.json": TINY}, "--no-row-scale"), 1)
print("FAILED" if failures else "all ok")
sys.exit(1 if failures else 0)
