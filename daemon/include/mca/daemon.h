/* SPDX-License-Identifier: MIT */
/** @file mca/daemon.h
 * The controller daemon's core (used by mcad and its tests): a cell's arms, controller and DDS bridge,
 * the per-tick step and the 1 kHz real-time loop around it.
 *
 * States (their values and names are mca_dds_state_t's, the one numbering the wire carries too):
 *   INIT -> READY (arms answered, DDS up) -> RUNNING (ticking the controller)
 *   RUNNING --(stop request: SIGTERM/SIGINT, stop_after)--> BRAKING --(all commands at 0)--> STOPPED
 *   RUNNING --(fault)--> BRAKING --(all commands at 0)--> FAULT
 * Faults: controller fault (NaN, infeasible/not converged QP, distance below d1, fake attractor),
 * rt.overrun_limit consecutive overruns, no new feedback from an arm for rt.lost_feedback_cycles,
 * an arm reporting FAULT/BRAKING on its own, a bus error burst, implausible feedback from an arm (see
 * mca_feedback_fault_t: checked as it is read, before anything uses it; the sample is dropped, never
 * integrated into a command). BRAKING runs mca_controller_brake each
 * tick (velocities closest to zero inside last command +- dec_limit dt, the joint limits and the collision
 * rows; without a QP answer each arm's whole velocity vector is scaled down, keeping its direction); after
 * 1.5 max_j |v_j|/dec_j + 20 periods from its start only that scale-down is used, so a stop is bounded.
 * Then STOPPED/FAULT command zero velocity with the servo released (the arm's brakes take over). The
 * reason is logged and published.
 *
 * Context: open/close and mca_daemon_start/join are start-up/shut-down; the loop's tick is rt (no
 * allocation, no locks, no blocking I/O; logs via mca/rtlog.h); the request/read-out functions are
 * any thread. A caller that steps the tick itself, in virtual time, uses mca/daemon_drive.h.
 */
#ifndef MCA_DAEMON_H
#define MCA_DAEMON_H

#include <pthread.h>
#include <stdatomic.h>
#include <stdint.h>
#include <stdio.h>

#include "mca/arm.h"
#include "mca/cell.h"
#include "mca/controller.h"
#include "mca/dds_bridge.h" /* mca_dds_state_t: the states' one numbering */
#include "mca/log.h"
#include "mca/ring.h"
#include "mca/rtlog.h"
#include "mca/rtstats.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum mca_daemon_state {
    MCA_DAEMON_INIT = MCA_DDS_STATE_INIT,
    MCA_DAEMON_READY = MCA_DDS_STATE_READY,
    MCA_DAEMON_RUNNING = MCA_DDS_STATE_RUNNING,
    MCA_DAEMON_BRAKING = MCA_DDS_STATE_BRAKING,
    MCA_DAEMON_STOPPED = MCA_DDS_STATE_STOPPED,
    MCA_DAEMON_FAULT = MCA_DDS_STATE_FAULT,
} mca_daemon_state_t;

/** Daemon fault causes (besides the controller's, which are reported as MCA_DAEMON_FAULT_CONTROLLER). */
typedef enum mca_daemon_fault {
    MCA_DAEMON_FAULT_NONE = 0,
    MCA_DAEMON_FAULT_CONTROLLER = 1,    /**< controller tick fault (info.fault says which) */
    MCA_DAEMON_FAULT_OVERRUN = 2,       /**< rt.overrun_limit consecutive overruns */
    MCA_DAEMON_FAULT_LOST_FEEDBACK = 3, /**< no new feedback for rt.lost_feedback_cycles */
    MCA_DAEMON_FAULT_ARM = 4,           /**< an arm reports FAULT or brakes on its own */
    MCA_DAEMON_FAULT_BUS = 5,           /**< bus error on an arm's link */
    MCA_DAEMON_FAULT_FEEDBACK = 6, /**< implausible feedback from an arm (mca_feedback_fault_t says how) */
    MCA_DAEMON_FAULT_STREAM_STALE = 7, /**< task.stream: an arm's target stream silent for brake_after */
    MCA_DAEMON_FAULT_TRACKS_LOST =
        8, /**< streamed_bodies: no message for lost_after ("streamed bodies lost") */
} mca_daemon_fault_t;

/**
 * Plausibility of one feedback sample ("feedback that is not plausible is a fault of that arm,
 * never integrated into a command"). Every sample an arm's read returns (mca_arm_read: MCA_OK/MCA_EFAULT)
 * is checked in this order before the daemon uses any of it; the first failed check names the fault.
 * A failed sample is dropped (positions, velocities, state and frame id stay the last good sample's),
 * the fault MCA_DAEMON_FAULT_FEEDBACK of that arm is latched (while running or braking) and every arm
 * brakes from the last good state. At start-up (the handshake) a failed sample fails the start.
 */
typedef enum mca_feedback_fault {
    MCA_FB_OK = 0,
    MCA_FB_JOINT_COUNT = 1,     /**< fb.n differs from the arm's joint count in the cell */
    MCA_FB_NONFINITE = 2,       /**< a position or velocity is NaN or +-Inf */
    MCA_FB_FRAME_BACKWARDS = 3, /**< fb.frame_id older than the last good sample's (serial arithmetic) */
    MCA_FB_FRAME_AHEAD = 4,     /**< fb.frame_id newer than the newest command sent: answers no command */
    MCA_FB_POSITION = 5,        /**< a position outside the joint's limits by more than the margin */
    MCA_FB_VELOCITY = 6,        /**< a |velocity| above MCA_FB_VELOCITY_FACTOR x the joint's limit */
} mca_feedback_fault_t;

/** Position margin beyond the URDF joint limits [rad] (plus 6 sigma of a sim arm's noise_pos): the
 *  firmware clamps positions at the limits and the controller's bounds keep them inside, so a sample
 *  beyond is a broken encoder, a wrong zero or model, or a corrupt frame (docs/daemon.md). */
#define MCA_FB_POSITION_MARGIN 0.05
/** Velocity factor over the URDF joint velocity limit: commands never exceed the limit, the firmware
 *  saturates them at it; 1.5 leaves room for a real velocity loop's overshoot and noise. */
#define MCA_FB_VELOCITY_FACTOR 1.5

/** "joint-count", "non-finite", "frame-backwards", "frame-ahead", "position-limit", "velocity-limit";
 *  "none" for MCA_FB_OK, "?" otherwise. */
const char *mca_feedback_fault_name(int kind);

const char *mca_daemon_state_name(int state);

/** Options not in the cell file. */
typedef struct mca_daemon_opts {
    int no_dds;           /**< 1: do not publish (overrides the cell) */
    int no_rt;            /**< 1: no SCHED_FIFO, mlockall, dma latency (tests under sanitizers) */
    const char *csv_path; /**< per-tick CSV (written by a non-rt thread), NULL: none */
    /** per-tick recording of what the controller read, bit for bit (mca/tick_rec.h; written by a non-rt
     *  thread; the replay backend plays it into the loop again), NULL: none */
    const char *record_path;
    double stop_after;     /**< > 0: overrides the cell's stop_after [s] */
    uint32_t dds_ab_block; /**< > 0: DDS cost benchmark of the loop (mcad --dds-ab, the bench): publish only
                            *   in every other block of this many ticks and time the whole tick of both kinds
                            *   of block (summary dds_ab_*); a measurement of the real loop, so not part of
                            *   the virtual-time driver (which ignores it) */
    /** Where the daemon's lines go (mca/log.h: it prints nothing itself; mcad writes "<LEVEL>mcad: TEXT" on
     *  stderr), called from the thread of the call that logs (start-up, mca_daemon_service, shut-down);
     *  NULL: the lines are dropped. */
    mca_log_fn log;
    void *log_arg;
    int clear_faults; /**< 1: clear an arm FAULT latched at start-up (logged); 0: refuse to start */
    /** The DDS publisher program (mca-dds-bridge, run as a process of its own). NULL: the one next
     *  to the running executable, else in its prefix's libexec/mca (PREFIX/sbin/mcad ->
     *  PREFIX/libexec/mca, mca/prefix.h), else MCA_LIBEXECDIR's (the configured install's libexec/mca). */
    const char *dds_bridge_exe;
} mca_daemon_opts_t;

/** One CSV row (rt -> writer ring). */
typedef struct mca_daemon_csv_rec {
    double t;
    int state;
    double q[MCA_MAX_ARMS][MCA_MAX_DOF];
    double qdot_cmd[MCA_MAX_ARMS][MCA_MAX_DOF];
    mca_tick_info_t info;
    int64_t cmd_gap_ns; /**< this tick's commands after the last tick's (0 for the first) */
    int64_t wake_ns;    /**< the tick's wake-up, CLOCK_MONOTONIC ns (virtual time: the virtual clock) */
    /* the rest of the feedback the controller read, for the recording (mca/tick_rec.h) */
    double v[MCA_MAX_ARMS][MCA_MAX_DOF]; /**< measured velocities (NaN: none yet) */
    uint32_t fresh;                      /**< bit a: arm a's feedback of this tick was new and taken */
    int32_t arm_state[MCA_MAX_ARMS];     /**< the feedback's mca_arm_state_t */
    uint32_t fault_code[MCA_MAX_ARMS];   /**< the feedback's enum mca_arm_fault */
    int64_t fb_stamp_ns[MCA_MAX_ARMS];   /**< the feedback's receive stamp */
} mca_daemon_csv_rec_t;

#define MCA_DAEMON_CSV_CAPACITY 4096

/** The DDS publisher wakes this long after a publishing tick was due (mca_dds_config_t.wake_offset_ns, from
 *  the snapshot's due_ns): above the tick's usual wake-up jitter plus compute time here (p50 ~15 + 8 us), so
 *  that most pushes find the publisher asleep on the grid (no system call; the loop woke it on 1-4 % of the
 *  publishing ticks in 10-s runs) and the sample leaves soon after the tick. 60, 40, 30 and 20 us, three
 *  interleaved rounds of 10 s (p50 tick -> mca-monitor): 205/91/97, 120/97/77, 62/90/57, 48/57/61 us, the
 *  loop's wakes 12/3/5, 8/12/6, 9/44/9, 22/55/84 per 1001 (docs/bench-runs/2026-12-05-issue13.md). */
#define MCA_DAEMON_DDS_WAKE_OFFSET_NS 30000

/** Controller ticks the loop runs on a scratch copy before its first command (the code runs cold once). */
#define MCA_DAEMON_WARM_TICKS 20

/** A loop stall: more than this many periods between two ticks' commands (logged, counted in the summary). */
#define MCA_DAEMON_STALL_PERIODS 5
/** Loop stalls logged one by one (all are counted). */
#define MCA_DAEMON_STALLS_LOGGED 20

/** Final/online figures. */
typedef struct mca_daemon_summary {
    int state;
    uint64_t ticks, overruns, skipped_periods;
    uint64_t
        pdnn_budget_time; /**< running ticks whose PDNN ran out of its time budget (repaired, no fault) */
    uint64_t pdnn_budget_steps; /**< the same, out of its step budget (below the cap) */
    double pdnn_budget_us;      /**< the time budget applied (0: none, a caller that steps the daemon) */
    int pdnn_step_budget;       /**< the step budget applied (0: none: the cap, mca) */
    int pdnn_max_steps;         /**< the step cap */
    uint64_t stalls;      /**< loop stalls: > MCA_DAEMON_STALL_PERIODS periods between two ticks' commands */
    int64_t stall_max_ns; /**< the longest gap between two ticks' commands of those */
    int64_t jitter_p50_ns, jitter_p99_ns, jitter_p999_ns, jitter_max_ns;
    int64_t compute_p50_ns, compute_p99_ns, compute_max_ns;
    int64_t ctrl_p50_ns, ctrl_p99_ns, ctrl_max_ns; /**< mca_controller_tick alone */
    uint32_t dds_ab_block;                         /**< 0: no DDS on/off comparison in this run */
    uint64_t dds_ab_n[2];                          /**< ticks timed with publishing [0] off, [1] on */
    int64_t dds_ab_p50_ns[2], dds_ab_p99_ns[2];    /**< whole tick, publishing [0] off, [1] on */
    double dds_ab_mean_ns[2];                      /**< the same, mean (exact, not binned) */
    uint64_t dds_ab_short_n[2];                    /**< of those, ticks shorter than half a period */
    double dds_ab_short_mean_ns[2];                /**< their mean: a machine's stall left out */
    double min_distance, min_distance_t;
    /* fixed bodies: the arm-body pair of least margin d - clearance (body_pair[0] -1: no bodies) */
    double body_margin, body_distance, body_t;
    int body_pair[3];   /**< arm, link, body (the cell's bodies, in order) */
    char body_name[32]; /**< that body's name */
    /* self pairs: the pair of least distance (self_pair[0] -1: no self pairs) */
    double self_distance, self_t;
    int self_pair[3]; /**< arm, link, the other link */
    int body_kind;    /**< and kind (mca_body_kind_t: mca_body_kind_name) */
    /* every kind of pair (mca_dds_pair_kind_t): its least distance over the run and when (+INF: none) */
    double kind_min[MCA_DDS_PAIR_KINDS], kind_min_t[MCA_DDS_PAIR_KINDS];
    /* each fixed body of the cell: its least distance over the run, when, and the link (arm -1: none) */
    int n_fixed_bodies;
    double fixed_min[MCA_MAX_BODIES], fixed_min_t[MCA_MAX_BODIES];
    int fixed_min_link[MCA_MAX_BODIES][2]; /**< arm, link */
    char fixed_name[MCA_MAX_BODIES][32];
    int fault;          /**< mca_daemon_fault_t */
    int ctrl_fault;     /**< mca_ctrl_fault_t when fault == CONTROLLER */
    int fault_arm;      /**< the arm the fault is about (ARM, LOST_FEEDBACK, BUS, FEEDBACK), else -1 */
    int feedback_fault; /**< mca_feedback_fault_t when fault == FEEDBACK */
    uint64_t implausible_samples; /**< feedback samples dropped as implausible (every arm, whole run) */
    int n_arms;
    char arm_name[MCA_MAX_ARMS][32];    /**< the cell's arm names */
    mca_arm_stats_t link[MCA_MAX_ARMS]; /**< each arm's link counters (mca_arm_stats) */
    /* The fault as the loop latched it: a code and numbers (no text is made on the rt path). */
    int fault_detail;   /**< ARM: 1 reports FAULT, 2 brakes on its own, 3 does not servo; FEEDBACK: the
                             mca_feedback_fault_t; CONTROLLER: the mca_ctrl_fault_t */
    int fault_arm_code; /**< ARM: the arm's fault code (1, 2) or state (3) */
    int fault_count;    /**< OVERRUN: periods missed in a row; LOST_FEEDBACK, BUS: cycles without feedback */
    mca_ctrl_fault_why_t ctrl_why; /**< CONTROLLER: the controller's cause */
    char fault_text[256];          /**< made by mca_daemon_summary() (non-rt) from the fields above */
    double fault_t;
    uint64_t log_dropped, csv_dropped;
    /* braking (SIGTERM or a fault; through mca_controller_brake) */
    double brake_t;                /**< task time braking began (-1: never braked) */
    double stop_duration_s;        /**< from brake_t to every command at zero (-1: not at rest yet) */
    uint64_t brake_fallback_ticks; /**< braking ticks with the keep-direction fallback (QP had no answer
                                        or the stop's deadline had passed) */
    uint64_t brake_forced_ticks;   /**< of those, ticks past the deadline (max_j |v_j|/dec_j + margin) */
    double max_dv_over_dt_dec;     /**< braking: largest per-tick |commanded velocity change| / (dec dt) */
    /* mca-ts path-time scaling */
    int deadlock;     /**< mca_deadlock_state_t now */
    int deadlock_arm; /**< the arm backing off (-1: none) */
    int deadlocks;    /**< deadlocks detected so far */
    int sched_fifo;   /**< 1 when the loop ran SCHED_FIFO */
    int mem_locked;
    int dma_latency_held;
} mca_daemon_summary_t;

typedef struct mca_daemon mca_daemon_t; /**< opaque */

/**
 * Open everything a cell needs (start-up): controller, arms (waits up to 2 s for each to answer),
 * DDS bridge, log ring. State READY on success.
 * @retval MCA_OK, MCA_ENOMEM, or a backend/controller/DDS error (err says which arm/part)
 * @retval MCA_ECONFIG  an arm's backend id is none the registry has (set in code after the file was read):
 *         "FILE:LINE: arms[N].backend: unknown backend id ID (known: ...)", nothing opened
 */
int mca_daemon_open(mca_daemon_t **d, const mca_cell_t *cell, const mca_daemon_opts_t *opts, char *err,
                    size_t errlen);

/** Start the real-time loop thread (SCHED_FIFO where permitted, else a warning and SCHED_OTHER).
 *  @retval MCA_OK, or MCA_EINVAL for a daemon a driver opened (mca/daemon_drive.h: it steps it itself) */
int mca_daemon_start(mca_daemon_t *d);

/** Ask the loop to brake and stop (any thread, async-signal safe). */
void mca_daemon_request_stop(mca_daemon_t *d);
/** 1 once the loop thread has ended. */
int mca_daemon_finished(const mca_daemon_t *d);
/** Ticks done so far (any thread; the supervisor's liveness check). */
uint64_t mca_daemon_ticks(const mca_daemon_t *d);
/** Current state (any thread). */
int mca_daemon_state(const mca_daemon_t *d);

/** Drain the log and CSV rings (non-rt; call often from ONE thread). @return records handled */
int mca_daemon_service(mca_daemon_t *d);

/** Wait for the loop thread to end. */
int mca_daemon_join(mca_daemon_t *d);

/** Figures so far: while the loop runs, the ones it published last (once a second; state and ticks are
 *  current); once it has ended (or without a loop thread), exact. Call from ONE non-rt thread. */
void mca_daemon_summary(mca_daemon_t *d, mca_daemon_summary_t *s);
/** The summary block as lines to fn (mca/log.h: "summary: ..." with their levels, 6 unless one says a
 *  problem). */
void mca_daemon_log_summary(const mca_daemon_summary_t *s, mca_log_fn fn, void *arg);
/** The loop's wake-up latency histogram (mcad --histogram writes it), and when the first and the last of
 *  those wake-ups were due [ns of CLOCK_MONOTONIC; 0 without any]. Once the loop has ended. */
const mca_hist_t *mca_daemon_wake_histogram(const mca_daemon_t *d, int64_t *first_due_ns,
                                            int64_t *last_due_ns);

/** Close arms, DDS (publishing the final status) and free (shut-down). NULL is allowed. */
void mca_daemon_close(mca_daemon_t *d);

/* Stepping the daemon in virtual time instead of the loop (mca-sim, the tests): mca/daemon_drive.h. */

#ifdef __cplusplus
}
#endif
#endif
