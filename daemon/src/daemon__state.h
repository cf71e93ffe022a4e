/* SPDX-License-Identifier: MIT */
/* The daemon's state (struct mca_daemon, opaque outside mca_daemon): one struct, its fields grouped by the
 * room that owns them (writes them); the other rooms read them as their comments say. Private to the
 * daemon's rooms (daemon.c, daemon_loop.c, daemon_tick.c, daemon_arms.c, daemon_plausibility.c,
 * daemon_fault.c, daemon_stream.c, daemon_publish.c, daemon_csv.c, daemon_summary.c, daemon_drive.c).
 *
 * Calling context: none of its own (a struct and helpers). Fields marked "shared with other threads" are
 * atomics; every other field is written by one thread at a time: start-up (mca_daemon_open) before the
 * loop starts, then the RT thread (the loop, or the driver through mca_drive_step), then
 * shut-down once the loop has ended. The service thread reads only what a ring record or the fault latch
 * (written once, before the record that carries it) hands it. */
#ifndef MCA_DAEMON__STATE_H
#define MCA_DAEMON__STATE_H

#include <pthread.h>
#include <stdatomic.h>
#include <stdint.h>
#include <stdio.h>
#include <time.h>

#include "mca/daemon.h"
#include "mca/dds_bridge.h"
#include "mca/tick_csv.h" /* mca_tick_csv_layout_t */

#define NS_PER_S 1000000000LL

/* What the virtual-time driver (mca/daemon_drive.h, daemon_drive.c) asks of the daemon; all zero (and the
 * schedule empty) under mcad's loop. */
typedef struct mcad_drive {
    int driven;       /* opened by mca_drive_open: mca_daemon_start refuses it */
    int virtual_time; /* the caller's clock: sim arms stamp it, no handshake sleep, no pinning, no publisher
                         grid, no stall count */
    uint32_t ideal_arms; /* bit a: arm a follows its command exactly */
    void (*controller_config)(mca_controller_config_t *, void *); /* before the controller's init */
    void *controller_config_arg;
    /* the schedule, by tick index (llround(t / dt)); < 0: none. Written and read by the driving thread */
    long long stop_k, fault_k;
    int fault_kind;
    unsigned fired; /* mca_drive_event bits */
    /* the streamed bodies' source in place of the DDS bridge (mca_drive_put_tracks); tracks_on 0: the bridge
     */
    int tracks_on;
    mca_ros2_tracks_t tracks;
} mcad_drive_t;

struct mca_daemon {
    /* ---- set at open (daemon.c), read-only after */
    mca_cell_t cell;
    mca_daemon_opts_t opts;
    mca_controller_config_t ccfg;
    mca_controller_t *ctrl; /* in storage allocated here at open, before the loop locks memory */
    int n_arms;
    int dof[MCA_MAX_ARMS];
    mca_rtlog_t log;
    mcad_drive_t drive; /* the driver's settings (daemon_drive.c); its schedule changes between steps */

    /* ---- loop and timing (daemon_loop.c) */
    /* shared with other threads */
    _Atomic int state;
    _Atomic uint64_t ticks;
    _Atomic int stop_request;
#ifdef MCA_TEST_HOOKS
    _Atomic int stall_request;
#endif
    _Atomic int finished;
    pthread_t thread;
    int thread_started;
    mca_controller_t *warm_ctrl; /* scratch copy the loop warms its code on before the first command (its
                                    storage allocated at open) */
    mca_tick_info_t warm_info;
    int consecutive_overruns;
    uint64_t overruns, skipped;
    int64_t wake_late_ns; /* this tick woke this late (the loop sets it; 0 in virtual time) */
    mca_hist_t jitter, compute;
    int64_t jitter_first_due_ns, jitter_last_due_ns; /* the wake-ups in jitter were due in this span */
    mca_hist_t compute_ab[2];          /* --dds-ab: whole tick with publishing [0] off, [1] on */
    double compute_ab_short_sum_ns[2]; /* the same, ticks shorter than half a period only */
    uint64_t compute_ab_short_n[2];
    int sched_fifo, mem_locked, dma_fd;
    int non_rt_pinned; /* rt.cpu: the non-rt threads were moved off the loop's CPU */

    /* ---- arms' I/O and supervision (daemon_arms.c; bounds set at open by daemon_plausibility.c) */
    mca_arm_t *arm[MCA_MAX_ARMS];
    mca_arm_feedback_t fb[MCA_MAX_ARMS];
    int have_fb[MCA_MAX_ARMS];
    int lost[MCA_MAX_ARMS];
    uint64_t bus_errors[MCA_MAX_ARMS];
    int not_servo[MCA_MAX_ARMS];      /* ticks RUNNING with the arm not servoing */
    int arm_fault_told[MCA_MAX_ARMS]; /* an arm's own fault after the first fault was logged (once) */
    /* feedback plausibility (mca_feedback_fault_t), bounds set at open */
    double fb_lo[MCA_MAX_ARMS][MCA_MAX_DOF], fb_hi[MCA_MAX_ARMS][MCA_MAX_DOF]; /* limits -+ margin */
    double fb_vmax[MCA_MAX_ARMS][MCA_MAX_DOF];                                 /* factor x vel limit */
    uint32_t fb_frame[MCA_MAX_ARMS];    /* frame id of the last good sample */
    uint64_t implausible[MCA_MAX_ARMS]; /* samples dropped */
    mca_arm_command_t cmd[MCA_MAX_ARMS];
    double q[MCA_MAX_ARMS][MCA_MAX_DOF];
    double vcmd[MCA_MAX_ARMS][MCA_MAX_DOF]; /* velocity last commanded (braking starts here) */
    uint32_t frame_id;
    uint64_t stalls;      /* ticks whose commands came > MCA_DAEMON_STALL_PERIODS periods after the last */
    int64_t stall_max_ns; /* the longest such gap */
    int64_t sent_ns;      /* when the last tick's commands went out (0: none yet) */
    int64_t cmd_gap_ns;   /* this tick's commands after the last tick's (CSV cmd_gap_us) */

    /* ---- faults and braking (daemon_fault.c) */
    int fault_arm, feedback_fault; /* latched with the fault */
    int fault;                     /* mca_daemon_fault_t; latched */
    int ctrl_fault;
    int fault_code; /* negative MCA_E* for DDS */
    /* The fault is latched as a code and numbers (no text on the rt path); mcad_fault_describe() makes the
     * text in the non-rt threads (log drainer, summary, DDS publisher), which read these once the record or
     * snapshot that carries the fault reached them (written once, before, by the loop). */
    int fault_detail;   /* ARM: ARM_FAULT_*; FEEDBACK: mca_feedback_fault_t; CONTROLLER: mca_ctrl_fault_t */
    int fault_arm_code; /* ARM: the arm's fault code (reports FAULT, brakes) or state (does not servo) */
    int fault_count;    /* OVERRUN: periods missed in a row; LOST_FEEDBACK/BUS: cycles without feedback */
    mca_ctrl_fault_why_t ctrl_why; /* CONTROLLER: the controller's cause (a code and numbers, copied once) */
    mca_arm_stats_t fault_link;    /* LOST_FEEDBACK: the arm's link counters then (why nothing was taken) */
    int have_fault_link;
    double fault_t;
    /* shared with the service thread: 1 once the fields above hold a latched fault (release; the service
     * thread hands its text to the DDS publisher after an acquire load, daemon_fault.c) */
    _Atomic int fault_latched;
    int fault_text_handed;                 /* service thread: the publisher has the fault's text */
    int stop_pending;                      /* BRAKING towards STOPPED (not FAULT) */
    double dec[MCA_MAX_ARMS][MCA_MAX_DOF]; /* braking deceleration per joint (cell dec_limit) */
    /* braking (mca_controller_brake): one stop at most per run */
    int brake_active;        /* braking started (brake_t0, brake_deadline valid) */
    double brake_t0;         /* task time braking began */
    double brake_deadline;   /* from here on the keep-direction scale-down is forced */
    double brake_rest_t;     /* task time all commands reached zero (-1: not yet) */
    uint64_t brake_fallback; /* braking ticks that used the keep-direction fallback (QP or forced) */
    uint64_t brake_forced;   /* of those, ticks past brake_deadline */
    int brake_fallback_logged;
    double brake_max_dv; /* max over braking ticks and joints of |dv| / (dec dt) */

    /* ---- the tick (daemon_tick.c) */
    double t_tick; /* this tick's task time */
    double qdot[MCA_MAX_ARMS][MCA_MAX_DOF];
    mca_tick_info_t info;
    mca_hist_t ctrl_time;
    /* running ticks whose PDNN ran out of its budget (mca_budget_hit_t: [0] the clock, [1] the step budget):
     * repaired answers, no fault; logged the first, then once a second how many more */
    uint64_t budget_hits[2];
    uint64_t budget_unlogged;
    /* mca-ts deadlock state as last seen */
    int deadlock, deadlock_arm, deadlocks;
    double min_d, min_d_t;
    int64_t min_d_stamp;
    /* fixed bodies: the arm-body pair of least margin (d - clearance) over the run, every tick */
    double body_margin, body_d, body_t;
    int body_pair[3]; /* arm, link, body */
    double self_d, self_t;
    int self_pair[3]; /* arm, link, other link */
    /* every kind of pair: this tick's closest link of each body and each arm's self pair (the snapshot's
     * named pairs), and over the run the least distance of each kind (mca_dds_pair_kind_t) and of each fixed
     * body */
    mca_pair_nearest_t pn;
    double kind_min[MCA_DDS_PAIR_KINDS], kind_min_t[MCA_DDS_PAIR_KINDS];
    double fixed_min[MCA_MAX_BODIES], fixed_min_t[MCA_MAX_BODIES];
    int fixed_min_link[MCA_MAX_BODIES][2]; /* arm, link */
    int64_t pct_cache[6];                  /* the summary's percentiles of the last second (the DDS status) */

    /* ---- streamed bodies (daemon_stream.c) */
    mca_ros2_tracks_t tracks; /* the last message read (kept while the bridge writes the next) */
    int64_t tracks_since_ns;  /* the first tick's stamp: no message since then counts as lost too */
    uint64_t tracks_bad;      /* messages the controller refused (the bridge had passed them) */
    double tracks_lost_age;   /* LOST: the silence when it latched [s] */

    /* ---- publishing (daemon_publish.c) */
    mca_dds_bridge_t *dds;
    mca_dds_snapshot_t snap;
    mca_ros2_config_t ros2; /* the bridge's ROS 2 topics (start-up only) */

    /* ---- CSV and recording: rt -> writer (daemon_csv.c) */
    mca_ring_t csv_ring;
    unsigned char *csv_storage; /* the ring's: set when either file is written */
    FILE *csv;
    FILE *rec;
    mca_daemon_csv_rec_t csv_rec; /* rt scratch */
    mca_daemon_csv_rec_t csv_out; /* writer scratch */
    mca_tick_csv_layout_t csv_layout;

    /* ---- figures: rt -> supervisor, once a second (daemon_summary.c) */
    mca_ring_t sum_ring;
    _Alignas(8) unsigned char sum_storage[MCA_RING_STORAGE_SIZE(sizeof(mca_daemon_summary_t), 4)];
    mca_daemon_summary_t sum_rt, sum_main;
};

static inline int64_t now_ns(void) {
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (int64_t)ts.tv_sec * NS_PER_S + ts.tv_nsec;
}

#define LOG0(d, lvl, fmt) mca_rtlog(&(d)->log, lvl, fmt, 0, 0, 0, 0, 0, NULL)
#define LOGN(d, lvl, fmt, n, a0, a1, a2, a3, txt) mca_rtlog(&(d)->log, lvl, fmt, n, a0, a1, a2, a3, txt)

#endif
