#!/bin/bash
# SPDX-License-Identifier: MIT
# The full random-task sweep (bench step MCA_BENCH_SWEEP=1, `make sweep`):
# 1000 two-arm tasks (500 two PA10+, 500 JACO2 + MICO2) in one table, the 200 three-arm tasks in another,
# and the pick and place (200 pnp-jaco-mico + 200 pnp-pa10) in a third.
# usage: tools/mca-sweep/run_full.sh BUILD_DIR OUT_DIR     (env MCA_SWEEP_SEED, default 1; MCA_SWEEP_JOBS, default nproc)
# Writes OUT_DIR/sweep.txt (the tables) and OUT_DIR/sweep-two.json, OUT_DIR/sweep-three.json, OUT_DIR/sweep-pnp.json
# (every task).
set -u
ROOT=$(cd "$(dirname "$0")/../.." && pwd)
B=${1:?usage: run_full.sh BUILD_DIR OUT_DIR}
OUT=${2:?usage: run_full.sh BUILD_DIR OUT_DIR}
PY=${PY:-$ROOT/.venv/bin/python3}
[ -x "$PY" ] || PY=python3
SEED=${MCA_SWEEP_SEED:-1}
JOBS=${MCA_SWEEP_JOBS:-$(nproc)}
mkdir -p "$OUT"
SIM=$B/tools/mca-sim/mca-sim
rc=0
"$PY" "$ROOT/tools/mca-sweep/mca_sweep.py" --sim "$SIM" --kind pa10,jaco-mico --n 500,500 --seed "$SEED" \
    --jobs "$JOBS" --json "$OUT/sweep-two.json" --table "$OUT/sweep-two.txt" || rc=1
"$PY" "$ROOT/tools/mca-sweep/mca_sweep.py" --sim "$SIM" --kind three --n 200 --seed "$SEED" \
    --jobs "$JOBS" --json "$OUT/sweep-three.json" --table "$OUT/sweep-three.txt" || rc=1
"$PY" "$ROOT/tools/mca-sweep/mca_sweep.py" --sim "$SIM" --kind pnp-jaco-mico,pnp-pa10 --n 200,200 --seed "$SEED" \
    --jobs "$JOBS" --json "$OUT/sweep-pnp.json" --table "$OUT/sweep-pnp.txt" || rc=1
{
    echo "# mca-sweep, $(date -u +%Y-%m-%dT%H:%MZ), git $(git -C "$ROOT" rev-parse --short HEAD 2>/dev/null)"
    echo
    echo "## two arms: 500 pa10 + 500 jaco-mico"
    cat "$OUT/sweep-two.txt" 2>/dev/null
    echo
    echo "## three arms: 200"
    cat "$OUT/sweep-three.txt" 2>/dev/null
    echo
    echo "## pick and place: 200 pnp-jaco-mico + 200 pnp-pa10"
    cat "$OUT/sweep-pnp.txt" 2>/dev/null
} >"$OUT/sweep.txt"
rm -f "$OUT/sweep-two.txt" "$OUT/sweep-three.txt" "$OUT/sweep-pnp.txt"
echo "sweep: $OUT/sweep.txt"
exit $rc
