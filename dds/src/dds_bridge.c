/* SPDX-License-Identifier: MIT */
/* DDS bridge: rt loop -> SPSC drop-oldest ring -> publisher -> Cyclone DDS writers. The publisher is a thread
 * of the caller (in-process mode) or the program mca-dds-bridge (process mode: a crash in Cyclone
 * cannot take the loop's process with it); both run the same code below over the same shared region
 * (dds_shm.h). The publisher parks on a futex when the ring is empty; a push wakes it only when it is parked.
 */
#include "mca/dds_bridge.h"

#include <errno.h>
#include <fcntl.h> /* F_ADD_SEALS */
#include <limits.h>
#include <linux/futex.h> /* FUTEX_WAIT, FUTEX_WAKE (shared: the word may be in a memfd) */
#include <math.h>
#include <pthread.h>
#include <sched.h>  /* SCHED_FIFO */
#include <signal.h> /* kill */
#include <stdarg.h> /* va_list: tell */
#include <spawn.h>  /* posix_spawn: vfork semantics, no copy-on-write of the owner's locked memory */
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>    /* memfd_create, mmap */
#include <sys/prctl.h>   /* PR_SET_TIMERSLACK */
#include <sys/syscall.h> /* SYS_futex */
#include <sys/wait.h>    /* waitpid */
#include <time.h>
#include <unistd.h> /* syscall */

#include "dds__supervise.h" /* mca_dds_backoff_s, mca_dds_describe_status, mca_dds_log_this_death */
#include "dds_shm.h"
#include "mca/dds_qos.h"
#include "mca/err.h"
#include "mca/errbuf.h" /* mca_errbuf_printf: reasons into the caller's buffer */
#include "mca/ring.h"
#include "mca/scheme.h" /* mca_brake_s: S(d) */
#include "mca_dds.h"    /* idlc output: mca_dds_JointState, ... */
#include "ros2_pub.h"

extern char **environ;

enum { W_STATE, W_COMMAND, W_DIST, W_STATUS, W_PAIRS, W_COUNT };
static const char *const topic_names[W_COUNT] = {MCA_DDS_TOPIC_JOINT_STATE, MCA_DDS_TOPIC_JOINT_COMMAND,
                                                 MCA_DDS_TOPIC_DISTANCES, MCA_DDS_TOPIC_STATUS,
                                                 MCA_DDS_TOPIC_PAIR_DISTANCES};

/* The publisher: DDS entities and its working state, in the process that publishes. */
typedef struct publisher {
    mca_dds_shm_t *shm;
    int process; /* 1: in mca-dds-bridge */
    void (*fault_text)(void *arg, const mca_dds_status_snapshot_t *st, char *text, size_t len);
    void *fault_text_arg;
    dds_entity_t domain, participant;
    dds_entity_t topic[W_COUNT], writer[W_COUNT];
    mca_ros2_pub_t *ros2; /* NULL: no ROS 2 topics */
    mca_dds_snapshot_t work;
    int have_status;
    mca_dds_status_snapshot_t last_status;
    uint64_t last_tick;
    int64_t last_stamp;
    uint64_t since_status;
    int32_t waited_code; /* the fault code whose text it waited for once already */
} publisher_t;

/* The owner's handle. */
struct mca_dds_bridge {
    mca_dds_shm_t *shm; /* heap (in-process) or the memfd mapping (process) */
    size_t shm_size;
    int process;
    /* owner-private copies: the loop reads no size, index bound or address from memory a bridge can write */
    mca_ring_producer_t producer;
    int n_stream_arms;
    int stream_kind[MCA_MAX_ARMS];
    /* in-process */
    publisher_t *pub;
    pthread_t thread;
    int thread_started;
    /* process mode (the owner's supervising thread only) */
    int memfd;
    char exe[PATH_MAX];
    pid_t pid;           /* the running publisher, 0: none */
    int quick_deaths;    /* deaths in a row, each within MCA_DDS_BRIDGE_STABLE_S of its start */
    double started_s;    /* when the running publisher was started */
    double next_start_s; /* when to restart it (pid 0) */
    double backoff_s;    /* the last back-off [s] */
    int up_logged;       /* a thinned-out series: its publisher's "up for a while" line was written */
    int stopped;         /* destroy began: up_at_stop says whether a publisher was alive then */
    int up_at_stop;
    double stop_s;
    uint32_t announced; /* generation whose readiness was logged */
    uint64_t deaths;
    uint64_t hung;          /* publishers killed for making no progress */
    uint64_t seen_progress; /* published + invalid + stale when last looked at */
    double progress_s;      /* when it last made progress (or had nothing to do); 0: not yet looked */
};

static void bump(_Atomic uint64_t *c) {
    /* Single writer per counter: load + store, no locked instruction. */
    atomic_store_explicit(c, atomic_load_explicit(c, memory_order_relaxed) + 1u, memory_order_relaxed);
}

static double mono_s(void) {
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + (double)ts.tv_nsec * 1e-9;
}

/* The wire's ControllerStatus.state carries mca_dds_state_t values as int32 (the IDL's comment says why
 * not the enum type): the IDL's enumerators must have the same values. */
_Static_assert(MCA_DDS_STATE_INIT == (int)mca_dds_STATE_INIT &&
                   MCA_DDS_STATE_READY == (int)mca_dds_STATE_READY &&
                   MCA_DDS_STATE_RUNNING == (int)mca_dds_STATE_RUNNING &&
                   MCA_DDS_STATE_BRAKING == (int)mca_dds_STATE_BRAKING &&
                   MCA_DDS_STATE_STOPPED == (int)mca_dds_STATE_STOPPED &&
                   MCA_DDS_STATE_FAULT == (int)mca_dds_STATE_FAULT,
               "mca_dds_state_t and the IDL's ControllerState number the states alike");

const char *mca_dds_state_name(int state) {
    static const char *const names[] = {"init", "ready", "running", "braking", "stopped", "fault"};
    _Static_assert(sizeof names / sizeof names[0] == MCA_DDS_STATE_FAULT + 1, "a name per state");
    return state >= MCA_DDS_STATE_INIT && state <= MCA_DDS_STATE_FAULT ? names[state] : NULL;
}

void mca_dds_config_default(mca_dds_config_t *cfg) {
    if (cfg == NULL) {
        return;
    }
    memset(cfg, 0, sizeof *cfg);
    cfg->domain_id = 0;
    cfg->config_path = NULL;
    cfg->ring_capacity = 1024; /* 1 s of publisher stall at 1 kHz, 7.5 MB */
    cfg->status_divisor = 100;
    cfg->controller_id = 0;
    cfg->frame_id = "world";
}

int mca_dds_pair_fill(mca_dds_pair_snapshot_t *out, const mca_arm_distances_t *dist, uint8_t arm_a,
                      uint8_t arm_b, double d1, double d2) {
    if (out == NULL || dist == NULL || dist->n_links_a < 0 || dist->n_links_a > MCA_MAX_LINKS ||
        dist->n_links_b < 0 || dist->n_links_b > MCA_MAX_LINKS || !(d1 >= 0.0 && d1 < d2)) {
        return MCA_EINVAL;
    }
    out->arm_a = arm_a;
    out->arm_b = arm_b;
    out->link_a = (int16_t)dist->min.link;
    out->link_b = (int16_t)dist->min.other_link;
    out->min_distance = dist->min.d;
    memcpy(out->p, dist->min.p, sizeof out->p);
    memcpy(out->e, dist->min.e, sizeof out->e);
    out->d1 = d1;
    out->d2 = d2;
    out->brake_factor = mca_brake_s(dist->min.d, d1, d2); /* core's S(d), eq. (13): one definition */
    out->n_links_a = (uint32_t)dist->n_links_a;
    out->n_links_b = (uint32_t)dist->n_links_b;
    for (int l = 0; l < dist->n_links_a; ++l) {
        out->link_distance_a[l] = dist->a_to_b[l].d;
    }
    for (int l = 0; l < dist->n_links_b; ++l) {
        out->link_distance_b[l] = dist->b_to_a[l].d;
    }
    return MCA_OK;
}

static dds_sequence_double seq_of(double *buf, uint32_t n) {
    dds_sequence_double s = {._maximum = n, ._length = n, ._buffer = buf, ._release = false};
    return s;
}

static int snapshot_valid(const mca_dds_snapshot_t *s) {
    if (s->n_arms > MCA_MAX_ARMS || s->n_pairs > MCA_MAX_PAIRS || s->n_named > MCA_DDS_MAX_PAIR_ENTRIES) {
        return 0;
    }
    for (uint32_t i = 0; i < s->n_arms; ++i) {
        if (s->arm[i].n_dof > MCA_MAX_DOF) {
            return 0;
        }
    }
    for (uint32_t k = 0; k < s->n_pairs; ++k) {
        if (s->pair[k].n_links_a > MCA_MAX_LINKS || s->pair[k].n_links_b > MCA_MAX_LINKS) {
            return 0;
        }
    }
    return 1;
}

static void add(_Atomic uint64_t *c, uint64_t n) {
    atomic_store_explicit(c, atomic_load_explicit(c, memory_order_relaxed) + n, memory_order_relaxed);
}

static void write_one(publisher_t *b, int w, const void *sample) {
    if (dds_write(b->writer[w], sample) < 0) {
        bump(&b->shm->write_errors);
    } else {
        bump(&b->shm->samples);
    }
}

/* The text of a status's fault: the owner's (mca_dds_bridge_fault_text), else the in-process callback. In
 * mca-dds-bridge the owner's supervising thread hands it over a few ms after the fault reached its log, so a
 * publisher that sees the fault first waits for it, at most 200 ms, once per fault (non-rt); a text that
 * never comes leaves the field empty. */
static void fault_text_for(publisher_t *b, const mca_dds_status_snapshot_t *st, char *text, size_t len) {
    mca_dds_shm_t *shm = b->shm;
    for (int waited = 0;; waited += 5) {
        if (atomic_load_explicit(&shm->fault_code, memory_order_acquire) == st->fault_code) {
            snprintf(text, len, "%.*s", MCA_DDS_FAULT_TEXT_MAX, shm->fault_text);
            return;
        }
        if (b->fault_text != NULL) {
            b->fault_text(b->fault_text_arg, st, text, len);
            return;
        }
        if (!b->process || waited >= 200 || b->waited_code == st->fault_code) {
            b->waited_code = st->fault_code; /* once per fault: never 200 ms for every status */
            return;
        }
        const struct timespec nap = {0, 5 * 1000 * 1000};
        nanosleep(&nap, NULL);
    }
}

static void write_status(publisher_t *b) {
    const mca_dds_status_snapshot_t *st = &b->last_status;
    mca_ring_stats_t rs;
    mca_ring_stats(&b->shm->ring, &rs);
    mca_dds_ControllerStatus m;
    memset(&m, 0, sizeof m);
    m.controller_id = b->shm->cfg.controller_id;
    m.tick = b->last_tick;
    m.stamp_ns = b->last_stamp;
    m.state = (int32_t)st->state;
    m.fault_code = st->fault_code;
    memcpy(m.fault_text, st->fault_text, sizeof m.fault_text - 1);
    m.fault_text[sizeof m.fault_text - 1] = '\0';
    if (m.fault_code != 0 && m.fault_text[0] == '\0') {
        /* the owner's rt side latched a code and numbers: the text is made off the rt path */
        fault_text_for(b, st, m.fault_text, sizeof m.fault_text);
        m.fault_text[sizeof m.fault_text - 1] = '\0';
    }
    m.ticks = st->ticks;
    m.overruns = st->overruns;
    m.skipped_periods = st->skipped_periods;
    m.compute_p50_ns = st->compute_p50_ns;
    m.compute_p99_ns = st->compute_p99_ns;
    m.compute_max_ns = st->compute_max_ns;
    m.jitter_p50_ns = st->jitter_p50_ns;
    m.jitter_p99_ns = st->jitter_p99_ns;
    m.jitter_p999_ns = st->jitter_p999_ns;
    m.jitter_max_ns = st->jitter_max_ns;
    m.pdnn_steps = st->pdnn_steps;
    m.pdnn_residual = st->pdnn_residual;
    m.min_distance_so_far = st->min_distance_so_far;
    m.min_distance_stamp_ns = st->min_distance_stamp_ns;
    m.snapshots_dropped = rs.dropped;
    m.pdnn_budget_hits = st->pdnn_budget_hits;
    write_one(b, W_STATUS, &m);
    if (b->ros2 != NULL) {
        uint64_t errors = 0;
        const mca_dds_shm_t *shm = b->shm;
        const int64_t death_ns = atomic_load_explicit(&shm->last_death_ns, memory_order_acquire);
        struct timespec ts;
        clock_gettime(CLOCK_MONOTONIC, &ts);
        const int64_t now_ns = (int64_t)ts.tv_sec * 1000000000 + ts.tv_nsec;
        char last_death[sizeof shm->last_death];
        memcpy(last_death, shm->last_death, sizeof last_death); /* written before this publisher started */
        last_death[sizeof last_death - 1] = '\0';
        const mca_ros2_bridge_health_t h = {
            .restarts = atomic_load_explicit(&shm->restarts, memory_order_relaxed),
            .deaths = atomic_load_explicit(&shm->deaths, memory_order_relaxed),
            .deaths_in_a_row = atomic_load_explicit(&shm->deaths_in_a_row, memory_order_relaxed),
            .backoff_s = atomic_load_explicit(&shm->backoff_ms, memory_order_relaxed) / 1e3,
            .since_death_s = death_ns > 0 ? (double)(now_ns - death_ns) / 1e9 : -1.0,
            .last_death = last_death,
        };
        add(&b->shm->samples, (uint64_t)mca_ros2_pub_status(b->ros2, &m, &h, &errors));
        add(&b->shm->write_errors, errors);
    }
    b->since_status = 0;
}

static void publish(publisher_t *b, mca_dds_snapshot_t *s) {
    if (!snapshot_valid(s)) {
        bump(&b->shm->invalid);
        return;
    }
    /* Distances first: the safety picture is what subscribers wait for (tick -> monitor latency) */
    for (uint32_t k = 0; k < s->n_pairs; ++k) {
        mca_dds_pair_snapshot_t *p = &s->pair[k];
        mca_dds_Distances d = {
            .pair_id = (uint8_t)k,
            .arm_a = p->arm_a,
            .arm_b = p->arm_b,
            .tick = s->tick,
            .stamp_ns = s->stamp_ns,
            .min_distance = p->min_distance,
            .link_a = p->link_a,
            .link_b = p->link_b,
            .d1 = p->d1,
            .d2 = p->d2,
            .brake_factor = p->brake_factor,
            .link_distance_a = seq_of(p->link_distance_a, p->n_links_a),
            .link_distance_b = seq_of(p->link_distance_b, p->n_links_b),
        };
        memcpy(d.p, p->p, sizeof d.p);
        memcpy(d.e, p->e, sizeof d.e);
        write_one(b, W_DIST, &d);
    }
    {
        /* every pair of every kind, named: one sample per snapshot (the publisher's own copy, so no bound
         * buffer outlives it) */
        mca_dds_PairDistance e[MCA_DDS_MAX_PAIR_ENTRIES];
        for (uint32_t k = 0; k < s->n_named; ++k) {
            const mca_dds_named_pair_t *n = &s->named[k];
            e[k] = (mca_dds_PairDistance){.kind = n->kind,
                                          .arm = n->arm,
                                          .link = n->link,
                                          .other_arm = n->other_arm,
                                          .other_link = n->other_link,
                                          .body = n->body,
                                          .distance = n->distance,
                                          .clearance = n->clearance};
            memcpy(e[k].name, n->name, sizeof e[k].name);
            e[k].name[sizeof e[k].name - 1] = '\0';
            memcpy(e[k].p, n->p, sizeof e[k].p);
            memcpy(e[k].q, n->q, sizeof e[k].q);
        }
        const mca_dds_PairDistances pd = {
            .controller_id = b->shm->cfg.controller_id,
            .tick = s->tick,
            .stamp_ns = s->stamp_ns,
            .pairs = {._maximum = s->n_named, ._length = s->n_named, ._buffer = e, ._release = false},
        };
        write_one(b, W_PAIRS, &pd);
    }
    for (uint32_t i = 0; i < s->n_arms; ++i) {
        mca_dds_arm_snapshot_t *a = &s->arm[i];
        const mca_dds_JointState js = {
            .arm_id = (uint8_t)i,
            .tick = s->tick,
            .stamp_ns = s->stamp_ns,
            .position = seq_of(a->position, a->n_dof),
            .velocity = seq_of(a->velocity, a->n_dof),
            .effort = seq_of(a->effort, a->n_dof),
        };
        write_one(b, W_STATE, &js);
        mca_dds_JointCommand jc = {
            .arm_id = (uint8_t)i,
            .tick = s->tick,
            .stamp_ns = s->stamp_ns,
            .velocity_setpoint = seq_of(a->velocity_setpoint, a->n_dof),
            .position_reference = seq_of(a->position_reference, a->n_dof),
        };
        memcpy(jc.frame_id, b->shm->cfg.frame_id, sizeof jc.frame_id);
        write_one(b, W_COMMAND, &jc);
    }
    if (b->ros2 != NULL) {
        uint64_t errors = 0;
        add(&b->shm->samples, (uint64_t)mca_ros2_pub_snapshot(b->ros2, s, &errors));
        add(&b->shm->write_errors, errors);
    }
    const int changed = !b->have_status || s->status.state != b->last_status.state ||
                        s->status.fault_code != b->last_status.fault_code;
    b->last_status = s->status;
    b->last_status.fault_text[MCA_DDS_FAULT_TEXT_MAX] = '\0';
    b->last_tick = s->tick;
    b->last_stamp = s->stamp_ns;
    b->have_status = 1;
    if (changed || ++b->since_status >= b->shm->cfg.status_divisor) {
        write_status(b);
    }
    bump(&b->shm->published);
}

/* Shared futex operations (no FUTEX_PRIVATE_FLAG): the word may be in a memfd two processes map. */
static long futex(_Atomic uint32_t *addr, int op, uint32_t val) {
    return syscall(SYS_futex, (uint32_t *)addr, op, val, NULL, NULL, 0);
}

/* Publisher side of the park/wake protocol: sleep until a push (or destroy) bumps wake_seq. Sets `parked`
 * and re-checks the ring after a full fence; the pusher stores into the ring, fences and then reads
 * `parked`: one of the two sees the other (no lost wake-up). A bump between the re-check and the sleep
 * makes FUTEX_WAIT return at once (the value differs from `seen`). */
static void park(mca_dds_shm_t *shm) {
    const uint32_t seen = atomic_load_explicit(&shm->wake_seq, memory_order_acquire);
    atomic_store_explicit(&shm->parked, 1, memory_order_relaxed);
    atomic_thread_fence(memory_order_seq_cst);
    mca_ring_stats_t rs;
    mca_ring_stats(&shm->ring, &rs);
    if (rs.pending == 0 && !atomic_load_explicit(&shm->stop, memory_order_acquire)) {
        bump(&shm->parks);
        futex(&shm->wake_seq, FUTEX_WAIT, seen); /* EAGAIN / EINTR: look again */
    }
    atomic_store_explicit(&shm->parked, 0, memory_order_relaxed);
}

static void wake(mca_dds_shm_t *shm) {
    atomic_fetch_add_explicit(&shm->wake_seq, 1u, memory_order_release);
    futex(&shm->wake_seq, FUTEX_WAKE, 1);
}

/* wake_period_ns: sleep until the next publishing tick of the caller's grid has pushed (the last
 * snapshot's due time + period + offset), unless that is already past or the ring is not empty. Anchored
 * on the due time, not the stamp: the stamp carries that tick's wake-up jitter, which the next tick does
 * not share (the offset had to cover both ticks' jitter). */
static void sleep_on_grid(mca_dds_shm_t *shm, int64_t due_ns) {
    mca_ring_stats_t rs;
    mca_ring_stats(&shm->ring, &rs);
    if (rs.pending > 0 || atomic_load_explicit(&shm->stop, memory_order_acquire)) {
        return;
    }
    struct timespec now;
    clock_gettime(CLOCK_MONOTONIC, &now);
    const int64_t t_now = (int64_t)now.tv_sec * 1000000000LL + now.tv_nsec;
    const int64_t step = (int64_t)(shm->cfg.wake_period_ns + shm->cfg.wake_offset_ns);
    int64_t target = due_ns + step;
    if (target <= t_now) {
        return; /* late already: look now, park if nothing is there */
    }
    if (target > t_now + step) {
        target = t_now + step; /* a stamp not on this clock: never sleep longer than one period */
    }
    bump(&shm->grid_sleeps);
    const struct timespec ts = {(time_t)(target / 1000000000LL), (long)(target % 1000000000LL)};
    while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, NULL) == EINTR) {
    }
}

static void publish_timed(publisher_t *b) {
    struct timespec t0, t1;
    clock_gettime(CLOCK_MONOTONIC, &t0);
    publish(b, &b->work);
    clock_gettime(CLOCK_MONOTONIC, &t1);
    const int64_t dt = (t1.tv_sec - t0.tv_sec) * 1000000000LL + (t1.tv_nsec - t0.tv_nsec);
    if (dt > atomic_load_explicit(&b->shm->max_publish_ns, memory_order_relaxed)) {
        atomic_store_explicit(&b->shm->max_publish_ns, dt, memory_order_relaxed);
    }
}

/* A publisher (re)started while the loop already pushes (mca-dds-bridge): what the ring holds is the backlog
 * of the time it was down. Publish only the newest snapshot, at once (with it the current status, written
 * because it is this publisher's first), and count the older ones as stale. */
static void skip_backlog(publisher_t *b) {
    uint64_t n = 0;
    while (mca_ring_pop(&b->shm->ring, &b->work) == MCA_OK) {
        n++;
    }
    if (n > 0) {
        add(&b->shm->stale, n - 1u);
        publish_timed(b);
    }
}

static void publisher_run(publisher_t *b) {
    mca_dds_shm_t *shm = b->shm;
    /* wake at the grid point itself, not up to 50 us later (the default slack of a normal thread) */
    prctl(PR_SET_TIMERSLACK, 1UL, 0UL, 0UL, 0UL);
    if (b->process) {
        skip_backlog(b);
    }
    for (;;) {
        /* Read stop BEFORE trying the ring: once stop is seen, one more empty pop means drained. */
        const int stop = atomic_load_explicit(&shm->stop, memory_order_acquire);
        if (mca_ring_pop(&shm->ring, &b->work) == MCA_OK) {
            mca_ring_stats_t rs;
            mca_ring_stats(&shm->ring, &rs);
            if (rs.pending + 1u > atomic_load_explicit(&shm->max_pending, memory_order_relaxed)) {
                atomic_store_explicit(&shm->max_pending, rs.pending + 1u, memory_order_relaxed);
            }
            publish_timed(b);
            if (shm->cfg.wake_period_ns > 0) {
                sleep_on_grid(shm, b->work.due_ns != 0 ? b->work.due_ns : b->work.stamp_ns);
            }
            continue;
        }
        if (stop) {
            break;
        }
        park(shm);
    }
}

static void *publisher_thread(void *arg) {
    publisher_run(arg);
    return NULL;
}

static int is_pow2(uint32_t x) {
    return x >= 2 && (x & (x - 1u)) == 0;
}

static void publisher_delete_entities(publisher_t *b) {
    if (b->participant > 0) {
        dds_delete(b->participant); /* deletes topics and writers too */
    }
    if (b->domain > 0) {
        dds_delete(b->domain);
    }
    b->participant = b->domain = 0;
}

/* Participant, topics, writers (and the ROS 2 ones) from shm->cfg. The reason of a failure in err. */
static int publisher_open(publisher_t *b, char *err, size_t errlen) {
    const mca_dds_shm_config_t *cfg = &b->shm->cfg;
    dds_entity_t p = 0;
    const int prc = mca_dds_open_participant(cfg->domain_id, cfg->has_config_path ? cfg->config_path : NULL,
                                             &p, &b->domain, err, errlen);
    if (prc != MCA_OK) {
        return prc;
    }
    b->participant = p;
    const dds_topic_descriptor_t *const descs[W_COUNT] = {
        &mca_dds_JointState_desc, &mca_dds_JointCommand_desc, &mca_dds_Distances_desc,
        &mca_dds_ControllerStatus_desc, &mca_dds_PairDistances_desc};
    dds_qos_t *qs = mca_dds_qos_stream();
    dds_qos_t *qst = mca_dds_qos_status();
    int rc = (qs != NULL && qst != NULL) ? MCA_OK : MCA_ENOMEM;
    dds_entity_t pub = p; /* writers hang off the participant, or a publisher with a partition */
    if (rc == MCA_OK && cfg->has_partition) {
        rc = mca_dds_create_publisher(p, cfg->partition, &pub, err, errlen);
    }
    for (int w = 0; w < W_COUNT && rc == MCA_OK; ++w) {
        const dds_qos_t *q = w == W_STATUS ? qst : qs;
        b->topic[w] = dds_create_topic(p, descs[w], topic_names[w], q, NULL);
        b->writer[w] = b->topic[w] > 0 ? dds_create_writer(pub, b->topic[w], q, NULL) : b->topic[w];
        if (b->writer[w] < 0) {
            mca_errbuf_printf(err, errlen, "cannot create topic/writer '%s': %s", topic_names[w],
                              dds_strretcode(b->writer[w]));
            rc = MCA_EIO;
        }
    }
    dds_delete_qos(qs);
    dds_delete_qos(qst);
    if (rc == MCA_OK && cfg->has_ros2) {
        rc = mca_ros2_pub_create(&b->ros2, p, &cfg->ros2, b->shm->box, &b->shm->tracks, err, errlen);
    }
    if (rc != MCA_OK) {
        publisher_delete_entities(b);
    }
    return rc;
}

/* After the last snapshot: the final status (with the final drop count), acks, entities gone. */
static void publisher_close(publisher_t *b) {
    if (b->have_status) {
        write_status(b);
    }
    for (int w = 0; w < W_COUNT; ++w) {
        if (b->writer[w] > 0) {
            dds_wait_for_acks(b->writer[w], DDS_SECS(1));
        }
    }
    mca_ros2_pub_destroy(b->ros2, DDS_SECS(1));
    b->ros2 = NULL;
    publisher_delete_entities(b);
}

/* ---------------------------------------------------------------- the shared region */

static size_t storage_off(void) {
    return (sizeof(mca_dds_shm_t) + 63u) & ~(size_t)63u;
}

size_t mca_dds_shm_size(uint32_t ring_capacity) {
    const size_t bytes = storage_off() + MCA_RING_STORAGE_SIZE(sizeof(mca_dds_snapshot_t), ring_capacity);
    const size_t page = 4096;
    return (bytes + page - 1u) & ~(page - 1u);
}

static void copy_str(char *dst, size_t len, const char *src) {
    snprintf(dst, len, "%s", src != NULL ? src : "");
}

int mca_dds_shm_init(mca_dds_shm_t *shm, size_t size, const mca_dds_config_t *cfg) {
    if (shm == NULL || cfg == NULL || size < mca_dds_shm_size(cfg->ring_capacity)) {
        return MCA_EINVAL;
    }
    shm->magic = MCA_DDS_SHM_MAGIC;
    shm->version = MCA_DDS_SHM_VERSION;
    shm->size = size;
    mca_dds_shm_config_t *c = &shm->cfg;
    c->domain_id = cfg->domain_id;
    c->ring_capacity = cfg->ring_capacity;
    c->status_divisor = cfg->status_divisor;
    c->controller_id = cfg->controller_id;
    c->has_config_path = cfg->config_path != NULL;
    copy_str(c->config_path, sizeof c->config_path, cfg->config_path);
    copy_str(c->frame_id, sizeof c->frame_id, cfg->frame_id != NULL ? cfg->frame_id : "world");
    c->has_partition = cfg->partition != NULL;
    copy_str(c->partition, sizeof c->partition, cfg->partition);
    c->wake_period_ns = cfg->wake_period_ns;
    c->wake_offset_ns = cfg->wake_offset_ns;
    c->sched_priority = cfg->sched_priority;
    c->has_ros2 = cfg->ros2 != NULL && cfg->ros2->enabled;
    if (c->has_ros2) {
        c->ros2 = *cfg->ros2;
    }
    shm->ring_storage_off = storage_off();
    return mca_ring_init(&shm->ring, (unsigned char *)shm + shm->ring_storage_off,
                         size - shm->ring_storage_off, sizeof(mca_dds_snapshot_t), cfg->ring_capacity);
}

int mca_dds_shm_check(const mca_dds_shm_t *shm, size_t size) {
    if (shm == NULL || size < sizeof *shm || shm->magic != MCA_DDS_SHM_MAGIC ||
        shm->version != MCA_DDS_SHM_VERSION || shm->size != size || !is_pow2(shm->cfg.ring_capacity) ||
        shm->cfg.ring_capacity > MCA_RING_MAX_CAPACITY || shm->cfg.status_divisor == 0 ||
        size < mca_dds_shm_size(shm->cfg.ring_capacity) || shm->ring_storage_off != storage_off() ||
        shm->ring.elem_size != sizeof(mca_dds_snapshot_t) || shm->ring.mask + 1u != shm->cfg.ring_capacity ||
        shm->ring.slots_off != (int64_t)(storage_off() - offsetof(mca_dds_shm_t, ring))) {
        return MCA_EINVAL;
    }
    return MCA_OK;
}

/* The publisher thread SCHED_FIFO at @p prio; only that thread: Cyclone's receive and timed-event threads
 * handle what peers send, and a flood of it at real-time priority would take the CPU from everything else
 * there (mcad's supervisor). 0 or the errno (EPERM without CAP_SYS_NICE / RLIMIT_RTPRIO). */
static int publisher_priority(pthread_t t, int prio) {
    const struct sched_param sp = {.sched_priority = prio};
    return pthread_setschedparam(t, SCHED_FIFO, &sp);
}

int mca_dds_publisher_process(mca_dds_shm_t *shm) {
    publisher_t *b = calloc(1, sizeof *b);
    if (b == NULL) {
        atomic_store_explicit(&shm->open_rc, MCA_ENOMEM, memory_order_release);
        return MCA_ENOMEM;
    }
    b->shm = shm;
    b->process = 1;
    shm->open_err[0] = '\0';
    const int rc = publisher_open(b, shm->open_err, sizeof shm->open_err); /* the owner reports it */
    if (rc == MCA_OK && shm->cfg.sched_priority > 0) {
        /* this thread publishes; Cyclone's threads, created above, keep the caller's policy */
        atomic_store_explicit(&shm->sched_refused,
                              publisher_priority(pthread_self(), shm->cfg.sched_priority) != 0,
                              memory_order_relaxed);
    }
    atomic_store_explicit(&shm->open_rc, rc, memory_order_release);
    atomic_store_explicit(&shm->ready_gen, atomic_load_explicit(&shm->start_gen, memory_order_acquire),
                          memory_order_release);
    if (rc == MCA_OK) {
        publisher_run(b);
        publisher_close(b);
    }
    free(b);
    return rc;
}

/* ---------------------------------------------------------------- the owner's side */

static int config_ok(const mca_dds_config_t *cfg, char *err, size_t errlen) {
    if (cfg->status_divisor == 0 || !is_pow2(cfg->ring_capacity) ||
        cfg->ring_capacity > MCA_RING_MAX_CAPACITY || cfg->domain_id > MCA_DDS_MAX_DOMAIN ||
        cfg->wake_period_ns > 10000000000ULL || cfg->wake_offset_ns > 10000000000ULL) {
        mca_errbuf_printf(
            err, errlen,
            "bad settings (status divisor %u, ring %u, domain %u, wake period %llu ns, offset %llu ns)",
            cfg->status_divisor, cfg->ring_capacity, cfg->domain_id, (unsigned long long)cfg->wake_period_ns,
            (unsigned long long)cfg->wake_offset_ns);
        return MCA_EINVAL;
    }
    const char *frame = cfg->frame_id != NULL ? cfg->frame_id : "world";
    if (strlen(frame) > MCA_DDS_FRAME_ID_MAX) {
        mca_errbuf_printf(err, errlen, "frame id '%s' longer than %d bytes", frame, MCA_DDS_FRAME_ID_MAX);
        return MCA_EINVAL;
    }
    if (cfg->partition != NULL && strlen(cfg->partition) > MCA_DDS_PARTITION_MAX) {
        mca_errbuf_printf(err, errlen, "partition '%s' longer than %d bytes", cfg->partition,
                          MCA_DDS_PARTITION_MAX);
        return MCA_EINVAL;
    }
    if (cfg->config_path != NULL && strlen(cfg->config_path) > MCA_DDS_CONFIG_PATH_MAX) {
        mca_errbuf_printf(err, errlen, "config path longer than %d bytes", MCA_DDS_CONFIG_PATH_MAX);
        return MCA_EINVAL;
    }
    if (cfg->process_exe != NULL && (cfg->process_exe[0] == '\0' || strlen(cfg->process_exe) >= PATH_MAX)) {
        mca_errbuf_printf(err, errlen, "bridge program path empty or longer than %d bytes", PATH_MAX - 1);
        return MCA_EINVAL;
    }
    if (cfg->sched_priority < 0 || cfg->sched_priority > 98) {
        mca_errbuf_printf(err, errlen, "publisher priority %d: must be 0 (the caller's policy) or 1..98",
                          cfg->sched_priority);
        return MCA_EINVAL;
    }
    return MCA_OK;
}

/* Start one publisher process over the region: the memfd as fd 3, every other descriptor of the owner closed
 * (its CAN sockets, CSV, cpu_dma_latency), default signal mask and dispositions (the owner blocks its
 * signals in every thread). posix_spawn runs the child on the caller's stack until exec (CLONE_VFORK): no
 * copy of the owner's locked memory is made and the loop's pages are never write-protected. */
static int spawn_publisher(mca_dds_bridge_t *b, char *err, size_t errlen) {
    char fd_arg[16], owner_arg[24];
    snprintf(fd_arg, sizeof fd_arg, "%d", 3);
    snprintf(owner_arg, sizeof owner_arg, "%ld", (long)getpid());
    char *const argv[] = {b->exe, "--shm-fd", fd_arg, "--owner", owner_arg, NULL};
    posix_spawn_file_actions_t fa;
    posix_spawnattr_t at;
    posix_spawn_file_actions_init(&fa);
    posix_spawnattr_init(&at);
    posix_spawn_file_actions_addopen(&fa, 0, "/dev/null", O_RDONLY, 0);
    posix_spawn_file_actions_adddup2(&fa, b->memfd, 3); /* memfd >= 10: dup2 clears its close-on-exec */
    posix_spawn_file_actions_addclosefrom_np(&fa, 4);
    sigset_t none, all;
    sigemptyset(&none);
    sigfillset(&all);
    sigdelset(&all, SIGKILL);
    sigdelset(&all, SIGSTOP);
    posix_spawnattr_setsigmask(&at, &none);
    posix_spawnattr_setsigdefault(&at, &all);
    posix_spawnattr_setflags(&at, POSIX_SPAWN_SETSIGMASK | POSIX_SPAWN_SETSIGDEF);
    atomic_fetch_add_explicit(&b->shm->start_gen, 1u, memory_order_release);
    pid_t pid = 0;
    const int e = posix_spawn(&pid, b->exe, &fa, &at, argv, environ);
    posix_spawn_file_actions_destroy(&fa);
    posix_spawnattr_destroy(&at);
    if (e != 0) {
        mca_errbuf_printf(err, errlen, "cannot start the bridge program %s: %s", b->exe, strerror(e));
        return e == ENOENT ? MCA_ENOENT : MCA_EIO;
    }
    b->pid = pid;
    b->started_s = mono_s();
    b->progress_s = 0.0; /* the hang watch starts afresh */
    return MCA_OK;
}

/* Wait for the running publisher to exit, up to timeout_s; then SIGKILL. Returns its wait status. */
static int reap(mca_dds_bridge_t *b, double timeout_s) {
    int status = 0;
    const double end = mono_s() + timeout_s;
    while (b->pid > 0) {
        const pid_t r = waitpid(b->pid, &status, WNOHANG);
        if (r == b->pid || (r < 0 && errno != EINTR)) {
            b->pid = 0;
            break;
        }
        if (mono_s() >= end) {
            kill(b->pid, SIGKILL);
            waitpid(b->pid, &status, 0);
            b->pid = 0;
            break;
        }
        const struct timespec nap = {0, 5 * 1000 * 1000};
        nanosleep(&nap, NULL);
    }
    return status;
}

static void free_bridge(mca_dds_bridge_t *b) {
    if (b->process) {
        if (b->shm != NULL) {
            munmap(b->shm, b->shm_size);
        }
        if (b->memfd >= 0) {
            close(b->memfd);
        }
    } else {
        free(b->shm);
        free(b->pub);
    }
    free(b);
}

static int create_process(mca_dds_bridge_t *b) {
    int fd = memfd_create("mca-dds-bridge", MFD_CLOEXEC | MFD_ALLOW_SEALING);
    if (fd < 0) {
        return MCA_EIO;
    }
    b->memfd = fcntl(fd, F_DUPFD_CLOEXEC, 10); /* never 3, the number the child gets it under */
    close(fd);
    if (b->memfd < 0 || ftruncate(b->memfd, (off_t)b->shm_size) != 0) {
        return MCA_EIO;
    }
    /* the size is fixed for good: a publisher cannot shrink it under the loop (SIGBUS) */
    fcntl(b->memfd, F_ADD_SEALS, F_SEAL_SHRINK | F_SEAL_GROW | F_SEAL_SEAL);
    void *p = mmap(NULL, b->shm_size, PROT_READ | PROT_WRITE, MAP_SHARED | MAP_POPULATE, b->memfd, 0);
    if (p == MAP_FAILED) {
        return MCA_ENOMEM;
    }
    b->shm = p;
    return MCA_OK;
}

/* The first publisher process: up within 20 s, or its set-up error. */
static int first_start(mca_dds_bridge_t *b, char *err, size_t errlen) {
    int rc = spawn_publisher(b, err, errlen);
    if (rc != MCA_OK) {
        return rc;
    }
    const uint32_t gen = atomic_load_explicit(&b->shm->start_gen, memory_order_acquire);
    const double end = mono_s() + 20.0;
    for (;;) {
        if (atomic_load_explicit(&b->shm->ready_gen, memory_order_acquire) == gen) {
            rc = atomic_load_explicit(&b->shm->open_rc, memory_order_acquire);
            if (rc != MCA_OK) {
                reap(b, 5.0);
                mca_errbuf_printf(err, errlen, "%.*s", (int)sizeof b->shm->open_err, b->shm->open_err);
            }
            b->announced = gen;
            return rc;
        }
        int status;
        if (waitpid(b->pid, &status, WNOHANG) == b->pid) {
            b->pid = 0;
            mca_errbuf_printf(err, errlen, "the bridge program %s ended at start-up (%s %d)", b->exe,
                              WIFSIGNALED(status) ? "signal" : "status",
                              WIFSIGNALED(status) ? WTERMSIG(status) : WEXITSTATUS(status));
            return MCA_EIO;
        }
        if (mono_s() >= end) {
            mca_errbuf_printf(err, errlen, "the bridge program %s did not come up within 20 s", b->exe);
            reap(b, 0.0);
            return MCA_ETIMEDOUT;
        }
        const struct timespec nap = {0, 2 * 1000 * 1000};
        nanosleep(&nap, NULL);
    }
}

int mca_dds_bridge_create(mca_dds_bridge_t **out, const mca_dds_config_t *cfg, char *err, size_t errlen) {
    char scratch[8]; /* no buffer given: the reasons go nowhere (ros2_pub writes them unconditionally) */
    if (err == NULL || errlen == 0) {
        err = scratch;
        errlen = sizeof scratch;
    }
    mca_errbuf_printf(err, errlen, "%s", "");
    if (out == NULL || cfg == NULL) {
        mca_errbuf_printf(err, errlen, "NULL argument");
        return MCA_EINVAL;
    }
    if (config_ok(cfg, err, errlen) != MCA_OK) {
        return MCA_EINVAL;
    }
    mca_dds_bridge_t *b = calloc(1, sizeof *b);
    if (b == NULL) {
        return MCA_ENOMEM;
    }
    b->memfd = -1;
    b->process = cfg->process_exe != NULL;
    b->shm_size = mca_dds_shm_size(cfg->ring_capacity);
    int rc = MCA_OK;
    if (b->process) {
        snprintf(b->exe, sizeof b->exe, "%s", cfg->process_exe);
        rc = create_process(b);
    } else {
        b->shm = aligned_alloc(4096, b->shm_size);
        b->pub = calloc(1, sizeof *b->pub);
        rc = b->shm != NULL && b->pub != NULL ? MCA_OK : MCA_ENOMEM;
        if (rc == MCA_OK) {
            memset(b->shm, 0, b->shm_size);
        }
    }
    if (rc == MCA_OK) {
        rc = mca_dds_shm_init(b->shm, b->shm_size, cfg);
    }
    if (rc == MCA_OK) {
        mca_ring_producer_init(&b->producer, &b->shm->ring);
    }
    if (rc == MCA_OK && b->shm->cfg.has_ros2) {
        b->n_stream_arms = (int)(cfg->ros2->n_arms <= MCA_MAX_ARMS ? cfg->ros2->n_arms : MCA_MAX_ARMS);
        for (int a = 0; a < b->n_stream_arms; a++) {
            b->stream_kind[a] = cfg->ros2->stream[a];
        }
    }
    if (rc == MCA_OK && b->process) {
        rc = first_start(b, err, errlen);
    } else if (rc == MCA_OK) {
        b->pub->shm = b->shm;
        b->pub->fault_text = cfg->fault_text;
        b->pub->fault_text_arg = cfg->fault_text_arg;
        rc = publisher_open(b->pub, err, errlen);
        if (rc == MCA_OK && pthread_create(&b->thread, NULL, publisher_thread, b->pub) != 0) {
            publisher_close(b->pub);
            rc = MCA_ENOMEM;
        }
        if (rc == MCA_OK && cfg->sched_priority > 0) {
            atomic_store_explicit(&b->shm->sched_refused,
                                  publisher_priority(b->thread, cfg->sched_priority) != 0,
                                  memory_order_relaxed);
        }
        if (rc == MCA_OK) {
            b->thread_started = 1;
            pthread_setname_np(b->thread, "mca-dds-pub");
        }
    }
    if (rc != MCA_OK) {
        free_bridge(b);
        return rc;
    }
    *out = b;
    return MCA_OK;
}

/* mca_ring_part_t ranges are whole words */
_Static_assert(offsetof(mca_dds_snapshot_t, arm) % 8 == 0 && sizeof(mca_dds_arm_snapshot_t) % 8 == 0 &&
                   offsetof(mca_dds_snapshot_t, pair) % 8 == 0 && sizeof(mca_dds_pair_snapshot_t) % 8 == 0 &&
                   offsetof(mca_dds_snapshot_t, named) % 8 == 0 && sizeof(mca_dds_named_pair_t) % 8 == 0 &&
                   offsetof(mca_dds_snapshot_t, status) % 8 == 0,
               "the snapshot's arm, pair and status parts must start on whole words");

void mca_dds_bridge_push(mca_dds_bridge_t *bridge, const mca_dds_snapshot_t *snap) {
    mca_dds_shm_t *shm = bridge->shm;
    bump(&shm->offered);
    /* only the arms and pairs in use (2 arms, 1 pair: 1.6 of 4 kB): the publisher reads no more */
    const size_t n_arms = snap->n_arms < MCA_MAX_ARMS ? snap->n_arms : MCA_MAX_ARMS;
    const size_t n_pairs = snap->n_pairs < MCA_MAX_PAIRS ? snap->n_pairs : MCA_MAX_PAIRS;
    const size_t n_named =
        snap->n_named < MCA_DDS_MAX_PAIR_ENTRIES ? snap->n_named : MCA_DDS_MAX_PAIR_ENTRIES;
    const mca_ring_part_t parts[4] = {
        {0, offsetof(mca_dds_snapshot_t, arm) + n_arms * sizeof snap->arm[0]},
        {offsetof(mca_dds_snapshot_t, pair), n_pairs * sizeof snap->pair[0]},
        {offsetof(mca_dds_snapshot_t, named), n_named * sizeof snap->named[0]},
        {offsetof(mca_dds_snapshot_t, status), sizeof snap->status},
    };
    mca_ring_producer_push_parts(&bridge->producer, snap, parts, 4);
    /* pairs with the fence in park(): the publisher sees the record or we see it parked */
    atomic_thread_fence(memory_order_seq_cst);
    if (atomic_load_explicit(&shm->parked, memory_order_relaxed) &&
        atomic_exchange_explicit(&shm->parked, 0, memory_order_relaxed)) {
        bump(&shm->wakes);
        wake(shm); /* one non-blocking system call */
    }
}

int mca_dds_bridge_stream_target(mca_dds_bridge_t *bridge, int arm, mca_ros2_target_t *out) {
    if (bridge == NULL || out == NULL || arm < 0 || arm >= bridge->n_stream_arms ||
        bridge->stream_kind[arm] == MCA_ROS2_STREAM_NONE) {
        return MCA_EINVAL;
    }
    return mca_dds_mailbox_read(&bridge->shm->box[arm], bridge->stream_kind[arm], out);
}

int mca_dds_bridge_tracks(mca_dds_bridge_t *bridge, mca_ros2_tracks_t *out) {
    if (bridge == NULL || out == NULL || !bridge->shm->cfg.has_ros2 || !bridge->shm->cfg.ros2.tracks) {
        return MCA_EINVAL;
    }
    return mca_dds_trackbox_read(&bridge->shm->tracks, out);
}

int mca_dds_bridge_stats(const mca_dds_bridge_t *bridge, mca_dds_stats_t *out) {
    if (bridge == NULL || out == NULL) {
        return MCA_EINVAL;
    }
    const mca_dds_shm_t *shm = bridge->shm;
    mca_ring_stats_t rs;
    mca_ring_stats(&shm->ring, &rs);
    memset(out, 0, sizeof *out);
    out->offered = atomic_load_explicit(&shm->offered, memory_order_relaxed);
    out->sched_refused = atomic_load_explicit(&shm->sched_refused, memory_order_relaxed);
    out->queued = rs.pushed;
    out->dropped = rs.dropped;
    out->pending = rs.pending;
    out->published = atomic_load_explicit(&shm->published, memory_order_relaxed);
    out->samples = atomic_load_explicit(&shm->samples, memory_order_relaxed);
    out->write_errors = atomic_load_explicit(&shm->write_errors, memory_order_relaxed);
    out->invalid = atomic_load_explicit(&shm->invalid, memory_order_relaxed);
    out->max_pending = atomic_load_explicit(&shm->max_pending, memory_order_relaxed);
    out->max_publish_ns = atomic_load_explicit(&shm->max_publish_ns, memory_order_relaxed);
    out->wakes = atomic_load_explicit(&shm->wakes, memory_order_relaxed);
    out->parks = atomic_load_explicit(&shm->parks, memory_order_relaxed);
    out->grid_sleeps = atomic_load_explicit(&shm->grid_sleeps, memory_order_relaxed);
    out->stale = atomic_load_explicit(&shm->stale, memory_order_relaxed);
    out->restarts = atomic_load_explicit(&shm->restarts, memory_order_relaxed);
    out->deaths = bridge->deaths;
    out->hung = bridge->hung;
    out->pid = bridge->process ? (int32_t)bridge->pid : 0;
    out->down = bridge->process && (bridge->stopped ? !bridge->up_at_stop : bridge->pid == 0);
    /* a publisher alive for MCA_DDS_BRIDGE_STABLE_S ends the series (the next death starts it afresh) */
    const int alive = bridge->stopped ? bridge->up_at_stop : bridge->pid > 0;
    const double until = bridge->stopped ? bridge->stop_s : mono_s();
    const int stable = alive && until - bridge->started_s >= MCA_DDS_BRIDGE_STABLE_S;
    out->deaths_in_a_row = bridge->process && !stable ? (uint32_t)bridge->quick_deaths : 0;
    out->backoff_s = bridge->process ? bridge->backoff_s : 0.0;
    return MCA_OK;
}

int mca_dds_bridge_wait_readers(mca_dds_bridge_t *bridge, const char *topic, uint32_t n,
                                uint32_t timeout_ms) {
    if (bridge == NULL || bridge->process) {
        return MCA_EINVAL;
    }
    int first = 0, last = W_STATUS; /* NULL: the four topics every subscriber of old reads */
    if (topic != NULL) {
        first = -1;
        for (int w = 0; w < W_COUNT; ++w) {
            if (strcmp(topic, topic_names[w]) == 0) {
                first = last = w;
            }
        }
        if (first < 0) {
            return MCA_EINVAL;
        }
    }
    struct timespec t0, now;
    clock_gettime(CLOCK_MONOTONIC, &t0);
    const struct timespec nap = {0, 10 * 1000 * 1000};
    for (;;) {
        int ok = 0;
        for (int w = first; w <= last; ++w) {
            dds_publication_matched_status_t st;
            if (dds_get_publication_matched_status(bridge->pub->writer[w], &st) == DDS_RETCODE_OK &&
                st.current_count >= n) {
                ok++;
            }
        }
        if (ok == last - first + 1) {
            return MCA_OK;
        }
        clock_gettime(CLOCK_MONOTONIC, &now);
        const int64_t ms = (now.tv_sec - t0.tv_sec) * 1000 + (now.tv_nsec - t0.tv_nsec) / 1000000;
        if (ms >= (int64_t)timeout_ms) {
            return MCA_ETIMEDOUT;
        }
        nanosleep(&nap, NULL);
    }
}

int mca_dds_bridge_fault_text(mca_dds_bridge_t *bridge, int32_t fault_code, const char *text) {
    if (bridge == NULL || text == NULL || fault_code == 0) {
        return MCA_EINVAL;
    }
    mca_dds_shm_t *shm = bridge->shm;
    if (atomic_load_explicit(&shm->fault_code, memory_order_acquire) != 0) {
        return MCA_EINVAL; /* written once */
    }
    snprintf(shm->fault_text, sizeof shm->fault_text, "%s", text);
    atomic_store_explicit(&shm->fault_code, fault_code, memory_order_release);
    return MCA_OK;
}

/* A dead publisher may have been writing a stream target: its seqlock would stay odd, and the loop would keep
 * the last velocity for good (it skips a mailbox being written). Close it as a target received long ago: the
 * loop's brake_after then stops the arms, as for any stream that went quiet. Only with no publisher alive. */
static void repair_mailboxes(mca_dds_bridge_t *b) {
    for (int a = 0; a < MCA_MAX_ARMS; a++) {
        mca_dds_mailbox_t *m = &b->shm->box[a];
        const uint32_t s = atomic_load_explicit(&m->seq, memory_order_relaxed);
        if (s & 1u) {
            atomic_store_explicit(&m->recv_ns, 1, memory_order_relaxed);
            atomic_store_explicit(&m->seq, s + 1u, memory_order_release);
        }
    }
    mca_dds_trackbox_t *t = &b->shm->tracks; /* the same for the streamed bodies: lost_after stops */
    const uint32_t s = atomic_load_explicit(&t->seq, memory_order_relaxed);
    if (s & 1u) {
        atomic_store_explicit(&t->recv_ns, 1, memory_order_relaxed);
        atomic_store_explicit(&t->seq, s + 1u, memory_order_release);
    }
}

#define STR_(x) #x
#define STR(x) STR_(x)

/* The death as the next publisher puts it on /diagnostics. */
static void record_death(mca_dds_bridge_t *b, const char *why, double delay) {
    mca_dds_shm_t *shm = b->shm;
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    snprintf(shm->last_death, sizeof shm->last_death, "%s", why);
    atomic_store_explicit(&shm->deaths, b->deaths, memory_order_relaxed);
    atomic_store_explicit(&shm->deaths_in_a_row, (uint32_t)b->quick_deaths, memory_order_relaxed);
    atomic_store_explicit(&shm->backoff_ms, (uint32_t)(delay * 1e3 + 0.5), memory_order_relaxed);
    atomic_store_explicit(&shm->last_death_ns, (int64_t)ts.tv_sec * 1000000000 + ts.tv_nsec,
                          memory_order_release);
}

/* One line of the supervisor to the caller's log (printf-like; non-rt). */
static void tell(mca_dds_log_fn log, void *arg, int level, const char *fmt, ...)
    __attribute__((format(printf, 4, 5)));
static void tell(mca_dds_log_fn log, void *arg, int level, const char *fmt, ...) {
    char line[1024];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(line, sizeof line, fmt, ap);
    va_end(ap);
    log(arg, level, line);
}

int mca_dds_bridge_supervise(mca_dds_bridge_t *bridge, mca_dds_log_fn log, void *log_arg) {
    if (bridge == NULL || !bridge->process ||
        atomic_load_explicit(&bridge->shm->stop, memory_order_relaxed)) {
        return 0;
    }
    mca_dds_bridge_t *b = bridge;
    const double now = mono_s();
    int lines = 0;
    if (b->pid > 0) {
        int status = 0;
        const pid_t r = waitpid(b->pid, &status, WNOHANG);
        if (r != b->pid) {
            const uint32_t gen = atomic_load_explicit(&b->shm->start_gen, memory_order_acquire);
            if (b->announced != gen &&
                atomic_load_explicit(&b->shm->ready_gen, memory_order_acquire) == gen) {
                b->announced = gen;
                if (log != NULL && (b->deaths == 0 || mca_dds_log_this_death(b->quick_deaths))) {
                    const int failed = atomic_load(&b->shm->open_rc) != MCA_OK;
                    tell(log, log_arg, 5,
                         "dds bridge restarted: pid %d (restart %llu), publishing again%s%.*s%s", (int)b->pid,
                         (unsigned long long)atomic_load(&b->shm->restarts),
                         failed ? " (NOT: its DDS set-up failed: " : "",
                         failed ? (int)sizeof b->shm->open_err : 0, b->shm->open_err, failed ? ")" : "");
                    lines++;
                }
            }
            /* a series whose restarts were not all logged: say once that this one lives */
            if (b->quick_deaths > MCA_DDS_BRIDGE_LOG_ALL && !b->up_logged &&
                now - b->started_s >= MCA_DDS_BRIDGE_UP_S &&
                atomic_load_explicit(&b->shm->ready_gen, memory_order_acquire) == gen) {
                b->up_logged = 1;
                if (log != NULL) {
                    tell(log, log_arg, 5,
                         "dds bridge up again: pid %d (restart %llu) has lived %.0f s after %d deaths "
                         "in a row, publishing",
                         (int)b->pid, (unsigned long long)atomic_load(&b->shm->restarts), now - b->started_s,
                         b->quick_deaths);
                    lines++;
                }
            }
            /* alive and up: one that publishes nothing for MCA_DDS_BRIDGE_HUNG_S while snapshots wait is hung
             * (a deadlock inside Cyclone, a stopped process): killed, then restarted as after any death */
            if (atomic_load_explicit(&b->shm->ready_gen, memory_order_acquire) == gen) {
                const uint64_t progress = atomic_load_explicit(&b->shm->published, memory_order_relaxed) +
                                          atomic_load_explicit(&b->shm->invalid, memory_order_relaxed) +
                                          atomic_load_explicit(&b->shm->stale, memory_order_relaxed);
                mca_ring_stats_t rs;
                mca_ring_stats(&b->shm->ring, &rs);
                if (b->progress_s == 0.0 || progress != b->seen_progress || rs.pending == 0) {
                    b->seen_progress = progress;
                    b->progress_s = now;
                } else if (now - b->progress_s > MCA_DDS_BRIDGE_HUNG_S) {
                    if (log != NULL) {
                        tell(log, log_arg, 3,
                             "dds bridge (pid %d) hung: nothing published for %.1f s with %llu snapshots "
                             "waiting: killing it",
                             (int)b->pid, now - b->progress_s, (unsigned long long)rs.pending);
                    }
                    kill(b->pid, SIGKILL); /* reaped and restarted by the next calls */
                    b->hung++;
                    b->progress_s = now;
                    lines++;
                }
            }
            return lines;
        }
        const pid_t dead = b->pid;
        b->pid = 0;
        b->deaths++;
        b->up_logged = 0;
        repair_mailboxes(b);
        b->quick_deaths = now - b->started_s < MCA_DDS_BRIDGE_STABLE_S ? b->quick_deaths + 1 : 1;
        char why[96];
        mca_dds_describe_status(status, why, sizeof why);
        /* capped exponential back-off, never a last restart: a peer that crashes every start (docs/dds.md)
         * costs one short-lived process per MCA_DDS_BRIDGE_BACKOFF_MAX_S while it is there, and monitoring
         * is back within that time after it left */
        const double delay = mca_dds_backoff_s(b->quick_deaths);
        b->next_start_s = now + delay;
        b->backoff_s = delay;
        record_death(b, why, delay);
        if (log != NULL && mca_dds_log_this_death(b->quick_deaths)) {
            tell(log, log_arg, 3,
                 "dds bridge (pid %d) died: %s; restart %llu in %.1f s (%d deaths in a row; the loop and "
                 "the arms are not affected)%s",
                 (int)dead, why, (unsigned long long)atomic_load(&b->shm->restarts) + 1u, delay,
                 b->quick_deaths,
                 b->quick_deaths == MCA_DDS_BRIDGE_LOG_ALL
                     ? "; it is restarted for as long as mcad runs, from now on every " STR(
                           MCA_DDS_BRIDGE_LOG_EVERY) "th death of this series is logged"
                     : "");
            return lines + 1;
        }
        return lines;
    }
    if (now < b->next_start_s) {
        return lines;
    }
    /* the count first: the new publisher publishes it with its first status */
    atomic_store_explicit(&b->shm->restarts, atomic_load(&b->shm->restarts) + 1u, memory_order_release);
    char why[256] = "";
    if (spawn_publisher(b, why, sizeof why) != MCA_OK) {
        b->started_s = now; /* counts as a quick death */
        b->quick_deaths++;
        b->backoff_s = MCA_DDS_BRIDGE_BACKOFF_MAX_S;
        b->next_start_s = now + MCA_DDS_BRIDGE_BACKOFF_MAX_S;
        record_death(b, "not started", MCA_DDS_BRIDGE_BACKOFF_MAX_S);
        if (log != NULL && mca_dds_log_this_death(b->quick_deaths)) {
            tell(log, log_arg, 3,
                 "dds bridge: %s: next try in %.1f s (the loop and the arms are not affected)", why,
                 MCA_DDS_BRIDGE_BACKOFF_MAX_S);
            lines++;
        }
    }
    return lines;
}

void mca_dds_bridge_destroy(mca_dds_bridge_t *bridge, mca_dds_stats_t *final_stats) {
    if (bridge == NULL) {
        return;
    }
    atomic_store_explicit(&bridge->shm->stop, 1, memory_order_seq_cst);
    wake(bridge->shm); /* a parked publisher sees stop, drains what is left and ends */
    if (bridge->thread_started) {
        pthread_join(bridge->thread, NULL);
        publisher_close(bridge->pub);
    }
    bridge->stopped = 1;
    bridge->up_at_stop = bridge->pid > 0;
    bridge->stop_s = mono_s();
    if (bridge->process && bridge->pid > 0) {
        /* it publishes what is queued, the final status, waits up to 1 s for acks (each writer) */
        reap(bridge, 10.0);
    }
    if (final_stats != NULL) {
        mca_dds_bridge_stats(bridge, final_stats);
    }
    free_bridge(bridge);
}
