/* SPDX-License-Identifier: MIT */
/** @file mca/rtstats.h
 * Fixed-size latency histogram for the 1 kHz loop (wake-up jitter, compute time): no allocation,
 * O(1) record, percentiles by a scan over the bins.
 *
 * Bins: 1 us wide from 0 to 2 ms (2000 bins), 100 us wide from 2 ms to 100 ms (980 bins), then one
 * overflow bin. The exact minimum, maximum and sum are kept besides, so max is never a bin edge.
 * A percentile is reported as the UPPER edge of the bin holding it (never optimistic), capped at max.
 *
 * Context: record rt (one writer); percentile/reset from the writer thread, or from any thread when
 * the writer is quiet (values are plain, not atomics).
 */
#ifndef MCA_RTSTATS_H
#define MCA_RTSTATS_H

#include <stdint.h>
#include <stdio.h>

#ifdef __cplusplus
extern "C" {
#endif

#define MCA_HIST_FINE_NS 1000LL     /**< fine bin width [ns] */
#define MCA_HIST_FINE_BINS 2000     /**< fine bins: 0 .. 2 ms */
#define MCA_HIST_COARSE_NS 100000LL /**< coarse bin width [ns] */
#define MCA_HIST_COARSE_BINS 980    /**< coarse bins: 2 ms .. 100 ms */
#define MCA_HIST_BINS (MCA_HIST_FINE_BINS + MCA_HIST_COARSE_BINS + 1)

typedef struct mca_hist {
    uint32_t bin[MCA_HIST_BINS];
    uint64_t count;
    int64_t min_ns, max_ns;
    double sum_ns;
} mca_hist_t;

/** Empty the histogram. Context: init or the writer. */
void mca_hist_reset(mca_hist_t *h);

/** Count one value [ns] (negative values count as 0). Context: rt. */
void mca_hist_record(mca_hist_t *h, int64_t ns);

/** Value [ns] at or below which a fraction p (0..1) of the values lie; 0 when empty. */
int64_t mca_hist_percentile(const mca_hist_t *h, double p);

/** Mean [ns]; 0 when empty. */
double mca_hist_mean(const mca_hist_t *h);

/** Write the histogram as cyclictest -h does, so one reader takes both (bench/rt): a line "US COUNT" per
 *  non-empty bin (US the bin's lower edge: 1-us bins to 2 ms, then 100-us bins to 100 ms), then
 *  "# Total:", "# Min Latencies:", "# Avg Latencies:", "# Max Latencies:" [us] and "# Histogram
 *  Overflows:" (values of 100 ms and more). @p title: a first "# " line, or NULL. 0 or MCA_EIO.
 *  Context: non-rt. */
int mca_hist_write(const mca_hist_t *h, const char *title, FILE *f);

#ifdef __cplusplus
}
#endif
#endif
