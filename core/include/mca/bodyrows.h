/* SPDX-License-Identifier: MIT */
/** @file mca/bodyrows.h
 * The fixed bodies of a cell on the tick (tables, fixtures, cups): each arm link against each body that does
 * not allow it gets the arm-pair rows' kind of hard row,
 *
 *     -n^T J_P qdot_a <= 2 min{ S_b(d) v_normal (d < d2_b only), (d - c_b') / (2 T_a) },
 *
 * n the unit normal from the body toward the link (mca/body.h), P the witness on the link's axis, J_P its
 * positional Jacobian, c_b the body's clearance (its d1), d2_b = c_b + (d2 - d1) (the arm pairs' band
 * width), c_b' = c_b + d1_margin (at most halfway to d2_b), S_b = S on [c_b', d2_b], T_a the arm's stop time
 * (mca_scheme_stop_time). The factor 2 is the whole share of the approach budget: a body does not move, so
 * the arm owns the whole margin (docs/scheme.md, "Fixed bodies"). Per link the MCA_BODY_PAIRS witness pairs
 * of least margin d - c_b are kept: the closest points and the distances of the link's two ends (for a
 * capsule body also its two ends against the link): the distance is the least of these, and which one is
 * least can jump (a link level above a table). Only pairs whose row can bind inside the QP's box are listed
 * (as the arm pairs': docs/scheme.md section 10), and a cheap bounding-sphere test skips the rest.
 *
 *
 * Self pairs (docs/scheme.md, "Self pairs") are one more kind of pair: link l against link q < l of the same
 * arm as if q were a capsule body of clearance d1, the row's Jacobian the difference of the two witnesses',
 *
 *     -n^T (J_P - J_Q) qdot_a <= 2 min{ S(d) v_normal (d < d2 only), (d - d1') / (2 T_a) },
 *
 * in the same lists and slots as the bodies' (the MCA_BODY_PAIRS of least margin per link, over both kinds).
 * The factor is again 2: both witnesses are on the one arm, which brakes them together, so it owns the
 * whole margin.
 *
 * Context: rt (no allocation, no locks, no formatting, bounded time), except mca_body_check (start-up).
 */
#ifndef MCA_BODYROWS_H
#define MCA_BODYROWS_H

#include "mca/body.h"
#include "mca/chain.h"
#include "mca/limits.h"
#include "mca/qp.h"
#include "mca/scheme.h"

#ifdef __cplusplus
extern "C" {
#endif

/** One fixed body of a cell, as the controller keeps it. */
typedef struct mca_fixed_body {
    char name[32];
    mca_body_t body;              /**< kind and geometry, world frame (mca/body.h) */
    double clearance;             /**< [m] what every link it does not allow keeps from it (its d1) */
    unsigned allow[MCA_MAX_ARMS]; /**< bit l of allow[a]: link l of arm a may touch it (no rows, no fault) */
    double v[3];                  /**< a streamed body's velocity [m/s] (mca/track.h); 0 for a fixed body */
    double grow;                  /**< a stale streamed body's surface growth [m/s]; 0 for a fixed body */
} mca_fixed_body_t;

/** An arm's self pairs: bit q of s[l] (q < l): link l is kept from the same arm's link q (mca/bodyrows.h, the
 *  self rows; bits with q >= l are ignored). */
typedef unsigned mca_self_pairs_t[MCA_MAX_LINKS];

/** One witness pair of a link against a body, or against another link of its own arm (a row's data). */
typedef struct mca_body_witness {
    int valid;
    int body;      /**< index into the bodies; -1 for a self pair */
    int link;      /**< a self pair's other link (its "body", the same arm's), -1 for a body */
    double d;      /**< signed surface distance [m] */
    double margin; /**< d - clearance [m]: the list's order */
    double p[3];   /**< on the link's axis (the Jacobian's point) */
    double q[3];   /**< on the body (on the other link's surface) */
    double n[3];   /**< unit normal from the body toward the link */
} mca_body_witness_t;

/** The self pair of least distance (two links of one arm). */
typedef struct mca_self_nearest {
    int valid;     /**< 0: no self pairs */
    int arm, link; /**< the arm, its outer link of the pair */
    int other;     /**< its inner link (other < link) */
    double d;      /**< surface distance [m] (+INF: no pair) */
    double p[3], q[3];
} mca_self_nearest_t;

/** The arm-body pair of least margin. */
typedef struct mca_body_nearest {
    int valid; /**< 0: no pair (no bodies, or every link allowed) */
    int arm, link, body, kind;
    double d, margin; /**< surface distance, d - clearance [m] */
    double p[3], q[3];
} mca_body_nearest_t;

/** How far a link's axis may move from its reference before mca_body_cache_update measures it again [m]. */
#define MCA_BODY_CACHE_REFRESH 0.01

/**
 * What the tick keeps between ticks to skip the pairs that are far (mca_body_cache_update): each link's axis
 * at a reference pose and the exact surface distances of that reference to every body and to the link's
 * self-pair partners (their references). A link whose two ends have each moved by at most s from their
 * reference is at least d_ref - s from a body (every point of a segment moves by at most the larger of its
 * ends' moves; a self pair: d_ref - s_l - s_q), so a pair whose bound already puts it beyond every use is
 * skipped without its distance. Only bounds come from it: the answers are those without a cache. A body
 * whose geometry changed (a streamed one) is measured as without it until it holds still for a tick. Zero
 * it to start (or after the bodies or arms changed).
 */
typedef struct mca_body_cache {
    int valid[MCA_MAX_ARMS][MCA_MAX_LINKS];   /**< the link's reference is set */
    double a[MCA_MAX_ARMS][MCA_MAX_LINKS][3]; /**< the reference: the axis's ends */
    double b[MCA_MAX_ARMS][MCA_MAX_LINKS][3];
    double radius[MCA_MAX_ARMS][MCA_MAX_LINKS];            /**< the link radius it was measured with */
    double d[MCA_MAX_ARMS][MCA_MAX_LINKS][MCA_MAX_BODIES]; /**< reference to body [m]; -INF: unknown */
    double ds[MCA_MAX_ARMS][MCA_MAX_LINKS][MCA_MAX_LINKS]; /**< [l][q], q < l: the two references [m] */
    mca_body_t body[MCA_MAX_BODIES];                       /**< the bodies the distances are to */
    int stale[MCA_MAX_BODIES];                             /**< changed last update: no distances yet */
    double seen[MCA_MAX_ARMS][MCA_MAX_POINTS][3];          /**< the poses of the last update */
    double move[MCA_MAX_ARMS][MCA_MAX_LINKS];              /**< their moves from the references [m] */
    int n_bodies;
} mca_body_cache_t;

/**
 * Bring the cache up to this tick's poses and bodies: a link that moved more than MCA_BODY_CACHE_REFRESH from
 * its reference (or has none) gets the pose as its new one, measured against every body and its self-pair
 * partners (self, NULL: none); a body whose geometry changed is marked unknown, and measured from every
 * reference at the first update it has not changed again. Context: rt (bounded: at most every pair once).
 * @retval MCA_OK, MCA_EINVAL (NULL, sizes out of range)
 */
int mca_body_cache_update(mca_body_cache_t *c, int n_arms, const mca_chain_t *const chain[],
                          const mca_kin_t kin[], const mca_fixed_body_t *bodies, int n_bodies,
                          const mca_self_pairs_t *self);

/** "plane", "sphere", "capsule", "box", "cylinder"; "unknown" otherwise. */
const char *mca_body_kind_name(int kind);

/**
 * A body's geometry and clearance are usable (start-up): finite, clearance >= 0, its motion finite (grow >=
 * 0), radii and half extents >= 0, normal and axis not zero, a box's rotation orthonormal (one probe distance
 * answers).
 * @retval MCA_OK, MCA_EINVAL
 */
int mca_body_check(const mca_fixed_body_t *b);

/** The scheme's parameters for a body of this clearance: d1 = clearance, d2 = clearance + (d2 - d1). */
void mca_body_band(const mca_scheme_params_t *p, double clearance, mca_scheme_params_t *pb);

/**
 * The arm-body pair of least margin over every link and every body that does not allow it. cache: bounds
 * that skip far pairs (mca_body_cache_update on these poses, or older ones; NULL: none), the same answer.
 * @retval MCA_OK, MCA_EINVAL (NULL, a distance failed: non-finite geometry)
 */
int mca_body_nearest(int n_arms, const mca_chain_t *const chain[], const mca_kin_t kin[],
                     const mca_fixed_body_t *bodies, int n_bodies, const mca_body_cache_t *cache,
                     mca_body_nearest_t *out);

/**
 * Per body its link of least margin (what a monitor shows: each body's closest link): out[k] for body k,
 * out[k].valid 0 when every link is allowed (body and kind are set either way).
 * @param out  n_bodies entries
 * @retval MCA_OK, MCA_EINVAL (NULL, n_bodies outside 0..MCA_MAX_BODIES, a distance failed)
 */
int mca_body_nearest_each(int n_arms, const mca_chain_t *const chain[], const mca_kin_t kin[],
                          const mca_fixed_body_t *bodies, int n_bodies, mca_body_nearest_t out[]);

/**
 * The self pair of least surface distance over every arm's self pairs (self[a], NULL: none); cache as for
 * mca_body_nearest.
 * @retval MCA_OK, MCA_EINVAL (NULL, a distance failed: non-finite geometry)
 */
int mca_self_nearest(int n_arms, const mca_chain_t *const chain[], const mca_kin_t kin[],
                     const mca_self_pairs_t *self, const mca_body_cache_t *cache, mca_self_nearest_t *out);

/**
 * Fill the fixed bodies' rows of a QP whose layout keeps them (p->body_pairs rows per link from
 * si->body_off[a]: mca_scheme_assemble with collision rows, or mca_scheme_near_rows; call after it, with the
 * QP's box final, since only witness pairs whose row can bind inside it are listed). Rows are written at the
 * QP's full width (after mca_scheme_add_timescale their extra columns are 0). Rows that cannot bind, or that
 * are parallel to one kept before (1e-3) stay inactive (beta = big). Adds to si->active_rows, lowers
 * si->brake. dec NULL or dec[a] <= 0: no stop bound for arm a (the paper's scheme). self: each arm's self
 * pairs (NULL: none), in the same lists and slots. cache as for mca_body_nearest (NULL: none; the same rows).
 * @param[out] lists  lists[a][l]: the witness pairs of each link (rows in this order), may be NULL
 * @retval MCA_OK (also with no bodies or body_pairs 0: nothing done), MCA_EINVAL
 */
int mca_body_rows(mca_qp_t *qp, mca_scheme_info_t *si, int n_arms, const mca_chain_t *const chain[],
                  const mca_kin_t kin[], const mca_fixed_body_t *bodies, int n_bodies,
                  const mca_self_pairs_t *self, const mca_scheme_params_t *p, const double *dec,
                  const mca_body_cache_t *cache, mca_body_witness_t lists[][MCA_MAX_LINKS][MCA_BODY_PAIRS]);

#ifdef __cplusplus
}
#endif
#endif
