/* SPDX-License-Identifier: MIT */
/** @file mca/coord.h
 * Coordination of fixed paths (mca-ts): who passes first where two arms' paths meet.
 *
 * The reactive rows keep the arms apart, but two arms that keep their tool tips on their paths can only wait
 * for each other: where each waits for the other (both heading into a shared place zone) the rows alone
 * deadlock, and backing off along a path often puts an arm back into the other's way. A plan at start-up
 * resolves that the classic way, on the pair's coordination diagram (O'Donnell and Lozano-Perez 1989):
 *  1. each arm's configurations along its own path, predicted alone (resolved rate, no other arm);
 *  2. the cells (tau_a, tau_b) of path time where the predicted arms come closer than a block distance;
 *  3. the quickest monotone schedule through the free cells from both starts to both ends;
 *  4. from it, per obstacle cell, who passes first: gates on the path clocks. Arm a may enter column x of
 *     its path time only once b's clock has passed every blocked cell of that column that the schedule
 *     passes above (need_b[x]), and the same for b by rows (need_a[y]).
 * With the schedule's diagonal steps kept off blocked corners, the two gates never hold both arms at once
 * (docs/scheme.md, "Coordination"). On the tick the gates are a bound on each arm's path rate, slowing it
 * to a stop before a gated cell. The rows stay the safety: the plan only orders the arms, so a prediction
 * that misses (an arm yielding in its null space) costs time, never distance; a deadlock the plan did not
 * foresee is still resolved by backing off.
 *
 * Calling context: mca_coord_plan() at start-up (it takes a caller's workspace, about 3 MB, and tens of
 * milliseconds to a second); mca_coord_gate() on the 1 kHz tick (bounded, no allocation).
 */
#ifndef MCA_COORD_H
#define MCA_COORD_H

#include "mca/chain.h"
#include "mca/path.h"

#ifdef __cplusplus
extern "C" {
#endif

/** Most cells of path time per arm (the cell grows beyond MCA_COORD_CELL_S for paths longer than this). */
#define MCA_COORD_MAX_CELLS 512
/** Shortest cell of path time [s]. */
#define MCA_COORD_CELL_S 0.1
/** The share of a path's tolerance the plan counts on to separate the arms where no schedule keeps the
 * predicted arms d_floor apart. */
#ifndef MCA_COORD_TUBE_SHARE
#define MCA_COORD_TUBE_SHARE 0.75
#endif
/** Most pairs (MCA_MAX_ARMS choose 2). */
#define MCA_COORD_MAX_PAIRS (MCA_MAX_ARMS * (MCA_MAX_ARMS - 1) / 2)

typedef struct mca_coord_pair {
    int a, b;                          /**< arms: a along the columns, b along the rows */
    int n_a, n_b;                      /**< cells */
    double h_a, h_b;                   /**< path time per cell [s] */
    double d_block;                    /**< the distance the plan kept between the predicted arms [m] */
    int in_tubes;                      /**< 1: only d_block less the tubes' shares (MCA_COORD_TUBE_SHARE) */
    int blocked;                       /**< blocked cells (after dilation) */
    int gates_a, gates_b;              /**< columns of a / rows of b with a gate */
    short need_b[MCA_COORD_MAX_CELLS]; /**< a may enter column x once b's clock is past row need_b[x] */
    short need_a[MCA_COORD_MAX_CELLS]; /**< b may enter row y once a's clock is past column need_a[y] */
} mca_coord_pair_t;

typedef struct mca_coord {
    int n_pairs;
    mca_coord_pair_t pair[MCA_COORD_MAX_PAIRS];
    int unplanned; /**< pairs for which no schedule was found (left to the rows and the back-off) */
} mca_coord_t;

/** Start-up scratch of mca_coord_plan (allocate it once; sizeof is about 3 MB). */
typedef struct mca_coord_work {
    double pts[MCA_MAX_ARMS][MCA_COORD_MAX_CELLS][MCA_MAX_POINTS][3]; /**< predicted link points per cell */
    float dist[MCA_COORD_MAX_CELLS][MCA_COORD_MAX_CELLS];             /**< least distance per cell [m] */
    unsigned char cell[MCA_COORD_MAX_CELLS][MCA_COORD_MAX_CELLS];     /**< blocked bit, predecessor */
    double q[MCA_COORD_MAX_CELLS][MCA_MAX_DOF]; /**< one arm's predicted configurations */
    double tube[2][MCA_COORD_MAX_CELLS];        /**< the pair's tube shares per cell [m] */
} mca_coord_work_t;

/** What mca_coord_plan needs of one arm. */
typedef struct mca_coord_arm {
    const mca_chain_t *chain;
    const mca_path_t *path; /**< anchored; only path-first circle and waypoint paths are coordinated */
    const double *q0;       /**< configuration at the start */
    double K;               /**< position feedback gain of the prediction [1/s] */
} mca_coord_arm_t;

/**
 * The arm's configuration at the start of each cell of path time (k h, k < n), predicted alone: damped
 * resolved rate towards its path (gain K, no other arm, no rows), joint limits clamped. Start-up only.
 * @retval MCA_OK, MCA_EINVAL (NULL, h <= 0, n outside [1, MCA_COORD_MAX_CELLS], a configuration FK refuses)
 */
int mca_coord_predict(const mca_coord_arm_t *arm, double h, int n, double q_out[][MCA_MAX_DOF]);

/**
 * Plan every pair of coordinated arms. d_block: the distance the plan keeps between the predicted arms;
 * where no schedule exists at it, the plan tries halfway to d_floor, then d_floor. Start-up only.
 * @retval MCA_OK (out filled; out->unplanned counts pairs without a schedule), MCA_EINVAL
 */
int mca_coord_plan(const mca_coord_arm_t *arms, int n_arms, double d_block, double d_floor,
                   mca_coord_work_t *work, mca_coord_t *out);

/**
 * The path time arm must stay below, given every arm's path clock (+INFINITY: no gate ahead). Only gates
 * within `ahead` seconds of path time are looked at. Real-time safe.
 */
double mca_coord_gate(const mca_coord_t *c, int arm, const double tau[MCA_MAX_ARMS], double ahead);

#ifdef __cplusplus
}
#endif
#endif
