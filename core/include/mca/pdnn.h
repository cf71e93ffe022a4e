/* SPDX-License-Identifier: MIT */
/** @file mca/pdnn.h
 * LVI-PDNN solver (paper (29)-(32)) for mca_qp_t:
 *   y = [phi; v_e; v_i],  M = [I -G^T U^T; G 0 0; -U 0 0],  q = [0; -alpha; beta],
 *   Omega = box [lb, ub] x [-big, big]^{n_eq} x [0, big]^{n_ineq},
 *   ydot = lambda (I + M^T) (P_Omega(y - (M y + q)) - y),
 * integrated by explicit Euler steps y += kappa (I + M^T) e(y), kappa = lambda * dt, warm-started from the
 * previous solve. Stops when ||e(y)||_inf <= tol or after max_steps. Matrix work on fixed-size Eigen
 * matrices in a C++ shim; no allocation after mca_pdnn_init(). Real-time safe.
 */
#ifndef MCA_PDNN_H
#define MCA_PDNN_H

#include "mca/qp.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct mca_pdnn_params {
    double kappa;  /**< Euler step (lambda * dt); <= 0: chosen each solve from the stability bound */
    double tol;    /**< residual tolerance ||P_Omega(y - (My+q)) - y||_inf */
    int max_steps; /**< step cap per solve */
    double big;    /**< the paper's varpi, stands for +infinity in Omega */
} mca_pdnn_params_t;

typedef struct mca_pdnn_result {
    int steps;          /**< Euler steps taken */
    double residual;    /**< final ||e(y)||_inf */
    int converged;      /**< residual <= tol */
    double kappa;       /**< step size used */
} mca_pdnn_result_t;

/** Solver state: the primal-dual vector kept between ticks for warm starts. */
typedef struct mca_pdnn {
    int h;                      /**< current length of y (0: cold) */
    double y[MCA_QP_MAX_H];
} mca_pdnn_t;

/** Defaults: kappa from the bound, tol 1e-9, max_steps, big 1e10. */
void mca_pdnn_default_params(mca_pdnn_params_t *params);

/** Cold state (y = 0). */
void mca_pdnn_init(mca_pdnn_t *s);

/**
 * Solve @p qp, starting from the state's y when its size matches the QP's (else from 0).
 * @param[out] phi  the primal part (qp->n values)
 * @retval MCA_OK         converged
 * @retval MCA_ENOTCONV   step cap hit (phi, result still filled from the last iterate)
 * @retval MCA_EINVAL     NULL, bad sizes or non-finite data
 */
int mca_pdnn_solve(mca_pdnn_t *s, const mca_qp_t *qp, const mca_pdnn_params_t *params, double *phi,
                   mca_pdnn_result_t *result);

#ifdef __cplusplus
}
#endif
#endif
