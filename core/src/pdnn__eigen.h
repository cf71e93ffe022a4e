/* SPDX-License-Identifier: MIT */
/* Private: the Eigen side of the LVI-PDNN solver (core/src/pdnn_eigen.cpp), called by pdnn.c only. */
#ifndef MCA_PDNN__EIGEN_H
#define MCA_PDNN__EIGEN_H

#include "mca/pdnn.h"

#ifdef __cplusplus
extern "C" {
#endif

/** What the iteration needs; all arrays belong to the caller (the mca_pdnn_t workspace). */
typedef struct mca_pdnn__problem {
    int n, m;         /**< primal size, dual size (n_eq + n_ineq) */
    const double *N;  /**< m x n row-major, [G; -U] (possibly rewritten, pdnn.c) */
    const double *q;  /**< m, [-alpha; beta] (likewise) */
    const double *lo; /**< n + m, Omega lower bounds */
    const double *hi; /**< n + m, Omega upper bounds */
    /** m, or NULL: how a row reads in the QP as given: multiplier f w, row value b / f (b = (N x + q)_i);
     *  finv = 1 / f. */
    const double *f, *finv;
    int64_t deadline_ns; /**< CLOCK_MONOTONIC instant to stop at (checked every 16 steps); 0: none */
    /** n, or NULL: each variable's box side in the last polished answer (0 unknown, 1 lower, 2 upper,
     *  4 free), the warm polish's seed for the box; overwritten with the sides of an accepted polish */
    unsigned char *side;
} mca_pdnn__problem_t;

/** Upper bound on ||N||_2^2: Gershgorin row bound of N^T N. No allocation. */
double mca_pdnn__norm_sq_bound(const mca_pdnn__problem_t *p);

/**
 * Explicit Euler steps y += kappa_k (I + M^T) e(y) from y (n + m values, updated in place) until the
 * residual, read through f in the QP as given, is <= tol, or max_steps updates were made; stops early on a
 * non-finite residual. keep_best: when the cap comes first, leave y at the least-residual point seen.
 * kappa_fixed > 0: constant step; else kappa_k = gamma ||e||^2 / ||(I + M^T) e||^2. polish_max: at most that
 * many active-set polish tries (an exact solve of a guessed active set, kept only if it meets tol). Fills
 * steps, residual, converged, kappa, polish_tries and sets polished when a polish ended it. No allocation.
 */
void mca_pdnn__iterate(const mca_pdnn__problem_t *p, double *y, double kappa_fixed, double gamma, double tol,
                       int max_steps, int keep_best, int polish_max, mca_pdnn_result_t *res);

#ifdef __cplusplus
}
#endif
#endif
