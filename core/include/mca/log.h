/* SPDX-License-Identifier: MIT */
/** @file mca/log.h
 * Where a library's lines go: libraries print nothing themselves; the program that uses them (mcad, mca-sim,
 * a test) owns the sink and writes each line its way (mcad: "<LEVEL>mcad: TEXT" on stderr, the
 * journald/syslog priority prefix of sd-daemon(3)). Context: the sink is called from the thread that called
 * the library function that takes it, never from the real-time loop (mca/rtlog.h queues the loop's lines).
 */
#ifndef MCA_LOG_H
#define MCA_LOG_H

#ifdef __cplusplus
extern "C" {
#endif

/** A sink: @p level is syslog's (3 error, 4 warning, 5 notice, 6 info, 7 debug), @p text one line without a
 *  level, a program's name or the newline. */
typedef void (*mca_log_fn)(void *arg, int level, const char *text);

#ifdef __cplusplus
}
#endif
#endif
