/* SPDX-License-Identifier: MIT */
/* sigma's own stoppability bound: the path rate from which an arm can still stop on its path (mca/path_rate.h
 * says what and why; docs/scheme.md section 11 the argument). */
#include "mca/path_rate.h"

#include <math.h>
#include <string.h>

#include "mca/apf.h" /* mca_apf_pinv_apply */
#include "mca/err.h"

/* The pseudo-inverse's damping (as the prediction's: a singular pose must not throw the limit to 0) and the
 * difference steps for the path's second derivative [s] and J's change along q_s [s of path time]. */
#define RATE_DAMPING 1e-2
#define RATE_DT 1e-4

/* q_s and q_ss at one predicted configuration: the joint velocity per unit path rate and its change. */
static int derivatives(const mca_coord_arm_t *arm, const double q[], double tau, double qs[], double qss[]) {
    const mca_chain_t *c = arm->chain;
    const int dof = c->dof;
    mca_kin_t kin;
    double J[3][MCA_MAX_DOF], J2[3][MCA_MAX_DOF], r[3], rd[3], r2[3], rd2[3], v[3];
    if (mca_fk(c, q, &kin) != MCA_OK || mca_jacobian_ee(&kin, J) != MCA_OK ||
        mca_path_eval(arm->path, tau, r, rd) != MCA_OK ||
        mca_path_eval(arm->path, tau + RATE_DT, r2, rd2) != MCA_OK) {
        return MCA_EINVAL;
    }
    mca_apf_pinv_apply(J, dof, RATE_DAMPING * RATE_DAMPING, rd, qs);
    double q2[MCA_MAX_DOF];
    for (int j = 0; j < dof; j++) {
        q2[j] = q[j] + RATE_DT * qs[j];
    }
    if (mca_fk(c, q2, &kin) != MCA_OK || mca_jacobian_ee(&kin, J2) != MCA_OK) {
        return MCA_EINVAL;
    }
    /* d/dtau (J q_s) = r'': J q_ss = r'' - (dJ/dtau) q_s */
    for (int i = 0; i < 3; i++) {
        v[i] = (rd2[i] - rd[i]) / RATE_DT;
        for (int j = 0; j < dof; j++) {
            v[i] -= (J2[i][j] - J[i][j]) / RATE_DT * qs[j];
        }
    }
    mca_apf_pinv_apply(J, dof, RATE_DAMPING * RATE_DAMPING, v, qss);
    return MCA_OK;
}

int mca_path_rate_plan(const mca_coord_arm_t *arm, double dec, double sigma_cap, double q_work[][MCA_MAX_DOF],
                       mca_path_rate_t *out) {
    if (!arm || !arm->chain || !arm->path || !arm->q0 || !q_work || !out || !(dec > 0.0) ||
        !(sigma_cap > 0.0)) {
        return MCA_EINVAL;
    }
    memset(out, 0, sizeof *out);
    const mca_path_t *p = arm->path;
    const double T = mca_path_end_time(p);
    if (!p->path_first || (p->kind != MCA_PATH_CIRCLE && p->kind != MCA_PATH_WAYPOINTS) || !isfinite(T)) {
        return MCA_OK;
    }
    const double h = fmax(MCA_COORD_CELL_S, T / (MCA_COORD_MAX_CELLS - 2));
    const int n = (int)ceil(T / h) + 1;
    if (mca_coord_predict(arm, h, n, q_work) != MCA_OK) {
        return MCA_EINVAL;
    }
    const double theta = MCA_PATH_RATE_CURVE_SHARE;
    double acc[MCA_COORD_MAX_CELLS]; /* path-rate deceleration available in each cell [1/s^2] */
    for (int k = 0; k < n; k++) {
        double qs[MCA_MAX_DOF], qss[MCA_MAX_DOF];
        if (derivatives(arm, q_work[k], fmin(k * h, T), qs, qss) != MCA_OK) {
            return MCA_EINVAL;
        }
        double lim = sigma_cap, a = INFINITY;
        for (int j = 0; j < arm->chain->dof; j++) {
            if (fabs(qss[j]) > 0.0) {
                lim = fmin(lim, sqrt(theta * dec / fabs(qss[j])));
            }
            if (fabs(qs[j]) > 0.0) {
                a = fmin(a, (1.0 - theta) * dec / fabs(qs[j]));
            }
        }
        out->sigma[k] = (float)lim;
        out->decel[k] = (float)fmin(a, 1e30);
        acc[k] = a;
    }
    /* backwards: from every cell the next cell's limit must be reachable by slowing at acc */
    out->least = out->sigma[n - 1];
    for (int k = n - 2; k >= 0; k--) {
        const double next = out->sigma[k + 1];
        out->sigma[k] = (float)fmin(out->sigma[k], sqrt(next * next + 2.0 * acc[k] * h));
        out->least = fmin(out->least, out->sigma[k]);
    }
    out->n = n;
    out->h = h;
    return MCA_OK;
}

double mca_path_rate_at(const mca_path_rate_t *r, double tau) {
    if (r->n == 0) {
        return INFINITY;
    }
    const double x = fmax(0.0, tau / r->h);
    const int k = (int)x;
    if (k >= r->n - 1) {
        return r->sigma[r->n - 1];
    }
    const double f = x - k;
    return (1.0 - f) * r->sigma[k] + f * r->sigma[k + 1];
}

double mca_path_rate_decel(const mca_path_rate_t *r, double tau) {
    if (r->n == 0) {
        return INFINITY;
    }
    const int k = (int)fmax(0.0, fmin(r->n - 1.0, tau / r->h));
    return r->decel[k];
}
