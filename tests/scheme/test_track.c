/* SPDX-License-Identifier: MIT */
/* Streamed bodies (mca/track.h): the growth of a stale track against its closed form (ISO 13855's 2.0 m/s
 * for the first 0.5 m, 1.6 m/s beyond), S_p's terms by hand, a track in the controller's bodies and a moving
 * body's row (its approach taken off the bound). */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <string.h>

#include "mca/bodyrows.h"
#include "mca/chain.h"
#include "mca/err.h"
#include "mca/scheme.h"
#include "mca/track.h"
#include "mca/urdf.h"

#ifndef MCA_SOURCE_DIR
#error MCA_SOURCE_DIR must be defined
#endif
#define PA10 MCA_SOURCE_DIR "/config/robots/pa10plus.urdf"

/* The closed form written out apart from track.c: r + 2.0 (age - max_age) while that growth is <= 0.5 m,
 * then 0.5 + 1.6 (age - max_age - 0.25). */
static double growth_truth(double age, double max_age) {
    const double tau = age - max_age;
    if (tau <= 0.0) {
        return 0.0;
    }
    return 2.0 * tau <= 0.5 ? 2.0 * tau : 0.5 + 1.6 * (tau - 0.25);
}

static void test_growth(void **state) {
    (void)state;
    mca_ssm_params_t p;
    mca_ssm_default(&p);
    assert_int_equal(mca_ssm_check(&p), MCA_OK);
    assert_true(p.approach_near == 2.0 && p.approach_far == 1.6 && p.approach_switch == 0.5);
    const double ages[] = {0.0, 0.05, 0.1, 0.1 + 1e-6, 0.2, 0.3, 0.35, 0.36, 0.5, 1.0, 3.0};
    for (size_t k = 0; k < sizeof ages / sizeof ages[0]; k++) {
        const double g = mca_track_growth(&p, ages[k]);
        assert_true(fabs(g - growth_truth(ages[k], p.max_age)) < 1e-12);
        /* never below ISO 13855's own S = 1.6 m/s T beyond 0.5 m */
        assert_true(g >= 1.6 * (ages[k] - p.max_age) - 1e-12);
    }
    /* the switch: 2.0 m/s just before 0.5 m of growth, 1.6 m/s after */
    assert_true(mca_track_growth_rate(&p, p.max_age + 0.2) == 2.0);
    assert_true(mca_track_growth_rate(&p, p.max_age + 0.3) == 1.6);
    assert_true(mca_track_growth_rate(&p, p.max_age) == 0.0);

    /* a stale sphere as a body of the rows: its radius grown, its centre where max_age put it, the growth's
     * rate as its approach, S_p with the approach speed */
    const mca_track_t tr = {.id = 3,
                            .kind = MCA_BODY_SPHERE,
                            .a = {1.0, 0.0, 0.5},
                            .radius = 0.2,
                            .v = {0.5, 0.0, 0.0},
                            .stamp = 10.0};
    const double v_r = 3.0, t_s = 0.4;
    mca_fixed_body_t b;
    mca_ssm_terms_t t;
    for (size_t k = 0; k < sizeof ages / sizeof ages[0]; k++) {
        assert_int_equal(mca_track_body(&p, &tr, 10.0 + ages[k], v_r, t_s, &b, &t), MCA_OK);
        assert_int_equal(b.body.kind, MCA_BODY_SPHERE);
        assert_true(fabs(b.body.u.sphere.radius - (0.2 + growth_truth(ages[k], p.max_age))) < 1e-12);
        assert_true(fabs(b.body.u.sphere.centre[0] - (1.0 + 0.5 * fmin(ages[k], p.max_age))) < 1e-12);
        const int stale = ages[k] > p.max_age;
        const double v_h = stale ? 2.0 : 0.5, t_r = p.reaction_time + p.latency;
        const double s_p = v_h * (t_r + t_s) + v_r * t_r + 0.5 * v_r * t_s + p.intrusion + p.z_d + p.z_r;
        assert_true(fabs(t.s_p - s_p) < 1e-12 && fabs(b.clearance - s_p) < 1e-12);
        assert_true(b.grow == (stale ? mca_track_growth_rate(&p, ages[k]) : 0.0));
        assert_true(b.v[0] == (stale ? 0.0 : 0.5));
    }
    /* a capsule grows alike; a bad track is refused */
    mca_track_t cap = tr;
    cap.kind = MCA_BODY_CAPSULE;
    cap.b[0] = 1.0;
    cap.b[2] = 1.5;
    assert_int_equal(mca_track_body(&p, &cap, 10.6, v_r, t_s, &b, NULL), MCA_OK);
    assert_true(fabs(b.body.u.capsule.radius - (0.2 + growth_truth(0.6, p.max_age))) < 1e-12);
    cap.kind = MCA_BODY_BOX;
    assert_int_equal(mca_track_body(&p, &cap, 10.6, v_r, t_s, &b, NULL), MCA_EINVAL);
    cap.kind = MCA_BODY_SPHERE;
    cap.radius = NAN;
    assert_int_equal(mca_track_body(&p, &cap, 10.6, v_r, t_s, &b, NULL), MCA_EINVAL);
    p.lost_after = p.max_age;
    assert_int_equal(mca_ssm_check(&p), MCA_EINVAL);
}

/* A body that moves toward a link lowers that link's row by its approach n^T v (a stale one by its growth).
 */
static void test_moving_body_row(void **state) {
    (void)state;
    mca_chain_t ch;
    char err[256];
    assert_int_equal(mca_chain_load_urdf(&ch, PA10, NULL, err, sizeof err), MCA_OK);
    const mca_chain_t *chains[1] = {&ch};
    mca_kin_t kin[1];
    const double q[MCA_MAX_DOF] = {0.1, 1.2, 0.0, 1.0, 0.0, 0.3, 0.0, 0.0};
    assert_int_equal(mca_fk(&ch, q, &kin[0]), MCA_OK);
    const int L = ch.dof; /* the last link: a sphere beside its end */
    mca_fixed_body_t s = {.name = "s", .clearance = 0.05};
    s.body.kind = MCA_BODY_SPHERE;
    s.body.u.sphere.radius = 0.1;
    for (int i = 0; i < 3; i++) {
        s.body.u.sphere.centre[i] = kin[0].point[L + 1][i];
    }
    s.body.u.sphere.centre[0] += ch.link_radius[L] + 0.1 + 0.09; /* 9 cm from the tool tip, along +x */
    for (int l = 0; l < L; l++) {
        s.allow[0] |= 1u << l;
    }
    mca_scheme_params_t p;
    mca_scheme_default_params(&p);
    p.body_pairs = MCA_BODY_PAIRS;
    p.d1_margin = 0.005;
    const double dec[1] = {2.0};
    double beta[3];
    for (int run = 0; run < 3; run++) {
        static mca_qp_t qp;
        assert_int_equal(mca_qp_reset(&qp, ch.dof, 3, 0), MCA_OK);
        for (int j = 0; j < ch.dof; j++) {
            qp.lb[j] = -ch.joint[j].vel_limit;
            qp.ub[j] = ch.joint[j].vel_limit;
        }
        static mca_link_critical_t near[MCA_MAX_ARMS][MCA_MAX_LINKS][MCA_NEAR_PAIRS];
        memset(near, 0, sizeof near);
        mca_scheme_info_t si = {0};
        assert_int_equal(
            mca_scheme_near_rows(&qp, &si, 1, chains, kin,
                                 (const mca_link_critical_t(*)[MCA_MAX_LINKS][MCA_NEAR_PAIRS])near, &p, dec,
                                 NULL),
            MCA_OK);
        s.v[0] = run == 1 ? -0.3 : 0.0; /* toward the tool tip (-x) */
        s.grow = run == 2 ? 2.0 : 0.0;
        static mca_body_witness_t lists[MCA_MAX_ARMS][MCA_MAX_LINKS][MCA_BODY_PAIRS];
        assert_int_equal(mca_body_rows(&qp, &si, 1, chains, kin, &s, 1, NULL, &p, dec, NULL, lists), MCA_OK);
        const mca_body_witness_t *w = &lists[0][L][0];
        assert_true(w->valid);
        beta[run] = qp.beta[si.body_off[0] + MCA_BODY_PAIRS * L];
        if (run == 1) {
            assert_true(fabs(beta[1] - (beta[0] - (w->n[0] * -0.3))) < 1e-12);
        }
    }
    assert_true(beta[0] < p.big);
    assert_true(beta[1] < beta[0] - 0.29); /* n ~ -x: the body's approach is +0.3 along n */
    assert_true(fabs(beta[2] - (beta[0] - 2.0)) < 1e-12);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_growth),
        cmocka_unit_test(test_moving_body_row),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
