/* SPDX-License-Identifier: MIT */
/* DDS bridge: rt loop -> SPSC drop-oldest ring -> publisher thread -> Cyclone DDS writers. The publisher
 * parks on a futex when the ring is empty; a push wakes it only when it is parked. */
#include "mca/dds_bridge.h"

#include <math.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <errno.h>
#include <linux/futex.h> /* FUTEX_WAIT_PRIVATE, FUTEX_WAKE_PRIVATE */
#include <sys/prctl.h>   /* PR_SET_TIMERSLACK */
#include <sys/syscall.h> /* SYS_futex */
#include <time.h>
#include <unistd.h> /* syscall */

#include "mca/dds_qos.h"
#include "mca/err.h"
#include "mca/ring.h"
#include "mca/scheme.h" /* mca_brake_s: S(d) */
#include "mca_dds.h"    /* idlc output: mca_dds_JointState, ... */
#include "ros2_pub.h"

enum { W_STATE, W_COMMAND, W_DIST, W_STATUS, W_COUNT };
static const char *const topic_names[W_COUNT] = {MCA_DDS_TOPIC_JOINT_STATE, MCA_DDS_TOPIC_JOINT_COMMAND,
                                                 MCA_DDS_TOPIC_DISTANCES, MCA_DDS_TOPIC_STATUS};

struct mca_dds_bridge {
    mca_ring_t ring; /* first: cache-line aligned by aligned_alloc */
    void *storage;
    mca_dds_config_t cfg;
    char frame_id[MCA_DDS_FRAME_ID_MAX + 1];
    char partition[MCA_DDS_PARTITION_MAX + 1];

    _Atomic uint64_t offered; /* written by the rt thread only */
    _Atomic uint64_t wakes;   /* written by the rt thread only */
    /* Park/wake (futex): the publisher sets `parked` before it re-checks the ring and sleeps on `wake_seq`;
     * a push that finds `parked` set clears it, bumps `wake_seq` and wakes the futex. */
    _Atomic uint32_t wake_seq;
    _Atomic int parked;
    _Atomic uint64_t parks, grid_sleeps; /* written by the publisher thread only */
    /* Written by the publisher thread only. */
    _Atomic uint64_t published, samples, write_errors, invalid, max_pending;
    _Atomic int64_t max_publish_ns;
    _Atomic int stop;

    dds_entity_t domain, participant;
    dds_entity_t topic[W_COUNT], writer[W_COUNT];
    mca_ros2_pub_t *ros2; /* NULL: no ROS 2 topics */
    pthread_t thread;
    int thread_started;

    /* Publisher thread state. */
    mca_dds_snapshot_t work;
    int have_status;
    mca_dds_status_snapshot_t last_status;
    uint64_t last_tick;
    int64_t last_stamp;
    uint64_t since_status;
};

static void bump(_Atomic uint64_t *c) {
    /* Single writer per counter: load + store, no locked instruction. */
    atomic_store_explicit(c, atomic_load_explicit(c, memory_order_relaxed) + 1u, memory_order_relaxed);
}

void mca_dds_config_default(mca_dds_config_t *cfg) {
    if (cfg == NULL) {
        return;
    }
    memset(cfg, 0, sizeof *cfg);
    cfg->domain_id = 0;
    cfg->config_path = NULL;
    cfg->ring_capacity = 1024; /* 1 s of publisher stall at 1 kHz, 3 MB */
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
    if (s->n_arms > MCA_MAX_ARMS || s->n_pairs > MCA_MAX_PAIRS) {
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

static void write_one(mca_dds_bridge_t *b, int w, const void *sample) {
    if (dds_write(b->writer[w], sample) < 0) {
        bump(&b->write_errors);
    } else {
        bump(&b->samples);
    }
}

static void write_status(mca_dds_bridge_t *b) {
    const mca_dds_status_snapshot_t *st = &b->last_status;
    mca_ring_stats_t rs;
    mca_ring_stats(&b->ring, &rs);
    mca_dds_ControllerStatus m;
    memset(&m, 0, sizeof m);
    m.controller_id = b->cfg.controller_id;
    m.tick = b->last_tick;
    m.stamp_ns = b->last_stamp;
    m.state = (int32_t)st->state;
    m.fault_code = st->fault_code;
    memcpy(m.fault_text, st->fault_text, sizeof m.fault_text - 1);
    m.fault_text[sizeof m.fault_text - 1] = '\0';
    if (m.fault_code != 0 && m.fault_text[0] == '\0' && b->cfg.fault_text != NULL) {
        /* the owner's rt side latched a code and numbers: the text is made here, off the rt path */
        b->cfg.fault_text(b->cfg.fault_text_arg, st, m.fault_text, sizeof m.fault_text);
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
    write_one(b, W_STATUS, &m);
    if (b->ros2 != NULL) {
        uint64_t errors = 0;
        add(&b->samples, (uint64_t)mca_ros2_pub_status(b->ros2, &m, &errors));
        add(&b->write_errors, errors);
    }
    b->since_status = 0;
}

static void publish(mca_dds_bridge_t *b, mca_dds_snapshot_t *s) {
    if (!snapshot_valid(s)) {
        bump(&b->invalid);
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
        memcpy(jc.frame_id, b->frame_id, sizeof jc.frame_id);
        write_one(b, W_COMMAND, &jc);
    }
    if (b->ros2 != NULL) {
        uint64_t errors = 0;
        add(&b->samples, (uint64_t)mca_ros2_pub_snapshot(b->ros2, s, &errors));
        add(&b->write_errors, errors);
    }
    const int changed = !b->have_status || s->status.state != b->last_status.state ||
                        s->status.fault_code != b->last_status.fault_code;
    b->last_status = s->status;
    b->last_status.fault_text[MCA_DDS_FAULT_TEXT_MAX] = '\0';
    b->last_tick = s->tick;
    b->last_stamp = s->stamp_ns;
    b->have_status = 1;
    if (changed || ++b->since_status >= b->cfg.status_divisor) {
        write_status(b);
    }
    bump(&b->published);
}

static long futex(_Atomic uint32_t *addr, int op, uint32_t val) {
    return syscall(SYS_futex, (uint32_t *)addr, op, val, NULL, NULL, 0);
}

/* Publisher side of the park/wake protocol: sleep until a push (or destroy) bumps wake_seq. Sets `parked`
 * and re-checks the ring after a full fence; the pusher stores into the ring, fences and then reads
 * `parked`: one of the two sees the other (no lost wake-up). A bump between the re-check and the sleep
 * makes FUTEX_WAIT return at once (the value differs from `seen`). */
static void park(mca_dds_bridge_t *b) {
    const uint32_t seen = atomic_load_explicit(&b->wake_seq, memory_order_acquire);
    atomic_store_explicit(&b->parked, 1, memory_order_relaxed);
    atomic_thread_fence(memory_order_seq_cst);
    mca_ring_stats_t rs;
    mca_ring_stats(&b->ring, &rs);
    if (rs.pending == 0 && !atomic_load_explicit(&b->stop, memory_order_acquire)) {
        bump(&b->parks);
        futex(&b->wake_seq, FUTEX_WAIT_PRIVATE, seen); /* EAGAIN / EINTR: look again */
    }
    atomic_store_explicit(&b->parked, 0, memory_order_relaxed);
}

static void wake(mca_dds_bridge_t *b) {
    atomic_fetch_add_explicit(&b->wake_seq, 1u, memory_order_release);
    futex(&b->wake_seq, FUTEX_WAKE_PRIVATE, 1);
}

/* wake_period_ns: sleep until the next publishing tick of the caller's grid has pushed (the last
 * snapshot's stamp + period + offset), unless that is already past or the ring is not empty. */
static void sleep_on_grid(mca_dds_bridge_t *b, int64_t stamp_ns) {
    mca_ring_stats_t rs;
    mca_ring_stats(&b->ring, &rs);
    if (rs.pending > 0 || atomic_load_explicit(&b->stop, memory_order_acquire)) {
        return;
    }
    struct timespec now;
    clock_gettime(CLOCK_MONOTONIC, &now);
    const int64_t t_now = (int64_t)now.tv_sec * 1000000000LL + now.tv_nsec;
    const int64_t step = (int64_t)(b->cfg.wake_period_ns + b->cfg.wake_offset_ns);
    int64_t target = stamp_ns + step;
    if (target <= t_now) {
        return; /* late already: look now, park if nothing is there */
    }
    if (target > t_now + step) {
        target = t_now + step; /* a stamp not on this clock: never sleep longer than one period */
    }
    bump(&b->grid_sleeps);
    const struct timespec ts = {(time_t)(target / 1000000000LL), (long)(target % 1000000000LL)};
    while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, NULL) == EINTR) {
    }
}

static void *publisher_main(void *arg) {
    mca_dds_bridge_t *b = arg;
    /* wake at the grid point itself, not up to 50 us later (the default slack of a normal thread) */
    prctl(PR_SET_TIMERSLACK, 1UL, 0UL, 0UL, 0UL);
    for (;;) {
        /* Read stop BEFORE trying the ring: once stop is seen, one more empty pop means drained. */
        const int stop = atomic_load_explicit(&b->stop, memory_order_acquire);
        if (mca_ring_pop(&b->ring, &b->work) == MCA_OK) {
            mca_ring_stats_t rs;
            mca_ring_stats(&b->ring, &rs);
            if (rs.pending + 1u > atomic_load_explicit(&b->max_pending, memory_order_relaxed)) {
                atomic_store_explicit(&b->max_pending, rs.pending + 1u, memory_order_relaxed);
            }
            struct timespec t0, t1;
            clock_gettime(CLOCK_MONOTONIC, &t0);
            publish(b, &b->work);
            clock_gettime(CLOCK_MONOTONIC, &t1);
            const int64_t dt = (t1.tv_sec - t0.tv_sec) * 1000000000LL + (t1.tv_nsec - t0.tv_nsec);
            if (dt > atomic_load_explicit(&b->max_publish_ns, memory_order_relaxed)) {
                atomic_store_explicit(&b->max_publish_ns, dt, memory_order_relaxed);
            }
            if (b->cfg.wake_period_ns > 0) {
                sleep_on_grid(b, b->work.stamp_ns);
            }
            continue;
        }
        if (stop) {
            break;
        }
        park(b);
    }
    return NULL;
}

static int is_pow2(uint32_t x) {
    return x >= 2 && (x & (x - 1u)) == 0;
}

static void delete_entities(mca_dds_bridge_t *b) {
    if (b->participant > 0) {
        dds_delete(b->participant); /* deletes topics and writers too */
    }
    if (b->domain > 0) {
        dds_delete(b->domain);
    }
}

int mca_dds_bridge_create(mca_dds_bridge_t **out, const mca_dds_config_t *cfg) {
    if (out == NULL || cfg == NULL || cfg->status_divisor == 0 || !is_pow2(cfg->ring_capacity) ||
        cfg->ring_capacity > MCA_RING_MAX_CAPACITY || cfg->domain_id > MCA_DDS_MAX_DOMAIN ||
        cfg->wake_period_ns > 10000000000ULL || cfg->wake_offset_ns > 10000000000ULL) {
        return MCA_EINVAL;
    }
    const char *frame = cfg->frame_id != NULL ? cfg->frame_id : "world";
    if (strlen(frame) > MCA_DDS_FRAME_ID_MAX) {
        fprintf(stderr, "mca dds: frame id '%s' longer than %d bytes\n", frame, MCA_DDS_FRAME_ID_MAX);
        return MCA_EINVAL;
    }
    if (cfg->partition != NULL && strlen(cfg->partition) > MCA_DDS_PARTITION_MAX) {
        fprintf(stderr, "mca dds: partition '%s' longer than %d bytes\n", cfg->partition,
                MCA_DDS_PARTITION_MAX);
        return MCA_EINVAL;
    }
    const size_t sz = (sizeof(mca_dds_bridge_t) + 63u) & ~(size_t)63u;
    mca_dds_bridge_t *b = aligned_alloc(64, sz);
    if (b == NULL) {
        return MCA_ENOMEM;
    }
    memset(b, 0, sizeof *b);
    b->cfg = *cfg;
    snprintf(b->frame_id, sizeof b->frame_id, "%s", frame);
    b->cfg.frame_id = b->frame_id;
    if (cfg->partition != NULL) {
        snprintf(b->partition, sizeof b->partition, "%s", cfg->partition);
        b->cfg.partition = b->partition;
    }
    b->cfg.config_path = NULL; /* not kept: the caller's string may go away */

    const size_t bytes = MCA_RING_STORAGE_SIZE(sizeof(mca_dds_snapshot_t), cfg->ring_capacity);
    b->storage = aligned_alloc(64, (bytes + 63u) & ~(size_t)63u);
    if (b->storage == NULL) {
        free(b);
        return MCA_ENOMEM;
    }
    int rc = mca_ring_init(&b->ring, b->storage, bytes, sizeof(mca_dds_snapshot_t), cfg->ring_capacity);
    if (rc != MCA_OK) {
        free(b->storage);
        free(b);
        return rc;
    }

    const dds_entity_t p = mca_dds_open_participant(cfg->domain_id, cfg->config_path, &b->domain);
    if (p < 0) {
        free(b->storage);
        free(b);
        return (int)p;
    }
    b->participant = p;

    const dds_topic_descriptor_t *const descs[W_COUNT] = {&mca_dds_JointState_desc,
                                                          &mca_dds_JointCommand_desc, &mca_dds_Distances_desc,
                                                          &mca_dds_ControllerStatus_desc};
    dds_qos_t *qs = mca_dds_qos_stream();
    dds_qos_t *qst = mca_dds_qos_status();
    rc = (qs != NULL && qst != NULL) ? MCA_OK : MCA_ENOMEM;
    dds_entity_t pub = p; /* writers hang off the participant, or a publisher with a partition */
    if (rc == MCA_OK && b->cfg.partition != NULL) {
        pub = mca_dds_create_publisher(p, b->cfg.partition);
        if (pub < 0) {
            rc = MCA_EIO;
        }
    }
    for (int w = 0; w < W_COUNT && rc == MCA_OK; ++w) {
        const dds_qos_t *q = w == W_STATUS ? qst : qs;
        b->topic[w] = dds_create_topic(p, descs[w], topic_names[w], q, NULL);
        b->writer[w] = b->topic[w] > 0 ? dds_create_writer(pub, b->topic[w], q, NULL) : b->topic[w];
        if (b->writer[w] < 0) {
            fprintf(stderr, "mca dds: cannot create topic/writer '%s': %s\n", topic_names[w],
                    dds_strretcode(b->writer[w]));
            rc = MCA_EIO;
        }
    }
    dds_delete_qos(qs);
    dds_delete_qos(qst);
    if (rc == MCA_OK && cfg->ros2 != NULL && cfg->ros2->enabled) {
        char err[256];
        rc = mca_ros2_pub_create(&b->ros2, p, cfg->ros2, err, sizeof err);
        if (rc != MCA_OK) {
            fprintf(stderr, "mca dds: %s\n", err);
        }
    }
    b->cfg.ros2 = NULL; /* copied into b->ros2 */
    if (rc == MCA_OK && pthread_create(&b->thread, NULL, publisher_main, b) != 0) {
        rc = MCA_ENOMEM;
    }
    if (rc != MCA_OK) {
        mca_ros2_pub_destroy(b->ros2, 0);
        delete_entities(b);
        free(b->storage);
        free(b);
        return rc;
    }
    b->thread_started = 1;
    pthread_setname_np(b->thread, "mca-dds-pub");
    *out = b;
    return MCA_OK;
}

void mca_dds_bridge_push(mca_dds_bridge_t *bridge, const mca_dds_snapshot_t *snap) {
    bump(&bridge->offered);
    mca_ring_push(&bridge->ring, snap);
    /* pairs with the fence in park(): the publisher sees the record or we see it parked */
    atomic_thread_fence(memory_order_seq_cst);
    if (atomic_load_explicit(&bridge->parked, memory_order_relaxed) &&
        atomic_exchange_explicit(&bridge->parked, 0, memory_order_relaxed)) {
        bump(&bridge->wakes);
        wake(bridge); /* one non-blocking system call */
    }
}

int mca_dds_bridge_stream_target(mca_dds_bridge_t *bridge, int arm, mca_ros2_target_t *out) {
    if (bridge == NULL || bridge->ros2 == NULL) {
        return MCA_EINVAL;
    }
    return mca_ros2_pub_target(bridge->ros2, arm, out);
}

int mca_dds_bridge_stats(const mca_dds_bridge_t *bridge, mca_dds_stats_t *out) {
    if (bridge == NULL || out == NULL) {
        return MCA_EINVAL;
    }
    mca_ring_stats_t rs;
    mca_ring_stats(&bridge->ring, &rs);
    out->offered = atomic_load_explicit(&bridge->offered, memory_order_relaxed);
    out->queued = rs.pushed;
    out->dropped = rs.dropped;
    out->pending = rs.pending;
    out->published = atomic_load_explicit(&bridge->published, memory_order_relaxed);
    out->samples = atomic_load_explicit(&bridge->samples, memory_order_relaxed);
    out->write_errors = atomic_load_explicit(&bridge->write_errors, memory_order_relaxed);
    out->invalid = atomic_load_explicit(&bridge->invalid, memory_order_relaxed);
    out->max_pending = atomic_load_explicit(&bridge->max_pending, memory_order_relaxed);
    out->max_publish_ns = atomic_load_explicit(&bridge->max_publish_ns, memory_order_relaxed);
    out->wakes = atomic_load_explicit(&bridge->wakes, memory_order_relaxed);
    out->parks = atomic_load_explicit(&bridge->parks, memory_order_relaxed);
    out->grid_sleeps = atomic_load_explicit(&bridge->grid_sleeps, memory_order_relaxed);
    return MCA_OK;
}

int mca_dds_bridge_wait_readers(mca_dds_bridge_t *bridge, const char *topic, uint32_t n,
                                uint32_t timeout_ms) {
    if (bridge == NULL) {
        return MCA_EINVAL;
    }
    int first = 0, last = W_COUNT - 1;
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
            if (dds_get_publication_matched_status(bridge->writer[w], &st) == DDS_RETCODE_OK &&
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

void mca_dds_bridge_destroy(mca_dds_bridge_t *bridge, mca_dds_stats_t *final_stats) {
    if (bridge == NULL) {
        return;
    }
    if (bridge->thread_started) {
        atomic_store_explicit(&bridge->stop, 1, memory_order_seq_cst);
        wake(bridge); /* a parked publisher sees stop, drains what is left and ends */
        pthread_join(bridge->thread, NULL);
    }
    if (bridge->have_status) {
        write_status(bridge); /* final status, with the final drop count */
    }
    for (int w = 0; w < W_COUNT; ++w) {
        if (bridge->writer[w] > 0) {
            dds_wait_for_acks(bridge->writer[w], DDS_SECS(1));
        }
    }
    mca_ros2_pub_destroy(bridge->ros2, DDS_SECS(1));
    if (final_stats != NULL) {
        mca_dds_bridge_stats(bridge, final_stats);
    }
    delete_entities(bridge);
    free(bridge->storage);
    free(bridge);
}
