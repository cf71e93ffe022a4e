#!/bin/sh
# Run the four tasks (MVN and MCA, plus APF on task 1) through mca-sim and draw the figures.
# usage: tools/plots/make_figures.sh BUILD_DIR OUT_DIR      (e.g. build docs/img/scheme)
set -eu
BUILD=${1:?build dir}
OUT=${2:?output dir}
ROOT=$(cd "$(dirname "$0")/../.." && pwd)
SIM="$BUILD/tools/mca-sim/mca-sim"
PY="$ROOT/.venv/bin/python3"
mkdir -p "$OUT"
run() { # name schemes title d1 d2
    "$SIM" --scenario "$ROOT/config/scenarios/$1.yaml" --scheme "$2" --csv "$OUT/$1.csv" > "$OUT/$1.txt"
    sed -i "s#$ROOT/##g" "$OUT/$1.txt" # repository-relative paths in the committed reports
    set --  "$1" "$2" "$3" "$4" "$5"
    args=""
    for s in $(echo "$2" | tr ',' ' '); do args="$args $s=$OUT/$1-$s.csv"; done
    # shellcheck disable=SC2086
    "$PY" "$ROOT/tools/plots/plot_run.py" --out "$OUT/$1" --d1 "$4" --d2 "$5" --title "$3" $args
    rm -f "$OUT"/"$1"-*.csv
}
run cross_circles mvn,mca,apf "cross circles (task 1)" 0.05 0.12
run hui mvn,mca "Hui (task 2)" 0.05 0.10
run cup_stacking mvn,mca "cup stacking (task 3)" 0.07 0.12
run negative mvn,mca "negative example (task 4)" 0.05 0.12
echo "figures and mca-sim reports in $OUT"
