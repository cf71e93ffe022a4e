/* SPDX-License-Identifier: MIT */
/* One tick (daemon_tick.c): mcad_step runs the daemon's state machine once: the stop
 * request, the arms' feedback (daemon__arms.h), streamed targets (daemon__stream.h), the controller tick or
 * the braking tick (daemon__fault.h), commands, once a second the figures (daemon__summary.h), the DDS
 * snapshot (daemon__publish.h) and the CSV row (daemon__csv.h); the PDNN budget and mca-ts deadlocks logged
 * as they happen. Private to mca_daemon.
 *
 * Calling context: RT thread: the loop (daemon_loop.c) or the driver's thread through mca_drive_step
 * (daemon_drive.c: mca-sim, the tests); never both. No allocation, no locks, no blocking I/O: logs through
 * d->log, hands rows and snapshots over through rings. */
#ifndef MCA_DAEMON__TICK_H
#define MCA_DAEMON__TICK_H

#include "daemon__state.h"

/* One tick at task time t [s] whose wake-up was stamp_ns; returns the state after it (mca_daemon_state_t). */
int mcad_step(mca_daemon_t *d, double t, int64_t stamp_ns);

#endif
