/* SPDX-License-Identifier: MIT */
/* mca-monitor: command-line DDS subscriber. One live line per pair of arms (minimum distance, margins
 * to d1 and d2, brake factor S(d), critical links, controller state, alarm word), optional CSV of every
 * Distances sample, and at exit the end-to-end latency (tick stamp -> receipt here, same host clock).
 * Samples are taken in a data-available listener, i.e. on Cyclone's receiving thread as they arrive (as
 * ddsperf's default subscriber does): a waitset would add the wake-up of a second thread to every
 * sample's latency.
 * The DDS participant lives in a child process (mca/dds_child.h) that hands each sample to this process over
 * a pipe: a peer that crashes libddsc 0.10.2 (docs/dds.md) kills the child, not the view or the CSV; the
 * child is restarted with mcad's capped back-off, the deaths and the gaps are said, and at exit counted.
 * This process keeps the view, the CSV and the figures; it creates no DDS entity.
 * Exit 0 on success or Ctrl-C, 1 on a run-time error, 2 on bad usage. */
#include <errno.h>
#include <getopt.h>
#include <math.h>
#include <pthread.h>
#include <sched.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "mca/dds_bridge.h" /* MCA_DDS_TOPIC_*, MCA_MAX_PAIRS */
#include "mca/dds_child.h"  /* the participant in a supervised child */
#include "mca/dds_qos.h"
#include "mca/err.h"
#include "mca/prog.h" /* mca_prog_parse_u64, mca_prog_on_stop_signals, mca_prog_ns_summary */
#include "mca_dds.h"  /* mca_dds_Distances, mca_dds_ControllerStatus */

static volatile sig_atomic_t g_stop;

static void on_signal(int sig) {
    (void)sig;
    g_stop = 1;
}

static const char *const state_names[] = {"INIT", "READY", "RUNNING", "BRAKING", "STOPPED", "FAULT"};

static const char *state_name(int s) {
    return (s >= 0 && s < (int)(sizeof state_names / sizeof state_names[0])) ? state_names[s] : "?";
}

typedef struct pair_view {
    int seen;
    mca_dds_Distances last; /* sequences not kept (loaned memory) */
} pair_view_t;

typedef struct status_view {
    uint64_t tick;
    int32_t state;
    int32_t fault_code;
    char fault_text[65];
    uint64_t dropped;
} status_view_t;

/* Statuses taken but not yet shown: a status is applied to the rows from its own tick on. Status and
 * distances are two topics with no order between them; a status taken together with a backlog of older
 * distance samples must not relabel those (seen: tick 2999 shown BRAKING, mcad braked from tick 3000). */
enum { PENDING_MAX = 32 };

/* The child's side: its readers, and one lock for its two senders (the listener, its main thread). */
typedef struct child {
    pthread_mutex_t lock;
    dds_entity_t rd, rs; /* Distances, ControllerStatus readers */
    dds_entity_t rp;     /* PairDistances reader (every kind of pair, named) */
    int fd;              /* the pipe to the parent */
    int broken;          /* the parent is gone */
    unsigned long long domain;
    const char *config, *partition;
    int keep_all; /* --csv: every sample (keep-all history) */
} child_t;

/* The frames the child sends. */
enum { FRAME_STATUS = 1, FRAME_DISTANCES = 2, FRAME_PAIRS = 3 };

/* One PairDistances sample, flattened (no pointers cross the pipe). */
typedef struct pairs_frame {
    uint64_t tick;
    uint32_t n;
    struct {
        int32_t kind;
        int16_t arm, link, other_arm, other_link, body;
        char name[MCA_DDS_NAME_MAX + 1];
        double distance, clearance;
    } e[MCA_DDS_MAX_PAIR_ENTRIES];
} pairs_frame_t;

typedef struct dist_frame {
    int64_t rx;          /* when the child took it (CLOCK_MONOTONIC, one clock for both processes) */
    mca_dds_Distances d; /* its sequences not sent (loaned memory) */
} dist_frame_t;

typedef struct monitor {
    int64_t last_rx; /* when distances last came */
    unsigned long long count;
    int done;        /* --count reached */
    int write_error; /* the CSV could not be written */
    int color, tty;
    int lines_drawn;
    pair_view_t pair[256];
    int have_pairs;
    pairs_frame_t pairs; /* the newest PairDistances */
    int have_status;
    int32_t state;
    int32_t fault_code;
    char fault_text[65];
    uint64_t dropped;
    status_view_t pending[PENDING_MAX];
    int n_pending;
    FILE *csv;
    uint64_t samples;
    int64_t *lat; /* latency samples [ns] */
    size_t n_lat, cap_lat;
} monitor_t;

static void apply_oldest_status(monitor_t *m) {
    const status_view_t *v = &m->pending[0];
    m->have_status = 1;
    m->state = v->state;
    m->fault_code = v->fault_code;
    m->dropped = v->dropped;
    memcpy(m->fault_text, v->fault_text, sizeof m->fault_text);
    memmove(&m->pending[0], &m->pending[1], (size_t)(m->n_pending - 1) * sizeof m->pending[0]);
    m->n_pending--;
}

/* Show every pending status up to tick `tick` (UINT64_MAX: all). */
static void apply_statuses(monitor_t *m, uint64_t tick) {
    while (m->n_pending > 0 && m->pending[0].tick <= tick) {
        apply_oldest_status(m);
    }
}

static void push_status(monitor_t *m, const status_view_t *s) {
    if (m->n_pending == PENDING_MAX) {
        apply_oldest_status(m);
    }
    m->pending[m->n_pending++] = *s;
}

static int64_t now_ns(void) {
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (int64_t)ts.tv_sec * 1000000000LL + ts.tv_nsec;
}

static void usage(FILE *f) {
    fprintf(
        f, "usage: mca-monitor [options]\n"
           "Live view of the mca distances and controller state published on DDS.\n"
           "  --domain N      DDS domain id (default 0)\n"
           "  --config FILE   Cyclone DDS XML (default: CYCLONEDDS_URI or built-in)\n"
           "  --partition P   subscribe in DDS partition P (default: the default partition)\n"
           "  --csv FILE      write every Distances sample to FILE (CSV, header line first)\n"
           "  --count N       exit after N Distances samples\n"
           "  --duration S    exit after S seconds\n"
           "  --priority N    run SCHED_FIFO N (1..98; 0, the default: SCHED_OTHER), Cyclone's threads too:\n"
           "                  samples are taken on its receive thread, which a real-time publisher on the\n"
           "                  same CPU (mcad's dds.priority) would otherwise hold off until it sleeps\n"
           "  --no-color      no ANSI colours (default when stdout is not a terminal)\n"
           "  --help\n"
           "Alarm word: OK above d2, WARN below d2, ALARM below d1. Ctrl-C exits cleanly.\n");
}

static const char *alarm_word(const mca_dds_Distances *d, const char **color) {
    if (d->min_distance < d->d1) {
        *color = "\033[1;31m";
        return "ALARM";
    }
    if (d->min_distance < d->d2) {
        *color = "\033[1;33m";
        return "WARN";
    }
    *color = "\033[32m";
    return "OK";
}

static void draw(monitor_t *m) {
    if (m->tty && m->lines_drawn > 0) {
        printf("\033[%dA", m->lines_drawn); /* back to the first line of the block */
    }
    int lines = 0;
    for (int k = 0; k < 256; ++k) {
        if (!m->pair[k].seen) {
            continue;
        }
        const mca_dds_Distances *d = &m->pair[k].last;
        const char *col = "";
        const char *word = alarm_word(d, &col);
        printf("%spair %d (arm %d-%d) d=%8.1f mm  d-d1=%8.1f mm  d-d2=%8.1f mm  S=%5.3f  links %d/%d  %-7s  "
               "%s%-5s%s",
               m->tty ? "\r\033[K" : "", k, d->arm_a, d->arm_b, d->min_distance * 1e3,
               (d->min_distance - d->d1) * 1e3, (d->min_distance - d->d2) * 1e3, d->brake_factor, d->link_a,
               d->link_b, m->have_status ? state_name(m->state) : "?", m->color ? col : "", word,
               m->color ? "\033[0m" : "");
        if (m->have_status && m->fault_code != 0) {
            printf("  fault %d %s", m->fault_code, m->fault_text);
        }
        printf("\n");
        lines++;
    }
    if (m->have_pairs) {
        /* per kind its least distance and pair, then each body with its closest link */
        const pairs_frame_t *pf = &m->pairs;
        printf("%sleast per kind:", m->tty ? "\r\033[K" : "");
        for (int kind = 0; kind < MCA_DDS_PAIR_KINDS; ++kind) {
            int best = -1;
            for (uint32_t i = 0; i < pf->n; ++i) {
                if (pf->e[i].kind == kind && (best < 0 || pf->e[i].distance < pf->e[best].distance)) {
                    best = (int)i;
                }
            }
            if (best < 0) {
                printf("  %s -", mca_dds_pair_kind_name(kind));
                continue;
            }
            const double d = pf->e[best].distance;
            if (kind == MCA_DDS_PAIR_ARM_ARM || kind == MCA_DDS_PAIR_SELF) {
                printf("  %s %.1f mm (arm %d link %d - arm %d link %d)", mca_dds_pair_kind_name(kind),
                       d * 1e3, pf->e[best].arm, pf->e[best].link, pf->e[best].other_arm,
                       pf->e[best].other_link);
            } else {
                printf("  %s %.1f mm ('%s')", mca_dds_pair_kind_name(kind), d * 1e3, pf->e[best].name);
            }
        }
        printf("\n");
        lines++;
        for (uint32_t i = 0; i < pf->n; ++i) {
            if (pf->e[i].kind != MCA_DDS_PAIR_ARM_BODY && pf->e[i].kind != MCA_DDS_PAIR_ARM_TRACK) {
                continue;
            }
            const double margin = pf->e[i].distance - pf->e[i].clearance;
            printf("%sbody %-16s %-9s d=%8.1f mm  d-clearance=%8.1f mm  closest: arm %d link %d%s\n",
                   m->tty ? "\r\033[K" : "", pf->e[i].name, mca_dds_pair_kind_name(pf->e[i].kind),
                   pf->e[i].distance * 1e3, margin * 1e3, pf->e[i].arm, pf->e[i].link,
                   margin < 0.0 ? "  INSIDE" : "");
            lines++;
        }
    }
    if (lines == 0) {
        printf("%swaiting for distances...\n", m->tty ? "\r\033[K" : "");
        lines = 1;
    }
    m->lines_drawn = lines;
    fflush(stdout);
}

static int csv_row(monitor_t *m, const mca_dds_Distances *d, int64_t rx) {
    if (m->csv == NULL) {
        return 0;
    }
    const int n =
        fprintf(m->csv,
                "%lld,%llu,%lld,%u,%u,%u,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%d,%d,%.17g,%.17g,%.17g,"
                "%.17g,%.17g,%.17g,%s\n",
                (long long)rx, (unsigned long long)d->tick, (long long)d->stamp_ns, d->pair_id, d->arm_a,
                d->arm_b, d->min_distance, d->min_distance - d->d1, d->min_distance - d->d2, d->d1, d->d2,
                d->brake_factor, d->link_a, d->link_b, d->p[0], d->p[1], d->p[2], d->e[0], d->e[1], d->e[2],
                m->have_status ? state_name(m->state) : "?");
    return n < 0 ? -1 : 0;
}

/* The child: take what arrived at rx and send it, statuses first (each applied from its own tick on), then
 * distances. Caller holds ch->lock. */
static void take_all(child_t *ch, int64_t rx) {
    enum { BATCH = 64 };
    void *buf[BATCH];
    dds_sample_info_t info[BATCH];
    memset(buf, 0, sizeof buf);
    int n = dds_take(ch->rs, buf, info, BATCH, BATCH);
    for (int i = 0; i < n; ++i) {
        if (info[i].valid_data && !ch->broken) {
            const mca_dds_ControllerStatus *s = buf[i];
            status_view_t v = {.tick = s->tick,
                               .state = s->state,
                               .fault_code = s->fault_code,
                               .dropped = s->snapshots_dropped};
            snprintf(v.fault_text, sizeof v.fault_text, "%s", s->fault_text);
            ch->broken = mca_dds_child_send(ch->fd, FRAME_STATUS, &v, sizeof v, NULL, 0) != 0;
        }
    }
    if (n > 0) {
        dds_return_loan(ch->rs, buf, n);
    }
    memset(buf, 0, sizeof buf);
    n = dds_take(ch->rd, buf, info, BATCH, BATCH);
    /* a sample that arrived while this callback waited for the lock came after rx: it was received by the
     * time of the take (never before its stamp; dds.monitor_csv saw "received before it was stamped") */
    const int64_t taken = n > 0 ? now_ns() : rx;
    for (int i = 0; i < n && !ch->broken; ++i) {
        if (!info[i].valid_data) {
            continue;
        }
        const mca_dds_Distances *d = buf[i];
        dist_frame_t f;
        memset(&f, 0, sizeof f);
        f.rx = d->stamp_ns > rx ? taken : rx;
        f.d = *d;
        f.d.link_distance_a._buffer = NULL; /* loaned memory: do not send pointers */
        f.d.link_distance_b._buffer = NULL;
        ch->broken = mca_dds_child_send(ch->fd, FRAME_DISTANCES, &f, sizeof f, NULL, 0) != 0;
    }
    if (n > 0) {
        dds_return_loan(ch->rd, buf, n);
    }
    memset(buf, 0, sizeof buf);
    n = dds_take(ch->rp, buf, info, BATCH, BATCH);
    for (int i = 0; i < n && !ch->broken; ++i) {
        if (!info[i].valid_data) {
            continue;
        }
        const mca_dds_PairDistances *pd = buf[i];
        pairs_frame_t f;
        memset(&f, 0, sizeof f);
        f.tick = pd->tick;
        f.n = pd->pairs._length < MCA_DDS_MAX_PAIR_ENTRIES ? pd->pairs._length : MCA_DDS_MAX_PAIR_ENTRIES;
        for (uint32_t k = 0; k < f.n; ++k) {
            const mca_dds_PairDistance *e = &pd->pairs._buffer[k];
            f.e[k].kind = e->kind;
            f.e[k].arm = e->arm;
            f.e[k].link = e->link;
            f.e[k].other_arm = e->other_arm;
            f.e[k].other_link = e->other_link;
            f.e[k].body = e->body;
            snprintf(f.e[k].name, sizeof f.e[k].name, "%s", e->name);
            f.e[k].distance = e->distance;
            f.e[k].clearance = e->clearance;
        }
        ch->broken = mca_dds_child_send(ch->fd, FRAME_PAIRS, &f, sizeof f, NULL, 0) != 0;
    }
    if (n > 0) {
        dds_return_loan(ch->rp, buf, n);
    }
}

static void on_data_available(dds_entity_t reader, void *arg) {
    (void)reader;
    child_t *ch = arg;
    const int64_t rx = now_ns(); /* before the lock: the receipt, not the wait for the other sender */
    pthread_mutex_lock(&ch->lock);
    if (ch->rd > 0 && ch->rs > 0 && ch->rp > 0) { /* every reader exists (the first may deliver before the
                                                    others are made) */
        take_all(ch, rx);
    }
    pthread_mutex_unlock(&ch->lock);
}

/* The child process: the participant, the readers, samples to the parent until it asks to stop. */
static int child_main(int fd, void *arg) {
    child_t *ch = arg;
    ch->fd = fd;
    pthread_mutex_init(&ch->lock, NULL);
    dds_entity_t dom = 0, pp = 0;
    char err[320] = "";
    if (mca_dds_open_participant((uint32_t)ch->domain, ch->config, &pp, &dom, err, sizeof err) != MCA_OK) {
        fprintf(stderr, "mca-monitor: %s\n", err);
        return 1;
    }
    dds_qos_t *qs = mca_dds_qos_stream();
    dds_qos_t *qst = mca_dds_qos_status();
    /* Reader history is not part of QoS matching: keep 1 s for the live view, and everything that
     * reached this process when recording (--csv records every sample even if we fall behind). */
    if (ch->keep_all) {
        dds_qset_history(qs, DDS_HISTORY_KEEP_ALL, 0);
    } else {
        dds_qset_history(qs, DDS_HISTORY_KEEP_LAST, 1024);
    }
    const dds_entity_t td = dds_create_topic(pp, &mca_dds_Distances_desc, MCA_DDS_TOPIC_DISTANCES, qs, NULL);
    const dds_entity_t ts =
        dds_create_topic(pp, &mca_dds_ControllerStatus_desc, MCA_DDS_TOPIC_STATUS, qst, NULL);
    /* the named pairs for the view only (the newest matters): keep-last, never kept whole for --csv */
    dds_qos_t *qp = mca_dds_qos_stream();
    dds_qset_history(qp, DDS_HISTORY_KEEP_LAST, 64);
    const dds_entity_t tp =
        dds_create_topic(pp, &mca_dds_PairDistances_desc, MCA_DDS_TOPIC_PAIR_DISTANCES, qp, NULL);
    dds_entity_t sub = DDS_RETCODE_ERROR; /* a DDS code: the reader creation below passes it on */
    if (mca_dds_create_subscriber(pp, ch->partition, &sub, err, sizeof err) != MCA_OK) {
        fprintf(stderr, "mca-monitor: %s\n", err);
    }
    dds_listener_t *lst = dds_create_listener(ch);
    dds_lset_data_available(lst, on_data_available);
    pthread_mutex_lock(&ch->lock);
    const dds_entity_t rd = td > 0 && sub > 0 ? dds_create_reader(sub, td, qs, lst) : (td > 0 ? sub : td);
    const dds_entity_t rs = ts > 0 && sub > 0 ? dds_create_reader(sub, ts, qst, lst) : (ts > 0 ? sub : ts);
    const dds_entity_t rp = tp > 0 && sub > 0 ? dds_create_reader(sub, tp, qp, lst) : (tp > 0 ? sub : tp);
    ch->rd = rd;
    ch->rs = rs;
    ch->rp = rp;
    pthread_mutex_unlock(&ch->lock);
    dds_delete_listener(lst);
    dds_delete_qos(qs);
    dds_delete_qos(qst);
    dds_delete_qos(qp);
    int rc = 0;
    if (rd < 0 || rs < 0 || rp < 0) {
        fprintf(stderr, "mca-monitor: cannot create readers: %s\n",
                dds_strretcode(rd < 0   ? rd
                               : rs < 0 ? rs
                                        : rp));
        rc = 1;
    } else {
        pthread_mutex_lock(&ch->lock);
        ch->broken = mca_dds_child_ready(fd) != 0;
        pthread_mutex_unlock(&ch->lock);
        while (!mca_dds_child_stopping() && !ch->broken) {
            const struct timespec tick = {0, 10000000}; /* 10 ms */
            nanosleep(&tick, NULL);
            pthread_mutex_lock(&ch->lock);
            take_all(ch, now_ns()); /* what came before the listeners were set (none after: they take it) */
            pthread_mutex_unlock(&ch->lock);
        }
        /* no listener runs after this (dds_set_listener waits for one that runs): then the rest is sent */
        dds_set_listener(rd, NULL);
        dds_set_listener(rs, NULL);
        dds_set_listener(rp, NULL);
        pthread_mutex_lock(&ch->lock);
        take_all(ch, now_ns());
        pthread_mutex_unlock(&ch->lock);
    }
    dds_delete(pp);
    if (dom > 0) {
        dds_delete(dom);
    }
    return rc;
}

/* The parent: one frame of the child. */
static int on_frame(void *ctx, uint32_t kind, const void *data, size_t len) {
    monitor_t *m = ctx;
    if (kind == FRAME_STATUS && len == sizeof(status_view_t)) {
        status_view_t v;
        memcpy(&v, data, sizeof v);
        push_status(m, &v);
    } else if (kind == FRAME_PAIRS && len == sizeof(pairs_frame_t)) {
        memcpy(&m->pairs, data, sizeof m->pairs);
        m->have_pairs = 1;
    } else if (kind == FRAME_DISTANCES && len == sizeof(dist_frame_t) && !m->done) {
        dist_frame_t f;
        memcpy(&f, data, sizeof f);
        const mca_dds_Distances *d = &f.d;
        apply_statuses(m, d->tick);
        pair_view_t *pv = &m->pair[d->pair_id];
        pv->seen = 1;
        pv->last = *d;
        if (csv_row(m, d, f.rx) != 0) {
            m->write_error = 1;
        }
        if (m->n_lat < m->cap_lat) {
            m->lat[m->n_lat++] = f.rx - d->stamp_ns;
        }
        m->samples++;
        m->last_rx = f.rx;
        if (m->count > 0 && m->samples >= m->count) {
            m->done = 1;
        }
    }
    return 0;
}

/* every integer option: 0..max, the error said */
static int parse_u64(const char *s, const char *name, unsigned long long max, unsigned long long *out) {
    return mca_prog_parse_u64("mca-monitor", name, s, max, out);
}

int main(int argc, char **argv) {
    unsigned long long domain = 0, count = 0, priority = 0;
    double duration = 0.0;
    const char *config = NULL, *csv_path = NULL, *partition = NULL;
    int no_color = 0;
    static const struct option opts[] = {
        {"domain", required_argument, NULL, 'd'},   {"config", required_argument, NULL, 'c'},
        {"csv", required_argument, NULL, 'o'},      {"count", required_argument, NULL, 'n'},
        {"duration", required_argument, NULL, 't'}, {"no-color", no_argument, NULL, 'C'},
        {"help", no_argument, NULL, 'h'},           {"partition", required_argument, NULL, 'P'},
        {"priority", required_argument, NULL, 'p'}, {NULL, 0, NULL, 0},
    };
    int c;
    while ((c = getopt_long(argc, argv, "", opts, NULL)) != -1) {
        switch (c) {
        case 'd':
            if (parse_u64(optarg, "--domain", MCA_DDS_MAX_DOMAIN, &domain) != 0) {
                return 2;
            }
            break;
        case 'c':
            config = optarg;
            break;
        case 'o':
            csv_path = optarg;
            break;
        case 'n':
            if (parse_u64(optarg, "--count", 1000000000ULL, &count) != 0) {
                return 2;
            }
            break;
        case 't': {
            char *end = NULL;
            duration = strtod(optarg, &end);
            if (end == optarg || *end != '\0' || !(duration > 0.0 && duration < 1e7)) {
                fprintf(stderr, "mca-monitor: --duration: '%s' is not a positive number of seconds\n",
                        optarg);
                return 2;
            }
            break;
        }
        case 'C':
            no_color = 1;
            break;
        case 'P':
            partition = optarg;
            break;
        case 'p':
            if (parse_u64(optarg, "--priority", 98, &priority) != 0) {
                return 2;
            }
            break;
        case 'h':
            usage(stdout);
            return 0;
        default:
            usage(stderr);
            return 2;
        }
    }
    if (mca_prog_no_operands("mca-monitor", argc, argv, optind, usage) != 0) {
        return 2;
    }

    /* before any DDS entity: the threads Cyclone creates inherit this thread's policy */
    if (priority > 0) {
        const struct sched_param sp = {.sched_priority = (int)priority};
        if (sched_setscheduler(0, SCHED_FIFO, &sp) != 0) {
            fprintf(stderr,
                    "mca-monitor: --priority %llu: cannot run SCHED_FIFO (%s): run as root or with "
                    "LimitRTPRIO / CAP_SYS_NICE\n",
                    priority, strerror(errno));
            return 1;
        }
    }

    static monitor_t m;
    m.count = count;
    m.tty = isatty(STDOUT_FILENO);
    m.color = m.tty && !no_color;
    if (csv_path != NULL) {
        m.csv = fopen(csv_path, "w");
        if (m.csv == NULL) {
            fprintf(stderr, "mca-monitor: cannot write CSV file '%s': %s\n", csv_path, strerror(errno));
            return 1;
        }
        fprintf(m.csv, "rx_ns,tick,stamp_ns,pair_id,arm_a,arm_b,min_distance,margin_d1,margin_d2,d1,d2,"
                       "brake_factor,link_a,link_b,px,py,pz,ex,ey,ez,state\n");
    }
    m.cap_lat = 1u << 20;
    m.lat = malloc(m.cap_lat * sizeof *m.lat);
    if (m.lat == NULL) {
        fprintf(stderr, "mca-monitor: out of memory\n");
        return 1;
    }

    mca_prog_on_stop_signals(on_signal);

    static child_t ch;
    ch.domain = domain;
    ch.config = config;
    ch.partition = partition;
    ch.keep_all = csv_path != NULL;
    static mca_dds_child_t kid;
    int rc = 0;
    if (mca_dds_child_start(&kid, "mca-monitor", child_main, &ch, stderr) != 0) {
        fprintf(stderr, "mca-monitor: cannot start its DDS process: %s\n", strerror(errno));
        rc = 1;
        goto out;
    }
    const int64_t t_start = now_ns();
    int64_t last_draw = 0;
    while (!g_stop) {
        /* 10 ms: --count and --duration end within it */
        const int prc = mca_dds_child_poll(&kid, 10, on_frame, &m);
        if (prc < 0) {
            rc = 1; /* its set-up failed (it said why) */
            break;
        }
        const int64_t now = now_ns();
        if (now - m.last_rx > 50000000LL) {
            apply_statuses(&m, UINT64_MAX); /* no distances for 50 ms: the newest status is current */
        }
        const int64_t redraw = m.tty ? 50000000LL : 1000000000LL; /* 20 Hz on a terminal, else 1 Hz */
        const int done = m.done;
        if (m.write_error) {
            fprintf(stderr, "mca-monitor: write error on '%s'\n", csv_path);
            rc = 1;
            g_stop = 1;
        }
        if (now - last_draw >= redraw || done) {
            draw(&m);
            last_draw = now;
        }
        if (done || (duration > 0.0 && (double)(now - t_start) * 1e-9 >= duration)) {
            break;
        }
    }
    /* the child takes and sends the rest, then exits */
    mca_dds_child_stop(&kid, on_frame, &m);
out:
    apply_statuses(&m, UINT64_MAX);
    if (m.csv != NULL && fclose(m.csv) != 0) {
        fprintf(stderr, "mca-monitor: write error on '%s'\n", csv_path);
        rc = 1;
    }
    fprintf(stderr, "mca-monitor: %llu distance samples", (unsigned long long)m.samples);
    if (m.n_lat > 0) {
        const mca_prog_ns_summary_t l = mca_prog_ns_summary(m.lat, m.n_lat);
        fprintf(stderr, "; latency stamp->receipt p50 %.1f us p99 %.1f us max %.1f us (n=%zu)", l.p50, l.p99,
                l.max, m.n_lat);
    }
    if (m.have_status) {
        fprintf(stderr, "; controller %s, bridge dropped %llu", state_name(m.state),
                (unsigned long long)m.dropped);
    }
    fprintf(stderr, "\n");
    if (kid.deaths > 0) {
        char line[256];
        mca_dds_child_describe(&kid, line, sizeof line);
        fprintf(stderr, "mca-monitor: %s\n", line);
    }
    mca_dds_child_free(&kid);
    free(m.lat);
    return rc;
}
