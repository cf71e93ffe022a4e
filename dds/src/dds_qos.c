/* SPDX-License-Identifier: MIT */
/* QoS and participant set-up shared by every mca DDS endpoint. */
#include "mca/dds_qos.h"

#include <pthread.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "mca/err.h"
#include "mca/errbuf.h" /* mca_errbuf_printf */

dds_qos_t *mca_dds_qos_stream(void) {
    dds_qos_t *q = dds_create_qos();
    if (q == NULL) {
        return NULL;
    }
    /* max_blocking_time 0: a writer never waits for a slow or lost reader. Cyclone throttles a reliable
     * writer whose unacknowledged data passes its high watermark for up to max_blocking_time on EVERY write,
     * and with keep-last it then writes anyway: with 100 ms, a 1 Mbit/s link to one monitor held one
     * snapshot's writes for 6.4 s (tests/dds/test_netns_faults.py) and mcad's ring overflowed. With 0 the
     * oldest unacknowledged sample goes instead, inside DDS; reliable delivery to readers that keep up stays.
     */
    dds_qset_reliability(q, DDS_RELIABILITY_RELIABLE, 0);
    /* keep-last 1 lost samples at 1 kHz here: 16 absorbs a scheduling hiccup of the reader. */
    dds_qset_history(q, DDS_HISTORY_KEEP_LAST, 16);
    dds_qset_durability(q, DDS_DURABILITY_VOLATILE);
    return q;
}

dds_qos_t *mca_dds_qos_status(void) {
    dds_qos_t *q = dds_create_qos();
    if (q == NULL) {
        return NULL;
    }
    dds_qset_reliability(q, DDS_RELIABILITY_RELIABLE, 0); /* never waits: see mca_dds_qos_stream */
    dds_qset_history(q, DDS_HISTORY_KEEP_LAST, 1);
    dds_qset_durability(q, DDS_DURABILITY_TRANSIENT_LOCAL);
    return q;
}

int mca_dds_rc(dds_return_t rc) {
    switch (rc) {
    case DDS_RETCODE_OK:
        return MCA_OK;
    case DDS_RETCODE_BAD_PARAMETER:
        return MCA_EINVAL;
    case DDS_RETCODE_OUT_OF_RESOURCES:
        return MCA_ENOMEM;
    case DDS_RETCODE_TIMEOUT:
        return MCA_ETIMEDOUT;
    case DDS_RETCODE_UNSUPPORTED:
        return MCA_ENOTSUP;
    case DDS_RETCODE_PRECONDITION_NOT_MET:
    case DDS_RETCODE_ILLEGAL_OPERATION:
    case DDS_RETCODE_NOT_ENABLED:
    case DDS_RETCODE_ALREADY_DELETED:
        return MCA_ESTATE;
    case DDS_RETCODE_NO_DATA:
    case DDS_RETCODE_TRY_AGAIN:
        return MCA_EAGAIN;
    default:
        return rc > 0 ? MCA_OK : MCA_EIO; /* > 0: a handle */
    }
}

int mca_dds_open_participant(uint32_t domain_id, const char *config_path, dds_entity_t *participant,
                             dds_entity_t *domain, char *err, size_t errlen) {
    if (participant == NULL || domain == NULL || domain_id > MCA_DDS_MAX_DOMAIN) {
        mca_errbuf_printf(err, errlen, "domain id %u out of range 0..%d", domain_id, MCA_DDS_MAX_DOMAIN);
        return MCA_EINVAL;
    }
    *domain = 0;
    if (config_path != NULL) {
        FILE *f = fopen(config_path, "r");
        if (f == NULL) {
            mca_errbuf_printf(err, errlen, "cannot read config file '%s'", config_path);
            return MCA_ENOENT;
        }
        fclose(f);
        const size_t len = strlen(config_path) + sizeof "file://";
        char *uri = malloc(len);
        if (uri == NULL) {
            return MCA_ENOMEM;
        }
        snprintf(uri, len, "file://%s", config_path);
        const dds_entity_t d = dds_create_domain((dds_domainid_t)domain_id, uri);
        free(uri);
        if (d < 0) {
            mca_errbuf_printf(err, errlen, "config '%s' for domain %u rejected: %s", config_path, domain_id,
                              dds_strretcode(d));
            return MCA_EIO; /* whatever Cyclone's code: the file or the network, not the caller's argument */
        }
        *domain = d;
    }
    const dds_entity_t p = dds_create_participant((dds_domainid_t)domain_id, NULL, NULL);
    if (p < 0) {
        mca_errbuf_printf(err, errlen, "cannot create participant on domain %u: %s", domain_id,
                          dds_strretcode(p));
        if (*domain > 0) {
            dds_delete(*domain);
            *domain = 0;
        }
        return MCA_EIO;
    }
    *participant = p;
    return MCA_OK;
}

static int create_in_partition(dds_entity_t pp, const char *partition, int publisher, dds_entity_t *out,
                               char *err, size_t errlen) {
    const char *what = publisher ? "publisher" : "subscriber";
    if (out == NULL) {
        return MCA_EINVAL;
    }
    dds_qos_t *q = NULL;
    if (partition != NULL) {
        q = dds_create_qos();
        if (q == NULL) {
            mca_errbuf_printf(err, errlen, "cannot create %s in partition '%s': out of memory", what,
                              partition);
            return MCA_ENOMEM;
        }
        dds_qset_partition1(q, partition);
    }
    const dds_entity_t e = publisher ? dds_create_publisher(pp, q, NULL) : dds_create_subscriber(pp, q, NULL);
    if (q != NULL) {
        dds_delete_qos(q);
    }
    if (e < 0) {
        mca_errbuf_printf(err, errlen, "cannot create %s in partition '%s': %s", what,
                          partition != NULL ? partition : "", dds_strretcode(e));
        return mca_dds_rc(e);
    }
    *out = e;
    return MCA_OK;
}

int mca_dds_create_publisher(dds_entity_t pp, const char *partition, dds_entity_t *out, char *err,
                             size_t errlen) {
    return create_in_partition(pp, partition, 1, out, err, errlen);
}

int mca_dds_create_subscriber(dds_entity_t pp, const char *partition, dds_entity_t *out, char *err,
                              size_t errlen) {
    return create_in_partition(pp, partition, 0, out, err, errlen);
}

/* ---- Cyclone's log messages, captured (mca_dds_log_capture) */

#define LOG_LINES 64
/* DDS Security's refusals are long (OpenSSL's error stack, then the reason at the end: "... Verify error:
 * self-signed certificate"); 200 cut the reason off */
#define LOG_LINE_MAX 400

static struct {
    pthread_mutex_t lock;
    int n;
    char line[LOG_LINES][LOG_LINE_MAX];
    uint64_t repeats[LOG_LINES]; /* the same message again right after: counted, not stored */
    _Atomic uint64_t lost;
} captured = {.lock = PTHREAD_MUTEX_INITIALIZER};

/* The stored line equals the first len characters of text, whose line breaks were stored as spaces. */
static int same_line(const char *line, const char *text, size_t len) {
    for (size_t i = 0; i < len; i++) {
        const char c = text[i] == '\n' || text[i] == '\r' ? ' ' : text[i];
        if (line[i] != c) {
            return 0;
        }
    }
    return line[len] == '\0';
}

static void capture_sink(void *arg, const dds_log_data_t *m) {
    (void)arg;
    if (pthread_mutex_trylock(&captured.lock) != 0) {
        atomic_fetch_add_explicit(&captured.lost, 1u, memory_order_relaxed);
        return;
    }
    const char *text = m->message;
    size_t len = strlen(text);
    while (len > 0 && (text[len - 1] == '\n' || text[len - 1] == '\r')) {
        len--;
    }
    if (len >= LOG_LINE_MAX) {
        len = LOG_LINE_MAX - 1;
    }
    if (captured.n > 0 && same_line(captured.line[captured.n - 1], text, len)) {
        captured.repeats[captured.n - 1]++; /* a flood of one warning (one per failed send) is one line */
    } else if (captured.n < LOG_LINES) {
        char *line = captured.line[captured.n];
        memcpy(line, text, len);
        line[len] = '\0';
        for (char *c = line; *c; c++) {
            if (*c == '\n' || *c == '\r') {
                *c = ' '; /* one message, one log line (the security plugins' messages carry newlines) */
            }
        }
        captured.repeats[captured.n] = 0;
        captured.n++;
    } else {
        atomic_fetch_add_explicit(&captured.lost, 1u, memory_order_relaxed);
    }
    pthread_mutex_unlock(&captured.lock);
}

void mca_dds_log_capture(int on) {
    dds_set_log_sink(on ? capture_sink : NULL, NULL);
}

int mca_dds_log_drain(int level, mca_dds_log_fn log, void *arg) {
    static char out[LOG_LINES][LOG_LINE_MAX]; /* one drainer (the daemon's supervisor) */
    static uint64_t reps[LOG_LINES];
    pthread_mutex_lock(&captured.lock);
    const int n = captured.n;
    memcpy(out, captured.line, (size_t)n * LOG_LINE_MAX);
    memcpy(reps, captured.repeats, (size_t)n * sizeof reps[0]);
    captured.n = 0;
    pthread_mutex_unlock(&captured.lock);
    const uint64_t lost = atomic_exchange_explicit(&captured.lost, 0u, memory_order_relaxed);
    char line[LOG_LINE_MAX + 64];
    for (int i = 0; i < n && log != NULL; i++) {
        if (reps[i] > 0) {
            snprintf(line, sizeof line, "%.*s (and %llu times more)", LOG_LINE_MAX - 1, out[i],
                     (unsigned long long)reps[i]);
            log(arg, level, line);
        } else {
            log(arg, level, out[i]);
        }
    }
    if (lost > 0 && log != NULL) {
        snprintf(line, sizeof line, "%llu more Cyclone DDS messages not shown", (unsigned long long)lost);
        log(arg, level, line);
    }
    return n;
}
