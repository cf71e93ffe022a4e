/* SPDX-License-Identifier: MIT */
/* DDS bridge, in one process: argument and config errors, every pushed snapshot arrives intact on a
 * DDS reader, the publisher parks (no polling) and every push is queued and wakes it, ring overrun accounting
 * (published + dropped == queued, also in the final ControllerStatus), rejected snapshots. argv[1] = Cyclone
 * XML, argv[2] = domain id. The bridge under test uses CYCLONEDDS_URI (set by ctest) so that the readers here
 * can share its domain. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include <dirent.h> /* opendir: /proc/self/task */
#include <signal.h> /* kill */

#include "mca/dds_bridge.h"
#include "mca/dds_qos.h"
#include "mca/dds_synth.h"
#include "mca/err.h"
#include "mca/scheme.h" /* mca_brake_s */
#include "mca_dds.h"
#include "ros2_msgs.h" /* geometry_msgs TwistStamped as ROS 2 puts it on DDS (idlc) */

static const char *g_config;
static uint32_t g_domain;
static const char *g_bridge_exe; /* mca-dds-bridge (process mode), argv[3] */
/* The crash a bad peer causes (tests/dds/crash_peer.py) is a SIGSEGV; under AddressSanitizer the bridge's own
 * SEGV handler would turn a SIGSEGV into an exit with a report, so the sanitizer build kills it with SIGKILL
 * instead. */
#if defined(__SANITIZE_ADDRESS__)
#define CRASH_SIGNAL SIGKILL
#define CRASH_TEXT "died: signal 9 (SIGKILL); restart 1 in 0.1 s"
#else
#define CRASH_SIGNAL SIGSEGV
#define CRASH_TEXT "died: signal 11 (SIGSEGV); restart 1 in 0.1 s"
#endif
static char g_partition[64]; /* per process: other tests' publishers may share the domain */

static void test_create_rejects_bad_arguments(void **state) {
    (void)state;
    mca_dds_config_t cfg;
    mca_dds_bridge_t *b = (mca_dds_bridge_t *)0x1;
    char err[320] = ""; /* mca_dds_bridge_create's reason */
    mca_dds_config_default(&cfg);
    cfg.domain_id = g_domain;
    assert_int_equal(mca_dds_bridge_create(NULL, &cfg, err, sizeof err), MCA_EINVAL);
    assert_int_equal(mca_dds_bridge_create(&b, NULL, NULL, 0), MCA_EINVAL);
    cfg.status_divisor = 0;
    assert_int_equal(mca_dds_bridge_create(&b, &cfg, err, sizeof err), MCA_EINVAL);
    cfg.status_divisor = 100;
    cfg.ring_capacity = 100;
    assert_int_equal(mca_dds_bridge_create(&b, &cfg, err, sizeof err), MCA_EINVAL);
    cfg.ring_capacity = 16;
    cfg.domain_id = 231;
    assert_int_equal(mca_dds_bridge_create(&b, &cfg, err, sizeof err), MCA_EINVAL);
    cfg.domain_id = g_domain;
    cfg.frame_id = "a_frame_name_that_is_longer_than_32_bytes";
    assert_int_equal(mca_dds_bridge_create(&b, &cfg, err, sizeof err), MCA_EINVAL);
    assert_non_null(strstr(err, "frame id 'a_frame_name_that_is_longer_than_32_bytes' longer than"));
    cfg.frame_id = NULL;
    cfg.partition = "a_partition_name_that_is_much_longer_than_the_sixty_three_bytes_allowed";
    assert_int_equal(mca_dds_bridge_create(&b, &cfg, err, sizeof err), MCA_EINVAL);
    cfg.partition = NULL;
    cfg.sched_priority = 99; /* 0 or 1..98: never the 99 of the kernel's own threads */
    assert_int_equal(mca_dds_bridge_create(&b, &cfg, err, sizeof err), MCA_EINVAL);
    assert_non_null(strstr(err, "publisher priority 99"));
    cfg.sched_priority = 0;
    cfg.config_path = "/nonexistent/mca/cyclone.xml";
    assert_int_equal(mca_dds_bridge_create(&b, &cfg, err, sizeof err), MCA_ENOENT);
    assert_string_equal(err, "cannot read config file '/nonexistent/mca/cyclone.xml'");
    assert_ptr_equal(b, (mca_dds_bridge_t *)0x1); /* untouched on error */
    mca_dds_stats_t st;
    assert_int_equal(mca_dds_bridge_stats(NULL, &st), MCA_EINVAL);
    assert_int_equal(mca_dds_bridge_wait_readers(NULL, NULL, 1, 1), MCA_EINVAL);
    mca_dds_bridge_destroy(NULL, NULL); /* no crash */
}

static void test_create_rejects_bad_xml(void **state) {
    (void)state;
    char path[] = "/tmp/mca_dds_bad_XXXXXX";
    const int fd = mkstemp(path);
    assert_true(fd >= 0);
    static const char bad[] = "<CycloneDDS><Domain><General><NoSuchElement>1</NoSuchElement></General>"
                              "</Domain></CycloneDDS>";
    assert_int_equal(write(fd, bad, sizeof bad - 1), (ssize_t)(sizeof bad - 1));
    close(fd);
    mca_dds_config_t cfg;
    mca_dds_config_default(&cfg);
    cfg.domain_id = g_domain;
    cfg.config_path = path;
    mca_dds_bridge_t *b = NULL;
    char err[320] = ""; /* mca_dds_bridge_create's reason */
    assert_int_equal(mca_dds_bridge_create(&b, &cfg, err, sizeof err), MCA_EIO);
    assert_non_null(strstr(err, "rejected")); /* Cyclone's refusal in the buffer, not on stderr */
    assert_null(b);
    unlink(path);

    /* The shipped loopback config itself is accepted. */
    cfg.config_path = g_config;
    assert_int_equal(mca_dds_bridge_create(&b, &cfg, err, sizeof err), MCA_OK);
    mca_dds_stats_t st;
    mca_dds_bridge_destroy(b, &st);
    assert_int_equal(st.offered, 0);
}

/* Readers on the bridge's domain, created in this process (local delivery). */
typedef struct readers {
    dds_entity_t pp, rd_dist, rd_js, rd_jc, rd_st;
} readers_t;

static void open_readers_in(readers_t *r, const char *partition) {
    dds_entity_t dom = 0;
    assert_int_equal(mca_dds_open_participant(g_domain, NULL, &r->pp, &dom, NULL, 0), MCA_OK);
    assert_true(r->pp > 0);
    dds_qos_t *qs = mca_dds_qos_stream();
    dds_qos_t *qst = mca_dds_qos_status();
    dds_qset_history(qs, DDS_HISTORY_KEEP_LAST, 4096); /* the test reads only at the end */
    const dds_entity_t td =
        dds_create_topic(r->pp, &mca_dds_Distances_desc, MCA_DDS_TOPIC_DISTANCES, qs, NULL);
    const dds_entity_t tj =
        dds_create_topic(r->pp, &mca_dds_JointState_desc, MCA_DDS_TOPIC_JOINT_STATE, qs, NULL);
    const dds_entity_t tc =
        dds_create_topic(r->pp, &mca_dds_JointCommand_desc, MCA_DDS_TOPIC_JOINT_COMMAND, qs, NULL);
    const dds_entity_t ts =
        dds_create_topic(r->pp, &mca_dds_ControllerStatus_desc, MCA_DDS_TOPIC_STATUS, qst, NULL);
    dds_entity_t sub = 0;
    assert_int_equal(mca_dds_create_subscriber(r->pp, partition, &sub, NULL, 0), MCA_OK);
    assert_true(sub > 0);
    r->rd_dist = dds_create_reader(sub, td, qs, NULL);
    r->rd_js = dds_create_reader(sub, tj, qs, NULL);
    r->rd_jc = dds_create_reader(sub, tc, qs, NULL);
    r->rd_st = dds_create_reader(sub, ts, qst, NULL);
    dds_delete_qos(qs);
    dds_delete_qos(qst);
    assert_true(r->rd_dist > 0 && r->rd_js > 0 && r->rd_jc > 0 && r->rd_st > 0);
}

static void open_readers(readers_t *r) {
    open_readers_in(r, g_partition);
}

static mca_dds_bridge_t *make_bridge(uint32_t capacity) {
    mca_dds_config_t cfg;
    mca_dds_config_default(&cfg);
    cfg.domain_id = g_domain;
    cfg.ring_capacity = capacity;
    cfg.frame_id = "base_link";
    cfg.partition = g_partition;
    mca_dds_bridge_t *b = NULL;
    char err[320] = ""; /* mca_dds_bridge_create's reason */
    assert_int_equal(mca_dds_bridge_create(&b, &cfg, err, sizeof err), MCA_OK);
    assert_non_null(b);
    return b;
}

/* Take every valid Distances sample: ticks into out (in arrival order); checks each one against the
 * snapshot that tick produced. Returns the count. */
static int take_distances(dds_entity_t rd, uint64_t *out, int max) {
    enum { BATCH = 256 };
    void *buf[BATCH];
    dds_sample_info_t info[BATCH];
    int got = 0;
    for (;;) {
        memset(buf, 0, sizeof buf);
        const int n = dds_take(rd, buf, info, BATCH, BATCH);
        assert_true(n >= 0);
        if (n == 0) {
            break;
        }
        for (int i = 0; i < n; ++i) {
            if (!info[i].valid_data) {
                continue;
            }
            const mca_dds_Distances *d = buf[i];
            mca_dds_snapshot_t ref;
            double mn = INFINITY;
            int64_t ms = 0;
            mca_dds_synth_fill(&ref, d->tick, 0, &mn, &ms);
            const mca_dds_pair_snapshot_t *p = &ref.pair[0];
            assert_int_equal(d->pair_id, 0);
            assert_int_equal(d->stamp_ns, (int64_t)(1000 + d->tick)); /* stamps chosen by the pushes */
            assert_true(d->min_distance == p->min_distance);
            assert_memory_equal(d->p, p->p, sizeof d->p);
            assert_memory_equal(d->e, p->e, sizeof d->e);
            assert_int_equal(d->link_a, p->link_a);
            assert_int_equal(d->link_b, p->link_b);
            assert_true(d->brake_factor == p->brake_factor);
            assert_int_equal(d->link_distance_a._length, p->n_links_a);
            assert_int_equal(d->link_distance_b._length, p->n_links_b);
            assert_memory_equal(d->link_distance_a._buffer, p->link_distance_a,
                                p->n_links_a * sizeof(double));
            assert_memory_equal(d->link_distance_b._buffer, p->link_distance_b,
                                p->n_links_b * sizeof(double));
            assert_true(got < max);
            out[got++] = d->tick;
        }
        dds_return_loan(rd, buf, n);
    }
    return got;
}

static int take_joint_states(dds_entity_t rd, int *per_arm) {
    enum { BATCH = 256 };
    void *buf[BATCH];
    dds_sample_info_t info[BATCH];
    int got = 0;
    for (;;) {
        memset(buf, 0, sizeof buf);
        const int n = dds_take(rd, buf, info, BATCH, BATCH);
        if (n <= 0) {
            break;
        }
        for (int i = 0; i < n; ++i) {
            if (!info[i].valid_data) {
                continue;
            }
            const mca_dds_JointState *js = buf[i];
            mca_dds_snapshot_t ref;
            double mn = INFINITY;
            int64_t ms = 0;
            mca_dds_synth_fill(&ref, js->tick, 0, &mn, &ms);
            assert_true(js->arm_id < ref.n_arms);
            const mca_dds_arm_snapshot_t *a = &ref.arm[js->arm_id];
            assert_int_equal(js->position._length, a->n_dof);
            assert_memory_equal(js->position._buffer, a->position, a->n_dof * sizeof(double));
            assert_memory_equal(js->velocity._buffer, a->velocity, a->n_dof * sizeof(double));
            assert_memory_equal(js->effort._buffer, a->effort, a->n_dof * sizeof(double));
            per_arm[js->arm_id]++;
            got++;
        }
        dds_return_loan(rd, buf, n);
    }
    return got;
}

static int take_last_status(dds_entity_t rd, mca_dds_ControllerStatus *out) {
    void *buf[1] = {NULL};
    dds_sample_info_t info[1];
    const int n = dds_take(rd, buf, info, 1, 1);
    int ok = 0;
    if (n == 1 && info[0].valid_data) {
        *out = *(const mca_dds_ControllerStatus *)buf[0];
        ok = 1;
    }
    if (n > 0) {
        dds_return_loan(rd, buf, n);
    }
    return ok;
}

static void push_range(mca_dds_bridge_t *b, uint64_t n) {
    static mca_dds_snapshot_t snap;
    double mn = INFINITY;
    int64_t ms = 0;
    for (uint64_t k = 0; k < n; ++k) {
        mca_dds_synth_fill(&snap, k, (int64_t)(1000 + k), &mn, &ms);
        mca_dds_bridge_push(b, &snap);
    }
}

static void test_every_snapshot_arrives_intact(void **state) {
    (void)state;
    mca_dds_bridge_t *b = make_bridge(256);
    readers_t r;
    open_readers(&r);
    assert_int_equal(mca_dds_bridge_wait_readers(b, NULL, 1, 10000), MCA_OK);
    assert_int_equal(mca_dds_bridge_wait_readers(b, "no/such/topic", 1, 10), MCA_EINVAL);
    enum { N = 200 };
    push_range(b, N); /* 200 < ring capacity 256: nothing can be dropped */
    mca_dds_stats_t st;
    mca_dds_bridge_destroy(b, &st);
    assert_int_equal(st.offered, N);
    assert_int_equal(st.queued, N);
    assert_int_equal(st.published, N);
    assert_int_equal(st.dropped, 0);
    assert_int_equal(st.write_errors, 0);
    /* per snapshot: 2 arms x (state + command) + 1 pair; status on changes, every 100th, and final */
    assert_true(st.samples >= (uint64_t)N * 5 + 1);

    uint64_t ticks[N];
    assert_int_equal(take_distances(r.rd_dist, ticks, N), N);
    for (int i = 0; i < N; ++i) {
        assert_int_equal(ticks[i], (uint64_t)i);
    }
    int per_arm[MCA_MAX_ARMS] = {0};
    assert_int_equal(take_joint_states(r.rd_js, per_arm), 2 * N);
    assert_int_equal(per_arm[0], N);
    assert_int_equal(per_arm[1], N);

    /* One JointCommand checked field by field, including the configured frame id. */
    void *buf[1] = {NULL};
    dds_sample_info_t info[1];
    assert_int_equal(dds_take(r.rd_jc, buf, info, 1, 1), 1);
    const mca_dds_JointCommand *jc = buf[0];
    assert_string_equal(jc->frame_id, "base_link");
    mca_dds_snapshot_t ref;
    double mn = INFINITY;
    int64_t ms = 0;
    mca_dds_synth_fill(&ref, jc->tick, 0, &mn, &ms);
    assert_memory_equal(jc->velocity_setpoint._buffer, ref.arm[jc->arm_id].velocity_setpoint,
                        ref.arm[jc->arm_id].n_dof * sizeof(double));
    assert_memory_equal(jc->position_reference._buffer, ref.arm[jc->arm_id].position_reference,
                        ref.arm[jc->arm_id].n_dof * sizeof(double));
    dds_return_loan(r.rd_jc, buf, 1);

    mca_dds_ControllerStatus s;
    assert_true(take_last_status(r.rd_st, &s));
    assert_int_equal(s.ticks, N); /* the final status is of the last snapshot */
    assert_int_equal(s.tick, N - 1);
    assert_int_equal(s.snapshots_dropped, 0);
    /* d falls from 0.18 m over ticks 0..1000: the running minimum is d at the last tick. */
    assert_true(s.min_distance_so_far == 0.02 + 0.16 * ((double)(1000 - (N - 1)) / 1000.0));
    dds_delete(r.pp);
}

/* /proc/self/task/TID/@p file of this process's thread named @p name, opened for reading; NULL if none. */
static FILE *thread_file(const char *name, const char *file) {
    char path[300], line[128];
    DIR *dir = opendir("/proc/self/task");
    FILE *out = NULL;
    for (struct dirent *e; dir != NULL && out == NULL && (e = readdir(dir)) != NULL;) {
        snprintf(path, sizeof path, "/proc/self/task/%s/comm", e->d_name);
        FILE *f = fopen(path, "r");
        if (f == NULL) {
            continue;
        }
        const int same = fgets(line, sizeof line, f) != NULL && strncmp(line, name, strlen(name)) == 0;
        fclose(f);
        if (same) {
            snprintf(path, sizeof path, "/proc/self/task/%s/%s", e->d_name, file);
            out = fopen(path, "r");
        }
    }
    if (dir != NULL) {
        closedir(dir);
    }
    return out;
}

/* Context switches (voluntary + involuntary) of this process's thread named @p name; -1 if none. */
static long thread_switches(const char *name) {
    char line[128];
    FILE *f = thread_file(name, "status");
    if (f == NULL) {
        return -1;
    }
    long n = 0, v;
    while (fgets(line, sizeof line, f) != NULL) {
        if (sscanf(line, "voluntary_ctxt_switches: %ld", &v) == 1 ||
            sscanf(line, "nonvoluntary_ctxt_switches: %ld", &v) == 1) {
            n += v;
        }
    }
    fclose(f);
    return n;
}

/* Issue 13: the publisher does not poll. With the ring empty it parks (the old one woke every 200 us:
 * ~5000 switches a second); every push is queued (decimation is the caller's) and a push wakes a parked
 * publisher, at most one wake per push. */
static void test_publisher_parks_and_wakes(void **state) {
    (void)state;
    mca_dds_bridge_t *b = make_bridge(64);
    readers_t r;
    open_readers(&r);
    assert_int_equal(mca_dds_bridge_wait_readers(b, MCA_DDS_TOPIC_DISTANCES, 1, 10000), MCA_OK);
    const long sw0 = thread_switches("mca-dds-pub");
    assert_true(sw0 >= 0);
    const struct timespec idle = {1, 0};
    nanosleep(&idle, NULL);
    const long sw1 = thread_switches("mca-dds-pub");
    print_message("publisher thread: %ld context switches in 1 s idle\n", sw1 - sw0);
    assert_true(sw1 - sw0 <= 2);

    static mca_dds_snapshot_t snap;
    double mn = INFINITY;
    int64_t ms = 0;
    enum { N = 20 };
    for (uint64_t k = 0; k < N; ++k) {
        mca_dds_synth_fill(&snap, 10 * k, (int64_t)(1000 + 10 * k), &mn, &ms);
        mca_dds_bridge_push(b, &snap);
        /* woken, not polled: the snapshot goes out at once (10 s: only a starved machine is that slow) */
        mca_dds_stats_t st;
        for (int i = 0; i < 10000; ++i) {
            assert_int_equal(mca_dds_bridge_stats(b, &st), MCA_OK);
            if (st.published == k + 1) {
                break;
            }
            const struct timespec ms1 = {0, 1000000};
            nanosleep(&ms1, NULL);
        }
        assert_int_equal(st.published, k + 1);
    }
    mca_dds_stats_t st;
    assert_int_equal(mca_dds_bridge_stats(b, &st), MCA_OK);
    print_message("wakes %llu parks %llu of %d pushes\n", (unsigned long long)st.wakes,
                  (unsigned long long)st.parks, N);
    assert_true(st.wakes >= 1 && st.wakes <= N);
    assert_true(st.parks >= st.wakes);
    mca_dds_bridge_destroy(b, &st);
    assert_int_equal(st.offered, N);
    assert_int_equal(st.queued, N); /* every push is queued: the caller decimates */
    assert_int_equal(st.published, N);
    uint64_t ticks[N + 4];
    assert_int_equal(take_distances(r.rd_dist, ticks, N + 4), N);
    for (int i = 0; i < N; ++i) {
        assert_int_equal(ticks[i], (uint64_t)(10 * i));
    }
    dds_delete(r.pp);
}

/* Scheduling policy and priority of this process's thread named @p name (/proc stat fields 41, 40); -1. */
static int thread_sched(const char *name, int *prio) {
    char line[1024];
    FILE *f = thread_file(name, "stat");
    if (f == NULL) {
        return -1;
    }
    const char *p = fgets(line, sizeof line, f) != NULL ? strrchr(line, ')') : NULL;
    fclose(f);
    for (int field = 2; p != NULL && field < 41; field++) { /* ") S ..." : field 3 follows */
        p = strchr(p + 1, ' ');
        if (p != NULL && field == 39) {
            *prio = atoi(p + 1);
        }
    }
    return p != NULL ? atoi(p + 1) : -1;
}

/* sched_priority: the in-process publisher thread runs SCHED_FIFO at it (as root; else it is refused and
 * the stats say so), and pushes still arrive. */
static void test_publisher_priority(void **state) {
    (void)state;
    mca_dds_config_t cfg;
    mca_dds_config_default(&cfg);
    cfg.domain_id = g_domain;
    cfg.ring_capacity = 16;
    cfg.partition = g_partition;
    cfg.sched_priority = 7;
    mca_dds_bridge_t *b = NULL;
    char err[320] = "";
    assert_int_equal(mca_dds_bridge_create(&b, &cfg, err, sizeof err), MCA_OK);
    mca_dds_stats_t st;
    assert_int_equal(mca_dds_bridge_stats(b, &st), MCA_OK);
    int prio = -1;
    const int policy = thread_sched("mca-dds-pub", &prio);
    print_message("publisher thread: policy %d priority %d (refused %d)\n", policy, prio, st.sched_refused);
    if (geteuid() == 0) {
        assert_int_equal(st.sched_refused, 0);
        assert_int_equal(policy, 1); /* SCHED_FIFO */
        assert_int_equal(prio, 7);
    } else {
        assert_true(st.sched_refused || policy == 1);
    }
    static mca_dds_snapshot_t snap;
    double mn = INFINITY;
    int64_t ms = 0;
    mca_dds_synth_fill(&snap, 0, 1, &mn, &ms);
    mca_dds_bridge_push(b, &snap);
    mca_dds_bridge_destroy(b, &st); /* flushes first */
    assert_int_equal(st.published, 1);
}

/* With wake_period_ns the publisher sleeps on the caller's grid (due time + period + offset) after each
 * snapshot: on-time pushes find it asleep there and make no system call (no FUTEX_WAKE). The stamps here are
 * 8 ms before the due times: a publisher anchored on the stamp would look 5 ms after each push, find the
 * ring empty, park, and need a FUTEX_WAKE for every push. */
static void test_publisher_wakes_on_grid(void **state) {
    (void)state;
    mca_dds_config_t cfg;
    mca_dds_config_default(&cfg);
    cfg.domain_id = g_domain;
    cfg.ring_capacity = 64;
    cfg.partition = g_partition;
    cfg.wake_period_ns = 10000000; /* a push every 10 ms */
    cfg.wake_offset_ns = 3000000;  /* the publisher looks 3 ms after each */
    mca_dds_bridge_t *b = NULL;
    char err[320] = ""; /* mca_dds_bridge_create's reason */
    assert_int_equal(mca_dds_bridge_create(&b, &cfg, err, sizeof err), MCA_OK);
    readers_t r;
    open_readers(&r);
    assert_int_equal(mca_dds_bridge_wait_readers(b, MCA_DDS_TOPIC_DISTANCES, 1, 10000), MCA_OK);
    static mca_dds_snapshot_t snap;
    double mn = INFINITY;
    int64_t ms = 0;
    enum { N = 30 };
    struct timespec t0;
    clock_gettime(CLOCK_MONOTONIC, &t0);
    const int64_t start = (int64_t)t0.tv_sec * 1000000000LL + t0.tv_nsec + 10000000;
    for (int k = 0; k < N; ++k) {
        const int64_t at = start + (int64_t)k * 10000000;
        const struct timespec ts = {(time_t)(at / 1000000000LL), (long)(at % 1000000000LL)};
        while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, NULL) != 0) {
        }
        mca_dds_synth_fill(&snap, (uint64_t)k, at, &mn, &ms);
        snap.due_ns = at;             /* the tick's grid time */
        snap.stamp_ns = at - 8000000; /* not the anchor (see above) */
        mca_dds_bridge_push(b, &snap);
    }
    mca_dds_stats_t st;
    for (int i = 0; i < 5000; ++i) {
        assert_int_equal(mca_dds_bridge_stats(b, &st), MCA_OK);
        if (st.published == N) {
            break;
        }
        const struct timespec ms1 = {0, 1000000};
        nanosleep(&ms1, NULL);
    }
    print_message("grid: %llu sleeps on the grid, %llu futex wakes of %d pushes\n",
                  (unsigned long long)st.grid_sleeps, (unsigned long long)st.wakes, N);
    assert_int_equal(st.published, N);
    assert_true(st.grid_sleeps >= N / 2);
    assert_true(st.wakes <= N / 2); /* only a push more than 3 ms late finds the publisher parked */
    mca_dds_bridge_destroy(b, &st);
    dds_delete(r.pp);
}

static void test_overrun_drops_oldest_and_counts(void **state) {
    (void)state;
    /* Ring of 4: 100 snapshots pushed back to back (~1 us each) while one publish takes tens of us: most are
     * dropped. */
    mca_dds_bridge_t *b = make_bridge(4);
    readers_t r;
    open_readers(&r);
    assert_int_equal(mca_dds_bridge_wait_readers(b, NULL, 1, 10000), MCA_OK);
    push_range(b, 100);
    mca_dds_stats_t st;
    assert_int_equal(mca_dds_bridge_stats(b, &st), MCA_OK);
    assert_int_equal(st.queued, 100);
    assert_true(st.dropped >= 50); /* the publisher drains one per publish, far slower than a push */
    mca_dds_bridge_destroy(b, &st);
    assert_int_equal(st.queued, 100);
    assert_int_equal(st.published + st.dropped + st.invalid, st.queued);
    assert_true(st.published >= 4);

    uint64_t ticks[100];
    const int n = take_distances(r.rd_dist, ticks, 100);
    assert_int_equal((uint64_t)n, st.published);
    for (int i = 1; i < n; ++i) {
        assert_true(ticks[i] > ticks[i - 1]);
    }
    assert_int_equal(ticks[n - 1], 99); /* the newest are kept */
    assert_int_equal(ticks[n - 4], 96);

    mca_dds_ControllerStatus s;
    assert_true(take_last_status(r.rd_st, &s));
    assert_int_equal(s.snapshots_dropped, st.dropped);
    dds_delete(r.pp);
}

static void test_partition_isolates(void **state) {
    (void)state;
    mca_dds_bridge_t *b = make_bridge(16);
    readers_t other, same;
    open_readers_in(&other, "mca-test-some-other-partition");
    /* A reader in another partition of the same domain never matches and gets nothing. */
    assert_int_equal(mca_dds_bridge_wait_readers(b, MCA_DDS_TOPIC_DISTANCES, 1, 300), MCA_ETIMEDOUT);
    open_readers(&same);
    assert_int_equal(mca_dds_bridge_wait_readers(b, MCA_DDS_TOPIC_DISTANCES, 1, 10000), MCA_OK);
    push_range(b, 5);
    mca_dds_bridge_destroy(b, NULL);
    uint64_t ticks[8];
    assert_int_equal(take_distances(other.rd_dist, ticks, 8), 0);
    assert_int_equal(take_distances(same.rd_dist, ticks, 8), 5);
    dds_delete(other.pp);
    dds_delete(same.pp);
}

static void test_invalid_snapshot_rejected(void **state) {
    (void)state;
    mca_dds_bridge_t *b = make_bridge(16);
    static mca_dds_snapshot_t snap;
    double mn = INFINITY;
    int64_t ms = 0;
    mca_dds_synth_fill(&snap, 0, 0, &mn, &ms);
    snap.n_arms = MCA_MAX_ARMS + 1;
    mca_dds_bridge_push(b, &snap);
    mca_dds_synth_fill(&snap, 1, 0, &mn, &ms);
    snap.arm[1].n_dof = MCA_MAX_DOF + 1;
    mca_dds_bridge_push(b, &snap);
    mca_dds_synth_fill(&snap, 2, 0, &mn, &ms);
    snap.pair[0].n_links_b = MCA_MAX_LINKS + 1;
    mca_dds_bridge_push(b, &snap);
    mca_dds_synth_fill(&snap, 3, 0, &mn, &ms);
    mca_dds_bridge_push(b, &snap);
    mca_dds_stats_t st;
    mca_dds_bridge_destroy(b, &st);
    assert_int_equal(st.invalid, 3);
    assert_int_equal(st.published, 1);
}

/* The published brake factor is core's S(d) (eq. 13; its closed values: scheme.unit): the pair fill at the
 * thresholds and at sin^2(pi/6). */
static void test_brake_factor_eq13(void **state) {
    (void)state;
    mca_arm_distances_t d;
    memset(&d, 0, sizeof d);
    mca_dds_pair_snapshot_t p;
    const double cases[][2] = {{0.20, 1.0}, {0.12, 1.0}, {0.05, 0.0}, {0.01, 0.0}, {0.05 + 0.07 / 3.0, 0.25}};
    for (size_t k = 0; k < sizeof cases / sizeof cases[0]; k++) {
        d.min.d = cases[k][0];
        assert_int_equal(mca_dds_pair_fill(&p, &d, 0, 1, 0.05, 0.12), MCA_OK);
        assert_true(fabs(p.brake_factor - cases[k][1]) < 1e-15);
        assert_true(p.brake_factor == mca_brake_s(cases[k][0], 0.05, 0.12));
    }
}

static void test_pair_fill_from_armdist(void **state) {
    (void)state;
    mca_arm_distances_t d;
    memset(&d, 0, sizeof d);
    d.n_links_a = 3;
    d.n_links_b = 2;
    for (int l = 0; l < 3; ++l) {
        d.a_to_b[l].d = 0.3 + 0.1 * l;
    }
    d.b_to_a[0].d = 0.5;
    d.b_to_a[1].d = 0.085;
    d.min = (mca_link_pair_t){.link = 2, .other_link = 1, .d = 0.085, .p = {1, 2, 3}, .e = {4, 5, 6}};
    mca_dds_pair_snapshot_t p;
    memset(&p, 0xff, sizeof p);
    assert_int_equal(mca_dds_pair_fill(&p, &d, 1, 3, 0.05, 0.12), MCA_OK);
    assert_int_equal(p.arm_a, 1);
    assert_int_equal(p.arm_b, 3);
    assert_int_equal(p.link_a, 2);
    assert_int_equal(p.link_b, 1);
    assert_true(p.min_distance == 0.085);
    assert_true(p.p[0] == 1 && p.p[1] == 2 && p.p[2] == 3 && p.e[0] == 4 && p.e[1] == 5 && p.e[2] == 6);
    assert_true(p.d1 == 0.05 && p.d2 == 0.12);
    assert_true(fabs(p.brake_factor - 0.5) < 1e-15); /* midpoint of d1..d2 */
    assert_int_equal(p.n_links_a, 3);
    assert_int_equal(p.n_links_b, 2);
    assert_true(p.link_distance_a[2] == 0.3 + 0.1 * 2);
    assert_true(p.link_distance_b[1] == 0.085);
    assert_int_equal(mca_dds_pair_fill(&p, &d, 0, 1, 0.12, 0.05), MCA_EINVAL); /* d1 >= d2 */
    d.n_links_a = MCA_MAX_LINKS + 1;
    assert_int_equal(mca_dds_pair_fill(&p, &d, 0, 1, 0.05, 0.12), MCA_EINVAL);
    assert_int_equal(mca_dds_pair_fill(NULL, &d, 0, 1, 0.05, 0.12), MCA_EINVAL);
}

static int wait_published(mca_dds_bridge_t *b, uint64_t n, mca_dds_stats_t *st) {
    for (int i = 0; i < 1000; ++i) {
        mca_dds_bridge_stats(b, st);
        if (st->published >= n) {
            return 1;
        }
        const struct timespec nap = {0, 5 * 1000 * 1000};
        nanosleep(&nap, NULL);
    }
    return 0;
}

/* The supervisor's lines as a program would print them (mca_dds_log_fn; arg: the FILE). */
static void test_log_line(void *arg, int level, const char *text) {
    fprintf((FILE *)arg, "<%d>test: %s\n", level, text);
}

/* Process mode (a crash of Cyclone's must not take mcad with it): the publisher is the program
 * mca-dds-bridge. Killed with SIGSEGV, it is reaped, logged and restarted by mca_dds_bridge_supervise(); the
 * restarted one publishes the newest snapshot of the backlog at once (the others count as stale) and then
 * every new one; destroy ends it after the final status.
 */
static void test_process_mode_restart(void **state) {
    (void)state;
    if (g_bridge_exe == NULL) {
        skip();
    }
    readers_t r;
    open_readers(&r);
    mca_dds_config_t cfg;
    mca_dds_config_default(&cfg);
    cfg.domain_id = g_domain;
    cfg.ring_capacity = 256;
    cfg.frame_id = "base_link";
    cfg.partition = g_partition;
    cfg.process_exe = "/nonexistent/mca-dds-bridge";
    mca_dds_bridge_t *b = (mca_dds_bridge_t *)0x1;
    char err[320] = ""; /* mca_dds_bridge_create's reason */
    assert_int_equal(mca_dds_bridge_create(&b, &cfg, err, sizeof err), MCA_ENOENT);
    assert_non_null(strstr(err, "cannot start the bridge program /nonexistent/mca-dds-bridge"));
    assert_ptr_equal(b, (mca_dds_bridge_t *)0x1);
    cfg.process_exe = g_bridge_exe;
    b = NULL;
    assert_int_equal(mca_dds_bridge_create(&b, &cfg, err, sizeof err), MCA_OK);
    mca_dds_stats_t st;
    mca_dds_bridge_stats(b, &st);
    const int pid0 = st.pid;
    assert_true(pid0 > 0 && pid0 != (int)getpid());
    assert_int_equal(mca_dds_bridge_wait_readers(b, NULL, 1, 10), MCA_EINVAL); /* not in process mode */
    sleep(1);                                                                  /* the readers match */

    static mca_dds_snapshot_t snap;
    double mn = INFINITY;
    int64_t ms = 0;
    for (uint64_t k = 0; k < 10; ++k) {
        mca_dds_synth_fill(&snap, k, (int64_t)(1000 + k), &mn, &ms);
        mca_dds_bridge_push(b, &snap);
    }
    assert_true(wait_published(b, 10, &st));

    char logbuf[4096] = "";
    FILE *log = fmemopen(logbuf, sizeof logbuf - 1, "w");
    assert_non_null(log);
    setvbuf(log, NULL, _IONBF, 0);
    assert_int_equal(kill(pid0, CRASH_SIGNAL), 0);
    for (int i = 0; i < 1000 && st.deaths == 0; ++i) {
        mca_dds_bridge_supervise(b, test_log_line, log);
        mca_dds_bridge_stats(b, &st);
        const struct timespec nap = {0, 2 * 1000 * 1000};
        nanosleep(&nap, NULL);
    }
    assert_int_equal(st.deaths, 1);
    assert_int_equal(st.pid, 0);
    /* down: the loop's pushes go on into the ring */
    for (uint64_t k = 10; k < 60; ++k) {
        mca_dds_synth_fill(&snap, k, (int64_t)(1000 + k), &mn, &ms);
        mca_dds_bridge_push(b, &snap);
    }
    for (int i = 0; i < 2500 && strstr(logbuf, "restarted") == NULL; ++i) {
        mca_dds_bridge_supervise(b, test_log_line, log);
        const struct timespec nap = {0, 2 * 1000 * 1000};
        nanosleep(&nap, NULL);
    }
    print_message("%s", logbuf);
    assert_non_null(strstr(logbuf, CRASH_TEXT));
    assert_non_null(strstr(logbuf, "dds bridge restarted: pid"));
    assert_true(wait_published(b, 11, &st)); /* the newest of the backlog, at once */
    assert_int_equal(st.restarts, 1);
    assert_int_equal(st.stale, 49);
    assert_true(st.pid > 0 && st.pid != pid0);
    sleep(1); /* the readers match the new writers */
    for (uint64_t k = 60; k < 70; ++k) {
        mca_dds_synth_fill(&snap, k, (int64_t)(1000 + k), &mn, &ms);
        mca_dds_bridge_push(b, &snap);
    }
    assert_true(wait_published(b, 21, &st));
    mca_dds_bridge_destroy(b, &st);
    fclose(log);
    assert_int_equal(st.queued, 70);
    assert_int_equal(st.published, 21);
    assert_int_equal(st.published + st.dropped + st.invalid + st.stale, st.queued);

    uint64_t ticks[128];
    const int n = take_distances(r.rd_dist, ticks, 128); /* each checked field by field */
    int seen59 = 0, seen69 = 0;
    for (int i = 0; i < n; ++i) {
        assert_false(ticks[i] >= 10 && ticks[i] < 59); /* the stale backlog is never published */
        seen59 |= ticks[i] == 59;
        seen69 |= ticks[i] == 69;
    }
    /* 59 goes out the moment the new writers exist, maybe before these readers matched them: not asserted */
    print_message("received %d Distances; tick 59 (the backlog's newest) %s\n", n,
                  seen59 ? "seen" : "not seen");
    assert_true(seen69);
    mca_dds_ControllerStatus s;
    assert_true(take_last_status(r.rd_st, &s));
    assert_int_equal(s.tick, 69); /* the final status, from the restarted bridge */
    dds_delete(r.pp);
}

/* Process mode: an arm's stream target lives in the shared region, so it outlives the bridge process. After a
 * death the loop still reads the last target with its old receive time (its age grows: task.stream's
 * hold_after and brake_after act on it) and after the restart new targets are accepted on top of it (the
 * count goes on). */
static void test_process_mode_stream_target_survives(void **state) {
    (void)state;
    if (g_bridge_exe == NULL) {
        skip();
    }
    static mca_ros2_config_t rc;
    mca_ros2_config_default(&rc);
    rc.enabled = 1;
    snprintf(rc.cell, sizeof rc.cell, "bridge_test_%ld",
             (long)getpid()); /* ROS 2 topics: default partition */
    rc.joint_states = rc.robot_description = rc.tf_static = rc.markers = rc.diagnostics = 0;
    rc.n_arms = 1;
    rc.stream[0] = MCA_ROS2_STREAM_TWIST;
    rc.stream_max_speed = 0.5;
    for (int i = 0; i < 3; i++) {
        rc.box_lo[i] = -1.0;
        rc.box_hi[i] = 1.0;
    }
    snprintf(rc.arm[0].name, sizeof rc.arm[0].name, "left");
    rc.arm[0].n_dof = 1;
    snprintf(rc.arm[0].joint_name[0], sizeof rc.arm[0].joint_name[0], "j1");
    snprintf(rc.arm[0].root_link, sizeof rc.arm[0].root_link, "base");
    rc.arm[0].n_links = 2;
    rc.arm[0].link_radius[0] = rc.arm[0].link_radius[1] = 0.05;
    mca_dds_config_t cfg;
    mca_dds_config_default(&cfg);
    cfg.domain_id = g_domain;
    cfg.partition = g_partition;
    cfg.ros2 = &rc;
    cfg.process_exe = g_bridge_exe;
    mca_dds_bridge_t *b = NULL;
    char err[320] = ""; /* mca_dds_bridge_create's reason */
    assert_int_equal(mca_dds_bridge_create(&b, &cfg, err, sizeof err), MCA_OK);
    mca_ros2_target_t tg;
    assert_int_equal(mca_dds_bridge_stream_target(b, 1, &tg), MCA_EINVAL); /* no such arm */
    assert_int_equal(mca_dds_bridge_stream_target(b, 0, &tg), MCA_OK);
    assert_int_equal(tg.accepted, 0);

    dds_entity_t dom = 0, pp = 0;
    assert_int_equal(mca_dds_open_participant(g_domain, NULL, &pp, &dom, NULL, 0), MCA_OK);
    assert_true(pp > 0);
    char name[160];
    snprintf(name, sizeof name, "rt/%s/left/target_twist", rc.cell);
    const dds_entity_t tp =
        dds_create_topic(pp, &geometry_msgs_msg_dds__TwistStamped__desc, name, NULL, NULL);
    const dds_entity_t w = dds_create_writer(pp, tp, NULL, NULL);
    assert_true(w > 0);
    geometry_msgs_msg_dds__TwistStamped_ m;
    memset(&m, 0, sizeof m);
    m.header.frame_id = "world";
    m.twist.linear.x = 0.1;
    for (int i = 0; i < 400 && tg.accepted == 0; ++i) { /* until the bridge's reader matched */
        dds_write(w, &m);
        const struct timespec nap = {0, 10 * 1000 * 1000};
        nanosleep(&nap, NULL);
        assert_int_equal(mca_dds_bridge_stream_target(b, 0, &tg), MCA_OK);
    }
    assert_true(tg.accepted >= 1);
    assert_true(tg.x[0] == 0.1 && tg.kind == MCA_ROS2_STREAM_TWIST);
    nanosleep(&(struct timespec){0, 50 * 1000 * 1000}, NULL);
    assert_int_equal(mca_dds_bridge_stream_target(b, 0, &tg),
                     MCA_OK); /* settled: the writes in flight are in */
    const mca_ros2_target_t before = tg;

    mca_dds_stats_t st;
    mca_dds_bridge_stats(b, &st);
    assert_int_equal(kill(st.pid, CRASH_SIGNAL), 0);
    for (int i = 0; i < 1000 && st.deaths == 0; ++i) {
        mca_dds_bridge_supervise(b, NULL, NULL);
        mca_dds_bridge_stats(b, &st);
        nanosleep(&(struct timespec){0, 2 * 1000 * 1000}, NULL);
    }
    assert_int_equal(st.deaths, 1);
    /* down: the last target is still there, as old as it was */
    assert_int_equal(mca_dds_bridge_stream_target(b, 0, &tg), MCA_OK);
    assert_int_equal(tg.accepted, before.accepted);
    assert_int_equal(tg.recv_ns, before.recv_ns);
    assert_true(tg.x[0] == 0.1);
    for (int i = 0; i < 1500 && (st.pid == 0 || st.restarts == 0); ++i) {
        mca_dds_bridge_supervise(b, NULL, NULL);
        mca_dds_bridge_stats(b, &st);
        nanosleep(&(struct timespec){0, 2 * 1000 * 1000}, NULL);
    }
    assert_int_equal(st.restarts, 1);
    m.twist.linear.x = 0.2;
    for (int i = 0; i < 500 && tg.x[0] != 0.2; ++i) { /* the restarted bridge's reader matches */
        dds_write(w, &m);
        nanosleep(&(struct timespec){0, 10 * 1000 * 1000}, NULL);
        mca_dds_bridge_supervise(b, NULL, NULL);
        assert_int_equal(mca_dds_bridge_stream_target(b, 0, &tg), MCA_OK);
    }
    assert_true(tg.x[0] == 0.2);
    assert_true(tg.accepted > before.accepted); /* counted on, not from 0 */
    assert_true(tg.recv_ns > before.recv_ns);
    print_message("target accepted %llu before the death, %llu after the restart\n",
                  (unsigned long long)before.accepted, (unsigned long long)tg.accepted);
    mca_dds_bridge_destroy(b, NULL);
    dds_delete(pp);
}

/* Process mode: a bridge that is alive but publishes nothing while snapshots wait (here: SIGSTOP, as a
 * deadlock inside Cyclone would look) is killed after MCA_DDS_BRIDGE_HUNG_S and restarted. */
static void test_process_mode_hung_bridge_killed(void **state) {
    (void)state;
    if (g_bridge_exe == NULL) {
        skip();
    }
    mca_dds_config_t cfg;
    mca_dds_config_default(&cfg);
    cfg.domain_id = g_domain;
    cfg.partition = g_partition;
    cfg.process_exe = g_bridge_exe;
    mca_dds_bridge_t *b = NULL;
    char err[320] = ""; /* mca_dds_bridge_create's reason */
    assert_int_equal(mca_dds_bridge_create(&b, &cfg, err, sizeof err), MCA_OK);
    static mca_dds_snapshot_t snap;
    double mn = INFINITY;
    int64_t ms = 0;
    uint64_t k = 0;
    mca_dds_stats_t st;
    mca_dds_bridge_stats(b, &st);
    const int pid0 = st.pid;
    char logbuf[4096] = "";
    FILE *log = fmemopen(logbuf, sizeof logbuf - 1, "w");
    assert_non_null(log);
    setvbuf(log, NULL, _IONBF, 0);
    mca_dds_synth_fill(&snap, k, (int64_t)(1000 + k), &mn, &ms);
    mca_dds_bridge_push(b, &snap);
    k++;
    assert_true(wait_published(b, 1, &st));
    mca_dds_bridge_supervise(b, test_log_line, log); /* starts the hang watch */
    assert_int_equal(kill(pid0, SIGSTOP), 0);
    struct timespec t0, now;
    clock_gettime(CLOCK_MONOTONIC, &t0);
    double hung_after = -1.0;
    for (int i = 0; i < 1000 && st.restarts == 0; ++i) { /* 10 s at most */
        mca_dds_synth_fill(&snap, k, (int64_t)(1000 + k), &mn, &ms);
        mca_dds_bridge_push(b, &snap);
        k++;
        mca_dds_bridge_supervise(b, test_log_line, log);
        mca_dds_bridge_stats(b, &st);
        if (hung_after < 0.0 && st.hung > 0) {
            clock_gettime(CLOCK_MONOTONIC, &now);
            hung_after = (double)(now.tv_sec - t0.tv_sec) + 1e-9 * (double)(now.tv_nsec - t0.tv_nsec);
        }
        nanosleep(&(struct timespec){0, 10 * 1000 * 1000}, NULL);
    }
    print_message("%skilled as hung %.2f s after SIGSTOP\n", logbuf, hung_after);
    assert_int_equal(st.hung, 1);
    assert_true(hung_after >= MCA_DDS_BRIDGE_HUNG_S && hung_after < MCA_DDS_BRIDGE_HUNG_S + 2.0);
    assert_non_null(strstr(logbuf, "hung: nothing published for"));
    assert_non_null(strstr(logbuf, "died: signal 9 (SIGKILL); restart 1 in 0.1 s"));
    assert_int_equal(st.deaths, 1);
    assert_int_equal(st.restarts, 1);
    const uint64_t published = st.published;
    for (int i = 0; i < 500 && st.published == published; ++i) { /* the restarted one publishes */
        mca_dds_bridge_supervise(b, test_log_line, log);
        mca_dds_bridge_stats(b, &st);
        nanosleep(&(struct timespec){0, 10 * 1000 * 1000}, NULL);
    }
    assert_true(st.published > published);
    mca_dds_bridge_destroy(b, &st);
    fclose(log);
}

/* Issue 32: a bridge that dies at every start (a peer that crashes libddsc 0.10.2 stays on the network) is
 * restarted for as long as its owner runs: a capped exponential back-off (0.1, 0.2, 0.4, 0.8, 1.6, 2.0, 2.0
 * s), never a last restart; the log says each of the first MCA_DDS_BRIDGE_LOG_ALL deaths and then thins out;
 * the counters say down / backing off; once the deaths stop, it publishes again. */
static void test_process_mode_never_gives_up(void **state) {
    (void)state;
    if (g_bridge_exe == NULL) {
        skip();
    }
    mca_dds_config_t cfg;
    mca_dds_config_default(&cfg);
    cfg.domain_id = g_domain;
    cfg.partition = g_partition;
    cfg.process_exe = g_bridge_exe;
    mca_dds_bridge_t *b = NULL;
    char err[320] = "";
    assert_int_equal(mca_dds_bridge_create(&b, &cfg, err, sizeof err), MCA_OK);
    static char logbuf[16384];
    logbuf[0] = '\0';
    FILE *log = fmemopen(logbuf, sizeof logbuf - 1, "w");
    assert_non_null(log);
    setvbuf(log, NULL, _IONBF, 0);
    static mca_dds_snapshot_t snap;
    double mn = INFINITY;
    int64_t ms = 0;
    uint64_t k = 0;
    mca_dds_stats_t st;
    mca_dds_bridge_stats(b, &st);
    const double want[] = {0.1, 0.2, 0.4, 0.8, 1.6, 2.0, 2.0};
    const int n_kills = (int)(sizeof want / sizeof want[0]); /* more than the 5 after which it once gave up */
    for (int n = 0; n < n_kills; n++) {
        /* the running publisher (the first, or the n-th restart) dies */
        for (int i = 0; i < 1500 && (st.pid == 0 || st.restarts != (uint64_t)n); ++i) {
            mca_dds_bridge_supervise(b, test_log_line, log);
            mca_dds_bridge_stats(b, &st);
            nanosleep(&(struct timespec){0, 2 * 1000 * 1000}, NULL);
        }
        assert_true(st.pid > 0);
        assert_int_equal(st.restarts, (uint64_t)n);
        for (int i = 0; i < 150; ++i) { /* it makes its DDS entities (as with the peer: ~0.5 s, then dies) */
            mca_dds_bridge_supervise(b, test_log_line, log);
            nanosleep(&(struct timespec){0, 2 * 1000 * 1000}, NULL);
        }
        assert_int_equal(kill(st.pid, CRASH_SIGNAL), 0);
        for (int i = 0; i < 1500 && st.deaths == (uint64_t)n; ++i) {
            mca_dds_bridge_supervise(b, test_log_line, log);
            mca_dds_bridge_stats(b, &st);
            nanosleep(&(struct timespec){0, 2 * 1000 * 1000}, NULL);
        }
        assert_int_equal(st.deaths, (uint64_t)n + 1);
        assert_true(st.down);
        assert_int_equal(st.deaths_in_a_row, (uint32_t)n + 1);
        assert_true(fabs(st.backoff_s - want[n]) < 1e-9);
        mca_dds_synth_fill(&snap, k, (int64_t)(1000 + k), &mn, &ms); /* the loop pushes on meanwhile */
        mca_dds_bridge_push(b, &snap);
        k++;
    }
    /* the last one is restarted too and publishes */
    const uint64_t published = st.published;
    for (int i = 0; i < 1500 && (st.published == published || st.pid == 0); ++i) {
        mca_dds_synth_fill(&snap, k, (int64_t)(1000 + k), &mn, &ms);
        mca_dds_bridge_push(b, &snap);
        k++;
        mca_dds_bridge_supervise(b, test_log_line, log);
        mca_dds_bridge_stats(b, &st);
        nanosleep(&(struct timespec){0, 5 * 1000 * 1000}, NULL);
    }
    print_message("%s", logbuf);
    assert_true(st.pid > 0 && !st.down);
    assert_int_equal(st.restarts, (uint64_t)n_kills);
    assert_true(st.published > published);
    /* the first MCA_DDS_BRIDGE_LOG_ALL deaths are logged, the 6th and 7th not (the 30th would be) */
    int died = 0, restarted = 0;
    for (const char *p = logbuf; (p = strstr(p, ") died: ")) != NULL; p++) {
        died++;
    }
    for (const char *p = logbuf; (p = strstr(p, "dds bridge restarted: pid")) != NULL; p++) {
        restarted++;
    }
    assert_int_equal(died, MCA_DDS_BRIDGE_LOG_ALL);
    assert_int_equal(restarted, MCA_DDS_BRIDGE_LOG_ALL);
    /* after the thinned-out ones, a publisher that lives is said to be up (after MCA_DDS_BRIDGE_UP_S) */
    for (int i = 0; i < 1500 && strstr(logbuf, "dds bridge up again") == NULL; ++i) {
        mca_dds_bridge_supervise(b, test_log_line, log);
        nanosleep(&(struct timespec){0, 5 * 1000 * 1000}, NULL);
    }
    print_message("%s", strstr(logbuf, "dds bridge up again") ? strstr(logbuf, "dds bridge up again") : "");
    assert_non_null(strstr(logbuf, "has lived 5 s after 7 deaths in a row, publishing"));
    assert_non_null(strstr(logbuf, "restart 5 in 1.6 s (5 deaths in a row"));
    assert_non_null(strstr(logbuf, "it is restarted for as long as mcad runs"));
    assert_null(strstr(logbuf, "stays down"));
    mca_dds_bridge_destroy(b, &st);
    assert_false(st.down); /* up at the end */
    fclose(log);
}

int main(int argc, char **argv) {
    if (argc != 3 && argc != 4) {
        fprintf(stderr, "usage: test_dds_bridge LOOPBACK_XML DOMAIN [MCA_DDS_BRIDGE]\n");
        return 2;
    }
    g_bridge_exe = argc == 4 ? argv[3] : NULL;
    g_config = argv[1];
    g_domain = (uint32_t)strtoul(argv[2], NULL, 10);
    snprintf(g_partition, sizeof g_partition, "mca-test-bridge-%ld", (long)getpid());
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_create_rejects_bad_arguments),
        cmocka_unit_test(test_create_rejects_bad_xml),
        cmocka_unit_test(test_every_snapshot_arrives_intact),
        cmocka_unit_test(test_publisher_parks_and_wakes),
        cmocka_unit_test(test_publisher_wakes_on_grid),
        cmocka_unit_test(test_publisher_priority),
        cmocka_unit_test(test_overrun_drops_oldest_and_counts),
        cmocka_unit_test(test_partition_isolates),
        cmocka_unit_test(test_invalid_snapshot_rejected),
        cmocka_unit_test(test_brake_factor_eq13),
        cmocka_unit_test(test_pair_fill_from_armdist),
        cmocka_unit_test(test_process_mode_restart),
        cmocka_unit_test(test_process_mode_stream_target_survives),
        cmocka_unit_test(test_process_mode_hung_bridge_killed),
        cmocka_unit_test(test_process_mode_never_gives_up),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
