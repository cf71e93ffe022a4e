/* SPDX-License-Identifier: MIT */
/** @file mca/rtlog.h
 * Logging from the real-time thread: mca_rtlog() copies a record (level, time, a format string
 * literal, up to 4 numbers, a short text) into a lock-free SPSC ring (mca/ring.h) and returns; no
 * formatting, allocation or I/O happens on the rt side. A normal thread calls mca_rtlog_drain(),
 * which formats each record and hands the line and its level to the owner's sink (mca/log.h: the library
 * prints nothing; mcad writes "<3>mcad: fault: distance 0.049 m below d1").
 *
 * Format rules: `fmt` must be a string literal (only its pointer is stored) whose conversions are
 * all double conversions (%g, %.3f, %e ...) taking the numbers in order, plus at most one %s, which
 * must come AFTER all the numbers and takes the text.
 *
 * A record can also carry a code and numbers without any format (mca_rtlog_code()): the drainer turns it
 * into text with the owner's formatter (mca_rtlog_set_formatter()), off the rt path; the daemon logs its
 * faults this way.
 *
 * If the drainer falls behind, the oldest records are overwritten and counted (mca_rtlog_dropped()).
 */
#ifndef MCA_RTLOG_H
#define MCA_RTLOG_H

#include <stddef.h>
#include <stdint.h>
#include "mca/log.h"
#include "mca/ring.h"

#ifdef __cplusplus
extern "C" {
#endif

/** Priorities (syslog numbering). */
enum { MCA_LOG_ERR = 3, MCA_LOG_WARNING = 4, MCA_LOG_NOTICE = 5, MCA_LOG_INFO = 6, MCA_LOG_DEBUG = 7 };

#define MCA_RTLOG_TEXT 96
#define MCA_RTLOG_CAPACITY 256

typedef struct mca_rtlog_rec {
    int level;
    int nargs;
    int code;         /**< mca_rtlog_code(): the owner's code (fmt is NULL then) */
    int64_t stamp_ns; /**< CLOCK_MONOTONIC */
    const char *fmt;
    double arg[4];
    char text[MCA_RTLOG_TEXT];
} mca_rtlog_rec_t;

/** Formatter of mca_rtlog_code() records (non-rt, called by the drainer): writes the message into buf. */
typedef void (*mca_rtlog_formatter_t)(void *arg, const struct mca_rtlog_rec *rec, char *buf, size_t len);

typedef struct mca_rtlog {
    mca_ring_t ring;
    _Alignas(8) unsigned char storage[MCA_RING_STORAGE_SIZE(sizeof(mca_rtlog_rec_t), MCA_RTLOG_CAPACITY)];
    mca_rtlog_formatter_t formatter;
    void *formatter_arg;
} mca_rtlog_t;

/** Context: init. @retval MCA_OK, MCA_EINVAL */
int mca_rtlog_init(mca_rtlog_t *log);

/** Queue one record (rt; one producer thread). text may be NULL. Unused args are ignored. */
void mca_rtlog(mca_rtlog_t *log, int level, const char *fmt, int nargs, double a0, double a1, double a2,
               double a3, const char *text);

/** Queue one record with a code and numbers, no format (rt; one producer thread): the drainer formats it
 *  with the formatter set by mca_rtlog_set_formatter(). text may be NULL. */
void mca_rtlog_code(mca_rtlog_t *log, int level, int code, int nargs, double a0, double a1, double a2,
                    double a3, const char *text);

/** Set the formatter of code records. Context: init (before the first record is drained). */
void mca_rtlog_set_formatter(mca_rtlog_t *log, mca_rtlog_formatter_t fn, void *arg);

/** Hand every queued record to fn as a line (non-rt; one consumer thread; fn NULL: the records are dropped).
 *  @return records drained */
int mca_rtlog_drain(mca_rtlog_t *log, mca_log_fn fn, void *arg);

/** Records lost to overrun so far. */
uint64_t mca_rtlog_dropped(const mca_rtlog_t *log);

/** Format one record's message (without level or name) into buf (for tests and the drainer). @return buf */
char *mca_rtlog_format(const mca_rtlog_t *log, const mca_rtlog_rec_t *rec, char *buf, size_t len);

#ifdef __cplusplus
}
#endif
#endif
