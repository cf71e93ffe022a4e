/* SPDX-License-Identifier: MIT */
/* The daemon's lines, to the sink its caller gave (mca_daemon_opts_t.log, mca/log.h): the library prints
 * nothing itself. Private to mca_daemon. Calling context: start-up, the service thread and shut-down, never
 * the RT thread (it formats; the loop queues its lines on mca/rtlog.h). */
#ifndef MCA_DAEMON__LOG_H
#define MCA_DAEMON__LOG_H

#include "mca/log.h"

struct mca_daemon;

/* One line (printf format, no newline) at a syslog level to fn (NULL: dropped). */
void mcad_logf(mca_log_fn fn, void *arg, int level, const char *fmt, ...)
    __attribute__((format(printf, 4, 5)));

/* One line to the daemon's sink. */
#define mcad_log(d, level, ...) mcad_logf((d)->opts.log, (d)->opts.log_arg, (level), __VA_ARGS__)

#endif
