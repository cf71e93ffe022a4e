/* SPDX-License-Identifier: MIT */
/* Real-time logging through an SPSC ring (see mca/rtlog.h). */
#include "mca/rtlog.h"

#include <stdio.h>
#include <string.h>
#include <time.h>

#include "mca/err.h"

int mca_rtlog_init(mca_rtlog_t *log) {
    if (!log) {
        return MCA_EINVAL;
    }
    log->formatter = NULL;
    log->formatter_arg = NULL;
    return mca_ring_init(&log->ring, log->storage, sizeof log->storage, sizeof(mca_rtlog_rec_t),
                         MCA_RTLOG_CAPACITY);
}

void mca_rtlog_set_formatter(mca_rtlog_t *log, mca_rtlog_formatter_t fn, void *arg) {
    log->formatter = fn;
    log->formatter_arg = arg;
}

static void rtlog_put(mca_rtlog_t *log, int level, const char *fmt, int code, int nargs, double a0, double a1,
                      double a2, double a3, const char *text) {
    mca_rtlog_rec_t r;
    r.code = code;
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts); /* vDSO: no system call */
    r.level = level;
    r.nargs = nargs < 0 ? 0 : (nargs > 4 ? 4 : nargs);
    r.stamp_ns = (int64_t)ts.tv_sec * 1000000000LL + ts.tv_nsec;
    r.fmt = fmt;
    r.arg[0] = a0;
    r.arg[1] = a1;
    r.arg[2] = a2;
    r.arg[3] = a3;
    size_t i = 0;
    if (text) {
        for (; i + 1 < MCA_RTLOG_TEXT && text[i]; i++) {
            r.text[i] = text[i];
        }
    }
    r.text[i] = 0;
    mca_ring_push(&log->ring, &r);
}

void mca_rtlog(mca_rtlog_t *log, int level, const char *fmt, int nargs, double a0, double a1, double a2,
               double a3, const char *text) {
    rtlog_put(log, level, fmt, 0, nargs, a0, a1, a2, a3, text);
}

void mca_rtlog_code(mca_rtlog_t *log, int level, int code, int nargs, double a0, double a1, double a2,
                    double a3, const char *text) {
    rtlog_put(log, level, NULL, code, nargs, a0, a1, a2, a3, text);
}

char *mca_rtlog_format(const mca_rtlog_t *log, const mca_rtlog_rec_t *r, char *buf, size_t len) {
    char *msg = buf;
    const size_t msglen = len;
    const double *a = r->arg;
    const char *t = r->text;
    if (r->fmt == NULL) {
        /* a code record: the owner's formatter (non-rt) */
        msg[0] = 0;
        if (log->formatter) {
            log->formatter(log->formatter_arg, r, msg, msglen);
        } else {
            snprintf(msg, msglen, "code %d: %g %g %g %g %s", r->code, a[0], a[1], a[2], a[3], t);
        }
        return buf;
    }
    /* the text goes right after the numbers (see the format rules) */
    switch (r->nargs) {
    case 0:
        snprintf(msg, msglen, r->fmt, t);
        break;
    case 1:
        snprintf(msg, msglen, r->fmt, a[0], t);
        break;
    case 2:
        snprintf(msg, msglen, r->fmt, a[0], a[1], t);
        break;
    case 3:
        snprintf(msg, msglen, r->fmt, a[0], a[1], a[2], t);
        break;
    default:
        snprintf(msg, msglen, r->fmt, a[0], a[1], a[2], a[3], t);
        break;
    }
    return buf;
}

int mca_rtlog_drain(mca_rtlog_t *log, mca_log_fn fn, void *arg) {
    mca_rtlog_rec_t r;
    int n = 0;
    char line[384];
    while (mca_ring_pop(&log->ring, &r) == MCA_OK) {
        if (fn) {
            fn(arg, r.level, mca_rtlog_format(log, &r, line, sizeof line));
        }
        n++;
    }
    return n;
}

uint64_t mca_rtlog_dropped(const mca_rtlog_t *log) {
    mca_ring_stats_t st;
    mca_ring_stats(&log->ring, &st);
    return st.dropped;
}
