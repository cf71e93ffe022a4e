/* SPDX-License-Identifier: MIT */
/* Capsule against the fixed-body kinds (mca/body.h): hand-derived closed-form cases for every kind and
 * every branch (separated at a face, an edge, a corner, the side, the cap and the rim; penetrating), the
 * identity p - q = d n, the dispatcher, and bad input. The random comparison with FCL is test_body_fcl.py;
 * the no-allocation check is in test_noalloc.c. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include <cmocka.h>

#include "mca/body.h"
#include "mca/err.h"

#define TOL 1e-14
#define PI 3.14159265358979323846

/* cmocka's assert_float_equal compares in single precision: this one compares doubles */
#define assert_near(got, want, tol) near_((got), (want), (tol), #got, __FILE__, __LINE__)
static void near_(double got, double want, double tol, const char *what, const char *file, int line) {
    if (!(fabs(got - want) <= tol)) {
        fail_msg("%s:%d: %s = %.17g, want %.17g within %g", file, line, what, got, want, tol);
    }
}

static void near3(const double got[3], double x, double y, double z) {
    assert_near(got[0], x, TOL);
    assert_near(got[1], y, TOL);
    assert_near(got[2], z, TOL);
}

/* p - q = d n, |n| = 1, p = p_axis - r n: true of every result */
static void identity(const mca_body_dist_t *r, double radius) {
    assert_near(r->n[0] * r->n[0] + r->n[1] * r->n[1] + r->n[2] * r->n[2], 1.0, 1e-15);
    for (int i = 0; i < 3; i++) {
        assert_near(r->p[i] - r->q[i], r->d * r->n[i], 1e-14);
        assert_near(r->p[i], r->p_axis[i] - radius * r->n[i], 1e-15);
    }
}

static mca_capsule_t capsule(double ax, double ay, double az, double bx, double by, double bz, double r) {
    mca_capsule_t c = {{ax, ay, az}, {bx, by, bz}, r};
    return c;
}

static void test_plane(void **state) {
    (void)state;
    mca_body_plane_t pl = {{0, 0, 0}, {0, 0, 2}}; /* normal of any length */
    mca_body_dist_t r;
    mca_capsule_t c = capsule(0, 0, 1, 1, 0, 2, 0.1);
    assert_int_equal(mca_capsule_plane_distance(&c, &pl, &r), MCA_OK);
    assert_near(r.d, 0.9, TOL);
    near3(r.p_axis, 0, 0, 1);
    near3(r.p, 0, 0, 0.9);
    near3(r.q, 0, 0, 0);
    near3(r.n, 0, 0, 1);
    assert_int_equal(r.exact, 1);
    identity(&r, 0.1);
    /* parallel: the midpoint */
    c = capsule(-1, 2, 0.5, 3, 2, 0.5, 0.2);
    assert_int_equal(mca_capsule_plane_distance(&c, &pl, &r), MCA_OK);
    assert_near(r.d, 0.3, TOL);
    near3(r.p_axis, 1, 2, 0.5);
    /* tilted plane through (1, 1, 1), normal (1, 1, 0)/sqrt2; B is lower */
    mca_body_plane_t tl = {{1, 1, 1}, {1, 1, 0}};
    c = capsule(5, 5, 0, 3, 2, 7, 0.25);
    assert_int_equal(mca_capsule_plane_distance(&c, &tl, &r), MCA_OK);
    assert_near(r.d, 3.0 / sqrt(2.0) - 0.25, TOL);
    near3(r.p_axis, 3, 2, 7);
    near3(r.q, 1.5, 0.5, 7);
    identity(&r, 0.25);
    /* penetrating: exact */
    c = capsule(0, 0, -0.3, 1, 0, 0.5, 0.1);
    assert_int_equal(mca_capsule_plane_distance(&c, &pl, &r), MCA_OK);
    assert_near(r.d, -0.4, TOL);
    near3(r.q, 0, 0, 0);
    assert_int_equal(r.exact, 1);
    identity(&r, 0.1);
}

static void test_sphere(void **state) {
    (void)state;
    mca_body_sphere_t sp = {{0, 0, 0}, 0.5};
    mca_body_dist_t r;
    mca_capsule_t c = capsule(1, -1, 1, 1, 1, 1, 0.1);
    assert_int_equal(mca_capsule_sphere_distance(&c, &sp, &r), MCA_OK);
    assert_near(r.d, sqrt(2.0) - 0.6, TOL);
    near3(r.p_axis, 1, 0, 1);
    near3(r.n, 1 / sqrt(2.0), 0, 1 / sqrt(2.0));
    near3(r.q, 0.5 / sqrt(2.0), 0, 0.5 / sqrt(2.0));
    identity(&r, 0.1);
    /* end point nearest */
    c = capsule(0, 0, 2, 0, 0, 3, 0.1);
    assert_int_equal(mca_capsule_sphere_distance(&c, &sp, &r), MCA_OK);
    assert_near(r.d, 1.4, TOL);
    near3(r.q, 0, 0, 0.5);
    /* penetrating, axis off the centre: exact */
    c = capsule(-1, 0.3, 0, 1, 0.3, 0, 0.1);
    assert_int_equal(mca_capsule_sphere_distance(&c, &sp, &r), MCA_OK);
    assert_near(r.d, 0.3 - 0.6, TOL);
    near3(r.n, 0, 1, 0);
    identity(&r, 0.1);
    /* axis through the centre: depth r + R, normal to the axis */
    c = capsule(-1, 0, 0, 1, 0, 0, 0.1);
    assert_int_equal(mca_capsule_sphere_distance(&c, &sp, &r), MCA_OK);
    assert_near(r.d, -0.6, TOL);
    assert_near(r.n[0], 0.0, TOL);
    assert_int_equal(r.exact, 1);
    identity(&r, 0.1);
}

static void test_capsule(void **state) {
    (void)state;
    mca_capsule_t o = capsule(0.5, -1, 1, 0.5, 1, 1, 0.2);
    mca_body_dist_t r;
    mca_capsule_t c = capsule(0, 0, 0, 1, 0, 0, 0.1);
    assert_int_equal(mca_capsule_capsule_distance(&c, &o, &r), MCA_OK);
    assert_near(r.d, 0.7, TOL);
    near3(r.p_axis, 0.5, 0, 0);
    near3(r.p, 0.5, 0, 0.1);
    near3(r.q, 0.5, 0, 0.8);
    near3(r.n, 0, 0, -1);
    identity(&r, 0.1);
    /* crossing axes: depth r1 + r2 along u x v */
    o = capsule(0.5, -1, 0, 0.5, 1, 0, 0.2);
    assert_int_equal(mca_capsule_capsule_distance(&c, &o, &r), MCA_OK);
    assert_near(r.d, -0.3, TOL);
    near3(r.n, 0, 0, 1);
    assert_int_equal(r.exact, 1);
    identity(&r, 0.1);
    /* collinear overlap: any normal of the axis */
    o = capsule(0.5, 0, 0, 2, 0, 0, 0.2);
    assert_int_equal(mca_capsule_capsule_distance(&c, &o, &r), MCA_OK);
    assert_near(r.d, -0.3, TOL);
    assert_near(r.n[0], 0.0, TOL);
    identity(&r, 0.1);
}

static const mca_body_box_t unit_box = {{0, 0, 0}, {1, 1, 1}, {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}}};

static void test_box_axis_aligned(void **state) {
    (void)state;
    mca_body_box_t b = unit_box;
    mca_body_dist_t r;
    b.half[1] = 2;
    b.half[2] = 3;
    /* face: end point A nearest */
    mca_capsule_t c = capsule(2, 0, 0, 3, 0, 1, 0.1);
    assert_int_equal(mca_capsule_box_distance(&c, &b, &r), MCA_OK);
    assert_near(r.d, 0.9, TOL);
    near3(r.q, 1, 0, 0);
    near3(r.n, 1, 0, 0);
    identity(&r, 0.1);
    /* corner: the segment passes over the corner (1, 1, 1) at height 1 */
    b = unit_box;
    c = capsule(2, 0, 2, 0, 2, 2, 0.05);
    assert_int_equal(mca_capsule_box_distance(&c, &b, &r), MCA_OK);
    assert_near(r.d, 0.95, TOL);
    near3(r.p_axis, 1, 1, 2);
    near3(r.q, 1, 1, 1);
    near3(r.n, 0, 0, 1);
    /* edge region, interior minimum: x = 2 + s, y = -1 + 2s, z = 3 - 2s; (1+s)^2 + (2-2s)^2 is least at
     * s = 0.6: (2.6, 0.2, 1.8) against the edge point (1, 0.2, 1), distance sqrt(3.2) */
    c = capsule(2, -1, 3, 3, 1, 1, 0.1);
    assert_int_equal(mca_capsule_box_distance(&c, &b, &r), MCA_OK);
    assert_near(r.d, sqrt(3.2) - 0.1, TOL);
    near3(r.p_axis, 2.6, 0.2, 1.8);
    near3(r.q, 1, 0.2, 1);
    near3(r.n, 1.6 / sqrt(3.2), 0, 0.8 / sqrt(3.2));
    identity(&r, 0.1);
    /* the axis crosses the box: SAT depth, exact. Along x through the middle at y = 0.7, z = 0.2: the
     * least push is 0.3 along +y */
    c = capsule(-3, 0.7, 0.2, 3, 0.7, 0.2, 0.1);
    assert_int_equal(mca_capsule_box_distance(&c, &b, &r), MCA_OK);
    assert_near(r.d, -0.4, TOL);
    near3(r.n, 0, 1, 0);
    assert_int_equal(r.exact, 1);
    identity(&r, 0.1);
    /* wholly inside, near the -z face (end points at z = -0.8 and -0.6): the least push is 0.4 along -z */
    c = capsule(0.1, 0.1, -0.8, -0.1, 0, -0.6, 0.05);
    assert_int_equal(mca_capsule_box_distance(&c, &b, &r), MCA_OK);
    assert_near(r.d, -0.45, TOL);
    near3(r.n, 0, 0, -1);
    near3(r.p_axis, -0.1, 0, -0.6);
    near3(r.q, -0.1, 0, -1);
    identity(&r, 0.05);
    /* the axis grazes the top face (r = 0): distance 0 */
    c = capsule(-2, 0, 1, 2, 0, 1, 0.0);
    assert_int_equal(mca_capsule_box_distance(&c, &b, &r), MCA_OK);
    assert_near(r.d, 0.0, TOL);
}

static void test_box_rotated(void **state) {
    (void)state;
    /* the edge-region case above, rotated by Rz(30 deg) and moved to (1, 2, 3) */
    const double cz = cos(PI / 6), sz = sin(PI / 6), t[3] = {1, 2, 3};
    mca_body_box_t b = {{1, 2, 3}, {1, 1, 1}, {{cz, -sz, 0}, {sz, cz, 0}, {0, 0, 1}}};
    double loc[4][3] = {{2, -1, 3}, {3, 1, 1}, {2.6, 0.2, 1.8}, {1, 0.2, 1}}, w[4][3];
    for (int k = 0; k < 4; k++) {
        w[k][0] = cz * loc[k][0] - sz * loc[k][1] + t[0];
        w[k][1] = sz * loc[k][0] + cz * loc[k][1] + t[1];
        w[k][2] = loc[k][2] + t[2];
    }
    mca_capsule_t c = capsule(w[0][0], w[0][1], w[0][2], w[1][0], w[1][1], w[1][2], 0.1);
    mca_body_dist_t r;
    assert_int_equal(mca_capsule_box_distance(&c, &b, &r), MCA_OK);
    assert_near(r.d, sqrt(3.2) - 0.1, TOL);
    near3(r.p_axis, w[2][0], w[2][1], w[2][2]);
    near3(r.q, w[3][0], w[3][1], w[3][2]);
    identity(&r, 0.1);
}

static void test_cylinder(void **state) {
    (void)state;
    mca_body_cylinder_t cy = {{0, 0, 0}, {0, 0, 3}, 1.0, 0.5}; /* axis of any length */
    mca_body_dist_t r;
    /* side, interior minimum of the segment */
    mca_capsule_t c = capsule(2, -1, 0, 2, 1, 0, 0.1);
    assert_int_equal(mca_capsule_cylinder_distance(&c, &cy, &r), MCA_OK);
    assert_near(r.d, 1.4, TOL);
    near3(r.p_axis, 2, 0, 0);
    near3(r.q, 0.5, 0, 0);
    near3(r.n, 1, 0, 0);
    assert_int_equal(r.exact, 1);
    identity(&r, 0.1);
    /* cap */
    c = capsule(0.1, 0, 2, 0.3, 0, 3, 0.1);
    assert_int_equal(mca_capsule_cylinder_distance(&c, &cy, &r), MCA_OK);
    assert_near(r.d, 0.9, TOL);
    near3(r.q, 0.1, 0, 1);
    near3(r.n, 0, 0, 1);
    /* rim, interior minimum: (1, 0, 2) against the rim point (0.5, 0, 1) */
    c = capsule(1, -1, 2, 1, 1, 2, 0.1);
    assert_int_equal(mca_capsule_cylinder_distance(&c, &cy, &r), MCA_OK);
    assert_near(r.d, sqrt(1.25) - 0.1, TOL);
    near3(r.p_axis, 1, 0, 2);
    near3(r.q, 0.5, 0, 1);
    near3(r.n, 0.5 / sqrt(1.25), 0, 1 / sqrt(1.25));
    identity(&r, 0.1);
    /* the same rim case about a cylinder lying along y at (1, 1, 1): (x, y, z) -> (x, z, -y) */
    mca_body_cylinder_t cy2 = {{1, 1, 1}, {0, 1, 0}, 1.0, 0.5};
    c = capsule(2, 3, 2, 2, 3, 0, 0.1);
    assert_int_equal(mca_capsule_cylinder_distance(&c, &cy2, &r), MCA_OK);
    assert_near(r.d, sqrt(1.25) - 0.1, TOL);
    near3(r.p_axis, 2, 3, 1);
    near3(r.q, 1.5, 2, 1);
    identity(&r, 0.1);
    /* the capsule overlaps but its axis stays outside: exact */
    c = capsule(0.55, -1, 0, 0.55, 1, 0, 0.1);
    assert_int_equal(mca_capsule_cylinder_distance(&c, &cy, &r), MCA_OK);
    assert_near(r.d, -0.05, TOL);
    assert_int_equal(r.exact, 1);
    /* the axis inside, along the cylinder's axis: radial escape 0.5 (cap escapes 1.2), flagged a bound */
    c = capsule(0, 0, -0.2, 0, 0, 0.2, 0.1);
    assert_int_equal(mca_capsule_cylinder_distance(&c, &cy, &r), MCA_OK);
    assert_near(r.d, -0.6, TOL);
    assert_near(r.n[2], 0.0, TOL);
    assert_int_equal(r.exact, 0);
    identity(&r, 0.1);
    /* the axis inside near the top: the cap escape 0.1 wins */
    c = capsule(-0.1, 0, 0.9, 0.1, 0, 0.95, 0.05);
    assert_int_equal(mca_capsule_cylinder_distance(&c, &cy, &r), MCA_OK);
    assert_near(r.d, -0.15, TOL);
    near3(r.n, 0, 0, 1);
    near3(r.p_axis, -0.1, 0, 0.9);
    identity(&r, 0.05);
}

static void test_dispatch(void **state) {
    (void)state;
    mca_capsule_t c = capsule(0.3, 0.2, 1.0, 0.5, -0.4, 1.7, 0.05);
    mca_body_t b[5];
    memset(b, 0, sizeof b);
    b[0].kind = MCA_BODY_PLANE;
    b[0].u.plane = (mca_body_plane_t){{0, 0, 0.2}, {0, 0, 1}};
    b[1].kind = MCA_BODY_SPHERE;
    b[1].u.sphere = (mca_body_sphere_t){{0, 0, 0}, 0.2};
    b[2].kind = MCA_BODY_CAPSULE;
    b[2].u.capsule = capsule(1, 0, 0, 1, 1, 0.2, 0.1);
    b[3].kind = MCA_BODY_BOX;
    b[3].u.box = unit_box;
    b[4].kind = MCA_BODY_CYLINDER;
    b[4].u.cylinder = (mca_body_cylinder_t){{0, 0, 0}, {0, 0, 1}, 0.5, 0.5};
    for (int k = 0; k < 5; k++) {
        mca_body_dist_t r1, r2;
        int rc;
        assert_int_equal(mca_capsule_body_distance(&c, &b[k], &r1), MCA_OK);
        switch (k) {
        case 0:
            rc = mca_capsule_plane_distance(&c, &b[k].u.plane, &r2);
            break;
        case 1:
            rc = mca_capsule_sphere_distance(&c, &b[k].u.sphere, &r2);
            break;
        case 2:
            rc = mca_capsule_capsule_distance(&c, &b[k].u.capsule, &r2);
            break;
        case 3:
            rc = mca_capsule_box_distance(&c, &b[k].u.box, &r2);
            break;
        default:
            rc = mca_capsule_cylinder_distance(&c, &b[k].u.cylinder, &r2);
            break;
        }
        assert_int_equal(rc, MCA_OK);
        assert_memory_equal(&r1, &r2, offsetof(mca_body_dist_t, exact)); /* all the doubles */
        assert_int_equal(r1.exact, r2.exact);
        identity(&r1, c.radius);
    }
    /* known answers: plane 0.75, cylinder 0.45, box -r (A lies on the top face z = 1: the axis touches) */
    mca_body_dist_t r;
    assert_int_equal(mca_capsule_body_distance(&c, &b[0], &r), MCA_OK);
    assert_near(r.d, 0.75, TOL);
    assert_int_equal(mca_capsule_body_distance(&c, &b[4], &r), MCA_OK);
    assert_near(r.d, 0.45, TOL);
    assert_int_equal(mca_capsule_body_distance(&c, &b[3], &r), MCA_OK);
    assert_near(r.d, -0.05, TOL);
}

static void test_bad_input(void **state) {
    (void)state;
    mca_capsule_t c = capsule(0, 0, 0, 1, 0, 0, 0.1), bad = c;
    mca_body_dist_t r, before;
    memset(&r, 0x5a, sizeof r);
    before = r;
    mca_body_t b;
    memset(&b, 0, sizeof b);
    b.kind = MCA_BODY_BOX;
    b.u.box = unit_box;
    assert_int_equal(mca_capsule_body_distance(NULL, &b, &r), MCA_EINVAL);
    assert_int_equal(mca_capsule_body_distance(&c, NULL, &r), MCA_EINVAL);
    assert_int_equal(mca_capsule_body_distance(&c, &b, NULL), MCA_EINVAL);
    bad.radius = -0.1;
    assert_int_equal(mca_capsule_body_distance(&bad, &b, &r), MCA_EINVAL);
    bad = c;
    bad.a[1] = NAN;
    assert_int_equal(mca_capsule_body_distance(&bad, &b, &r), MCA_EINVAL);
    bad = c;
    bad.b[2] = INFINITY;
    assert_int_equal(mca_capsule_body_distance(&bad, &b, &r), MCA_EINVAL);
    b.u.box.R[0][1] = 0.1; /* not orthonormal */
    assert_int_equal(mca_capsule_body_distance(&c, &b, &r), MCA_EINVAL);
    b.u.box = unit_box;
    b.u.box.half[2] = -1;
    assert_int_equal(mca_capsule_body_distance(&c, &b, &r), MCA_EINVAL);
    b.kind = MCA_BODY_PLANE;
    b.u.plane = (mca_body_plane_t){{0, 0, 0}, {0, 0, 0}};
    assert_int_equal(mca_capsule_body_distance(&c, &b, &r), MCA_EINVAL);
    b.kind = MCA_BODY_CYLINDER;
    b.u.cylinder = (mca_body_cylinder_t){{0, 0, 0}, {0, 0, 0}, 1, 1};
    assert_int_equal(mca_capsule_body_distance(&c, &b, &r), MCA_EINVAL);
    b.u.cylinder.axis[2] = 1;
    b.u.cylinder.radius = NAN;
    assert_int_equal(mca_capsule_body_distance(&c, &b, &r), MCA_EINVAL);
    b.kind = MCA_BODY_SPHERE;
    b.u.sphere = (mca_body_sphere_t){{0, 0, 0}, -1};
    assert_int_equal(mca_capsule_body_distance(&c, &b, &r), MCA_EINVAL);
    b.kind = (mca_body_kind_t)7;
    assert_int_equal(mca_capsule_body_distance(&c, &b, &r), MCA_EINVAL);
    assert_memory_equal(&r, &before, sizeof r); /* untouched on error */
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_plane),       cmocka_unit_test(test_sphere),
        cmocka_unit_test(test_capsule),     cmocka_unit_test(test_box_axis_aligned),
        cmocka_unit_test(test_box_rotated), cmocka_unit_test(test_cylinder),
        cmocka_unit_test(test_dispatch),    cmocka_unit_test(test_bad_input),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
