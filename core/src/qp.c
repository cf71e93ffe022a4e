/* SPDX-License-Identifier: MIT */
/* The standard QP container (its JSON dump is model/src/qp_dump.c). */
#include "mca/qp.h"

#include <string.h>

#include "mca/err.h"

int mca_qp_reset(mca_qp_t *qp, int n, int n_eq, int n_ineq) {
    if (qp == NULL || n < 0 || n_eq < 0 || n_ineq < 0) {
        return MCA_EINVAL;
    }
    if (n > MCA_QP_MAX_VARS || n_eq > MCA_QP_MAX_EQ || n_ineq > MCA_QP_MAX_INEQ) {
        return MCA_ERANGE;
    }
    /* Only the rows in use: rows past the counts are never read, and zeroing all of them (46 kB) was a
     * fifth of a tick. Equality rows at full width (mca_scheme_add_timescale appends columns to them);
     * inequality rows only in their first n columns, all that is read of them (columns appended later are
     * cleared by whoever appends them): a cell's 100-odd body slots at full width were half its tick. */
    memset(qp->G, 0, sizeof(qp->G[0]) * (size_t)n_eq);
    for (int i = 0; i < n_ineq; i++) {
        memset(qp->U[i], 0, sizeof(double) * (size_t)n);
    }
    memset(qp->alpha, 0, sizeof(qp->alpha));
    memset(qp->beta, 0, sizeof(qp->beta));
    memset(qp->lb, 0, sizeof(qp->lb));
    memset(qp->ub, 0, sizeof(qp->ub));
    qp->n = n;
    qp->n_eq = n_eq;
    qp->n_ineq = n_ineq;
    return MCA_OK;
}
