/* SPDX-License-Identifier: MIT */
/* The tests' sink of the daemon's lines (mca/log.h; the library prints nothing): mcad's own form,
 * "<LEVEL>mcad: TEXT", on the FILE given as arg, so a test reads the lines an operator would. */
#ifndef MCA_TEST_LOG_SINK_H
#define MCA_TEST_LOG_SINK_H

#include <stdio.h>

static inline void test_log_line(void *arg, int level, const char *text) {
    fprintf((FILE *)arg, "<%d>mcad: %s\n", level, text);
    fflush((FILE *)arg);
}

#endif
