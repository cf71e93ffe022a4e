/* SPDX-License-Identifier: MIT */
/* Random segment-pair classes shared by the LSDM study and the benchmark (deterministic, seeded). */
#ifndef MCA_BENCH_PAIRS_H
#define MCA_BENCH_PAIRS_H

#include <math.h>
#include <stdint.h>
#include <string.h>

enum pair_class { PC_GENERIC, PC_NEAR_PARALLEL, PC_INTERSECTING, PC_COLLINEAR, PC_DEGENERATE, PC_N };

static const char *const pair_class_name[PC_N] = {"generic", "near-parallel", "intersecting",
                                                  "collinear-overlap", "degenerate"};

static uint64_t pairs_rng = 0x9e3779b97f4a7c15ULL;

static inline void pairs_seed(uint64_t s) {
    pairs_rng = s ? s : 0x9e3779b97f4a7c15ULL;
}

static inline double pairs_urand(void) {
    pairs_rng ^= pairs_rng >> 12;
    pairs_rng ^= pairs_rng << 25;
    pairs_rng ^= pairs_rng >> 27;
    return (double)((pairs_rng * 2685821657736338717ULL) >> 11) * (1.0 / 9007199254740992.0);
}

static inline void pairs_pt(double p[3], double lo, double hi) {
    for (int k = 0; k < 3; k++) {
        p[k] = lo + (hi - lo) * pairs_urand();
    }
}

/* Arm-scale pairs in a 2 m cube. *angle gets the tilt for near-parallel pairs (else 0). */
static inline void pairs_make(enum pair_class cls, double a[3], double b[3], double c[3], double d[3],
                              double *angle) {
    double x[3], s, t;
    *angle = 0.0;
    pairs_pt(a, -1, 1);
    pairs_pt(b, -1, 1);
    switch (cls) {
    case PC_GENERIC:
        pairs_pt(c, -1, 1);
        pairs_pt(d, -1, 1);
        break;
    case PC_NEAR_PARALLEL: {
        /* CD = shifted copy of part of AB, its far end pushed sideways: tilt ~ 10^-1 .. 10^-9 rad */
        double off[3], u[3], len, tilt = pow(10.0, -1.0 - 8.0 * pairs_urand()), xn;
        pairs_pt(off, -0.3, 0.3);
        pairs_pt(x, -1, 1);
        for (int k = 0; k < 3; k++) {
            u[k] = b[k] - a[k];
        }
        len = sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
        xn = sqrt(x[0] * x[0] + x[1] * x[1] + x[2] * x[2]);
        s = 0.5 * pairs_urand();
        t = 0.5 + pairs_urand();
        for (int k = 0; k < 3; k++) {
            c[k] = a[k] + off[k] - s * u[k];
            d[k] = c[k] + t * u[k] + tilt * t * len * x[k] / xn;
        }
        *angle = tilt;
        break;
    }
    case PC_INTERSECTING:
        s = pairs_urand();
        t = pairs_urand();
        pairs_pt(x, -1, 1);
        for (int k = 0; k < 3; k++) {
            double m = a[k] + s * (b[k] - a[k]);
            c[k] = m - t * x[k];
            d[k] = m + (1.0 - t) * x[k];
        }
        break;
    case PC_COLLINEAR:
        /* overlapping: C in [0, 1] of AB, D anywhere on the line up to 2 lengths away */
        s = pairs_urand();
        t = -1.0 + 3.0 * pairs_urand();
        for (int k = 0; k < 3; k++) {
            c[k] = a[k] + s * (b[k] - a[k]);
            d[k] = a[k] + t * (b[k] - a[k]);
        }
        break;
    default:
        pairs_pt(c, -1, 1);
        if (pairs_urand() < 0.5) {
            memcpy(d, c, sizeof(double) * 3);
        } else {
            pairs_pt(d, -1, 1);
        }
        memcpy(b, a, sizeof(double) * 3);
        if (pairs_urand() < 0.3) {
            double tmp[3];
            memcpy(tmp, a, sizeof tmp);
            memcpy(a, c, sizeof tmp);
            memcpy(b, d, sizeof tmp);
            memcpy(c, tmp, sizeof tmp);
            memcpy(d, tmp, sizeof tmp);
        }
        break;
    }
}

#endif
