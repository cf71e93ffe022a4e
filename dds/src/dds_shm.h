/* SPDX-License-Identifier: MIT */
/* Internal to mca_dds: the region the loop's side of the bridge shares with its publisher (mca/dds_bridge.h).
 *
 * In-process mode it is plain heap memory and the publisher is a thread; in process mode it is a
 * memfd mapped MAP_SHARED by mcad and by mca-dds-bridge, which owns the DDS participant. Everything the two
 * sides exchange lives here, and none of it is a pointer: the ring keeps its storage as an offset from itself
 * (mca/ring.h), the settings are plain data, and the futex word is waited on and woken with the shared (not
 * FUTEX_PRIVATE_FLAG) operations, so the region works at whatever address each process maps it.
 *
 * Writers: "owner" = the process that created the bridge (its rt thread for the loop's fields, its non-rt
 * threads for the rest); "publisher" = the publisher thread or process. A publisher that dies leaves its
 * fields as they were; the next one continues from them. */
#ifndef MCA_DDS_SHM_H
#define MCA_DDS_SHM_H

#include <stdatomic.h>
#include <stddef.h>
#include <stdint.h>

#include "mca/dds_bridge.h"
#include "mca/ring.h"
#include "mca/ros2.h"

#define MCA_DDS_SHM_MAGIC 0x316d73736464616dULL /* "mddssm1" */
#define MCA_DDS_SHM_VERSION 6u
#define MCA_DDS_CONFIG_PATH_MAX 1023

/** One arm's latest accepted stream target: a seqlock (the publisher's DDS listener writes, the loop reads;
 *  odd seq = being written). Fields are relaxed atomics so that the reader's copy of a torn write is no data
 *  race. */
typedef struct mca_dds_mailbox {
    _Atomic uint32_t seq;
    _Atomic double x[3];
    _Atomic int64_t recv_ns;
    _Atomic uint64_t accepted;
} mca_dds_mailbox_t;

/** The latest accepted message of streamed bodies: a seqlock as mca_dds_mailbox_t. x[k]: a[3], b[3],
 *  radius, v[3], age at send (mca_ros2_tracks_t). */
#define MCA_DDS_TRACK_NUMS 11
typedef struct mca_dds_trackbox {
    _Atomic uint32_t seq;
    _Atomic uint32_t n;
    _Atomic uint32_t id[MCA_MAX_TRACKS];
    _Atomic int32_t kind[MCA_MAX_TRACKS];
    _Atomic double x[MCA_MAX_TRACKS][MCA_DDS_TRACK_NUMS];
    _Atomic int64_t recv_ns;
    _Atomic uint64_t accepted;
} mca_dds_trackbox_t;

/** Settings as plain data (the publisher process gets them from here, not from the owner's pointers). */
typedef struct mca_dds_shm_config {
    uint32_t domain_id;
    uint32_t ring_capacity;
    uint32_t status_divisor;
    uint8_t controller_id;
    int has_config_path, has_partition, has_ros2;
    char config_path[MCA_DDS_CONFIG_PATH_MAX + 1];
    char frame_id[MCA_DDS_FRAME_ID_MAX + 1];
    char partition[MCA_DDS_PARTITION_MAX + 1];
    uint64_t wake_period_ns, wake_offset_ns;
    int32_t sched_priority; /* > 0: the publisher thread SCHED_FIFO at it (mca_dds_config_t) */
    mca_ros2_config_t ros2; /* plain data: names, URDF paths (the publisher reads the URDFs itself) */
} mca_dds_shm_config_t;

typedef struct mca_dds_shm {
    uint64_t magic;
    uint32_t version;
    uint32_t pad0;
    uint64_t size; /* bytes of the whole region */
    mca_dds_shm_config_t cfg;

    /* owner, rt thread */
    _Alignas(64) _Atomic uint64_t offered;
    _Atomic uint64_t wakes;
    /* park/wake: the publisher sets `parked` before it re-checks the ring and sleeps on `wake_seq`; a push
     * that finds `parked` set clears it, bumps `wake_seq` and wakes the futex (shared futex operations). */
    _Alignas(64) _Atomic uint32_t wake_seq;
    _Atomic int parked;
    /* publisher */
    _Alignas(64) _Atomic uint64_t parks, grid_sleeps;
    _Atomic uint64_t published, samples, write_errors, invalid, max_pending, stale;
    _Atomic int64_t max_publish_ns;
    _Atomic int open_rc;       /* process mode: the publisher's set-up result (MCA_OK or an error) */
    _Atomic int sched_refused; /* sched_priority was not permitted (process mode: written before ready_gen) */
    char open_err[256];        /* process mode: why its set-up failed (written before ready_gen) */
    _Atomic uint32_t ready_gen; /* process mode: = start_gen once its DDS entities exist */
    /* owner, non-rt */
    _Alignas(64) _Atomic int stop;
    _Atomic uint32_t start_gen; /* publisher processes started so far (1 = the first) */
    _Atomic uint64_t restarts;  /* publisher restarts after a death (published on /diagnostics) */
    /* the supervisor's record of deaths, for /diagnostics (written before the next publisher is started) */
    _Atomic uint64_t deaths;          /* publishers that died */
    _Atomic uint32_t deaths_in_a_row; /* quick deaths in a row (0 after a stable run) */
    _Atomic uint32_t backoff_ms;      /* the back-off before the running publisher's start */
    _Atomic int64_t last_death_ns;    /* CLOCK_MONOTONIC of the last death seen, 0: none */
    char last_death[64];              /* its cause: "signal 11 (SIGSEGV)" */
    _Atomic int32_t fault_code;       /* != 0: fault_text below is the text of this code (written once) */
    char fault_text[MCA_DDS_FAULT_TEXT_MAX + 1];
    /* publisher (its DDS listener), read by the loop */
    _Alignas(64) mca_dds_mailbox_t box[MCA_MAX_ARMS];
    _Alignas(64) mca_dds_trackbox_t tracks;
    /* the snapshot ring; its storage follows at ring_storage_off from the start of the region */
    _Alignas(64) mca_ring_t ring;
    uint64_t ring_storage_off;
} mca_dds_shm_t;

/** Bytes of a region for ring_capacity snapshots (page multiple). */
size_t mca_dds_shm_size(uint32_t ring_capacity);

/** Lay out a zeroed region of size bytes: header, settings, ring. @retval MCA_OK @retval MCA_EINVAL */
int mca_dds_shm_init(mca_dds_shm_t *shm, size_t size, const mca_dds_config_t *cfg);

/** Check a region handed to a publisher process (magic, version, size, ring geometry). */
int mca_dds_shm_check(const mca_dds_shm_t *shm, size_t size);

/** The publisher process's body (mca-dds-bridge): open the DDS entities from shm->cfg, publish until the
 *  owner sets stop (or forever), then the final status. log: where its own lines go (prefix included).
 *  @return MCA_OK after a clean stop, else the set-up error (also in shm->open_rc) */
int mca_dds_publisher_process(mca_dds_shm_t *shm);

/** Seqlock read of a mailbox (never waits). @retval MCA_OK @retval MCA_EAGAIN (being written) */
int mca_dds_mailbox_read(const mca_dds_mailbox_t *b, int kind, mca_ros2_target_t *out);

/** Seqlock read of the streamed bodies' box (never waits). @retval MCA_OK @retval MCA_EAGAIN */
int mca_dds_trackbox_read(const mca_dds_trackbox_t *b, mca_ros2_tracks_t *out);

#endif
