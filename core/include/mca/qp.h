/* SPDX-License-Identifier: MIT */
/** @file mca/qp.h
 * The standard QP of the paper (25)-(28), fixed-size:
 *     minimize 1/2 phi^T phi
 *     subject to G phi = alpha,  U phi <= beta,  lb <= phi <= ub
 * Its JSON dump for the independent OSQP check is in the model library (mca/qp_dump.h).
 */
#ifndef MCA_QP_H
#define MCA_QP_H

#include "mca/limits.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct mca_qp {
    int n;      /**< variables (2n for two arms) */
    int n_eq;   /**< equality rows */
    int n_ineq; /**< inequality rows */
    double G[MCA_QP_MAX_EQ][MCA_QP_MAX_VARS];
    double alpha[MCA_QP_MAX_EQ];
    double U[MCA_QP_MAX_INEQ][MCA_QP_MAX_VARS];
    double beta[MCA_QP_MAX_INEQ];
    double lb[MCA_QP_MAX_VARS]; /**< may be -INFINITY */
    double ub[MCA_QP_MAX_VARS]; /**< may be +INFINITY */
} mca_qp_t;

/** Set the QP's sizes and zero what they use: the equality rows at full width, the first n columns of the
 *  inequality rows (rows past n_eq / n_ineq and those rows' columns past n are left as they are).
 *  @retval MCA_OK, MCA_ERANGE (size above the maximums) */
int mca_qp_reset(mca_qp_t *qp, int n, int n_eq, int n_ineq);

#ifdef __cplusplus
}
#endif
#endif
