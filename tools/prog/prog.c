/* SPDX-License-Identifier: MIT */
/* Helpers of the command-line programs (see mca/prog.h). */
#include "mca/prog.h"

#include <errno.h>
#include <math.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

int mca_prog_parse_u64(const char *prog, const char *opt, const char *s, unsigned long long max,
                       unsigned long long *out) {
    char *end = NULL;
    errno = 0;
    const unsigned long long v = strtoull(s, &end, 10);
    /* strtoull takes "-1" as ULLONG_MAX: the sign is refused by hand */
    if (errno != 0 || end == s || *end != '\0' || s[0] == '-' || v > max) {
        fprintf(stderr, "%s: %s: '%s' is not an integer in 0..%llu\n", prog, opt, s, max);
        return -1;
    }
    *out = v;
    return 0;
}

void mca_prog_on_stop_signals(void (*handler)(int)) {
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = handler;
    sigemptyset(&sa.sa_mask);
    sigaction(SIGINT, &sa, NULL);
    sigaction(SIGTERM, &sa, NULL);
}

static int cmp_i64(const void *a, const void *b) {
    const int64_t x = *(const int64_t *)a, y = *(const int64_t *)b;
    return (x > y) - (x < y);
}

mca_prog_ns_summary_t mca_prog_ns_summary(int64_t *v, size_t n) {
    mca_prog_ns_summary_t s = {0, 0, 0, 0};
    if (n == 0) {
        return s;
    }
    qsort(v, n, sizeof *v, cmp_i64);
    double sum = 0;
    for (size_t i = 0; i < n; ++i) {
        sum += (double)v[i];
    }
    s.p50 = (double)v[(n - 1) / 2] * 1e-3;
    s.p99 = (double)v[(size_t)floor(0.99 * (double)(n - 1))] * 1e-3;
    s.max = (double)v[n - 1] * 1e-3;
    s.mean = sum / (double)n * 1e-3;
    return s;
}

int mca_prog_no_operands(const char *prog, int argc, char *const argv[], int optind_, void (*usage)(FILE *)) {
    if (optind_ >= argc) {
        return 0;
    }
    fprintf(stderr, "%s: unexpected argument '%s'\n", prog, argv[optind_]);
    if (usage) {
        usage(stderr);
    }
    return 2;
}
