/* SPDX-License-Identifier: MIT */
/* Publishing (daemon_publish.c): the DDS bridge, a process of its own (mca-dds-bridge), with the cell's
 * ROS 2 topics; the loop fills one snapshot per publishing tick and pushes it into the bridge's ring; at
 * shut-down the final status and the bridge's figures. Private to mca_daemon.
 *
 * Calling context: mcad_publish_open at start-up (mca_daemon_open: finds and starts the bridge, logs with
 * fprintf); mcad_fill_snapshot and mcad_dds_ab_publishes on the RT thread (no allocation, no locks; the
 * push makes a system call only when it finds the publisher parked); mcad_publish_close at shut-down
 * (mca_daemon_close, once the loop has ended). */
#ifndef MCA_DAEMON__PUBLISH_H
#define MCA_DAEMON__PUBLISH_H

#include <stddef.h>
#include <stdint.h>

#include "daemon__state.h"

/* --dds-ab: tick @p n publishes only in the odd blocks; without it every tick publishes */
static inline int mcad_dds_ab_publishes(const mca_daemon_t *d, uint64_t n) {
    return d->opts.dds_ab_block == 0 || (n / d->opts.dds_ab_block) % 2 == 1;
}

/* Start-up: create the bridge (d->dds) as the cell's dds section says. err says why not. */
int mcad_publish_open(mca_daemon_t *d, char *err, size_t errlen);
/* RT (and shut-down): d->snap from this tick's feedback, commands, distances and status. */
void mcad_fill_snapshot(mca_daemon_t *d, int64_t stamp_ns, int state);
/* Service thread: the DDS library's lines (mca_dds_log_fn; arg is the daemon) to the daemon's sink. */
void mcad_dds_log_line(void *arg, int level, const char *text);
/* Shut-down (d->dds set, the loop ended): push the final status, destroy the bridge, log its figures. */
void mcad_publish_close(mca_daemon_t *d);

#endif
