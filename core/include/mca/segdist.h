/* SPDX-License-Identifier: MIT */
/** @file mca/segdist.h
 * Minimum distance between two line segments AB and CD:
 *  - mca_segdist_lsdm(): the paper's iterative line-segment distance measure (Section III-B);
 *  - mca_segdist_closed(): closed-form clamped parametric solution (robust for parallel,
 *    collinear, intersecting and zero-length segments), the independent check.
 * Both are real-time safe (no allocation, bounded time).
 */
#ifndef MCA_SEGDIST_H
#define MCA_SEGDIST_H

#ifdef __cplusplus
extern "C" {
#endif

typedef struct mca_segdist {
    double d;      /**< distance |P - E| */
    double p[3];   /**< critical point P on AB */
    double e[3];   /**< critical point E on CD */
    double s;      /**< P = A + s (B - A), s in [0, 1] */
    double t;      /**< E = C + t (D - C), t in [0, 1] */
    int iterations; /**< point-to-segment projections done (LSDM); 0 for the closed form */
} mca_segdist_t;

typedef struct mca_lsdm_params {
    double tol;   /**< stop when the distance decreases by less than this [m] */
    int max_iter; /**< projection cap */
} mca_lsdm_params_t;

/** Closed-form segment-segment distance. @retval MCA_OK, MCA_EINVAL (NULL or non-finite input) */
int mca_segdist_closed(const double a[3], const double b[3], const double c[3], const double d[3],
                       mca_segdist_t *out);

/** The paper's LSDM, started at endpoint B. @retval MCA_OK, MCA_EINVAL, MCA_ENOTCONV (cap hit; out
 *  still holds the best pair found) */
int mca_segdist_lsdm(const double a[3], const double b[3], const double c[3], const double d[3],
                     const mca_lsdm_params_t *params, mca_segdist_t *out);

#ifdef __cplusplus
}
#endif
#endif
