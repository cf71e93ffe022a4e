#!/bin/bash
# SPDX-License-Identifier: MIT
# PDNN (polish on) against DAQP on consecutive ticks of the hardest sweep tasks.
# usage: bench/daqp/run.sh BUILD_DIR OUT_DIR   (env PY: the venv's python)
# Regenerates three seeded sweep tasks (jaco-mico 1 and 7 of --n 16 --seed 501, pnp-jaco-mico 1 of --n 4
# --seed 501: the most binding ticks under mca-ts), dumps every tick's QP with mca-sim (capped ones too),
# builds DAQP from its PyPI sdist outside the repository (bench/daqp/build.sh) and replays the QPs with
# `bench_pdnn daqp` (OUT/daqp.txt; 3 passes, the median one), then checks the answers against OSQP and by their KKT residuals (OUT/daqp_osqp.txt, every 50th QP).
# The dumps (about 350 MB) are removed at the end (kept with MCA_DAQP_KEEP=1: OUT/daqp_work). Without DAQP: daqp.txt says "skipped: daqp not available".
set -u
ROOT=$(cd "$(dirname "$0")/../.." && pwd)
B=$(cd "${1:?usage: bench/daqp/run.sh BUILD_DIR OUT_DIR}" && pwd) || exit 1
OUT=${2:?usage: bench/daqp/run.sh BUILD_DIR OUT_DIR}
PY=${PY:-$ROOT/.venv/bin/python3}
SIM=$B/tools/mca-sim/mca-sim
mkdir -p "$OUT"
W=$OUT/daqp_work
[ "${MCA_DAQP_KEEP:-0}" = 1 ] || rm -rf "$W"
mkdir -p "$W/qp"
for t in jaco-mico:1:16 jaco-mico:7:16 pnp-jaco-mico:1:4; do
    IFS=: read -r kind i n <<<"$t"
    "$PY" "$ROOT/tools/mca-sweep/mca_sweep.py" --sim "$SIM" --kind "$kind" --n "$n" --seed 501 --only "$i" \
        --schemes mca-ts --no-stop --jobs 1 --work "$W/$kind" --keep >"$W/sweep_${kind}_$i.out" 2>&1
    scn=$(ls -d "$W/$kind"/sweep_*_"$i" | head -1)
    mkdir -p "$W/qp/${kind}_$i"
    "$SIM" --scenario "$scn/scenario.yaml" --scheme mca-ts --dump-qp "$W/qp/${kind}_$i" --dump-every 1 \
        --dump-capped >"$W/qp/sim_${kind}_$i.txt" 2>&1
done
LIB=$("$ROOT/bench/daqp/build.sh" "$B/daqp" 2>"$OUT/daqp_build.err" | tail -1)
[ -n "$LIB" ] || LIB=$B/daqp/none.so
# three passes over the same QPs, the median-ratio pass reported; SCHED_FIFO like the other timing rows
# when allowed (MCA_DAQP_FIFO=0: never)
FIFO=${MCA_DAQP_FIFO:-80}
BP=("$B/bench/pdnn/bench_pdnn" daqp "$W/qp" --daqp-lib "$LIB" --csv "$W/daqp.csv" --runs 3)
if [ "$FIFO" != 0 ] && chrt -f "$FIFO" true 2>/dev/null; then
    chrt -f "$FIFO" "${BP[@]}" >"$OUT/daqp.txt" 2>&1
    echo "exit $? (SCHED_FIFO $FIFO)" >>"$OUT/daqp.txt"
else
    "${BP[@]}" >"$OUT/daqp.txt" 2>&1
    echo "exit $? (SCHED_OTHER)" >>"$OUT/daqp.txt"
fi
if [ -s "$W/daqp.csv" ]; then
    "$PY" "$ROOT/bench/daqp/osqp_daqp.py" "$W/daqp.csv" --every 50 >"$OUT/daqp_osqp.txt" 2>&1
    echo "exit $?" >>"$OUT/daqp_osqp.txt"
fi
[ "${MCA_DAQP_KEEP:-0}" = 1 ] || rm -rf "$W"
