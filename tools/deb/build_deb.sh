#!/bin/sh
# SPDX-License-Identifier: MIT
# Build the Debian package mca (cmake/package.cmake) from SOURCE_DIR in its own build DEB_BUILD_DIR,
# configured with the prefix /usr (mcad has its prefix compiled in), building only what is installed (the
# target mca-installed: mcad, mca-dds-bridge, the tools, the exported libraries) and packing it with cpack.
# Prints the .deb's path as its last line.
# usage: build_deb.sh SOURCE_DIR DEB_BUILD_DIR [JOBS]          (`make deb`: build/deb-build)
set -eu
S=$(cd "$1" && pwd)
D=$2
J=${3:-$(nproc)}
mkdir -p "$D"
D=$(cd "$D" && pwd)
cmake -S "$S" -B "$D" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_INSTALL_PREFIX=/usr >"$D/deb-configure.log" 2>&1 ||
    { cat "$D/deb-configure.log"; exit 1; }
cmake --build "$D" -j "$J" --target mca-installed >"$D/deb-build.log" 2>&1 || { tail -50 "$D/deb-build.log"; exit 1; }
rm -f "$D"/deb/mca_*.deb
(cd "$D" && cpack -G DEB) >"$D/deb-cpack.log" 2>&1 || { cat "$D/deb-cpack.log"; exit 1; }
ls "$D"/deb/mca_*.deb
