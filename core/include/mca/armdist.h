/* SPDX-License-Identifier: MIT */
/** @file mca/armdist.h
 * Arm-to-arm distances (the paper's Fig. 4(d)): for each link of one arm the closest link of the other
 * arm with its critical pair, and the global minimum. Links are capsules: the distance reported is the
 * axis-to-axis segment distance minus both radii (negative when the capsules overlap). Critical points
 * P and E lie on the link AXES (the direction P->E is the escape direction).
 * Real-time safe: no allocation, bounded time (MCA_MAX_LINKS^2 segment pairs).
 */
#ifndef MCA_ARMDIST_H
#define MCA_ARMDIST_H

#include "mca/chain.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum mca_dist_method {
    MCA_DIST_CLOSED = 0, /**< closed-form segment distance (exact; the controller default) */
    MCA_DIST_LSDM = 1,   /**< the paper's iterative LSDM */
} mca_dist_method_t;

typedef struct mca_link_pair {
    int link;       /**< link index on this arm */
    int other_link; /**< closest link on the other arm */
    double d;       /**< surface distance = axis distance - both radii [m] */
    double d_axis;  /**< axis-to-axis segment distance [m] */
    double p[3];    /**< critical point on this link's axis (world) */
    double e[3];    /**< critical point on the other link's axis (world) */
} mca_link_pair_t;

typedef struct mca_arm_distances {
    int n_links_a; /**< links of arm A (dof_a + 1) */
    int n_links_b;
    mca_link_pair_t a_to_b[MCA_MAX_LINKS]; /**< per link of A: closest link of B (p on A, e on B) */
    mca_link_pair_t b_to_a[MCA_MAX_LINKS]; /**< per link of B: closest link of A (p on B, e on A) */
    mca_link_pair_t min;                   /**< global minimum, seen from A (p on A, e on B) */
    mca_link_pair_t pair[MCA_MAX_LINKS]
                        [MCA_MAX_LINKS]; /**< [i][j]: link i of A against link j of B (p on A) */
    int iterations;                      /**< total LSDM iterations (0 for the closed form) */
} mca_arm_distances_t;

/**
 * All link-pair distances between two arms at their current kinematic states.
 * Pairs where either link has zero moving joints on both sides are still included.
 * MCA_DIST_LSDM uses the default LSDM parameters of segdist.h.
 * @retval MCA_OK, MCA_EINVAL
 */
int mca_arm_distances(const mca_chain_t *chain_a, const mca_kin_t *kin_a, const mca_chain_t *chain_b,
                      const mca_kin_t *kin_b, mca_dist_method_t method, mca_arm_distances_t *out);

/**
 * Least surface distance between two arms given their link points (mca_kin_t.point: link k is point[k] ->
 * point[k+1]), or `cap` when it is at least that; links whose bounding spheres are farther than the best so
 * far are skipped. The pair of both fixed links (link 0 of each) is left out: it never moves, and the rows do
 * not act on it. Real-time safe.
 */
double mca_arm_least_distance(const mca_chain_t *chain_a, const double pa[][3], const mca_chain_t *chain_b,
                              const double pb[][3], double cap);

#ifdef __cplusplus
}
#endif
#endif
