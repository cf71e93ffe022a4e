/* SPDX-License-Identifier: MIT */
/* Summary (daemon_summary.c): the run's figures (mca_daemon_summary_t) from the loop's own data, handed
 * to the supervisor once a second through a ring; their read-out (mca_daemon_summary, with the fault's
 * text) and the lines to the caller's sink (mca_daemon_log_summary). Private to mca_daemon.
 *
 * Calling context: mcad_compute_summary on the RT thread (once a second, from mcad_step: no
 * formatting, no allocation) or once the loop has ended; mca_daemon_summary from ONE non-rt thread (the
 * supervisor; it formats the fault's text); mca_daemon_log_summary anywhere off the RT path. */
#ifndef MCA_DAEMON__SUMMARY_H
#define MCA_DAEMON__SUMMARY_H

#include "daemon__state.h"

/* RT (once a second) or after the loop: the figures from the loop's data, the fault as a record. */
void mcad_compute_summary(const mca_daemon_t *d, mca_daemon_summary_t *s);

#endif
