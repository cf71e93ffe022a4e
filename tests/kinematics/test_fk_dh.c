/* SPDX-License-Identifier: MIT */
/* FK of config/robots/{jaco2,mico2}.urdf against Kinova's classic DH chain, computed here
 * independently with 4x4 matrices (T_i = Rz(theta_i) Tz(d_i) Tx(a_i) Rx(alpha_i)).
 *
 * Point correspondence: URDF joint i (1-based) sits at DH frame i-1 (frame 0 = base), so
 * kin.point[i] = origin of DH frame i-1 for i = 1..6, kin.point[0] = base origin and
 * kin.point[7] (tool tip) = origin of DH frame 6. The joint axis i is sign_i * z of DH frame i-1. */
#include "kin_test_util.h"

#include <math.h>
#include <string.h>

#define N_CONFIGS 1000
#define TOL_POS 1e-9
#define TOL_ROT 1e-9

typedef struct {
    double D1, D2, D3, D4, D5, D6, e2;
} kinova_geom_t;

/* Kinova's published numbers (JACO2 j2n6s300, MICO2 m1n6s300 DH documents). */
static const kinova_geom_t JACO2 = {0.2755, 0.4100, 0.2073, 0.0741, 0.0741, 0.1600, 0.0098};
static const kinova_geom_t MICO2 = {0.2755, 0.2900, 0.1233, 0.0741, 0.0741, 0.1600, 0.0070};

static void m4_identity(double T[4][4]) {
    memset(T, 0, sizeof(double) * 16);
    for (int i = 0; i < 4; i++) {
        T[i][i] = 1.0;
    }
}

static void m4_mul(double out[4][4], const double A[4][4], const double B[4][4]) {
    double r[4][4];
    for (int i = 0; i < 4; i++) {
        for (int j = 0; j < 4; j++) {
            r[i][j] = 0.0;
            for (int k = 0; k < 4; k++) {
                r[i][j] += A[i][k] * B[k][j];
            }
        }
    }
    memcpy(out, r, sizeof(r));
}

/* Classic DH: Rz(theta) Tz(d) Tx(a) Rx(alpha) */
static void dh(double T[4][4], double theta, double d, double a, double alpha) {
    const double ct = cos(theta), st = sin(theta), ca = cos(alpha), sa = sin(alpha);
    const double M[4][4] = {
        {ct, -st * ca, st * sa, a * ct},
        {st, ct * ca, -ct * sa, a * st},
        {0.0, sa, ca, d},
        {0.0, 0.0, 0.0, 1.0},
    };
    memcpy(T, M, sizeof(M));
}

/* frames[i] = base <- DH frame i, i = 0..6 */
static void kinova_dh_fk(const kinova_geom_t *g, const double q[6], double frames[7][4][4]) {
    const double aa = 30.0 * KIN_DEG;
    const double k = sin(aa) / sin(2.0 * aa);
    const double d4b = g->D3 + k * g->D4;
    const double d5b = k * (g->D4 + g->D5);
    const double d6b = k * g->D5 + g->D6;
    const double alpha[6] = {KIN_PI / 2, KIN_PI, KIN_PI / 2, 2 * aa, 2 * aa, KIN_PI};
    const double a[6] = {0.0, g->D2, 0.0, 0.0, 0.0, 0.0};
    const double d[6] = {g->D1, 0.0, -g->e2, -d4b, -d5b, -d6b};
    /* Kinova angle q -> DH theta */
    const double theta[6] = {-q[0], q[1] - KIN_PI / 2, q[2] + KIN_PI / 2,
                             q[3],  q[4] - KIN_PI,     q[5] + KIN_PI / 2};
    m4_identity(frames[0]);
    for (int i = 0; i < 6; i++) {
        double T[4][4];
        dh(T, theta[i], d[i], a[i], alpha[i]);
        m4_mul(frames[i + 1], frames[i], T);
    }
}

static void check_robot(const char *file, const kinova_geom_t *g, uint64_t seed) {
    mca_chain_t c;
    kin_load_robot(&c, file);
    assert_int_equal(c.dof, 6);
    const double sign[6] = {-1, 1, 1, 1, 1, 1};
    double worst_pos = 0.0, worst_rot = 0.0;
    for (int n = 0; n < N_CONFIGS; n++) {
        double q[6];
        for (int i = 0; i < 6; i++) {
            q[i] = kin_rand(&seed, -2.0 * KIN_PI, 2.0 * KIN_PI);
        }
        mca_kin_t kin;
        assert_int_equal(mca_fk(&c, q, &kin), MCA_OK);
        assert_int_equal(kin.n_points, 8);
        double F[7][4][4];
        kinova_dh_fk(g, q, F);
        for (int p = 0; p < 3; p++) {
            worst_pos = kin_worst(worst_pos, fabs(kin.point[0][p]));
        }
        for (int i = 1; i <= 7; i++) {
            for (int p = 0; p < 3; p++) {
                worst_pos = kin_worst(worst_pos, fabs(kin.point[i][p] - F[i - 1][p][3]));
            }
        }
        for (int p = 0; p < 3; p++) {
            worst_pos = kin_worst(worst_pos, fabs(kin.ee[p] - F[6][p][3]));
        }
        for (int i = 0; i < 6; i++) {
            for (int p = 0; p < 3; p++) {
                worst_rot = kin_worst(worst_rot, fabs(kin.axis[i][p] - sign[i] * F[i][p][2]));
            }
        }
        /* full tool orientation: world <- tool tip equals DH frame 6 */
        mca_pose_t tool;
        mca_pose_mul(&tool, &kin.frame[5], &c.tool);
        for (int r = 0; r < 3; r++) {
            for (int s = 0; s < 3; s++) {
                worst_rot = kin_worst(worst_rot, fabs(tool.R[r][s] - F[6][r][s]));
            }
        }
    }
    print_message("%s: %d configs, max |FK - DH| = %.3g m, max axis/orientation error = %.3g\n", file,
                  N_CONFIGS, worst_pos, worst_rot);
    /* written so that a NaN anywhere fails (kin_worst keeps it, and NaN <= tol is false) */
    assert_true(worst_pos <= TOL_POS);
    assert_true(worst_rot <= TOL_ROT);
}

static void test_jaco2_matches_dh(void **state) {
    (void)state;
    check_robot("jaco2.urdf", &JACO2, 12345);
}

static void test_mico2_matches_dh(void **state) {
    (void)state;
    check_robot("mico2.urdf", &MICO2, 6789);
}

/* The DH reference itself against hand-worked geometry, so that it cannot silently share an
 * error with the URDF: at Kinova's q = (0, 180, 180, 0, 0, 0) deg (theta2 = pi/2, theta3 = 3pi/2,
 * the "candle" posture) the shoulder is at (0, 0, D1), the elbow straight above it at D1 + D2,
 * frame 3 is offset sideways by e2 only, and the forearm (d4b ~ 0.25 m) continues upward. */
static void test_dh_reference_sanity(void **state) {
    (void)state;
    const double q[6] = {0.0, KIN_PI, KIN_PI, 0.0, 0.0, 0.0};
    double F[7][4][4];
    kinova_dh_fk(&JACO2, q, F);
    /* shoulder at D1 on the z axis */
    assert_true(fabs(F[1][0][3]) < 1e-12 && fabs(F[1][1][3]) < 1e-12);
    assert_true(fabs(F[1][2][3] - JACO2.D1) < 1e-12);
    /* elbow straight above the shoulder at D1 + D2 */
    assert_true(fabs(F[2][0][3]) < 1e-12 && fabs(F[2][1][3]) < 1e-12);
    assert_true(fabs(F[2][2][3] - (JACO2.D1 + JACO2.D2)) < 1e-12);
    /* the forearm continues upward: frame 3 origin only offset by e2 sideways */
    const double off = hypot(F[3][0][3], F[3][1][3]);
    assert_true(fabs(off - JACO2.e2) < 1e-12);
    assert_true(F[4][2][3] > F[2][2][3] + 0.2);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_dh_reference_sanity),
        cmocka_unit_test(test_jaco2_matches_dh),
        cmocka_unit_test(test_mico2_matches_dh),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
