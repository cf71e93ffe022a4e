/* SPDX-License-Identifier: MIT */
/* Capsule vs obstacle (GJK on libccd support functions, MPR for overlap): against closed forms on
 * axis-aligned / rotated boxes, cups and the table, against a brute-force golden section on random
 * rotated boxes, and capsule-capsule against mca_segdist_closed(). */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include <cmocka.h>

#include "mca/err.h"
#include "mca/obstacle.h"
#include "mca/segdist.h"
#include "mca/urdf.h"

static uint64_t rng_state = 0x1234567887654321ULL;
static double urand(void) {
    rng_state ^= rng_state >> 12;
    rng_state ^= rng_state << 25;
    rng_state ^= rng_state >> 27;
    return (double)((rng_state * 2685821657736338717ULL) >> 11) * (1.0 / 9007199254740992.0);
}

static void identity_pose(mca_pose_t *p, double x, double y, double z) {
    memset(p, 0, sizeof *p);
    p->R[0][0] = p->R[1][1] = p->R[2][2] = 1.0;
    p->p[0] = x;
    p->p[1] = y;
    p->p[2] = z;
}

/* R = Rz(yaw) Ry(pitch) Rx(roll), written out here (independent of chain.c) */
static void rpy_pose(mca_pose_t *p, const double xyz[3], double roll, double pitch, double yaw) {
    double cr = cos(roll), sr = sin(roll), cp = cos(pitch), sp = sin(pitch), cy = cos(yaw), sy = sin(yaw);
    p->R[0][0] = cy * cp;
    p->R[0][1] = cy * sp * sr - sy * cr;
    p->R[0][2] = cy * sp * cr + sy * sr;
    p->R[1][0] = sy * cp;
    p->R[1][1] = sy * sp * sr + cy * cr;
    p->R[1][2] = sy * sp * cr - cy * sr;
    p->R[2][0] = -sp;
    p->R[2][1] = cp * sr;
    p->R[2][2] = cp * cr;
    memcpy(p->p, xyz, sizeof p->p);
}

static double dist3(const double a[3], const double b[3]) {
    return sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) +
                (a[2] - b[2]) * (a[2] - b[2]));
}

static void capsule(mca_capsule_t *c, double ax, double ay, double az, double bx, double by, double bz,
                    double r) {
    c->a[0] = ax;
    c->a[1] = ay;
    c->a[2] = az;
    c->b[0] = bx;
    c->b[1] = by;
    c->b[2] = bz;
    c->radius = r;
}

/* Result sanity: p on the axis, |p - q| = d + r when separated, dir unit along p - q. */
static void check_witness(const mca_capsule_t *c, const mca_obst_dist_t *r, double tol) {
    mca_segdist_t sd;
    assert_int_equal(mca_segdist_closed(c->a, c->b, r->p, r->p, &sd), MCA_OK);
    assert_true(sd.d <= tol);
    assert_true(fabs(sqrt(r->dir[0] * r->dir[0] + r->dir[1] * r->dir[1] + r->dir[2] * r->dir[2]) - 1.0) <
                1e-12);
    if (!r->penetrating) {
        assert_true(fabs(dist3(r->p, r->q) - (r->d + c->radius)) <= tol);
    }
}

static void test_box_axis_aligned(void **state) {
    (void)state;
    mca_obstacle_t box;
    mca_pose_t pose;
    mca_capsule_t c;
    mca_obst_dist_t r;
    const double half[3] = {0.5, 0.5, 0.5};
    identity_pose(&pose, 0, 0, 0);
    assert_int_equal(mca_obstacle_box(&box, "box", &pose, half), MCA_OK);

    /* horizontal capsule 1 m up: 1 - 0.5 - 0.1 */
    capsule(&c, -1, 0, 1, 1, 0, 1, 0.1);
    assert_int_equal(mca_capsule_obstacle_distance(&c, &box, &r), MCA_OK);
    assert_true(fabs(r.d - 0.4) < 1e-9);
    assert_true(fabs(r.q[2] - 0.5) < 1e-9 && fabs(r.p[2] - 1.0) < 1e-12 && fabs(r.p[0]) <= 0.5 + 1e-9);
    assert_true(fabs(r.dir[2] - 1.0) < 1e-9);
    assert_int_equal(r.penetrating, 0);
    check_witness(&c, &r, 1e-9);

    /* point capsule off a corner: sqrt(3) * 0.5 */
    capsule(&c, 1, 1, 1, 1, 1, 1, 0.0);
    assert_int_equal(mca_capsule_obstacle_distance(&c, &box, &r), MCA_OK);
    assert_true(fabs(r.d - sqrt(3.0) * 0.5) < 1e-9);
    assert_true(fabs(r.q[0] - 0.5) < 1e-9 && fabs(r.q[1] - 0.5) < 1e-9 && fabs(r.q[2] - 0.5) < 1e-9);

    /* segment parallel to an edge: dx = 0.5, dz = 0.2 */
    capsule(&c, 1, -1, 0.7, 1, 1, 0.7, 0.05);
    assert_int_equal(mca_capsule_obstacle_distance(&c, &box, &r), MCA_OK);
    assert_true(fabs(r.d - (sqrt(0.25 + 0.04) - 0.05)) < 1e-9);
    check_witness(&c, &r, 1e-9);

    /* axis inside the box, 0.3 above the centre: the capsule must rise 0.5 - 0.3 + 0.1 = 0.3 */
    capsule(&c, -1, 0, 0.3, 1, 0, 0.3, 0.1);
    assert_int_equal(mca_capsule_obstacle_distance(&c, &box, &r), MCA_OK);
    assert_int_equal(r.penetrating, 1);
    assert_true(fabs(r.d + 0.3) < 1e-12); /* SAT: exact */
    assert_true(fabs(r.dir[2] - 1.0) < 1e-12);
    assert_true(fabs(r.q[2] - 0.5) < 1e-12 && fabs(r.p[2] - 0.3) < 1e-12);

    /* capsule surface overlapping, axis outside: 0.55 - 0.5 - 0.1 = -0.05 (GJK path, exact) */
    capsule(&c, -0.2, 0, 0.55, 0.2, 0, 0.55, 0.1);
    assert_int_equal(mca_capsule_obstacle_distance(&c, &box, &r), MCA_OK);
    assert_true(fabs(r.d + 0.05) < 1e-9);
    assert_int_equal(r.penetrating, 0);
}

static void test_box_rotated(void **state) {
    (void)state;
    mca_obstacle_t box;
    mca_pose_t pose;
    mca_capsule_t c;
    mca_obst_dist_t r;
    const double half[3] = {0.5, 0.5, 0.5}, at[3] = {0, 0, 0};
    rpy_pose(&pose, at, 0, 0, M_PI / 4);
    assert_int_equal(mca_obstacle_box(&box, "rot", &pose, half), MCA_OK);
    /* vertical capsule at x = 1 faces the vertical edge at x = sqrt(0.5) */
    capsule(&c, 1, 0, -0.2, 1, 0, 0.2, 0.02);
    assert_int_equal(mca_capsule_obstacle_distance(&c, &box, &r), MCA_OK);
    assert_true(fabs(r.d - (1.0 - sqrt(0.5) - 0.02)) < 1e-9);
    assert_true(fabs(r.q[0] - sqrt(0.5)) < 1e-9 && fabs(r.q[1]) < 1e-9);
    check_witness(&c, &r, 1e-9);
}

static void test_cylinder_and_table(void **state) {
    (void)state;
    mca_obstacle_t cup, table;
    mca_pose_t pose;
    mca_capsule_t c;
    mca_obst_dist_t r;
    identity_pose(&pose, 0.5, 0, 0.05);
    assert_int_equal(mca_obstacle_cylinder(&cup, "cup", &pose, 0.04, 0.1), MCA_OK);
    /* beside the cup: 0.1 - 0.04 - 0.01 */
    capsule(&c, 0.6, 0, 0, 0.6, 0, 0.1, 0.01);
    assert_int_equal(mca_capsule_obstacle_distance(&c, &cup, &r), MCA_OK);
    assert_true(fabs(r.d - 0.05) < 1e-9);
    check_witness(&c, &r, 1e-9);
    /* above it: 0.2 - 0.1 - 0.02 */
    capsule(&c, 0.3, 0, 0.2, 0.7, 0, 0.2, 0.02);
    assert_int_equal(mca_capsule_obstacle_distance(&c, &cup, &r), MCA_OK);
    assert_true(fabs(r.d - 0.08) < 1e-9);
    /* off the rim, diagonally: a point 0.03 out and 0.04 up from the rim is 0.05 away */
    capsule(&c, 0.57, 0, 0.14, 0.57, 0, 0.14, 0.0);
    assert_int_equal(mca_capsule_obstacle_distance(&c, &cup, &r), MCA_OK);
    assert_true(fabs(r.d - 0.05) < 1e-9);
    assert_true(fabs(r.q[0] - 0.54) < 1e-6 && fabs(r.q[2] - 0.1) < 1e-9);
    /* rim seen from a skew direction (curved side: GJK converges, not finite) */
    capsule(&c, 0.5 + 0.04 * cos(0.7) + 0.1 * cos(0.7), 0.04 * sin(0.7) + 0.1 * sin(0.7), -0.3,
            0.5 + 0.04 * cos(0.7) + 0.1 * cos(0.7), 0.04 * sin(0.7) + 0.1 * sin(0.7), 0.3, 0.0);
    assert_int_equal(mca_capsule_obstacle_distance(&c, &cup, &r), MCA_OK);
    assert_true(fabs(r.d - 0.1) < 1e-9);

    assert_int_equal(mca_obstacle_table(&table, "table", 0.7, 0, 0, 1.0, 1.0, 2.0), MCA_OK);
    capsule(&c, 0.2, 0.1, 0.8, 0.2, 0.1, 1.2, 0.03);
    assert_int_equal(mca_capsule_obstacle_distance(&c, &table, &r), MCA_OK);
    assert_true(fabs(r.d - 0.07) < 1e-9);
    assert_true(fabs(r.q[2] - 0.7) < 1e-9 && fabs(r.dir[2] - 1.0) < 1e-9);
    /* a link lying in the table top by 0.01 */
    capsule(&c, -0.3, 0.1, 0.69, 0.3, 0.1, 0.69, 0.03);
    assert_int_equal(mca_capsule_obstacle_distance(&c, &table, &r), MCA_OK);
    assert_int_equal(r.penetrating, 1);
    assert_true(fabs(r.d + 0.04) < 1e-12);
    /* axis poking 0.02 into the cup's top (libccd MPR): rise 0.02 + 0.01 */
    capsule(&c, 0.5, 0, 0.3, 0.5, 0, 0.08, 0.01);
    assert_int_equal(mca_capsule_obstacle_distance(&c, &cup, &r), MCA_OK);
    assert_int_equal(r.penetrating, 1);
    assert_true(fabs(r.d + 0.03) < 1e-6);
    assert_true(fabs(r.dir[2] - 1.0) < 1e-6);
}

/* Minkowski difference support of (box - segment) in the box frame along unit n. */
static double mtd_support(const double half[3], const double al[3], const double bl[3], const double n[3]) {
    double h = half[0] * fabs(n[0]) + half[1] * fabs(n[1]) + half[2] * fabs(n[2]);
    double sa = al[0] * n[0] + al[1] * n[1] + al[2] * n[2], sb = bl[0] * n[0] + bl[1] * n[1] + bl[2] * n[2];
    return h - fmin(sa, sb);
}

/* Segment inside / through a box: the SAT depth is the least translation (never above a dense search over
 * directions, which can only overestimate). Box at the origin, axis-aligned, so box frame = world. */
static void test_box_penetration_vs_directions(void **state) {
    (void)state;
    for (int trial = 0; trial < 100; trial++) {
        mca_obstacle_t box;
        mca_pose_t pose;
        mca_capsule_t c;
        mca_obst_dist_t r;
        double half[3] = {0.1 + 0.4 * urand(), 0.1 + 0.4 * urand(), 0.1 + 0.4 * urand()};
        identity_pose(&pose, 0, 0, 0);
        assert_int_equal(mca_obstacle_box(&box, NULL, &pose, half), MCA_OK);
        /* one end inside the box */
        capsule(&c, (urand() - 0.5) * half[0], (urand() - 0.5) * half[1], (urand() - 0.5) * half[2],
                2 * urand() - 1, 2 * urand() - 1, 2 * urand() - 1, 0.02);
        assert_int_equal(mca_capsule_obstacle_distance(&c, &box, &r), MCA_OK);
        assert_int_equal(r.penetrating, 1);
        double depth = -r.d - c.radius, best = INFINITY;
        for (int i = 0; i < 20000; i++) { /* Fibonacci sphere */
            double z = 1.0 - (2.0 * i + 1.0) / 20000.0, rr = sqrt(1.0 - z * z), ph = i * 2.399963229728653;
            double n[3] = {rr * cos(ph), rr * sin(ph), z};
            best = fmin(best, mtd_support(half, c.a, c.b, n));
        }
        assert_true(depth <= best + 1e-12);
        assert_true(depth >= best - 0.05); /* the search is coarse; it only bounds from above */
        /* moving the capsule by depth along dir makes the axis touch: GJK distance ~ 0 */
        mca_capsule_t moved = c;
        for (int k = 0; k < 3; k++) {
            moved.a[k] += (depth + 1e-9) * r.dir[k];
            moved.b[k] += (depth + 1e-9) * r.dir[k];
        }
        mca_obst_dist_t r2;
        assert_int_equal(mca_capsule_obstacle_distance(&moved, &box, &r2), MCA_OK);
        assert_int_equal(r2.penetrating, 0);
        assert_true(fabs(r2.d + c.radius) < 1e-8);
    }
}

static void test_capsule_axes_crossing(void **state) {
    (void)state;
    mca_capsule_t a, b;
    mca_obst_dist_t r;
    capsule(&a, -1, 0, 0, 1, 0, 0, 0.1);
    capsule(&b, 0.5, -1, 0, 0.5, 1, 0, 0.05);
    assert_int_equal(mca_capsule_capsule_distance_ccd(&a, &b, &r), MCA_OK);
    assert_int_equal(r.penetrating, 1);
    assert_true(fabs(r.d + 0.15) < 1e-15);
    assert_true(fabs(fabs(r.dir[2]) - 1.0) < 1e-15);
    assert_true(fabs(r.p[0] - 0.5) < 1e-12);
}

/* independent point-box distance: clamp in the box frame */
static double point_box(const mca_pose_t *pose, const double half[3], const double x[3]) {
    double rel[3], l[3], d2 = 0;
    for (int i = 0; i < 3; i++) {
        rel[i] = x[i] - pose->p[i];
    }
    for (int i = 0; i < 3; i++) {
        l[i] = pose->R[0][i] * rel[0] + pose->R[1][i] * rel[1] + pose->R[2][i] * rel[2];
        double e = fabs(l[i]) - half[i];
        if (e > 0) {
            d2 += e * e;
        }
    }
    return sqrt(d2);
}

static double seg_box_brute(const mca_pose_t *pose, const double half[3], const double a[3],
                            const double b[3]) {
    const double g = (sqrt(5.0) - 1.0) / 2.0;
    double lo = 0, hi = 1, x[3];
#define F(s)                                                                                                 \
    (x[0] = a[0] + (s) * (b[0] - a[0]), x[1] = a[1] + (s) * (b[1] - a[1]),                                   \
     x[2] = a[2] + (s) * (b[2] - a[2]), point_box(pose, half, x))
    double x1 = hi - g * (hi - lo), x2 = lo + g * (hi - lo), f1 = F(x1), f2 = F(x2);
    for (int i = 0; i < 200; i++) {
        if (f1 <= f2) {
            hi = x2;
            x2 = x1;
            f2 = f1;
            x1 = hi - g * (hi - lo);
            f1 = F(x1);
        } else {
            lo = x1;
            x1 = x2;
            f1 = f2;
            x2 = lo + g * (hi - lo);
            f2 = F(x2);
        }
    }
    double best = fmin(f1, f2);
    best = fmin(best, F(0.0));
    best = fmin(best, F(1.0));
#undef F
    return best;
}

static void test_box_random_vs_brute(void **state) {
    (void)state;
    double worst = 0;
    int max_it = 0, n = 0;
    for (int i = 0; i < 3000; i++) {
        mca_obstacle_t box;
        mca_pose_t pose;
        mca_capsule_t c;
        mca_obst_dist_t r;
        double at[3] = {urand() - 0.5, urand() - 0.5, urand() - 0.5};
        double half[3] = {0.05 + 0.4 * urand(), 0.05 + 0.4 * urand(), 0.05 + 0.4 * urand()};
        rpy_pose(&pose, at, 6 * urand(), 6 * urand(), 6 * urand());
        assert_int_equal(mca_obstacle_box(&box, NULL, &pose, half), MCA_OK);
        capsule(&c, 3 * urand() - 1.5, 3 * urand() - 1.5, 3 * urand() - 1.5, 3 * urand() - 1.5,
                3 * urand() - 1.5, 3 * urand() - 1.5, 0.05 * urand());
        double ref = seg_box_brute(&pose, half, c.a, c.b);
        assert_int_equal(mca_capsule_obstacle_distance(&c, &box, &r), MCA_OK);
        if (ref < 1e-6) {
            assert_true(r.d <= -c.radius + 1e-9); /* axis touches or enters */
            continue;
        }
        n++;
        assert_int_equal(r.penetrating, 0);
        assert_true(fabs(r.d + c.radius - ref) < 1e-9);
        /* witnesses: q on the box surface, p on the axis */
        assert_true(fabs(point_box(&pose, half, r.q)) < 1e-9);
        assert_true(fabs(point_box(&pose, half, r.p) - ref) < 1e-9);
        check_witness(&c, &r, 1e-9);
        worst = fmax(worst, fabs(r.d + c.radius - ref));
        max_it = r.iterations > max_it ? r.iterations : max_it;
    }
    print_message(
        "segment-box GJK vs golden section: %d separated pairs, max |diff| %.3g, max iterations %d\n", n,
        worst, max_it);
    assert_true(n > 1000);
}

/* independent point-cylinder distance (axis = pose z) */
static double point_cyl(const mca_pose_t *pose, double rad, double hh, const double x[3]) {
    double rel[3], l[3];
    for (int i = 0; i < 3; i++) {
        rel[i] = x[i] - pose->p[i];
    }
    for (int i = 0; i < 3; i++) {
        l[i] = pose->R[0][i] * rel[0] + pose->R[1][i] * rel[1] + pose->R[2][i] * rel[2];
    }
    double er = fmax(0.0, hypot(l[0], l[1]) - rad), ez = fmax(0.0, fabs(l[2]) - hh);
    return hypot(er, ez);
}

static double cyl_at(const mca_pose_t *pose, double rad, double hh, const double a[3], const double b[3],
                     double s) {
    double x[3];
    for (int k = 0; k < 3; k++) {
        x[k] = a[k] + s * (b[k] - a[k]);
    }
    return point_cyl(pose, rad, hh, x);
}

static double seg_cyl_brute(const mca_pose_t *pose, double rad, double hh, const double a[3],
                            const double b[3]) {
    const double g = (sqrt(5.0) - 1.0) / 2.0;
    double lo = 0, hi = 1;
    double x1 = hi - g * (hi - lo), x2 = lo + g * (hi - lo);
    double f1 = cyl_at(pose, rad, hh, a, b, x1), f2 = cyl_at(pose, rad, hh, a, b, x2);
    for (int i = 0; i < 200; i++) {
        if (f1 <= f2) {
            hi = x2;
            x2 = x1;
            f2 = f1;
            x1 = hi - g * (hi - lo);
            f1 = cyl_at(pose, rad, hh, a, b, x1);
        } else {
            lo = x1;
            x1 = x2;
            f1 = f2;
            x2 = lo + g * (hi - lo);
            f2 = cyl_at(pose, rad, hh, a, b, x2);
        }
    }
    double e0 = cyl_at(pose, rad, hh, a, b, 0.0), e1 = cyl_at(pose, rad, hh, a, b, 1.0);
    return fmin(fmin(f1, f2), fmin(e0, e1));
}

/* Curved shape: GJK converges (not finitely) within its cap and tolerance on random cups. */
static void test_cylinder_random_vs_brute(void **state) {
    (void)state;
    double worst = 0;
    int max_it = 0, n = 0;
    for (int i = 0; i < 3000; i++) {
        mca_obstacle_t cup;
        mca_pose_t pose;
        mca_capsule_t c;
        mca_obst_dist_t r;
        double at[3] = {urand() - 0.5, urand() - 0.5, urand() - 0.5};
        double rad = 0.02 + 0.3 * urand(), h = 0.05 + 0.6 * urand();
        rpy_pose(&pose, at, 6 * urand(), 6 * urand(), 6 * urand());
        assert_int_equal(mca_obstacle_cylinder(&cup, "cup", &pose, rad, h), MCA_OK);
        capsule(&c, 3 * urand() - 1.5, 3 * urand() - 1.5, 3 * urand() - 1.5, 3 * urand() - 1.5,
                3 * urand() - 1.5, 3 * urand() - 1.5, 0.03 * urand());
        double ref = seg_cyl_brute(&pose, rad, 0.5 * h, c.a, c.b);
        int rc = mca_capsule_obstacle_distance(&c, &cup, &r);
        if (ref < 1e-6) {
            assert_int_equal(rc, MCA_OK);
            assert_true(r.d <= -c.radius + 1e-9);
            continue;
        }
        n++;
        assert_int_equal(rc, MCA_OK);
        assert_true(fabs(r.d + c.radius - ref) < 1e-9);
        assert_true(point_cyl(&pose, rad, 0.5 * h, r.q) < 1e-9); /* q on the solid */
        check_witness(&c, &r, 1e-9);
        worst = fmax(worst, fabs(r.d + c.radius - ref));
        max_it = r.iterations > max_it ? r.iterations : max_it;
    }
    print_message(
        "segment-cylinder GJK vs golden section: %d separated pairs, max |diff| %.3g, max iterations %d\n", n,
        worst, max_it);
    assert_true(n > 1000);
}

static void test_capsule_capsule_vs_closed(void **state) {
    (void)state;
    double worst = 0;
    int n = 0;
    for (int i = 0; i < 5000; i++) {
        mca_capsule_t c1, c2;
        mca_obst_dist_t r;
        mca_segdist_t sd;
        capsule(&c1, 2 * urand() - 1, 2 * urand() - 1, 2 * urand() - 1, 2 * urand() - 1, 2 * urand() - 1,
                2 * urand() - 1, 0.05 * urand());
        capsule(&c2, 2 * urand() - 1, 2 * urand() - 1, 2 * urand() - 1, 2 * urand() - 1, 2 * urand() - 1,
                2 * urand() - 1, 0.05 * urand());
        if (i % 10 == 0) { /* some degenerate (point) capsules */
            memcpy(c2.b, c2.a, sizeof c2.a);
        }
        assert_int_equal(mca_segdist_closed(c1.a, c1.b, c2.a, c2.b, &sd), MCA_OK);
        assert_int_equal(mca_capsule_capsule_distance_ccd(&c1, &c2, &r), MCA_OK);
        if (sd.d < 1e-6) {
            continue;
        }
        n++;
        assert_true(fabs(r.d - (sd.d - c1.radius - c2.radius)) < 1e-9);
        worst = fmax(worst, fabs(r.d - (sd.d - c1.radius - c2.radius)));
        /* q on the second axis */
        mca_segdist_t on;
        assert_int_equal(mca_segdist_closed(c2.a, c2.b, r.q, r.q, &on), MCA_OK);
        assert_true(on.d < 1e-9);
    }
    print_message("capsule-capsule GJK vs closed form: %d pairs, max |diff| %.3g\n", n, worst);
}

static void test_bad_input(void **state) {
    (void)state;
    mca_obstacle_t box;
    mca_pose_t pose;
    mca_capsule_t c;
    mca_obst_dist_t r;
    double half[3] = {0.5, 0.5, 0.0};
    identity_pose(&pose, 0, 0, 0);
    assert_int_equal(mca_obstacle_box(&box, "flat", &pose, half), MCA_EINVAL);
    half[2] = 0.5;
    assert_int_equal(mca_obstacle_box(&box, "ok", &pose, half), MCA_OK);
    assert_string_equal(box.name, "ok");
    assert_int_equal(mca_obstacle_cylinder(&box, "cup", &pose, -0.1, 0.1), MCA_EINVAL);
    capsule(&c, 0, 0, 2, 0, 0, 3, -0.1);
    assert_int_equal(mca_capsule_obstacle_distance(&c, &box, &r), MCA_EINVAL);
    capsule(&c, 0, NAN, 2, 0, 0, 3, 0.1);
    assert_int_equal(mca_capsule_obstacle_distance(&c, &box, &r), MCA_EINVAL);
    assert_int_equal(mca_capsule_obstacle_distance(NULL, &box, &r), MCA_EINVAL);
    assert_int_equal(mca_obstacle_table(&box, "t", NAN, 0, 0, 1, 1, 1), MCA_EINVAL);
}

/* PA10+ (real URDF and FK) standing straight up among a table, a box and a cup: every link is a vertical
 * capsule on the z axis, so each link-obstacle distance has a closed form. */
static void test_arm_obstacles_pa10(void **state) {
    (void)state;
    mca_chain_t ch;
    mca_kin_t kin;
    mca_obstacle_t obs[3];
    mca_arm_obstacles_t out;
    mca_pose_t pose;
    char err[256];
    double q[MCA_MAX_DOF] = {0};
    const double box_half[3] = {0.1, 0.1, 2.0};
    assert_int_equal(mca_chain_load_urdf(&ch, MCA_ROBOTS_DIR "/pa10plus.urdf", NULL, err, sizeof err),
                     MCA_OK);
    assert_int_equal(mca_fk(&ch, q, &kin), MCA_OK);
    assert_int_equal(mca_obstacle_table(&obs[0], "table", -0.1, 0, 0, 3, 3, 1), MCA_OK);
    identity_pose(&pose, 0.5, 0, 0);
    assert_int_equal(mca_obstacle_box(&obs[1], "box", &pose, box_half), MCA_OK);
    identity_pose(&pose, 0, 0.3, 1.6);
    assert_int_equal(mca_obstacle_cylinder(&obs[2], "cup", &pose, 0.04, 0.1), MCA_OK);
    assert_int_equal(mca_arm_obstacle_distances(&ch, &kin, obs, 3, &out), MCA_OK);
    assert_int_equal(out.n_links, ch.dof + 1);
    double gmin = INFINITY;
    for (int k = 0; k <= ch.dof; k++) {
        double zlo = fmin(kin.point[k][2], kin.point[k + 1][2]),
               zhi = fmax(kin.point[k][2], kin.point[k + 1][2]);
        double r = ch.link_radius[k];
        double dk[3] = {zlo + 0.1 - r, 0.4 - r, hypot(0.26, fmax(0.0, fmax(1.55 - zhi, zlo - 1.65))) - r};
        int best = 0;
        for (int j = 1; j < 3; j++) {
            best = dk[j] < dk[best] ? j : best;
        }
        assert_int_equal(out.per_link[k].link, k);
        assert_int_equal(out.per_link[k].obstacle, best);
        assert_true(fabs(out.per_link[k].d - dk[best]) < 1e-9);
        gmin = fmin(gmin, dk[best]);
    }
    assert_true(fabs(out.min.d - gmin) < 1e-9);
    /* the tool link (last) is closest to the cup */
    assert_int_equal(out.per_link[ch.dof].obstacle, 2);
    assert_true(out.iterations > 0);
    /* no obstacles: every link at +inf, obstacle -1 */
    assert_int_equal(mca_arm_obstacle_distances(&ch, &kin, NULL, 0, &out), MCA_OK);
    assert_true(isinf(out.min.d) && out.per_link[0].obstacle == -1);
    assert_int_equal(mca_arm_obstacle_distances(&ch, &kin, obs, MCA_MAX_OBSTACLES + 1, &out), MCA_ERANGE);
    kin.dof = 3;
    assert_int_equal(mca_arm_obstacle_distances(&ch, &kin, obs, 3, &out), MCA_EINVAL);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_box_axis_aligned),
        cmocka_unit_test(test_box_rotated),
        cmocka_unit_test(test_cylinder_and_table),
        cmocka_unit_test(test_box_random_vs_brute),
        cmocka_unit_test(test_capsule_capsule_vs_closed),
        cmocka_unit_test(test_bad_input),
        cmocka_unit_test(test_box_penetration_vs_directions),
        cmocka_unit_test(test_capsule_axes_crossing),
        cmocka_unit_test(test_cylinder_random_vs_brute),
        cmocka_unit_test(test_arm_obstacles_pa10),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
