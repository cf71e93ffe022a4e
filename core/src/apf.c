/* SPDX-License-Identifier: MIT */
/* APF baseline, paper Section V-B (40)-(46); see mca/apf.h. */
#include "mca/apf.h"

#include <math.h>
#include <string.h>

#include "mca/err.h"
#include "mca/vec3.h"

void mca_apf_default_params(mca_apf_params_t *p) {
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

double mca_apf_rep_speed(const mca_apf_params_t *p, double d_min) {
    return p->v_rep_max / (1.0 + exp(2.0 * d_min * p->theta / p->d));
}

void mca_apf_attractive(const mca_apf_params_t *p, const double ee[3], const double goal[3],
                        const double goal_vel[3], double v_att[3]) {
    double ep[3], n[3] = {0, 0, 0};
    mca_v3_sub(ep, goal, ee);
    const double e_p = mca_v3_norm(ep);
    if (e_p > 0.0) {
        for (int i = 0; i < 3; i++) {
            n[i] = ep[i] / e_p;
        }
    }
    /* (c I + a n n^T) V = b, c = 1 + (1 - rho) K_V, a = rho D_P,
     * b = rho K_P e_P n + a n (n^T S_G) + (1 - rho) K_V S_G */
    const double c = 1.0 + (1.0 - p->rho) * p->k_vel;
    const double a = p->rho * p->d_pos;
    const double ns = mca_v3_dot(n, goal_vel);
    double b[3];
    for (int i = 0; i < 3; i++) {
        b[i] = p->rho * p->k_pos * e_p * n[i] + a * n[i] * ns + (1.0 - p->rho) * p->k_vel * goal_vel[i];
    }
    /* Sherman-Morrison: V = (b - a/(c + a |n|^2) n (n^T b)) / c */
    const double nn = mca_v3_dot(n, n);
    const double nb = mca_v3_dot(n, b);
    for (int i = 0; i < 3; i++) {
        v_att[i] = (b[i] - a / (c + a * nn) * n[i] * nb) / c;
    }
}

int mca_apf_pinv_apply(const double J[3][MCA_MAX_DOF], int dof, double damping, const double v[3],
                       double *qdot) {
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
