/* SPDX-License-Identifier: MIT */
/* Unit tests of the MCA scheme: S(d), diamond rows, joint bounds (19)-(20), collision rows vs finite
 * differences of FK, the stable row layout, APF formulas, paths, scenario files and controller faults. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "mca/apf.h"
#include "mca/bodyrows.h"
#include "mca/chain.h"
#include "mca/controller.h"
#include "mca/err.h"
#include "mca/path_rate.h"
#include "mca/scenario.h"
#include "mca/scheme.h"
#include "mca/segdist.h"
#include "mca/urdf.h"
#include "mca/vec3.h"

/* core's white-box test: the witnesses, the rate scale and the critical links are the state's own */
#include "controller__state.h"

#ifndef MCA_SOURCE_DIR
#error MCA_SOURCE_DIR must be defined
#endif
#define PA10 MCA_SOURCE_DIR "/config/robots/pa10plus.urdf"
#define SCN(x) MCA_SOURCE_DIR "/config/scenarios/" x

/* ------------------------------------------------------------------ sigma's own stop bound (mca/path_rate.h)
 */

/* The limit against a second computation: central differences of the arm's predicted configurations along its
 * path time (no Jacobian, no pseudo-inverse) give q_ss; no cell's limit may exceed the local bound
 * sqrt(theta dec / |q_ss,j|) they imply (beyond the differences' own error), the limit binds on cup stacking
 * at dec 0.5 rad/s^2, and each cell's limit can be slowed to the next one's at the cell's deceleration. */
static void test_path_rate_limit(void **state) {
    (void)state;
    static mca_scenario_t s;
    static mca_controller_config_t cfg;
    static double qw[MCA_COORD_MAX_CELLS][MCA_MAX_DOF], qf[MCA_COORD_MAX_CELLS][MCA_MAX_DOF];
    static mca_path_rate_t r;
    char err[512];
    assert_int_equal(mca_scenario_load(SCN("cup_stacking.yaml"), &s, err, sizeof err), MCA_OK);
    assert_int_equal(mca_controller_config_from_scenario(&cfg, &s, MCA_SCHEME_MCA_TS, err, sizeof err),
                     MCA_OK);
    const double dec = 0.5, theta = MCA_PATH_RATE_CURVE_SHARE, hf = 0.02;
    int bound_somewhere = 0;
    for (int a = 0; a < cfg.n_arms; a++) {
        mca_kin_t kin;
        assert_int_equal(mca_fk(&cfg.chain[a], s.arm[a].q0, &kin), MCA_OK);
        mca_path_t path = cfg.path[a];
        mca_path_anchor(&path, kin.ee);
        const mca_coord_arm_t arm = {&cfg.chain[a], &path, s.arm[a].q0, cfg.sp.K};
        assert_int_equal(mca_path_rate_plan(&arm, dec, 1.5, qw, &r), MCA_OK);
        assert_true(r.n > 10 && r.h >= MCA_COORD_CELL_S);
        bound_somewhere |= r.least < 1.0;
        for (int k = 0; k + 1 < r.n; k++) {
            assert_true(r.sigma[k] > 0.0f && r.sigma[k] <= 1.5f);
            const double lhs = (double)r.sigma[k] * r.sigma[k];
            const double rhs = (double)r.sigma[k + 1] * r.sigma[k + 1] + 2.0 * r.decel[k] * r.h;
            assert_true(lhs <= rhs * (1.0 + 1e-5) + 1e-9);
        }
        /* the second computation over the path's first 10 s (512 samples at 0.02 s) */
        const int nf = MCA_COORD_MAX_CELLS;
        assert_int_equal(mca_coord_predict(&arm, hf, nf, qf), MCA_OK);
        int checked = 0;
        for (int k = 1; (k + 1) * r.h < (nf - 2) * hf; k++) {
            const int i = (int)lround(k * r.h / hf);
            double local = 1.5;
            for (int j = 0; j < cfg.chain[a].dof; j++) {
                const double qss = (qf[i + 1][j] - 2.0 * qf[i][j] + qf[i - 1][j]) / (hf * hf);
                if (fabs(qss) > 1e-9) {
                    local = fmin(local, sqrt(theta * dec / fabs(qss)));
                }
            }
            if (r.sigma[k] > 1.15 * local + 0.02) {
                print_error("arm %d cell %d: limit %.4f above the differences' bound %.4f\n", a, k,
                            r.sigma[k], local);
                fail();
            }
            checked++;
        }
        assert_true(checked > 50);
    }
    assert_true(bound_somewhere); /* at dec 0.5 the curve limits cup stacking's arms */
}

/* ------------------------------------------------------------------ S(d) (13) */

static void test_brake_values(void **state) {
    (void)state;
    const double d1 = 0.05, d2 = 0.12;
    assert_true(mca_brake_s(0.2, d1, d2) == 1.0);
    assert_true(mca_brake_s(d2, d1, d2) == 1.0);
    assert_true(mca_brake_s(d1, d1, d2) == 0.0);
    assert_true(mca_brake_s(0.0, d1, d2) == 0.0);
    assert_true(mca_brake_s(-0.1, d1, d2) == 0.0);
    /* midpoint: sin^2(pi/4) = 1/2 */
    assert_true(fabs(mca_brake_s(0.5 * (d1 + d2), d1, d2) - 0.5) < 1e-15);
    /* quarter: sin^2(pi/8) = (1 - cos(pi/4))/2 */
    assert_true(fabs(mca_brake_s(d1 + 0.25 * (d2 - d1), d1, d2) - 0.5 * (1.0 - sqrt(0.5))) < 1e-15);
    /* smooth and monotonic: continuous at both ends, derivative 0 at both ends */
    double prev = 0.0;
    for (int i = 0; i <= 1000; i++) {
        const double d = d1 + (d2 - d1) * i / 1000.0;
        const double s = mca_brake_s(d, d1, d2);
        assert_true(s >= prev - 1e-15);
        prev = s;
    }
    const double h = 1e-6;
    assert_true(mca_brake_s(d1 + h, d1, d2) < 1e-8);
    assert_true(1.0 - mca_brake_s(d2 - h, d1, d2) < 1e-8);
}

/* ------------------------------------------------------------------ diamond (10) */

static void test_diamond_rows(void **state) {
    (void)state;
    double J[3][MCA_MAX_DOF], rows[3][MCA_MAX_DOF];
    for (int i = 0; i < 3; i++) {
        for (int j = 0; j < MCA_MAX_DOF; j++) {
            J[i][j] = 10.0 * i + j + 1.0;
        }
    }
    const double r[3] = {0.5, -2.0, 0.0};
    mca_diamond_rows(r, J, 6, rows);
    /* hand computation: row i = r_i * J_i for the first dof columns, zero beyond */
    assert_true(rows[0][0] == 0.5 && rows[0][5] == 3.0 && rows[0][6] == 0.0);
    assert_true(rows[1][0] == -22.0 && rows[1][3] == -28.0 && rows[1][7] == 0.0);
    for (int j = 0; j < MCA_MAX_DOF; j++) {
        assert_true(rows[2][j] == 0.0);
    }
    /* componentwise rows times qdot = r_i * (J qdot)_i */
    const double qd[MCA_MAX_DOF] = {0.1, -0.2, 0.3, 0.05, 0.0, 1.0, 7.0, 7.0};
    for (int i = 0; i < 3; i++) {
        double a = 0.0, b = 0.0;
        for (int j = 0; j < 6; j++) {
            a += rows[i][j] * qd[j];
            b += J[i][j] * qd[j];
        }
        assert_true(fabs(a - r[i] * b) < 1e-12);
    }
}

/* ------------------------------------------------------------------ bounds (19)-(20) */

static void make_chain(mca_chain_t *c) {
    memset(c, 0, sizeof *c);
    c->dof = 3;
    for (int j = 0; j < 3; j++) {
        c->joint[j].lower = -1.0;
        c->joint[j].upper = 2.0;
        c->joint[j].vel_limit = 0.5;
        c->joint[j].axis[2] = 1.0;
    }
    c->joint[2].continuous = 1;
    c->joint[2].lower = -INFINITY;
    c->joint[2].upper = INFINITY;
}

static void test_joint_bounds(void **state) {
    (void)state;
    mca_chain_t c;
    make_chain(&c);
    double lb[3], ub[3];
    /* joint 0 mid-range: velocity limits win; joint 1 near the upper limit: eps (q+ - q) wins */
    const double q[3] = {0.5, 1.95, 100.0};
    assert_int_equal(mca_joint_bounds(&c, q, 5.0, lb, ub), MCA_OK);
    assert_true(lb[0] == -0.5 && ub[0] == 0.5);
    assert_true(fabs(ub[1] - 5.0 * (2.0 - 1.95)) < 1e-15); /* 0.25 < 0.5 */
    assert_true(lb[1] == -0.5);                            /* eps (q- - q) = -14.75 < -0.5 */
    /* continuous joint: velocity only, whatever q is */
    assert_true(lb[2] == -0.5 && ub[2] == 0.5);
    /* near the lower limit */
    const double q2[3] = {-0.98, 0.0, 0.0};
    assert_int_equal(mca_joint_bounds(&c, q2, 5.0, lb, ub), MCA_OK);
    assert_true(fabs(lb[0] - 5.0 * (-1.0 + 0.98)) < 1e-15);
    /* beyond a limit by more than vel/eps: lb > ub, reported */
    const double q3[3] = {2.2, 0.0, 0.0};
    assert_int_equal(mca_joint_bounds(&c, q3, 5.0, lb, ub), MCA_EINFEASIBLE);
    const double qn[3] = {NAN, 0.0, 0.0};
    assert_int_equal(mca_joint_bounds(&c, qn, 5.0, lb, ub), MCA_EINVAL);
}

/* ------------------------------------------------------------------ collision rows vs FK */

static void load_pa10(mca_chain_t *c) {
    char err[256];
    assert_int_equal(mca_chain_load_urdf(c, PA10, "tool_tip", err, sizeof err), MCA_OK);
}

/* World position of a point rigidly attached to link l at configuration q, given its position x at q0. */
static void moved_point(const mca_chain_t *c, const double *q0, const double *q, int l, const double x[3],
                        double out[3]) {
    mca_kin_t k0, k1;
    assert_int_equal(mca_fk(c, q0, &k0), MCA_OK);
    assert_int_equal(mca_fk(c, q, &k1), MCA_OK);
    if (l == 0) {
        mca_v3_set(out, x);
        return;
    }
    /* link l is carried by joint frame l-1 (after its rotation): local = R^T (x - p), out = R1 local + p1 */
    const mca_pose_t *f0 = &k0.frame[l - 1], *f1 = &k1.frame[l - 1];
    double d[3], loc[3];
    mca_v3_sub(d, x, f0->p);
    for (int i = 0; i < 3; i++) {
        loc[i] = f0->R[0][i] * d[0] + f0->R[1][i] * d[1] + f0->R[2][i] * d[2];
    }
    for (int i = 0; i < 3; i++) {
        out[i] = f1->p[i] + f1->R[i][0] * loc[0] + f1->R[i][1] * loc[1] + f1->R[i][2] * loc[2];
    }
}

static void test_collision_rows_fd(void **state) {
    (void)state;
    static mca_chain_t ch[2];
    load_pa10(&ch[0]);
    load_pa10(&ch[1]);
    const double xyz[3] = {0.45, -0.5, 0.0}, rpy[3] = {0, 0, 0};
    mca_chain_set_base(&ch[1], xyz, rpy);
    const double q0[8] = {0.1, 0.7, 0.2, -1.4, 0.3, 0.6, -0.2, 0.7};
    const double q1[8] = {-1.5, -0.8, 0.1, 1.5, 0.1, -0.7, 0.2, -0.8};
    mca_kin_t kin[2];
    assert_int_equal(mca_fk(&ch[0], q0, &kin[0]), MCA_OK);
    assert_int_equal(mca_fk(&ch[1], q1, &kin[1]), MCA_OK);
    /* critical points: a made-up P on link 5 of arm 0 (a point of its segment) and E nearby */
    static mca_link_critical_t crit[MCA_MAX_ARMS][MCA_MAX_LINKS];
    memset(crit, 0, sizeof crit);
    const int L = 5;
    double P[3], E[3];
    mca_v3_axpy(P, kin[0].point[L], 0.3,
                (double[3]){kin[0].point[L + 1][0] - kin[0].point[L][0],
                            kin[0].point[L + 1][1] - kin[0].point[L][1],
                            kin[0].point[L + 1][2] - kin[0].point[L][2]});
    const double off[3] = {0.05, -0.06, 0.02};
    mca_v3_add(E, P, off);
    crit[0][L].valid = 1;
    crit[0][L].d = 0.08;
    mca_v3_set(crit[0][L].p, P);
    mca_v3_set(crit[0][L].e, E);
    const mca_chain_t *chains[2] = {&ch[0], &ch[1]};
    const double *qs[2] = {q0, q1};
    double rd[2][3], rdd[2][3] = {{0, 0, 0}, {0, 0, 0}};
    mca_v3_set(rd[0], kin[0].ee);
    mca_v3_set(rd[1], kin[1].ee);
    static mca_qp_t qp;
    mca_scheme_state_t st;
    mca_scheme_params_t sp;
    mca_scheme_info_t si;
    for (int form = 0; form < 2; form++) {
        mca_scheme_default_params(&sp);
        sp.form = form ? MCA_FORM_NORMAL : MCA_FORM_COMPONENTWISE;
        sp.v_floor = 0.1;
        mca_scheme_state_reset(&st);
        assert_int_equal(
            mca_scheme_assemble(&sp, 2, chains, kin, qs, (const double(*)[3])rd, (const double(*)[3])rdd,
                                (const mca_link_critical_t(*)[MCA_MAX_LINKS])crit, NULL, &st, &qp, &si),
            MCA_OK);
        const int rpl = form ? 1 : 3;
        assert_int_equal(si.rows_per_link, rpl);
        assert_int_equal(qp.n, 16);
        assert_int_equal(qp.n_eq, 6);
        assert_int_equal(qp.n_ineq, rpl * 18); /* fixed: 9 links per arm, whatever is active */
        assert_int_equal(si.active_rows, rpl);
        const double s = mca_brake_s(0.08, sp.d1, sp.d2);
        assert_true(fabs(si.brake - s) < 1e-15);
        const int r0 = si.row_off[0] + rpl * L;
        /* every other row inactive: zero row, bound = big */
        for (int i = 0; i < qp.n_ineq; i++) {
            if (i >= r0 && i < r0 + rpl) {
                continue;
            }
            assert_true(qp.beta[i] == sp.big);
            for (int j = 0; j < qp.n; j++) {
                assert_true(qp.U[i][j] == 0.0);
            }
        }
        /* row(s) vs central finite differences of the moved point P */
        const double h = 1e-6;
        double r_pe[3];
        mca_v3_sub(r_pe, E, P);
        const double nrm = mca_v3_norm(r_pe);
        for (int j = 0; j < 8; j++) {
            double qp_[8], qm[8], pp[3], pm[3], v[3];
            memcpy(qp_, q0, sizeof qp_);
            memcpy(qm, q0, sizeof qm);
            qp_[j] += h;
            qm[j] -= h;
            moved_point(&ch[0], q0, qp_, L, P, pp);
            moved_point(&ch[0], q0, qm, L, P, pm);
            for (int i = 0; i < 3; i++) {
                v[i] = (pp[i] - pm[i]) / (2 * h);
            }
            if (form) {
                assert_true(fabs(qp.U[r0][j] - mca_v3_dot(r_pe, v) / nrm) < 1e-7);
            } else {
                for (int i = 0; i < 3; i++) {
                    assert_true(fabs(qp.U[r0 + i][j] - r_pe[i] * v[i]) < 1e-7);
                }
            }
            /* arm 1's columns untouched by arm 0's rows */
            for (int i = 0; i < rpl; i++) {
                assert_true(qp.U[r0 + i][8 + j] == 0.0);
            }
        }
        if (form) {
            assert_true(fabs(qp.beta[r0] - s * sp.v_normal) < 1e-15);
        } else {
            /* entered the band at rest (phi_prev NULL): captured 0, bound = S(d) v_floor |r_i| */
            for (int i = 0; i < 3; i++) {
                assert_true(fabs(qp.beta[r0 + i] - s * sp.v_floor * fabs(r_pe[i])) < 1e-15);
            }
        }
        /* equality rows: J_ee and alpha = rdot + K (r_d - r) = 0 here */
        double Je[3][MCA_MAX_DOF];
        assert_int_equal(mca_jacobian_ee(&kin[1], Je), MCA_OK);
        for (int i = 0; i < 3; i++) {
            assert_true(fabs(qp.alpha[3 + i]) < 1e-15);
            for (int j = 0; j < 8; j++) {
                assert_true(qp.G[3 + i][8 + j] == Je[i][j]);
                assert_true(qp.G[i][8 + j] == 0.0);
            }
        }
    }
    /* componentwise capture: entering the band with a velocity keeps max(r <> J qdot, 0), frozen */
    mca_scheme_default_params(&sp);
    sp.form = MCA_FORM_COMPONENTWISE;
    mca_scheme_state_reset(&st);
    double phi[16] = {0};
    phi[1] = 0.3;
    phi[3] = -0.2;
    assert_int_equal(
        mca_scheme_assemble(&sp, 2, chains, kin, qs, (const double(*)[3])rd, (const double(*)[3])rdd,
                            (const mca_link_critical_t(*)[MCA_MAX_LINKS])crit, phi, &st, &qp, &si),
        MCA_OK);
    const int r0 = si.row_off[0] + 3 * L;
    const double s = mca_brake_s(0.08, sp.d1, sp.d2);
    double cap[3];
    for (int i = 0; i < 3; i++) {
        double v = 0.0;
        for (int j = 0; j < 8; j++) {
            v += qp.U[r0 + i][j] * phi[j];
        }
        cap[i] = fmax(v, 0.0);
        assert_true(fabs(qp.beta[r0 + i] - s * cap[i]) < 1e-12);
    }
    assert_true(cap[0] + cap[1] + cap[2] > 0.0);
    /* next tick, other velocity, still inside: same captured rates */
    double phi2[16] = {0};
    assert_int_equal(
        mca_scheme_assemble(&sp, 2, chains, kin, qs, (const double(*)[3])rd, (const double(*)[3])rdd,
                            (const mca_link_critical_t(*)[MCA_MAX_LINKS])crit, phi2, &st, &qp, &si),
        MCA_OK);
    for (int i = 0; i < 3; i++) {
        assert_true(fabs(qp.beta[r0 + i] - s * cap[i]) < 1e-12);
    }
    /* MVN: no inequality rows at all */
    sp.collision = 0;
    assert_int_equal(mca_scheme_assemble(&sp, 2, chains, kin, qs, (const double(*)[3])rd,
                                         (const double(*)[3])rdd, NULL, NULL, &st, &qp, &si),
                     MCA_OK);
    assert_int_equal(qp.n_ineq, 0);
}

/* ------------------------------------------------------------------ APF (40)-(46) */

static void test_apf(void **state) {
    (void)state;
    mca_apf_params_t p;
    mca_apf_default_params(&p);
    assert_true(p.k_pos == 100 && p.d_pos == 0.1 && p.k_vel == 5 && p.d_vel == 0.1 && p.rho == 0.8 &&
                p.d == 0.12 && p.v_rep_max == 0.001 && p.theta == 1);
    /* (43) */
    assert_true(fabs(mca_apf_rep_speed(&p, 0.0) - 0.0005) < 1e-18);
    assert_true(fabs(mca_apf_rep_speed(&p, 0.12) - 0.001 / (1.0 + exp(2.0))) < 1e-18);
    /* attractive velocity satisfies V = rho (K_P e + D_P n.(S_G - V)) n + (1 - rho) K_V (S_G - V) */
    const double ee[3] = {0.1, 0.2, 0.3}, goal[3] = {0.11, 0.19, 0.305}, gv[3] = {0.05, -0.1, 0.02};
    double v[3], e[3];
    mca_apf_attractive(&p, ee, goal, gv, v);
    mca_v3_sub(e, goal, ee);
    const double ep = mca_v3_norm(e);
    double n[3] = {e[0] / ep, e[1] / ep, e[2] / ep}, sv[3];
    mca_v3_sub(sv, gv, v);
    const double dp = p.k_pos * ep + p.d_pos * mca_v3_dot(n, sv);
    for (int i = 0; i < 3; i++) {
        const double rhs = p.rho * dp * n[i] + (1.0 - p.rho) * p.k_vel * sv[i];
        assert_true(fabs(v[i] - rhs) < 1e-12);
    }
    /* zero error, zero goal velocity: zero */
    mca_apf_attractive(&p, ee, ee, (double[3]){0, 0, 0}, v);
    assert_true(v[0] == 0.0 && v[1] == 0.0 && v[2] == 0.0);
    /* pseudoinverse: J J^+ w = w, and J^+ w is the minimum-norm solution (in the row space of J) */
    double J[3][MCA_MAX_DOF] = {{1, 2, 0, 1, 0, 0, 0, 0}, {0, 1, 1, 0, 2, 0, 0, 0}, {1, 0, 0, 1, 1, 3, 0, 0}};
    const double w[3] = {0.3, -0.2, 0.5};
    double qd[MCA_MAX_DOF];
    assert_int_equal(mca_apf_pinv_apply(J, 6, 0.0, w, qd), MCA_OK);
    for (int i = 0; i < 3; i++) {
        double s = 0.0;
        for (int j = 0; j < 6; j++) {
            s += J[i][j] * qd[j];
        }
        assert_true(fabs(s - w[i]) < 1e-12);
    }
    double Js[3][MCA_MAX_DOF] = {
        {1, 0, 0, 0, 0, 0, 0, 0}, {2, 0, 0, 0, 0, 0, 0, 0}, {3, 0, 0, 0, 0, 0, 0, 0}};
    assert_int_equal(mca_apf_pinv_apply(Js, 6, 0.0, w, qd), MCA_EINFEASIBLE);
}

/* ------------------------------------------------------------------ paths */

static void test_paths(void **state) {
    (void)state;
    mca_path_t c;
    memset(&c, 0, sizeof c);
    c.kind = MCA_PATH_CIRCLE;
    c.relative = 1;
    c.radius = 0.2;
    c.period = 10.0;
    c.turns = 1.0;
    c.u[0] = 1.0;
    c.v[1] = 0.5;
    c.v[2] = sqrt(0.75);
    const double a[3] = {0.3, 0.1, 1.0};
    mca_path_anchor(&c, a);
    double r[3], rd[3], r1[3], r2[3], tmp[3];
    mca_path_eval(&c, 0.0, r, rd);
    assert_true(mca_v3_dist(r, a) < 1e-15 && mca_v3_norm(rd) == 0.0);
    mca_path_eval(&c, 10.0, r, rd);
    assert_true(mca_v3_dist(r, a) < 1e-12 && mca_v3_norm(rd) < 1e-12);
    /* halfway: opposite side of the circle, 2R away */
    mca_path_eval(&c, 5.0, r, rd);
    assert_true(fabs(mca_v3_dist(r, a) - 0.4) < 1e-12);
    /* radius stays 0.2 from the centre, velocity = finite difference */
    const double ctr[3] = {a[0] - 0.2, a[1], a[2]};
    for (double t = 0.3; t < 10.0; t += 0.77) {
        mca_path_eval(&c, t, r, rd);
        assert_true(fabs(mca_v3_dist(r, ctr) - 0.2) < 1e-12);
        mca_path_eval(&c, t + 1e-6, r1, tmp);
        mca_path_eval(&c, t - 1e-6, r2, tmp);
        for (int i = 0; i < 3; i++) {
            assert_true(fabs((r1[i] - r2[i]) / 2e-6 - rd[i]) < 1e-7);
        }
    }
    /* waypoints: starts at the anchor, quintic per segment, ends at rest at the last point */
    mca_path_t w;
    memset(&w, 0, sizeof w);
    w.kind = MCA_PATH_WAYPOINTS;
    w.relative = 0;
    w.n_points = 3;
    w.p[1][0] = 1.0;
    w.p[2][0] = 1.0;
    w.p[2][1] = 2.0;
    w.dur[0] = 2.0;
    w.dur[1] = 4.0;
    const double zero[3] = {0, 0, 0};
    mca_path_anchor(&w, zero);
    assert_true(fabs(mca_path_end_time(&w) - 6.0) < 1e-15);
    mca_path_eval(&w, 1.0, r, rd); /* mid first segment: h(1/2) = 1/2, hdot = 30/16 / T */
    assert_true(fabs(r[0] - 0.5) < 1e-15 && fabs(rd[0] - 1.875 / 2.0) < 1e-12);
    mca_path_eval(&w, 2.0, r, rd);
    assert_true(fabs(r[0] - 1.0) < 1e-15 && mca_v3_norm(rd) < 1e-15);
    mca_path_eval(&w, 9.0, r, rd);
    assert_true(r[0] == 1.0 && r[1] == 2.0 && mca_v3_norm(rd) == 0.0);
    for (double t = 0.1; t < 6.0; t += 0.37) {
        mca_path_eval(&w, t, r, rd);
        mca_path_eval(&w, t + 1e-6, r1, tmp);
        mca_path_eval(&w, t - 1e-6, r2, tmp);
        for (int i = 0; i < 3; i++) {
            assert_true(fabs((r1[i] - r2[i]) / 2e-6 - rd[i]) < 1e-7);
        }
    }
    assert_int_equal(mca_path_eval(&w, NAN, r, rd), MCA_EINVAL);
}

/* ------------------------------------------------------------------ scenario files */

static const char *write_tmp(const char *name, const char *text) {
    static char path[256];
    snprintf(path, sizeof path, "/tmp/mca_scheme_test_%d_%s.yaml", (int)getpid(), name);
    FILE *f = fopen(path, "w");
    assert_non_null(f);
    fputs(text, f);
    fclose(f);
    return path;
}

static void test_scenario_files(void **state) {
    (void)state;
    static mca_scenario_t s;
    char err[1024];
    const char *files[] = {"cross_circles.yaml", "hui.yaml", "cup_stacking.yaml", "negative.yaml"};
    for (int i = 0; i < 4; i++) {
        char p[512];
        snprintf(p, sizeof p, SCN("%s"), files[i]);
        assert_int_equal(mca_scenario_load(p, &s, err, sizeof err), MCA_OK);
        assert_int_equal(s.n_arms, 2);
        assert_true(s.duration > 0.0);
    }
    snprintf(err, sizeof err, "%s", SCN("cross_circles.yaml"));
    assert_int_equal(mca_scenario_load(err, &s, err, sizeof err), MCA_OK);
    assert_true(s.params.d1 == 0.05 && s.params.d2 == 0.12 && s.arm[0].n_q0 == 8);
    assert_true(fabs(s.arm[0].q0[1] - M_PI / 4) < 1e-15 && fabs(s.arm[1].q0[0] + M_PI / 2) < 1e-15);
    assert_int_equal(s.arm[0].path.kind, MCA_PATH_CIRCLE);
    assert_true(fabs(mca_v3_dot(s.arm[0].path.u, s.arm[0].path.v)) < 1e-15);
    /* slope pi/3 to the xy plane: the circle plane's normal makes pi/3 with z */
    double nrm[3];
    mca_v3_cross(nrm, s.arm[0].path.u, s.arm[0].path.v);
    assert_true(fabs(fabs(nrm[2]) - 0.5) < 1e-12);

    /* missing file */
    assert_int_equal(mca_scenario_load("/nonexistent/x.yaml", &s, err, sizeof err), MCA_ENOENT);
    assert_non_null(strstr(err, "/nonexistent/x.yaml"));
    /* unknown key: libcyaml names it with its line */
    const char *base = "name: t\nduration: 1\narms:\n  - name: a\n    urdf: " MCA_SOURCE_DIR
                       "/config/robots/pa10plus.urdf\n    base_xyz: [0, 0, 0]\n"
                       "    q0: [0]\n    path:\n      kind: hold\n";
    /* a URDF that is not there: named at load, with its line (the cell's check, shared) */
    {
        char nourdf[512];
        snprintf(nourdf, sizeof nourdf,
                 "name: t\nduration: 1\narms:\n  - name: a\n    base_xyz: [0, 0, 0]\n    urdf: nothere.urdf\n"
                 "    q0: [0]\n    path:\n      kind: hold\n");
        const char *np = write_tmp("nourdf", nourdf);
        assert_int_equal(mca_scenario_load(np, &s, err, sizeof err), MCA_ENOENT);
        char want_u[300];
        snprintf(want_u, sizeof want_u, "%s:6: arms[0].urdf: file '", np);
        if (strncmp(err, want_u, strlen(want_u)) != 0 || !strstr(err, "nothere.urdf' not found")) {
            fail_msg("got '%s', want '%s...nothere.urdf' not found'", err, want_u);
        }
        remove(np);
    }
    char buf[1024];
    snprintf(buf, sizeof buf, "%s    bogus: 3\n", base);
    const char *p = write_tmp("unknown", buf);
    assert_int_equal(mca_scenario_load(p, &s, err, sizeof err), MCA_EPARSE);
    {
        /* the key's own line and its path, as the cell loader names it */
        char want_key[300];
        snprintf(want_key, sizeof want_key, "%s:10: arms[0].bogus: Unexpected key: bogus", p);
        if (strncmp(err, want_key, strlen(want_key)) != 0) {
            fail_msg("got '%s', want '%s...'", err, want_key);
        }
    }
    remove(p);
    /* bad enum value */
    snprintf(buf, sizeof buf, "%s", base);
    char *k = strstr(buf, "kind: hold");
    memcpy(k, "kind: oval", 10);
    p = write_tmp("enum", buf);
    assert_int_equal(mca_scenario_load(p, &s, err, sizeof err), MCA_EPARSE);
    {
        char want_kind[300];
        snprintf(want_kind, sizeof want_kind, "%s:9:13: arms[0].path.kind: ", p);
        if (strncmp(err, want_kind, strlen(want_kind)) != 0) {
            fail_msg("got '%s', want '%s...'", err, want_kind);
        }
    }
    assert_non_null(strstr(err, "oval"));
    remove(p);
    /* semantic error: d1 >= d2, message names file, line and field */
    snprintf(buf, sizeof buf, "d1: 0.2\nd2: 0.1\n%s", base);
    p = write_tmp("d1d2", buf);
    assert_int_equal(mca_scenario_load(p, &s, err, sizeof err), MCA_ECONFIG);
    char want[300];
    snprintf(want, sizeof want, "%s:1: d1/d2: ", p); /* d1's line (test_scenario_marks.c: every error) */
    assert_memory_equal(err, want, strlen(want));
    remove(p);
    /* waypoints without matching durations */
    snprintf(buf, sizeof buf,
             "name: t\nduration: 1\narms:\n  - name: a\n    urdf: " MCA_SOURCE_DIR
             "/config/robots/pa10plus.urdf\n    base_xyz: [0, 0, 0]\n    q0: [0]\n"
             "    path:\n      kind: waypoints\n      points:\n        - [0, 0, 0]\n        - [1, 0, 0]\n"
             "      durations: [1]\n");
    p = write_tmp("dur", buf);
    assert_int_equal(mca_scenario_load(p, &s, err, sizeof err), MCA_ECONFIG);
    assert_non_null(strstr(err, "durations"));
    snprintf(want, sizeof want, "%s:13: arms[0].path.durations: ", p); /* the line of "durations:" */
    assert_memory_equal(err, want, strlen(want));
    remove(p);
    /* circle without a radius */
    snprintf(buf, sizeof buf, "%s", base);
    k = strstr(buf, "kind: hold");
    snprintf(k, sizeof buf - (size_t)(k - buf), "kind: circle\n      period: 1\n");
    p = write_tmp("circle", buf);
    assert_int_equal(mca_scenario_load(p, &s, err, sizeof err), MCA_ECONFIG);
    assert_non_null(strstr(err, "radius"));
    remove(p);
    /* q0 count must match the URDF at config time */
    static mca_controller_config_t cfg;
    snprintf(buf, sizeof buf, "%s", SCN("cross_circles.yaml"));
    assert_int_equal(mca_scenario_load(buf, &s, err, sizeof err), MCA_OK);
    s.arm[1].n_q0 = 7;
    assert_int_equal(mca_controller_config_from_scenario(&cfg, &s, MCA_SCHEME_MCA, err, sizeof err),
                     MCA_EINVAL);
    assert_non_null(strstr(err, "q0"));
}

/* ------------------------------------------------------------------ the opaque controller, the stream law */

/* The state's storage as mca/controller.h states it (within its bound, create checks size and alignment),
 * and the streamed targets' law against its arithmetic: a twist as it is, a pose at gain x the gap from the
 * reference, nothing before the paths are anchored, zero for a hold or a non-finite target, capped. */
static void test_controller_stream_law(void **state) {
    (void)state;
    static mca_scenario_t s;
    static mca_controller_config_t cfg;
    char err[512];
    assert_int_equal(mca_scenario_load(SCN("cross_circles.yaml"), &s, err, sizeof err), MCA_OK);
    assert_int_equal(mca_controller_config_from_scenario(&cfg, &s, MCA_SCHEME_MCA, err, sizeof err), MCA_OK);
    cfg.path[0].kind = MCA_PATH_STREAM; /* arm 0 streamed, arm 1 keeps its circle */
    for (int i = 0; i < 3; i++) {
        cfg.path[0].box_lo[i] = -10.0;
        cfg.path[0].box_hi[i] = 10.0;
    }
    const size_t size = mca_controller_size();
    assert_true(size <= MCA_CONTROLLER_SIZE_MAX && size > MCA_CONTROLLER_SIZE_MAX / 10 * 9);
    unsigned char *mem = malloc(size + 16);
    assert_non_null(mem);
    mca_controller_t *c = (mca_controller_t *)mem;
    assert_int_equal(mca_controller_create(mem, size - 1, &cfg, &c), MCA_EINVAL);
    assert_null(c);
    assert_int_equal(mca_controller_create(mem + 1, size, &cfg, &c), MCA_EINVAL);
    assert_int_equal(mca_controller_create(mem, size, &cfg, &c), MCA_OK);
    assert_ptr_equal(c, mem);
    const mca_path_t *p0 = &mca_controller_get_config(c)->path[0];
    const mca_stream_law_t law = {.pose_gain = 2.0, .max_speed = 0.5};
    const double twist[3] = {0.1, -0.2, 0.05}, fast[3] = {0.3, 0.4, 1.2}, bad[3] = {0.1, NAN, 0.0};
    const double far[3] = {5.0, 5.0, 5.0};
    /* before the first tick: a pose holds (no reference to start from), a twist is taken as it is */
    assert_int_equal(mca_controller_started(c), 0);
    assert_int_equal(mca_controller_stream_target(c, 0, MCA_STREAM_TWIST, twist, &law), MCA_OK);
    assert_memory_equal(p0->stream_v, twist, sizeof twist);
    assert_int_equal(mca_controller_stream_target(c, 0, MCA_STREAM_POSE, far, &law), MCA_OK);
    assert_true(p0->stream_v[0] == 0.0 && p0->stream_v[1] == 0.0 && p0->stream_v[2] == 0.0);
    /* a twist beyond max_speed: its direction at max_speed (|(0.3, 0.4, 1.2)| = 1.3) */
    assert_int_equal(mca_controller_stream_target(c, 0, MCA_STREAM_TWIST, fast, &law), MCA_OK);
    for (int i = 0; i < 3; i++) {
        assert_true(fabs(p0->stream_v[i] - fast[i] * 0.5 / 1.3) < 1e-14);
    }
    assert_int_equal(mca_controller_stream_target(c, 0, MCA_STREAM_TWIST, bad, &law), MCA_OK);
    assert_true(p0->stream_v[0] == 0.0 && p0->stream_v[1] == 0.0 && p0->stream_v[2] == 0.0);
    assert_int_equal(mca_controller_stream_target(c, 0, MCA_STREAM_TWIST, twist, &law), MCA_OK);
    assert_int_equal(mca_controller_stream_target(c, 0, MCA_STREAM_HOLD, NULL, &law), MCA_OK);
    assert_true(p0->stream_v[0] == 0.0 && p0->stream_v[1] == 0.0 && p0->stream_v[2] == 0.0);
    /* bad calls: no law, no target, not a stream, no such arm */
    assert_int_equal(mca_controller_stream_target(c, 0, MCA_STREAM_TWIST, twist, NULL), MCA_EINVAL);
    assert_int_equal(mca_controller_stream_target(c, 0, MCA_STREAM_POSE, NULL, &law), MCA_EINVAL);
    assert_int_equal(mca_controller_stream_target(c, 1, MCA_STREAM_TWIST, twist, &law), MCA_EINVAL);
    assert_int_equal(mca_controller_stream_target(c, 2, MCA_STREAM_TWIST, twist, &law), MCA_EINVAL);
    /* after the first tick (the reference anchored at the tool tip): a pose at gain x the gap */
    double q[2][MCA_MAX_DOF], qd[2][MCA_MAX_DOF];
    memcpy(q[0], s.arm[0].q0, sizeof q[0]);
    memcpy(q[1], s.arm[1].q0, sizeof q[1]);
    const double *qs[MCA_MAX_ARMS] = {q[0], q[1]};
    double *qds[MCA_MAX_ARMS] = {qd[0], qd[1]};
    mca_tick_info_t info;
    assert_int_equal(mca_controller_tick(c, 0.0, qs, qds, &info), MCA_OK);
    assert_int_equal(mca_controller_started(c), 1);
    double r[3], near[3];
    memcpy(r, p0->stream_r, sizeof r);
    assert_true(mca_v3_dist(r, mca_controller_kin(c, 0)->ee) < 1e-12);
    near[0] = r[0] + 0.01;
    near[1] = r[1] - 0.02;
    near[2] = r[2];
    assert_int_equal(mca_controller_stream_target(c, 0, MCA_STREAM_POSE, near, &law), MCA_OK);
    for (int i = 0; i < 3; i++) {
        assert_true(fabs(p0->stream_v[i] - 2.0 * (near[i] - r[i])) < 1e-15);
    }
    assert_int_equal(mca_controller_stream_target(c, 0, MCA_STREAM_POSE, far, &law), MCA_OK);
    assert_true(fabs(mca_v3_norm(p0->stream_v) - 0.5) < 1e-12);
    /* the budget's setter */
    assert_int_equal(mca_controller_set_pdnn_budget(c, -1), MCA_EINVAL);
    assert_int_equal(mca_controller_set_pdnn_budget(c, 250000), MCA_OK);
    assert_int_equal(mca_controller_get_config(c)->pdnn_budget_ns, 250000);
    free(mem);
}

/* ------------------------------------------------------------------ controller faults */

static void test_controller_faults(void **state) {
    (void)state;
    static mca_scenario_t s;
    static mca_controller_config_t cfg;
    char err[512];
    assert_int_equal(mca_scenario_load(SCN("cross_circles.yaml"), &s, err, sizeof err), MCA_OK);
    assert_int_equal(mca_controller_config_from_scenario(&cfg, &s, MCA_SCHEME_MCA, err, sizeof err), MCA_OK);
    mca_controller_t *c = malloc(mca_controller_size());
    assert_non_null(c);
    assert_int_equal(mca_controller_init(c, &cfg), MCA_OK);
    double q[2][MCA_MAX_DOF], qd[2][MCA_MAX_DOF];
    memcpy(q[0], s.arm[0].q0, sizeof q[0]);
    memcpy(q[1], s.arm[1].q0, sizeof q[1]);
    const double *qs[MCA_MAX_ARMS] = {q[0], q[1]};
    double *qds[MCA_MAX_ARMS] = {qd[0], qd[1]};
    mca_tick_info_t info;
    /* a normal tick */
    assert_int_equal(mca_controller_tick(c, 0.0, qs, qds, &info), MCA_OK);
    assert_int_equal(info.fault, MCA_CTRL_FAULT_NONE);
    assert_true(info.min_distance > 0.05 && info.min_distance < 0.12);
    assert_true(info.brake < 1.0 && info.active_rows > 0);
    assert_true(info.eq_residual < 1e-6 && info.pdnn_converged);
    assert_true(info.compute_ns > 0);
    for (int i = 0; i < 20; i++) {
        assert_int_equal(mca_controller_tick(c, 0.001 * (i + 1), qs, qds, &info), MCA_OK);
    }
    /* NaN joint: zero command, named fault, latched */
    q[1][3] = NAN;
    qd[0][0] = 123.0;
    assert_int_equal(mca_controller_tick(c, 0.1, qs, qds, &info), MCA_EFAULT);
    assert_int_equal(info.fault, MCA_CTRL_FAULT_NAN);
    assert_string_equal(mca_ctrl_fault_name(info.fault), "nan");
    char why[192];
    assert_int_equal(info.fault_why.why, MCA_WHY_NONFINITE_Q);
    assert_int_equal(info.fault_why.i[0], 1);
    assert_string_equal(mca_ctrl_fault_format(&info.fault_why, why, sizeof why),
                        "arm 1: non-finite joint position");
    for (int a = 0; a < 2; a++) {
        for (int j = 0; j < 8; j++) {
            assert_true(qd[a][j] == 0.0);
        }
    }
    q[1][3] = s.arm[1].q0[3];
    assert_int_equal(mca_controller_tick(c, 0.101, qs, qds, &info), MCA_EFAULT);
    assert_int_equal(info.fault, MCA_CTRL_FAULT_NAN);                /* latched */
    assert_true(info.min_distance > 0.0 && info.min_distance < 1.0); /* distances still reported */
    mca_controller_clear_fault(c);
    assert_int_equal(mca_controller_tick(c, 0.102, qs, qds, &info), MCA_OK);
    /* arms overlapping: distance below d1 -> fault, zero command */
    static mca_controller_config_t cfg2;
    cfg2 = cfg;
    const double xyz[3] = {0.1, 0.0, 0.0}, rpy[3] = {0, 0, 0};
    mca_chain_set_base(&cfg2.chain[1], xyz, rpy);
    assert_int_equal(mca_controller_init(c, &cfg2), MCA_OK);
    assert_int_equal(mca_controller_tick(c, 0.0, qs, qds, &info), MCA_EFAULT);
    assert_int_equal(info.fault, MCA_CTRL_FAULT_DISTANCE);
    assert_string_equal(mca_ctrl_fault_name(info.fault), "distance-below-d1");
    /* the baselines never fault on distance (they are run to show the collision) */
    cfg2.scheme = MCA_SCHEME_MVN;
    cfg2.fault_distance = 0;
    assert_int_equal(mca_controller_init(c, &cfg2), MCA_OK);
    const int rc_mvn = mca_controller_tick(c, 0.0, qs, qds, &info);
    if (rc_mvn != MCA_OK) {
        char why[192];
        print_message("MVN tick: %s (%s) steps %d residual %g\n", mca_ctrl_fault_name(info.fault),
                      mca_ctrl_fault_format(&info.fault_why, why, sizeof why), info.pdnn_steps,
                      info.pdnn_residual);
    }
    assert_int_equal(rc_mvn, MCA_OK);
    assert_true(info.min_distance < 0.05);
    /* a joint far beyond its limit: contradicting bounds */
    assert_int_equal(mca_controller_init(c, &cfg), MCA_OK);
    q[0][1] = 3.0; /* S2 limit +-1.64 rad */
    assert_int_equal(mca_controller_tick(c, 0.0, qs, qds, &info), MCA_EFAULT);
    assert_int_equal(info.fault, MCA_CTRL_FAULT_INFEASIBLE);
    /* bad config */
    cfg2 = cfg;
    cfg2.sp.d1 = 0.2;
    assert_int_equal(mca_controller_init(c, &cfg2), MCA_EINVAL);
    assert_int_equal(mca_controller_tick(c, 0.0, NULL, qds, &info), MCA_EINVAL);
    free(c);
}

/* One arm (no pairs: no distance, rows inactive) and three arms (per link the closest of the two others). */
static void test_controller_n_arms(void **state) {
    (void)state;
    static mca_scenario_t s;
    static mca_controller_config_t cfg;
    char err[512];
    assert_int_equal(mca_scenario_load(SCN("cross_circles.yaml"), &s, err, sizeof err), MCA_OK);
    assert_int_equal(mca_controller_config_from_scenario(&cfg, &s, MCA_SCHEME_MCA, err, sizeof err), MCA_OK);
    mca_controller_t *c = malloc(mca_controller_size());
    assert_non_null(c);
    double q[3][MCA_MAX_DOF], qd[3][MCA_MAX_DOF];
    memcpy(q[0], s.arm[0].q0, sizeof q[0]);
    memcpy(q[1], s.arm[1].q0, sizeof q[1]);
    memcpy(q[2], s.arm[1].q0, sizeof q[2]);
    const double *qs[MCA_MAX_ARMS] = {q[0], q[1], q[2]};
    double *qds[MCA_MAX_ARMS] = {qd[0], qd[1], qd[2]};
    mca_tick_info_t info;
    cfg.n_arms = 1;
    assert_int_equal(mca_controller_init(c, &cfg), MCA_OK);
    for (int k = 0; k < 10; k++) {
        assert_int_equal(mca_controller_tick(c, 0.001 * k, qs, qds, &info), MCA_OK);
    }
    assert_true(isinf(info.min_distance) && info.active_rows == 0 && info.brake == 1.0);
    assert_int_equal(mca_controller_last_qp(c, NULL)->n, 8);
    assert_int_equal(mca_controller_last_qp(c, NULL)->n_ineq, 9);
    /* three arms: the third a copy of the right arm 1.5 m further along -y (far from both) */
    assert_int_equal(mca_controller_config_from_scenario(&cfg, &s, MCA_SCHEME_MCA, err, sizeof err), MCA_OK);
    cfg.n_arms = 3;
    cfg.chain[2] = cfg.chain[1];
    cfg.path[2] = cfg.path[1];
    const double xyz[3] = {0.45, -2.0, 0.0}, rpy[3] = {0, 0, 0};
    mca_chain_set_base(&cfg.chain[2], xyz, rpy);
    assert_int_equal(mca_controller_init(c, &cfg), MCA_OK);
    for (int k = 0; k < 10; k++) {
        assert_int_equal(mca_controller_tick(c, 0.001 * k, qs, qds, &info), MCA_OK);
    }
    assert_int_equal(mca_controller_last_qp(c, NULL)->n, 24);
    assert_int_equal(mca_controller_last_qp(c, NULL)->n_eq, 9);
    assert_int_equal(mca_controller_last_qp(c, NULL)->n_ineq, 27);
    /* the global minimum is still between arms 0 and 1; every link of arm 2 sees arm 1 as its closest */
    assert_true(info.min_distance > 0.05 && info.min_distance < 0.12);
    assert_true(info.min_arm_a == 0 && info.min_arm_b == 1);
    for (int l = 0; l < 9; l++) {
        assert_true(c->crit[2][l].valid && c->crit[2][l].other_arm == 1);
        assert_true(info.link_distance[2][l] > 0.5);
    }
    assert_true(info.eq_residual < 1e-6);
    free(c);
}

/* ------------------------------------------------------------------ mca-ts */

/* Run a scenario under mca-ts with the arms integrated exactly (q += qdot dt); calls back every tick. */
typedef void (*ts_tick_fn)(const mca_controller_t *c, const mca_tick_info_t *info, void *user);

/* An mca-ts config for a scenario, every arm's dec_limit 5 rad/s^2 (the stop bound's). */
static void load_ts(const char *scenario, mca_scenario_t *s, mca_controller_config_t *cfg) {
    char err[512];
    assert_int_equal(mca_scenario_load(scenario, s, err, sizeof err), MCA_OK);
    assert_int_equal(mca_controller_config_from_scenario(cfg, s, MCA_SCHEME_MCA_TS, err, sizeof err), MCA_OK);
    for (int a = 0; a < cfg->n_arms; a++) {
        cfg->ts.dec_limit[a] = 5.0;
    }
}

static void run_ts(const char *scenario, double seconds, ts_tick_fn fn, void *user, mca_tick_info_t *last) {
    static mca_scenario_t s;
    static mca_controller_config_t cfg;
    load_ts(scenario, &s, &cfg);
    mca_controller_t *c = malloc(mca_controller_size());
    assert_non_null(c);
    assert_int_equal(mca_controller_init(c, &cfg), MCA_OK);
    double q[MCA_MAX_ARMS][MCA_MAX_DOF] = {{0}}, qd[MCA_MAX_ARMS][MCA_MAX_DOF] = {{0}};
    const double *qs[MCA_MAX_ARMS];
    double *qds[MCA_MAX_ARMS];
    for (int a = 0; a < MCA_MAX_ARMS; a++) {
        qs[a] = q[a];
        qds[a] = qd[a];
        memcpy(q[a], s.arm[a].q0, sizeof q[a]);
    }
    const long n = lround(seconds / cfg.dt);
    for (long k = 0; k <= n; k++) {
        assert_int_equal(mca_controller_tick(c, k * cfg.dt, qs, qds, last), MCA_OK);
        fn(c, last, user);
        for (int a = 0; a < cfg.n_arms; a++) {
            for (int j = 0; j < cfg.chain[a].dof; j++) {
                q[a][j] += qd[a][j] * cfg.dt;
            }
        }
    }
    free(c);
}

typedef struct ts_seen {
    double min_d, d1, max_stand_still_err;
    int back_off_ticks, backed_off_neg_sigma, qps, zero_in_box;
} ts_seen_t;

/* docs/scheme.md: standing still (qdot = 0, sigma = 0, the slack taking up the feedback term) is a point of
 * every mca-ts QP; check it on the QP of every tick. */
static void check_tick(const mca_controller_t *c, const mca_tick_info_t *info, void *user) {
    ts_seen_t *seen = user;
    seen->min_d = fmin(seen->min_d, info->min_distance);
    const mca_qp_t *qp = mca_controller_last_qp(c, NULL);
    const int na = mca_controller_get_config(c)->n_arms;
    int nj = 0;
    for (int a = 0; a < na; a++) {
        nj += mca_controller_get_config(c)->chain[a].dof;
    }
    assert_int_equal(qp->n, nj + MCA_TS_VARS * na);
    double phi[MCA_QP_MAX_VARS] = {0};
    const double re = 1.0 / sqrt(mca_controller_get_config(c)->ts.w_slack);
    for (int a = 0; a < na; a++) {
        const int o = nj + MCA_TS_VARS * a;
        /* sigma = target + rs u, bounded to [lo, hi] with lo = 0 (running, waiting) or -1 (backing off: then
         * hi = 0, a width of exactly 1; running has hi = sigma_max = 1.5): sigma = 0 is u = ub while backing
         * off, u = lb otherwise, and always inside the bounds */
        assert_true(mca_controller_get_config(c)->ts.sigma_max != 1.0);
        const double rs = 1.0 / c->ts_scale[a]; /* sigma = target + u / m */
        const double u = fabs((qp->ub[o] - qp->lb[o]) * rs - 1.0) < 1e-9 ? qp->ub[o] : qp->lb[o];
        phi[o] = u;
        for (int i = 0; i < 3; i++) {
            /* G phi = alpha with qdot = 0: the slack takes up the rest */
            phi[o + 1 + i] = -(qp->alpha[3 * a + i] - qp->G[3 * a + i][o] * u) / re;
        }
    }
    for (int i = 0; i < qp->n_eq; i++) {
        double r = -qp->alpha[i];
        for (int j = 0; j < qp->n; j++) {
            r += qp->G[i][j] * phi[j];
        }
        seen->max_stand_still_err = fmax(seen->max_stand_still_err, fabs(r));
    }
    for (int i = 0; i < qp->n_ineq; i++) {
        assert_true(qp->beta[i] >= 0.0); /* U 0 = 0 <= beta */
    }
    /* the joint box is the joint limits within dec_limit dt of the last command: zero lies in it whenever the
     * arm is that slow, and then the point above is feasible; otherwise the box alone excludes standing
     * still (the equality never does: any qdot is completed by the slack) */
    int zero_in_box = 1;
    for (int j = 0; j < nj; j++) {
        zero_in_box &= qp->lb[j] <= 0.0 && qp->ub[j] >= 0.0;
    }
    seen->zero_in_box += zero_in_box;
    seen->qps++;
    if (info->deadlock == MCA_DEADLOCK_BACK_OFF) {
        seen->back_off_ticks++;
        seen->backed_off_neg_sigma += info->sigma[info->deadlock_arm] < 0.0;
    }
}

static void test_timescale_stand_still_feasible(void **state) {
    (void)state;
    ts_seen_t seen = {INFINITY, 0, 0, 0, 0, 0, 0};
    mca_tick_info_t last;
    run_ts(SCN("cross_circles.yaml"), 10.5, check_tick, &seen, &last);
    print_message(
        "cross_circles mca-ts: %d QPs (%d with zero in the joint box), |G phi0 - alpha| <= %.2e, min d "
        "%.4f, tau %.3f/%.3f\n",
        seen.qps, seen.zero_in_box, seen.max_stand_still_err, seen.min_d, last.tau[0], last.tau[1]);
    assert_true(seen.zero_in_box > 100);
    assert_true(seen.max_stand_still_err < 1e-9);
    assert_true(seen.min_d >= 0.05);
    assert_int_equal(last.paths_done, 1); /* the clocks caught up with the lag they lost */
    assert_int_equal(last.deadlocks, 0);
}

/* The paper's negative task (tracking and avoidance contradict): mca-ts yields instead of faulting, names
 * the deadlock, and the arm that backs off runs its path backwards while every distance stays >= d1. */
static void test_timescale_deadlock(void **state) {
    (void)state;
    ts_seen_t seen = {INFINITY, 0, 0, 0, 0, 0, 0};
    mca_tick_info_t last;
    run_ts(SCN("negative.yaml"), 12.0, check_tick, &seen, &last);
    print_message("negative mca-ts: min d %.4f, %d deadlocks, %d back-off ticks (%d with sigma < 0)\n",
                  seen.min_d, last.deadlocks, seen.back_off_ticks, seen.backed_off_neg_sigma);
    assert_true(seen.min_d >= 0.05);
    assert_true(seen.max_stand_still_err < 1e-9);
    assert_true(last.deadlocks >= 1);
    assert_true(seen.back_off_ticks > 100);
    assert_true(seen.backed_off_neg_sigma > seen.back_off_ticks / 2);
    assert_int_equal(last.paths_done, 0);
}

/* Independent point-to-segment distance: the foot of o on [a, b] by the clamped projection. */
static double point_seg(const double o[3], const double a[3], const double b[3], double h[3]) {
    double ab[3], ao[3], t = 0.0, l2 = 0.0;
    for (int k = 0; k < 3; k++) {
        ab[k] = b[k] - a[k];
        ao[k] = o[k] - a[k];
        l2 += ab[k] * ab[k];
        t += ab[k] * ao[k];
    }
    t = l2 > 0.0 ? fmin(1.0, fmax(0.0, t / l2)) : 0.0;
    double d2 = 0.0;
    for (int k = 0; k < 3; k++) {
        h[k] = a[k] + t * ab[k];
        d2 += (o[k] - h[k]) * (o[k] - h[k]);
    }
    return sqrt(d2);
}

typedef struct witness_seen {
    int ticks, ends_listed, entries, ends_unbindable;
} witness_seen_t;

/* The fastest point p of arm a can approach anything with the joint speeds of the tick's QP box:
 * sum_j max|qdot_j| |p - o_j| over the joints that move p's link (a second, point-wise computation of what
 * the controller bounds per link). */
static double point_reach(const mca_controller_t *c, int a, int link, const double p[3]) {
    const mca_kin_t *k = mca_controller_kin(c, a);
    const int vo = a == 0 ? 0 : mca_controller_get_config(c)->chain[0].dof;
    double v = 0.0;
    for (int j = 0; j < link; j++) {
        v += fmax(fabs(mca_controller_last_qp(c, NULL)->lb[vo + j]),
                  fabs(mca_controller_last_qp(c, NULL)->ub[vo + j])) *
             mca_v3_dist(p, k->point[j + 1]);
    }
    return v;
}

/* A link's list (row input of mca-ts and braking) has its MCA_NEAR_PAIRS nearest witness pairs that can bind:
 * every end of two links against the other link, nearer than the list's last entry, is listed (or one at
 * the same point and direction, nearer) unless no joint speed in the tick's box moves its point as fast as
 * its row's bound (then the row could not bind: point_reach); every entry lies on both links, at its
 * distance. */
static void check_witnesses(const mca_controller_t *c, const mca_tick_info_t *info, void *user) {
    (void)info;
    witness_seen_t *seen = user;
    if (c->ticks % 25) {
        return;
    }
    seen->ticks++;
    const mca_kin_t *k0 = mca_controller_kin(c, 0), *k1 = mca_controller_kin(c, 1);
    const double *r0 = mca_controller_get_config(c)->chain[0].link_radius,
                 *r1 = mca_controller_get_config(c)->chain[1].link_radius;
    for (int side = 0; side < 2; side++) {
        const mca_kin_t *km = side ? k1 : k0, *ko = side ? k0 : k1;
        const double *rm = side ? r1 : r0, *ro = side ? r0 : r1;
        for (int i = 0; i <= km->dof; i++) {
            const mca_link_critical_t *list = c->near[side][i];
            for (int e = 0; e < MCA_NEAR_PAIRS && list[e].valid; e++) {
                const mca_link_critical_t *w = &list[e];
                double h[3];
                seen->entries++;
                assert_true(point_seg(w->p, km->point[i], km->point[i + 1], h) < 1e-9);
                assert_true(point_seg(w->e, ko->point[w->other_link], ko->point[w->other_link + 1], h) <
                            1e-9);
                assert_true(fabs(mca_v3_dist(w->p, w->e) - rm[i] - ro[w->other_link] - w->d) < 1e-9);
                assert_true(e == 0 || list[e - 1].d <= w->d);
            }
            const int full = list[MCA_NEAR_PAIRS - 1].valid;
            for (int j = 0; j <= ko->dof; j++) {
                for (int end = 0; end < 4; end++) {
                    /* ends 0, 1: this link's ends against link j; 2, 3: link j's ends against this link */
                    double p[3], o[3];
                    const double *src = end < 2 ? km->point[i + end] : ko->point[j + end - 2];
                    const double d = (end < 2 ? point_seg(src, ko->point[j], ko->point[j + 1], o)
                                              : point_seg(src, km->point[i], km->point[i + 1], o)) -
                                     rm[i] - ro[j];
                    mca_v3_set(p, end < 2 ? src : o);
                    if (end >= 2) {
                        mca_v3_set(o, src);
                    }
                    if (full && !(d < list[MCA_NEAR_PAIRS - 1].d - 1e-9)) {
                        continue;
                    }
                    const double bound =
                        mca_scheme_row_bound(
                            &mca_controller_get_config(c)->sp, d,
                            mca_scheme_stop_time(&mca_controller_get_config(c)->chain[side],
                                                 mca_controller_get_config(c)->ts.dec_limit[side])) *
                        mca_scheme_row_share(mca_controller_get_config(c)->ts.priority, side, 1 - side);
                    if (point_reach(c, side, i, p) < bound) {
                        seen->ends_unbindable++;
                        continue;
                    }
                    double n[3];
                    mca_v3_sub(n, o, p);
                    const double nn = mca_v3_norm(n);
                    int found = 0;
                    for (int e = 0; e < MCA_NEAR_PAIRS && list[e].valid && !found; e++) {
                        double m[3];
                        mca_v3_sub(m, list[e].e, list[e].p);
                        const double mn = mca_v3_norm(m);
                        double dn = 0.0;
                        for (int x = 0; x < 3; x++) {
                            const double y = n[x] / nn - m[x] / mn;
                            dn += y * y;
                        }
                        found =
                            list[e].d <= d + 1e-9 && mca_v3_dist(list[e].p, p) < 1e-4 + 1e-9 && dn < 1.01e-8;
                    }
                    assert_true(found);
                    seen->ends_listed++;
                }
            }
        }
    }
}

static void test_near_witnesses(void **state) {
    (void)state;
    witness_seen_t seen = {0, 0, 0, 0};
    mca_tick_info_t last;
    /* cross circles: the arms come to 0.056 m (d1 0.05) and rows bind; far pairs cannot */
    run_ts(SCN("cross_circles.yaml"), 10.0, check_witnesses, &seen, &last);
    print_message("cross_circles mca-ts: %d ticks checked, %d list entries, %d segment ends listed, %d that "
                  "cannot bind left out\n",
                  seen.ticks, seen.entries, seen.ends_listed, seen.ends_unbindable);
    assert_true(seen.ticks > 300);
    assert_true(seen.ends_listed > 100);
    assert_true(seen.ends_unbindable > 1000);
}

/* Every collision row of the last QP and the joint box hold at the command (the controller's phi). */
static void assert_rows_hold(const mca_controller_t *c, double *const qds[MCA_MAX_ARMS], int box) {
    const double *phi;
    const mca_qp_t *qp = mca_controller_last_qp(c, &phi);
    int rows = 0;
    for (int i = 0; i < qp->n_ineq; i++) {
        if (qp->beta[i] < mca_controller_get_config(c)->sp.big) {
            double s = 0.0;
            for (int j = 0; j < qp->n; j++) {
                s += qp->U[i][j] * phi[j];
            }
            assert_true(s <= qp->beta[i] + 1e-9);
            rows++;
        }
    }
    int off = 0;
    for (int a = 0; a < mca_controller_get_config(c)->n_arms; a++) {
        for (int j = 0; j < mca_controller_get_config(c)->chain[a].dof; j++) {
            assert_true(qds[a][j] == phi[off + j]);
            if (box) {
                assert_true(phi[off + j] >= qp->lb[off + j] - 1e-12 &&
                            phi[off + j] <= qp->ub[off + j] + 1e-12);
            }
        }
        off += mca_controller_get_config(c)->chain[a].dof;
    }
    print_message("  %d collision rows hold at the command\n", rows);
}

/* The PDNN's budget: a tick whose solve runs out of its time is no fault. A budget of 1 ns runs
 * out at each block's first clock check (after 16 steps): the first tick of the negative task whose solve
 * needs over 100 steps (mca: its fault at the cap) is repeated with it. mca-ts commands repair_capped's
 * answer, mca the iterate scaled into the rows and the box; both keep every collision row, and the task goes
 * on. A braking tick that runs out of it has no answer and takes the keep-direction fallback. */
static void budget_tick(mca_scheme_kind_t scheme) {
    static mca_scenario_t s;
    static mca_controller_config_t cfg;
    load_ts(SCN("negative.yaml"), &s, &cfg);
    cfg.scheme = scheme;
    cfg.pdnn.no_polish = 1; /* the network's clock checks: with the polish no tick here takes 16 steps */
    mca_controller_t *c = malloc(mca_controller_size()), *b = malloc(mca_controller_size());
    assert_non_null(c);
    assert_non_null(b);
    double q[MCA_MAX_ARMS][MCA_MAX_DOF] = {{0}}, qd[MCA_MAX_ARMS][MCA_MAX_DOF] = {{0}};
    double vl[MCA_MAX_ARMS][MCA_MAX_DOF] = {{0}}, dec[MCA_MAX_ARMS][MCA_MAX_DOF];
    const double *qs[MCA_MAX_ARMS], *vls[MCA_MAX_ARMS], *decs[MCA_MAX_ARMS];
    double *qds[MCA_MAX_ARMS];
    for (int a = 0; a < MCA_MAX_ARMS; a++) {
        qs[a] = q[a];
        qds[a] = qd[a];
        vls[a] = vl[a];
        decs[a] = dec[a];
        memcpy(q[a], s.arm[a].q0, sizeof q[a]);
        for (int j = 0; j < MCA_MAX_DOF; j++) {
            dec[a][j] = 5.0;
        }
    }
    mca_tick_info_t info;
    /* no budget: the first tick whose solve takes more than 16 steps; the controller kept as it was before */
    assert_int_equal(mca_controller_init(c, &cfg), MCA_OK);
    int k_long = -1;
    for (int k = 0; k < 8000 && k_long < 0; k++) {
        mca_controller_copy(b, c);
        mca_controller_tick(c, k * cfg.dt, qs, qds, &info);
        if (info.pdnn_steps > 100 || info.fault) {
            k_long = k;
            break;
        }
        for (int a = 0; a < cfg.n_arms; a++) {
            for (int j = 0; j < cfg.chain[a].dof; j++) {
                vl[a][j] = qd[a][j];
                q[a][j] += qd[a][j] * cfg.dt;
            }
        }
    }
    assert_true(k_long > 0);
    const int full_steps = info.pdnn_steps, full_fault = info.fault;
    /* that tick again with 1 ns: out of time, a repaired command, no fault */
    mca_controller_set_pdnn_budget(b, 1);
    mca_controller_t *r = malloc(mca_controller_size());
    assert_non_null(r);
    mca_controller_copy(r, b); /* for the braking below */
    const int rc = mca_controller_tick(b, k_long * cfg.dt, qs, qds, &info);
    print_message(
        "%s, 1 ns budget: tick %d (%d steps without): rc %d, fault %s, budget hit %d after %d steps, "
        "residual %.2e, eq %.2e\n",
        mca_scheme_name(scheme), k_long, full_steps, rc, mca_ctrl_fault_name(info.fault),
        info.pdnn_budget_hit, info.pdnn_steps, info.pdnn_residual, info.eq_residual);
    assert_int_equal(rc, MCA_OK);
    assert_int_equal(info.fault, MCA_CTRL_FAULT_NONE);
    assert_int_equal(info.pdnn_budget_hit, MCA_BUDGET_TIME);
    assert_true(info.pdnn_steps <= 64 && info.pdnn_steps < full_steps); /* 16 per block and pass */
    assert_true(info.pdnn_residual > cfg.fault_residual); /* a short answer: the repair was needed */
    assert_rows_hold(b, qds, scheme == MCA_SCHEME_MCA);
    /* with the budget back (a stall passed), what the next ticks would have done without it */
    mca_controller_set_pdnn_budget(b, 0);
    int k_next;
    for (k_next = k_long + 1; k_next < k_long + 50; k_next++) {
        for (int a = 0; a < cfg.n_arms; a++) {
            for (int j = 0; j < cfg.chain[a].dof; j++) {
                q[a][j] += qd[a][j] * cfg.dt;
            }
        }
        if (mca_controller_tick(b, k_next * cfg.dt, qs, qds, &info) != MCA_OK) {
            break;
        }
    }
    print_message("  then: %s at tick %d\n", mca_ctrl_fault_name(info.fault), k_next);
    if (full_fault) {
        /* the QP is infeasible: the cap's fault, a tick later */
        assert_int_equal(info.fault, full_fault);
        assert_int_equal(k_next, k_long + 1);
    } else {
        assert_int_equal(k_next, k_long + 50);
    }
    /* braking from there with 1 ns: every tick either converged within 16 steps or took the fallback */
    int fallback = 0;
    for (int k = 0; k < 50; k++) {
        const int brc = mca_controller_brake(r, (k_long + k) * cfg.dt, qs, vls, decs, qds, &info);
        assert_true(brc >= 0);
        assert_true(info.brake_fallback || info.pdnn_steps <= 16);
        fallback += info.brake_fallback;
        for (int a = 0; a < cfg.n_arms; a++) {
            for (int j = 0; j < cfg.chain[a].dof; j++) {
                vl[a][j] = qd[a][j];
            }
        }
    }
    print_message("1 ns budget: %d of 50 braking ticks took the fallback\n", fallback);
    free(r);
    free(b);
    free(c);
}

static void test_pdnn_time_budget(void **state) {
    (void)state;
    budget_tick(MCA_SCHEME_MCA_TS);
    budget_tick(MCA_SCHEME_MCA);
}

/* Run the negative task (Euler) until its first fault or n ticks; counts budget hits. */
static int run_negative(mca_controller_config_t *cfg, const mca_scenario_t *s, int n,
                        mca_tick_info_t *fault_info, int *hits, double *qd_sum) {
    mca_controller_t *c = malloc(mca_controller_size());
    assert_non_null(c);
    assert_int_equal(mca_controller_init(c, cfg), MCA_OK);
    double q[MCA_MAX_ARMS][MCA_MAX_DOF] = {{0}}, qd[MCA_MAX_ARMS][MCA_MAX_DOF] = {{0}};
    const double *qs[MCA_MAX_ARMS];
    double *qds[MCA_MAX_ARMS];
    for (int a = 0; a < MCA_MAX_ARMS; a++) {
        qs[a] = q[a];
        qds[a] = qd[a];
        memcpy(q[a], s->arm[a].q0, sizeof q[a]);
    }
    mca_tick_info_t info;
    int k;
    *hits = 0;
    *qd_sum = 0.0;
    for (k = 0; k < n; k++) {
        if (mca_controller_tick(c, k * cfg->dt, qs, qds, &info) != MCA_OK) {
            *fault_info = info;
            break;
        }
        *hits += info.pdnn_budget_hit != MCA_BUDGET_NONE;
        assert_true(info.pdnn_budget_hit != MCA_BUDGET_TIME); /* no clock here */
        for (int a = 0; a < cfg->n_arms; a++) {
            for (int j = 0; j < cfg->chain[a].dof; j++) {
                q[a][j] += qd[a][j] * cfg->dt;
                *qd_sum += fabs(qd[a][j]);
            }
        }
    }
    free(c);
    return k;
}

/* The step budget: deterministic, below the cap a non-fault event under mca-ts (the same tick
 * twice: the same commands); under the paper's scheme mca the cap stays its limit, so the negative task
 * faults as published (pdnn-not-converged after 2000 steps, at the tick it did without a budget). */
static void test_pdnn_step_budget(void **state) {
    (void)state;
    static mca_scenario_t s;
    static mca_controller_config_t cfg;
    mca_tick_info_t fi;
    int hits, hits2;
    double sum, sum2;
    assert_int_equal(mca_pdnn_budget_steps(0), 0);
    assert_int_equal(mca_pdnn_budget_steps(1), 1);
    assert_int_equal(mca_pdnn_budget_steps(500000), 500000 / MCA_PDNN_STEP_NS);

    load_ts(SCN("negative.yaml"), &s, &cfg);
    cfg.pdnn.no_polish = 1; /* the network's own steps: the polish finishes these QPs at step 0 */
    cfg.pdnn_budget_steps = 100;
    const int n_ts = run_negative(&cfg, &s, 6000, &fi, &hits, &sum);
    const int n_ts2 = run_negative(&cfg, &s, 6000, &fi, &hits2, &sum2);
    print_message("mca-ts, step budget 100: %d ticks, %d out of budget\n", n_ts, hits);
    assert_int_equal(n_ts, 6000); /* no fault */
    assert_true(hits > 0);
    assert_int_equal(n_ts2, n_ts);
    assert_int_equal(hits, hits2);
    assert_true(sum == sum2);

    cfg.scheme = MCA_SCHEME_MCA;
    cfg.pdnn_budget_steps = 0;
    assert_int_equal(mca_controller_step_budget(&cfg), 0);
    const int n0 = run_negative(&cfg, &s, 8000, &fi, &hits, &sum);
    print_message("mca, no budget: fault %s at tick %d after %d steps\n", mca_ctrl_fault_name(fi.fault), n0,
                  fi.pdnn_steps);
    assert_true(n0 < 8000);
    assert_int_equal(fi.fault, MCA_CTRL_FAULT_NOT_CONVERGED);
    assert_int_equal(fi.pdnn_steps, 2000);
    cfg.pdnn_budget_steps = mca_pdnn_budget_steps(500000); /* mcad's and mca-sim's default */
    assert_int_equal(mca_controller_step_budget(&cfg), 0);
    const int n1 = run_negative(&cfg, &s, 8000, &fi, &hits, &sum2);
    assert_int_equal(n1, n0);
    assert_int_equal(fi.fault, MCA_CTRL_FAULT_NOT_CONVERGED);
    assert_int_equal(fi.pdnn_steps, 2000);
    assert_int_equal(fi.pdnn_budget_hit, MCA_BUDGET_NONE);
    assert_int_equal(hits, 0);
    assert_true(sum == sum2);
}

/* Two parallel rows of one arm (the same point and direction, two distances) are one row, the tighter. */
static void test_near_rows_parallel(void **state) {
    (void)state;
    static mca_chain_t ch;
    char err[256];
    assert_int_equal(mca_chain_load_urdf(&ch, PA10, NULL, err, sizeof err), MCA_OK);
    const mca_chain_t *chains[2] = {&ch, &ch};
    mca_kin_t kin[2];
    const double q[MCA_MAX_DOF] = {0.1, 0.4, 0.0, 0.8, 0.0, 0.3, 0.0, 0.0};
    assert_int_equal(mca_fk(&ch, q, &kin[0]), MCA_OK);
    kin[1] = kin[0];
    static mca_qp_t qp;
    mca_scheme_params_t p;
    mca_scheme_default_params(&p);
    mca_scheme_info_t si = {0};
    si.var_off[1] = ch.dof;
    assert_int_equal(mca_qp_reset(&qp, 2 * ch.dof, 6, 0), MCA_OK);
    static mca_link_critical_t near[MCA_MAX_ARMS][MCA_MAX_LINKS][MCA_NEAR_PAIRS];
    memset(near, 0, sizeof near);
    /* link 4: the same P and direction at 0.08 m and 0.09 m (listed apart), and a third pair across */
    near[0][4][0] = (mca_link_critical_t){1, 1, 3, 0.08, {0.3, 0.0, 0.9}, {0.3, 0.1, 0.9}};
    near[0][4][1] = (mca_link_critical_t){1, 1, 4, 0.09, {0.3, 0.0, 0.9}, {0.3, 0.2, 0.9}};
    near[0][4][2] = (mca_link_critical_t){1, 1, 5, 0.10, {0.3, 0.0, 0.9}, {0.4, 0.0, 0.9}};
    const double dec[2] = {2.0, 2.0};
    assert_int_equal(mca_scheme_near_rows(&qp, &si, 2, chains, kin,
                                          (const mca_link_critical_t(*)[MCA_MAX_LINKS][MCA_NEAR_PAIRS])near,
                                          &p, dec, NULL),
                     MCA_OK);
    const int R = MCA_NEAR_PAIRS;
    assert_int_equal(si.active_rows, 2);
    assert_true(qp.beta[R * 4 + 0] < p.big);
    assert_true(qp.beta[R * 4 + 1] == p.big); /* parallel to row 0, looser: merged */
    assert_true(qp.beta[R * 4 + 2] < p.big);
    /* the other order: the tighter one comes second and takes the first one's place */
    const double b_tight = qp.beta[R * 4 + 0];
    near[0][4][0].d = 0.09;
    near[0][4][1].d = 0.08;
    assert_int_equal(mca_scheme_near_rows(&qp, &si, 2, chains, kin,
                                          (const mca_link_critical_t(*)[MCA_MAX_LINKS][MCA_NEAR_PAIRS])near,
                                          &p, dec, NULL),
                     MCA_OK);
    assert_int_equal(si.active_rows, 2);
    assert_true(qp.beta[R * 4 + 0] == b_tight);
    assert_true(qp.beta[R * 4 + 1] == p.big);
}

/* mca-ts rows against their closed form: priority shares, the stoppability bound w (d - d1) / T beyond the
 * band too, one row per near link, and a pair repeated from the previous link left inactive. */
static void test_near_rows(void **state) {
    (void)state;
    mca_chain_t ch;
    char err[256];
    assert_int_equal(mca_chain_load_urdf(&ch, PA10, NULL, err, sizeof err), MCA_OK);
    const mca_chain_t *chains[2] = {&ch, &ch};
    mca_kin_t kin[2];
    const double q[MCA_MAX_DOF] = {0.1, 0.4, 0.0, 0.8, 0.0, 0.3, 0.0, 0.0};
    assert_int_equal(mca_fk(&ch, q, &kin[0]), MCA_OK);
    kin[1] = kin[0];
    static mca_qp_t qp;
    mca_scheme_params_t p;
    mca_scheme_default_params(&p);
    mca_scheme_info_t si = {0};
    si.var_off[1] = ch.dof;
    assert_int_equal(mca_qp_reset(&qp, 2 * ch.dof, 6, 0), MCA_OK);
    static mca_link_critical_t near[MCA_MAX_ARMS][MCA_MAX_LINKS][MCA_NEAR_PAIRS];
    memset(near, 0, sizeof near);
    const double d_in = 0.08, d_far = 0.5;
    /* arm 0, link 4: two near links of arm 1 (one inside the band, one far); link 5 repeats link 4's first */
    near[0][4][0] = (mca_link_critical_t){1, 1, 3, d_in, {0.3, 0.0, 0.9}, {0.3, 0.1, 0.9}};
    near[0][4][1] = (mca_link_critical_t){1, 1, 6, d_far, {0.3, 0.0, 0.9}, {0.8, 0.0, 0.9}};
    near[0][5][0] = near[0][4][0];
    near[1][3][0] = (mca_link_critical_t){1, 0, 4, d_in, {0.3, 0.1, 0.9}, {0.3, 0.0, 0.9}};
    const double dec[2] = {2.0, 2.0}, prio[2] = {3.0, 1.0};
    double t_stop = 0.0;
    for (int j = 0; j < ch.dof; j++) {
        t_stop = fmax(t_stop, ch.joint[j].vel_limit / 2.0);
    }
    assert_int_equal(mca_scheme_near_rows(&qp, &si, 2, chains, kin,
                                          (const mca_link_critical_t(*)[MCA_MAX_LINKS][MCA_NEAR_PAIRS])near,
                                          &p, dec, prio),
                     MCA_OK);
    const int R = MCA_NEAR_PAIRS;
    assert_int_equal(qp.n_ineq, 2 * R * (ch.dof + 1));
    assert_int_equal(si.rows_per_link, R);
    assert_int_equal(si.row_off[1], R * (ch.dof + 1));
    /* 2 w_a S v_normal in the band; the stop bound w_a (d - d1) / T (docs/scheme.md, "Stoppability") */
    const double in_a =
        2.0 * 0.75 * fmin(mca_brake_s(d_in, p.d1, p.d2) * p.v_normal, (d_in - p.d1) / (2.0 * t_stop));
    const double far_a = 0.75 * (d_far - p.d1) / t_stop; /* beyond d2: the stop bound alone */
    const double in_b =
        2.0 * 0.25 * fmin(mca_brake_s(d_in, p.d1, p.d2) * p.v_normal, (d_in - p.d1) / (2.0 * t_stop));
    assert_true(fabs(qp.beta[R * 4 + 0] - in_a) < 1e-15);
    assert_true(fabs(qp.beta[R * 4 + 1] - far_a) < 1e-15);
    assert_true(qp.beta[R * 4 + 2] == p.big); /* no third near link */
    assert_true(qp.beta[R * 5 + 0] == p.big); /* repeats link 4's pair */
    assert_true(fabs(qp.beta[si.row_off[1] + R * 3] - in_b) < 1e-15);
    assert_int_equal(si.active_rows, 3);
    /* the row is the approach speed of P towards E: n = +y here, so the row is J_P's y row */
    double Jp[3][MCA_MAX_DOF];
    assert_int_equal(mca_jacobian_point(&kin[0], 4, near[0][4][0].p, Jp), MCA_OK);
    for (int j = 0; j < ch.dof; j++) {
        assert_true(fabs(qp.U[R * 4][j] - Jp[1][j]) < 1e-12);
        assert_true(qp.U[R * 4][ch.dof + j] == 0.0);
    }
    /* without dec and priorities: the paper's band only */
    assert_int_equal(mca_scheme_near_rows(&qp, &si, 2, chains, kin,
                                          (const mca_link_critical_t(*)[MCA_MAX_LINKS][MCA_NEAR_PAIRS])near,
                                          &p, NULL, NULL),
                     MCA_OK);
    assert_true(fabs(qp.beta[R * 4] - mca_brake_s(d_in, p.d1, p.d2) * p.v_normal) < 1e-15);
    assert_true(qp.beta[R * 4 + 1] == p.big);
}

/* The fixed bodies' rows (mca_body_rows): a table under link 4 of a PA10+ (every other link allowed): rows on
 * the link's witnesses in its slots after the arm's own, -n^T J_P qdot <= 2 min{S_b v_normal, (d - c')/(2T)}
 * with the body's band [clearance, clearance + d2 - d1]; none for allowed links, none without bodies. */
static void test_body_rows(void **state) {
    (void)state;
    mca_chain_t ch;
    char err[256];
    assert_int_equal(mca_chain_load_urdf(&ch, PA10, NULL, err, sizeof err), MCA_OK);
    const mca_chain_t *chains[1] = {&ch};
    mca_kin_t kin[1];
    const double q[MCA_MAX_DOF] = {0.1, 1.2, 0.0, 1.0, 0.0, 0.3, 0.0, 0.0};
    assert_int_equal(mca_fk(&ch, q, &kin[0]), MCA_OK);
    const int L = 4;
    const double zlow = fmin(kin[0].point[L][2], kin[0].point[L + 1][2]);
    mca_fixed_body_t table = {.name = "table", .clearance = 0.03};
    table.body.kind = MCA_BODY_PLANE;
    table.body.u.plane.normal[2] = 1.0;
    const double d_want = 0.07; /* link 4's surface 7 cm above the table: inside its band (0.03 .. 0.10) */
    table.body.u.plane.point[2] = zlow - ch.link_radius[L] - d_want;
    table.allow[0] = ~(1u << L);
    mca_scheme_params_t p;
    mca_scheme_default_params(&p);
    p.body_pairs = MCA_BODY_PAIRS;
    p.d1_margin = 0.005;
    static mca_qp_t qp;
    assert_int_equal(mca_qp_reset(&qp, ch.dof, 3, 0), MCA_OK);
    for (int j = 0; j < ch.dof; j++) {
        qp.lb[j] = -ch.joint[j].vel_limit;
        qp.ub[j] = ch.joint[j].vel_limit;
    }
    static mca_link_critical_t near[MCA_MAX_ARMS][MCA_MAX_LINKS][MCA_NEAR_PAIRS];
    memset(near, 0, sizeof near);
    mca_scheme_info_t si = {0};
    const double dec[1] = {2.0};
    assert_int_equal(mca_scheme_near_rows(&qp, &si, 1, chains, kin,
                                          (const mca_link_critical_t(*)[MCA_MAX_LINKS][MCA_NEAR_PAIRS])near,
                                          &p, dec, NULL),
                     MCA_OK);
    assert_int_equal(qp.n_ineq, (MCA_NEAR_PAIRS + MCA_BODY_PAIRS) * (ch.dof + 1));
    assert_int_equal(si.body_off[0], MCA_NEAR_PAIRS * (ch.dof + 1));
    assert_int_equal(si.active_rows, 0);
    static mca_body_witness_t lists[MCA_MAX_ARMS][MCA_MAX_LINKS][MCA_BODY_PAIRS];
    assert_int_equal(mca_body_rows(&qp, &si, 1, chains, kin, &table, 1, NULL, &p, dec, NULL, lists), MCA_OK);
    const mca_body_witness_t *w = &lists[0][L][0];
    assert_true(w->valid && w->body == 0);
    assert_true(fabs(w->d - d_want) < 1e-12);
    assert_true(fabs(w->margin - (d_want - 0.03)) < 1e-12);
    assert_true(lists[0][L][1].valid); /* the link's other end, above it */
    assert_true(lists[0][L][1].d > w->d);
    mca_scheme_params_t pb;
    mca_body_band(&p, table.clearance, &pb);
    assert_true(pb.d1 == 0.03 && fabs(pb.d2 - (0.03 + p.d2 - p.d1)) < 1e-15);
    const double t_stop = mca_scheme_stop_time(&ch, dec[0]);
    const double d1m = 0.03 + 0.005;
    const double want =
        2.0 * fmin(mca_brake_s(d_want, d1m, pb.d2) * p.v_normal, (d_want - d1m) / (2.0 * t_stop));
    const int r = si.body_off[0] + MCA_BODY_PAIRS * L;
    assert_true(fabs(qp.beta[r] - want) < 1e-15);
    double Jp[3][MCA_MAX_DOF];
    assert_int_equal(mca_jacobian_point(&kin[0], L, w->p, Jp), MCA_OK);
    for (int j = 0; j < ch.dof; j++) {
        assert_true(fabs(qp.U[r][j] + Jp[2][j]) < 1e-12); /* the approach speed towards the table: -z */
    }
    for (int l = 0; l <= ch.dof; l++) {
        for (int k = 0; k < MCA_BODY_PAIRS; k++) {
            if (l != L) {
                assert_false(lists[0][l][k].valid); /* allowed links: no witnesses, no rows */
                assert_true(qp.beta[si.body_off[0] + MCA_BODY_PAIRS * l + k] == p.big);
            }
        }
    }
    assert_true(si.active_rows >= 1 && si.active_rows <= 2);
    assert_true(si.brake < 1.0);
    /* link 4 allowed too: no rows; no bodies: nothing happens */
    table.allow[0] = ~0u;
    const int before = si.active_rows;
    mca_scheme_info_t si2 = si;
    assert_int_equal(mca_scheme_near_rows(&qp, &si2, 1, chains, kin,
                                          (const mca_link_critical_t(*)[MCA_MAX_LINKS][MCA_NEAR_PAIRS])near,
                                          &p, dec, NULL),
                     MCA_OK);
    assert_int_equal(mca_body_rows(&qp, &si2, 1, chains, kin, &table, 1, NULL, &p, dec, NULL, lists), MCA_OK);
    assert_int_equal(si2.active_rows, 0);
    assert_int_equal(mca_body_rows(&qp, &si2, 1, chains, kin, &table, 0, NULL, &p, dec, NULL, lists), MCA_OK);
    assert_int_equal(si2.active_rows, 0);
    (void)before;
    /* the paper's layout: slots after each arm's own rows, with collision rows only */
    p.collision = 1;
    const double *qq[1] = {q};
    const double rd[1][3] = {{0, 0, 0}}, rdd[1][3] = {{0, 0, 0}};
    static mca_link_critical_t crit[MCA_MAX_ARMS][MCA_MAX_LINKS];
    memset(crit, 0, sizeof crit);
    mca_scheme_state_t st;
    mca_scheme_state_reset(&st);
    assert_int_equal(mca_scheme_assemble(&p, 1, chains, kin, qq, rd, rdd,
                                         (const mca_link_critical_t(*)[MCA_MAX_LINKS])crit, NULL, &st, &qp,
                                         &si),
                     MCA_OK);
    assert_int_equal(qp.n_ineq, (1 + MCA_BODY_PAIRS) * (ch.dof + 1));
    assert_int_equal(si.body_off[0], ch.dof + 1);
    table.allow[0] = ~(1u << L);
    assert_int_equal(mca_body_rows(&qp, &si, 1, chains, kin, &table, 1, NULL, &p, NULL, NULL, lists), MCA_OK);
    /* no stop bound: 2 S_b v_normal */
    assert_true(fabs(qp.beta[si.body_off[0] + MCA_BODY_PAIRS * L] -
                     2.0 * mca_brake_s(d_want, d1m, pb.d2) * p.v_normal) < 1e-15);
}

/* Links 4 and 2 of a PA10+ at q: their surface distance from the segment distance of their axes (an
 * independent computation: mca/segdist.h's closed form, not the bodies' capsule code). */
static double self_d42(const mca_chain_t *ch, const double *q) {
    mca_kin_t k;
    assert_int_equal(mca_fk(ch, q, &k), MCA_OK);
    mca_segdist_t sd;
    assert_int_equal(mca_segdist_closed(k.point[4], k.point[5], k.point[2], k.point[3], &sd), MCA_OK);
    return sd.d - ch->link_radius[4] - ch->link_radius[2];
}

/* The self rows (mca_body_rows with self pairs): the elbow of a PA10+ closed until links 4 and 2 are inside
 * the band; the row of their closest points is -n^T (J_P - J_Q) qdot <= 2 min{S v_normal, (d - d1')/(2T)},
 * and its left side is the approach speed: minus the derivative of the witness distance, checked against
 * central finite differences of that distance along random joint velocities. No row without the pair. */
static void test_self_rows(void **state) {
    (void)state;
    mca_chain_t ch;
    char err[256];
    assert_int_equal(mca_chain_load_urdf(&ch, PA10, "tool_tip", err, sizeof err), MCA_OK);
    const mca_chain_t *chains[1] = {&ch};
    mca_kin_t kin[1];
    double q[MCA_MAX_DOF] = {0.3, 0.7853981633974483, 0.2, -1.5707963267948966,
                             0.1, 0.7853981633974483, 0.0, 0.5};
    while (self_d42(&ch, q) > 0.075) {
        q[3] -= 0.005; /* close the elbow */
    }
    const double d_want = self_d42(&ch, q);
    assert_true(d_want > 0.06 && d_want <= 0.075);
    assert_int_equal(mca_fk(&ch, q, &kin[0]), MCA_OK);
    static mca_self_pairs_t self[MCA_MAX_ARMS];
    memset(self, 0, sizeof self);
    self[0][4] = 1u << 2;
    mca_self_nearest_t sn;
    assert_int_equal(mca_self_nearest(1, chains, kin, self, NULL, &sn), MCA_OK);
    assert_true(sn.valid && sn.arm == 0 && sn.link == 4 && sn.other == 2);
    assert_true(fabs(sn.d - d_want) < 1e-12);

    mca_scheme_params_t p;
    mca_scheme_default_params(&p);
    p.body_pairs = MCA_BODY_PAIRS;
    p.d1_margin = 0.005;
    static mca_qp_t qp;
    assert_int_equal(mca_qp_reset(&qp, ch.dof, 3, 0), MCA_OK);
    for (int j = 0; j < ch.dof; j++) {
        qp.lb[j] = -ch.joint[j].vel_limit;
        qp.ub[j] = ch.joint[j].vel_limit;
    }
    static mca_link_critical_t near[MCA_MAX_ARMS][MCA_MAX_LINKS][MCA_NEAR_PAIRS];
    memset(near, 0, sizeof near);
    mca_scheme_info_t si = {0};
    const double dec[1] = {2.0};
    assert_int_equal(mca_scheme_near_rows(&qp, &si, 1, chains, kin,
                                          (const mca_link_critical_t(*)[MCA_MAX_LINKS][MCA_NEAR_PAIRS])near,
                                          &p, dec, NULL),
                     MCA_OK);
    static mca_body_witness_t lists[MCA_MAX_ARMS][MCA_MAX_LINKS][MCA_BODY_PAIRS];
    assert_int_equal(mca_body_rows(&qp, &si, 1, chains, kin, NULL, 0, self, &p, dec, NULL, lists), MCA_OK);
    const mca_body_witness_t *w = &lists[0][4][0];
    assert_true(w->valid && w->body == -1 && w->link == 2);
    assert_true(fabs(w->d - d_want) < 1e-12);
    const int r = si.body_off[0] + MCA_BODY_PAIRS * 4;
    const double t_stop = mca_scheme_stop_time(&ch, dec[0]);
    const double d1m = p.d1 + p.d1_margin;
    const double want =
        2.0 * fmin(mca_brake_s(d_want, d1m, p.d2) * p.v_normal, (d_want - d1m) / (2.0 * t_stop));
    assert_true(fabs(qp.beta[r] - want) < 1e-15);
    assert_true(si.active_rows >= 1);
    /* the approach speed U qdot = -d/dt d(q + t qdot), by central differences */
    srand(31);
    for (int trial = 0; trial < 20; trial++) {
        double qd[MCA_MAX_DOF] = {0}, qp_[MCA_MAX_DOF], qm[MCA_MAX_DOF];
        double u = 0.0;
        for (int j = 0; j < ch.dof; j++) {
            qd[j] = 2.0 * rand() / (double)RAND_MAX - 1.0;
            u += qp.U[r][j] * qd[j];
        }
        const double h = 1e-6;
        for (int j = 0; j < MCA_MAX_DOF; j++) {
            qp_[j] = q[j] + h * qd[j];
            qm[j] = q[j] - h * qd[j];
        }
        const double fd = -(self_d42(&ch, qp_) - self_d42(&ch, qm)) / (2.0 * h);
        assert_true(fabs(u - fd) < 1e-6 * fmax(1.0, fabs(fd)));
    }
    /* without the pair: no witnesses, no rows */
    self[0][4] = 0;
    mca_scheme_info_t si2 = {0};
    assert_int_equal(mca_scheme_near_rows(&qp, &si2, 1, chains, kin,
                                          (const mca_link_critical_t(*)[MCA_MAX_LINKS][MCA_NEAR_PAIRS])near,
                                          &p, dec, NULL),
                     MCA_OK);
    assert_int_equal(mca_body_rows(&qp, &si2, 1, chains, kin, NULL, 0, self, &p, dec, NULL, lists), MCA_OK);
    assert_false(lists[0][4][0].valid);
    assert_int_equal(si2.active_rows, 0);
    assert_int_equal(mca_self_nearest(1, chains, kin, self, NULL, &sn), MCA_OK);
    assert_false(sn.valid);
}

/* Braking: every tick within dec dt of the last, at rest in the time the fastest joint needs; the fallback
 * (no distances: non-finite joint input) keeps each arm's direction. */
static void test_controller_brake(void **state) {
    (void)state;
    static mca_scenario_t s;
    static mca_controller_config_t cfg;
    char err[512];
    assert_int_equal(mca_scenario_load(SCN("cross_circles.yaml"), &s, err, sizeof err), MCA_OK);
    assert_int_equal(mca_controller_config_from_scenario(&cfg, &s, MCA_SCHEME_MCA_TS, err, sizeof err),
                     MCA_OK);
    mca_controller_t *c = malloc(mca_controller_size());
    assert_non_null(c);
    assert_int_equal(mca_controller_init(c, &cfg), MCA_OK);
    double q[2][MCA_MAX_DOF], v[2][MCA_MAX_DOF] = {{0}}, cmd[2][MCA_MAX_DOF], dec[2][MCA_MAX_DOF];
    memcpy(q[0], s.arm[0].q0, sizeof q[0]);
    memcpy(q[1], s.arm[1].q0, sizeof q[1]);
    double vmax = 0.0;
    for (int a = 0; a < 2; a++) {
        for (int j = 0; j < MCA_MAX_DOF; j++) {
            v[a][j] = (a ? -0.1 : 0.1) * (j + 1) * (j % 2 ? -1 : 1) * (j < 8);
            dec[a][j] = 2.0;
            vmax = fmax(vmax, fabs(v[a][j]));
        }
    }
    const double *qs[MCA_MAX_ARMS] = {q[0], q[1]}, *vs[MCA_MAX_ARMS] = {v[0], v[1]},
                 *ds[MCA_MAX_ARMS] = {dec[0], dec[1]};
    double *cs[MCA_MAX_ARMS] = {cmd[0], cmd[1]};
    mca_tick_info_t info;
    const int bound = (int)ceil(vmax / (2.0 * cfg.dt)) + 2;
    int k, rc = 0;
    for (k = 0; k < 10 * bound && rc == 0; k++) {
        rc = mca_controller_brake(c, k * cfg.dt, qs, vs, ds, cs, &info);
        assert_true(rc == 0 || rc == 1);
        for (int a = 0; a < 2; a++) {
            for (int j = 0; j < 8; j++) {
                assert_true(fabs(cmd[a][j] - v[a][j]) <= 2.0 * cfg.dt * (1 + 1e-12));
                v[a][j] = cmd[a][j];
                q[a][j] += cmd[a][j] * cfg.dt;
            }
        }
    }
    assert_int_equal(rc, 1);
    assert_true(k <= bound);
    /* fallback: one factor per arm, the joint that needs longest to stop changes by exactly dec dt */
    for (int j = 0; j < 8; j++) {
        v[0][j] = 0.2 * (j + 1);
        v[1][j] = -0.05;
    }
    q[1][2] = NAN;
    rc = mca_controller_brake(c, 1.0, qs, vs, ds, cs, &info);
    assert_int_equal(rc, 0);
    assert_int_equal(info.brake_fallback, 1);
    const double f0 = cmd[0][0] / v[0][0], f1 = cmd[1][0] / v[1][0];
    for (int j = 0; j < 8; j++) {
        assert_true(fabs(cmd[0][j] / v[0][j] - f0) < 1e-12);
        assert_true(fabs(cmd[1][j] / v[1][j] - f1) < 1e-12);
    }
    assert_true(fabs((v[0][7] - cmd[0][7]) - 2.0 * cfg.dt) < 1e-12);
    assert_true(fabs(fabs(v[1][0] - cmd[1][0]) - 2.0 * cfg.dt) < 1e-12);
    free(c);
}

/* The path tube (mca_scheme_tube_bounds): standing still (e = -K err) and 0 are inside it (strictly, within
 * MCA_TUBE_FLOOR of the path), the first-order error after one tick at either bound is exactly R_i, and an
 * infinite radius gives no tube. */
static void test_tube_bounds(void **state) {
    (void)state;
    const double K = 20.0, dt = 0.001;
    const double errs[4][3] = {{0, 0, 0}, {1e-3, -2e-3, 5e-4}, {0.05, 0, -0.03}, {-1e-6, 1e-6, 0}};
    const double radii[3] = {0.0, 0.01, 0.05};
    for (int e = 0; e < 4; e++) {
        for (int r = 0; r < 3; r++) {
            double lo[3], hi[3];
            mca_scheme_tube_bounds(errs[e], radii[r], K, dt, lo, hi);
            for (int i = 0; i < 3; i++) {
                const double R = fmax(fmax(radii[r] / sqrt(3.0), fabs(errs[e][i])), MCA_TUBE_FLOOR);
                assert_true(lo[i] <= 0.0 && hi[i] >= 0.0);
                if (fabs(errs[e][i]) < MCA_TUBE_FLOOR) { /* standing still strictly inside, not on an edge */
                    assert_true(-K * errs[e][i] - lo[i] > 0.5 * (MCA_TUBE_FLOOR - fabs(errs[e][i])) / dt &&
                                hi[i] + K * errs[e][i] > 0.5 * (MCA_TUBE_FLOOR - fabs(errs[e][i])) / dt);
                }
                assert_true(-K * errs[e][i] >= lo[i] - 1e-12 && -K * errs[e][i] <= hi[i] + 1e-12);
                const double next_lo = (1.0 - K * dt) * errs[e][i] - dt * lo[i];
                const double next_hi = (1.0 - K * dt) * errs[e][i] - dt * hi[i];
                assert_true(fabs(fabs(next_lo) - R) < 1e-12 || lo[i] == 0.0);
                assert_true(fabs(fabs(next_hi) - R) < 1e-12 || hi[i] == 0.0);
            }
        }
    }
    double lo[3], hi[3];
    mca_scheme_tube_bounds(errs[1], INFINITY, K, dt, lo, hi);
    assert_true(isinf(lo[0]) && lo[0] < 0 && isinf(hi[2]) && hi[2] > 0);
}

/* mca_path_distance against closed forms, and mca_path_tolerance's narrowing at an exact point. */
static void test_path_distance_tolerance(void **state) {
    (void)state;
    mca_path_t p;
    memset(&p, 0, sizeof p);
    p.kind = MCA_PATH_WAYPOINTS;
    p.n_points = 4; /* start (0,0,0) -> (1,0,0) -> (1,0,0) dwell -> (1,1,0) */
    const double pts[4][3] = {{0, 0, 0}, {1, 0, 0}, {1, 0, 0}, {1, 1, 0}};
    memcpy(p.p, pts, sizeof pts);
    p.dur[0] = 2.0;
    p.dur[1] = 1.0;
    p.dur[2] = 2.0;
    for (int i = 0; i < MCA_PATH_MAX_POINTS; i++) {
        p.seg_tol[i] = 0.05;
    }
    p.exact_tol = 0.001;
    p.exact[1] = p.exact[2] = 1;
    const double x1[3] = {0.5, 0.3, 0.4}; /* above the first segment's middle: sqrt(0.09 + 0.16) */
    assert_float_equal(mca_path_distance(&p, x1), 0.5, 1e-15);
    const double x2[3] = {2.0, 0.5, 0.0}; /* beside the last segment */
    assert_float_equal(mca_path_distance(&p, x2), 1.0, 1e-15);
    const double x3[3] = {-3.0, -4.0, 0.0}; /* nearest the start point */
    assert_float_equal(mca_path_distance(&p, x3), 5.0, 1e-15);
    assert_float_equal(mca_path_tolerance(&p, 1.0), 0.001 + 0.049 * 0.5, 1e-15); /* narrowing */
    assert_float_equal(mca_path_tolerance(&p, 2.5), 0.001, 1e-15);               /* the dwell */
    assert_float_equal(mca_path_tolerance(&p, 4.0), 0.001 + 0.049 * 0.5, 1e-15); /* widening */
    assert_float_equal(mca_path_tolerance(&p, 9.0), 0.05, 1e-15);                /* after the end */
    assert_float_equal(mca_path_point_time(&p, 2), 3.0, 1e-15);

    mca_path_t c;
    memset(&c, 0, sizeof c);
    c.kind = MCA_PATH_CIRCLE;
    c.radius = 0.2;
    c.u[0] = 1.0;
    c.v[1] = 1.0;
    c.anchor[0] = 1.0; /* centre (0.8, 0, 0) */
    const double centre[3] = {0.8, 0.0, 0.0};
    assert_float_equal(mca_path_distance(&c, centre), 0.2, 1e-15);
    const double above[3] = {0.8, 0.2, 0.3}; /* on the ring's axis-parallel line above a ring point */
    assert_float_equal(mca_path_distance(&c, above), 0.3, 1e-15);
}

/* The body cache (mca_body_cache_update) only skips pairs it can prove far: along a random walk of a PA10+
 * (small steps and jumps beyond the refresh distance) among five bodies of every kind, one of which moves now
 * and then (as a streamed body), the least body margin, the least self distance and the body and self rows
 * with the cache are those without it, bit for bit. */
static void test_body_cache(void **state) {
    (void)state;
    mca_chain_t ch;
    char err[256];
    assert_int_equal(mca_chain_load_urdf(&ch, PA10, "tool_tip", err, sizeof err), MCA_OK);
    const mca_chain_t *chains[1] = {&ch};
    static mca_fixed_body_t bodies[5];
    memset(bodies, 0, sizeof bodies);
    bodies[0].body.kind = MCA_BODY_PLANE;
    bodies[0].body.u.plane.normal[2] = 1.0;
    bodies[0].allow[0] = 0x3u; /* the base and its column stand on it */
    bodies[1].body.kind = MCA_BODY_SPHERE;
    bodies[1].body.u.sphere = (mca_body_sphere_t){{0.3, 0.2, 0.9}, 0.05};
    bodies[2].body.kind = MCA_BODY_BOX;
    bodies[2].body.u.box.centre[0] = -0.3;
    bodies[2].body.u.box.centre[2] = 0.8;
    bodies[2].body.u.box.half[0] = bodies[2].body.u.box.half[1] = bodies[2].body.u.box.half[2] = 0.1;
    for (int i = 0; i < 3; i++) {
        bodies[2].body.u.box.R[i][i] = 1.0;
    }
    bodies[3].body.kind = MCA_BODY_CYLINDER;
    bodies[3].body.u.cylinder = (mca_body_cylinder_t){
        .centre = {0.45, -0.1, 0.4}, .axis = {0, 0, 1}, .half_len = 0.4, .radius = 0.04};
    bodies[4].body.kind = MCA_BODY_CAPSULE;
    bodies[4].body.u.capsule = (mca_capsule_t){{0.0, 0.5, 1.3}, {0.4, -0.4, 1.3}, 0.04};
    for (int k = 0; k < 5; k++) {
        bodies[k].clearance = 0.02 + 0.01 * k;
        assert_int_equal(mca_body_check(&bodies[k]), MCA_OK);
    }
    static mca_self_pairs_t self[MCA_MAX_ARMS];
    memset(self, 0, sizeof self);
    for (int l = 2; l <= ch.dof; l++) {
        self[0][l] = (1u << (l - 1)) - 1u; /* every pair that is not adjacent */
    }
    mca_scheme_params_t p;
    mca_scheme_default_params(&p);
    p.body_pairs = MCA_BODY_PAIRS;
    p.d2 = 0.2; /* a wide band: many rows */
    static mca_body_cache_t cache;
    memset(&cache, 0, sizeof cache);
    static mca_qp_t qa, qb;
    static mca_body_witness_t la[MCA_MAX_ARMS][MCA_MAX_LINKS][MCA_BODY_PAIRS];
    static mca_body_witness_t lb[MCA_MAX_ARMS][MCA_MAX_LINKS][MCA_BODY_PAIRS];
    static mca_link_critical_t near[MCA_MAX_ARMS][MCA_MAX_LINKS][MCA_NEAR_PAIRS];
    memset(near, 0, sizeof near);
    double q[MCA_MAX_DOF] = {0.0, 0.7853981633974483, 0.0, -1.5707963267948966,
                             0.0, 0.7853981633974483, 0.0, 0.5};
    const double *dec = NULL; /* the paper's rows: the band is the cut, which pairs cross on the walk */
    srand(7);
    int rows = 0, skipped_far = 0;
    for (int step = 0; step < 600; step++) {
        const double h = step % 50 == 49 ? 0.3 : 0.015; /* now and then a jump beyond the refresh distance */
        for (int j = 0; j < ch.dof; j++) {
            q[j] += h * (2.0 * rand() / (double)RAND_MAX - 1.0);
        }
        if (step % 97 == 40) {
            bodies[1].body.u.sphere.centre[0] += 0.05; /* a body that moved (a streamed one) */
        }
        mca_kin_t kin[1];
        assert_int_equal(mca_fk(&ch, q, &kin[0]), MCA_OK);
        assert_int_equal(mca_body_cache_update(&cache, 1, chains, kin, bodies, 5, self), MCA_OK);
        mca_body_nearest_t b0, b1;
        assert_int_equal(mca_body_nearest(1, chains, kin, bodies, 5, NULL, &b0), MCA_OK);
        assert_int_equal(mca_body_nearest(1, chains, kin, bodies, 5, &cache, &b1), MCA_OK);
        assert_true(b1.valid && b0.link == b1.link && b0.body == b1.body);
        assert_true(b0.margin == b1.margin && b0.d == b1.d);
        mca_self_nearest_t s0, s1;
        assert_int_equal(mca_self_nearest(1, chains, kin, self, NULL, &s0), MCA_OK);
        assert_int_equal(mca_self_nearest(1, chains, kin, self, &cache, &s1), MCA_OK);
        assert_true(s1.valid && s0.link == s1.link && s0.other == s1.other && s0.d == s1.d);
        for (int nb = 0; nb <= 5; nb += 5) { /* the self pairs alone, then with the bodies */
            mca_scheme_info_t sa = {0}, sb = {0};
            for (int k = 0; k < 2; k++) {
                mca_qp_t *qp = k ? &qb : &qa;
                assert_int_equal(mca_qp_reset(qp, ch.dof, 3, 0), MCA_OK);
                for (int j = 0; j < ch.dof; j++) {
                    qp->lb[j] = -ch.joint[j].vel_limit;
                    qp->ub[j] = ch.joint[j].vel_limit;
                }
                assert_int_equal(
                    mca_scheme_near_rows(qp, k ? &sb : &sa, 1, chains, kin,
                                         (const mca_link_critical_t(*)[MCA_MAX_LINKS][MCA_NEAR_PAIRS])near,
                                         &p, dec, NULL),
                    MCA_OK);
            }
            assert_int_equal(mca_body_rows(&qa, &sa, 1, chains, kin, bodies, nb, self, &p, dec, NULL, la),
                             MCA_OK);
            assert_int_equal(mca_body_rows(&qb, &sb, 1, chains, kin, bodies, nb, self, &p, dec, &cache, lb),
                             MCA_OK);
            assert_int_equal(sa.active_rows, sb.active_rows);
            assert_true(sa.brake == sb.brake);
            assert_int_equal(qa.n_ineq, qb.n_ineq);
            for (int i = 0; i < qa.n_ineq; i++) {
                assert_true(qa.beta[i] == qb.beta[i]);
                if (qa.beta[i] < p.big) {
                    assert_memory_equal(qa.U[i], qb.U[i], sizeof(double) * (size_t)ch.dof);
                }
            }
            assert_memory_equal(la[0], lb[0], sizeof la[0]);
            rows += sa.active_rows;
        }
        for (int l = 0; l <= ch.dof; l++) {
            for (int k = 0; k < 5; k++) {
                skipped_far += cache.d[0][l][k] - cache.move[0][l] > 0.5; /* pairs the cache can skip */
            }
        }
    }
    assert_true(rows > 100);         /* the rows were there to compare */
    assert_true(skipped_far > 1000); /* and so were pairs to skip */
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_brake_values),
        cmocka_unit_test(test_diamond_rows),
        cmocka_unit_test(test_joint_bounds),
        cmocka_unit_test(test_collision_rows_fd),
        cmocka_unit_test(test_apf),
        cmocka_unit_test(test_paths),
        cmocka_unit_test(test_scenario_files),
        cmocka_unit_test(test_controller_stream_law),
        cmocka_unit_test(test_controller_faults),
        cmocka_unit_test(test_controller_n_arms),
        cmocka_unit_test(test_timescale_stand_still_feasible),
        cmocka_unit_test(test_timescale_deadlock),
        cmocka_unit_test(test_near_rows),
        cmocka_unit_test(test_near_witnesses),
        cmocka_unit_test(test_pdnn_time_budget),
        cmocka_unit_test(test_pdnn_step_budget),
        cmocka_unit_test(test_near_rows_parallel),
        cmocka_unit_test(test_controller_brake),
        cmocka_unit_test(test_body_rows),
        cmocka_unit_test(test_self_rows),
        cmocka_unit_test(test_body_cache),
        cmocka_unit_test(test_tube_bounds),
        cmocka_unit_test(test_path_distance_tolerance),
        cmocka_unit_test(test_path_rate_limit),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
