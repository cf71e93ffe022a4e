/* SPDX-License-Identifier: MIT */
/* Segment-pair distance cost: closed form vs the paper's LSDM vs the GJK capsule distance on libccd's
 * support-function API, on ONE shared pair set in one run. Prints ns per pair, ratios to the closed form and
 * the max error against the closed form. Not a test (timings depend on the machine).
 * usage: segdist_bench [--n PAIRS] [--reps R] [--mix generic|all] */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include <ccd/ccd.h>

#include "mca/err.h"
#include "mca/obstacle.h"
#include "mca/segdist.h"
#include "pairs.h"

typedef struct pair {
    double a[3], b[3], c[3], d[3];
} pair_t;

static double now_ns(void) {
    struct timespec ts;
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts); /* CPU time: preemption by other load excluded */
    return (double)ts.tv_sec * 1e9 + (double)ts.tv_nsec;
}

enum method { M_CLOSED, M_LSDM_PAPER, M_LSDM_DEF, M_LSDM_CERT, M_GJK, M_CCD_MPR_INTERSECT, M_N };
static const char *const method_name[M_N] = {
    "closed form (mca_segdist_closed)",         "LSDM, paper tol 1e-5",
    "LSDM, default tol 1e-12 cap 200",          "LSDM, certified gap 1e-9 cap 200",
    "GJK capsule-capsule (libccd support API)", "libccd ccdMPRIntersect (yes/no only)",
};

/* libccd objects for the intersect-only timing (capsule radius 0.05) */
typedef struct cap_obj {
    const double *a, *b;
    double r;
} cap_obj_t;
static void cap_support(const void *obj, const ccd_vec3_t *dir, ccd_vec3_t *out) {
    const cap_obj_t *c = obj;
    const double *p =
        (c->b[0] - c->a[0]) * dir->v[0] + (c->b[1] - c->a[1]) * dir->v[1] + (c->b[2] - c->a[2]) * dir->v[2] >
                0
            ? c->b
            : c->a;
    double n = sqrt(dir->v[0] * dir->v[0] + dir->v[1] * dir->v[1] + dir->v[2] * dir->v[2]);
    for (int k = 0; k < 3; k++) {
        out->v[k] = p[k] + (n > 0 ? c->r * dir->v[k] / n : 0.0);
    }
}
static void cap_center(const void *obj, ccd_vec3_t *out) {
    const cap_obj_t *c = obj;
    for (int k = 0; k < 3; k++) {
        out->v[k] = 0.5 * (c->a[k] + c->b[k]);
    }
}

static double run(enum method m, const pair_t *pp, long n, double *dist, int *iters) {
    const mca_lsdm_params_t paper = {MCA_LSDM_PAPER_TOL, MCA_LSDM_DEFAULT_MAX_ITER};
    const mca_lsdm_params_t def = {MCA_LSDM_DEFAULT_TOL, MCA_LSDM_DEFAULT_MAX_ITER};
    const mca_lsdm_params_t cert = {1e-9, MCA_LSDM_DEFAULT_MAX_ITER};
    ccd_t ccd;
    CCD_INIT(&ccd);
    ccd.support1 = ccd.support2 = cap_support;
    ccd.center1 = ccd.center2 = cap_center;
    ccd.max_iterations = 100;
    double t0 = now_ns();
    for (long i = 0; i < n; i++) {
        const pair_t *p = &pp[i];
        mca_segdist_t r;
        mca_obst_dist_t g;
        switch (m) {
        case M_CLOSED:
            mca_segdist_closed(p->a, p->b, p->c, p->d, &r);
            break;
        case M_LSDM_PAPER:
            mca_segdist_lsdm(p->a, p->b, p->c, p->d, &paper, &r);
            break;
        case M_LSDM_DEF:
            mca_segdist_lsdm(p->a, p->b, p->c, p->d, &def, &r);
            break;
        case M_LSDM_CERT:
            mca_segdist_lsdm_certified(p->a, p->b, p->c, p->d, &cert, &r);
            break;
        case M_GJK: {
            mca_capsule_t c1, c2;
            memcpy(c1.a, p->a, sizeof c1.a);
            memcpy(c1.b, p->b, sizeof c1.b);
            memcpy(c2.a, p->c, sizeof c2.a);
            memcpy(c2.b, p->d, sizeof c2.b);
            c1.radius = c2.radius = 0.0;
            mca_capsule_capsule_distance_ccd(&c1, &c2, &g);
            r.d = g.d;
            r.iterations = g.iterations;
            break;
        }
        default: {
            cap_obj_t o1 = {p->a, p->b, 0.05}, o2 = {p->c, p->d, 0.05};
            r.d = ccdMPRIntersect(&o1, &o2, &ccd);
            r.iterations = 0;
            break;
        }
        }
        dist[i] = r.d;
        iters[i] = r.iterations;
    }
    return (now_ns() - t0) / (double)n;
}

int main(int argc, char **argv) {
    long n = 20000;
    int reps = 7, all = 0;
    for (int i = 1; i < argc; i++) {
        if (strcmp(argv[i], "--n") == 0 && i + 1 < argc) {
            n = atol(argv[++i]);
        } else if (strcmp(argv[i], "--reps") == 0 && i + 1 < argc) {
            reps = atoi(argv[++i]);
        } else if (strcmp(argv[i], "--mix") == 0 && i + 1 < argc) {
            all = strcmp(argv[++i], "all") == 0;
        } else {
            fprintf(stderr, "usage: %s [--n PAIRS] [--reps R] [--mix generic|all]\n", argv[0]);
            return 2;
        }
    }
    if (n < 1 || reps < 1) {
        fprintf(stderr, "--n and --reps must be >= 1\n");
        return 2;
    }
    pair_t *pp = malloc(sizeof(pair_t) * (size_t)n);
    double *ref = malloc(sizeof(double) * (size_t)n), *dist = malloc(sizeof(double) * (size_t)n);
    int *iters = malloc(sizeof(int) * (size_t)n);
    if (!pp || !ref || !dist || !iters) {
        return 1;
    }
    pairs_seed(7);
    for (long i = 0; i < n; i++) {
        double tilt;
        enum pair_class c = all ? (enum pair_class)(i % PC_N) : PC_GENERIC;
        pairs_make(c, pp[i].a, pp[i].b, pp[i].c, pp[i].d, &tilt);
    }
    run(M_CLOSED, pp, n, ref, iters);

    double best[M_N], maxerr[M_N];
    long sum_it[M_N];
    for (int m = 0; m < M_N; m++) {
        best[m] = INFINITY;
    }
    /* interleave methods per repetition so frequency drift hits all alike; keep the fastest repetition */
    for (int r = 0; r < reps; r++) {
        for (int m = 0; m < M_N; m++) {
            double ns = run((enum method)m, pp, n, dist, iters);
            best[m] = fmin(best[m], ns);
            if (r == 0) {
                maxerr[m] = 0;
                sum_it[m] = 0;
                for (long i = 0; i < n; i++) {
                    if (m != M_CCD_MPR_INTERSECT) {
                        maxerr[m] = fmax(maxerr[m], fabs(dist[i] - ref[i]));
                    }
                    sum_it[m] += iters[i];
                }
            }
        }
    }
    printf("segment-pair distance, %ld %s pairs, best of %d runs, one process, thread CPU time\n\n", n,
           all ? "mixed-class (generic, near-parallel, intersecting, collinear, degenerate)"
               : "generic arm-scale",
           reps);
    printf("| method | ns / pair | ratio to closed form | max |d - d_closed| [m] | mean iterations |\n");
    printf("|---|---|---|---|---|\n");
    for (int m = 0; m < M_N; m++) {
        if (m == M_CCD_MPR_INTERSECT) {
            printf("| %s | %.1f | %.2f | n/a (no distance) | - |\n", method_name[m], best[m],
                   best[m] / best[M_CLOSED]);
        } else {
            printf("| %s | %.1f | %.2f | %.3g | %.2f |\n", method_name[m], best[m], best[m] / best[M_CLOSED],
                   maxerr[m], (double)sum_it[m] / (double)n);
        }
    }
    printf("\nper 1 ms cycle, two 8-DOF arms = 9 x 9 = 81 link pairs: closed form %.1f us, LSDM default %.1f "
           "us\n",
           81.0 * best[M_CLOSED] / 1000.0, 81.0 * best[M_LSDM_DEF] / 1000.0);
    /* worst case for the real-time budget: the pairs on which the default LSDM runs to its cap */
    run(M_LSDM_DEF, pp, n, dist, iters);
    long n_cap = 0;
    for (long i = 0; i < n; i++) {
        if (iters[i] >= MCA_LSDM_DEFAULT_MAX_ITER) {
            pp[n_cap++] = pp[i];
        }
    }
    if (n_cap > 0) {
        double worst = INFINITY, worst_c = INFINITY;
        for (int r = 0; r < reps; r++) {
            worst = fmin(worst, run(M_LSDM_DEF, pp, n_cap, dist, iters));
            worst_c = fmin(worst_c, run(M_CLOSED, pp, n_cap, dist, iters));
        }
        printf(
            "LSDM default on the %ld pairs that hit its cap of %d: %.1f ns / pair (closed form on the same: "
            "%.1f ns); 81 such pairs = %.1f us\n",
            n_cap, MCA_LSDM_DEFAULT_MAX_ITER, worst, worst_c, 81.0 * worst / 1000.0);
    } else {
        printf("no pair hit the LSDM cap\n");
    }
    free(pp);
    free(ref);
    free(dist);
    free(iters);
    return 0;
}
