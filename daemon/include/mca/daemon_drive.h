/* SPDX-License-Identifier: MIT */
/** @file mca/daemon_drive.h
 * The virtual-time driver of the controller daemon: a caller steps mcad's own tick itself, tick by tick,
 * instead of the 1 kHz loop thread. What mca-sim (and through it the sweep, mca-sweep, and the bench's
 * virtual-time rows), tests/scheme and the daemon's tests use of the daemon; mcad itself never calls any
 * of it (the daemon.prod_symbols test checks that its binary holds none of these functions).
 *
 * The daemon a driver opens is mcad's: the same cell, controller, arms' I/O and supervision, fault latch,
 * braking (mca_controller_brake and the keep-direction fallback) and outputs (CSV, recording, DDS). What
 * differs is only what the driver asks for here:
 *   - time: the caller gives each tick's task time t and stamp; in virtual time (the default) the sim
 *     backend's arms stamp the caller's virtual clock, start-up does not sleep between handshake reads, no
 *     thread is pinned, the DDS publisher is not put on the loop's grid and no loop stall is counted;
 *   - ideal arms: a sim backend arm that follows its command exactly (q += qdot dt, no limits, lag or rate
 *     limits: mca-sim --euler);
 *   - the controller's configuration, changed once after the cell built it and before the controller's
 *     init (mca-sim's solver overrides);
 *   - a stop request or a controller fault at a task time (mca-sim --stop-at, --fault-at): each acts
 *     before the first tick at or after that time, as mcad's SIGTERM and a fault the tick had found would;
 *   - read-outs of the last tick (its report, the controller, positions, commands, an arm's handle).
 * A test-only power (stalling the loop, swapping an arm's handle) is not here: mca/daemon_test.h, in the
 * test build only.
 *
 * Calling context: one thread, the driver's, owns the daemon: mca_drive_open and mca_daemon_close are
 * start-up and shut-down; mca_drive_step is rt (no allocation, no locks, no blocking I/O: the same code as
 * the loop's tick); the schedule and read-out functions are for the same thread, between steps. Never
 * call mca_daemon_start on a driven daemon (it refuses: MCA_EINVAL). mca_daemon_service,
 * mca_daemon_summary, mca_daemon_request_stop and mca_daemon_close of mca/daemon.h apply as for mcad.
 */
#ifndef MCA_DAEMON_DRIVE_H
#define MCA_DAEMON_DRIVE_H

#include <stdint.h>

#include "mca/arm.h"
#include "mca/cell.h"
#include "mca/controller.h"
#include "mca/daemon.h"
#include "mca/ros2.h" /* mca_ros2_tracks_t */

#ifdef __cplusplus
extern "C" {
#endif

/** How a driver opens the daemon. */
typedef struct mca_drive_opts {
    /** As mcad's options (log, csv_path, record_path, no_dds, clear_faults, stop_after, ...). no_rt is
     *  implied (a driven daemon runs no loop thread); dds_ab_block belongs to mcad's loop and is ignored. */
    mca_daemon_opts_t daemon;
    /** 0 (virtual time, mca-sim): as the header says. 1: wall-clock stamps as mcad's: the sim arms stamp
     *  CLOCK_MONOTONIC, the handshake waits a period between reads, stalls between two steps' commands
     *  are counted (tests that step the daemon but check what the loop would see). */
    int wall_clock;
    /** bit a: arm a, which must be on the sim backend, follows its command exactly (mca-sim --euler) */
    uint32_t ideal_arms;
    /** Called once with the controller configuration the cell built, before the controller's init
     *  (start-up). NULL: none. */
    void (*controller_config)(mca_controller_config_t *cfg, void *arg);
    void *controller_config_arg;
} mca_drive_opts_t;

/** What mca_drive_fired reports. */
enum mca_drive_event {
    MCA_DRIVE_STOPPED = 1u << 0, /**< the stop of mca_drive_stop_at was requested */
    MCA_DRIVE_FAULTED = 1u << 1, /**< the fault of mca_drive_fault_at was latched */
};

/**
 * Open a cell's daemon for stepping (start-up): as mca_daemon_open, with the driver's options.
 * @retval MCA_OK  state READY
 * @retval MCA_EINVAL  NULL argument, or an ideal arm not on the sim backend (err says which)
 * @retval else  the codes of mca_daemon_open (err says which arm or part)
 */
int mca_drive_open(mca_daemon_t **d, const mca_cell_t *cell, const mca_drive_opts_t *opts, char *err,
                   size_t errlen);

/**
 * One tick at task time t (rt): first what is scheduled for it (the stop, then the fault), then the
 * daemon's tick: feedback, controller or braking, commands, DDS snapshot, CSV row.
 * @param t  task time [s] of this tick (the first tick's is 0; ticks one period apart)
 * @param stamp_ns  the tick's wake-up stamp (virtual time: llround(t 1e9))
 * @return the state after the tick (mca_daemon_state_t)
 */
int mca_drive_step(mca_daemon_t *d, double t, int64_t stamp_ns);

/** From now on the daemon's streamed bodies (the cell's streamed_bodies) come from here instead of the DDS
 *  bridge: the message *t as if the bridge had just accepted it (t->recv_ns on the ticks' stamp clock,
 *  t->accepted counting messages: a message with the same count is the same message, only older; each
 *  body's stamp how old it was when sent). The controller checks it as it checks the bridge's. A driven
 *  daemon may have streamed bodies with DDS off (mca-sim's simulated sphere, the tests); mcad, never driven,
 *  takes them over DDS Security only. Between steps. */
void mca_drive_put_tracks(mca_daemon_t *d, const mca_ros2_tracks_t *t);

/** Schedule a stop request (as mcad's SIGTERM) before the first tick at or after task time t [s]; a
 *  later call replaces it. */
void mca_drive_stop_at(mca_daemon_t *d, double t);
/** Schedule controller fault @p ctrl_fault (mca_ctrl_fault_t, > 0) before the first tick at or after task
 *  time t [s]: latched as if that tick had found it, then RUNNING -> BRAKING -> FAULT through the same path
 *  (named "injected fault KIND at t = T s"); a later call replaces it. */
void mca_drive_fault_at(mca_daemon_t *d, int ctrl_fault, double t);
/** The scheduled events that have acted so far (mca_drive_event bits). */
unsigned mca_drive_fired(const mca_daemon_t *d);

/** The last tick's report (the controller's; while braking or stopped its distances are current, its
 *  solver figures the last running tick's). */
const mca_tick_info_t *mca_drive_tick_info(const mca_daemon_t *d);
/** The controller (per-pair distances, the last QP, its configuration). */
const mca_controller_t *mca_drive_controller(const mca_daemon_t *d);
/** Joint positions of arm a the last tick used (NULL if a is out of range). */
const double *mca_drive_positions(const mca_daemon_t *d, int a);
/** The last command sent to arm a (NULL if a is out of range). */
const mca_arm_command_t *mca_drive_last_command(const mca_daemon_t *d, int a);
/** Arm a's handle (the sim backend's firmware through mca_sim_backend_firmware; NULL if a is out of
 *  range). The daemon owns it. */
mca_arm_t *mca_drive_arm(mca_daemon_t *d, int a);

#ifdef __cplusplus
}
#endif
#endif
