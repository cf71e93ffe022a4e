/* SPDX-License-Identifier: MIT */
/* Random dual-arm-shaped QPs (n = 16, n_eq = 6, n_ineq = 54) for the PDNN tests and benchmark.
 * A "scene" holds what a controller tick would produce: each arm's 3x8 end-effector Jacobian, per link a
 * 3-row critical-point Jacobian (nonzero only in the joints before that link, as U = blkdiag(J_NL, J_NR)),
 * a feasible phi0 inside the joint-velocity box and a slack per collision row; alpha = G phi0 and
 * beta = U phi0 + slack make every QP feasible, and small slacks give a realistic few active rows. */
#ifndef MCA_TEST_QPGEN_H
#define MCA_TEST_QPGEN_H

#include <stdint.h>

#include "mca/qp.h"

#define QPGEN_ARMS 2
#define QPGEN_DOF 8
#define QPGEN_LINKS 9
#define QPGEN_N (QPGEN_ARMS * QPGEN_DOF)
#define QPGEN_NEQ (QPGEN_ARMS * 3)
#define QPGEN_NINEQ (QPGEN_ARMS * QPGEN_LINKS * 3)

typedef struct qpgen_rng {
    uint64_t s;
} qpgen_rng_t;

/** Uniform in [lo, hi) (splitmix64, reproducible across platforms). */
double qpgen_uniform(qpgen_rng_t *r, double lo, double hi);

typedef struct qpgen_scene {
    double J[QPGEN_ARMS][3][QPGEN_DOF];
    double Jc[QPGEN_ARMS][QPGEN_LINKS][3][QPGEN_DOF];
    double phi0[QPGEN_N];
    double slack[QPGEN_NINEQ];
    double lb[QPGEN_N], ub[QPGEN_N];
    double dir[QPGEN_ARMS][QPGEN_LINKS][3]; /**< unit P -> E direction per link (normal form) */
} qpgen_scene_t;

/** A fresh random scene; tight_prob is the chance that a collision row is nearly tight at phi0
 *  (slack in [1e-3, 0.03) instead of [0.05, 1)). */
void qpgen_scene_random(qpgen_scene_t *sc, qpgen_rng_t *r, double tight_prob);

/** Move the scene a little (relative size eps), as one control tick would; stays feasible. */
void qpgen_scene_perturb(qpgen_scene_t *sc, qpgen_rng_t *r, double eps);

/** The QP of the scene. */
void qpgen_build(const qpgen_scene_t *sc, mca_qp_t *qp);

/** The normal-form QP of the scene (mca_scheme's default): one row per link, dir^T Jc, n_ineq = 18, with
 *  the slack of the link's first componentwise row. */
#define QPGEN_NINEQ_NORMAL (QPGEN_ARMS * QPGEN_LINKS)
void qpgen_build_normal(const qpgen_scene_t *sc, mca_qp_t *qp);

/** Make inequality row @p row couple the two arms (entries in both arms' columns), keeping the QP feasible
 *  at phi0: the QP then no longer splits into one block per arm. */
void qpgen_couple(const qpgen_scene_t *sc, mca_qp_t *qp, int row);

#endif
