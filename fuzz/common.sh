# SPDX-License-Identifier: MIT
# Sourced by fuzz/run.sh and fuzz/merge.sh: what both need to know of the targets.

# every target, in the order `make fuzz` runs them
MCA_FUZZ_ALL_TARGETS=(can_link armsim_rx cell scenario urdf inject ros2_target canopen)

# The longest input libFuzzer makes for target $1. The file parsers read every input from scratch
# (libcyaml, TinyXML + urdfdom): inputs of 60 kB made them crawl (348 exec/s for urdf); the largest shipped
# file is a 4.4 kB URDF, and 16 kB still nests any depth bound thousands of times over. The frame sequences
# keep 64 kB.
mca_fuzz_maxlen() {
  case $1 in cell | scenario | urdf) echo 16384 ;; *) echo 65536 ;; esac
}

# The tree's corpus folders of target $1 (SRC = fuzz/): the seeds, and the merged corpus if there is one.
mca_fuzz_corpus_dirs() {
  echo "$src/corpus/$1"
  [ -d "$src/corpus-merged/$1" ] && echo "$src/corpus-merged/$1"
  return 0
}
