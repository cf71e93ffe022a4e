/* SPDX-License-Identifier: MIT */
/** @file mca/qp_dump.h
 * The JSON dump of a QP (one file per QP) for the independent OSQP check (tools/qp-check). Part of the model
 * library (mca_model): it writes files, which the real-time core never does.
 */
#ifndef MCA_QP_DUMP_H
#define MCA_QP_DUMP_H

#include "mca/qp.h"

#ifdef __cplusplus
extern "C" {
#endif

/**
 * Write the QP (and, when phi != NULL, the solver's answer with its steps and residual) as JSON:
 * {"n":..,"n_eq":..,"n_ineq":..,"G":[[..]],"alpha":[..],"U":[[..]],"beta":[..],"lb":[..],"ub":[..],
 *  "phi":[..],"steps":..,"residual":..,"tag":".."}; infinities are written as null. Non-real-time (file I/O).
 * @retval MCA_OK, MCA_EIO
 */
int mca_qp_dump_json(const mca_qp_t *qp, const double *phi, int steps, double residual, const char *tag,
                     const char *path);

#ifdef __cplusplus
}
#endif
#endif
