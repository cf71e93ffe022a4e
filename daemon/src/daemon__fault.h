/* SPDX-License-Identifier: MIT */
/* Faults and braking (daemon_fault.c): the one latch every fault of the daemon goes through (the first
 * wins; RUNNING -> BRAKING), the braking tick that brings every arm to rest, and the fault's text. Whoever
 * finds a fault (daemon_arms.c, daemon_stream.c, daemon_tick.c, daemon_loop.c) calls mcad_latch_fault;
 * what a stop does is decided in mcad_brake_tick. Private to mca_daemon.
 *
 * Calling context: mcad_latch_fault, mcad_ctrl_fault_code and mcad_brake_tick on the RT thread (no
 * allocation, no locks, no text: a code and numbers, logged through d->log). mcad_fault_describe,
 * mcad_link_ignored_text, mcad_fault_text_to_dds and mcad_log_format off the RT path: the service thread
 * (mcad_log_format is d->log's formatter, called by mca_rtlog_drain), the summary and shut-down; they read
 * the latched fault once the record or snapshot that carries it reached them. */
#ifndef MCA_DAEMON__FAULT_H
#define MCA_DAEMON__FAULT_H

#include <stddef.h>

#include "daemon__state.h"

/* codes of mca_rtlog_code() records (formatted by mcad_log_format, non-rt) */
enum { LOGC_FAULT = 1, LOGC_ARM_FAULT_TOO = 2 };
/* fault_detail of MCA_DAEMON_FAULT_FEEDBACK when the arm's link refused the feedback (arm_code: its
 * link_fault), not the daemon's own check (mca_feedback_fault_t) */
#define FB_DETAIL_LINK (-1)

/* fault_detail of MCA_DAEMON_FAULT_ARM */
enum { ARM_FAULT_REPORTS = 1, ARM_FAULT_BRAKES = 2, ARM_FAULT_NOT_SERVO = 3 };

/* RT: latch fault (mca_daemon_fault_t) with its code and numbers, unless one is latched already. */
void mcad_latch_fault(mca_daemon_t *d, int fault, int code, double t, int arm, int detail, int arm_code,
                      int count, const mca_ctrl_fault_why_t *ctrl_why);
/* RT: the MCA_E* code a controller fault (mca_ctrl_fault_t) is published with. */
int mcad_ctrl_fault_code(int f);
/* RT: one braking tick at task time t from positions qp (commands into d->qdot). @return 1 when every
 * command is zero. */
int mcad_brake_tick(mca_daemon_t *d, double t, const double *const qp[MCA_MAX_ARMS]);

/* Non-rt: what an arm's link did not take, and why. */
void mcad_link_ignored_text(const mca_arm_stats_t *st, char *buf, size_t len);
/* Non-rt: the text of a latched fault. */
void mcad_fault_describe(const mca_daemon_t *d, int fault, int arm, int detail, int arm_code, int count,
                         const mca_ctrl_fault_why_t *ctrl_why, char *buf, size_t len);
/* Service thread: once a fault is latched, hand its text to the DDS publisher (once; nothing without DDS). */
void mcad_fault_text_to_dds(mca_daemon_t *d);
/* Service thread: d->log's formatter of mca_rtlog_code() records (mca_rtlog_formatter_t; arg is d). */
void mcad_log_format(void *arg, const mca_rtlog_rec_t *rec, char *buf, size_t len);

#endif
