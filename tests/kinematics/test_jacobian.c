/* SPDX-License-Identifier: MIT */
/* mca_jacobian_point / mca_jacobian_ee against central finite differences of FK, for every link
 * of all three robots, random configurations and random points rigidly attached to the link,
 * with a non-identity base pose. Also: the base pose, the pose helpers and bad arguments. */
#include "kin_test_util.h"

#include <math.h>
#include <string.h>

#define N_CONFIGS 1000
#define N_POINTS 3
#define FD_STEP 1e-6
#define TOL_J 1e-6

/* world <- frame that carries link `link`: the base for link 0, else joint link-1's frame */
static const mca_pose_t *link_frame(const mca_chain_t *c, const mca_kin_t *k, int link) {
    return link == 0 ? &c->base : &k->frame[link - 1];
}

/* local = pose^-1 x (R orthonormal) */
static void pose_inv_apply(double out[3], const mca_pose_t *pose, const double x[3]) {
    double d[3] = {x[0] - pose->p[0], x[1] - pose->p[1], x[2] - pose->p[2]};
    for (int i = 0; i < 3; i++) {
        out[i] = pose->R[0][i] * d[0] + pose->R[1][i] * d[1] + pose->R[2][i] * d[2];
    }
}

static double check_robot(const char *file, uint64_t seed) {
    mca_chain_t c;
    kin_load_robot(&c, file);
    const double base_xyz[3] = {0.4, -0.7, 0.25};
    const double base_rpy[3] = {0.3, -0.5, 2.1};
    mca_chain_set_base(&c, base_xyz, base_rpy);
    const int n = c.dof;
    double worst = 0.0;
    for (int cfg = 0; cfg < N_CONFIGS; cfg++) {
        double q[MCA_MAX_DOF];
        for (int i = 0; i < n; i++) {
            q[i] = kin_rand(&seed, -KIN_PI, KIN_PI);
        }
        mca_kin_t kin;
        assert_int_equal(mca_fk(&c, q, &kin), MCA_OK);
        for (int link = 0; link <= n; link++) {
            for (int s = 0; s < N_POINTS; s++) {
                /* a point on the segment plus an offset, rigidly attached to the link */
                const double t = kin_rand(&seed, 0.0, 1.0);
                double x[3], local[3];
                for (int p = 0; p < 3; p++) {
                    x[p] = kin.point[link][p] + t * (kin.point[link + 1][p] - kin.point[link][p]) +
                           kin_rand(&seed, -0.1, 0.1);
                }
                pose_inv_apply(local, link_frame(&c, &kin, link), x);
                double J[3][MCA_MAX_DOF];
                assert_int_equal(mca_jacobian_point(&kin, link, x, J), MCA_OK);
                for (int j = 0; j < MCA_MAX_DOF; j++) {
                    double fd[3] = {0.0, 0.0, 0.0};
                    if (j < n) {
                        double qp[MCA_MAX_DOF], qm[MCA_MAX_DOF], xp[3], xm[3];
                        memcpy(qp, q, sizeof(qp));
                        memcpy(qm, q, sizeof(qm));
                        qp[j] += FD_STEP;
                        qm[j] -= FD_STEP;
                        mca_kin_t kp, km;
                        assert_int_equal(mca_fk(&c, qp, &kp), MCA_OK);
                        assert_int_equal(mca_fk(&c, qm, &km), MCA_OK);
                        mca_pose_apply(xp, link_frame(&c, &kp, link), local);
                        mca_pose_apply(xm, link_frame(&c, &km, link), local);
                        for (int p = 0; p < 3; p++) {
                            fd[p] = (xp[p] - xm[p]) / (2.0 * FD_STEP);
                        }
                    }
                    for (int p = 0; p < 3; p++) {
                        const double e = fabs(J[p][j] - fd[p]);
                        worst = kin_worst(worst, e);
                        if (!(e <= TOL_J)) { /* NaN fails too */
                            fail_msg("%s cfg %d link %d col %d row %d: J %.9g vs FD %.9g", file, cfg, link, j,
                                     p, J[p][j], fd[p]);
                        }
                    }
                }
            }
        }
        /* end-effector Jacobian = point Jacobian of the tool tip on the last link, and = FD */
        double Je[3][MCA_MAX_DOF], Jp[3][MCA_MAX_DOF];
        assert_int_equal(mca_jacobian_ee(&kin, Je), MCA_OK);
        assert_int_equal(mca_jacobian_point(&kin, n, kin.ee, Jp), MCA_OK);
        assert_memory_equal(Je, Jp, sizeof(Je));
        for (int j = 0; j < n; j++) {
            double qp[MCA_MAX_DOF], qm[MCA_MAX_DOF];
            memcpy(qp, q, sizeof(qp));
            memcpy(qm, q, sizeof(qm));
            qp[j] += FD_STEP;
            qm[j] -= FD_STEP;
            mca_kin_t kp, km;
            assert_int_equal(mca_fk(&c, qp, &kp), MCA_OK);
            assert_int_equal(mca_fk(&c, qm, &km), MCA_OK);
            for (int p = 0; p < 3; p++) {
                const double fd = (kp.ee[p] - km.ee[p]) / (2.0 * FD_STEP);
                worst = kin_worst(worst, fabs(Je[p][j] - fd));
                assert_true(fabs(Je[p][j] - fd) <= TOL_J); /* NaN fails */
            }
        }
    }
    print_message("%s: max |J - FD| = %.3g over %d configs x %d links x %d points\n", file, worst, N_CONFIGS,
                  n + 1, N_POINTS);
    assert_true(worst <= TOL_J);
    return worst;
}

static void test_jacobian_jaco2(void **state) {
    (void)state;
    check_robot("jaco2.urdf", 1);
}

static void test_jacobian_mico2(void **state) {
    (void)state;
    check_robot("mico2.urdf", 2);
}

static void test_jacobian_pa10plus(void **state) {
    (void)state;
    check_robot("pa10plus.urdf", 3);
}

/* Guards against a vacuous pass (J and FD both zero): the EE Jacobian is not zero and the tool
 * joint column has the tool length as its lever arm. */
static void test_ee_jacobian_nontrivial(void **state) {
    (void)state;
    mca_chain_t c;
    kin_load_robot(&c, "pa10plus.urdf");
    const double q[8] = {0.1, 0.7, -0.3, -1.2, 0.4, 0.9, -0.2, 0.5};
    mca_kin_t kin;
    assert_int_equal(mca_fk(&c, q, &kin), MCA_OK);
    double J[3][MCA_MAX_DOF];
    assert_int_equal(mca_jacobian_ee(&kin, J), MCA_OK);
    double norm = 0.0;
    for (int j = 0; j < 8; j++) {
        for (int p = 0; p < 3; p++) {
            norm += J[p][j] * J[p][j];
        }
    }
    assert_true(norm > 0.1); /* columns are not all zero */
    /* moving the tool joint changes only the tool tip, by |tool| = 0.25 m lever */
    const double col7 = sqrt(J[0][7] * J[0][7] + J[1][7] * J[1][7] + J[2][7] * J[2][7]);
    assert_true(fabs(col7 - 0.25) < 1e-12);
}

static void test_base_pose(void **state) {
    (void)state;
    mca_chain_t c0, c1;
    kin_load_robot(&c0, "jaco2.urdf");
    c1 = c0;
    const double xyz[3] = {1.0, 2.0, 3.0}, rpy[3] = {0.2, 0.4, -1.3};
    mca_chain_set_base(&c1, xyz, rpy);
    /* R = Rz(yaw) Ry(pitch) Rx(roll), built here from elementary rotations */
    const double cr = cos(rpy[0]), sr = sin(rpy[0]), cp = cos(rpy[1]), sp = sin(rpy[1]), cy = cos(rpy[2]),
                 sy = sin(rpy[2]);
    const double Rz[3][3] = {{cy, -sy, 0}, {sy, cy, 0}, {0, 0, 1}};
    const double Ry[3][3] = {{cp, 0, sp}, {0, 1, 0}, {-sp, 0, cp}};
    const double Rx[3][3] = {{1, 0, 0}, {0, cr, -sr}, {0, sr, cr}};
    double RzRy[3][3], R[3][3];
    for (int i = 0; i < 3; i++) {
        for (int j = 0; j < 3; j++) {
            RzRy[i][j] = Rz[i][0] * Ry[0][j] + Rz[i][1] * Ry[1][j] + Rz[i][2] * Ry[2][j];
        }
    }
    for (int i = 0; i < 3; i++) {
        for (int j = 0; j < 3; j++) {
            R[i][j] = RzRy[i][0] * Rx[0][j] + RzRy[i][1] * Rx[1][j] + RzRy[i][2] * Rx[2][j];
            assert_true(fabs(R[i][j] - c1.base.R[i][j]) < 1e-15);
        }
    }
    const double q[6] = {4.8, 2.9, 1.0, 4.2, 1.4, 1.3};
    mca_kin_t k0, k1;
    assert_int_equal(mca_fk(&c0, q, &k0), MCA_OK);
    assert_int_equal(mca_fk(&c1, q, &k1), MCA_OK);
    for (int p = 0; p < k0.n_points; p++) {
        for (int i = 0; i < 3; i++) {
            const double w =
                R[i][0] * k0.point[p][0] + R[i][1] * k0.point[p][1] + R[i][2] * k0.point[p][2] + xyz[i];
            assert_true(fabs(w - k1.point[p][i]) < 1e-12);
        }
    }
    for (int j = 0; j < 6; j++) {
        for (int i = 0; i < 3; i++) {
            const double w = R[i][0] * k0.axis[j][0] + R[i][1] * k0.axis[j][1] + R[i][2] * k0.axis[j][2];
            assert_true(fabs(w - k1.axis[j][i]) < 1e-12);
        }
    }
}

static void test_bad_arguments(void **state) {
    (void)state;
    mca_chain_t c;
    kin_load_robot(&c, "mico2.urdf");
    double q[6] = {1, 2, 3, 4, 5, 6};
    mca_kin_t kin, before;
    assert_int_equal(mca_fk(&c, q, &kin), MCA_OK);
    before = kin;
    q[3] = NAN;
    assert_int_equal(mca_fk(&c, q, &kin), MCA_EINVAL);
    q[3] = INFINITY;
    assert_int_equal(mca_fk(&c, q, &kin), MCA_EINVAL);
    assert_memory_equal(&kin, &before, sizeof(kin)); /* unchanged on error */
    assert_int_equal(mca_fk(NULL, q, &kin), MCA_EINVAL);
    assert_int_equal(mca_fk(&c, NULL, &kin), MCA_EINVAL);
    assert_int_equal(mca_fk(&c, q, NULL), MCA_EINVAL);
    double J[3][MCA_MAX_DOF];
    assert_int_equal(mca_jacobian_point(&kin, -1, kin.ee, J), MCA_EINVAL);
    assert_int_equal(mca_jacobian_point(&kin, 7, kin.ee, J), MCA_EINVAL);
    assert_int_equal(mca_jacobian_point(&kin, 6, kin.ee, J), MCA_OK);
    /* link 0 never moves: its Jacobian is zero */
    assert_int_equal(mca_jacobian_point(&kin, 0, kin.point[0], J), MCA_OK);
    for (int j = 0; j < MCA_MAX_DOF; j++) {
        assert_true(J[0][j] == 0.0 && J[1][j] == 0.0 && J[2][j] == 0.0);
    }
}

static void test_clamp(void **state) {
    (void)state;
    mca_chain_t c;
    kin_load_robot(&c, "jaco2.urdf");
    double q[6] = {100.0, 0.0, 7.0, -100.0, 3.0, 0.5};
    assert_int_equal(mca_chain_clamp_q(&c, q), 2);
    assert_true(q[0] == 100.0 && q[3] == -100.0); /* continuous joints untouched */
    assert_true(fabs(q[1] - 47.0 * KIN_DEG) < 1e-12);
    assert_true(fabs(q[2] - 341.0 * KIN_DEG) < 1e-12);
    q[4] = NAN;
    double before[6];
    memcpy(before, q, sizeof(q));
    assert_int_equal(mca_chain_clamp_q(&c, q), MCA_EINVAL);
    assert_memory_equal(before, q, sizeof(q));
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_jacobian_jaco2),
        cmocka_unit_test(test_jacobian_mico2),
        cmocka_unit_test(test_jacobian_pa10plus),
        cmocka_unit_test(test_ee_jacobian_nontrivial),
        cmocka_unit_test(test_base_pose),
        cmocka_unit_test(test_bad_arguments),
        cmocka_unit_test(test_clamp),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
