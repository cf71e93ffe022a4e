#!/bin/sh
# SPDX-License-Identifier: MIT
# Builds OUT/libmca_daqp.so for `bench_pdnn daqp`: bench/daqp/daqp_shim.c with the C sources of the daqp
# sdist from PyPI (the version installed in the venv, tools/deps/requirements.txt), all outside the
# repository. No DAQP code is kept in the repository.
# usage: bench/daqp/build.sh OUT_DIR   (env PY: the venv's python; env MCA_DAQP_CSRC: an unpacked csrc/ to
#        use instead of the sdist). Exit 0 and OUT/libmca_daqp.so, or exit 1 and the reason on stderr.
set -eu
ROOT=$(cd "$(dirname "$0")/../.." && pwd)
OUT=$1
PY=${PY:-$ROOT/.venv/bin/python3}
mkdir -p "$OUT"
OUT=$(cd "$OUT" && pwd)
CSRC=${MCA_DAQP_CSRC:-}
if [ -z "$CSRC" ]; then
    VER=$("$PY" -c 'import importlib.metadata as m; print(m.version("daqp"))' 2>/dev/null) ||
        { echo "daqp not installed in the venv ($PY)" >&2; exit 1; }
    CSRC=$OUT/daqp-$VER/csrc
    if [ ! -d "$CSRC" ]; then
        # pip's cache keeps the sdist: later builds need no network
        "$PY" -m pip download -q --no-deps --no-binary :all: "daqp==$VER" -d "$OUT" >&2 ||
            { echo "cannot download the daqp $VER sdist" >&2; exit 1; }
        tar xzf "$OUT/daqp-$VER.tar.gz" -C "$OUT"
    fi
fi
[ -f "$CSRC/include/api.h" ] || { echo "no DAQP C sources in $CSRC" >&2; exit 1; }
# the flags of daqp's own setup.py (less its -DPROFILING timers: bench_pdnn times the calls itself)
${CC:-cc} -O3 -fassociative-math -fno-signed-zeros -fno-trapping-math -fPIC -shared -I"$CSRC/include" \
    -o "$OUT/libmca_daqp.so" "$ROOT/bench/daqp/daqp_shim.c" "$CSRC"/src/*.c -lm
echo "$OUT/libmca_daqp.so"
