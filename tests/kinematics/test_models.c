/* SPDX-License-Identifier: MIT */
/* The three robot models as loaded: joint limits, velocity limits and capsule radii equal the
 * published / documented numbers (docs/robots.md), and the paper's PA10+ start postures are
 * inside the limits with the bent elbow worked out by hand here. */
#include "kin_test_util.h"

#include <math.h>
#include <string.h>

#define EPS 1e-12

static void assert_near(double a, double b, double tol) {
    if (!(fabs(a - b) <= tol)) {
        fail_msg("%.17g != %.17g (tol %g)", a, b, tol);
    }
}

static void check_kinova(const char *file, double lo2, double hi2, double lo3, double hi3) {
    mca_chain_t c;
    kin_load_robot(&c, file);
    assert_int_equal(c.dof, 6);
    const char *names[6] = {"joint_1", "joint_2", "joint_3", "joint_4", "joint_5", "joint_6"};
    for (int i = 0; i < 6; i++) {
        assert_string_equal(c.joint[i].name, names[i]);
        /* KA-75+ actuators (joints 1-3) 36 deg/s, KA-58 (joints 4-6) 48 deg/s */
        assert_near(c.joint[i].vel_limit, (i < 3 ? 36.0 : 48.0) * KIN_DEG, EPS);
        const int limited = (i == 1 || i == 2);
        assert_int_equal(c.joint[i].continuous, !limited);
        if (!limited) {
            assert_true(isinf(c.joint[i].lower) && isinf(c.joint[i].upper));
        }
    }
    assert_near(c.joint[1].lower, lo2 * KIN_DEG, EPS);
    assert_near(c.joint[1].upper, hi2 * KIN_DEG, EPS);
    assert_near(c.joint[2].lower, lo3 * KIN_DEG, EPS);
    assert_near(c.joint[2].upper, hi3 * KIN_DEG, EPS);
    /* joint 1 turns about -z (theta1 = -q1), the others about +z of their frame */
    assert_near(c.joint[0].axis[2], -1.0, EPS);
    for (int i = 1; i < 6; i++) {
        assert_near(c.joint[i].axis[2], 1.0, EPS);
    }
    const double radii[7] = {0.05, 0.05, 0.045, 0.045, 0.04, 0.04, 0.045};
    for (int l = 0; l < 7; l++) {
        assert_near(c.link_radius[l], radii[l], EPS);
    }
    for (int l = 7; l < MCA_MAX_LINKS; l++) {
        assert_true(c.link_radius[l] == 0.0);
    }
    /* base pose is the identity after loading */
    for (int i = 0; i < 3; i++) {
        assert_true(c.base.p[i] == 0.0);
        for (int j = 0; j < 3; j++) {
            assert_true(c.base.R[i][j] == (i == j ? 1.0 : 0.0));
        }
    }
}

static void test_jaco2_limits(void **state) {
    (void)state;
    check_kinova("jaco2.urdf", 47, 313, 19, 341);
    mca_chain_t c;
    kin_load_robot(&c, "jaco2.urdf");
    assert_string_equal(c.name, "jaco2");
    assert_non_null(strstr(c.source, "config/robots/jaco2.urdf"));
}

static void test_mico2_limits(void **state) {
    (void)state;
    check_kinova("mico2.urdf", 50, 310, 35, 325);
}

static const double PA10_LIM_DEG[8] = {177, 94, 174, 137, 255, 165, 255, 90};

static void test_pa10plus_limits(void **state) {
    (void)state;
    mca_chain_t c;
    kin_load_robot(&c, "pa10plus.urdf");
    assert_int_equal(c.dof, 8);
    const char *names[8] = {"S1", "S2", "S3", "E1", "E2", "W1", "W2", "T"};
    const double vel_deg[8] = {57, 57, 57, 57, 114, 114, 114, 114};
    const double radii[9] = {0.08, 0.08, 0.07, 0.07, 0.06, 0.06, 0.06, 0.05, 0.02};
    for (int i = 0; i < 8; i++) {
        assert_string_equal(c.joint[i].name, names[i]);
        assert_int_equal(c.joint[i].continuous, 0);
        assert_near(c.joint[i].lower, -PA10_LIM_DEG[i] * KIN_DEG, EPS);
        assert_near(c.joint[i].upper, PA10_LIM_DEG[i] * KIN_DEG, EPS);
        assert_near(c.joint[i].vel_limit, vel_deg[i] * KIN_DEG, EPS);
    }
    for (int l = 0; l < 9; l++) {
        assert_near(c.link_radius[l], radii[l], EPS);
    }
    /* 0.25 m tool along the flange axis */
    assert_near(c.tool.p[2], 0.25, EPS);
    assert_near(hypot(c.tool.p[0], c.tool.p[1]), 0.0, EPS);
}

static void in_limits(const mca_chain_t *c, const double *q) {
    for (int i = 0; i < c->dof; i++) {
        if (!(q[i] >= c->joint[i].lower && q[i] <= c->joint[i].upper)) {
            fail_msg("joint %s: %g outside [%g, %g]", c->joint[i].name, q[i], c->joint[i].lower,
                     c->joint[i].upper);
        }
    }
}

/* Paper, Sec. VI task 1: theta_L0 = [0, pi/4, 0, -pi/2, 0, pi/4, 0, pi/4]. With the zero posture
 * straight up and all pitch axes along +y, Ry(a) z = (sin a, 0, cos a): the upper arm leans +45 deg
 * to +x, the forearm -45 deg (elbow bent 90 deg), the flange is vertical again and the tool leans
 * +45 deg. */
static void test_pa10plus_paper_start_left(void **state) {
    (void)state;
    mca_chain_t c;
    kin_load_robot(&c, "pa10plus.urdf");
    const double q[8] = {0, KIN_PI / 4, 0, -KIN_PI / 2, 0, KIN_PI / 4, 0, KIN_PI / 4};
    in_limits(&c, q);
    mca_kin_t k;
    assert_int_equal(mca_fk(&c, q, &k), MCA_OK);
    const double s = sqrt(0.5);
    const double shoulder[3] = {0, 0, 0.317};
    const double elbow[3] = {0.45 * s, 0, 0.317 + 0.45 * s};
    const double wrist[3] = {elbow[0] - 0.48 * s, 0, elbow[2] + 0.48 * s};
    const double flange[3] = {wrist[0], 0, wrist[2] + 0.07};
    const double tip[3] = {flange[0] + 0.25 * s, 0, flange[2] + 0.25 * s};
    for (int i = 0; i < 3; i++) {
        assert_near(k.point[2][i], shoulder[i], EPS); /* S2 */
        assert_near(k.point[4][i], elbow[i], EPS);    /* E1 */
        assert_near(k.point[6][i], wrist[i], EPS);    /* W1 */
        assert_near(k.point[7][i], flange[i], EPS);   /* W2 at the flange */
        assert_near(k.point[8][i], flange[i], EPS);   /* tool joint at the flange */
        assert_near(k.ee[i], tip[i], EPS);
    }
    /* the elbow angle between upper arm and forearm is 90 deg */
    double u[3], f[3];
    for (int i = 0; i < 3; i++) {
        u[i] = k.point[4][i] - k.point[2][i];
        f[i] = k.point[6][i] - k.point[4][i];
    }
    assert_near(u[0] * f[0] + u[1] * f[1] + u[2] * f[2], 0.0, EPS);
    print_message("PA10+ theta_L0: elbow (%.4f %.4f %.4f), wrist (%.4f %.4f %.4f), tip (%.4f %.4f %.4f)\n",
                  k.point[4][0], k.point[4][1], k.point[4][2], k.point[6][0], k.point[6][1], k.point[6][2],
                  k.ee[0], k.ee[1], k.ee[2]);
}

/* theta_R0 = [-pi/2, -pi/4, 0, pi/2, 0, -pi/4, 0, -pi/4]: the mirror image of theta_L0 turned by
 * S1 = -90 deg about z, i.e. every point (x, 0, z) of the left posture maps to (0, x, z). */
static void test_pa10plus_paper_start_right(void **state) {
    (void)state;
    mca_chain_t c;
    kin_load_robot(&c, "pa10plus.urdf");
    const double qL[8] = {0, KIN_PI / 4, 0, -KIN_PI / 2, 0, KIN_PI / 4, 0, KIN_PI / 4};
    const double qR[8] = {-KIN_PI / 2, -KIN_PI / 4, 0, KIN_PI / 2, 0, -KIN_PI / 4, 0, -KIN_PI / 4};
    in_limits(&c, qR);
    mca_kin_t kl, kr;
    assert_int_equal(mca_fk(&c, qL, &kl), MCA_OK);
    assert_int_equal(mca_fk(&c, qR, &kr), MCA_OK);
    for (int p = 0; p < kl.n_points; p++) {
        /* mirror x -> -x, then Rz(-90 deg): (x, y, z) -> (y, x, z) for y = 0 gives (0, x, z) */
        assert_near(kr.point[p][0], 0.0, EPS);
        assert_near(kr.point[p][1], kl.point[p][0], EPS);
        assert_near(kr.point[p][2], kl.point[p][2], EPS);
    }
}

/* q = 0 is the straight-up posture of the PA10+: all points on the z axis at the published
 * cumulative lengths. */
static void test_pa10plus_zero(void **state) {
    (void)state;
    mca_chain_t c;
    kin_load_robot(&c, "pa10plus.urdf");
    const double q[8] = {0};
    mca_kin_t k;
    assert_int_equal(mca_fk(&c, q, &k), MCA_OK);
    const double z[10] = {0, 0, 0.317, 0.317 + 0.225, 0.767, 0.767 + 0.24, 1.247, 1.317, 1.317, 1.567};
    for (int p = 0; p < 10; p++) {
        assert_near(k.point[p][0], 0.0, EPS);
        assert_near(k.point[p][1], 0.0, EPS);
        assert_near(k.point[p][2], z[p], EPS);
    }
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_jaco2_limits),
        cmocka_unit_test(test_mico2_limits),
        cmocka_unit_test(test_pa10plus_limits),
        cmocka_unit_test(test_pa10plus_paper_start_left),
        cmocka_unit_test(test_pa10plus_paper_start_right),
        cmocka_unit_test(test_pa10plus_zero),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
