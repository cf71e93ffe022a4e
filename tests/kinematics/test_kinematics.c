/* SPDX-License-Identifier: MIT */
/* Kinematics (core/src/chain.c, core/src/urdf_shim.cpp) against independent truth:
 *  - dh:       FK of jaco2.urdf / mico2.urdf equals Kinova's classic DH chain, computed here from the
 *              published D1..D6, e2 with plain 4x4 DH matrices (1000 random q, 1e-9 m);
 *  - fold:     a URDF with fixed joints, general axes and a side branch equals a 4x4 product of its
 *              own <origin> elements computed here (quaternion axis-angle, not Rodrigues);
 *  - jacobian: every link's point Jacobian equals central finite differences of FK (1e-6), all robots,
 *              non-identity base pose;
 *  - bad:      bad URDFs return their code and a message naming the file and the element;
 *  - limits:   joint limits, speeds and capsule radii read as written; the paper's PA10+ start posture.
 * Usage: test_kinematics [group]   (no group: all). Paths come from CMake, never from the cwd. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "mca/chain.h"
#include "mca/err.h"

#ifndef MCA_ROBOTS_DIR
#error "MCA_ROBOTS_DIR (config/robots) must be defined by CMake"
#endif
#ifndef MCA_TEST_TMPDIR
#error "MCA_TEST_TMPDIR (a writable build directory) must be defined by CMake"
#endif

#define JACO2_URDF MCA_ROBOTS_DIR "/jaco2.urdf"
#define MICO2_URDF MCA_ROBOTS_DIR "/mico2.urdf"
#define PA10_URDF MCA_ROBOTS_DIR "/pa10plus.urdf"
#define DEG (M_PI / 180.0)

/* ---- deterministic RNG (xorshift64*) so runs are repeatable ---- */
static uint64_t rng_state = 0x2545f4914f6cdd1dULL;
static double urand(void) {
    rng_state ^= rng_state >> 12;
    rng_state ^= rng_state << 25;
    rng_state ^= rng_state >> 27;
    return (double)((rng_state * 2685821657736338717ULL) >> 11) * (1.0 / 9007199254740992.0);
}
static double urange(double lo, double hi) {
    return lo + (hi - lo) * urand();
}

/* ---- independent 4x4 homogeneous matrices ---- */
typedef double m4_t[4][4];

static void m4_eye(m4_t m) {
    memset(m, 0, sizeof(m4_t));
    for (int i = 0; i < 4; i++) {
        m[i][i] = 1.0;
    }
}
static void m4_mul(m4_t out, m4_t a, m4_t b) {
    m4_t r;
    for (int i = 0; i < 4; i++) {
        for (int j = 0; j < 4; j++) {
            r[i][j] = 0.0;
            for (int k = 0; k < 4; k++) {
                r[i][j] += a[i][k] * b[k][j];
            }
        }
    }
    memcpy(out, r, sizeof(m4_t));
}
static void m4_rx(m4_t m, double t) {
    m4_eye(m);
    m[1][1] = cos(t);
    m[1][2] = -sin(t);
    m[2][1] = sin(t);
    m[2][2] = cos(t);
}
static void m4_ry(m4_t m, double t) {
    m4_eye(m);
    m[0][0] = cos(t);
    m[0][2] = sin(t);
    m[2][0] = -sin(t);
    m[2][2] = cos(t);
}
static void m4_rz(m4_t m, double t) {
    m4_eye(m);
    m[0][0] = cos(t);
    m[0][1] = -sin(t);
    m[1][0] = sin(t);
    m[1][1] = cos(t);
}
static void m4_trans(m4_t m, double x, double y, double z) {
    m4_eye(m);
    m[0][3] = x;
    m[1][3] = y;
    m[2][3] = z;
}
/* URDF <origin xyz rpy>: Trans(xyz) Rz(yaw) Ry(pitch) Rx(roll), built from elementary factors. */
static void m4_origin(m4_t m, const double xyz[3], const double rpy[3]) {
    m4_t t, a;
    m4_trans(m, xyz[0], xyz[1], xyz[2]);
    m4_rz(t, rpy[2]);
    m4_mul(m, m, t);
    m4_ry(t, rpy[1]);
    m4_mul(m, m, t);
    m4_rx(a, rpy[0]);
    m4_mul(m, m, a);
}
/* Rotation by angle q about axis u (any length) via the unit quaternion (independent of Rodrigues). */
static void m4_axis_angle(m4_t m, const double u[3], double q) {
    const double n = sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
    const double w = cos(q / 2), s = sin(q / 2) / n;
    const double x = u[0] * s, y = u[1] * s, z = u[2] * s;
    m4_eye(m);
    m[0][0] = w * w + x * x - y * y - z * z;
    m[0][1] = 2 * (x * y - w * z);
    m[0][2] = 2 * (x * z + w * y);
    m[1][0] = 2 * (x * y + w * z);
    m[1][1] = w * w - x * x + y * y - z * z;
    m[1][2] = 2 * (y * z - w * x);
    m[2][0] = 2 * (x * z - w * y);
    m[2][1] = 2 * (y * z + w * x);
    m[2][2] = w * w - x * x - y * y + z * z;
}
/* Classic DH: Rz(theta) Tz(d) Tx(a) Rx(alpha), the textbook closed form. */
static void m4_dh(m4_t m, double th, double d, double a, double al) {
    const double ct = cos(th), st = sin(th), ca = cos(al), sa = sin(al);
    m4_eye(m);
    m[0][0] = ct;
    m[0][1] = -st * ca;
    m[0][2] = st * sa;
    m[0][3] = a * ct;
    m[1][0] = st;
    m[1][1] = ct * ca;
    m[1][2] = -ct * sa;
    m[1][3] = a * st;
    m[2][1] = sa;
    m[2][2] = ca;
    m[2][3] = d;
}

static double dist3(const double a[3], const double b[3]) {
    const double dx = a[0] - b[0], dy = a[1] - b[1], dz = a[2] - b[2];
    return sqrt(dx * dx + dy * dy + dz * dz);
}

static void load_ok(mca_chain_t *c, const char *path, const char *tip) {
    char err[512] = "";
    const int rc = mca_chain_load_urdf(c, path, tip, err, sizeof(err));
    if (rc != MCA_OK) {
        print_error("load %s: rc %d: %s\n", path, rc, err);
    }
    assert_int_equal(rc, MCA_OK);
}

/* ================= 1. Kinova URDFs == Kinova classic DH ================= */

typedef struct kinova_dims {
    double D1, D2, D3, D4, D5, D6, e2;
} kinova_dims_t;

/* Frame origins of the DH chain: o[i] = origin of DH frame i (i = 0..6; frame 0 = base). */
static void kinova_dh_points(const kinova_dims_t *k, const double q[6], double o[7][3]) {
    const double aa = 30.0 * DEG;
    const double sa_s2a = sin(aa) / sin(2 * aa);
    const double d4b = k->D3 + sa_s2a * k->D4;
    const double d5b = sa_s2a * (k->D4 + k->D5);
    const double d6b = sa_s2a * k->D5 + k->D6;
    const double alpha[6] = {M_PI / 2, M_PI, M_PI / 2, 2 * aa, 2 * aa, M_PI};
    const double a[6] = {0, k->D2, 0, 0, 0, 0};
    const double d[6] = {k->D1, 0, -k->e2, -d4b, -d5b, -d6b};
    const double sign[6] = {-1, 1, 1, 1, 1, 1};
    const double off[6] = {0, -M_PI / 2, M_PI / 2, 0, -M_PI, M_PI / 2};
    m4_t T, A;
    m4_eye(T);
    o[0][0] = o[0][1] = o[0][2] = 0.0;
    for (int i = 0; i < 6; i++) {
        m4_dh(A, sign[i] * q[i] + off[i], d[i], a[i], alpha[i]);
        m4_mul(T, T, A);
        for (int r = 0; r < 3; r++) {
            o[i + 1][r] = T[r][3];
        }
    }
}

/* URDF point mapping (see docs/robots.md): point[0] = root = DH frame 0 origin, point[i] (joint i
 * origin, i = 1..6) = DH frame i-1 origin, point[7] (tool tip) = DH frame 6 origin. */
static void check_kinova_dh(const char *path, const kinova_dims_t *dims) {
    mca_chain_t c;
    load_ok(&c, path, "tool_tip");
    assert_int_equal(c.dof, 6);
    double worst = 0.0;
    for (int trial = 0; trial < 1000; trial++) {
        double q[6];
        for (int i = 0; i < 6; i++) {
            q[i] = urange(-2 * M_PI, 2 * M_PI); /* FK identity holds for every q, not only within limits */
        }
        mca_kin_t kin;
        assert_int_equal(mca_fk(&c, q, &kin), MCA_OK);
        assert_int_equal(kin.n_points, 8);
        double o[7][3];
        kinova_dh_points(dims, q, o);
        worst = fmax(worst, dist3(kin.point[0], o[0]));
        for (int i = 1; i <= 6; i++) {
            worst = fmax(worst, dist3(kin.point[i], o[i - 1]));
        }
        worst = fmax(worst, dist3(kin.point[7], o[6]));
        worst = fmax(worst, dist3(kin.ee, o[6]));
    }
    print_message("%s: worst |URDF FK - DH| over 1000 configurations = %.3g m\n", path, worst);
    assert_true(worst < 1e-9);
}

static void test_dh_jaco2(void **state) {
    (void)state;
    const kinova_dims_t jaco2 = {0.2755, 0.4100, 0.2073, 0.0741, 0.0741, 0.1600, 0.0098};
    check_kinova_dh(JACO2_URDF, &jaco2);
}

static void test_dh_mico2(void **state) {
    (void)state;
    const kinova_dims_t mico2 = {0.2755, 0.2900, 0.1233, 0.0741, 0.0741, 0.1600, 0.0070};
    check_kinova_dh(MICO2_URDF, &mico2);
}

/* Physical sanity of the Kinova angle convention: q2 = q3 = 180 deg is the upright "candle",
 * shoulder and elbow straight above the base (the middle of the 47..313 / 19..341 ranges). */
static void test_dh_candle(void **state) {
    (void)state;
    mca_chain_t c;
    load_ok(&c, JACO2_URDF, NULL);
    const double q[6] = {0.3, M_PI, M_PI, 0.0, 0.0, 0.0};
    mca_kin_t kin;
    assert_int_equal(mca_fk(&c, q, &kin), MCA_OK);
    const double shoulder[3] = {0, 0, 0.2755}, elbow[3] = {0, 0, 0.2755 + 0.41};
    assert_true(dist3(kin.point[2], shoulder) < 1e-12);
    assert_true(dist3(kin.point[3], elbow) < 1e-12);
    assert_true(kin.ee[2] > 1.1); /* whole arm above the elbow */
}

/* ================= fixed-joint folding, general axes, side branch ================= */

typedef struct tjoint {
    const char *name, *type, *parent, *child;
    double xyz[3], rpy[3], axis[3];
} tjoint_t;

static const tjoint_t fold_joints[] = {
    {"f0", "fixed", "r", "a", {0.1, -0.2, 0.3}, {0.3, -0.2, 0.5}, {0, 0, 1}},
    {"j1", "revolute", "a", "b", {0.05, 0.0, 0.2}, {0.0, 0.4, -0.7}, {1, 2, 3}},
    {"f1", "fixed", "b", "c", {0.0, 0.3, 0.1}, {1.1, 0.2, 0.0}, {0, 0, 1}},
    {"side", "fixed", "b", "sensor", {0.2, 0.2, 0.2}, {0, 0, 0}, {0, 0, 1}},
    {"j2", "continuous", "c", "d", {0.25, 0.0, 0.0}, {-0.5, 0.0, 0.9}, {0, -1, 0}},
    {"j3", "revolute", "d", "e", {0.0, 0.0, 0.3}, {0.2, 0.3, 0.4}, {0.3, 0, -0.4}},
    {"ftip", "fixed", "e", "tip", {0.0, 0.1, 0.15}, {0.6, -0.1, 0.2}, {0, 0, 1}},
};
#define N_FOLD ((int)(sizeof(fold_joints) / sizeof(fold_joints[0])))

static void write_file(const char *path, const char *text) {
    FILE *f = fopen(path, "w");
    assert_non_null(f);
    assert_int_equal(fputs(text, f) >= 0, 1);
    assert_int_equal(fclose(f), 0);
}

static void write_fold_urdf(const char *path) {
    static char buf[8192];
    int n = snprintf(
        buf, sizeof(buf),
        "<?xml version=\"1.0\"?>\n<robot name=\"fold\">\n"
        "  <link name=\"r\"><collision><geometry><sphere radius=\"0.1\"/></geometry></collision></link>\n"
        "  <link name=\"a\"><collision><geometry><cylinder radius=\"0.11\" length=\"0.2\"/>"
        "</geometry></collision></link>\n"
        "  <link name=\"b\"><collision><geometry><cylinder radius=\"0.12\" length=\"0.2\"/>"
        "</geometry></collision></link>\n"
        "  <link name=\"c\"><collision><geometry><cylinder radius=\"0.13\" length=\"0.2\"/>"
        "</geometry></collision></link>\n"
        "  <link name=\"sensor\"><collision><geometry><sphere radius=\"0.5\"/></geometry>"
        "</collision></link>\n"
        "  <link name=\"d\"><collision><geometry><box size=\"1 1 1\"/></geometry></collision>"
        "<collision><geometry><cylinder radius=\"0.14\" length=\"0.2\"/></geometry></collision></link>\n"
        "  <link name=\"e\"><collision><geometry><cylinder radius=\"0.15\" length=\"0.2\"/>"
        "</geometry></collision></link>\n"
        "  <link name=\"tip\"/>\n");
    for (int i = 0; i < N_FOLD; i++) {
        const tjoint_t *j = &fold_joints[i];
        n += snprintf(buf + n, sizeof(buf) - (size_t)n,
                      "  <joint name=\"%s\" type=\"%s\"><parent link=\"%s\"/><child link=\"%s\"/>\n"
                      "    <origin xyz=\"%.17g %.17g %.17g\" rpy=\"%.17g %.17g %.17g\"/>\n"
                      "    <axis xyz=\"%.17g %.17g %.17g\"/>%s</joint>\n",
                      j->name, j->type, j->parent, j->child, j->xyz[0], j->xyz[1], j->xyz[2], j->rpy[0],
                      j->rpy[1], j->rpy[2], j->axis[0], j->axis[1], j->axis[2],
                      strcmp(j->type, "fixed")
                          ? "<limit lower=\"-2\" upper=\"2.5\" velocity=\"1.5\" effort=\"1\"/>"
                          : "");
    }
    snprintf(buf + n, sizeof(buf) - (size_t)n, "</robot>\n");
    write_file(path, buf);
}

static void test_fold(void **state) {
    (void)state;
    const char *path = MCA_TEST_TMPDIR "/kin_fold.urdf";
    write_fold_urdf(path);
    mca_chain_t c;
    load_ok(&c, path, "tip");
    assert_int_equal(c.dof, 3);
    assert_string_equal(c.name, "fold");
    assert_string_equal(c.joint[0].name, "j1");
    assert_string_equal(c.joint[1].name, "j2");
    assert_string_equal(c.joint[2].name, "j3");
    assert_int_equal(c.joint[1].continuous, 1);
    /* radii: segment k takes the largest of the child link of joint k-1 and its fixed children on the path;
     * segment 0 the root and its fixed children; the side branch 'sensor' is off the path; boxes ignored */
    const double r_exp[4] = {0.11, 0.13, 0.14, 0.15};
    for (int k = 0; k < 4; k++) {
        assert_true(fabs(c.link_radius[k] - r_exp[k]) < 1e-15);
    }
    const double bxyz[3] = {0.4, -1.0, 0.25}, brpy[3] = {0.3, -0.6, 2.0};
    mca_chain_set_base(&c, bxyz, brpy);
    double worst = 0.0;
    for (int trial = 0; trial < 200; trial++) {
        double q[3];
        for (int i = 0; i < 3; i++) {
            q[i] = urange(-3.0, 3.0);
        }
        mca_kin_t kin;
        assert_int_equal(mca_fk(&c, q, &kin), MCA_OK);
        /* truth: base * product of every origin, revolutes rotated about their (unnormalised) axis */
        m4_t T, A;
        m4_origin(T, bxyz, brpy);
        worst = fmax(worst, sqrt(pow(T[0][3] - kin.point[0][0], 2) + pow(T[1][3] - kin.point[0][1], 2) +
                                 pow(T[2][3] - kin.point[0][2], 2)));
        int k = 0;
        for (int i = 0; i < N_FOLD; i++) {
            const tjoint_t *j = &fold_joints[i];
            if (!strcmp(j->name, "side")) {
                continue;
            }
            m4_origin(A, j->xyz, j->rpy);
            m4_mul(T, T, A);
            if (strcmp(j->type, "fixed")) {
                const double o[3] = {T[0][3], T[1][3], T[2][3]};
                const double n =
                    sqrt(j->axis[0] * j->axis[0] + j->axis[1] * j->axis[1] + j->axis[2] * j->axis[2]);
                double ax[3];
                for (int r = 0; r < 3; r++) {
                    ax[r] = (T[r][0] * j->axis[0] + T[r][1] * j->axis[1] + T[r][2] * j->axis[2]) / n;
                }
                worst = fmax(worst, dist3(kin.point[k + 1], o));
                worst = fmax(worst, dist3(kin.axis[k], ax));
                m4_axis_angle(A, j->axis, q[k]);
                m4_mul(T, T, A);
                k++;
            }
        }
        const double tip[3] = {T[0][3], T[1][3], T[2][3]};
        worst = fmax(worst, dist3(kin.point[4], tip));
        worst = fmax(worst, dist3(kin.ee, tip));
    }
    print_message("fold: worst |FK - 4x4 product| = %.3g\n", worst);
    assert_true(worst < 1e-12);

    /* a tip in the middle of the chain: only the joints up to it */
    mca_chain_t c2;
    load_ok(&c2, path, "c");
    assert_int_equal(c2.dof, 1);
    /* the tip may be any link; a side branch without a tip name is ambiguous */
    char err[512];
    mca_chain_t c3;
    assert_int_equal(mca_chain_load_urdf(&c3, path, NULL, err, sizeof(err)), MCA_EPARSE);
    assert_non_null(strstr(err, path));
    assert_non_null(strstr(err, "sensor"));
    print_message("branch without tip: %s\n", err);
}

/* ================= 2. Jacobians == central finite differences ================= */

/* World pose of link k's body frame: base for link 0, else the frame of joint k-1 after its rotation. */
static const mca_pose_t *link_frame(const mca_chain_t *c, const mca_kin_t *kin, int k) {
    return k == 0 ? &c->base : &kin->frame[k - 1];
}

static void check_jacobian(const char *path, const char *tip) {
    mca_chain_t c;
    load_ok(&c, path, tip);
    const double bxyz[3] = {0.7, -0.3, 0.12}, brpy[3] = {0.25, -0.4, 1.9};
    mca_chain_set_base(&c, bxyz, brpy);
    const int n = c.dof;
    const double h = 1e-6;
    double worst = 0.0;
    for (int trial = 0; trial < 50; trial++) {
        double q[MCA_MAX_DOF];
        for (int i = 0; i < n; i++) {
            q[i] = urange(-M_PI, M_PI);
        }
        mca_kin_t kin;
        assert_int_equal(mca_fk(&c, q, &kin), MCA_OK);
        for (int k = 0; k <= n; k++) {
            /* two kinds of point on link k: a random body-fixed offset, and a point on the segment */
            double local[3], t = urand();
            for (int r = 0; r < 3; r++) {
                local[r] = urange(-0.3, 0.3);
            }
            for (int kind = 0; kind < 2; kind++) {
                double x[3];
                if (kind == 0) {
                    mca_pose_apply(x, link_frame(&c, &kin, k), local);
                } else {
                    for (int r = 0; r < 3; r++) {
                        x[r] = kin.point[k][r] + t * (kin.point[k + 1][r] - kin.point[k][r]);
                    }
                }
                double J[3][MCA_MAX_DOF];
                assert_int_equal(mca_jacobian_point(&kin, k, x, J), MCA_OK);
                for (int j = 0; j < MCA_MAX_DOF; j++) {
                    double fd[3] = {0, 0, 0};
                    if (j < n) {
                        double xp[3], xm[3];
                        for (int s = 0; s < 2; s++) {
                            double qs[MCA_MAX_DOF];
                            memcpy(qs, q, sizeof(qs));
                            qs[j] += s == 0 ? h : -h;
                            mca_kin_t ks;
                            assert_int_equal(mca_fk(&c, qs, &ks), MCA_OK);
                            double *dst = s == 0 ? xp : xm;
                            if (kind == 0) {
                                mca_pose_apply(dst, link_frame(&c, &ks, k), local);
                            } else {
                                for (int r = 0; r < 3; r++) {
                                    dst[r] = ks.point[k][r] + t * (ks.point[k + 1][r] - ks.point[k][r]);
                                }
                            }
                        }
                        for (int r = 0; r < 3; r++) {
                            fd[r] = (xp[r] - xm[r]) / (2 * h);
                        }
                    }
                    for (int r = 0; r < 3; r++) {
                        worst = fmax(worst, fabs(J[r][j] - fd[r]));
                        if (j >= k || j >= n) {
                            assert_true(J[r][j] == 0.0); /* link k is not moved by joints >= k */
                        }
                    }
                }
            }
        }
        /* end effector: mca_jacobian_ee == FD of kin.ee */
        double Je[3][MCA_MAX_DOF];
        assert_int_equal(mca_jacobian_ee(&kin, Je), MCA_OK);
        for (int j = 0; j < n; j++) {
            double qp[MCA_MAX_DOF], qm[MCA_MAX_DOF];
            memcpy(qp, q, sizeof(qp));
            memcpy(qm, q, sizeof(qm));
            qp[j] += h;
            qm[j] -= h;
            mca_kin_t kp, km;
            assert_int_equal(mca_fk(&c, qp, &kp), MCA_OK);
            assert_int_equal(mca_fk(&c, qm, &km), MCA_OK);
            for (int r = 0; r < 3; r++) {
                worst = fmax(worst, fabs(Je[r][j] - (kp.ee[r] - km.ee[r]) / (2 * h)));
            }
        }
    }
    print_message("%s: worst |J - central FD| = %.3g\n", path, worst);
    assert_true(worst < 1e-6);
}

static void test_jacobian_jaco2(void **state) {
    (void)state;
    check_jacobian(JACO2_URDF, "tool_tip");
}
static void test_jacobian_mico2(void **state) {
    (void)state;
    check_jacobian(MICO2_URDF, "tool_tip");
}
static void test_jacobian_pa10(void **state) {
    (void)state;
    check_jacobian(PA10_URDF, "tool_tip");
}

static void test_bad_args(void **state) {
    (void)state;
    mca_chain_t c;
    load_ok(&c, JACO2_URDF, NULL);
    double q[6] = {0, 1, 2, 3, 4, 5};
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
    assert_int_equal(mca_jacobian_point(&kin, 0, kin.ee, J), MCA_OK);
    for (int j = 0; j < MCA_MAX_DOF; j++) {
        assert_true(J[0][j] == 0.0 && J[1][j] == 0.0 && J[2][j] == 0.0); /* link 0 never moves */
    }
    assert_int_equal(mca_jacobian_ee(NULL, J), MCA_EINVAL);
    assert_int_equal(mca_chain_load_urdf(NULL, JACO2_URDF, NULL, NULL, 0), MCA_EINVAL);
    assert_int_equal(mca_chain_load_urdf(&c, NULL, NULL, NULL, 0), MCA_EINVAL);
}

/* ================= 3. Bad URDFs ================= */

#define LINK(n) "<link name=\"" n "\"/>"
#define REV(n, p, ch)                                                                                        \
    "<joint name=\"" n "\" type=\"revolute\"><parent link=\"" p "\"/><child link=\"" ch "\"/>"               \
    "<origin xyz=\"0 0 0.1\"/><axis xyz=\"0 0 1\"/><limit lower=\"-1\" upper=\"1\" velocity=\"1\" "          \
    "effort=\"1\"/>"                                                                                         \
    "</joint>\n"

typedef struct bad_case {
    const char *file; /* written into MCA_TEST_TMPDIR (NULL text: never written) */
    const char *text;
    const char *tip;
    int rc;
    const char *needle[3]; /* each must appear in the message, besides the file path */
} bad_case_t;

static const bad_case_t bad_cases[] = {
    {"kin_missing.urdf", NULL, NULL, MCA_ENOENT, {"cannot open", NULL, NULL}},
    {"kin_malformed.urdf",
     "<?xml version=\"1.0\"?>\n<robot name=\"x\">\n" LINK("a") "\n<link name=\"b\">\n</robot>\n",
     NULL,
     MCA_EPARSE,
     {"malformed XML", "line ", NULL}},
    {"kin_prismatic.urdf",
     "<robot name=\"x\">" LINK("a") LINK("b") LINK("c") "\n" REV(
         "j1", "a", "b") "<joint name=\"slide\" type=\"prismatic\"><parent link=\"b\"/><child link=\"c\"/>"
                         "<axis xyz=\"1 0 0\"/><limit lower=\"0\" upper=\"1\" velocity=\"1\" "
                         "effort=\"1\"/></joint>\n</robot>\n",
     NULL,
     MCA_EPARSE,
     {"joint 'slide'", "prismatic", "line 3"}},
    {"kin_nolimit.urdf",
     "<robot name=\"x\">" LINK("a") LINK("b") LINK("c") LINK("d") "\n" REV("j1", "a", "b")
         REV("j2", "b", "c") "<joint name=\"j3\" type=\"revolute\"><parent link=\"c\"/><child "
                             "link=\"d\"/><axis xyz=\"0 1 0\"/>"
                             "</joint>\n</robot>\n",
     NULL,
     MCA_EPARSE,
     {"joint 'j3'", "revolute joint has no <limit>", "line 4"}},
    {"kin_continuous_nolimit.urdf",
     "<robot name=\"x\">" LINK("a")
         LINK("b") "\n<joint name=\"spin\" type=\"continuous\"><parent link=\"a\"/>"
                   "<child link=\"b\"/><axis xyz=\"0 1 0\"/></joint>\n</robot>\n",
     NULL,
     MCA_EPARSE,
     {"joint 'spin'", "<limit>", NULL}},
    {"kin_too_many.urdf",
     "<robot name=\"x\">" LINK("l0") LINK("l1") LINK("l2") LINK("l3") LINK("l4") LINK("l5") LINK("l6")
         LINK("l7") LINK("l8") LINK("l9") "\n" REV("j1", "l0", "l1") REV("j2", "l1", "l2")
             REV("j3", "l2", "l3") REV("j4", "l3", "l4") REV("j5", "l4", "l5") REV("j6", "l5", "l6")
                 REV("j7", "l6", "l7") REV("j8", "l7", "l8") REV("j9", "l8", "l9") "</robot>\n",
     NULL,
     MCA_ERANGE,
     {"9 revolute joints", "'l0' -> 'l9'", "MCA_MAX_DOF"}},
    {"kin_unknown_tip.urdf",
     "<robot name=\"x\">" LINK("a") LINK("b") "\n" REV("j1", "a", "b") "</robot>\n",
     "gripper",
     MCA_ENOENT,
     {"tip link 'gripper'", "no such <link>", NULL}},
    {"kin_zero_axis.urdf",
     "<robot name=\"x\">" LINK("a") LINK("b") "\n<joint name=\"j1\" type=\"revolute\"><parent link=\"a\"/>"
                                              "<child link=\"b\"/><axis xyz=\"0 0 0\"/><limit lower=\"-1\" "
                                              "upper=\"1\" velocity=\"1\" effort=\"1\"/>"
                                              "</joint>\n</robot>\n",
     NULL,
     MCA_EPARSE,
     {"joint 'j1'", "<axis>", NULL}},
    {"kin_zero_velocity.urdf",
     "<robot name=\"x\">" LINK("a") LINK("b") "\n<joint name=\"j1\" type=\"revolute\"><parent link=\"a\"/>"
                                              "<child link=\"b\"/><axis xyz=\"0 0 1\"/><limit lower=\"-1\" "
                                              "upper=\"1\" velocity=\"0\" effort=\"1\"/>"
                                              "</joint>\n</robot>\n",
     NULL,
     MCA_EPARSE,
     {"joint 'j1'", "velocity", NULL}},
    {"kin_floating.urdf",
     "<robot name=\"x\">" LINK("a") LINK("b") "\n<joint name=\"free\" type=\"floating\"><parent link=\"a\"/>"
                                              "<child link=\"b\"/></joint>\n</robot>\n",
     NULL,
     MCA_EPARSE,
     {"joint 'free'", "floating", NULL}},
    {"kin_not_urdf.urdf",
     "<?xml version=\"1.0\"?>\n<robut name=\"x\"/>\n",
     NULL,
     MCA_EPARSE,
     {"<robot>", NULL, NULL}},
    {"kin_no_joint.urdf",
     "<robot name=\"x\">" LINK("a") "</robot>\n",
     NULL,
     MCA_EPARSE,
     {"no revolute", NULL, NULL}},
};

static void test_bad_urdf(void **state) {
    (void)state;
    for (size_t i = 0; i < sizeof(bad_cases) / sizeof(bad_cases[0]); i++) {
        const bad_case_t *b = &bad_cases[i];
        char path[512];
        snprintf(path, sizeof(path), "%s/%s", MCA_TEST_TMPDIR, b->file);
        if (b->text) {
            write_file(path, b->text);
        } else {
            remove(path);
        }
        mca_chain_t c, before;
        memset(&c, 0x5a, sizeof(c));
        before = c;
        char err[512] = "";
        const int rc = mca_chain_load_urdf(&c, path, b->tip, err, sizeof(err));
        print_message("%-28s rc %d: %s\n", b->file, rc, err);
        assert_int_equal(rc, b->rc);
        assert_non_null(strstr(err, path)); /* names the file */
        for (int k = 0; k < 3; k++) {
            if (b->needle[k] && !strstr(err, b->needle[k])) {
                fail_msg("%s: message lacks \"%s\": %s", b->file, b->needle[k], err);
            }
        }
        assert_memory_equal(&c, &before, sizeof(c)); /* unchanged on error */
        /* a tiny buffer truncates, never overflows */
        char small[8];
        memset(small, 'x', sizeof(small));
        assert_int_equal(mca_chain_load_urdf(&c, path, b->tip, small, 4), b->rc);
        assert_int_equal(small[3], '\0');
        assert_int_equal(small[4], 'x');
    }
}

/* ================= 4. Limits, speeds, radii, the paper's PA10+ start posture ================= */

static void test_limits_kinova(void **state) {
    (void)state;
    mca_chain_t c;
    load_ok(&c, JACO2_URDF, "tool_tip");
    assert_string_equal(c.name, "jaco2");
    assert_string_equal(c.source, JACO2_URDF);
    const double tol = 1e-12;
    /* joint 2: 47..313 deg, joint 3: 19..341 deg, in Kinova's own angle; others continuous */
    assert_int_equal(c.joint[1].continuous, 0);
    assert_true(fabs(c.joint[1].lower - 47 * DEG) < tol && fabs(c.joint[1].upper - 313 * DEG) < tol);
    assert_true(fabs(c.joint[2].lower - 19 * DEG) < tol && fabs(c.joint[2].upper - 341 * DEG) < tol);
    for (int i = 0; i < 6; i++) {
        const int cont = i != 1 && i != 2;
        assert_int_equal(c.joint[i].continuous, cont);
        if (cont) {
            assert_true(isinf(c.joint[i].lower) && c.joint[i].lower < 0);
            assert_true(isinf(c.joint[i].upper) && c.joint[i].upper > 0);
        }
        const double v = (i < 3 ? 36 : 48) * DEG;
        assert_true(fabs(c.joint[i].vel_limit - v) < tol);
    }
    const double r_jaco[7] = {0.05, 0.05, 0.045, 0.045, 0.04, 0.04, 0.045};
    for (int k = 0; k < 7; k++) {
        assert_true(fabs(c.link_radius[k] - r_jaco[k]) < tol);
    }
    mca_chain_t m;
    load_ok(&m, MICO2_URDF, "tool_tip");
    assert_true(fabs(m.joint[1].lower - 50 * DEG) < tol && fabs(m.joint[1].upper - 310 * DEG) < tol);
    assert_true(fabs(m.joint[2].lower - 35 * DEG) < tol && fabs(m.joint[2].upper - 325 * DEG) < tol);

    /* clamp helper */
    double q[6] = {100.0, 0.1, 6.2, -100.0, 0.0, 0.0};
    assert_int_equal(mca_chain_clamp_q(&c, q), 2);
    assert_true(q[0] == 100.0 && q[3] == -100.0); /* continuous untouched */
    assert_true(q[1] == c.joint[1].lower && q[2] == c.joint[2].upper);
    assert_int_equal(mca_chain_clamp_q(&c, q), 0);
    q[4] = NAN;
    assert_int_equal(mca_chain_clamp_q(&c, q), MCA_EINVAL);
}

static void test_limits_pa10(void **state) {
    (void)state;
    mca_chain_t c;
    load_ok(&c, PA10_URDF, NULL); /* the tip is the single leaf, tool_tip */
    assert_int_equal(c.dof, 8);
    const double lim[8] = {177, 94, 174, 137, 255, 165, 255, 90};
    const double vel[8] = {57, 57, 57, 57, 114, 114, 114, 114};
    const char *names[8] = {"S1", "S2", "S3", "E1", "E2", "W1", "W2", "T"};
    for (int i = 0; i < 8; i++) {
        assert_string_equal(c.joint[i].name, names[i]);
        assert_int_equal(c.joint[i].continuous, 0);
        assert_true(fabs(c.joint[i].lower + lim[i] * DEG) < 1e-12);
        assert_true(fabs(c.joint[i].upper - lim[i] * DEG) < 1e-12);
        assert_true(fabs(c.joint[i].vel_limit - vel[i] * DEG) < 1e-12);
    }
    const double r_pa10[9] = {0.08, 0.08, 0.07, 0.07, 0.06, 0.06, 0.06, 0.05, 0.02};
    for (int k = 0; k < 9; k++) {
        assert_true(fabs(c.link_radius[k] - r_pa10[k]) < 1e-12);
    }

    /* the paper's task-1 start, both arms: inside the limits (clamp changes nothing) */
    double qL[8] = {0, M_PI / 4, 0, -M_PI / 2, 0, M_PI / 4, 0, M_PI / 4};
    double qR[8] = {-M_PI / 2, -M_PI / 4, 0, M_PI / 2, 0, -M_PI / 4, 0, -M_PI / 4};
    assert_int_equal(mca_chain_clamp_q(&c, qL), 0);
    assert_int_equal(mca_chain_clamp_q(&c, qR), 0);
    /* closed form of the theta_L0 posture (all pitch axes +y, arm straight up at q = 0):
     * upper arm 45 deg forward, elbow bent 90 deg, wrist vertical, tool 45 deg forward */
    mca_kin_t kin;
    assert_int_equal(mca_fk(&c, qL, &kin), MCA_OK);
    const double s = sqrt(0.5);
    const double shoulder[3] = {0, 0, 0.317};
    const double elbow[3] = {0.45 * s, 0, 0.317 + 0.45 * s};
    const double wrist[3] = {elbow[0] - 0.48 * s, 0, elbow[2] + 0.48 * s};
    const double flange[3] = {wrist[0], 0, wrist[2] + 0.07};
    const double tip[3] = {flange[0] + 0.25 * s, 0, flange[2] + 0.25 * s};
    assert_true(dist3(kin.point[2], shoulder) < 1e-12);
    assert_true(dist3(kin.point[4], elbow) < 1e-12);
    assert_true(dist3(kin.point[6], wrist) < 1e-12);
    assert_true(dist3(kin.point[8], flange) < 1e-12);
    assert_true(dist3(kin.ee, tip) < 1e-12);
    double u[3], f[3];
    for (int r = 0; r < 3; r++) {
        u[r] = kin.point[4][r] - kin.point[2][r];
        f[r] = kin.point[6][r] - kin.point[4][r];
    }
    assert_true(fabs(u[0] * f[0] + u[1] * f[1] + u[2] * f[2]) < 1e-12); /* 90 deg elbow */
    print_message("PA10+ theta_L0: elbow (%.4f %.4f %.4f) wrist (%.4f %.4f %.4f) tip (%.4f %.4f %.4f)\n",
                  kin.point[4][0], kin.point[4][1], kin.point[4][2], kin.point[6][0], kin.point[6][1],
                  kin.point[6][2], kin.ee[0], kin.ee[1], kin.ee[2]);
    /* theta_R0 is the mirror posture turned -90 deg about z: same shape, same heights */
    mca_kin_t kr;
    assert_int_equal(mca_fk(&c, qR, &kr), MCA_OK);
    for (int p = 0; p < kr.n_points; p++) {
        assert_true(fabs(kr.point[p][2] - kin.point[p][2]) < 1e-12);
        assert_true(fabs(hypot(kr.point[p][0], kr.point[p][1]) - hypot(kin.point[p][0], kin.point[p][1])) <
                    1e-12);
    }
}

/* pose_from_xyz_rpy against the elementary-factor product */
static void test_pose_rpy(void **state) {
    (void)state;
    for (int trial = 0; trial < 100; trial++) {
        const double xyz[3] = {urange(-1, 1), urange(-1, 1), urange(-1, 1)};
        const double rpy[3] = {urange(-4, 4), urange(-4, 4), urange(-4, 4)};
        mca_pose_t p;
        mca_pose_from_xyz_rpy(&p, xyz, rpy);
        m4_t T;
        m4_origin(T, xyz, rpy);
        for (int i = 0; i < 3; i++) {
            assert_true(fabs(p.p[i] - T[i][3]) < 1e-15);
            for (int j = 0; j < 3; j++) {
                assert_true(fabs(p.R[i][j] - T[i][j]) < 1e-14);
            }
        }
    }
}

int main(int argc, char **argv) {
    const struct CMUnitTest dh[] = {
        cmocka_unit_test(test_dh_jaco2), cmocka_unit_test(test_dh_mico2), cmocka_unit_test(test_dh_candle),
        cmocka_unit_test(test_fold),     cmocka_unit_test(test_pose_rpy),
    };
    const struct CMUnitTest jacobian[] = {
        cmocka_unit_test(test_jacobian_jaco2),
        cmocka_unit_test(test_jacobian_mico2),
        cmocka_unit_test(test_jacobian_pa10),
        cmocka_unit_test(test_bad_args),
    };
    const struct CMUnitTest bad[] = {
        cmocka_unit_test(test_bad_urdf),
    };
    const struct CMUnitTest limits[] = {
        cmocka_unit_test(test_limits_kinova),
        cmocka_unit_test(test_limits_pa10),
    };
    const char *group = argc > 1 ? argv[1] : "all";
    const int all = !strcmp(group, "all");
    int failed = 0, ran = 0;
    if (all || !strcmp(group, "dh")) {
        failed += cmocka_run_group_tests_name("kinematics.dh", dh, NULL, NULL);
        ran++;
    }
    if (all || !strcmp(group, "jacobian")) {
        failed += cmocka_run_group_tests_name("kinematics.jacobian", jacobian, NULL, NULL);
        ran++;
    }
    if (all || !strcmp(group, "bad")) {
        failed += cmocka_run_group_tests_name("kinematics.bad_urdf", bad, NULL, NULL);
        ran++;
    }
    if (all || !strcmp(group, "limits")) {
        failed += cmocka_run_group_tests_name("kinematics.limits", limits, NULL, NULL);
        ran++;
    }
    if (!ran) {
        fprintf(stderr, "unknown group '%s' (dh, jacobian, bad, limits, all)\n", group);
        return 2;
    }
    return failed ? 1 : 0;
}
