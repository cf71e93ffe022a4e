#!/usr/bin/env bash
# make fuzz: run every libFuzzer target of BUILD (a -DMCA_FUZZ=ON build) for SECONDS each, one after the
# other (one core each: -workers 1), starting from the seed corpus, the merged corpus (fuzz/merge.sh) and the
# regression inputs in the tree.
# New corpus entries go to BUILD/fuzz-work/TARGET (the tree's corpus is read, never written); a crash,
# leak or timeout leaves its input in BUILD/fuzz-artifacts/TARGET/ and fails the run.
# Prints one line per target: executions, exec/s, coverage, corpus size, result. Each run is also appended to
# BUILD/fuzz-work/ledger.tsv (time, git, target, seconds, executions, result), and the summary adds each
# target's sum over the ledger: runs that start from the corpus the earlier ones grew add up to one long run
# (issue 16 asks for 10 million executions per target; the slow parsers need hours for that).
# usage: fuzz/run.sh BUILD SECONDS [TARGET...]
set -uo pipefail
build=$1
secs=$2
shift 2
src=$(cd "$(dirname "$0")" && pwd)
. "$src/common.sh"
targets=("$@")
[ ${#targets[@]} -gt 0 ] || targets=("${MCA_FUZZ_ALL_TARGETS[@]}")
# The file targets write every input to a file (fuzz/fuzz_file.h): on this ext4 (mounted with discard) each
# rewrite freed blocks with a synchronous discard, 31 % of a cell run's time in the kernel. tmpfs doubled the
# rate (cell 2040 -> 4044, urdf 1725 -> 3092 exec/s). MCA_FUZZ_TMPDIR overrides.
tmp=${MCA_FUZZ_TMPDIR:-/dev/shm}
[ -d "$tmp" ] && [ -w "$tmp" ] && export TMPDIR=$tmp
fail=0
summary=()
for t in "${targets[@]}"; do
  exe="$build/fuzz/fuzz_$t"
  work="$build/fuzz-work/$t"
  art="$build/fuzz-artifacts/$t"
  mkdir -p "$work" "$art"
  mapfile -t dirs < <(mca_fuzz_corpus_dirs "$t")
  dirs=("$work" "${dirs[@]}")
  [ -d "$src/regress/$t" ] && dirs+=("$src/regress/$t")
  log="$build/fuzz-work/$t.log"
  echo "fuzz: $t for ${secs} s (log $log)"
  # the tree as the run starts (the ledger's git column; a commit during a long run must not relabel it)
  rev=$(git -C "$src" rev-parse --short HEAD 2>/dev/null || echo ?)
  maxlen=$(mca_fuzz_maxlen "$t")
  ASAN_OPTIONS=detect_leaks=1:allocator_may_return_null=1 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
    "$exe" -max_total_time="$secs" -timeout=10 -rss_limit_mb=2048 -max_len=$maxlen -print_final_stats=1 \
    -artifact_prefix="$art/" "${dirs[@]}" >"$log" 2>&1
  rc=$?
  execs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -1)
  rate=$(sed -n 's/^stat::average_exec_per_sec: *//p' "$log" | tail -1)
  cov=$(grep -o 'cov: [0-9]*' "$log" | tail -1 | cut -d' ' -f2)
  corp=$(ls "$work" | wc -l)
  if [ $rc -eq 0 ]; then res=ok; else res="FAIL (rc $rc; see $log, $art)"; fail=1; fi
  summary+=("$(printf '%-10s %12s execs %8s exec/s  cov %6s  new corpus %5s  %s' "$t" "${execs:-?}" \
    "${rate:-?}" "${cov:-?}" "$corp" "$res")")
  [ $rc -eq 0 ] || tail -40 "$log"
  printf '%s\t%s\t%s\t%s\t%s\t%s\n' "$(date -u +%FT%TZ)" "$rev" \
    "$t" "$secs" "${execs:-0}" "$([ $rc -eq 0 ] && echo ok || echo "fail-rc$rc")" >>"$build/fuzz-work/ledger.tsv"
done
echo "fuzz summary (${secs} s per target):"
printf '%s\n' "${summary[@]}"
echo "ledger ($build/fuzz-work/ledger.tsv), every run so far:"
awk -F'\t' '{ n[$3] += $5; r[$3]++; s[$3] += $4; if ($6 !~ /^ok/) f[$3]++; if (!($3 in first)) first[$3] = $1 " " $2; last[$3] = $1 " " $2 }
  END { for (t in n) printf "%-12s %13d execs in %3d runs, %7d s, %d failed runs (%s .. %s)\n", t, n[t], r[t], s[t], f[t], first[t], last[t] }' \
  "$build/fuzz-work/ledger.tsv" | sort
exit $fail
