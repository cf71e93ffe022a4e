/* SPDX-License-Identifier: MIT */
/* The arms' I/O and supervision (daemon_arms.c): each arm opened through its backend and waited for, then
 * every tick its feedback read, checked and supervised (lost cycles, bus errors, an arm's own fault, an
 * arm that does not servo: each latched through daemon__fault.h) and its command sent. Private to
 * mca_daemon.
 *
 * Calling context: mcad_open_arm and mcad_handshake at start-up (mca_daemon_open; the handshake sleeps a
 * period between reads unless in virtual time, and logs with fprintf); mcad_read_feedback and
 * mcad_send_commands on the RT thread (the loop, or the driver through mca_drive_step): no allocation, no
 * locks, no blocking I/O, logs through d->log only. */
#ifndef MCA_DAEMON__ARMS_H
#define MCA_DAEMON__ARMS_H

#include <stddef.h>

#include "daemon__state.h"

/* Start-up: open arm a through its backend. err says which arm and why. */
int mcad_open_arm(mca_daemon_t *d, int a, char *err, size_t errlen);
/* Start-up: wait (up to 2 s) until arm a answers with a plausible sample; its FAULT cleared only on
 * --clear-faults. */
int mcad_handshake(mca_daemon_t *d, int a, char *err, size_t errlen);

/* RT: every arm's feedback of this tick (task time t), checked; faults latched. */
void mcad_read_feedback(mca_daemon_t *d, double t);
/* RT: every arm's command from d->qdot (@p servo 0: zero velocity, servo released); stalls counted. */
void mcad_send_commands(mca_daemon_t *d, int servo);

#endif
