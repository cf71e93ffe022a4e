/* SPDX-License-Identifier: MIT */
#include "qpgen.h"

#include <math.h>

double qpgen_uniform(qpgen_rng_t *r, double lo, double hi) {
    uint64_t z = (r->s += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    z ^= z >> 31;
    return lo + (hi - lo) * ((double)(z >> 11) * 0x1.0p-53);
}

void qpgen_scene_random(qpgen_scene_t *sc, qpgen_rng_t *r, double tight_prob) {
    for (int a = 0; a < QPGEN_ARMS; a++) {
        for (int k = 0; k < 3; k++) {
            for (int j = 0; j < QPGEN_DOF; j++) {
                /* lever arms shrink towards the tool, like a real arm's Jacobian columns */
                sc->J[a][k][j] = qpgen_uniform(r, -1.0, 1.0) * (1.0 - 0.08 * j);
            }
        }
        for (int l = 0; l < QPGEN_LINKS; l++) {
            for (int k = 0; k < 3; k++) {
                for (int j = 0; j < QPGEN_DOF; j++) {
                    sc->Jc[a][l][k][j] = j <= l ? qpgen_uniform(r, -0.8, 0.8) : 0.0;
                }
            }
        }
    }
    for (int j = 0; j < QPGEN_N; j++) {
        sc->ub[j] = qpgen_uniform(r, 0.8, 1.5);
        sc->lb[j] = -qpgen_uniform(r, 0.8, 1.5);
        sc->phi0[j] = qpgen_uniform(r, 0.7 * sc->lb[j], 0.7 * sc->ub[j]);
    }
    /* a joint or two without a bound, as the paper's box may be one-sided */
    sc->ub[(int)qpgen_uniform(r, 0, QPGEN_N)] = INFINITY;
    sc->lb[(int)qpgen_uniform(r, 0, QPGEN_N)] = -INFINITY;
    /* the normal-form directions come from a side stream, so the componentwise scenes (and the figures in
     * docs/pdnn.md) are the same as before they were added */
    qpgen_rng_t rd = {r->s ^ 0xD1B54A32D192ED03ull};
    for (int a = 0; a < QPGEN_ARMS; a++) {
        for (int l = 0; l < QPGEN_LINKS; l++) {
            double *d = sc->dir[a][l], nn = 0.0;
            do {
                for (int k = 0; k < 3; k++) {
                    d[k] = qpgen_uniform(&rd, -1.0, 1.0);
                }
                nn = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
            } while (nn < 1e-2 || nn > 1.0);
            for (int k = 0; k < 3; k++) {
                d[k] /= sqrt(nn);
            }
        }
    }
    for (int i = 0; i < QPGEN_NINEQ; i++) {
        /* tight rows get a small positive slack: exact zeros would make the three parallel rows of a
         * first link an implicit equality that rounding in beta can turn infeasible */
        sc->slack[i] = qpgen_uniform(r, 0.0, 1.0) < tight_prob ? qpgen_uniform(r, 1e-3, 0.03)
                                                               : qpgen_uniform(r, 0.05, 1.0);
    }
}

static void wiggle(double *v, int len, qpgen_rng_t *r, double eps) {
    for (int i = 0; i < len; i++) {
        if (v[i] != 0.0) { /* keep the structural zeros */
            v[i] += eps * qpgen_uniform(r, -1.0, 1.0);
        }
    }
}

void qpgen_scene_perturb(qpgen_scene_t *sc, qpgen_rng_t *r, double eps) {
    wiggle(&sc->J[0][0][0], QPGEN_ARMS * 3 * QPGEN_DOF, r, eps);
    wiggle(&sc->Jc[0][0][0][0], QPGEN_ARMS * QPGEN_LINKS * 3 * QPGEN_DOF, r, eps);
    for (int j = 0; j < QPGEN_N; j++) {
        const double p = sc->phi0[j] + eps * qpgen_uniform(r, -1.0, 1.0);
        if (p > 0.7 * sc->lb[j] && p < 0.7 * sc->ub[j]) {
            sc->phi0[j] = p;
        }
    }
    for (int i = 0; i < QPGEN_NINEQ; i++) {
        if (sc->slack[i] > 0.0) {
            sc->slack[i] = fmax(1e-3, sc->slack[i] + eps * qpgen_uniform(r, -1.0, 1.0));
        }
    }
}

void qpgen_build(const qpgen_scene_t *sc, mca_qp_t *qp) {
    mca_qp_reset(qp, QPGEN_N, QPGEN_NEQ, QPGEN_NINEQ);
    for (int a = 0; a < QPGEN_ARMS; a++) {
        for (int k = 0; k < 3; k++) {
            for (int j = 0; j < QPGEN_DOF; j++) {
                qp->G[3 * a + k][QPGEN_DOF * a + j] = sc->J[a][k][j];
            }
        }
        for (int l = 0; l < QPGEN_LINKS; l++) {
            for (int k = 0; k < 3; k++) {
                for (int j = 0; j < QPGEN_DOF; j++) {
                    qp->U[(a * QPGEN_LINKS + l) * 3 + k][QPGEN_DOF * a + j] = sc->Jc[a][l][k][j];
                }
            }
        }
    }
    for (int i = 0; i < QPGEN_NEQ; i++) {
        double s = 0.0;
        for (int j = 0; j < QPGEN_N; j++) {
            s += qp->G[i][j] * sc->phi0[j];
        }
        qp->alpha[i] = s;
    }
    for (int i = 0; i < QPGEN_NINEQ; i++) {
        double s = 0.0;
        for (int j = 0; j < QPGEN_N; j++) {
            s += qp->U[i][j] * sc->phi0[j];
        }
        qp->beta[i] = s + sc->slack[i];
    }
    for (int j = 0; j < QPGEN_N; j++) {
        qp->lb[j] = sc->lb[j];
        qp->ub[j] = sc->ub[j];
    }
}

void qpgen_build_normal(const qpgen_scene_t *sc, mca_qp_t *qp) {
    qpgen_build(sc, qp); /* G, alpha, box */
    qp->n_ineq = QPGEN_NINEQ_NORMAL;
    for (int a = 0; a < QPGEN_ARMS; a++) {
        for (int l = 0; l < QPGEN_LINKS; l++) {
            const int i = a * QPGEN_LINKS + l;
            double s = 0.0;
            for (int j = 0; j < QPGEN_N; j++) {
                qp->U[i][j] = 0.0;
            }
            for (int j = 0; j < QPGEN_DOF; j++) {
                double v = 0.0;
                for (int k = 0; k < 3; k++) {
                    v += sc->dir[a][l][k] * sc->Jc[a][l][k][j];
                }
                qp->U[i][QPGEN_DOF * a + j] = v;
                s += v * sc->phi0[QPGEN_DOF * a + j];
            }
            qp->beta[i] = s + sc->slack[(a * QPGEN_LINKS + l) * 3];
        }
    }
    for (int i = QPGEN_NINEQ_NORMAL; i < QPGEN_NINEQ; i++) {
        for (int j = 0; j < QPGEN_N; j++) {
            qp->U[i][j] = 0.0;
        }
        qp->beta[i] = 0.0;
    }
}

void qpgen_couple(const qpgen_scene_t *sc, mca_qp_t *qp, int row) {
    double s = 0.0;
    for (int j = 0; j < QPGEN_N; j++) {
        qp->U[row][j] += 0.3 * (1.0 - 0.05 * j);
        s += qp->U[row][j] * sc->phi0[j];
    }
    qp->beta[row] = s + sc->slack[row];
}
