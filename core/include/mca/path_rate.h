/* SPDX-License-Identifier: MIT */
/** @file mca/path_rate.h
 * mca-ts: the path rate from which an arm can still stop on its path (sigma's own stoppability bound).
 *
 * The collision rows' stop argument (docs/scheme.md section 10) assumes that an arm brakes by scaling its
 * whole joint velocity down (keeping its direction). An arm that keeps its tool tip on a curved path cannot:
 * with qdot = sigma q_s (q_s = dq/dtau along the path), slowing down on the path needs
 *     qddot = sigma_dot q_s + sigma^2 q_ss     (q_ss = d^2 q / dtau^2: the path's curvature and J's change),
 * and the second term grows with sigma^2. With a share theta of each joint's deceleration limit kept for it,
 *     sigma^2 |q_ss,j| <= theta dec          for every joint j,
 * the rest slows the path down at a = (1 - theta) min_j dec / |q_s,j| (path time per second squared), so the
 * arm stops on its path within sigma / a, at most T_a / (1 - theta) with T_a the keep-direction stop time.
 * The limit is carried backwards along the path (sigma(tau)^2 <= sigma(tau')^2 + 2 a (tau' - tau)) so that
 * every later limit can be met by slowing at a: the classic maximum-velocity curve of time-optimal path
 * parameterisation, on the arm's configurations predicted alone along its path (mca_coord_predict).
 *
 * Calling context: mca_path_rate_plan() at start-up; mca_path_rate_at() on the 1 kHz tick (bounded, no
 * allocation).
 */
#ifndef MCA_PATH_RATE_H
#define MCA_PATH_RATE_H

#include "mca/coord.h"

#ifdef __cplusplus
extern "C" {
#endif

/** Share of the deceleration limit kept for the path's curvature (theta above). */
#define MCA_PATH_RATE_CURVE_SHARE 0.5

typedef struct mca_path_rate {
    int n;                            /**< cells (0: no limit: not a path-first circle or waypoint path) */
    double h;                         /**< path time per cell [s] */
    float sigma[MCA_COORD_MAX_CELLS]; /**< the limit at path time k h, capped at sigma_cap */
    float decel[MCA_COORD_MAX_CELLS]; /**< the path-rate deceleration left beside the curvature [1/s^2] */
    double least;                     /**< the smallest limit along the path */
} mca_path_rate_t;

/**
 * The limit along @p arm's path (anchored), from its configurations predicted alone; dec: the arm's joint
 * deceleration limit [rad/s^2], sigma_cap: the largest path rate (mca-ts's sigma_max). q_work: scratch of
 * MCA_COORD_MAX_CELLS configurations. Paths that are not path-first circles or waypoints get n = 0.
 * @retval MCA_OK, MCA_EINVAL
 */
int mca_path_rate_plan(const mca_coord_arm_t *arm, double dec, double sigma_cap, double q_work[][MCA_MAX_DOF],
                       mca_path_rate_t *out);

/** The limit at path time tau (linear between cells; +INFINITY without a limit). Real-time safe. */
double mca_path_rate_at(const mca_path_rate_t *r, double tau);

/** The path-rate deceleration the arm has at path time tau beside the curvature [1/s^2] (the cell's;
 * +INFINITY without a limit). Real-time safe. */
double mca_path_rate_decel(const mca_path_rate_t *r, double tau);

#ifdef __cplusplus
}
#endif
#endif
