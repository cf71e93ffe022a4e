#!/bin/sh
# LVI-PDNN figures for docs/pdnn.md. usage: bench/pdnn/run.sh [BUILD_DIR] (default build)
# Needs the venv (.venv) with osqp. Takes a few minutes on 2 cores.
set -eu
ROOT=$(cd "$(dirname "$0")/../.." && pwd)
BUILD=${1:-$ROOT/build}
BIN=$BUILD/bench/pdnn/bench_pdnn
PY=${PY:-$ROOT/.venv/bin/python3}
OUT=$(mktemp -d)
trap 'rm -rf "$OUT"' EXIT

echo "== time: default solver (ORTH rewrite, adaptive step, far rows 0.3), 100 runs x 10 ticks, eps 1e-3"
"$BIN" time
echo "== the same QPs with the plain variants"
"$BIN" time --far 1
"$BIN" time --precond scale --far 1
"$BIN" time --precond none --max-steps 200000 --runs 20
"$BIN" time --rule bound --max-steps 200000 --runs 20
echo "== tolerance"
"$BIN" time --tol 1e-6
"$BIN" time --tol 1e-12 --max-steps 200000
echo "== normal form (mca_scheme's default: one row per link, n_ineq 18)"
"$BIN" time --form normal
"$BIN" time --form normal --far 1
"$BIN" time --form normal --tol 1e-6
echo "== PDNN vs OSQP on the same QPs"
"$BIN" dump "$OUT/seq" --runs 50 >/dev/null
"$PY" "$ROOT/bench/pdnn/osqp_vs_pdnn.py" "$OUT/seq"
"$BIN" dump "$OUT/seqn" --runs 50 --form normal >/dev/null
"$PY" "$ROOT/bench/pdnn/osqp_vs_pdnn.py" "$OUT/seqn"
echo "== stability edge: measured (fixed kappa) and predicted (local spectrum)"
"$BIN" edge --runs 40 --max-steps 100000
"$BIN" dump "$OUT/edge" --ticks 1 --runs 40 --max-steps 200000 >/dev/null
"$PY" "$ROOT/bench/pdnn/edge_spectrum.py" "$OUT/edge"
