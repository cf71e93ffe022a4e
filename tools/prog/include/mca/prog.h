/* SPDX-License-Identifier: MIT */
/** @file mca/prog.h
 * What the command-line programs (mca-dds-synth, mca-monitor, bench_dds, ...) would otherwise each write
 * again: an integer option with its range checked and the error said, the Ctrl-C/SIGTERM handler, the
 * p50/p99/max/mean of a run of nanosecond samples. Only programs link it (their main files), never a
 * library. Context: non-rt.
 */
#ifndef MCA_PROG_H
#define MCA_PROG_H

#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#ifdef __cplusplus
extern "C" {
#endif

/**
 * Parse s as a decimal integer in 0..max (no sign, nothing after it); on error print
 * "PROG: OPT: 'S' is not an integer in 0..MAX" on stderr.
 * @param[out] out  the value (unchanged on error)
 * @retval 0 @retval -1 not such an integer
 */
int mca_prog_parse_u64(const char *prog, const char *opt, const char *s, unsigned long long max,
                       unsigned long long *out);

/**
 * After getopt: refuse what is left on the command line ("PROG: unexpected argument 'X'" and the usage on
 * stderr) for a program that takes options only.
 * @retval 0 nothing left @retval 2 (the exit code) something left
 */
int mca_prog_no_operands(const char *prog, int argc, char *const argv[], int optind_, void (*usage)(FILE *));

/** Run handler on SIGINT and SIGTERM (sigaction, no SA_RESTART: a blocking call returns EINTR). */
void mca_prog_on_stop_signals(void (*handler)(int));

/** Order statistics of n samples in ns, reported in us. */
typedef struct mca_prog_ns_summary {
    double p50, p99, max, mean; /**< [us]; p50 = v[(n-1)/2], p99 = v[floor(0.99 (n-1))] of the sorted v */
} mca_prog_ns_summary_t;

/** Sort v (in place) and summarize it; all zero for n = 0. */
mca_prog_ns_summary_t mca_prog_ns_summary(int64_t *v, size_t n);

#ifdef __cplusplus
}
#endif
#endif
