#!/bin/bash
# SPDX-License-Identifier: MIT
# The mca demo (`make demo`): usage: tools/demo.sh BUILD_DIR
#  1. mca-sim runs of the paper's tasks in virtual time, MVN vs MCA (and APF), with the comparison tables;
#  2. mcad drives task 1 (cross circles, dual PA10+) on the simulated arms in REAL time (1 kHz, SCHED_FIFO)
#     and publishes on DDS while mca-monitor shows the distances live;
#  3. plots from the daemon's CSV and the simulation CSVs.
# mca-record records the daemon's run for ROS 2 tools (ros2 bag, Foxglove, PlotJuggler): out/demo/mcad_cross_circles.mcap.
# Everything goes under out/demo/ (gitignored). Needs root (or rtprio/memlock limits) for SCHED_FIFO;
# without them mcad warns and runs SCHED_OTHER.
set -euo pipefail
BUILD=${1:-build}
ROOT=$(cd "$(dirname "$0")/.." && pwd)
case "$BUILD" in /*) ;; *) BUILD="$ROOT/$BUILD" ;; esac
OUT="$ROOT/out/demo"
PY="$ROOT/.venv/bin/python3"
[ -x "$PY" ] || PY=python3
MCAD="$BUILD/daemon/mcad"
SIM="$BUILD/tools/mca-sim/mca-sim"
MON="$BUILD/tools/mca-monitor/mca-monitor"
REC="$BUILD/tools/mca-record/mca-record"
for exe in "$MCAD" "$SIM"; do
    [ -x "$exe" ] || { echo "demo: $exe not built (run make build)" >&2; exit 1; }
done
rm -rf "$OUT"
mkdir -p "$OUT/sim" "$OUT/plots"
bold() { printf '\n\033[1m== %s\033[0m\n' "$*"; }

# ------------------------------------------------------------------ 1. MVN vs MCA in simulation
bold "1. mca-sim: MVN vs MCA (and APF on task 1) on the paper's tasks (virtual time, sim backend)"
for run in cross_circles:mvn,mca,apf hui:mvn,mca cup_stacking:mvn,mca; do
    task=${run%%:*} schemes=${run#*:}
    scn="$ROOT/config/scenarios/$task.yaml"
    [ -f "$scn" ] || continue
    "$SIM" --scenario "$scn" --scheme "$schemes" --csv "$OUT/sim/$task.csv" \
        --summary "$OUT/sim/$task.json" > "$OUT/sim/$task.txt" 2>&1 || true
    echo "--- $task (full output: out/demo/sim/$task.txt)"
    cat "$OUT/sim/$task.txt"
done

# ------------------------------------------------------------------ 2. the daemon in real time
bold "2. mcad: task 1 (cross circles) in real time on the simulated arms, mca-monitor on DDS"
CELL="$ROOT/config/cells/cross_circles_sim.yaml"
"$MCAD" --check "$CELL"
MON_PID=
if [ -x "$MON" ]; then
    # live view on this terminal; every Distances sample also to CSV
    "$MON" --config "$ROOT/config/dds/loopback.xml" --duration 16 --csv "$OUT/monitor.csv" &
    MON_PID=$!
    sleep 1
fi
REC_PID=
if [ -x "$REC" ]; then
    # every topic of the cell into MCAP (docs/ros2.md); its progress lines go to out/demo/record.log
    "$REC" --cell "$CELL" --output "$OUT/mcad_cross_circles.mcap" --quiet 2> "$OUT/record.log" &
    REC_PID=$!
    sleep 1
fi
set +e
"$MCAD" --csv "$OUT/mcad_cross_circles.csv" "$CELL" 2> "$OUT/mcad.log"
MCAD_RC=$?
set -e
[ -n "$MON_PID" ] && { kill -INT "$MON_PID" 2>/dev/null; wait "$MON_PID" 2>/dev/null || true; }
if [ -n "$REC_PID" ]; then
    sleep 0.5 # the last samples
    kill -INT "$REC_PID" 2>/dev/null
    wait "$REC_PID" 2>/dev/null || true
    echo "--- mca-record (out/demo/record.log): out/demo/mcad_cross_circles.mcap"
    tail -1 "$OUT/record.log"
fi
echo
echo "--- mcad log (out/demo/mcad.log), exit status $MCAD_RC"
cat "$OUT/mcad.log"

# ------------------------------------------------------------------ 3. plots
bold "3. plots (out/demo/plots)"
PLOTS="$ROOT/tools/plots/plot_run.py"
thresholds() { # d1 d2 of a scenario, from mca-sim's report line "d1 0.050 m, d2 0.120 m"
    sed -n 's/.*d1 \([0-9.]*\) m, d2 \([0-9.]*\) m.*/\1 \2/p' "$OUT/sim/$1.txt" | head -1
}
if [ -f "$PLOTS" ]; then
    for f in "$OUT"/sim/*.txt; do
        task=$(basename "$f" .txt)
        read -r d1 d2 < <(thresholds "$task") || continue
        runs=()
        for c in "$OUT/sim/$task"-*.csv; do
            [ -f "$c" ] || continue
            s=$(basename "$c" .csv); runs+=("${s#"$task"-}=$c")
        done
        # the real-time daemon run next to the simulations of the same task
        [ "$task" = cross_circles ] && runs+=("mcad-realtime=$OUT/mcad_cross_circles.csv")
        "$PY" "$PLOTS" --out "$OUT/plots/$task" --d1 "$d1" --d2 "$d2" --title "$task" "${runs[@]}" ||
            echo "demo: plotting $task failed (matplotlib missing? run make deps)"
    done
else
    echo "demo: $PLOTS not found: no plots"
fi
ls -1 "$OUT/plots"

bold "summary"
grep "summary" "$OUT/mcad.log" || true
echo "outputs: $OUT"
exit "$MCAD_RC"
