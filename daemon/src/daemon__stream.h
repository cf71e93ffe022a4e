/* SPDX-License-Identifier: MIT */
/* Streamed input (daemon_stream.c): the streamed bodies (streamed_bodies) and task.stream's targets, taken
 * each running tick from the bridge's mailbox (a seqlock read), turned into each arm's reference velocity for
 * the controller; a stream silent for brake_after is a fault (through daemon__fault.h). Private to
 * mca_daemon.
 *
 * Calling context: RT thread (mcad_step, RUNNING only): no allocation, no locks, never waits. */
#ifndef MCA_DAEMON__STREAM_H
#define MCA_DAEMON__STREAM_H

#include <stdint.h>

#include "daemon__state.h"

/* RT: every arm's streamed velocity into the controller at task time t (the tick's wake-up now_ns). */
void mcad_stream_targets(mca_daemon_t *d, double t, int64_t now_ns);

/* RT: the streamed bodies' latest message into the controller at task time t (every tick, running or
 * braking: a stale track keeps growing); no message for lost_after: MCA_DAEMON_FAULT_TRACKS_LOST. */
void mcad_stream_bodies(mca_daemon_t *d, double t, int64_t now_ns);

#endif
