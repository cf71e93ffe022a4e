/* SPDX-License-Identifier: MIT */
/* mca-record: records a cell's DDS topics into an MCAP file that ROS 2 tools open (ros2 bag with the mcap
 * storage, Foxglove, PlotJuggler, rosbags): profile "ros2", one channel per topic with message encoding
 * "cdr", one schema per type with encoding "ros2msg" and the full message definition (msgdefs.h).
 *
 * How it reads: the DCPSPublication built-in topic names every writer on the domain with its topic, type
 * and QoS; for each writer whose type mca-record knows (every type mcad publishes, ROS 2 and mca/) and
 * whose topic is selected, it creates a reader of that topic with idlc's descriptor of that type (the same
 * type identifiers as mcad's writer: no type lookup), keep-all history, and the writer's reliability,
 * durability and partition (a transient-local topic such as /tf_static delivers what was written before
 * the reader came). Samples are taken serialized (dds_takecdr) and written unchanged: the CDR bytes with
 * their 4-byte encapsulation header as the writer sent them, nothing decoded or encoded again. log_time is
 * when mca-record took the sample (CLOCK_REALTIME), publish_time the writer's source timestamp.
 *
 * The DDS participant lives in a child process (mca/dds_child.h) that sends each topic it subscribes and
 * each sample to this process over a pipe; this process alone writes the file. A peer that crashes libddsc
 * 0.10.2 (docs/dds.md) kills the child, not the recording: the file stays one valid MCAP, the child is
 * restarted with mcad's capped back-off, and the gaps (no participant from a death to the next child up)
 * are said on stderr and written into the file as the metadata record "mca-record". A latched
 * (transient-local) sample a restarted child receives again, byte for byte the last one recorded on its
 * topic, is not recorded twice.
 *
 * Exit 0 after --duration or SIGINT/SIGTERM (the file is closed with its summary and index either way),
 * 1 on a run-time error, 2 on bad usage. */
#include <errno.h>
#include <fnmatch.h>
#include <getopt.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include <dds/dds.h>

#include "mca/cell.h"      /* mca_cell_load: --cell */
#include "mca/dds_child.h" /* the participant in a supervised child */
#include "mca/dds_qos.h"   /* mca_dds_open_participant, MCA_DDS_MAX_DOMAIN */
#include "mca/err.h"
#include "mca/prog.h" /* mca_prog_parse_u64, mca_prog_on_stop_signals, mca_prog_no_operands */
#include "mcap_writer.h"
#include "msgdefs.h"

#define PROG "mca-record"

enum { MAX_TOPICS = 256, MAX_PATTERNS = 64, BATCH = 64 };

/* A serialized sample as dds_takecdr returns it. <dds/ddsi/ddsi_serdata.h> defines these inline (libddsc
 * exports them too), but its atomics need GNU C's asm, which this C11 build does not allow: the exported
 * functions, declared as libddsc 0.10 defines them. */
uint32_t ddsi_serdata_size(const struct ddsi_serdata *d);
void ddsi_serdata_to_ser(const struct ddsi_serdata *d, size_t off, size_t sz, void *buf);
void ddsi_serdata_unref(struct ddsi_serdata *serdata);

static volatile sig_atomic_t g_stop;

static void on_signal(int sig) {
    (void)sig;
    g_stop = 1;
}

/* The child's side: its participant, a reader per recorded topic, the pipe to the parent. */
typedef struct topic {
    char dds_name[256]; /* "rt/cell/left/joint_states" */
    const rec_type_t *type;
    dds_entity_t reader;
} topic_t;

typedef struct recorder {
    unsigned long long domain;
    const char *config;
    dds_entity_t pp;
    int fd;     /* the pipe to the parent */
    int broken; /* the parent is gone */
    const char *patterns[MAX_PATTERNS];
    int n_patterns;
    topic_t topic[MAX_TOPICS];
    int n_topics;
    char skipped[MAX_TOPICS][256]; /* topics seen that are not recorded (said once) */
    int n_skipped;
    unsigned char *scratch;
    size_t scratch_cap;
} recorder_t;

/* The frames the child sends: a topic it subscribed (then its channel's metadata, rosbag2's QoS YAML), a
 * sample (then its CDR). */
enum { FRAME_TOPIC = 1, FRAME_SAMPLE = 2 };

typedef struct topic_frame {
    uint16_t local; /* the child's number of the topic */
    uint16_t type;  /* index in rec_types */
    uint8_t transient_local;
    char dds_name[256];
} topic_frame_t;

typedef struct sample_frame {
    uint64_t log_time, publish_time;
    uint16_t local;
} sample_frame_t;

/* The parent's side: the file and its channels, for as long as it runs (children come and go). */
typedef struct channel {
    char dds_name[256];
    char name[256]; /* as recorded: "/cell/left/joint_states" (ROS 2 name), or the DDS name */
    const rec_type_t *type;
    uint16_t channel;
    uint32_t seq;
    int transient_local;
    unsigned char *last; /* a latched topic's last sample: a restarted child receives it again */
    size_t last_len;
    uint64_t child; /* the child (its start number) that sent the last sample */
} channel_t;

typedef struct sink {
    mcap_writer_t *w;
    channel_t ch[MAX_TOPICS];
    int n_ch;
    int16_t map[MAX_TOPICS]; /* the current child's topic number -> ch, set by its topic frames */
    uint16_t schema[32];     /* schema id per known type (index in rec_types), 0: not written yet */
    uint64_t repeats;        /* latched samples received again and not recorded twice */
    int quiet;
    const mca_dds_child_t *kid; /* its start count tells a restarted child's samples */
} sink_t;

static int64_t now_ns(clockid_t clk) {
    struct timespec ts;
    clock_gettime(clk, &ts);
    return (int64_t)ts.tv_sec * 1000000000LL + ts.tv_nsec;
}

static void usage(FILE *f) {
    fprintf(
        f,
        "usage: mca-record --output FILE.mcap [options]\n"
        "Records mcad's DDS topics (ROS 2 and mca/) into an MCAP file for ROS 2 tools (ros2 bag, Foxglove,\n"
        "PlotJuggler, rosbags): CDR messages as received, ros2msg schemas with the full definitions.\n"
        "  --output FILE    the MCAP file to write (required)\n"
        "  --cell FILE      a cell: its dds.domain and dds.config, and (without --topic) only its topics:\n"
        "                   /<ns>/*, /tf_static, /diagnostics and mca/*\n"
        "  --domain N       DDS domain id (default 0; after --cell: overrides the cell's)\n"
        "  --config FILE    Cyclone DDS XML (default: CYCLONEDDS_URI or built-in; after --cell: overrides)\n"
        "  --topic PATTERN  record only topics matching PATTERN (shell pattern on the ROS 2 name, e.g.\n"
        "                   '/cell/*/joint_states', or on the DDS name of mca/ topics); repeatable\n"
        "  --duration S     stop after S seconds (default: at SIGINT or SIGTERM)\n"
        "  --progress S     a progress line on stderr every S seconds (default 5; 0: none)\n"
        "  --quiet          no line per new topic\n"
        "  --help\n"
        "Every topic of a type it knows is recorded from its first sample received on; a topic of another\n"
        "type is named once and skipped. The file is complete (summary, index) after --duration, SIGINT or\n"
        "SIGTERM.\n");
}

/* "rt/a/b" -> "/a/b" (ROS 2's naming of topics on DDS); any other name as it is */
static void recorded_name(const char *dds_name, char *out, size_t len) {
    if (strncmp(dds_name, "rt/", 3) == 0) {
        snprintf(out, len, "%s", dds_name + 2);
    } else {
        snprintf(out, len, "%s", dds_name);
    }
}

static int selected(const recorder_t *r, const char *name) {
    if (r->n_patterns == 0) {
        return 1;
    }
    for (int i = 0; i < r->n_patterns; ++i) {
        if (fnmatch(r->patterns[i], name, 0) == 0) {
            return 1;
        }
    }
    return 0;
}

static void skip_once(recorder_t *r, const char *name, const char *why) {
    for (int i = 0; i < r->n_skipped; ++i) {
        if (strcmp(r->skipped[i], name) == 0) {
            return;
        }
    }
    if (r->n_skipped < MAX_TOPICS) {
        snprintf(r->skipped[r->n_skipped++], sizeof r->skipped[0], "%s", name);
    }
    fprintf(stderr, PROG ": %s: not recorded (%s)\n", name, why);
}

/* ROS 2's offered_qos_profiles (rosbag2's metadata, Jazzy's spelling): `ros2 bag play` offers the same
 * durability again (the latched topics stay latched). */
static void qos_yaml(const dds_qos_t *q, char *out, size_t len) {
    dds_history_kind_t hk = DDS_HISTORY_KEEP_LAST;
    int32_t depth = 1;
    dds_reliability_kind_t rk = DDS_RELIABILITY_BEST_EFFORT;
    dds_duration_t blk = 0;
    dds_durability_kind_t dk = DDS_DURABILITY_VOLATILE;
    (void)dds_qget_history(q, &hk, &depth);
    (void)dds_qget_reliability(q, &rk, &blk);
    (void)dds_qget_durability(q, &dk);
    static const char never[] = "    sec: 9223372036\n    nsec: 854775807\n";
    snprintf(out, len,
             "- history: %s\n  depth: %d\n  reliability: %s\n  durability: %s\n  deadline:\n%s  lifespan:\n%s"
             "  liveliness: automatic\n  liveliness_lease_duration:\n%s"
             "  avoid_ros_namespace_conventions: false\n",
             hk == DDS_HISTORY_KEEP_ALL ? "keep_all" : "keep_last", hk == DDS_HISTORY_KEEP_ALL ? 0 : depth,
             rk == DDS_RELIABILITY_RELIABLE ? "reliable" : "best_effort",
             dk == DDS_DURABILITY_VOLATILE ? "volatile" : "transient_local", never, never, never);
}

/* The schema of type t, written on first use; 0 on error. */
static uint16_t schema_of(sink_t *r, const rec_type_t *t) {
    size_t n = 0;
    const rec_type_t *all = rec_types(&n);
    const size_t k = (size_t)(t - all);
    if (k >= sizeof r->schema / sizeof r->schema[0]) {
        return 0;
    }
    if (r->schema[k] == 0) {
        char *def = rec_msgdef_full(t->ros_name);
        if (def == NULL) {
            return 0;
        }
        r->schema[k] = mcap_writer_schema(r->w, t->ros_name, "ros2msg", def, strlen(def));
        free(def);
    }
    return r->schema[k];
}

/* In the child: a writer was discovered: a reader for its topic if it is new, known and selected, and the
 * topic to the parent. */
static int add_topic(recorder_t *r, const dds_builtintopic_endpoint_t *ep) {
    char name[256];
    recorded_name(ep->topic_name, name, sizeof name);
    for (int i = 0; i < r->n_topics; ++i) {
        if (strcmp(r->topic[i].dds_name, ep->topic_name) == 0) {
            if (strcmp(r->topic[i].type->desc->m_typename, ep->type_name) != 0) {
                skip_once(r, name, "a second writer of another type");
            }
            return 0;
        }
    }
    if (!selected(r, name)) {
        return 0;
    }
    const rec_type_t *t = rec_type_find(ep->type_name);
    if (t == NULL) {
        char why[320];
        snprintf(why, sizeof why, "type %s unknown to mca-record", ep->type_name);
        skip_once(r, name, why);
        return 0;
    }
    if (r->n_topics == MAX_TOPICS) {
        skip_once(r, name, "too many topics");
        return 0;
    }
    topic_t *tp = &r->topic[r->n_topics];
    memset(tp, 0, sizeof *tp);
    snprintf(tp->dds_name, sizeof tp->dds_name, "%s", ep->topic_name);
    tp->type = t;

    /* the writer's reliability, durability and partition; everything it sends kept until taken */
    dds_qos_t *q = dds_create_qos();
    dds_reliability_kind_t rk = DDS_RELIABILITY_RELIABLE;
    dds_duration_t blk = 0;
    dds_durability_kind_t dk = DDS_DURABILITY_VOLATILE;
    if (ep->qos != NULL) {
        (void)dds_qget_reliability(ep->qos, &rk, &blk);
        (void)dds_qget_durability(ep->qos, &dk);
        uint32_t np = 0;
        char **parts = NULL;
        if (dds_qget_partition(ep->qos, &np, &parts) && np > 0) {
            dds_qset_partition(q, np, (const char **)parts);
        }
        for (uint32_t i = 0; i < np; ++i) {
            dds_free(parts[i]);
        }
        dds_free(parts);
    }
    dds_qset_reliability(q, rk, DDS_MSECS(100));
    dds_qset_durability(q, dk == DDS_DURABILITY_VOLATILE ? DDS_DURABILITY_VOLATILE
                                                         : DDS_DURABILITY_TRANSIENT_LOCAL);
    dds_qset_history(q, DDS_HISTORY_KEEP_ALL, 0);
    char yaml[1024];
    qos_yaml(ep->qos != NULL ? ep->qos : q, yaml, sizeof yaml);
    const dds_entity_t topic = dds_create_topic(r->pp, t->desc, ep->topic_name, NULL, NULL);
    tp->reader = topic > 0 ? dds_create_reader(r->pp, topic, q, NULL) : topic;
    dds_delete_qos(q);
    if (tp->reader < 0) {
        fprintf(stderr, PROG ": %s: cannot subscribe: %s\n", name, dds_strretcode(tp->reader));
        skip_once(r, name, "no reader");
        return 0;
    }
    size_t n_types = 0;
    topic_frame_t f;
    memset(&f, 0, sizeof f);
    f.local = (uint16_t)r->n_topics;
    f.type = (uint16_t)(t - rec_types(&n_types));
    f.transient_local = dk != DDS_DURABILITY_VOLATILE;
    snprintf(f.dds_name, sizeof f.dds_name, "%s", ep->topic_name);
    r->n_topics++;
    return mca_dds_child_send(r->fd, FRAME_TOPIC, &f, sizeof f, yaml, strlen(yaml));
}

static int discover(recorder_t *r, dds_entity_t pubs) {
    void *buf[BATCH];
    dds_sample_info_t info[BATCH];
    int rc = 0;
    for (;;) {
        memset(buf, 0, sizeof buf);
        const int n = dds_take(pubs, buf, info, BATCH, BATCH);
        if (n <= 0) {
            break;
        }
        for (int i = 0; i < n && rc == 0; ++i) {
            if (info[i].valid_data && info[i].instance_state == DDS_IST_ALIVE) {
                rc = add_topic(r, buf[i]);
            }
        }
        dds_return_loan(pubs, buf, n);
        if (rc != 0 || n < BATCH) {
            break;
        }
    }
    return rc;
}

/* In the child: everything each reader holds, to the parent. */
static int drain(recorder_t *r) {
    struct ddsi_serdata *sd[BATCH];
    dds_sample_info_t info[BATCH];
    int rc = 0;
    for (int k = 0; k < r->n_topics; ++k) {
        topic_t *tp = &r->topic[k];
        for (;;) {
            const int n = dds_takecdr(tp->reader, sd, BATCH, info, DDS_ANY_STATE);
            if (n <= 0) {
                break;
            }
            const uint64_t log_time = (uint64_t)now_ns(CLOCK_REALTIME);
            for (int i = 0; i < n; ++i) {
                if (info[i].valid_data && rc == 0) {
                    const size_t size = ddsi_serdata_size(sd[i]);
                    if (size > r->scratch_cap) {
                        unsigned char *p = realloc(r->scratch, size);
                        if (p == NULL) {
                            rc = -1;
                        } else {
                            r->scratch = p;
                            r->scratch_cap = size;
                        }
                    }
                    if (rc == 0) {
                        ddsi_serdata_to_ser(sd[i], 0, size, r->scratch);
                        sample_frame_t f;
                        memset(&f, 0, sizeof f);
                        f.local = (uint16_t)k;
                        f.log_time = log_time;
                        f.publish_time =
                            info[i].source_timestamp > 0 ? (uint64_t)info[i].source_timestamp : log_time;
                        rc = mca_dds_child_send(r->fd, FRAME_SAMPLE, &f, sizeof f, r->scratch, size);
                    }
                }
                ddsi_serdata_unref(sd[i]);
            }
            if (n < BATCH) {
                break;
            }
        }
    }
    return rc;
}

/* The child process: the participant, discovery, the samples to the parent until it asks to stop. */
static int child_main(int fd, void *arg) {
    recorder_t *r = arg;
    r->fd = fd;
    char err[320] = "";
    dds_entity_t dom = 0;
    if (mca_dds_open_participant((uint32_t)r->domain, r->config, &r->pp, &dom, err, sizeof err) != MCA_OK) {
        fprintf(stderr, PROG ": %s\n", err);
        return 1;
    }
    int rc = 0;
    const dds_entity_t pubs = dds_create_reader(r->pp, DDS_BUILTIN_TOPIC_DCPSPUBLICATION, NULL, NULL);
    if (pubs < 0) {
        fprintf(stderr, PROG ": cannot read the discovered writers: %s\n", dds_strretcode(pubs));
        rc = 1;
    } else if (mca_dds_child_ready(fd) != 0) {
        rc = 1;
    }
    while (rc == 0 && !mca_dds_child_stopping()) {
        const struct timespec tick = {0, 10000000}; /* 10 ms */
        nanosleep(&tick, NULL);
        if (discover(r, pubs) != 0 || drain(r) != 0) {
            rc = 1; /* the parent is gone */
        }
    }
    if (rc == 0) {
        rc = drain(r) != 0; /* what arrived since the last round */
    }
    free(r->scratch);
    dds_delete(r->pp);
    if (dom > 0) {
        dds_delete(dom);
    }
    return rc;
}

/* In the parent: one frame of the child, into the file. */
static int on_frame(void *ctx, uint32_t kind, const void *data, size_t len) {
    sink_t *s = ctx;
    if (kind == FRAME_TOPIC && len >= sizeof(topic_frame_t)) {
        topic_frame_t f;
        memcpy(&f, data, sizeof f);
        f.dds_name[sizeof f.dds_name - 1] = '\0';
        size_t n_types = 0;
        const rec_type_t *all = rec_types(&n_types);
        if (f.local >= MAX_TOPICS) {
            return 0;
        }
        s->map[f.local] = -1; /* until it has its channel */
        if (f.type >= n_types) {
            return 0;
        }
        int k = 0;
        while (k < s->n_ch && strcmp(s->ch[k].dds_name, f.dds_name) != 0) {
            k++;
        }
        if (k == s->n_ch) { /* first seen: its channel (a restarted child's topics have theirs) */
            if (s->n_ch == MAX_TOPICS) {
                return 0;
            }
            channel_t *c = &s->ch[k];
            memset(c, 0, sizeof *c);
            snprintf(c->dds_name, sizeof c->dds_name, "%s", f.dds_name);
            recorded_name(f.dds_name, c->name, sizeof c->name);
            c->type = &all[f.type];
            c->transient_local = f.transient_local;
            char yaml[1024];
            const size_t ny = len - sizeof f < sizeof yaml - 1 ? len - sizeof f : sizeof yaml - 1;
            memcpy(yaml, (const unsigned char *)data + sizeof f, ny);
            yaml[ny] = '\0';
            const char *keys[] = {"offered_qos_profiles"};
            const char *vals[] = {yaml};
            const uint16_t sid = schema_of(s, c->type);
            c->channel = sid != 0 ? mcap_writer_channel(s->w, sid, c->name, "cdr", 1, keys, vals) : 0;
            if (c->channel == 0) {
                fprintf(stderr, PROG ": %s: cannot write its channel: %s\n", c->name, strerror(errno));
                return -1;
            }
            s->n_ch++;
            if (!s->quiet) {
                fprintf(stderr, PROG ": recording %s (%s)\n", c->name, c->type->ros_name);
            }
        }
        s->map[f.local] = (int16_t)k;
    } else if (kind == FRAME_SAMPLE && len >= sizeof(sample_frame_t)) {
        sample_frame_t f;
        memcpy(&f, data, sizeof f);
        if (f.local >= MAX_TOPICS || s->map[f.local] < 0) {
            return 0;
        }
        channel_t *c = &s->ch[s->map[f.local]];
        const unsigned char *cdr = (const unsigned char *)data + sizeof f;
        const size_t size = len - sizeof f;
        if (c->transient_local) {
            /* the first sample a restarted child got of a latched topic: the writer's history again, not
             * recorded twice if it is the sample recorded last (a writer may well send one value twice) */
            const int first_of_child = c->child != s->kid->starts;
            c->child = s->kid->starts;
            if (first_of_child && c->last != NULL && c->last_len == size && memcmp(c->last, cdr, size) == 0) {
                s->repeats++;
                return 0;
            }
            unsigned char *p = realloc(c->last, size > 0 ? size : 1);
            if (p != NULL) {
                memcpy(p, cdr, size);
                c->last = p;
                c->last_len = size;
            }
        }
        return mcap_writer_message(s->w, c->channel, ++c->seq, f.log_time, f.publish_time, cdr, size);
    }
    return 0;
}

static void progress(const sink_t *s, const mca_dds_child_t *kid, double elapsed, int final) {
    char line[4096];
    int at = snprintf(line, sizeof line, PROG ": %s%.1f s, %llu messages, %.2f MB", final ? "recorded " : "",
                      elapsed, (unsigned long long)mcap_writer_messages(s->w),
                      (double)mcap_writer_bytes(s->w) / 1e6);
    if (kid->deaths > 0 && at > 0 && (size_t)at < sizeof line) {
        at +=
            snprintf(line + at, sizeof line - (size_t)at, " (DDS child died %llu times, %u gaps %.2f s)",
                     (unsigned long long)kid->deaths, kid->n_gaps + (unsigned)kid->in_gap, kid->gap_total_s);
    }
    for (int k = 0; k < s->n_ch && at > 0 && (size_t)at < sizeof line; ++k) {
        at += snprintf(line + at, sizeof line - (size_t)at, "%s %s %u", k == 0 ? ":" : ",", s->ch[k].name,
                       s->ch[k].seq);
    }
    fprintf(stderr, "%s\n", line);
}

/* The gaps into the file (metadata "mca-record": times as log_time, CLOCK_REALTIME ns) and on stderr. */
static int write_gaps(sink_t *s, const mca_dds_child_t *kid, int64_t mono_to_real_ns, int64_t t0_mono) {
    enum { KEYS = 4 + MCA_DDS_CHILD_GAPS };
    static char kbuf[KEYS][32], vbuf[KEYS][96];
    const char *keys[KEYS], *vals[KEYS];
    size_t n = 0;
    snprintf(kbuf[n], sizeof kbuf[n], "dds_child_deaths");
    snprintf(vbuf[n++], sizeof vbuf[0], "%llu", (unsigned long long)kid->deaths);
    snprintf(kbuf[n], sizeof kbuf[n], "gaps");
    snprintf(vbuf[n++], sizeof vbuf[0], "%u", kid->n_gaps);
    snprintf(kbuf[n], sizeof kbuf[n], "gap_seconds");
    snprintf(vbuf[n++], sizeof vbuf[0], "%.6f", kid->gap_total_s);
    snprintf(kbuf[n], sizeof kbuf[n], "latched_repeats_skipped");
    snprintf(vbuf[n++], sizeof vbuf[0], "%llu", (unsigned long long)s->repeats);
    for (uint32_t g = 0; g < kid->n_gaps && g < MCA_DDS_CHILD_GAPS; ++g) {
        const mca_dds_child_gap_t *x = &kid->gaps[g];
        const int64_t from = (int64_t)(x->from_s * 1e9) + mono_to_real_ns;
        const int64_t to = (int64_t)(x->to_s * 1e9) + mono_to_real_ns;
        snprintf(kbuf[n], sizeof kbuf[n], "gap_%u", g + 1);
        /* from and to (log_time ns), deaths in it */
        snprintf(vbuf[n++], sizeof vbuf[0], "%lld %lld %u", (long long)from, (long long)to, x->deaths);
        fprintf(stderr,
                PROG ": gap %u: no DDS participant from %.2f s to %.2f s of the recording (%.2f s, %u "
                     "death(s))\n",
                g + 1, x->from_s - (double)t0_mono * 1e-9, x->to_s - (double)t0_mono * 1e-9,
                x->to_s - x->from_s, x->deaths);
    }
    for (size_t i = 0; i < n; ++i) {
        keys[i] = kbuf[i];
        vals[i] = vbuf[i];
    }
    return mcap_writer_metadata(s->w, "mca-record", n, keys, vals);
}

static int parse_seconds(const char *s, const char *opt, double min, double *out) {
    char *end = NULL;
    const double v = strtod(s, &end);
    if (end == s || *end != '\0' || !(v >= min && v < 1e7)) {
        fprintf(stderr, PROG ": %s: '%s' is not a number of seconds%s\n", opt, s, min > 0 ? " > 0" : "");
        return -1;
    }
    *out = v;
    return 0;
}

int main(int argc, char **argv) {
    static recorder_t r;
    static sink_t sink;
    static mca_cell_t cell;
    unsigned long long domain = 0;
    int have_domain = 0;
    double duration = 0.0, every = 5.0;
    const char *config = NULL, *out = NULL, *cell_path = NULL;
    static char ns_pattern[64];
    static const struct option opts[] = {
        {"output", required_argument, NULL, 'o'},   {"cell", required_argument, NULL, 'C'},
        {"domain", required_argument, NULL, 'd'},   {"config", required_argument, NULL, 'c'},
        {"topic", required_argument, NULL, 't'},    {"duration", required_argument, NULL, 'D'},
        {"progress", required_argument, NULL, 'p'}, {"quiet", no_argument, NULL, 'q'},
        {"help", no_argument, NULL, 'h'},           {NULL, 0, NULL, 0},
    };
    int c;
    while ((c = getopt_long(argc, argv, "o:", opts, NULL)) != -1) {
        switch (c) {
        case 'o':
            out = optarg;
            break;
        case 'C':
            cell_path = optarg;
            break;
        case 'd':
            if (mca_prog_parse_u64(PROG, "--domain", optarg, MCA_DDS_MAX_DOMAIN, &domain) != 0) {
                return 2;
            }
            have_domain = 1;
            break;
        case 'c':
            config = optarg;
            break;
        case 't':
            if (r.n_patterns == MAX_PATTERNS) {
                fprintf(stderr, PROG ": at most %d --topic\n", MAX_PATTERNS);
                return 2;
            }
            r.patterns[r.n_patterns++] = optarg;
            break;
        case 'D':
            if (parse_seconds(optarg, "--duration", 1e-3, &duration) != 0) {
                return 2;
            }
            break;
        case 'p':
            if (parse_seconds(optarg, "--progress", 0.0, &every) != 0) {
                return 2;
            }
            break;
        case 'q':
            sink.quiet = 1;
            break;
        case 'h':
            usage(stdout);
            return 0;
        default:
            usage(stderr);
            return 2;
        }
    }
    if (mca_prog_no_operands(PROG, argc, argv, optind, usage) != 0) {
        return 2;
    }
    if (out == NULL) {
        fprintf(stderr, PROG ": --output FILE is required\n");
        usage(stderr);
        return 2;
    }
    if (cell_path != NULL) {
        char err[1024];
        const int rc = mca_cell_load(cell_path, &cell, err, sizeof err);
        if (rc != MCA_OK) {
            fprintf(stderr, PROG ": %s\n", err);
            return rc == MCA_ENOENT ? 1 : 2;
        }
        if (!cell.dds.enabled) {
            fprintf(stderr, PROG ": %s: dds.enabled is false: the cell publishes nothing\n", cell_path);
            return 2;
        }
        if (!have_domain) {
            domain = cell.dds.domain;
        }
        if (config == NULL && cell.dds.config[0] != '\0') {
            config = cell.dds.config;
        }
        if (r.n_patterns == 0) {
            snprintf(ns_pattern, sizeof ns_pattern, "/%s/*", cell.dds.ros2.ns);
            r.patterns[r.n_patterns++] = ns_pattern;
            r.patterns[r.n_patterns++] = "/tf_static";
            r.patterns[r.n_patterns++] = "/diagnostics";
            r.patterns[r.n_patterns++] = "mca/*";
        }
    }
    mca_prog_on_stop_signals(on_signal);
    r.domain = domain;
    r.config = config;
    for (int k = 0; k < MAX_TOPICS; ++k) {
        sink.map[k] = -1;
    }
    int rc = 0;
    sink.w = mcap_writer_open(out, "ros2", "mca-record", 1u << 20);
    if (sink.w == NULL) {
        fprintf(stderr, PROG ": cannot write '%s': %s\n", out, strerror(errno));
        return 1;
    }
    static mca_dds_child_t kid;
    sink.kid = &kid;
    if (mca_dds_child_start(&kid, PROG, child_main, &r, stderr) != 0) {
        fprintf(stderr, PROG ": cannot start its DDS process: %s\n", strerror(errno));
        rc = 1;
    }
    const int64_t t0 = now_ns(CLOCK_MONOTONIC);
    const int64_t mono_to_real = now_ns(CLOCK_REALTIME) - t0;
    int64_t next_progress = t0 + (int64_t)(every * 1e9);
    while (rc == 0 && !g_stop) {
        const int prc = mca_dds_child_poll(&kid, 10, on_frame, &sink);
        if (prc != 0) {
            if (prc > 0) {
                fprintf(stderr, PROG ": write error on '%s': %s\n", out, strerror(errno));
            }
            rc = 1; /* a write error, or the child's set-up failed (it said why) */
            break;
        }
        const int64_t now = now_ns(CLOCK_MONOTONIC);
        if (every > 0.0 && now >= next_progress) {
            progress(&sink, &kid, (double)(now - t0) * 1e-9, 0);
            next_progress += (int64_t)(every * 1e9);
            if (mcap_writer_flush(sink.w) != 0) { /* what was recorded survives a crash of this process */
                fprintf(stderr, PROG ": write error on '%s': %s\n", out, strerror(errno));
                rc = 1;
            }
        }
        if (duration > 0.0 && (double)(now - t0) * 1e-9 >= duration) {
            break;
        }
    }
    mca_dds_child_stop(&kid, on_frame, &sink); /* it takes what arrived and sends it */
    const double elapsed = (double)(now_ns(CLOCK_MONOTONIC) - t0) * 1e-9;
    progress(&sink, &kid, elapsed, 1);
    if (kid.deaths > 0 || sink.repeats > 0) {
        char line[256];
        mca_dds_child_describe(&kid, line, sizeof line);
        fprintf(stderr, PROG ": %s; %llu latched samples received again, not recorded twice\n", line,
                (unsigned long long)sink.repeats);
    }
    if (write_gaps(&sink, &kid, mono_to_real, t0) != 0 || mcap_writer_close(sink.w) != 0) {
        fprintf(stderr, PROG ": write error on '%s': %s\n", out, strerror(errno));
        rc = 1;
    }
    for (int k = 0; k < sink.n_ch; ++k) {
        free(sink.ch[k].last);
    }
    mca_dds_child_free(&kid);
    return rc;
}
