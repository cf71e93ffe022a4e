/* SPDX-License-Identifier: MIT */
/** @file mca/scheme.h
 * QP assembly of the MCA scheme (paper (19)-(28)) for N arms:
 *
 *   phi = [qdot_0; qdot_1; ...]                   (arm a's joints at offset var_off[a])
 *   G phi = alpha:   rows 3a..3a+2 = J_a qdot_a = rdot_d + K (r_d - r)         (22)/(26)
 *   lb <= phi <= ub: eta-/eta+ of (19)-(20)                                     (24)/(27)
 *   U phi <= beta:   per arm a, per link l of a, a FIXED block of rows (3 rows componentwise, 1 row
 *                    normal form) for the critical point P on link l against the closest link of any
 *                    other arm (E on that link).                                (10)-(14)/(28)
 * Inactive rows (link farther than d2, or a link with no critical point) keep their place with
 * beta = +big and U = 0, so the layout never changes between ticks and the PDNN warm start stays valid.
 *
 * Collision forms (see docs/scheme.md for the reading of the paper's (12)):
 *  - componentwise (paper (10)-(12)): rows r_PE <> J_P (r_PE = E - P, <> = row-wise scaling),
 *    beta_i = S(d) max{c_i, v_floor * |r_PE,i|} where c_i = (r_PE <> J_P qdot)_i captured when the
 *    link entered the band (d fell below d2) and frozen while it stays inside;
 *  - normal: one row n^T J_P qdot <= S(d) v_normal with n = (E - P) / |E - P| (approach speed of P
 *    towards E; each arm limits its own approach, as the paper's block-diagonal U).
 * Real-time safe: no allocation, no I/O.
 */
#ifndef MCA_SCHEME_H
#define MCA_SCHEME_H

#include "mca/chain.h"
#include "mca/qp.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum mca_collision_form {
    MCA_FORM_COMPONENTWISE = 0, /**< paper (10)-(12): three rows per critical point */
    MCA_FORM_NORMAL = 1,        /**< one row per critical point along P -> E */
} mca_collision_form_t;

typedef struct mca_scheme_params {
    int collision; /**< 1: collision rows (MCA), 0: none (MVN (25)-(27)) */
    mca_collision_form_t form;
    double d1, d2;    /**< safety thresholds [m], 0 <= d1 < d2 */
    double K;         /**< position feedback gain [1/s] */
    double epsilon;   /**< joint-limit gain of (19) [1/s] */
    double v_normal;  /**< normal form: approach speed allowed at d >= d2 [m/s] */
    double v_floor;   /**< componentwise: least allowed approach speed per axis [m/s] */
    double big;       /**< bound of an inactive row (the PDNN's varpi or less) */
    double d1_margin; /**< mca-ts rows (mca_scheme_near_rows) brake towards d1 + d1_margin, at most halfway to
                         d2 [m]; the distance fault stays at d1 (0 here; the controller sets it for mca-ts) */
    int body_pairs;   /**< rows per link kept for the fixed bodies after each arm's own rows (mca_body_rows,
                           mca/bodyrows.h): MCA_BODY_PAIRS with bodies, 0 without (the layout of before) */
} mca_scheme_params_t;

/** Critical point of one link against the closest link of the other arms. */
typedef struct mca_link_critical {
    int valid; /**< 0: no other arm (row inactive) */
    int other_arm;
    int other_link;
    double d;    /**< surface distance [m] */
    double p[3]; /**< on this link's axis */
    double e[3]; /**< on the other link's axis */
} mca_link_critical_t;

/** Memory between ticks (componentwise capture). Zero it with mca_scheme_state_reset(). */
typedef struct mca_scheme_state {
    int in_band[MCA_MAX_ARMS][MCA_MAX_LINKS];
    double captured[MCA_MAX_ARMS][MCA_MAX_LINKS][3];
} mca_scheme_state_t;

/** What one assembly found. */
typedef struct mca_scheme_info {
    int active_rows; /**< collision rows with a finite bound */
    double brake;    /**< smallest S(d) over the links with a critical point (1 when none) */
    int var_off[MCA_MAX_ARMS];
    int row_off[MCA_MAX_ARMS];  /**< first inequality row of each arm */
    int rows_per_link;          /**< 3 componentwise, 1 normal, 0 MVN */
    int body_off[MCA_MAX_ARMS]; /**< first fixed-body row of each arm: p->body_pairs rows per link follow its
                                     own rows (mca_scheme_assemble with collision rows, mca_scheme_near_rows)
                                 */
} mca_scheme_info_t;

/** Defaults: collision on, normal form, d1 0.05, d2 0.12, K 20, epsilon 5, v_normal 0.5, v_floor 0,
 *  big 1e6. */
void mca_scheme_default_params(mca_scheme_params_t *p);

/** Smooth brake (13): 1 for d >= d2, sin^2(pi/2 (d - d1)/(d2 - d1)) between, 0 for d <= d1. */
double mca_brake_s(double d, double d1, double d2);

/** Diamond product (10): rows[i][j] = r[i] * J[i][j] for the first dof columns (others zeroed). */
void mca_diamond_rows(const double r[3], const double J[3][MCA_MAX_DOF], int dof,
                      double rows[3][MCA_MAX_DOF]);

/**
 * Joint bounds (19)-(20): lb = max{eps (q- - q), -qdot_max}, ub = min{eps (q+ - q), qdot_max};
 * continuous joints get the velocity limits only.
 * @retval MCA_OK
 * @retval MCA_EINFEASIBLE a joint is so far beyond a limit that lb > ub (lb, ub still written)
 * @retval MCA_EINVAL NULL or non-finite q
 */
int mca_joint_bounds(const mca_chain_t *chain, const double *q, double epsilon, double *lb, double *ub);

/** Reset the between-tick memory (task start, fault clear). */
void mca_scheme_state_reset(mca_scheme_state_t *st);

/** Rows per link for these parameters (0, 1 or 3). */
int mca_scheme_rows_per_link(const mca_scheme_params_t *p);

/**
 * Assemble the QP (25)-(28) for n_arms arms (real-time safe).
 * @param p       parameters
 * @param n_arms  1..MCA_MAX_ARMS
 * @param chain   chain of each arm
 * @param kin     kinematic state of each arm (mca_fk at q)
 * @param q       joint positions of each arm
 * @param r_d     desired end-effector position of each arm
 * @param rdot_d  desired end-effector velocity of each arm
 * @param crit    critical point of each link of each arm ([a][l], l < dof_a + 1)
 * @param phi_prev previous tick's phi (for the componentwise capture; NULL = zero)
 * @param st      between-tick memory (updated)
 * @param[out] qp    the QP (reset and filled)
 * @param[out] info  layout and brake summary (may be NULL)
 * @retval MCA_OK, MCA_EINVAL (NULL/sizes), MCA_ERANGE (QP above the maximums),
 *         MCA_EINFEASIBLE (joint bounds contradict)
 */
int mca_scheme_assemble(const mca_scheme_params_t *p, int n_arms, const mca_chain_t *const chain[],
                        const mca_kin_t kin[], const double *const q[], const double r_d[][3],
                        const double rdot_d[][3], const mca_link_critical_t crit[][MCA_MAX_LINKS],
                        const double *phi_prev, mca_scheme_state_t *st, mca_qp_t *qp,
                        mca_scheme_info_t *info);

/**
 * The collision rows of mca-ts (normal form; on a QP assembled without collision rows; real-time safe).
 * Per arm a, per link l, one row per near pair near[a][l][k] (valid ones first: the first invalid entry
 * ends the link's list): the link's MCA_NEAR_PAIRS nearest witness pairs
 * against the other arms' links (each link pair's closest points and the closest points of its four segment
 * ends, so that a pair approaching while it is not the closest one is bounded too; see the controller):
 *   n^T J_P qdot_a <= min{ 2 w_a S(d) v_normal (d < d2 only), w_a (d - d1) / T_a },
 *   w_a = priority_a / (priority_a + priority_b),  T_a = max_j qdot_max,j / dec_a,
 * (d1 here is d1 + d1_margin) so the pair's approach speeds sum to at most what both arms can brake away
 * within half the gap, and braking alone keeps each arm inside its row (docs/scheme.md, "Stoppability"). dec
 * NULL or dec[a] <= 0: no stop bound for arm a; priority NULL: equal shares. Rows without a pair, or
 * repeating a pair of the previous link (a shared joint), get beta = big, and their U row is left as it was
 * (an inactive row is never read: mca_scheme_prune_rows and mca_scheme_compact_rows skip it; compact before
 * the PDNN). Columns added later (mca_scheme_add_timescale) are not zero in the rows: add them first. Sets
 * qp->n_ineq and si's row layout, active_rows and brake.
 * @retval MCA_OK, MCA_EINVAL, MCA_ERANGE (rows above the maximum)
 */
int mca_scheme_near_rows(mca_qp_t *qp, mca_scheme_info_t *si, int n_arms, const mca_chain_t *const chain[],
                         const mca_kin_t kin[],
                         const mca_link_critical_t near[][MCA_MAX_LINKS][MCA_NEAR_PAIRS],
                         const mca_scheme_params_t *p, const double *dec, const double *priority);

/** d1' = d1 + d1_margin, at most halfway to d2: the distance the mca-ts and braking rows aim to keep. */
double mca_scheme_rows_d1(const mca_scheme_params_t *p);

/** T_a of the stop bound: the longest stop of an arm from its fastest joint speed, max_j qdot_max,j / dec
 *  (0 when dec <= 0: no stop bound). */
double mca_scheme_stop_time(const mca_chain_t *chain, double dec);

/**
 * The bound on a witness pair's approach speed that mca_scheme_near_rows gives its row at distance d,
 * before the priority share: S(d) v_normal inside d2 (S from d1 + margin), and with a stop time t_stop > 0
 * at most (d - d1 - margin) / (2 t_stop). p->big when neither applies (an inactive row). Non-decreasing in d.
 */
double mca_scheme_row_bound(const mca_scheme_params_t *p, double d, double t_stop);

/** The priority share of arm a's row against arm b (2 w_a; 1 with priority NULL). */
double mca_scheme_row_share(const double *priority, int a, int b);

/**
 * Drop the inequality rows that no point of the box lb <= phi <= ub can bring to their bound (the largest
 * U_i phi over the box is below beta_i): redundant rows, so the QP's answer is the same, and the PDNN
 * iterates fewer rows. mca-ts's box is the acceleration box (last command +- dec_limit dt), so most
 * witness-pair rows are dropped here while their pairs are not closing in. A dropped row becomes inactive
 * (zero, beta = big) and leaves si->active_rows. RT safe.
 * @return the number of rows dropped
 */
int mca_scheme_prune_rows(mca_qp_t *qp, double big, mca_scheme_info_t *si);

/**
 * Move the active inequality rows (beta < big) to the front, in order, and drop the rest: n_ineq becomes
 * their count, src[i] the row that row i was, and si->row_off each arm's first row in the new order (arm
 * a's rows stay [row_off[a], row_off[a + 1]), the last arm's up to n_ineq). The QP is the same; the PDNN
 * then never sees the many inactive witness-pair rows (mca_pdnn_remap_ineq keeps its warm start). RT safe.
 * @return the new n_ineq
 */
int mca_scheme_compact_rows(mca_qp_t *qp, double big, mca_scheme_info_t *si, int *src);

/** How an arm's tracking slack is charged (mca_scheme_add_timescale). */
typedef enum mca_tracking_mode {
    MCA_TRACK_ELASTIC = 0,    /**< L2 slack (w_slack), no tube: a path without a tolerance key */
    MCA_TRACK_PATH_FIRST = 1, /**< exact L1 (w_path) plus L2, inside the tube: the path before its timing */
    MCA_TRACK_TUBE = 2,       /**< L2 inside the tube: a blocked arm may give way within its tolerance */
} mca_tracking_mode_t;

/** Path-time scaling weights (see mca_scheme_add_timescale). */
typedef struct mca_timescale_weights {
    double w_sigma; /**< weight of (sigma - sigma_target)^2 */
    double w_slack; /**< quadratic weight of |e|^2 (keeps the slack's columns well scaled) */
    double w_path;  /**< exact weight of |e|_1: no slack while slowing down costs less (docs/scheme.md) */
    double w_tube;  /**< quadratic weight of |e|^2 for a path with a tube (in place of w_slack) */
} mca_timescale_weights_t;

/**
 * Append the mca-ts variables of every arm (real-time safe): after the joint velocities, per arm a
 * u_a = m (sigma_a - target_a), m = sqrt(w_sigma), then the tracking slack e_a = p_a - n_a (p, n >= 0) as
 * y_p = s p + k and y_n = s n + k, s = sqrt(w_tube), k = w_path / s (3 values each), so that the PDNN's
 * identity Hessian is the objective
 *     1/2 |qdot|^2 + w_sigma / 2 (sigma - target)^2 + w_tube / 2 |e|^2 + w_path |e|_1   (+ a constant).
 * The L1 term is an exact penalty: the slack stays 0 whenever the same QP with e = 0 has an answer whose
 * tracking multipliers are below w_path (docs/scheme.md, "The path first"). Tracking row (26) becomes
 * J_a qdot_a - sigma_a rdot_a - e_a = K (r_a - f(q_a)):
 *   J_a qdot_a - rdot_a / m u_a - (y_p - y_n) / s = target_a rdot_a + K (r_a - f(q_a)).
 * sigma_a is bounded to [sigma_lo[a], sigma_hi[a]], the slack to [slack_lo[a], slack_hi[a]] per component
 * (slack_lo <= 0 <= slack_hi, +-INFINITY allowed: the path tube, mca_scheme_tube_bounds).
 * mode[a] (mca_tracking_mode_t): MCA_TRACK_PATH_FIRST as above; MCA_TRACK_TUBE the same without the L1
 * term (k = 0); MCA_TRACK_ELASTIC an L2 slack alone as before the tube (s = sqrt(w_slack), y_p the whole
 * slack, y_n fixed at 0 and out of every row; its slack bounds must be infinite): a path without a tolerance
 * key.
 * @param rdot_d  path velocity of each arm at its path clock (d r / d tau)
 * @param[out] ts_off       first added variable of each arm
 * @param[out] sigma_scale  m of each arm (sigma = target + u / m)
 * @retval MCA_OK, MCA_ERANGE (too many variables), MCA_EINVAL (NULL, weights, a slack bound of the wrong
 * sign)
 */
int mca_scheme_add_timescale(mca_qp_t *qp, int n_arms, const double rdot_d[][3], const double *target,
                             const double *sigma_lo, const double *sigma_hi, const double slack_lo[][3],
                             const double slack_hi[][3], const mca_timescale_weights_t *w, const int *mode,
                             int ts_off[], double sigma_scale[]);

/** The tracking slack e_i (i < 3) of the arm whose mca-ts variables start at phi[ts_off] (its mode). */
double mca_scheme_ts_slack(const double *phi, int ts_off, int i, const mca_timescale_weights_t *w, int mode);

/** The tube's least half width per axis [m]: a tolerance of 0 means within this (standing still is then
 * inside the tube, not on three of its edges at once). */
#define MCA_TUBE_FLOOR 1e-6

/**
 * The path tube as bounds on the slack (real-time safe). With err = r(tau) - f(q), the error after one tick
 * of dt is err + dt (sigma rdot - J qdot) = (1 - K dt) err - dt e to first order; each component is kept
 * within R_i = max(radius / sqrt(3), |err_i|, MCA_TUBE_FLOOR) (so |err| <= radius, or no growth where it is
 * already outside):
 *   slack_lo_i = ((1 - K dt) err_i - R_i) / dt <= 0 <= slack_hi_i = ((1 - K dt) err_i + R_i) / dt.
 * At rest (qdot = 0, sigma = 0, e = -K err) the error stays err: a point of the tube, always.
 * radius = INFINITY: no tube (bounds +-INFINITY).
 */
void mca_scheme_tube_bounds(const double err[3], double radius, double K, double dt, double lo[3],
                            double hi[3]);

#ifdef __cplusplus
}
#endif
#endif
