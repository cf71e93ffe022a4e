/* SPDX-License-Identifier: MIT */
/* APF baseline, paper Section V-B (40)-(46); see mca/apf.h. */
#include "mca/apf.h"

#include <math.h>
#include <string.h>

#include "mca/err.h"
#include "mca/vec3.h"

void mca_apf_default_params(mca_apf_params_t *p)
{
    memset(p, 0, sizeof *p);
    p->k_pos = 100.0;
    p->d_pos = 0.1;
    p->k_vel = 5.0;
    p->d_vel = 0.1;
    p->rho = 0.8;
    p->d = 0.12;
    p->v_rep_max = 0.001;
    p->theta = 1.0;
    p->damping = 0.0;
}

double mca_apf_rep_speed(const mca_apf_params_t *p, double d_min)
{
    return p->v_rep_max / (1.0 + exp(2.0 * d_min * p->theta / p->d));
}

void mca_apf_attractive(const mca_apf_params_t *p, mca_apf_state_t *st, const double ee[3],
                        const double ee_vel[3], const double goal[3], const double goal_vel[3], double dt,
                        double v_att[3])
{
    double ep[3], ev[3];
    mca_v3_sub(ep, goal, ee);
    mca_v3_sub(ev, goal_vel, ee_vel);
    const double e_p = mca_v3_norm(ep), e_v = mca_v3_norm(ev);
    double de_p = 0.0, de_v = 0.0;
    if (st->primed && dt > 0.0) {
        de_p = (e_p - st->e_pos_prev) / dt;
        de_v = (e_v - st->e_vel_prev) / dt;
    }
    st->primed = 1;
    st->e_pos_prev = e_p;
    st->e_vel_prev = e_v;
    const double dp = p->k_pos * e_p + p->d_pos * de_p; /* (40) */
    const double dv = p->k_vel * e_v + p->d_vel * de_v; /* (41) */
    for (int i = 0; i < 3; i++) {
        const double vp = e_p > 0.0 ? dp * ep[i] / e_p : 0.0;
        const double vv = e_v > 0.0 ? dv * ev[i] / e_v : 0.0;
        v_att[i] = p->rho * vp + (1.0 - p->rho) * vv; /* (42) */
    }
}

int mca_apf_pinv_apply(const double J[3][MCA_MAX_DOF], int dof, double damping, const double v[3],
                       double *qdot)
{
    /* A = J J^T + damping I (3 x 3, symmetric), x = A^-1 v, qdot = J^T x */
    double A[3][3];
    for (int i = 0; i < 3; i++) {
        for (int k = 0; k < 3; k++) {
            double s = 0.0;
            for (int j = 0; j < dof; j++) {
                s += J[i][j] * J[k][j];
            }
            A[i][k] = s + (i == k ? damping : 0.0);
        }
    }
    const double c00 = A[1][1] * A[2][2] - A[1][2] * A[2][1];
    const double c01 = A[1][2] * A[2][0] - A[1][0] * A[2][2];
    const double c02 = A[1][0] * A[2][1] - A[1][1] * A[2][0];
    const double det = A[0][0] * c00 + A[0][1] * c01 + A[0][2] * c02;
    const double scale = A[0][0] + A[1][1] + A[2][2];
    if (!(fabs(det) > 1e-15 * scale * scale * scale) || !isfinite(det)) {
        for (int j = 0; j < dof; j++) {
            qdot[j] = 0.0;
        }
        return MCA_EINFEASIBLE;
    }
    double inv[3][3];
    inv[0][0] = c00 / det;
    inv[0][1] = (A[0][2] * A[2][1] - A[0][1] * A[2][2]) / det;
    inv[0][2] = (A[0][1] * A[1][2] - A[0][2] * A[1][1]) / det;
    inv[1][0] = c01 / det;
    inv[1][1] = (A[0][0] * A[2][2] - A[0][2] * A[2][0]) / det;
    inv[1][2] = (A[0][2] * A[1][0] - A[0][0] * A[1][2]) / det;
    inv[2][0] = c02 / det;
    inv[2][1] = (A[0][1] * A[2][0] - A[0][0] * A[2][1]) / det;
    inv[2][2] = (A[0][0] * A[1][1] - A[0][1] * A[1][0]) / det;
    double x[3];
    for (int i = 0; i < 3; i++) {
        x[i] = inv[i][0] * v[0] + inv[i][1] * v[1] + inv[i][2] * v[2];
    }
    for (int j = 0; j < dof; j++) {
        qdot[j] = J[0][j] * x[0] + J[1][j] * x[1] + J[2][j] * x[2];
    }
    return MCA_OK;
}
