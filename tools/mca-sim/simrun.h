/* SPDX-License-Identifier: MIT */
/** @file simrun.h
 * Run one scenario in virtual time through mcad's own pipeline: a cell around the scenario (every arm on
 * the in-process sim backend), opened and stepped by the daemon's virtual-time driver (mca/daemon_drive.h:
 * no thread, no DDS, mca_drive_step per tick), so the tick, the fault latching and the braking
 * (mca_controller_brake) are the daemon's. --euler makes the sim arms ideal (q += qdot dt). Used by mca-sim
 * and by tests/scheme. Not real-time code (it writes CSV/JSON).
 */
#ifndef MCA_SIMRUN_H
#define MCA_SIMRUN_H

#include <stddef.h>
#include <stdint.h>

#include "mca/controller.h"
#include "mca/dds_bridge.h" /* MCA_DDS_PAIR_KINDS, mca_dds_pair_kind_name */
#include "mca/qp_dump.h"
#include "mca/scenario.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct mca_simrun_opts {
    mca_scheme_kind_t scheme;
    int form;             /**< -1: the scenario's; else mca_collision_form_t */
    int use_backend;      /**< 1: sim backend (default), 0: Euler integration q += qdot dt */
    const char *csv_path; /**< per-tick CSV, NULL: none */
    const char *dump_dir; /**< QP dumps (mca_qp_dump_json), NULL: none */
    int dump_every;    /**< dump every Nth tick (default 1; and every max(1, N/5)th tick with binding rows) */
    int dump_max;      /**< most dumps per run (0: no limit) */
    double w_tube;     /**< > 0: mca-ts's quadratic slack weight with a tube */
    double w_path;     /**< > 0: mca-ts's exact slack weight (mca_timescale_params_t.w_path) */
    int no_coordinate; /**< 1: mca-ts without the start-up plan of who passes first (mca/coord.h) */
    int no_body_rows;  /**< 1: the fixed bodies measured only, no rows and no fault (the run without them) */
    int no_self_rows;  /**< 1: the self pairs measured only, no rows and no fault (the run without them) */
    int dump_capped;   /**< 1: also the picked ticks whose PDNN ended unconverged, as NAME.json.capped (their
                            phi is the solver's last iterate, not an answer: for a look at the QP itself) */
    double duration;   /**< <= 0: the scenario's */
    double settle;     /**< seconds to run on after the arms stopped following a fault */
    int pdnn_max_steps; /**< > 0: override */
    int pdnn_budget_us; /**< >= 0: the step budget of this time budget (mca_pdnn_budget_steps; 0: none); < 0:
                             the cell's, half the period (mcad's default rt.pdnn_budget_us) */
    double v_normal;    /**< > 0: override the scenario's */
    double v_floor;     /**< >= 0: override the scenario's (< 0: keep) */
    int dist_lsdm;      /**< 1: the paper's LSDM for the distances instead of the closed form */
    double overtime;    /**< mca-ts: run on after the duration until the path clocks end, this long at most
                             (< 0: the duration again) */
    double stop_at;     /**< >= 0: stop request at this task time, as SIGTERM to mcad (< 0: none) */
    double fault_at;    /**< >= 0: inject fault_kind at this task time (< 0: none) */
    int fault_kind;     /**< mca_ctrl_fault_t to inject (mca_simrun_fault_from_name) */
    double dec_limit;   /**< > 0: every joint's dec_limit [rad/s^2], the daemon's braking and the sim arm's
                             (0: the cell default, 10) */
} mca_simrun_opts_t;

typedef struct mca_simrun_result {
    char scheme[8];
    int ticks;
    double min_distance, min_distance_t;
    int arm_ticks_below;    /**< ticks (running and braking) with two arms below d1 */
    double max_err;         /**< max |r_d - r| over arms and ticks before any fault [m] */
    double max_err_free;    /**< same, over ticks where no collision row binds */
    double max_err_nobrake; /**< same, over ticks with S(d) = 1 (no link inside d2) */
    int fault;              /**< first fault (mca_ctrl_fault_t) */
    char fault_text[256];
    double fault_t, fault_distance;
    int stopped; /**< 1: all joints at rest after the fault */
    double stop_t;
    double min_distance_after_fault;
    int n_samples;
    double sample_t[16], sample_d[16];
    int pdnn_steps_max;
    double pdnn_steps_mean;
    double pdnn_residual_max;
    double eq_residual_max;
    int binding_ticks; /**< ticks with at least one binding collision row */
    int pdnn_capped;   /**< ticks where the PDNN hit its step cap but stayed below fault_residual */
    int budget_steps;  /**< the step budget applied (0: none) */
    int budget_hits_steps, budget_hits_time;       /**< running ticks out of budget (info.pdnn_budget_hit) */
    int64_t compute_p50, compute_p99, compute_max; /**< info.compute_ns (CLOCK_MONOTONIC, wall) */
    int64_t cpu_p50, cpu_p99, cpu_max;             /**< thread CPU time of the tick call (no preemption) */
    int dumped, dumped_binding;
    int dump_skipped_capped; /**< ticks --dump-every picked but not dumped: PDNN at its cap (not converged) */
    int completed; /**< 1: every arm's path clock reached its path's end (no fault) and every exact waypoint
                        was met */
    double path_error_max; /**< the tool tips' largest distance to their paths' curves while running [m] */
    double path_error_brake_max; /**< the same while braking after a stop or a fault (path-first circle and
                                      waypoint arms; the stop keeps the rows, not the path) [m] */
    double path_error_p99;  /**< its 99th percentile over the running ticks (each tick: the arms' largest) */
    int exact_points;       /**< exact waypoints reached (met or missed) */
    int exact_missed;       /**< of those, missed (farther than exact_tolerance while on the point) */
    double exact_error_max; /**< the largest distance to an exact point while on it [m] */
    int pdnn_steps_p50, pdnn_steps_p999; /**< PDNN steps per running tick */
    /* every solve, running and braking: steps and the polish's exact solves per tick */
    int solves; /**< ticks that solved a QP */
    int solve_steps_p50, solve_steps_p999, solve_steps_max;
    int exact_p50, exact_p999, exact_max;
    int solves_unconverged; /**< of them, ended without meeting the tolerance */
    /* where the run ended (an unfinished task named with its pair and positions) */
    int end_pair[4];                /**< the closest pair: arm, link, arm, link */
    double end_distance;            /**< its distance [m] */
    double end_ee[MCA_MAX_ARMS][3]; /**< the tool tips */
    double end_tau[MCA_MAX_ARMS];   /**< the path clocks [s] */
    int end_done[MCA_MAX_ARMS];     /**< 1: the arm's clock had reached its path's end */
    int coord_pairs;                /**< pairs of arms ordered by the start-up plan (mca/coord.h) */
    int coord_unplanned; /**< pairs on fixed paths for which no schedule exists (the predicted arms meet) */
    double path_time_lost_s;   /**< task time at completion (or at the end) minus the paths' nominal end */
    int deadlocks;             /**< mca-ts deadlocks detected */
    double max_slack;          /**< mca-ts: largest tracking slack [m/s] */
    int stop_requested;        /**< 1: --stop-at fired */
    double brake_t;            /**< task time braking began (stop or fault; -1: none) */
    double stop_duration_s;    /**< from brake_t until every simulated joint is at rest (-1: not at rest) */
    int brake_fallback_ticks;  /**< braking ticks with the keep-direction fallback */
    int brake_forced_ticks;    /**< of those, past the stop's deadline */
    double max_dv_over_dt_dec; /**< braking: largest per-tick |commanded velocity change| / (dec dt) */
    int daemon_state;          /**< mca_daemon_state_t at the end */
    /* fixed bodies, every tick (running and braking): the arm-body pair of least margin d - clearance */
    int n_bodies;
    double body_min_margin;   /**< [m] (+INF: no bodies); below 0 a link was inside a body's clearance */
    double body_min_distance; /**< that pair's surface distance [m] */
    double body_min_t;        /**< task time [s] */
    int body_min_arm, body_min_link, body_min_body, body_min_kind;
    int body_ticks_below; /**< ticks with the margin below 0 */
    /* self pairs, every tick: the pair of least distance */
    int has_self;
    double self_min_distance; /**< [m] (+INF: no self pairs) */
    double self_min_t;        /**< task time [s] */
    int self_min_arm, self_min_link, self_min_other;
    int self_ticks_below; /**< ticks with it below d1 */
    /* the simulated streamed sphere (scenario simulated_sphere), every tick (running and braking); the arm
     * pairs' and the fixed bodies' figures above leave it out */
    int has_sphere;
    int sphere_sent, sphere_lost; /**< samples delivered to the daemon, samples lost */
    double track_min_margin;      /**< least d - S_p of any arm's link against the track as the controller
                                       holds it (position, grown radius, clearance S_p) [m] (+INF: none) */
    double track_min_t;           /**< its task time [s] */
    int track_min_arm;
    double track_sp_max;      /**< the largest S_p the track had [m] */
    int track_ticks_rest;     /**< (arm, tick) pairs below S_p with that arm at rest on the tick and the one
                                   before (every joint |qdot| <= MCA_SIMRUN_REST): the sphere walked into it */
    int track_ticks_moving;   /**< (arm, tick) pairs below S_p with that arm moving */
    int track_ticks_braking;  /**< of those, while the daemon brakes (a stop or a fault: the arm stopping) */
    double sphere_true_min_d; /**< least surface distance of any link to the true sphere (where it is, not
                                   where the controller last heard of it) [m] */
    /* every kind of pair and each fixed body over the run, as mcad's summary counts them (mca_daemon_summary)
     */
    double kind_min[MCA_DDS_PAIR_KINDS], kind_min_t[MCA_DDS_PAIR_KINDS]; /**< [m] (+INF: none), [s] */
    int n_fixed_bodies;
    double fixed_min[MCA_MAX_BODIES], fixed_min_t[MCA_MAX_BODIES]; /**< [m] (+INF: none), [s] */
    int fixed_min_link[MCA_MAX_BODIES][2];                         /**< arm, link (-1: every link allowed) */
} mca_simrun_result_t;

/** An arm is at rest when every joint's velocity is at most this [rad/s] (the sim arm's true velocity). */
#define MCA_SIMRUN_REST 1e-6

void mca_simrun_default_opts(mca_simrun_opts_t *o);

/** Run. @retval MCA_OK (the run happened; faults are in the result), or an error (err says why). */
int mca_simrun(const mca_scenario_t *scn, const mca_simrun_opts_t *o, mca_simrun_result_t *r, char *err,
               size_t errlen);

/** Controller fault code from its name (mca_ctrl_fault_name, "pdnn-not-converged"), -1 if unknown. */
int mca_simrun_fault_from_name(const char *name);

#ifdef __cplusplus
}
#endif
#endif
