/* SPDX-License-Identifier: MIT */
/* Segment distances: closed form against hand-derived exact answers (1e-12), against an independent
 * golden-section implementation on random pairs (1e-13), LSDM against the closed form, and the arm-to-arm
 * distances against a brute-force loop. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "mca/armdist.h"
#include "mca/err.h"
#include "mca/segdist.h"
#include "mca/urdf.h"

/* ---- tiny deterministic RNG (xorshift64*) so runs are repeatable ---- */
static uint64_t rng_state = 0x9e3779b97f4a7c15ULL;
static double urand(void) {
    rng_state ^= rng_state >> 12;
    rng_state ^= rng_state << 25;
    rng_state ^= rng_state >> 27;
    return (double)((rng_state * 2685821657736338717ULL) >> 11) * (1.0 / 9007199254740992.0);
}
static void rand_pt(double p[3], double lo, double hi) {
    for (int k = 0; k < 3; k++) {
        p[k] = lo + (hi - lo) * urand();
    }
}

static double dist3(const double a[3], const double b[3]) {
    double dx = a[0] - b[0], dy = a[1] - b[1], dz = a[2] - b[2];
    return sqrt(dx * dx + dy * dy + dz * dz);
}

/* ---- independent third implementation: golden section on the convex f(s) = min_t |P(s) - E(t)| ---- */
static double pt_seg(const double p[3], const double c[3], const double d[3]) {
    /* Ternary-free: exact projection with its own arithmetic (long double) */
    long double v[3], w[3], vv = 0, wv = 0, t, r2 = 0;
    for (int k = 0; k < 3; k++) {
        v[k] = (long double)d[k] - c[k];
        w[k] = (long double)p[k] - c[k];
        vv += v[k] * v[k];
        wv += w[k] * v[k];
    }
    t = vv > 0 ? wv / vv : 0;
    t = t < 0 ? 0 : (t > 1 ? 1 : t);
    for (int k = 0; k < 3; k++) {
        long double x = w[k] - t * v[k];
        r2 += x * x;
    }
    return (double)sqrtl(r2);
}
static double f_of_s(const double a[3], const double b[3], const double c[3], const double d[3], double s) {
    double p[3];
    for (int k = 0; k < 3; k++) {
        p[k] = a[k] + s * (b[k] - a[k]);
    }
    return pt_seg(p, c, d);
}
static double brute_segdist(const double a[3], const double b[3], const double c[3], const double d[3]) {
    const double g = (sqrt(5.0) - 1.0) / 2.0;
    double lo = 0.0, hi = 1.0, x1 = hi - g * (hi - lo), x2 = lo + g * (hi - lo);
    double f1 = f_of_s(a, b, c, d, x1), f2 = f_of_s(a, b, c, d, x2), best;
    for (int i = 0; i < 200 && hi - lo > 1e-15; i++) {
        if (f1 <= f2) {
            hi = x2;
            x2 = x1;
            f2 = f1;
            x1 = hi - g * (hi - lo);
            f1 = f_of_s(a, b, c, d, x1);
        } else {
            lo = x1;
            x1 = x2;
            f1 = f2;
            x2 = lo + g * (hi - lo);
            f2 = f_of_s(a, b, c, d, x2);
        }
    }
    best = fmin(f1, f2);
    best = fmin(best, f_of_s(a, b, c, d, 0.0));
    best = fmin(best, f_of_s(a, b, c, d, 1.0));
    /* symmetric pass: also from CD's side (guards the golden section against flat valleys) */
    best = fmin(best, pt_seg(c, a, b));
    best = fmin(best, pt_seg(d, a, b));
    return best;
}

/* Checks shared by every result: P on AB at s, E on CD at t, d = |P - E|. */
static void check_consistent(const double a[3], const double b[3], const double c[3], const double d[3],
                             const mca_segdist_t *r, double tol) {
    assert_true(r->s >= 0.0 && r->s <= 1.0);
    assert_true(r->t >= 0.0 && r->t <= 1.0);
    for (int k = 0; k < 3; k++) {
        assert_true(fabs(r->p[k] - (a[k] + r->s * (b[k] - a[k]))) <= tol);
        assert_true(fabs(r->e[k] - (c[k] + r->t * (d[k] - c[k]))) <= tol);
    }
    assert_true(fabs(r->d - dist3(r->p, r->e)) <= tol);
}

/* The hand-derived exact cases live in tests/segdist/exact_cases.txt, shared with test_mca_geom.py (which
 * sends the same cases through the mca-geom tool). Format: see the file's header. */
#ifndef SEGDIST_EXACT_CASES
#error "SEGDIST_EXACT_CASES (path of exact_cases.txt) must be set by CMake"
#endif
#define MAX_EXACT_CASES 64
#define MIN_EXACT_CASES 21 /* as many as the file holds today: a truncated file fails */

struct exact_case {
    char name[128];
    double a[3], b[3], c[3], d[3];
    double dist;
    int has_pts; /* witness points unique? */
    double p[3], e[3];
};

/* Parses exactly n numbers from s (whitespace separated, nothing else); returns 0 on success. */
static int parse_numbers(const char *s, double *out, int n) {
    int k = 0;
    for (;;) {
        char *q;
        while (*s == ' ' || *s == '\t') {
            s++;
        }
        if (*s == '\0') {
            break;
        }
        if (k == n) {
            return -1;
        }
        out[k] = strtod(s, &q);
        if (q == s || !isfinite(out[k])) {
            return -1;
        }
        k++;
        s = q;
    }
    return k == n ? 0 : -1;
}

/* Strips leading and trailing blanks in place. */
static char *trim(char *s) {
    char *end;
    while (*s == ' ' || *s == '\t') {
        s++;
    }
    end = s + strlen(s);
    while (end > s && (end[-1] == ' ' || end[-1] == '\t' || end[-1] == '\r')) {
        *--end = '\0';
    }
    return s;
}

static int load_exact_cases(struct exact_case *cases, int max) {
    FILE *f = fopen(SEGDIST_EXACT_CASES, "r");
    char line[512];
    int n = 0, lineno = 0;
    if (f == NULL) {
        fail_msg("cannot open %s", SEGDIST_EXACT_CASES);
    }
    while (fgets(line, sizeof line, f) != NULL) {
        char *field[4], *s, *nl = strchr(line, '\n');
        double v[12];
        lineno++;
        if (nl != NULL) {
            *nl = '\0';
        }
        s = trim(line);
        if (*s == '\0' || *s == '#') {
            continue;
        }
        field[0] = s;
        for (int i = 1; i < 4; i++) {
            char *bar = strchr(field[i - 1], '|');
            if (bar == NULL) {
                fail_msg("%s:%d: need 4 fields separated by '|'", SEGDIST_EXACT_CASES, lineno);
            }
            *bar = '\0';
            field[i] = bar + 1;
        }
        for (int i = 0; i < 4; i++) {
            field[i] = trim(field[i]);
        }
        if (strchr(field[3], '|') != NULL || n == max) {
            fail_msg("%s:%d: more than 4 fields or more than %d cases", SEGDIST_EXACT_CASES, lineno, max);
        }
        struct exact_case *ec = &cases[n];
        memset(ec, 0, sizeof *ec);
        snprintf(ec->name, sizeof ec->name, "%s", field[0]);
        if (parse_numbers(field[1], v, 12) != 0 || parse_numbers(field[2], &ec->dist, 1) != 0) {
            fail_msg("%s:%d: need 12 coordinates and one distance", SEGDIST_EXACT_CASES, lineno);
        }
        memcpy(ec->a, v, sizeof ec->a);
        memcpy(ec->b, v + 3, sizeof ec->b);
        memcpy(ec->c, v + 6, sizeof ec->c);
        memcpy(ec->d, v + 9, sizeof ec->d);
        ec->has_pts = strcmp(field[3], "-") != 0;
        if (ec->has_pts) {
            if (parse_numbers(field[3], v, 6) != 0) {
                fail_msg("%s:%d: need 6 numbers (P E) or '-'", SEGDIST_EXACT_CASES, lineno);
            }
            memcpy(ec->p, v, sizeof ec->p);
            memcpy(ec->e, v + 3, sizeof ec->e);
        }
        n++;
    }
    fclose(f);
    return n;
}

static void test_closed_exact(void **state) {
    (void)state;
    static struct exact_case exact_cases[MAX_EXACT_CASES];
    const int n = load_exact_cases(exact_cases, MAX_EXACT_CASES);
    int n_pts = 0;
    assert_true(n >= MIN_EXACT_CASES);
    for (int i = 0; i < n; i++) {
        const struct exact_case *ec = &exact_cases[i];
        mca_segdist_t r, r2;
        print_message("case: %s\n", ec->name);
        assert_int_equal(mca_segdist_closed(ec->a, ec->b, ec->c, ec->d, &r), MCA_OK);
        assert_true(fabs(r.d - ec->dist) <= 1e-12);
        assert_int_equal(r.iterations, 0);
        check_consistent(ec->a, ec->b, ec->c, ec->d, &r, 1e-12);
        /* Swapping the segments (and each segment's direction) gives the same distance, P and E swapped. */
        assert_int_equal(mca_segdist_closed(ec->d, ec->c, ec->b, ec->a, &r2), MCA_OK);
        assert_true(fabs(r2.d - ec->dist) <= 1e-12);
        check_consistent(ec->d, ec->c, ec->b, ec->a, &r2, 1e-12);
        if (ec->has_pts) {
            n_pts++;
            for (int k = 0; k < 3; k++) {
                assert_true(fabs(r.p[k] - ec->p[k]) <= 1e-12);
                assert_true(fabs(r.e[k] - ec->e[k]) <= 1e-12);
                assert_true(fabs(r2.p[k] - ec->e[k]) <= 1e-12);
                assert_true(fabs(r2.e[k] - ec->p[k]) <= 1e-12);
            }
        }
    }
    print_message("%d exact cases (%d with unique witness points), both orders\n", n, n_pts);
}

static void test_closed_rejects_bad_input(void **state) {
    (void)state;
    const double a[3] = {0, 0, 0}, b[3] = {1, 0, 0}, c[3] = {0, 1, 0};
    double bad[3] = {0, NAN, 0}, inf[3] = {INFINITY, 0, 0};
    mca_segdist_t r;
    memset(&r, 0x5a, sizeof r);
    mca_segdist_t before = r;
    assert_int_equal(mca_segdist_closed(a, b, c, bad, &r), MCA_EINVAL);
    assert_int_equal(mca_segdist_closed(inf, b, c, c, &r), MCA_EINVAL);
    double huge[3] = {0, 0, 1e101};
    assert_int_equal(mca_segdist_closed(a, b, c, huge, &r), MCA_EINVAL);
    assert_int_equal(mca_segdist_lsdm(huge, b, c, c, NULL, &r), MCA_EINVAL);
    assert_int_equal(mca_segdist_closed(NULL, b, c, c, &r), MCA_EINVAL);
    assert_int_equal(mca_segdist_closed(a, b, c, c, NULL), MCA_EINVAL);
    assert_int_equal(mca_segdist_lsdm(a, b, c, bad, NULL, &r), MCA_EINVAL);
    mca_lsdm_params_t p = {-1.0, 10};
    assert_int_equal(mca_segdist_lsdm(a, b, c, c, &p, &r), MCA_EINVAL);
    p.tol = 1e-9;
    p.max_iter = 1;
    assert_int_equal(mca_segdist_lsdm(a, b, c, c, &p, &r), MCA_EINVAL);
    assert_memory_equal(&r, &before, sizeof r); /* unchanged on error */
}

/* Random pair classes. */
enum pair_class { GENERIC, NEAR_PARALLEL, INTERSECTING, COLLINEAR, DEGENERATE, N_CLASSES };

static void make_pair(enum pair_class cls, double a[3], double b[3], double c[3], double d[3]) {
    double u[3], x[3], s, t;
    rand_pt(a, -1, 1);
    rand_pt(b, -1, 1);
    switch (cls) {
    case GENERIC:
        rand_pt(c, -1, 1);
        rand_pt(d, -1, 1);
        break;
    case NEAR_PARALLEL: {
        double off[3], ang = pow(10.0, -1.0 - 8.0 * urand());
        rand_pt(off, -0.3, 0.3);
        rand_pt(x, -1, 1);
        for (int k = 0; k < 3; k++) {
            u[k] = b[k] - a[k];
            c[k] = a[k] + off[k] - 0.5 * u[k] * urand();
            d[k] = c[k] + u[k] * (0.5 + urand()) + ang * x[k];
        }
        break;
    }
    case INTERSECTING:
        s = urand();
        t = urand();
        rand_pt(x, -1, 1);
        for (int k = 0; k < 3; k++) {
            double m = a[k] + s * (b[k] - a[k]); /* common point, exactly on AB up to rounding */
            c[k] = m - t * x[k];
            d[k] = m + (1.0 - t) * x[k];
        }
        break;
    case COLLINEAR:
        s = -1.0 + 3.0 * urand();
        t = -1.0 + 3.0 * urand();
        for (int k = 0; k < 3; k++) {
            c[k] = a[k] + s * (b[k] - a[k]);
            d[k] = a[k] + t * (b[k] - a[k]);
        }
        break;
    default:
        /* zero-length on one or both sides */
        rand_pt(c, -1, 1);
        if (urand() < 0.5) {
            memcpy(d, c, sizeof(double) * 3);
        } else {
            rand_pt(d, -1, 1);
        }
        memcpy(b, a, sizeof(double) * 3);
        if (urand() < 0.3) {
            double tmp[3];
            memcpy(tmp, a, sizeof tmp);
            memcpy(a, c, sizeof tmp); /* put the degenerate one on CD instead */
            memcpy(b, d, sizeof tmp);
            memcpy(c, tmp, sizeof tmp);
            memcpy(d, tmp, sizeof tmp);
        }
        break;
    }
}

/* Closed form vs the golden-section brute force. The brute force stops at hi - lo <= 1e-15 in s, so its
 * point on AB is within 1e-15 |AB| <= 3.5e-15 m (endpoints in [-1, 1]^3) of the optimal one and its
 * distance at most that much above the true minimum (less where the valley is flat); both sides' own
 * rounding adds a few 1e-16 m. Measured: at most 5.5e-16 m per class (printed below, docs/segdist.md).
 * 1e-13 is 30x the analytic bound and ~200x the measured worst; a closed form that mishandled a case
 * (wrong clamp, wrong candidate) would be off by far more. */
#define BRUTE_TOL 1e-13

static void test_closed_vs_brute(void **state) {
    (void)state;
    double worst[N_CLASSES] = {0};
    for (int cls = 0; cls < N_CLASSES; cls++) {
        for (int i = 0; i < 4000; i++) {
            double a[3], b[3], c[3], d[3], ref;
            mca_segdist_t r;
            make_pair((enum pair_class)cls, a, b, c, d);
            assert_int_equal(mca_segdist_closed(a, b, c, d, &r), MCA_OK);
            check_consistent(a, b, c, d, &r, 1e-12);
            ref = brute_segdist(a, b, c, d);
            /* Closed form never worse than the brute force, and within BRUTE_TOL of it. */
            assert_true(r.d <= ref + BRUTE_TOL);
            assert_true(fabs(r.d - ref) <= BRUTE_TOL);
            worst[cls] = fmax(worst[cls], fabs(r.d - ref));
        }
    }
    print_message("closed vs golden-section max |diff| per class: %.3g %.3g %.3g %.3g %.3g\n", worst[0],
                  worst[1], worst[2], worst[3], worst[4]);
}

static double angle_between(const double a[3], const double b[3], const double c[3], const double d[3]) {
    double u[3], v[3], uu = 0, vv = 0, uv = 0;
    for (int k = 0; k < 3; k++) {
        u[k] = b[k] - a[k];
        v[k] = d[k] - c[k];
        uu += u[k] * u[k];
        vv += v[k] * v[k];
        uv += u[k] * v[k];
    }
    return acos(fmin(1.0, fabs(uv) / sqrt(uu * vv)));
}

/* Non-pathological pairs: both longer than 0.2, at least 20 degrees apart. */
static void test_lsdm_vs_closed(void **state) {
    (void)state;
    const mca_lsdm_params_t paper = {1e-10, 10000};
    const mca_lsdm_params_t cert = {1e-10, 100000};
    double worst_paper = 0, worst_cert = 0;
    int n = 0, max_it = 0;
    while (n < 20000) {
        double a[3], b[3], c[3], d[3];
        mca_segdist_t rc, rl, rg;
        make_pair(GENERIC, a, b, c, d);
        if (dist3(a, b) < 0.2 || dist3(c, d) < 0.2 || angle_between(a, b, c, d) < 20.0 * M_PI / 180.0) {
            continue;
        }
        n++;
        assert_int_equal(mca_segdist_closed(a, b, c, d, &rc), MCA_OK);
        assert_int_equal(mca_segdist_lsdm(a, b, c, d, &paper, &rl), MCA_OK);
        assert_int_equal(mca_segdist_lsdm_certified(a, b, c, d, &cert, &rg), MCA_OK);
        check_consistent(a, b, c, d, &rl, 1e-12);
        check_consistent(a, b, c, d, &rg, 1e-12);
        /* LSDM pairs are feasible, so never below the true minimum (rounding aside) */
        assert_true(rl.d >= rc.d - 1e-12);
        assert_true(rg.d >= rc.d - 1e-12);
        /* paper rule at >= 20 degrees: contraction <= cos^2(20) per step, so error <= tol * 1 / (1 - 0.883)
         */
        assert_true(rl.d - rc.d <= 10.0 * paper.tol);
        /* certified rule: within its tolerance, by construction */
        assert_true(rg.d - rc.d <= cert.tol + 1e-12);
        worst_paper = fmax(worst_paper, rl.d - rc.d);
        worst_cert = fmax(worst_cert, rg.d - rc.d);
        max_it = rl.iterations > max_it ? rl.iterations : max_it;
    }
    print_message(
        "LSDM (tol 1e-10) vs closed: paper rule worst %.3g, certified worst %.3g, max iterations %d\n",
        worst_paper, worst_cert, max_it);
}

/* The paper's rule on a near-parallel pair stops far from the minimum; the certificate does not lie. */
static void test_lsdm_near_parallel_early_stop(void **state) {
    (void)state;
    /* AB along x; CD: y = 0.1, z = 1e-3 x (tilted by 1e-3 rad); the minimum is P = A, E = (0, 0.1, 0),
     * d = 0.1. From B the iterates creep towards x = 0 by a factor 1/(1 + 1e-6) per cycle. */
    const double a[3] = {0, 0, 0}, b[3] = {1, 0, 0}, c[3] = {-1, 0.1, -1e-3}, d[3] = {1, 0.1, 1e-3};
    const mca_lsdm_params_t paper = {MCA_LSDM_PAPER_TOL, 1000000};
    mca_segdist_t rc, rl, rg;
    assert_int_equal(mca_segdist_closed(a, b, c, d, &rc), MCA_OK);
    assert_true(fabs(rc.d - 0.1) < 1e-12);
    assert_true(fabs(rc.s) < 1e-12 && fabs(rc.t - 0.5) < 1e-12);
    assert_int_equal(mca_segdist_lsdm(a, b, c, d, &paper, &rl), MCA_OK);
    /* B -> H1 = (x', 0.1, 1e-3 x'), x' = 1 / (1 + 1e-6); H1 -> (x', 0, 0); the decline is ~1e-11 < 1e-5, so
     * it stops after 2 projections at sqrt(0.01 + 1e-6 x'^2), still ~5e-6 m off */
    print_message("paper rule: d = %.12g after %d iterations (true %.12g)\n", rl.d, rl.iterations, rc.d);
    assert_int_equal(rl.iterations, 2);
    assert_true(fabs(rl.d - sqrt(0.01 + 1e-6 / ((1 + 1e-6) * (1 + 1e-6)))) < 1e-14);
    /* certified rule with a cap: ENOTCONV (honest) or within tol */
    const mca_lsdm_params_t cert = {1e-9, 200};
    int r = mca_segdist_lsdm_certified(a, b, c, d, &cert, &rg);
    assert_true(r == MCA_ENOTCONV || (r == MCA_OK && rg.d - rc.d <= 1e-9 + 1e-15));
    if (r == MCA_OK) {
        assert_true(rg.iterations <= 200);
    }
}

static void test_lower_bound_is_a_bound(void **state) {
    (void)state;
    for (int i = 0; i < 20000; i++) {
        double a[3], b[3], c[3], d[3], p[3], e[3], s = urand(), t = urand();
        mca_segdist_t rc;
        make_pair((enum pair_class)(i % N_CLASSES), a, b, c, d);
        for (int k = 0; k < 3; k++) {
            p[k] = a[k] + s * (b[k] - a[k]);
            e[k] = c[k] + t * (d[k] - c[k]);
        }
        assert_int_equal(mca_segdist_closed(a, b, c, d, &rc), MCA_OK);
        assert_true(mca_segdist_lower_bound(a, b, c, d, p, e) <= rc.d + 1e-12);
        /* at the optimum the bound is tight */
        assert_true(rc.d - mca_segdist_lower_bound(a, b, c, d, rc.p, rc.e) <= 1e-9 || rc.d < 1e-9);
    }
}

static void test_paper_step1_cases(void **state) {
    (void)state;
    const double a[3] = {0, 0, 0}, b[3] = {2, 0, 0};
    double h[3], s;
    const double o1[3] = {-1, 1, 0}, o2[3] = {0.5, 3, 4}, o3[3] = {5, 4, 0};
    assert_true(fabs(mca_point_segment_paper(o1, a, b, h, &s) - sqrt(2.0)) < 1e-15); /* case 1: P = A */
    assert_true(s == 0.0 && h[0] == 0.0);
    assert_true(fabs(mca_point_segment_paper(o2, a, b, h, &s) - 5.0) < 1e-15); /* case 2: H on AB */
    assert_true(fabs(s - 0.25) < 1e-15 && fabs(h[0] - 0.5) < 1e-15);
    assert_true(fabs(mca_point_segment_paper(o3, a, b, h, &s) - 5.0) < 1e-15); /* case 3: P = B */
    assert_true(s == 1.0 && h[0] == 2.0);
    assert_true(fabs(mca_point_segment_paper(o3, a, a, h, &s) - sqrt(41.0)) < 1e-15); /* zero length */
    assert_true(s == 0.0);
}

/* ---- arm distances against brute force on random two-arm configurations ---- */
static void random_arm(mca_chain_t *ch, mca_kin_t *k, int dof, double x0) {
    memset(ch, 0, sizeof *ch);
    memset(k, 0, sizeof *k);
    ch->dof = dof;
    k->dof = dof;
    k->n_points = dof + 2;
    for (int i = 0; i <= dof; i++) {
        ch->link_radius[i] = 0.02 + 0.06 * urand();
    }
    k->point[0][0] = x0;
    for (int i = 1; i < k->n_points; i++) {
        for (int j = 0; j < 3; j++) {
            k->point[i][j] = k->point[i - 1][j] + (urand() - 0.5) * 0.6;
        }
        if (urand() < 0.1) { /* coincident joint origins: zero-length link */
            memcpy(k->point[i], k->point[i - 1], sizeof k->point[i]);
        }
    }
}

static void test_arm_distances_brute(void **state) {
    (void)state;
    for (int trial = 0; trial < 300; trial++) {
        mca_chain_t ca, cb;
        mca_kin_t ka, kb;
        mca_arm_distances_t out, out_l;
        int da = 1 + (int)(urand() * MCA_MAX_DOF), db = 1 + (int)(urand() * MCA_MAX_DOF);
        random_arm(&ca, &ka, da, 0.0);
        random_arm(&cb, &kb, db, 0.4);
        assert_int_equal(mca_arm_distances(&ca, &ka, &cb, &kb, MCA_DIST_CLOSED, &out), MCA_OK);
        assert_int_equal(out.n_links_a, da + 1);
        assert_int_equal(out.n_links_b, db + 1);
        assert_int_equal(out.iterations, 0);
        double gmin = INFINITY;
        double bmin[MCA_MAX_LINKS];
        for (int j = 0; j <= db; j++) {
            bmin[j] = INFINITY;
        }
        for (int i = 0; i <= da; i++) {
            double amin = INFINITY;
            for (int j = 0; j <= db; j++) {
                double ds = brute_segdist(ka.point[i], ka.point[i + 1], kb.point[j], kb.point[j + 1]) -
                            ca.link_radius[i] - cb.link_radius[j];
                amin = fmin(amin, ds);
                bmin[j] = fmin(bmin[j], ds);
            }
            gmin = fmin(gmin, amin);
            const mca_link_pair_t *lp = &out.a_to_b[i];
            assert_int_equal(lp->link, i);
            assert_true(fabs(lp->d - amin) <= 1e-9);
            assert_true(fabs(lp->d - (lp->d_axis - ca.link_radius[i] - cb.link_radius[lp->other_link])) <=
                        1e-12);
            /* the critical points are on the named axes and |p - e| = d_axis */
            assert_true(fabs(dist3(lp->p, lp->e) - lp->d_axis) <= 1e-12);
            assert_true(pt_seg(lp->p, ka.point[i], ka.point[i + 1]) <= 1e-12);
            assert_true(pt_seg(lp->e, kb.point[lp->other_link], kb.point[lp->other_link + 1]) <= 1e-12);
        }
        for (int j = 0; j <= db; j++) {
            const mca_link_pair_t *lp = &out.b_to_a[j];
            assert_int_equal(lp->link, j);
            assert_true(fabs(lp->d - bmin[j]) <= 1e-9);
            assert_true(pt_seg(lp->p, kb.point[j], kb.point[j + 1]) <= 1e-12);
            assert_true(pt_seg(lp->e, ka.point[lp->other_link], ka.point[lp->other_link + 1]) <= 1e-12);
        }
        assert_true(fabs(out.min.d - gmin) <= 1e-9);
        assert_true(pt_seg(out.min.p, ka.point[out.min.link], ka.point[out.min.link + 1]) <= 1e-12);
        /* LSDM method agrees loosely (it is the paper's iteration, capped) and counts iterations */
        assert_int_equal(mca_arm_distances(&ca, &ka, &cb, &kb, MCA_DIST_LSDM, &out_l), MCA_OK);
        assert_true(out_l.iterations >= 2 * (da + 1) * (db + 1));
        assert_true(out_l.min.d >= out.min.d - 1e-12);
        assert_true(out_l.min.d - out.min.d <= 1e-3);
    }
}

static void test_arm_distances_bad_input(void **state) {
    (void)state;
    mca_chain_t ca, cb;
    mca_kin_t ka, kb;
    mca_arm_distances_t out;
    random_arm(&ca, &ka, 3, 0.0);
    random_arm(&cb, &kb, 4, 1.0);
    assert_int_equal(mca_arm_distances(NULL, &ka, &cb, &kb, MCA_DIST_CLOSED, &out), MCA_EINVAL);
    assert_int_equal(mca_arm_distances(&ca, &ka, &cb, &kb, (mca_dist_method_t)7, &out), MCA_EINVAL);
    kb.dof = 3; /* kinematic state of another chain */
    assert_int_equal(mca_arm_distances(&ca, &ka, &cb, &kb, MCA_DIST_CLOSED, &out), MCA_EINVAL);
    kb.dof = 4;
    kb.point[2][1] = NAN;
    assert_int_equal(mca_arm_distances(&ca, &ka, &cb, &kb, MCA_DIST_CLOSED, &out), MCA_EINVAL);
}

/* Two parallel vertical arms: the answer is obvious (base gap minus radii). */
static void test_arm_distances_known(void **state) {
    (void)state;
    mca_chain_t ca, cb;
    mca_kin_t ka, kb;
    mca_arm_distances_t out;
    memset(&ca, 0, sizeof ca);
    memset(&ka, 0, sizeof ka);
    ca.dof = 2;
    ka.dof = 2;
    ka.n_points = 4;
    for (int i = 0; i < 4; i++) {
        ka.point[i][2] = 0.3 * i;
        ca.link_radius[i < 3 ? i : 2] = 0.05;
    }
    cb = ca;
    kb = ka;
    for (int i = 0; i < 4; i++) {
        kb.point[i][0] = 0.5;
    }
    kb.point[3][0] = 0.2; /* B's last link leans towards A: tip at x = 0.2, z = 0.9 */
    assert_int_equal(mca_arm_distances(&ca, &ka, &cb, &kb, MCA_DIST_CLOSED, &out), MCA_OK);
    assert_true(fabs(out.min.d - (0.2 - 0.1)) <= 1e-12);
    assert_int_equal(out.min.link, 2);
    assert_int_equal(out.min.other_link, 2);
    assert_true(fabs(out.min.p[2] - 0.9) <= 1e-12 && fabs(out.min.e[0] - 0.2) <= 1e-12);
    /* link 0 of A: closest on B is link 0 or 1 at x-gap 0.5 */
    assert_true(fabs(out.a_to_b[0].d - (0.5 - 0.1)) <= 1e-12);
}

/* Two PA10+ (real URDF, real FK) standing straight up 1 m apart: every link lies on a vertical line, so
 * the axis distance of links i, j is 1 when their height ranges overlap, else hypot(1, gap). */
static void test_arm_distances_pa10_pair(void **state) {
    (void)state;
    mca_chain_t ca, cb;
    mca_kin_t ka, kb;
    mca_arm_distances_t out;
    char err[256];
    const char *urdf = MCA_ROBOTS_DIR "/pa10plus.urdf";
    const double base_b[3] = {1.0, 0.0, 0.0}, yaw[3] = {0, 0, 2.0};
    double q[MCA_MAX_DOF] = {0};
    assert_int_equal(mca_chain_load_urdf(&ca, urdf, NULL, err, sizeof err), MCA_OK);
    cb = ca;
    mca_chain_set_base(&cb, base_b, yaw); /* yaw about its own vertical axis moves no link */
    assert_int_equal(mca_fk(&ca, q, &ka), MCA_OK);
    assert_int_equal(mca_fk(&cb, q, &kb), MCA_OK);
    assert_int_equal(mca_arm_distances(&ca, &ka, &cb, &kb, MCA_DIST_CLOSED, &out), MCA_OK);
    double gmin = INFINITY;
    for (int i = 0; i <= ca.dof; i++) {
        double amin = INFINITY;
        for (int j = 0; j <= cb.dof; j++) {
            double lo_a = fmin(ka.point[i][2], ka.point[i + 1][2]),
                   hi_a = fmax(ka.point[i][2], ka.point[i + 1][2]);
            double lo_b = fmin(kb.point[j][2], kb.point[j + 1][2]),
                   hi_b = fmax(kb.point[j][2], kb.point[j + 1][2]);
            double gap = fmax(0.0, fmax(lo_a - hi_b, lo_b - hi_a));
            amin = fmin(amin, sqrt(1.0 + gap * gap) - ca.link_radius[i] - cb.link_radius[j]);
        }
        assert_true(fabs(out.a_to_b[i].d - amin) < 1e-12);
        gmin = fmin(gmin, amin);
    }
    assert_true(fabs(out.min.d - gmin) < 1e-12);
    assert_true(fabs(out.min.d_axis - 1.0) < 1e-12);
    /* the direction P -> E is +x */
    assert_true(fabs(out.min.e[0] - out.min.p[0] - 1.0) < 1e-12);
    print_message("PA10+ pair 1 m apart: min surface distance %.6f m (links %d, %d)\n", out.min.d,
                  out.min.link, out.min.other_link);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_closed_exact),
        cmocka_unit_test(test_closed_rejects_bad_input),
        cmocka_unit_test(test_paper_step1_cases),
        cmocka_unit_test(test_closed_vs_brute),
        cmocka_unit_test(test_lsdm_vs_closed),
        cmocka_unit_test(test_lsdm_near_parallel_early_stop),
        cmocka_unit_test(test_lower_bound_is_a_bound),
        cmocka_unit_test(test_arm_distances_known),
        cmocka_unit_test(test_arm_distances_brute),
        cmocka_unit_test(test_arm_distances_bad_input),
        cmocka_unit_test(test_arm_distances_pa10_pair),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
