/* SPDX-License-Identifier: MIT */
/* LSDM accuracy study: the paper's LSDM (several stopping rules) against the closed form on random
 * segment pairs of five classes. Prints markdown tables (docs/segdist.md quotes them).
 * usage: segdist_study [--n PAIRS_PER_CLASS] [--seed S] [--csv FILE]
 * --csv writes one row per pair (class, tilt, then per rule: status, iterations, error) for plot_study.py. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "mca/err.h"
#include "mca/segdist.h"
#include "pairs.h"

#define CAP 10000

typedef struct rule {
    const char *name;
    int certified;
    mca_lsdm_params_t params;
} rule_t;

static const rule_t rules[] = {
    {"paper rule, tol 1e-5 (paper)", 0, {1e-5, CAP}},
    {"paper rule, tol 1e-12", 0, {1e-12, CAP}},
    {"paper rule, default (1e-12, cap 200)", 0, {MCA_LSDM_DEFAULT_TOL, MCA_LSDM_DEFAULT_MAX_ITER}},
    {"certified gap rule, tol 1e-9", 1, {1e-9, CAP}},
};
#define N_RULES ((int)(sizeof rules / sizeof rules[0]))

typedef struct stats {
    double max_err; /* max (d_lsdm - d_closed) */
    double min_err; /* most negative: LSDM below the closed form (must be rounding only) */
    long wrong_ok;  /* returned MCA_OK but > 1e-9 m above the true minimum */
    long notconv;   /* hit the cap */
    long bad_point; /* witness P or E > 1e-6 m from the closed form's while d is within 1e-9 */
    int *iters;     /* per pair */
    long n;
} stats_t;

static int cmp_int(const void *a, const void *b) {
    return *(const int *)a - *(const int *)b;
}

static int pct(int *v, long n, double q) {
    long i = (long)ceil(q * (double)n) - 1;
    return v[i < 0 ? 0 : (i >= n ? n - 1 : i)];
}

static double d3(const double a[3], const double b[3]) {
    return sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) +
                (a[2] - b[2]) * (a[2] - b[2]));
}

/* independent brute force in long double: golden section on f(s) = min_t |P(s) - CD| */
static long double pt_seg_l(const long double p[3], const double c[3], const double d[3]) {
    long double v[3], w[3], vv = 0, wv = 0, t, r2 = 0;
    for (int k = 0; k < 3; k++) {
        v[k] = (long double)d[k] - c[k];
        w[k] = p[k] - c[k];
        vv += v[k] * v[k];
        wv += w[k] * v[k];
    }
    t = vv > 0 ? wv / vv : 0;
    t = t < 0 ? 0 : (t > 1 ? 1 : t);
    for (int k = 0; k < 3; k++) {
        long double x = w[k] - t * v[k];
        r2 += x * x;
    }
    return sqrtl(r2);
}
static long double f_s(const double a[3], const double b[3], const double c[3], const double d[3],
                       long double s) {
    long double p[3];
    for (int k = 0; k < 3; k++) {
        p[k] = a[k] + s * ((long double)b[k] - a[k]);
    }
    return pt_seg_l(p, c, d);
}
static double brute(const double a[3], const double b[3], const double c[3], const double d[3]) {
    const long double g = (sqrtl(5.0L) - 1.0L) / 2.0L;
    long double lo = 0, hi = 1, x1 = hi - g, x2 = g, f1 = f_s(a, b, c, d, x1), f2 = f_s(a, b, c, d, x2), best;
    for (int i = 0; i < 120; i++) {
        if (f1 <= f2) {
            hi = x2;
            x2 = x1;
            f2 = f1;
            x1 = hi - g * (hi - lo);
            f1 = f_s(a, b, c, d, x1);
        } else {
            lo = x1;
            x1 = x2;
            f1 = f2;
            x2 = lo + g * (hi - lo);
            f2 = f_s(a, b, c, d, x2);
        }
    }
    best = fminl(f1, f2);
    best = fminl(best, f_s(a, b, c, d, 0));
    best = fminl(best, f_s(a, b, c, d, 1));
    long double pc[3] = {c[0], c[1], c[2]}, pd[3] = {d[0], d[1], d[2]};
    best = fminl(best, pt_seg_l(pc, a, b));
    best = fminl(best, pt_seg_l(pd, a, b));
    return (double)best;
}

int main(int argc, char **argv) {
    long n = 40000;
    unsigned long long seed = 1;
    FILE *csv = NULL;
    for (int i = 1; i < argc; i++) {
        if (strcmp(argv[i], "--n") == 0 && i + 1 < argc) {
            n = atol(argv[++i]);
        } else if (strcmp(argv[i], "--seed") == 0 && i + 1 < argc) {
            seed = strtoull(argv[++i], NULL, 10);
        } else if (strcmp(argv[i], "--csv") == 0 && i + 1 < argc) {
            csv = fopen(argv[++i], "w");
            if (csv == NULL) {
                fprintf(stderr, "segdist_study: cannot write %s\n", argv[i]);
                return 2;
            }
        } else {
            fprintf(stderr, "usage: %s [--n PAIRS_PER_CLASS] [--seed S] [--csv FILE]\n", argv[0]);
            return 2;
        }
    }
    if (n < 10) {
        fprintf(stderr, "--n must be >= 10\n");
        return 2;
    }
    pairs_seed(seed);
    if (csv != NULL) {
        fprintf(csv, "class,tilt");
        for (int k = 0; k < N_RULES; k++) {
            fprintf(csv, ",rc%d,iters%d,err%d", k, k, k);
        }
        fprintf(csv, "\n");
    }

    static stats_t st[PC_N][N_RULES];
    double closed_vs_brute[PC_N] = {0};
    /* near-parallel by tilt decade (1e-1 .. 1e-9): rules 0 and 1 */
    double np_err[2][9] = {{0}};
    long np_cnt[9] = {0};
    int *np_it[2][9];
    for (int r = 0; r < 2; r++) {
        for (int k = 0; k < 9; k++) {
            np_it[r][k] = malloc(sizeof(int) * (size_t)n);
        }
    }
    for (int c = 0; c < PC_N; c++) {
        for (int r = 0; r < N_RULES; r++) {
            st[c][r].iters = malloc(sizeof(int) * (size_t)n);
            st[c][r].min_err = INFINITY;
            st[c][r].max_err = -INFINITY;
        }
    }

    for (int c = 0; c < PC_N; c++) {
        for (long i = 0; i < n; i++) {
            double a[3], b[3], cc[3], d[3], tilt;
            mca_segdist_t ref, r;
            pairs_make((enum pair_class)c, a, b, cc, d, &tilt);
            mca_segdist_closed(a, b, cc, d, &ref);
            if (i < n / 10) {
                closed_vs_brute[c] = fmax(closed_vs_brute[c], fabs(ref.d - brute(a, b, cc, d)));
            }
            int dec = -1;
            if (c == PC_NEAR_PARALLEL) {
                dec = (int)floor(-log10(tilt)) - 1; /* tilt in (1e-(k+2), 1e-(k+1)] -> k */
                dec = dec < 0 ? 0 : (dec > 8 ? 8 : dec);
            }
            if (csv != NULL) {
                fprintf(csv, "%s,%.6g", pair_class_name[c], tilt);
            }
            for (int k = 0; k < N_RULES; k++) {
                int rc = rules[k].certified ? mca_segdist_lsdm_certified(a, b, cc, d, &rules[k].params, &r)
                                            : mca_segdist_lsdm(a, b, cc, d, &rules[k].params, &r);
                stats_t *s = &st[c][k];
                double err = r.d - ref.d;
                s->max_err = fmax(s->max_err, err);
                s->min_err = fmin(s->min_err, err);
                if (rc == MCA_ENOTCONV) {
                    s->notconv++;
                } else if (err > 1e-9) {
                    s->wrong_ok++;
                }
                if (err <= 1e-9 && (d3(r.p, ref.p) > 1e-6 || d3(r.e, ref.e) > 1e-6)) {
                    s->bad_point++;
                }
                s->iters[s->n++] = r.iterations;
                if (csv != NULL) {
                    fprintf(csv, ",%d,%d,%.6g", rc, r.iterations, err);
                }
                if (dec >= 0 && k < 2) {
                    np_err[k][dec] = fmax(np_err[k][dec], err);
                    np_it[k][dec][np_cnt[dec]] = r.iterations;
                }
            }
            if (dec >= 0) {
                np_cnt[dec]++;
            }
            if (csv != NULL) {
                fprintf(csv, "\n");
            }
        }
    }

    printf("## LSDM vs closed form: %ld pairs per class, %ld in all, seed %llu\n\n", n, n * PC_N, seed);
    printf("closed form vs long-double golden section (first %ld pairs of each class), max |diff| [m]:",
           n / 10);
    for (int c = 0; c < PC_N; c++) {
        printf(" %s %.2g%s", pair_class_name[c], closed_vs_brute[c], c + 1 < PC_N ? "," : "\n\n");
    }
    for (int k = 0; k < N_RULES; k++) {
        printf("### %s\n\n", rules[k].name);
        printf("| class | max err [m] | min err [m] | OK but > 1e-9 off | cap hit | witness > 1e-6 off | "
               "iterations p50 / p90 / p99 / max |\n");
        printf("|---|---|---|---|---|---|---|\n");
        for (int c = 0; c < PC_N; c++) {
            stats_t *s = &st[c][k];
            qsort(s->iters, (size_t)s->n, sizeof(int), cmp_int);
            printf("| %s | %.3g | %.3g | %ld (%.2f%%) | %ld (%.2f%%) | %ld | %d / %d / %d / %d |\n",
                   pair_class_name[c], s->max_err, s->min_err, s->wrong_ok,
                   100.0 * (double)s->wrong_ok / (double)s->n, s->notconv,
                   100.0 * (double)s->notconv / (double)s->n, s->bad_point, pct(s->iters, s->n, 0.5),
                   pct(s->iters, s->n, 0.9), pct(s->iters, s->n, 0.99), s->iters[s->n - 1]);
        }
        printf("\n");
    }
    /* iteration histogram, paper rule tol 1e-12, all classes */
    static const int edges[] = {2, 4, 8, 16, 32, 64, 128, 256, 1024, CAP - 1, CAP};
    printf("### Iteration histogram, paper rule tol 1e-12 (projections per pair)\n\n| class |");
    for (int e = 0; e < (int)(sizeof edges / sizeof edges[0]); e++) {
        printf(e == 0 ? " <=%d |" : (edges[e] == CAP ? " =%d (cap) |" : " <=%d |"), edges[e]);
    }
    printf("\n|---|");
    for (int e = 0; e < (int)(sizeof edges / sizeof edges[0]); e++) {
        printf("---|");
    }
    printf("\n");
    for (int c = 0; c < PC_N; c++) {
        stats_t *s = &st[c][1];
        printf("| %s |", pair_class_name[c]);
        long j = 0;
        for (int e = 0; e < (int)(sizeof edges / sizeof edges[0]); e++) {
            long cnt = 0;
            while (j < s->n && s->iters[j] <= edges[e]) {
                cnt++;
                j++;
            }
            printf(" %ld |", cnt);
        }
        printf("\n");
    }
    printf("\n### Near-parallel pairs by tilt angle\n\n");
    printf("| tilt [rad] | pairs | tol 1e-5: max err [m], median iters | tol 1e-12: max err [m], median / "
           "max iters |\n");
    printf("|---|---|---|---|\n");
    for (int k = 0; k < 9; k++) {
        if (np_cnt[k] == 0) {
            continue;
        }
        qsort(np_it[0][k], (size_t)np_cnt[k], sizeof(int), cmp_int);
        qsort(np_it[1][k], (size_t)np_cnt[k], sizeof(int), cmp_int);
        printf("| 1e-%d .. 1e-%d | %ld | %.3g, %d | %.3g, %d / %d |\n", k + 2, k + 1, np_cnt[k], np_err[0][k],
               pct(np_it[0][k], np_cnt[k], 0.5), np_err[1][k], pct(np_it[1][k], np_cnt[k], 0.5),
               np_it[1][k][np_cnt[k] - 1]);
    }
    /* Closed-form stress: long segments (up to 20 m), far from the origin (up to 1e3 m), near-parallel and
     * near-intersecting, against the long-double brute force. */
    {
        double worst[3] = {0, 0, 0};
        const char *kind[3] = {"near-parallel, tilt 1e-12..1e-2", "near-intersecting (gap 1e-12..1e-3 m)",
                               "long + far (20 m segments, 1e3 m offset)"};
        long m = n / 4;
        for (int kk = 0; kk < 3; kk++) {
            for (long i = 0; i < m; i++) {
                double a[3], b[3], cc[3], d[3], u[3], x[3], off[3], scale = kk == 2 ? 10.0 : 1.0;
                pairs_pt(off, -1e3, 1e3);
                pairs_pt(a, -scale, scale);
                pairs_pt(b, -scale, scale);
                pairs_pt(x, -1, 1);
                for (int k = 0; k < 3; k++) {
                    u[k] = b[k] - a[k];
                }
                if (kk == 0) {
                    double tilt = pow(10.0, -2.0 - 10.0 * pairs_urand()), o = 0.5 * pairs_urand();
                    for (int k = 0; k < 3; k++) {
                        cc[k] = a[k] + 0.3 * u[k] + o * x[k];
                        d[k] = cc[k] + (0.2 + pairs_urand()) * u[k] + tilt * x[k] * (k == 1 ? -1.0 : 1.0);
                    }
                } else if (kk == 1) {
                    double s = pairs_urand(), gap = pow(10.0, -3.0 - 9.0 * pairs_urand()), y[3],
                           t = pairs_urand();
                    pairs_pt(y, -1, 1);
                    for (int k = 0; k < 3; k++) {
                        double mpt = a[k] + s * u[k] + gap * y[k];
                        cc[k] = mpt - t * x[k];
                        d[k] = mpt + (1.0 - t) * x[k];
                    }
                } else {
                    pairs_pt(cc, -scale, scale);
                    pairs_pt(d, -scale, scale);
                }
                if (kk != 1) {
                    for (int k = 0; k < 3; k++) {
                        a[k] += off[k];
                        b[k] += off[k];
                        cc[k] += off[k];
                        d[k] += off[k];
                    }
                }
                mca_segdist_t ref;
                mca_segdist_closed(a, b, cc, d, &ref);
                worst[kk] = fmax(worst[kk], fabs(ref.d - brute(a, b, cc, d)));
            }
        }
        printf("\n### Closed-form stress vs long-double brute force (%ld pairs each)\n\n| set | max abs diff "
               "[m] |\n"
               "|---|---|\n",
               m);
        for (int kk = 0; kk < 3; kk++) {
            printf("| %s | %.3g |\n", kind[kk], worst[kk]);
        }
    }
    if (csv != NULL) {
        fclose(csv);
    }
    for (int c = 0; c < PC_N; c++) {
        for (int r = 0; r < N_RULES; r++) {
            free(st[c][r].iters);
        }
    }
    for (int r = 0; r < 2; r++) {
        for (int k = 0; k < 9; k++) {
            free(np_it[r][k]);
        }
    }
    return 0;
}
