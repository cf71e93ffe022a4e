/* SPDX-License-Identifier: MIT */
/* LVI-PDNN solver (paper (29)-(32)): input checks, row scaling, warm start, step-size rule.
 * The Euler loop itself is in pdnn_eigen.cpp. Real-time safe: no allocation, no I/O. */
#include "mca/pdnn.h"

#include <math.h>
#include <string.h>

#include "mca/err.h"
#include "pdnn__eigen.h"

#define PDNN_DEFAULT_GAMMA 1.9

void mca_pdnn_default_params(mca_pdnn_params_t *params)
{
    if (params == NULL) {
        return;
    }
    memset(params, 0, sizeof(*params));
    params->kappa = 0.0;
    params->tol = 1e-9;
    params->max_steps = 20000;
    params->big = 1e10;
    params->step_rule = MCA_PDNN_STEP_ADAPTIVE;
    params->gamma = PDNN_DEFAULT_GAMMA;
    params->no_row_scaling = 0;
}

void mca_pdnn_init(mca_pdnn_t *s)
{
    if (s != NULL) {
        memset(s, 0, sizeof(*s));
    }
}

static int all_finite(const double *v, int len)
{
    for (int i = 0; i < len; i++) {
        if (!isfinite(v[i])) {
            return 0;
        }
    }
    return 1;
}

static int check_qp(const mca_qp_t *qp)
{
    if (qp->n < 1 || qp->n > MCA_QP_MAX_VARS || qp->n_eq < 0 || qp->n_eq > MCA_QP_MAX_EQ ||
        qp->n_ineq < 0 || qp->n_ineq > MCA_QP_MAX_INEQ) {
        return MCA_EINVAL;
    }
    for (int i = 0; i < qp->n_eq; i++) {
        if (!all_finite(qp->G[i], qp->n)) {
            return MCA_EINVAL;
        }
    }
    for (int i = 0; i < qp->n_ineq; i++) {
        if (!all_finite(qp->U[i], qp->n)) {
            return MCA_EINVAL;
        }
    }
    if (!all_finite(qp->alpha, qp->n_eq) || !all_finite(qp->beta, qp->n_ineq)) {
        return MCA_EINVAL;
    }
    for (int i = 0; i < qp->n; i++) {
        const double lb = qp->lb[i], ub = qp->ub[i];
        /* NaN fails every comparison below; an empty box is bad data, not an iteration problem. */
        if (!(lb <= ub) || lb == INFINITY || ub == -INFINITY) {
            return MCA_EINVAL;
        }
    }
    return MCA_OK;
}

static int check_params(const mca_pdnn_params_t *p)
{
    if (!isfinite(p->kappa) || !(p->tol > 0.0) || !isfinite(p->tol) || p->max_steps < 0 || !(p->big > 0.0) ||
        !isfinite(p->big) || !(p->gamma < 2.0) || (p->step_rule != MCA_PDNN_STEP_ADAPTIVE &&
                                                    p->step_rule != MCA_PDNN_STEP_BOUND)) {
        return MCA_EINVAL;
    }
    return MCA_OK;
}

static double clampd(double x, double lo, double hi)
{
    return x < lo ? lo : (x > hi ? hi : x);
}

/* Build N = D [G; -U], q = D [-alpha; beta] and Omega in the workspace. Rows scaled to unit 2-norm give
 * the same phi (D G phi = D alpha has the same solutions) and only rescale the duals (v = D v_scaled). */
static void setup(mca_pdnn_t *s, const mca_qp_t *qp, const mca_pdnn_params_t *prm)
{
    const int n = qp->n, m = qp->n_eq + qp->n_ineq;
    for (int i = 0; i < m; i++) {
        const int eq = i < qp->n_eq;
        const double *row = eq ? qp->G[i] : qp->U[i - qp->n_eq];
        const double sign = eq ? 1.0 : -1.0;
        double nrm2 = 0.0;
        for (int j = 0; j < n; j++) {
            nrm2 += row[j] * row[j];
        }
        const double di = (prm->no_row_scaling || !(nrm2 > 0.0)) ? 1.0 : 1.0 / sqrt(nrm2);
        double *Ni = &s->ws_N[i * n];
        for (int j = 0; j < n; j++) {
            Ni[j] = sign * di * row[j];
        }
        s->ws_q[i] = di * (eq ? -qp->alpha[i] : qp->beta[i - qp->n_eq]);
        s->ws_d[i] = di;
        s->ws_lo[n + i] = eq ? -prm->big : 0.0;
        s->ws_hi[n + i] = prm->big;
    }
    for (int j = 0; j < n; j++) {
        s->ws_lo[j] = clampd(qp->lb[j], -prm->big, prm->big);
        s->ws_hi[j] = clampd(qp->ub[j], -prm->big, prm->big);
    }
}

int mca_pdnn_solve(mca_pdnn_t *s, const mca_qp_t *qp, const mca_pdnn_params_t *params, double *phi,
                   mca_pdnn_result_t *result)
{
    mca_pdnn_params_t defaults;
    if (params == NULL) {
        mca_pdnn_default_params(&defaults);
        params = &defaults;
    }
    if (s == NULL || qp == NULL || phi == NULL || check_qp(qp) != MCA_OK || check_params(params) != MCA_OK) {
        return MCA_EINVAL;
    }
    mca_pdnn_params_t prm = *params;
    if (!(prm.gamma > 0.0)) {
        prm.gamma = PDNN_DEFAULT_GAMMA;
    }
    const int n = qp->n, m = qp->n_eq + qp->n_ineq, h = n + m;
    setup(s, qp, &prm);

    /* Warm start: reuse what still means the same thing. A state left non-finite is dropped. */
    int warm = 0;
    if (s->h > 0 && s->n == n && s->n_eq == qp->n_eq && all_finite(s->y, s->h)) {
        warm = (s->n_ineq == qp->n_ineq) ? 2 : 1;
    }
    for (int i = 0; i < h; i++) {
        double yi = 0.0;
        if (i < n + qp->n_eq ? warm >= 1 : warm == 2) {
            yi = s->y[i];
        }
        s->ws_y[i] = i < n ? yi : yi / s->ws_d[i - n];
    }

    const mca_pdnn__problem_t p = {n, m, qp->n_eq, s->ws_N, s->ws_q, s->ws_d, s->ws_lo, s->ws_hi};
    mca_pdnn_result_t res = {0};
    res.warm = warm;
    double kappa_fixed = prm.kappa;
    if (kappa_fixed > 0.0 || prm.step_rule == MCA_PDNN_STEP_BOUND) {
        /* ||I+M||_2^2 = (5 + 2 s^2 + sqrt(9 + 4 s^2)) / 2 with s = ||N||_2 (docs/pdnn.md), increasing in s. */
        const double s2 = mca_pdnn__norm_sq_bound(&p);
        const double L2 = 0.5 * (5.0 + 2.0 * s2 + sqrt(9.0 + 4.0 * s2));
        res.kappa_bound = prm.gamma / L2;
        if (kappa_fixed <= 0.0) {
            kappa_fixed = res.kappa_bound;
        }
    }
    mca_pdnn__iterate(&p, s->ws_y, kappa_fixed, prm.gamma, prm.tol, prm.max_steps, &res);

    for (int j = 0; j < n; j++) {
        phi[j] = s->ws_y[j];
    }
    if (isfinite(res.residual)) {
        for (int i = 0; i < h; i++) {
            s->y[i] = i < n ? s->ws_y[i] : s->ws_y[i] * s->ws_d[i - n];
        }
        s->h = h;
        s->n = n;
        s->n_eq = qp->n_eq;
        s->n_ineq = qp->n_ineq;
    } else {
        s->h = 0; /* diverged: next solve starts cold */
    }
    if (result != NULL) {
        *result = res;
    }
    return res.converged ? MCA_OK : MCA_ENOTCONV;
}
