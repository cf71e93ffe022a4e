/* SPDX-License-Identifier: MIT */
/* One tick (daemon_tick.c): mca_daemon_step (mca/daemon.h) runs the daemon's state machine once: the stop
 * request, the arms' feedback (daemon__arms.h), streamed targets (daemon__stream.h), the controller tick or
 * the braking tick (daemon__fault.h), commands, once a second the figures (daemon__summary.h), the DDS
 * snapshot (daemon__publish.h) and the CSV row (daemon__csv.h); the PDNN budget and mca-ts deadlocks logged
 * as they happen. Private to mca_daemon.
 *
 * Calling context: RT thread: the loop (daemon_loop.c) or, in virtual time, the caller that steps the daemon
 * itself (mca-sim, the tests); never both. No allocation, no locks, no blocking I/O: logs through d->log,
 * hands rows and snapshots over through rings. */
#ifndef MCA_DAEMON__TICK_H
#define MCA_DAEMON__TICK_H

#include "daemon__state.h"

/* int mca_daemon_step(mca_daemon_t *d, double t, int64_t stamp_ns);   mca/daemon.h */

#endif
