#!/bin/bash
# SPDX-License-Identifier: MIT
# Minimise what the fuzzers found into the tree: libFuzzer's -merge=1 of fuzz/corpus/TARGET, the old
# fuzz/corpus-merged/TARGET and BUILD/fuzz-work/TARGET (the corpus `make fuzz` grew) into a new
# fuzz/corpus-merged/TARGET, the smallest set of inputs that keeps every feature they reach. The CI smoke
# (fuzz/run.sh) starts from it and ctest's fuzz_regress_TARGET replays it, so coverage found in long runs
# is checked on every commit. usage: fuzz/merge.sh [BUILD (build-fuzz)] [TARGET...]
set -u
src=$(cd "$(dirname "$0")" && pwd)
. "$src/common.sh"
build=${1:-build-fuzz}
shift || true
targets=("$@")
[ ${#targets[@]} -eq 0 ] && targets=("${MCA_FUZZ_ALL_TARGETS[@]}")
export TMPDIR=${MCA_FUZZ_TMPDIR:-/dev/shm}
for t in "${targets[@]}"; do
  new=$(mktemp -d)
  maxlen=$(mca_fuzz_maxlen "$t")
  mapfile -t dirs < <(mca_fuzz_corpus_dirs "$t")
  [ -d "$build/fuzz-work/$t" ] && dirs+=("$build/fuzz-work/$t")
  if ! ASAN_OPTIONS=detect_leaks=0:allocator_may_return_null=1 "$build/fuzz/fuzz_$t" -merge=1 -max_len=$maxlen \
    -timeout=10 -rss_limit_mb=2048 "$new" "${dirs[@]}" >"$build/fuzz-work/$t.merge.log" 2>&1; then
    echo "merge: $t failed (see $build/fuzz-work/$t.merge.log)"
    rm -rf "$new"
    exit 1
  fi
  rm -rf "$src/corpus-merged/$t"
  mkdir -p "$src/corpus-merged"
  mv "$new" "$src/corpus-merged/$t"
  chmod 755 "$src/corpus-merged/$t"
  echo "merge: $t: $(ls "$src/corpus-merged/$t" | wc -l) inputs ($(du -s --apparent-size --block-size=1K \
    "$src/corpus-merged/$t" | cut -f1) kB)"
done
