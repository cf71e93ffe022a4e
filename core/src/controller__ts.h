/* SPDX-License-Identifier: MIT */
/* mca-ts's path time (controller_ts.c): the acceleration box and the tube's braking step that shape the QP
 * before the solve; each arm's target rate and bounds from the deadlock state and the coordination gates
 * (before the solve); each arm's rate and clock, giving way, deadlock and back-off (after it); the exact
 * waypoints and the path-time figures of the tick report (every scheme). Private to mca_core.
 *
 * Calling context: RT, the thread that ticks the controller (mca_controller_tick); no allocation. */
#ifndef MCA_CONTROLLER__TS_H
#define MCA_CONTROLLER__TS_H

#include "controller__state.h" /* struct mca_controller */

/* Giving way ends where the error reaches this fraction of the tube's per-axis half width. */
#define MCA_TUBE_EDGE 0.8

/* RT: mca-ts, each joint's bounds within dec_limit dt of its present velocity (ctrl->box_center). */
void mca_ctrl__accel_box(mca_controller_t *ctrl, const mca_scheme_info_t *si, int na);
/* RT: mca-ts, the tube [lo, hi] of arm a widened to admit one keep-direction braking step. */
void mca_ctrl__tube_keep_brake(mca_controller_t *ctrl, const mca_scheme_info_t *si, int a,
                               const double rdot[3], double sig_lo, double sig_hi, double lo[3],
                               double hi[3]);
/* RT: mca-ts, before the solve: each arm's target rate and its bounds. */
void mca_ctrl__ts_plan(mca_controller_t *ctrl, double task_t, double target[], double lo[], double hi[]);
/* RT: mca-ts, after the solve: each arm's rate and clock, deadlock detection and back-off. */
void mca_ctrl__ts_advance(mca_controller_t *ctrl, mca_tick_info_t *info, const int ts_off[],
                          const double rdot_d[][3], const double target[], const double lo[],
                          const double hi[]);
/* RT: arm a's exact waypoints at path time tau. */
void mca_ctrl__exact_check(mca_controller_t *ctrl, int a, double tau);
/* RT: the path-time figures of the tick report. */
void mca_ctrl__fill_path_info(mca_controller_t *ctrl, mca_tick_info_t *info);

#endif
