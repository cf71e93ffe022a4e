/* SPDX-License-Identifier: MIT */
/* Fixed-size latency histogram (see mca/rtstats.h). */
#include "mca/rtstats.h"

#include "mca/err.h"

#include <inttypes.h>
#include <math.h>
#include <string.h>

void mca_hist_reset(mca_hist_t *h) {
    memset(h, 0, sizeof *h);
}

static int bin_of(int64_t ns) {
    if (ns < MCA_HIST_FINE_NS * MCA_HIST_FINE_BINS) {
        return (int)(ns / MCA_HIST_FINE_NS);
    }
    const int64_t c = (ns - MCA_HIST_FINE_NS * MCA_HIST_FINE_BINS) / MCA_HIST_COARSE_NS;
    if (c < MCA_HIST_COARSE_BINS) {
        return MCA_HIST_FINE_BINS + (int)c;
    }
    return MCA_HIST_BINS - 1;
}

/* Upper edge of bin b [ns] (the overflow bin has none: INT64_MAX). */
static int64_t bin_upper(int b) {
    if (b < MCA_HIST_FINE_BINS) {
        return (int64_t)(b + 1) * MCA_HIST_FINE_NS;
    }
    if (b < MCA_HIST_BINS - 1) {
        return MCA_HIST_FINE_NS * MCA_HIST_FINE_BINS +
               (int64_t)(b - MCA_HIST_FINE_BINS + 1) * MCA_HIST_COARSE_NS;
    }
    return INT64_MAX;
}

void mca_hist_record(mca_hist_t *h, int64_t ns) {
    if (ns < 0) {
        ns = 0;
    }
    h->bin[bin_of(ns)]++;
    if (h->count == 0 || ns < h->min_ns) {
        h->min_ns = ns;
    }
    if (h->count == 0 || ns > h->max_ns) {
        h->max_ns = ns;
    }
    h->count++;
    h->sum_ns += (double)ns;
}

int64_t mca_hist_percentile(const mca_hist_t *h, double p) {
    if (h->count == 0) {
        return 0;
    }
    if (!(p > 0.0)) {
        return h->min_ns;
    }
    if (p >= 1.0) {
        return h->max_ns;
    }
    /* smallest bin whose cumulative count reaches ceil(p * count) */
    uint64_t need = (uint64_t)ceil(p * (double)h->count);
    if (need < 1) {
        need = 1;
    }
    uint64_t cum = 0;
    for (int b = 0; b < MCA_HIST_BINS; b++) {
        cum += h->bin[b];
        if (cum >= need) {
            const int64_t up = bin_upper(b);
            return up < h->max_ns ? up : h->max_ns;
        }
    }
    return h->max_ns;
}

double mca_hist_mean(const mca_hist_t *h) {
    return h->count ? h->sum_ns / (double)h->count : 0.0;
}

int mca_hist_write(const mca_hist_t *h, const char *title, FILE *f) {
    if (title) {
        fprintf(f, "# %s\n", title);
    }
    for (int b = 0; b < MCA_HIST_BINS - 1; b++) {
        if (h->bin[b]) {
            const int64_t lower_us =
                b < MCA_HIST_FINE_BINS ? (int64_t)b * MCA_HIST_FINE_NS / 1000 : bin_upper(b - 1) / 1000;
            fprintf(f, "%06" PRId64 " %06" PRIu32 "\n", lower_us, h->bin[b]);
        }
    }
    fprintf(f, "# Total: %09" PRIu64 "\n", h->count);
    fprintf(f, "# Min Latencies: %05" PRId64 "\n", h->min_ns / 1000);
    fprintf(f, "# Avg Latencies: %05.0f\n", mca_hist_mean(h) / 1000.0);
    fprintf(f, "# Max Latencies: %05" PRId64 "\n", h->max_ns / 1000);
    fprintf(f, "# Histogram Overflows: %05" PRIu32 "\n", h->bin[MCA_HIST_BINS - 1]);
    return fflush(f) == 0 && !ferror(f) ? MCA_OK : MCA_EIO;
}
