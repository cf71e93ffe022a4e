/* SPDX-License-Identifier: MIT */
/* The controller's state (struct mca_controller, opaque outside mca_core: mca/controller.h declares it and
 * states its size, MCA_CONTROLLER_SIZE_MAX, checked in controller.c). Every room of the controller
 * (controller*.c) reads and writes it; nothing outside core includes this header but core's own white-box
 * tests and the tick's stage profiler (bench/scaling/bench_tick.c).
 *
 * Calling context: none of its own (a struct). The caller provides its storage at start-up
 * (mca_controller_create); the tick, observe, brake and the setters then write it on the one thread that
 * ticks the controller. */
#ifndef MCA_CONTROLLER__STATE_H
#define MCA_CONTROLLER__STATE_H

#include <stdint.h>

#include "mca/controller.h"

struct mca_controller {
    mca_controller_config_t cfg;
    int started; /**< paths anchored */
    double t_start;
    int fault;
    mca_ctrl_fault_why_t fault_why;
    mca_kin_t kin[MCA_MAX_ARMS];
    mca_arm_distances_t dist[MCA_MAX_ARMS][MCA_MAX_ARMS]; /**< [a][b], a < b */
    mca_link_critical_t crit[MCA_MAX_ARMS][MCA_MAX_LINKS];
    mca_link_critical_t near[MCA_MAX_ARMS][MCA_MAX_LINKS]
                            [MCA_NEAR_PAIRS]; /**< nearest links (mca-ts, braking) */
    mca_body_witness_t body_near[MCA_MAX_ARMS][MCA_MAX_LINKS][MCA_BODY_PAIRS]; /**< fixed bodies' rows */
    mca_body_cache_t body_cache; /**< bounds that skip far body and self pairs (this tick's poses) */
    double body_margin_prev;     /**< last tick's least body margin (the prediction of the distance fault) */
    double self_distance_prev;   /**< last tick's least self distance (the same prediction) */
    mca_scheme_state_t sstate;
    mca_qp_t qp;
    mca_pdnn_t pdnn;
    double phi[MCA_QP_MAX_VARS];
    double phi_prev[MCA_QP_MAX_VARS];
    double min_distance_prev;
    int has_prev;
    uint64_t ticks;
    /* mca-ts */
    double tau[MCA_MAX_ARMS];   /**< path clocks */
    double sigma[MCA_MAX_ARMS]; /**< last path rates */
    double path_end[MCA_MAX_ARMS];
    double t_prev;     /**< last tick's t (tau advances by sigma (t - t_prev)) */
    double stall_time; /**< how long every unfinished arm's sigma has been below deadlock_sigma */
    int deadlock, deadlock_arm, deadlocks;
    int exact_next[MCA_MAX_ARMS];             /**< the next exact waypoint to check (path point index) */
    int track_mode[MCA_MAX_ARMS];             /**< mca_tracking_mode_t of each arm in the last QP */
    double keep_q[MCA_MAX_ARMS][MCA_MAX_DOF]; /**< path with a tube: one keep-direction braking step */
    double keep_sigma[MCA_MAX_ARMS];          /**< and the path rate that fits it */
    int giving_way[MCA_MAX_ARMS];   /**< path first: 1 while the arm may slide within its tube (held too long)
                                     */
    double held_time[MCA_MAX_ARMS]; /**< how long its path rate has been held below deadlock_sigma [s] */
    int at_tube_edge[MCA_MAX_ARMS]; /**< this tick's error reached its tube's edge (giving way ends) */
    double rate_avg[MCA_MAX_ARMS]; /**< path rate averaged over MCA_TS_RATE_AVG_S: held and deadlock see it */
    int exact_bad[MCA_MAX_ARMS];   /**< 1: the point being checked was missed */
    int exact_met, exact_missed;
    double exact_error_max;
    double deadlock_until;              /**< back-off ends at this task time */
    double wait_tau[MCA_MAX_ARMS];      /**< WAIT: the others' clocks when it began */
    int back_offs;                      /**< back-offs of deadlock_arm since the deadlock began */
    double ts_scale[MCA_MAX_ARMS];      /**< u = ts_scale (sigma - target) in the last QP */
    double v_meas[MCA_QP_MAX_VARS];     /**< measured joint velocities for the next tick (phi layout) */
    double box_center[MCA_QP_MAX_VARS]; /**< the joint velocities the acceleration box was centred on */
    int has_v_meas;
    /* braking QP (kept apart from the tick's so a fault does not disturb the last tick's dump) */
    mca_qp_t brake_qp;
    mca_pdnn_t brake_pdnn;
    /* mca-ts and braking: the compacted rows' slots in the full row layout (warm starts follow them) */
    int row_key[MCA_QP_MAX_INEQ], n_row_key;
    int brake_row_key[MCA_QP_MAX_INEQ], n_brake_row_key;
    /* mca-ts: who passes first where fixed paths meet (mca_controller_plan; empty without a plan) */
    mca_coord_t coord;
    /* mca-ts: each path-first arm's path-rate limit, sigma's own stop bound (mca_controller_plan; n = 0:
     * none) */
    mca_path_rate_t rate[MCA_MAX_ARMS];
    /* streamed bodies: cfg.body[n_fixed ..] are the tracks of the last mca_controller_set_tracks */
    int n_fixed; /**< the cell's fixed bodies */
    /* the last distances' pairs of every kind (mca_controller_pair_nearest): each body's closest link and
     * each arm's least self pair; the report's least-margin body pair and least self pair are the least of
     * these */
    mca_pair_nearest_t near_kinds;
    double track_arm_speed, track_stop_time;     /**< v_r and T_s of S_p (set at init) */
    mca_ssm_terms_t track_terms[MCA_MAX_TRACKS]; /**< each track's S_p as last set */
};

#endif
