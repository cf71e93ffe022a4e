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
    double d;       /**< distance |P - E| */
    double p[3];    /**< critical point P on AB */
    double e[3];    /**< critical point E on CD */
    double s;       /**< P = A + s (B - A), s in [0, 1] */
    double t;       /**< E = C + t (D - C), t in [0, 1] */
    int iterations; /**< point-to-segment projections done (LSDM); 0 for the closed form */
} mca_segdist_t;

typedef struct mca_lsdm_params {
    double tol;   /**< stop when the distance decreases by less than this [m] */
    int max_iter; /**< projection cap */
} mca_lsdm_params_t;

/** Default LSDM parameters (used by mca_arm_distances with MCA_DIST_LSDM). The paper stops when the
 *  distance declines by less than 1e-5 m (MCA_LSDM_PAPER_TOL); the default is tighter, see docs/segdist.md
 *  for what either rule really guarantees (not the 1e-9 m the controller needs: use the closed form). */
#define MCA_LSDM_DEFAULT_TOL 1e-12
#define MCA_LSDM_DEFAULT_MAX_ITER 200
#define MCA_LSDM_PAPER_TOL 1e-5

/** Largest accepted |coordinate| [m]: beyond it squared differences could overflow (MCA_EINVAL). */
#define MCA_SEGDIST_MAX_COORD 1e100

/** Closed-form segment-segment distance.
 *  @retval MCA_OK, MCA_EINVAL (NULL, non-finite input or |coordinate| > MCA_SEGDIST_MAX_COORD) */
int mca_segdist_closed(const double a[3], const double b[3], const double c[3], const double d[3],
                       mca_segdist_t *out);

/** The paper's LSDM, started at endpoint B (Step 3); each point-segment projection (Step 1) is one
 *  iteration; stops when the distance declined by less than params->tol. params NULL = the defaults.
 *  NOT accurate to 1e-9 m in general (docs/segdist.md): the controller uses mca_segdist_closed().
 *  @retval MCA_OK, MCA_EINVAL (NULL point/out, non-finite or too large input, tol < 0, max_iter < 2),
 *  MCA_ENOTCONV (cap hit; out still holds the best pair found) */
int mca_segdist_lsdm(const double a[3], const double b[3], const double c[3], const double d[3],
                     const mca_lsdm_params_t *params, mca_segdist_t *out);

/**
 * LSDM with a provably right stopping rule: the same alternating projections as mca_segdist_lsdm(), but it
 * stops only when the duality gap d - lb <= params->tol, where lb = min(n.A, n.B) - max(n.C, n.D) with
 * n = (P - E) / |P - E| is a lower bound on the true minimum (separating-plane certificate). On MCA_OK the
 * returned d is within tol of the true minimum (plus rounding). @retval MCA_OK, MCA_EINVAL, MCA_ENOTCONV
 */
int mca_segdist_lsdm_certified(const double a[3], const double b[3], const double c[3], const double d[3],
                               const mca_lsdm_params_t *params, mca_segdist_t *out);

/**
 * Certificate for any pair P = A + s(B - A), E = C + t(D - C): a lower bound on the minimum distance
 * (separating-plane bound along P - E; 0 when P == E, and never above the true minimum up to rounding).
 */
double mca_segdist_lower_bound(const double a[3], const double b[3], const double c[3], const double d[3],
                               const double p[3], const double e[3]);

/** Paper's Step 1: closest point H on segment AB to point O (zero-length AB gives A).
 *  @param[out] h closest point; @param[out] s H = A + s (B - A) (may be NULL). @return |OH| */
double mca_point_segment_paper(const double o[3], const double a[3], const double b[3], double h[3],
                               double *s);

#ifdef __cplusplus
}
#endif
#endif
