/* SPDX-License-Identifier: MIT */
/* What the row builders of the core share (scheme.c, bodyrows.c); private to mca_core. Context: rt. */
#ifndef MCA_SCHEME__ROWS_H
#define MCA_SCHEME__ROWS_H

#include "mca/qp.h"

/* Row r of one arm (columns vo..vo+dof-1) against that arm's rows kept before it (kept[0..n_kept), their
 * norms in kept_norm; r's norm is written to kept_norm[n_kept]): when one of them is parallel to r within
 * 1e-3, the tighter bound of the two stays in the kept row and 1 is returned (r is to be dropped). Rows
 * parallel to 1e-7 made the active set degenerate. */
int mca__scheme_merge_parallel(mca_qp_t *qp, int vo, int dof, int r, const int *kept, double *kept_norm,
                               int n_kept);

#endif
