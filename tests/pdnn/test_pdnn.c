/* SPDX-License-Identifier: MIT */
/* LVI-PDNN solver against independent truth: the closed-form minimum-norm solution (by our own Gaussian
 * elimination), small QPs solved by hand from their KKT conditions, warm-start step counts, a malloc
 * tripwire around mca_pdnn_solve, and the input checks. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "mca/err.h"
#include "mca/pdnn.h"
#include "fixture_sim7200.h"
#include "qpgen.h"

/* ---- malloc tripwire (linked with -Wl,--wrap=..., see CMakeLists.txt) ---- */
static int trip_armed;
static long trip_count;

void *__real_malloc(size_t n);
void *__real_calloc(size_t k, size_t n);
void *__real_realloc(void *p, size_t n);
int __real_posix_memalign(void **p, size_t a, size_t n);
void *__real_aligned_alloc(size_t a, size_t n);
void *__real__Znwm(size_t n);
void *__real__Znam(size_t n);
void *__real__ZnwmSt11align_val_t(size_t n, size_t a);
void *__real__ZnamSt11align_val_t(size_t n, size_t a);

static void trip(void) {
    if (trip_armed) {
        trip_count++;
    }
}
void *__wrap_malloc(size_t n) {
    trip();
    return __real_malloc(n);
}
void *__wrap_calloc(size_t k, size_t n) {
    trip();
    return __real_calloc(k, n);
}
void *__wrap_realloc(void *p, size_t n) {
    trip();
    return __real_realloc(p, n);
}
int __wrap_posix_memalign(void **p, size_t a, size_t n) {
    trip();
    return __real_posix_memalign(p, a, n);
}
void *__wrap_aligned_alloc(size_t a, size_t n) {
    trip();
    return __real_aligned_alloc(a, n);
}
void *__wrap__Znwm(size_t n) {
    trip();
    return __real__Znwm(n);
}
void *__wrap__Znam(size_t n) {
    trip();
    return __real__Znam(n);
}
void *__wrap__ZnwmSt11align_val_t(size_t n, size_t a) {
    trip();
    return __real__ZnwmSt11align_val_t(n, a);
}
void *__wrap__ZnamSt11align_val_t(size_t n, size_t a) {
    trip();
    return __real__ZnamSt11align_val_t(n, a);
}

/* ---- helpers ---- */
/* cmocka 1.1.5 (Debian 12) has no assert_double_equal; print both values when it fails. */
#define assert_near(a, b, tol) near_impl((a), (b), (tol), #a, __FILE__, __LINE__)
static void near_impl(double a, double b, double tol, const char *what, const char *file, int line) {
    if (!(fabs(a - b) <= tol)) {
        print_error("%s = %.17g, expected %.17g +- %g\n", what, a, b, tol);
        _fail(file, line);
    }
}

static mca_pdnn_t solver; /* large: static */

/* Solve A x = b (k x k, row-major, destroyed) by Gaussian elimination with partial pivoting. */
static void gauss(double *A, double *b, double *x, int k) {
    for (int c = 0; c < k; c++) {
        int p = c;
        for (int r = c + 1; r < k; r++) {
            if (fabs(A[r * k + c]) > fabs(A[p * k + c])) {
                p = r;
            }
        }
        for (int j = 0; j < k; j++) {
            const double t = A[c * k + j];
            A[c * k + j] = A[p * k + j];
            A[p * k + j] = t;
        }
        const double t = b[c];
        b[c] = b[p];
        b[p] = t;
        assert_true(fabs(A[c * k + c]) > 1e-12);
        for (int r = c + 1; r < k; r++) {
            const double f = A[r * k + c] / A[c * k + c];
            for (int j = c; j < k; j++) {
                A[r * k + j] -= f * A[c * k + j];
            }
            b[r] -= f * b[c];
        }
    }
    for (int r = k - 1; r >= 0; r--) {
        double s = b[r];
        for (int j = r + 1; j < k; j++) {
            s -= A[r * k + j] * x[j];
        }
        x[r] = s / A[r * k + r];
    }
}

static void free_box(mca_qp_t *qp) {
    for (int j = 0; j < qp->n; j++) {
        qp->lb[j] = -INFINITY;
        qp->ub[j] = INFINITY;
    }
}

static int solve(const mca_qp_t *qp, const mca_pdnn_params_t *prm, double *phi, mca_pdnn_result_t *res) {
    mca_pdnn_init(&solver);
    return mca_pdnn_solve(&solver, qp, prm, phi, res);
}

/* Every variant of the solver: adaptive / bound step x ORTH / SCALE / NONE rewriting. */
#define N_VARIANTS 6
static void variant(mca_pdnn_params_t *prm, int v) {
    mca_pdnn_default_params(prm);
    prm->step_rule = (v & 1) ? MCA_PDNN_STEP_BOUND : MCA_PDNN_STEP_ADAPTIVE;
    prm->precond = v >> 1;
    prm->max_steps = 200000;
    prm->tol = 1e-12; /* the hand-solved answers are checked to 1e-9 */
}

/* ---- 1. equality-only: phi = G^T (G G^T)^-1 alpha ---- */
static void test_equality_closed_form(void **state) {
    (void)state;
    qpgen_rng_t rng = {42};
    for (int trial = 0; trial < 5; trial++) {
        mca_qp_t qp;
        assert_int_equal(mca_qp_reset(&qp, 16, 6, 0), MCA_OK);
        free_box(&qp);
        for (int i = 0; i < 6; i++) {
            qp.alpha[i] = qpgen_uniform(&rng, -1, 1);
            for (int j = 0; j < 16; j++) {
                qp.G[i][j] = qpgen_uniform(&rng, -1, 1) * (trial + 1); /* several row scales */
            }
        }
        double A[36], b[6], lam[6], truth[16];
        for (int i = 0; i < 6; i++) {
            b[i] = qp.alpha[i];
            for (int k = 0; k < 6; k++) {
                double s = 0.0;
                for (int j = 0; j < 16; j++) {
                    s += qp.G[i][j] * qp.G[k][j];
                }
                A[i * 6 + k] = s;
            }
        }
        gauss(A, b, lam, 6);
        for (int j = 0; j < 16; j++) {
            truth[j] = 0.0;
            for (int i = 0; i < 6; i++) {
                truth[j] += qp.G[i][j] * lam[i];
            }
        }
        for (int v = 0; v < N_VARIANTS; v++) {
            mca_pdnn_params_t prm;
            variant(&prm, v);
            double phi[16];
            mca_pdnn_result_t res;
            assert_int_equal(solve(&qp, &prm, phi, &res), MCA_OK);
            assert_true(res.converged);
            assert_true(res.residual <= 1e-9);
            for (int j = 0; j < 16; j++) {
                assert_near(phi[j], truth[j], 1e-8);
            }
            /* the duals kept in the state are the unscaled multipliers: v_e = (G G^T)^-1 alpha */
            for (int i = 0; i < 6; i++) {
                assert_near(solver.y[16 + i], lam[i], 1e-6 * (1.0 + fabs(lam[i])));
            }
        }
    }
}

/* ---- 2. box, box + equality, active inequality, infeasible ---- */
static void test_box_only(void **state) {
    (void)state;
    mca_qp_t qp;
    mca_qp_reset(&qp, 3, 0, 0);
    const double lb[3] = {0.5, -2.0, -INFINITY}, ub[3] = {1.0, -1.0, INFINITY};
    memcpy(qp.lb, lb, sizeof(lb));
    memcpy(qp.ub, ub, sizeof(ub));
    for (int v = 0; v < N_VARIANTS; v++) {
        mca_pdnn_params_t prm;
        variant(&prm, v);
        double phi[3];
        assert_int_equal(solve(&qp, &prm, phi, NULL), MCA_OK);
        /* minimum norm in a box: the point of the box nearest 0 */
        assert_near(phi[0], 0.5, 1e-9);
        assert_near(phi[1], -1.0, 1e-9);
        assert_near(phi[2], 0.0, 1e-9);
    }
}

static void test_box_and_equality(void **state) {
    (void)state;
    /* min a^2+b^2 s.t. a + b = 2, a <= 0.5: unconstrained (1,1) violates the bound, so a = 0.5, b = 1.5;
     * KKT: (a, b) = v_e (1, 1) - mu (1, 0) with v_e = 1.5, mu = 1 >= 0. */
    mca_qp_t qp;
    mca_qp_reset(&qp, 2, 1, 0);
    qp.G[0][0] = 1.0;
    qp.G[0][1] = 1.0;
    qp.alpha[0] = 2.0;
    qp.lb[0] = -1.0;
    qp.ub[0] = 0.5;
    qp.lb[1] = -INFINITY;
    qp.ub[1] = INFINITY;
    for (int v = 0; v < N_VARIANTS; v++) {
        mca_pdnn_params_t prm;
        variant(&prm, v);
        double phi[2];
        assert_int_equal(solve(&qp, &prm, phi, NULL), MCA_OK);
        assert_near(phi[0], 0.5, 1e-9);
        assert_near(phi[1], 1.5, 1e-9);
        assert_near(solver.y[2], 1.5, 1e-8);
    }
}

static void test_active_inequality(void **state) {
    (void)state;
    /* min |phi|^2/2 s.t. phi1 + phi2 + phi3 = 3, 2 phi1 <= 0.
     * Without the row: (1,1,1), which violates it; active: phi1 = 0, phi2 = phi3 = 1.5.
     * KKT: phi = G^T v_e - U^T v_i = (v_e - 2 v_i, v_e, v_e): v_e = 1.5, v_i = 0.75 >= 0. */
    mca_qp_t qp;
    mca_qp_reset(&qp, 3, 1, 2);
    free_box(&qp);
    qp.G[0][0] = qp.G[0][1] = qp.G[0][2] = 1.0;
    qp.alpha[0] = 3.0;
    qp.U[0][0] = 2.0;
    qp.beta[0] = 0.0;
    /* and an inactive row: phi3 <= 5 */
    qp.U[1][2] = 1.0;
    qp.beta[1] = 5.0;
    for (int v = 0; v < N_VARIANTS; v++) {
        mca_pdnn_params_t prm;
        variant(&prm, v);
        double phi[3];
        assert_int_equal(solve(&qp, &prm, phi, NULL), MCA_OK);
        assert_near(phi[0], 0.0, 1e-9);
        assert_near(phi[1], 1.5, 1e-9);
        assert_near(phi[2], 1.5, 1e-9);
        assert_near(solver.y[3], 1.5, 1e-8);  /* v_e */
        assert_near(solver.y[4], 0.75, 1e-8); /* v_i of the active row */
        assert_near(solver.y[5], 0.0, 1e-8);  /* v_i of the inactive row */
    }
}

static void test_infeasible(void **state) {
    (void)state;
    mca_pdnn_params_t prm;
    mca_pdnn_default_params(&prm);
    prm.max_steps = 5000;
    double phi[2];
    mca_pdnn_result_t res;
    /* phi1 = 1 and phi1 <= 0 */
    mca_qp_t qp;
    mca_qp_reset(&qp, 2, 1, 1);
    free_box(&qp);
    qp.G[0][0] = 1.0;
    qp.alpha[0] = 1.0;
    qp.U[0][0] = 1.0;
    qp.beta[0] = 0.0;
    for (int v = 0; v < N_VARIANTS; v++) {
        variant(&prm, v);
        prm.max_steps = 5000;
        assert_int_equal(solve(&qp, &prm, phi, &res), MCA_ENOTCONV);
        assert_false(res.converged);
        assert_true(res.residual > 1e-3);
        /* the default (ORTH, adaptive) sees at once that U's row is G's row with a contradicting bound
         * (a zero row with beta' < 0) and stops when the residual makes no progress; the others may run
         * into the step cap */
        assert_true(v == 0 ? res.steps < 5000 : res.steps <= 5000);
    }
    mca_pdnn_default_params(&prm);
    prm.max_steps = 5000;
    /* phi1 = 2 with phi1 <= 1 (box) */
    mca_qp_reset(&qp, 2, 1, 0);
    free_box(&qp);
    qp.G[0][0] = 1.0;
    qp.alpha[0] = 2.0;
    qp.ub[0] = 1.0;
    assert_int_equal(solve(&qp, &prm, phi, &res), MCA_ENOTCONV);
    assert_true(res.residual > 1e-3);
}

/* ---- 3. warm start ---- */
static void test_warm_start(void **state) {
    (void)state;
    qpgen_rng_t rng = {3};
    mca_pdnn_params_t prm;
    mca_pdnn_default_params(&prm);
    prm.max_steps = 200000;
    prm.no_polish = 1; /* the network's own warm start (the polish would end most of these at step 0) */
    long cold_sum = 0, pert_sum = 0;
    for (int trial = 0; trial < 10; trial++) {
        qpgen_scene_t sc;
        mca_qp_t qp;
        double phi[16], phi2[16];
        mca_pdnn_result_t res;
        qpgen_scene_random(&sc, &rng, 0.05);
        qpgen_build(&sc, &qp);
        mca_pdnn_init(&solver);
        assert_int_equal(mca_pdnn_solve(&solver, &qp, &prm, phi, &res), MCA_OK);
        assert_int_equal(res.warm, 0);
        const int cold = res.steps;
        assert_true(cold > 10);
        /* the same QP again: already at the tolerance */
        assert_int_equal(mca_pdnn_solve(&solver, &qp, &prm, phi2, &res), MCA_OK);
        assert_int_equal(res.warm, 2);
        assert_int_equal(res.steps, 0);
        assert_memory_equal(phi, phi2, sizeof(phi));
        /* a small move: warm takes far fewer steps than the same QP cold (measured ~0.15 of cold here;
         * without the far-row weighting it was ~0.5: the convergence is linear, docs/pdnn.md) */
        qpgen_scene_perturb(&sc, &rng, 1e-6);
        qpgen_build(&sc, &qp);
        assert_int_equal(mca_pdnn_solve(&solver, &qp, &prm, phi, &res), MCA_OK);
        const int warm = res.steps;
        mca_pdnn_init(&solver);
        assert_int_equal(mca_pdnn_solve(&solver, &qp, &prm, phi2, &res), MCA_OK);
        print_message("warm start: cold %d, same QP 0, perturbed warm %d vs cold %d\n", cold, warm,
                      res.steps);
        cold_sum += res.steps;
        pert_sum += warm;
        for (int j = 0; j < 16; j++) {
            assert_near(phi[j], phi2[j], 1e-7);
        }
    }
    assert_true(4 * pert_sum < cold_sum);
}

static void test_partial_warm_start(void **state) {
    (void)state;
    /* n_ineq changes between ticks: phi and v_e are kept, v_i restarts at 0 */
    mca_qp_t qp;
    mca_qp_reset(&qp, 3, 1, 2);
    free_box(&qp);
    qp.G[0][0] = qp.G[0][1] = qp.G[0][2] = 1.0;
    qp.alpha[0] = 3.0;
    qp.U[0][0] = 2.0;
    qp.U[1][2] = 1.0;
    qp.beta[1] = 5.0;
    double phi[3];
    mca_pdnn_result_t res;
    mca_pdnn_init(&solver);
    assert_int_equal(mca_pdnn_solve(&solver, &qp, NULL, phi, &res), MCA_OK);
    qp.n_ineq = 1;
    assert_int_equal(mca_pdnn_solve(&solver, &qp, NULL, phi, &res), MCA_OK);
    assert_int_equal(res.warm, 1);
    assert_near(phi[0], 0.0, 1e-9);
    qp.n = 2; /* different problem: cold */
    qp.n_ineq = 0;
    assert_int_equal(mca_pdnn_solve(&solver, &qp, NULL, phi, &res), MCA_OK);
    assert_int_equal(res.warm, 0);
    assert_near(phi[0], 1.5, 1e-9);
}

/* ---- 4. no heap allocation inside mca_pdnn_solve ---- */
static void test_no_malloc(void **state) {
    (void)state;
    /* the tripwire itself works (a test that cannot fail is worthless) */
    void *(*volatile alloc)(size_t) = malloc; /* through a pointer: the compiler may not elide it */
    trip_count = 0;
    trip_armed = 1;
    void *p = alloc(16);
    trip_armed = 0;
    free(p);
    assert_int_equal(trip_count, 1);

    qpgen_rng_t rng = {11};
    qpgen_scene_t sc;
    mca_qp_t qp;
    qpgen_scene_random(&sc, &rng, 0.1);
    qpgen_build(&sc, &qp);
    double phi[16];
    mca_pdnn_result_t res;
    mca_pdnn_init(&solver);
    for (int v = 0; v < N_VARIANTS; v++) {
        mca_pdnn_params_t prm;
        variant(&prm, v);
        prm.max_steps = 2000;
        trip_count = 0;
        trip_armed = 1;
        const int rc = mca_pdnn_solve(&solver, &qp, &prm, phi, &res); /* cold or warm, both paths */
        prm.kappa = 0.01;                                             /* the user-fixed step path */
        const int rc2 = mca_pdnn_solve(&solver, &qp, &prm, phi, &res);
        trip_armed = 0;
        assert_true(rc == MCA_OK || rc == MCA_ENOTCONV);
        assert_true(rc2 == MCA_OK || rc2 == MCA_ENOTCONV);
        assert_int_equal(trip_count, 0);
    }
    /* the polish's pivoted QR on the real tick of test_polish_real_qp, warm and cold */
    mca_pdnn_params_t prm;
    mca_pdnn_default_params(&prm);
    prm.max_steps = 2000;
    fixture_tick7199(&qp);
    mca_pdnn_init(&solver);
    trip_count = 0;
    trip_armed = 1;
    const int rc1 = mca_pdnn_solve(&solver, &qp, &prm, phi, &res);
    fixture_tick7200(&qp);
    const int rc2 = mca_pdnn_solve(&solver, &qp, &prm, phi, &res);
    trip_armed = 0;
    assert_int_equal(rc1, MCA_OK);
    assert_int_equal(rc2, MCA_OK);
    assert_true(res.polished > 0 && res.polish_tries > 0);
    assert_int_equal(trip_count, 0);
}

/* ---- 5. bad input, divergence, the stability bound ---- */
static void test_bad_input(void **state) {
    (void)state;
    mca_qp_t qp;
    mca_qp_reset(&qp, 2, 1, 1);
    free_box(&qp);
    qp.G[0][0] = 1.0;
    qp.alpha[0] = 1.0;
    qp.U[0][1] = 1.0;
    qp.beta[0] = 1.0;
    double phi[2] = {7.0, 7.0};
    mca_pdnn_params_t prm;
    mca_pdnn_default_params(&prm);
    mca_pdnn_init(&solver);
    assert_int_equal(mca_pdnn_solve(NULL, &qp, &prm, phi, NULL), MCA_EINVAL);
    assert_int_equal(mca_pdnn_solve(&solver, NULL, &prm, phi, NULL), MCA_EINVAL);
    assert_int_equal(mca_pdnn_solve(&solver, &qp, &prm, NULL, NULL), MCA_EINVAL);
    mca_qp_t bad = qp;
    bad.G[0][1] = NAN;
    assert_int_equal(mca_pdnn_solve(&solver, &bad, &prm, phi, NULL), MCA_EINVAL);
    bad = qp;
    bad.beta[0] = INFINITY;
    assert_int_equal(mca_pdnn_solve(&solver, &bad, &prm, phi, NULL), MCA_EINVAL);
    bad = qp;
    bad.U[0][0] = -INFINITY;
    assert_int_equal(mca_pdnn_solve(&solver, &bad, &prm, phi, NULL), MCA_EINVAL);
    bad = qp;
    bad.lb[1] = NAN;
    assert_int_equal(mca_pdnn_solve(&solver, &bad, &prm, phi, NULL), MCA_EINVAL);
    bad = qp;
    bad.lb[0] = 1.0;
    bad.ub[0] = 0.0;
    assert_int_equal(mca_pdnn_solve(&solver, &bad, &prm, phi, NULL), MCA_EINVAL);
    bad = qp;
    bad.n_ineq = MCA_QP_MAX_INEQ + 1;
    assert_int_equal(mca_pdnn_solve(&solver, &bad, &prm, phi, NULL), MCA_EINVAL);
    bad = qp;
    bad.n = 0;
    assert_int_equal(mca_pdnn_solve(&solver, &bad, &prm, phi, NULL), MCA_EINVAL);
    mca_pdnn_params_t bp = prm;
    bp.tol = NAN;
    assert_int_equal(mca_pdnn_solve(&solver, &qp, &bp, phi, NULL), MCA_EINVAL);
    bp = prm;
    bp.gamma = 2.0;
    assert_int_equal(mca_pdnn_solve(&solver, &qp, &bp, phi, NULL), MCA_EINVAL);
    /* errors leave phi and the state alone */
    assert_near(phi[0], 7.0, 0.0);
    assert_int_equal(solver.h, 0);
    assert_int_equal(mca_qp_reset(&qp, MCA_QP_MAX_VARS + 1, 0, 0), MCA_ERANGE);
    assert_int_equal(mca_qp_reset(NULL, 1, 0, 0), MCA_EINVAL);
    /* and the good QP solves: phi = (1, 0) */
    assert_int_equal(mca_pdnn_solve(&solver, &qp, NULL, phi, NULL), MCA_OK);
    assert_near(phi[0], 1.0, 1e-9);
    assert_near(phi[1], 0.0, 1e-9);
}

static void test_divergence_reported(void **state) {
    (void)state;
    /* A step far above the stability edge blows up: reported as not converged, and the state is
     * dropped so the next (sane) solve starts cold and succeeds. */
    qpgen_rng_t rng = {5};
    qpgen_scene_t sc;
    mca_qp_t qp;
    qpgen_scene_random(&sc, &rng, 0.05);
    qpgen_build(&sc, &qp);
    mca_pdnn_params_t prm;
    mca_pdnn_default_params(&prm);
    prm.kappa = 5.0;
    prm.max_steps = 5000;
    prm.no_polish = 1; /* the polish would finish this QP at step 0, before the blow-up */
    double phi[16];
    mca_pdnn_result_t res;
    mca_pdnn_init(&solver);
    assert_int_equal(mca_pdnn_solve(&solver, &qp, &prm, phi, &res), MCA_ENOTCONV);
    assert_false(res.converged);
    assert_true(res.steps < 5000); /* stopped on the non-finite residual */
    assert_true(res.kappa > res.kappa_bound);
    assert_int_equal(solver.h, 0);
    prm.kappa = 0.0;
    prm.max_steps = 200000;
    assert_int_equal(mca_pdnn_solve(&solver, &qp, &prm, phi, &res), MCA_OK);
    assert_int_equal(res.warm, 0);
}

static void test_split_blocks(void **state) {
    (void)state;
    /* The dual-arm QP splits into two blocks; one coupling row makes it one. Either way the split and the
     * single-network solves agree (OSQP checks both kinds too: pdnn.osqp_check). */
    qpgen_rng_t rng = {21};
    for (int coupled = 0; coupled < 2; coupled++) {
        qpgen_scene_t sc;
        mca_qp_t qp;
        qpgen_scene_random(&sc, &rng, 0.15);
        qpgen_build(&sc, &qp);
        if (coupled) {
            qpgen_couple(&sc, &qp, QPGEN_NINEQ - 1);
        }
        mca_pdnn_params_t prm;
        mca_pdnn_default_params(&prm);
        prm.max_steps = 400000;
        double phi1[16], phi2[16];
        mca_pdnn_result_t r1, r2;
        assert_int_equal(solve(&qp, &prm, phi1, &r1), MCA_OK);
        assert_int_equal(r1.blocks, coupled ? 1 : 2);
        assert_true(r1.steps_total >= r1.steps);
        prm.no_split = 1;
        assert_int_equal(solve(&qp, &prm, phi2, &r2), MCA_OK);
        assert_int_equal(r2.blocks, 1);
        for (int j = 0; j < 16; j++) {
            assert_near(phi1[j], phi2[j], 1e-8);
        }
    }
}

static void test_inactive_zero_rows(void **state) {
    (void)state;
    /* mca_scheme keeps inactive collision rows in place as U = 0, beta = big: the answer must be that of
     * the QP without them, and they must not slow the solve down (they belong to no block). */
    qpgen_rng_t rng = {33};
    qpgen_scene_t sc;
    mca_qp_t qp, red;
    qpgen_scene_random(&sc, &rng, 0.15);
    qpgen_build(&sc, &qp);
    mca_qp_reset(&red, qp.n, qp.n_eq, 0);
    memcpy(red.G, qp.G, sizeof(qp.G));
    memcpy(red.alpha, qp.alpha, sizeof(qp.alpha));
    memcpy(red.lb, qp.lb, sizeof(qp.lb));
    memcpy(red.ub, qp.ub, sizeof(qp.ub));
    for (int i = 0; i < qp.n_ineq; i++) {
        if (i % 3 == 0) { /* keep a third of the rows */
            memcpy(red.U[red.n_ineq], qp.U[i], sizeof(qp.U[i]));
            red.beta[red.n_ineq++] = qp.beta[i];
        } else {
            memset(qp.U[i], 0, sizeof(qp.U[i]));
            qp.beta[i] = 1e6;
        }
    }
    mca_pdnn_params_t prm;
    mca_pdnn_default_params(&prm);
    prm.max_steps = 400000;
    double phi1[16], phi2[16];
    mca_pdnn_result_t r1, r2;
    assert_int_equal(solve(&qp, &prm, phi1, &r1), MCA_OK);
    for (int i = 0; i < qp.n_ineq; i++) {
        if (i % 3 != 0) {
            assert_near(solver.y[qp.n + qp.n_eq + i], 0.0, 0.0); /* the zero rows' duals are exactly 0 */
        }
    }
    assert_int_equal(solve(&red, &prm, phi2, &r2), MCA_OK);
    assert_int_equal(r1.blocks, 2);
    assert_int_equal(r1.steps, r2.steps);
    for (int j = 0; j < 16; j++) {
        assert_near(phi1[j], phi2[j], 1e-12);
    }
}

static void test_warm_restart_real_qp(void **state) {
    (void)state;
    /* mca-sim, componentwise form, t = 7.199 s -> 7.200 s: the QP jumps. From the old answer the
     * projection method crawls (residual stuck near 1e-4 for thousands of steps); with half the cap spent
     * warm, the cold restart reaches ~2e-7 in the rest. The answer is the better of the two, and
     * whatever is returned is the least-residual point seen. */
    mca_qp_t qp;
    double phi[16];
    mca_pdnn_result_t res;
    mca_pdnn_params_t prm;
    mca_pdnn_default_params(&prm);
    prm.max_steps = 2000;
    prm.no_polish = 1; /* the network's rescue (test_polish_real_qp: the polish finishes this tick) */
    fixture_tick7199(&qp);
    mca_pdnn_init(&solver);
    assert_int_equal(mca_pdnn_solve(&solver, &qp, &prm, phi, &res), MCA_OK);
    fixture_tick7200(&qp);
    assert_int_equal(mca_pdnn_solve(&solver, &qp, &prm, phi, &res), MCA_ENOTCONV);
    assert_int_equal(res.warm, 2);
    assert_int_equal(res.restarted, 1);
    assert_true(res.steps <= 2000);
    assert_true(res.residual < 1e-6);
    /* the same QP solved cold to 1e-9 (43000 steps: a nearly degenerate active set) */
    double phi_ref[16];
    mca_pdnn_result_t ref;
    prm.max_steps = 200000;
    mca_pdnn_init(&solver);
    assert_int_equal(mca_pdnn_solve(&solver, &qp, &prm, phi_ref, &ref), MCA_OK);
    /* ill-conditioned (smallest singular value of one arm's active rows 0.08, multipliers ~24): a residual of
     * 2e-7 still leaves 3.5e-4 in phi; the residual is not an error bound on such QPs */
    double err = 0.0;
    for (int j = 0; j < 16; j++) {
        err = fmax(err, fabs(phi[j] - phi_ref[j]));
    }
    assert_true(err < 1e-3);
    print_message(
        "sim t=7.200: %d steps (warm + restart), residual %.3g, |phi - phi_ref| %.2g; cold to 1e-9: "
        "%d steps\n",
        res.steps, res.residual, err, ref.steps);
}

static void test_bound_step_is_stable(void **state) {
    (void)state;
    /* The derived bound kappa < 2 / ||I+M||^2 (docs/pdnn.md): the residual never blows up at the bound
     * step, and the bound uses an upper estimate of ||N|| so it stays below the true edge. */
    qpgen_rng_t rng = {9};
    for (int trial = 0; trial < 5; trial++) {
        qpgen_scene_t sc;
        mca_qp_t qp;
        qpgen_scene_random(&sc, &rng, 0.05);
        qpgen_build(&sc, &qp);
        mca_pdnn_params_t prm;
        mca_pdnn_default_params(&prm);
        prm.step_rule = MCA_PDNN_STEP_BOUND;
        prm.max_steps = 400000;
        double phi[16];
        mca_pdnn_result_t res;
        mca_pdnn_init(&solver);
        assert_int_equal(mca_pdnn_solve(&solver, &qp, &prm, phi, &res), MCA_OK);
        /* the QP splits into the two arms: each block steps at its own bound, the smaller one is reported */
        assert_int_equal(res.blocks, 2);
        assert_true(res.kappa_bound > 0.0 && res.kappa >= res.kappa_bound);
    }
}

/* ---- 6. active-set polish ---- */
/* KKT violation of (phi, y = [phi; v_e; v_i]) for the QP as given, computed here from the definitions and
 * nothing of the solver's: primal feasibility (equalities, rows, box), dual signs (v_i >= 0), complementarity
 * (v_i * slack), and stationarity with the box multipliers z = phi - (G^T v_e - U^T v_i) of the right sign
 * (z_j > 0 only at lb_j, z_j < 0 only at ub_j). A strictly convex QP's KKT point is its unique solution. */
static double kkt_error(const mca_qp_t *qp, const double *phi, const double *y) {
    const int n = qp->n, ne = qp->n_eq, ni = qp->n_ineq;
    const double *ve = y + n, *vi = y + n + ne;
    double err = 0.0;
    for (int i = 0; i < ne; i++) {
        double r = -qp->alpha[i];
        for (int j = 0; j < n; j++) {
            r += qp->G[i][j] * phi[j];
        }
        err = fmax(err, fabs(r));
    }
    for (int i = 0; i < ni; i++) {
        double slack = qp->beta[i];
        for (int j = 0; j < n; j++) {
            slack -= qp->U[i][j] * phi[j];
        }
        err = fmax(err, fmax(-slack, -vi[i]));
        err = fmax(err, fabs(vi[i] * slack));
    }
    for (int j = 0; j < n; j++) {
        double a = 0.0;
        for (int i = 0; i < ne; i++) {
            a += qp->G[i][j] * ve[i];
        }
        for (int i = 0; i < ni; i++) {
            a -= qp->U[i][j] * vi[i];
        }
        const double z = phi[j] - a; /* phi = a + z: z > 0 pushes up from lb, z < 0 down from ub */
        err = fmax(err, fmax(qp->lb[j] - phi[j], phi[j] - qp->ub[j]));
        err = fmax(err, fmax(z, 0.0) * fmin(phi[j] - qp->lb[j], 1.0));
        err = fmax(err, fmax(-z, 0.0) * fmin(qp->ub[j] - phi[j], 1.0));
    }
    return err;
}

static void test_polish_parallel_rows(void **state) {
    (void)state;
    /* min |phi|^2/2 s.t. phi1 + phi2 + phi3 = 3 and the same active row three times: 2 phi1 <= 0,
     * 4 phi1 <= 0 (parallel), -phi1 >= 0 written as 0.5 phi1 <= 0. Answer (0, 1.5, 1.5) as in
     * test_active_inequality; the multipliers are not unique (any split of 0.75 * 2 over the rows), so the
     * KKT system is singular: the polish's pivoted QR must see rank 2 and put the multiplier on one row.
     * Without the rank test the triangular solve divides by ~0 and the candidate is rejected (polished 0). */
    mca_qp_t qp;
    mca_qp_reset(&qp, 3, 1, 3);
    free_box(&qp);
    qp.G[0][0] = qp.G[0][1] = qp.G[0][2] = 1.0;
    qp.alpha[0] = 3.0;
    qp.U[0][0] = 2.0;
    qp.U[1][0] = 4.0;
    qp.U[2][0] = 0.5;
    for (int v = 0; v < N_VARIANTS; v++) {
        mca_pdnn_params_t prm;
        variant(&prm, v);
        prm.max_steps = 2000;
        double phi[3];
        mca_pdnn_result_t res;
        assert_int_equal(solve(&qp, &prm, phi, &res), MCA_OK);
        assert_int_equal(res.polished, 1);
        assert_true(res.steps <= 1); /* cold: the guess at y = 0 (no row violated), then one correction */
        assert_near(phi[0], 0.0, 1e-12);
        assert_near(phi[1], 1.5, 1e-12);
        assert_near(phi[2], 1.5, 1e-12);
        assert_true(kkt_error(&qp, phi, solver.y) <= 1e-12);
        assert_near(2.0 * solver.y[4] + 4.0 * solver.y[5] + 0.5 * solver.y[6], 1.5, 1e-12);
        /* near-parallel (1e-12 rad off): numerically the same row; the dependent row's own equation then
         * holds to ~1e-12 only, which the default tol accepts (the network cannot reach 1e-12 here either) */
        mca_qp_t q2 = qp;
        q2.U[1][1] = 4e-12;
        prm.tol = 1e-9;
        assert_int_equal(solve(&q2, &prm, phi, &res), MCA_OK);
        assert_int_equal(res.polished, 1);
        assert_true(kkt_error(&q2, phi, solver.y) <= 1e-11);
        assert_near(phi[1], 1.5, 1e-11);
    }
}

static void test_polish_dependent_row(void **state) {
    (void)state;
    /* min |phi|^2/2 s.t. phi1 + phi2 + phi3 = 3, phi1 <= 0, phi2 <= 0, phi1 + phi2 <= beta2. Tick A (beta2 =
     * 5): (0, 0, 3), the first two rows active (multipliers 3, 3). Tick B (beta2 = -1), warm from A: the
     * third row is violated and its normal is the sum of the two active ones, so no step in phi can reach it:
     * the polish's dual step moves the multipliers until one of the two leaves, then the next one; answer
     * (-0.5, -0.5, 4), v_e = 4, v_i = (0, 0, 4.5), exact at step 0. A polish that gives up on a dependent
     * row leaves this tick to the network (steps > 0). */
    mca_qp_t qp;
    mca_qp_reset(&qp, 3, 1, 3);
    free_box(&qp);
    qp.G[0][0] = qp.G[0][1] = qp.G[0][2] = 1.0;
    qp.alpha[0] = 3.0;
    qp.U[0][0] = 1.0;
    qp.U[1][1] = 1.0;
    qp.U[2][0] = qp.U[2][1] = 1.0;
    for (int v = 0; v < N_VARIANTS; v++) {
        mca_pdnn_params_t prm;
        variant(&prm, v);
        prm.max_steps = 2000;
        double phi[3];
        mca_pdnn_result_t res;
        qp.beta[2] = 5.0;
        assert_int_equal(solve(&qp, &prm, phi, &res), MCA_OK);
        assert_near(solver.y[4], 3.0, 1e-12);
        assert_near(solver.y[5], 3.0, 1e-12);
        qp.beta[2] = -1.0;
        assert_int_equal(mca_pdnn_solve(&solver, &qp, &prm, phi, &res), MCA_OK);
        assert_int_equal(res.warm, 2);
        assert_int_equal(res.polished, 1);
        assert_int_equal(res.steps, 0);
        assert_near(phi[0], -0.5, 1e-12);
        assert_near(phi[1], -0.5, 1e-12);
        assert_near(phi[2], 4.0, 1e-12);
        assert_near(solver.y[3], 4.0, 1e-12);
        assert_near(solver.y[4], 0.0, 1e-12);
        assert_near(solver.y[5], 0.0, 1e-12);
        assert_near(solver.y[6], 4.5, 1e-12);
        assert_true(kkt_error(&qp, phi, solver.y) <= 1e-12);
    }
}

static void test_polish_wrong_guess(void **state) {
    (void)state;
    /* min |phi|^2/2 s.t. phi1 >= 1, phi1 + phi2 >= 3 (as -phi1 <= -1, -phi1 - phi2 <= -3). Both rows are
     * violated at 0, so the guess at the cold start makes both active: candidate (1, 2) with multipliers
     * (-1, 2), a wrong sign. The answer is (1.5, 1.5), the first row inactive (multipliers (0, 1.5)). */
    mca_qp_t qp;
    mca_qp_reset(&qp, 2, 0, 2);
    free_box(&qp);
    qp.U[0][0] = -1.0;
    qp.beta[0] = -1.0;
    qp.U[1][0] = qp.U[1][1] = -1.0;
    qp.beta[1] = -3.0;
    double phi[2];
    mca_pdnn_result_t res;
    mca_pdnn_params_t prm;
    mca_pdnn_default_params(&prm);
    prm.max_steps = 2000;
    /* one try only: the wrong candidate must be rejected and the network's answer returned */
    prm.polish_max = 1;
    assert_int_equal(solve(&qp, &prm, phi, &res), MCA_OK);
    assert_int_equal(res.polish_tries, 1);
    assert_int_equal(res.polished, 0);
    assert_true(res.steps > 0);
    assert_near(phi[0], 1.5, 1e-8);
    assert_near(phi[1], 1.5, 1e-8);
    assert_true(kkt_error(&qp, phi, solver.y) <= 1e-8);
    /* by default the correction drops the row with the negative multiplier: exact at step 0 */
    prm.polish_max = 0;
    assert_int_equal(solve(&qp, &prm, phi, &res), MCA_OK);
    assert_int_equal(res.polished, 1);
    assert_int_equal(res.polish_tries, 2);
    assert_int_equal(res.steps, 0);
    assert_near(phi[0], 1.5, 1e-14);
    assert_near(phi[1], 1.5, 1e-14);
    assert_near(solver.y[2], 0.0, 0.0);
    assert_near(solver.y[3], 1.5, 1e-14);
    /* the state is the polished answer: the same QP again takes no step and no try */
    assert_int_equal(mca_pdnn_solve(&solver, &qp, &prm, phi, &res), MCA_OK);
    assert_int_equal(res.steps, 0);
    assert_int_equal(res.polish_tries, 0);
    /* an infeasible QP is never "polished": phi1 >= 1 and phi1 <= 0 */
    qp.U[1][0] = 1.0;
    qp.U[1][1] = 0.0;
    qp.beta[1] = 0.0;
    assert_int_equal(solve(&qp, &prm, phi, &res), MCA_ENOTCONV);
    assert_int_equal(res.polished, 0);
    assert_true(res.polish_tries > 0);
}

static void test_polish_real_qp(void **state) {
    (void)state;
    /* The mca-sim tick of test_warm_restart_real_qp that the network cannot finish in 2000 steps (43000
     * cold): with the polish, exact at once, and its KKT conditions hold in the QP as given. */
    mca_qp_t qp;
    double phi[16];
    mca_pdnn_result_t res;
    mca_pdnn_params_t prm;
    mca_pdnn_default_params(&prm);
    prm.max_steps = 2000;
    fixture_tick7199(&qp);
    mca_pdnn_init(&solver);
    assert_int_equal(mca_pdnn_solve(&solver, &qp, &prm, phi, &res), MCA_OK);
    fixture_tick7200(&qp);
    assert_int_equal(mca_pdnn_solve(&solver, &qp, &prm, phi, &res), MCA_OK);
    assert_int_equal(res.warm, 2);
    assert_int_equal(res.polished, 2); /* both arms' blocks */
    assert_true(res.steps <= 300);
    const double kkt = kkt_error(&qp, phi, solver.y);
    assert_true(kkt <= 1e-9);
    /* and agrees with the network run to 1e-9 (43000 steps) within what its residual allows */
    double phi_ref[16];
    mca_pdnn_result_t ref;
    prm.max_steps = 200000;
    prm.no_polish = 1;
    mca_pdnn_init(&solver);
    assert_int_equal(mca_pdnn_solve(&solver, &qp, &prm, phi_ref, &ref), MCA_OK);
    double err = 0.0;
    for (int j = 0; j < 16; j++) {
        err = fmax(err, fabs(phi[j] - phi_ref[j]));
    }
    assert_true(err < 1e-6);
    print_message("sim t=7.200 polished: %d steps, %d tries, KKT error %.2g, |phi - phi_net(1e-9)| %.2g\n",
                  res.steps, res.polish_tries, kkt, err);
}

static void test_polish_meets_deadline(void **state) {
    (void)state;
    /* The same tick with a deadline already past: the polish makes no solve (it checks the clock before
     * each), the network stops at its first check (16 steps), and the solve reports the time-out, not an
     * answer. */
    mca_qp_t qp;
    double phi[16];
    mca_pdnn_result_t res;
    mca_pdnn_params_t prm;
    mca_pdnn_default_params(&prm);
    prm.max_steps = 2000;
    fixture_tick7199(&qp);
    mca_pdnn_init(&solver);
    assert_int_equal(mca_pdnn_solve(&solver, &qp, &prm, phi, &res), MCA_OK);
    fixture_tick7200(&qp);
    prm.deadline_ns = 1; /* CLOCK_MONOTONIC is past 1 ns */
    assert_int_equal(mca_pdnn_solve(&solver, &qp, &prm, phi, &res), MCA_ETIMEDOUT);
    assert_int_equal(res.timed_out, 1);
    assert_int_equal(res.polished, 0);
    assert_int_equal(res.polish_tries, 0);
    assert_true(res.steps <= 16);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_equality_closed_form),
        cmocka_unit_test(test_box_only),
        cmocka_unit_test(test_box_and_equality),
        cmocka_unit_test(test_active_inequality),
        cmocka_unit_test(test_infeasible),
        cmocka_unit_test(test_warm_start),
        cmocka_unit_test(test_partial_warm_start),
        cmocka_unit_test(test_no_malloc),
        cmocka_unit_test(test_bad_input),
        cmocka_unit_test(test_divergence_reported),
        cmocka_unit_test(test_split_blocks),
        cmocka_unit_test(test_inactive_zero_rows),
        cmocka_unit_test(test_warm_restart_real_qp),
        cmocka_unit_test(test_bound_step_is_stable),
        cmocka_unit_test(test_polish_parallel_rows),
        cmocka_unit_test(test_polish_dependent_row),
        cmocka_unit_test(test_polish_wrong_guess),
        cmocka_unit_test(test_polish_real_qp),
        cmocka_unit_test(test_polish_meets_deadline),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
