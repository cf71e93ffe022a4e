/* SPDX-License-Identifier: MIT */
/* The daemon's lines to its caller's sink (daemon__log.h). */
#include "daemon__log.h"

#include <stdarg.h>
#include <stdio.h>

void mcad_logf(mca_log_fn fn, void *arg, int level, const char *fmt, ...) {
    if (!fn) {
        return;
    }
    char line[1024];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(line, sizeof line, fmt, ap);
    va_end(ap);
    fn(arg, level, line);
}
