/* SPDX-License-Identifier: MIT */
/** @file mca/dds_bridge.h
 * DDS bridge: publishes the controller's state on Cyclone DDS without ever making the 1 kHz loop
 * wait. On a tick that publishes (the CALLER decides which: the bridge queues every snapshot it is
 * given), the loop fills a plain C snapshot and calls mca_dds_bridge_push() (wait-free copy into a
 * lock-free drop-oldest ring, see mca/ring.h); a normal-priority publisher drains the ring and writes
 * the DDS samples. The publisher never polls. With wake_period_ns set it
 * wakes on the caller's own grid (absolute clock_nanosleep until the last snapshot's stamp_ns +
 * wake_period_ns + wake_offset_ns, i.e. just after the next publishing tick has pushed) and the push
 * costs the loop no system call; whenever it finds the ring empty (a late or skipped tick, or without
 * wake_period_ns) it parks on a futex, and a push wakes it only if it is parked (one FUTEX_WAKE, a
 * non-blocking system call, at most once per push). If the publisher falls behind, the oldest snapshots are
 * dropped and counted, never the loop delayed.
 *
 * The publisher is either a thread of the caller (in-process: mca-dds-synth, tests) or, with
 * cfg.process_exe set, a separate program (mca-dds-bridge) that owns the DDS participant: ring,
 * futex word, counters and the stream-target mailboxes are then in a memfd both processes map (MAP_SHARED,
 * shared futex operations), and a crash inside Cyclone (a peer on the network can cause one, docs/dds.md)
 * kills only that process. The owner's non-rt supervisor calls mca_dds_bridge_supervise() to notice its
 * death, log it and restart it with a back-off; the loop's calls (push, stream_target) are the same in both
 * modes and never learn whether a publisher is alive.
 *
 * Topics (types in dds/mca_dds.idl, QoS in docs/dds.md), one sample per published snapshot:
 *   mca/joint_state      mca::dds::JointState       one per arm   (key arm_id = index in arm[])
 *   mca/joint_command    mca::dds::JointCommand     one per arm   (key arm_id = index in arm[])
 *   mca/distances        mca::dds::Distances        one per pair  (key pair_id = index in pair[])
 *   mca/pair_distances   mca::dds::PairDistances    one per snapshot: every pair of every kind, named
 *   mca/controller_status mca::dds::ControllerStatus every status_divisor-th published snapshot,
 *                        on any change of state or fault code, and once more at destroy.
 *
 * Calling context of each function: init (start-up/shut-down, may allocate and block), rt (the 1 kHz
 * loop: no allocation, no lock, no system call but the wake-up above), non-rt (any normal thread).
 */
#ifndef MCA_DDS_BRIDGE_H
#define MCA_DDS_BRIDGE_H

#include <stddef.h>
#include <stdint.h>
#include <stdio.h> /* FILE */

#include "mca/armdist.h"    /* mca_arm_distances_t */
#include "mca/controller.h" /* mca_controller_config_t, mca_pair_nearest_t */
#include "mca/dds_log.h"    /* mca_dds_log_fn */
#include "mca/limits.h"
#include "mca/ros2.h"

#ifdef __cplusplus
extern "C" {
#endif

/** Unordered pairs of arms a snapshot can carry. */
#define MCA_MAX_PAIRS (MCA_MAX_ARMS * (MCA_MAX_ARMS - 1) / 2)
/** Longest fault text (bytes, without the terminating NUL), = string<64> in the IDL. */
#define MCA_DDS_FAULT_TEXT_MAX 64
/** Longest partition name accepted (bytes, without NUL). */
#define MCA_DDS_PARTITION_MAX 63
/** Longest frame id (bytes, without NUL), = string<32> in the IDL. */
#define MCA_DDS_FRAME_ID_MAX 32

/** Controller state: the one numbering of the daemon's states (mca_daemon_state_t takes its values from
 *  here) and of the wire's mca::dds::ControllerState (dds_bridge.c asserts at compile time that the IDL's
 *  enumerators have these values). */
typedef enum mca_dds_state {
    MCA_DDS_STATE_INIT = 0,
    MCA_DDS_STATE_READY = 1,
    MCA_DDS_STATE_RUNNING = 2,
    MCA_DDS_STATE_BRAKING = 3,
    MCA_DDS_STATE_STOPPED = 4,
    MCA_DDS_STATE_FAULT = 5,
} mca_dds_state_t;

/** The states' one set of names: "init", "ready", "running", "braking", "stopped", "fault"; NULL for a
 *  value no state has (the caller says how it prints one: mcad "?", the ROS 2 diagnostics "unknown"). */
const char *mca_dds_state_name(int state);

/** One arm at one tick: measured state and the command sent. Entries [n_dof..] are ignored. */
typedef struct mca_dds_arm_snapshot {
    uint32_t n_dof;                         /**< joints, <= MCA_MAX_DOF */
    double position[MCA_MAX_DOF];           /**< measured [rad] */
    double velocity[MCA_MAX_DOF];           /**< measured [rad/s] */
    double effort[MCA_MAX_DOF];             /**< measured [N m] */
    double velocity_setpoint[MCA_MAX_DOF];  /**< commanded [rad/s] */
    double position_reference[MCA_MAX_DOF]; /**< commanded [rad] */
    uint32_t n_points;                      /**< capsule axis points (n_dof + 2; 0: no link markers) */
    double point[MCA_MAX_POINTS][3];        /**< world: root, joint origins, tool tip; link k = [k, k+1] */
} mca_dds_arm_snapshot_t;

/** Distance picture of one pair of arms (P on arm_a, E on arm_b). */
typedef struct mca_dds_pair_snapshot {
    uint8_t arm_a, arm_b;
    int16_t link_a, link_b;                /**< links holding P and E */
    uint32_t n_links_a, n_links_b;         /**< valid entries of link_distance_a/_b */
    double min_distance;                   /**< global minimum surface distance [m] */
    double p[3], e[3];                     /**< critical points (world) */
    double d1, d2;                         /**< safety thresholds [m] */
    double brake_factor;                   /**< S(d), eq. (13) */
    double link_distance_a[MCA_MAX_LINKS]; /**< per link of a: closest distance to b */
    double link_distance_b[MCA_MAX_LINKS]; /**< per link of b: closest distance to a */
} mca_dds_pair_snapshot_t;

/** Kinds of pair: the one numbering of the wire's mca::dds::PairKind (dds_pairs.c asserts at compile time
 * that the IDL's enumerators have these values). */
typedef enum mca_dds_pair_kind {
    MCA_DDS_PAIR_ARM_ARM = 0,   /**< two arms */
    MCA_DDS_PAIR_ARM_BODY = 1,  /**< an arm and a fixed body of the cell */
    MCA_DDS_PAIR_SELF = 2,      /**< two links of one arm (its self pairs) */
    MCA_DDS_PAIR_ARM_TRACK = 3, /**< an arm and a streamed body (mca/track.h) */
} mca_dds_pair_kind_t;
#define MCA_DDS_PAIR_KINDS 4

/** The kinds' one set of names: "arm-arm", "arm-body", "self", "arm-track"; NULL for a value no kind has. */
const char *mca_dds_pair_kind_name(int kind);

/** Entries of a snapshot's named pairs: each arm pair, each body, each arm's self pairs
 *  (= MAX_PAIR_ENTRIES in the IDL). */
#define MCA_DDS_MAX_PAIR_ENTRIES (MCA_MAX_PAIRS + MCA_MAX_BODIES + MCA_MAX_ARMS)
/** Longest body name (bytes, without NUL), = string<32> in the IDL. */
#define MCA_DDS_NAME_MAX 32

/** One named pair of one kind (mca::dds::PairDistance): P on arm `arm`'s link `link`, Q on the other side:
 *  arm other_arm's link other_link (arm and self pairs) or body `body` (-1 for the other two). */
typedef struct mca_dds_named_pair {
    int32_t kind;                    /**< mca_dds_pair_kind_t */
    int16_t arm, link;               /**< the link holding P */
    int16_t other_arm, other_link;   /**< the other link (-1: a body) */
    int16_t body;                    /**< the body (cfg.body[] index; -1: none) */
    char name[MCA_DDS_NAME_MAX + 1]; /**< the body's name, NUL-terminated ("" for arm and self pairs) */
    double distance;                 /**< surface distance [m] */
    double clearance;                /**< what the pair keeps [m]: d1, or the body's clearance */
    double p[3], q[3];               /**< witness points (world) */
} mca_dds_named_pair_t;

/** Controller health (published on mca/controller_status). */
typedef struct mca_dds_status_snapshot {
    mca_dds_state_t state;
    int32_t fault_code;                          /**< 0 or a negative MCA_E* code */
    char fault_text[MCA_DDS_FAULT_TEXT_MAX + 1]; /**< NUL-terminated (truncated if longer) */
    uint64_t ticks, overruns;
    uint64_t skipped_periods;  /**< periods missed in all (one overrun can skip several) */
    uint64_t pdnn_budget_hits; /**< running ticks out of the PDNN's budget (time or steps; not faults) */
    int64_t compute_p50_ns, compute_p99_ns, compute_max_ns;
    int64_t jitter_p50_ns, jitter_p99_ns, jitter_p999_ns, jitter_max_ns;
    uint32_t pdnn_steps;
    double pdnn_residual;
    double min_distance_so_far;
    int64_t min_distance_stamp_ns;
} mca_dds_status_snapshot_t;

/** Everything published for one tick. Plain data: the loop keeps one and overwrites it each tick. */
typedef struct mca_dds_snapshot {
    uint64_t tick;    /**< controller tick number */
    int64_t stamp_ns; /**< tick time stamp [ns] (CLOCK_MONOTONIC in this repo's programs) */
    int64_t due_ns;   /**< when the tick was due, its point on the caller's grid (same clock; 0: stamp_ns):
                       *   the publisher's wake-up anchor (wake_period_ns), free of the tick's own jitter */
    uint32_t n_arms;  /**< <= MCA_MAX_ARMS */
    uint32_t n_pairs; /**< <= MCA_MAX_PAIRS */
    uint32_t n_named; /**< <= MCA_DDS_MAX_PAIR_ENTRIES */
    mca_dds_arm_snapshot_t arm[MCA_MAX_ARMS];
    mca_dds_pair_snapshot_t pair[MCA_MAX_PAIRS];
    mca_dds_named_pair_t
        named[MCA_DDS_MAX_PAIR_ENTRIES]; /**< every pair of every kind (mca/pair_distances) */
    mca_dds_status_snapshot_t status;
} mca_dds_snapshot_t;

/** Bridge settings; start from mca_dds_config_default(). */
typedef struct mca_dds_config {
    uint32_t domain_id;      /**< DDS domain (0..230) */
    const char *config_path; /**< Cyclone XML file, or NULL for CYCLONEDDS_URI / built-in defaults */
    uint32_t ring_capacity;  /**< snapshots in the ring, power of two (default 1024) */
    uint32_t status_divisor; /**< status every Nth published snapshot (default 100) + on change */
    uint8_t controller_id;   /**< key of ControllerStatus (default 0) */
    const char *frame_id;    /**< JointCommand.frame_id (default "world"); copied at create */
    const char *partition;   /**< DDS partition of the writers, NULL = default partition; copied.
                                  Separates controllers (or test runs) sharing a domain. */
    /** Optional, called by the publisher thread (non-rt) before it writes a ControllerStatus whose
     *  fault_code is not 0 and whose fault_text is empty: the owner writes the text (len bytes with
     *  the NUL) from what its rt side latched as a code and numbers, so that no text is formatted on
     *  the rt path. NULL: the snapshot's text as pushed. */
    void (*fault_text)(void *arg, const mca_dds_status_snapshot_t *st, char *text, size_t len);
    void *fault_text_arg;
    /** The caller's publishing period on CLOCK_MONOTONIC [ns] (publish divisor x loop period; the
     *  snapshots' stamp_ns must be CLOCK_MONOTONIC wake times of the ticks): after each snapshot the
     *  publisher sleeps until its stamp + wake_period_ns + wake_offset_ns instead of parking, so the push
     *  of an on-time tick makes no system call. 0 (default): parked, woken by the pushes. */
    uint64_t wake_period_ns;
    /** How long after a publishing tick's wake-up its push is expected [ns] (a bit over the tick's
     *  compute time): a push later than that finds the publisher parked and wakes it. */
    uint64_t wake_offset_ns;
    /** ROS 2 topics (mca/ros2.h), written from the same snapshots; NULL or !enabled: none. Copied. They are
     *  in the default partition whatever `partition` says (ROS 2 uses none). */
    const mca_ros2_config_t *ros2;
    /** Path of the publisher program (mca-dds-bridge): the publisher runs as that separate process, which
     *  alone talks DDS; NULL (default): a thread of the caller. In process mode fault_text is not called
     *  (the owner hands the text over with mca_dds_bridge_fault_text()) and wait_readers is not available. */
    const char *process_exe;
    /** > 0: the publisher thread runs SCHED_FIFO at this priority (1..98), so that a loaded CPU delays its
     *  samples no more than its own work does. Only that thread (it writes the samples): Cyclone's receive
     *  and timed-event threads handle what peers send, and keep the caller's policy so that a flood from the
     *  network cannot take a CPU at real-time priority. Not permitted (no CAP_SYS_NICE / RLIMIT_RTPRIO): the
     *  caller's policy, and mca_dds_stats_t.sched_refused says so. 0 (default): the caller's policy. */
    int sched_priority;
} mca_dds_config_t;

/** Bridge counters. */
typedef struct mca_dds_stats {
    uint64_t offered;         /**< mca_dds_bridge_push() calls */
    uint64_t queued;          /**< snapshots put into the ring (= offered: the caller decimates) */
    uint64_t published;       /**< snapshots written to DDS */
    uint64_t dropped;         /**< snapshots lost to ring overrun */
    uint64_t pending;         /**< snapshots in the ring now */
    uint64_t samples;         /**< DDS samples written (all topics) */
    uint64_t write_errors;    /**< dds_write failures */
    uint64_t invalid;         /**< snapshots rejected (n_arms, n_dof, ... out of range) */
    uint64_t max_pending;     /**< most snapshots seen waiting in the ring (high-water mark) */
    int64_t max_publish_ns;   /**< longest time spent writing one snapshot's samples */
    uint64_t wakes;           /**< pushes that woke the parked publisher (FUTEX_WAKE calls of the rt side) */
    uint64_t parks;           /**< times the publisher parked (slept on the futex with the ring empty) */
    uint64_t grid_sleeps;     /**< wake_period_ns: sleeps until the next publishing tick (no futex) */
    uint64_t stale;           /**< snapshots a restarted publisher skipped (older than the newest it found) */
    uint64_t restarts;        /**< process mode: publisher processes started after a death */
    uint64_t deaths;          /**< process mode: publisher processes that died (not at destroy) */
    uint64_t hung;            /**< process mode: of those, killed by the supervisor as hung */
    int32_t pid;              /**< process mode: the running publisher's pid, 0: none (down or restarting) */
    int down;                 /**< process mode: 1 = no publisher now: it died and its restart is pending (the
                               *   supervisor keeps restarting it for as long as the owner runs) */
    uint32_t deaths_in_a_row; /**< process mode: quick deaths in a row (each within
                               *   MCA_DDS_BRIDGE_STABLE_S of its start), 0 after a stable run */
    double backoff_s;         /**< process mode: the last back-off before a restart [s], 0: none yet */
    int sched_refused; /**< 1: sched_priority was not permitted; the publisher runs the caller's policy */
} mca_dds_stats_t;

/** Process mode: the first restart comes this long after a death [s], each further one (while each dies
 *  within MCA_DDS_BRIDGE_STABLE_S of its start) twice as long after the last, at most
 *  MCA_DDS_BRIDGE_BACKOFF_MAX_S, and never a last one: the supervisor keeps restarting it for as long as the
 *  owner runs (a peer that crashes every libddsc 0.10.2 participant, docs/dds.md, would otherwise
 *  take monitoring down for the rest of the run). Its log lines are thinned out after
 *  MCA_DDS_BRIDGE_LOG_ALL deaths in a row. */
#define MCA_DDS_BRIDGE_BACKOFF_S 0.1
#define MCA_DDS_BRIDGE_BACKOFF_MAX_S 2.0
/** A publisher that lived this long [s] was stable: the next death starts the back-off afresh. */
#define MCA_DDS_BRIDGE_STABLE_S 30.0
/** A publisher process that publishes nothing this long [s] while snapshots wait is hung: killed (SIGKILL),
 *  then restarted as after a death. */
#define MCA_DDS_BRIDGE_HUNG_S 5.0
/** Deaths in a row that are each logged with their restart; after that every MCA_DDS_BRIDGE_LOG_EVERY-th. */
#define MCA_DDS_BRIDGE_LOG_ALL 5
#define MCA_DDS_BRIDGE_LOG_EVERY 30
/** In a series whose restarts are no longer all logged, a publisher alive this long [s] is said to be up. */
#define MCA_DDS_BRIDGE_UP_S 5.0

typedef struct mca_dds_bridge mca_dds_bridge_t;

/** Default settings (domain 0, no config file, every tick, 1024 snapshots = 1 s). Context: any. */
void mca_dds_config_default(mca_dds_config_t *cfg);

/**
 * Create participant, topics and writers, allocate the ring and start the publisher thread, or (process_exe)
 * map the shared region and start the publisher program, waiting until it has made its DDS entities (its
 * set-up error is this function's). The program is started with posix_spawn (no fork of the caller's
 * memory), the region as its fd 3, every other descriptor closed, default signal mask. Context: init.
 * @param[out] out  new bridge (unchanged on error)
 * @param[in]  cfg  settings (copied)
 * @param[out] err  why it failed (Cyclone's or the publisher program's reason), errlen bytes; may be NULL.
 *                  Nothing is printed (in process mode the publisher program prints its own reason too).
 * @retval MCA_OK
 * @retval MCA_EINVAL  NULL argument, divisor 0, capacity not a power of two, domain id out of range,
 *                     frame id or partition too long
 * @retval MCA_ENOENT  config_path names a file that cannot be read
 * @retval MCA_EIO     Cyclone DDS refused (bad XML, no usable network interface, ...)
 * @retval MCA_ENOENT  ros2: a URDF for robot_description cannot be read; process_exe cannot be started
 * @retval MCA_ETIMEDOUT the publisher program was not up within 20 s
 * @retval MCA_ENOMEM
 */
int mca_dds_bridge_create(mca_dds_bridge_t **out, const mca_dds_config_t *cfg, char *err, size_t errlen);

/**
 * Hand one snapshot to the publisher: copies it into the ring (every call: decimation is the caller's,
 * so that a tick that does not publish fills nothing; only arm[0..n_arms), pair[0..n_pairs) and the rest
 * of the record: the entries past them are not published) and, if the publisher is parked, wakes it with
 * one FUTEX_WAKE (non-blocking); never waits, never fails. Context: rt, from ONE thread only (the loop).
 */
void mca_dds_bridge_push(mca_dds_bridge_t *bridge, const mca_dds_snapshot_t *snap);

/**
 * Process mode: notice a dead publisher (waitpid, WNOHANG: never blocks) or a hung one (nothing published for
 * MCA_DDS_BRIDGE_HUNG_S while snapshots wait: told and killed), tell a death with its cause to @p log
 * (level 3, `dds bridge (pid N) died: signal 11 (SIGSEGV); restart 1 in 0.5 s ...`), restart it when its
 * back-off has passed (the restarted one publishes the newest snapshot and the current status at once, and
 * the restart count, deaths and back-off on /diagnostics), log that it is up again; it never gives up (capped
 * back-off, MCA_DDS_BRIDGE_BACKOFF_*; logging thinned out after MCA_DDS_BRIDGE_LOG_ALL deaths in a row; the
 * loop is not affected: pushes go on into the ring, nobody reads them while it is down).
 * A mailbox the dead publisher was writing is closed as a target received long ago (task.stream brakes).
 * Call it every few ms from ONE non-rt thread, the one that created the bridge (the publisher process
 * ends with that thread: PR_SET_PDEATHSIG). In-process mode: does nothing. Context: non-rt.
 * The library prints nothing: its lines go to @p log (NULL: none are made).
 * @return lines given to log
 */
int mca_dds_bridge_supervise(mca_dds_bridge_t *bridge, mca_dds_log_fn log, void *log_arg);

/**
 * The text of the fault whose code the snapshots carry (written once per bridge): the publisher uses it for
 * ControllerStatus.fault_text when a snapshot has a fault code and no text (so the loop never formats).
 * Context: non-rt (the owner's supervisor, after the fault reached it).
 * @retval MCA_OK @retval MCA_EINVAL (NULL, code 0, or a text was already given)
 */
int mca_dds_bridge_fault_text(mca_dds_bridge_t *bridge, int32_t fault_code, const char *text);

/** Counters. Context: non-rt (any thread). @retval MCA_OK @retval MCA_EINVAL */
int mca_dds_bridge_stats(const mca_dds_bridge_t *bridge, mca_dds_stats_t *out);

/**
 * Wait until the writer of topic (one of the MCA_DDS_TOPIC_* names; NULL = every topic) has at least
 * n matched readers, or timeout_ms passes. For tests and tools that must not lose the first samples.
 * Context: non-rt.
 * @retval MCA_OK @retval MCA_ETIMEDOUT @retval MCA_EINVAL NULL bridge, unknown topic, or process mode
 */
int mca_dds_bridge_wait_readers(mca_dds_bridge_t *bridge, const char *topic, uint32_t n, uint32_t timeout_ms);

/**
 * Stop the publisher after it has written every queued snapshot, publish the final status
 * (with the final drop count), wait up to 1 s for reliable readers to acknowledge, delete the DDS
 * entities and free the bridge. Process mode: the publisher process does that and exits (waited for up to
 * 10 s, then SIGKILL); one that is down at that moment publishes nothing more. NULL is ignored. The loop
 * must no longer call push. Context: init.
 * @param[out] final_stats  if not NULL, the counters after the last write (published + dropped +
 *                          invalid == queued)
 */
void mca_dds_bridge_destroy(mca_dds_bridge_t *bridge, mca_dds_stats_t *final_stats);

/**
 * Fill one pair of a snapshot from the arm-to-arm distances of mca/armdist.h: global minimum with its
 * critical points and links, per-link closest distances of both arms, the thresholds and S(d) of
 * eq. (13). Context: rt (no allocation, bounded time).
 * @retval MCA_OK
 * @retval MCA_EINVAL NULL pointer, link counts outside 0..MCA_MAX_LINKS, or not 0 <= d1 < d2
 */
int mca_dds_pair_fill(mca_dds_pair_snapshot_t *out, const mca_arm_distances_t *dist, uint8_t arm_a,
                      uint8_t arm_b, double d1, double d2);

/**
 * Fill a snapshot's named pairs (n_named, named[]) from the controller's distances: each arm pair's least
 * (arm-arm), each body's closest link (arm-body for the cell's fixed bodies, arm-track for the streamed ones;
 * none for a body that allows every link), each arm's least self pair (self). Context: rt (no allocation,
 * bounded time).
 * @param cfg   the configuration the controller runs (mca_controller_get_config: n_arms, d1, the bodies)
 * @param dist  mca_controller_distances
 * @param pn    mca_controller_pair_nearest (NULL: arm pairs only)
 * @retval MCA_OK @retval MCA_EINVAL NULL snap, cfg or dist
 */
int mca_dds_named_fill(mca_dds_snapshot_t *snap, const mca_controller_config_t *cfg,
                       const mca_arm_distances_t (*dist)[MCA_MAX_ARMS], const mca_pair_nearest_t *pn);

/**
 * The latest accepted target of arm's ROS 2 stream (mca/ros2.h): a seqlock read, never waits, no system
 * call. Context: rt.
 * @retval MCA_OK @retval MCA_EINVAL (no bridge, no ROS 2 topics or no stream for that arm)
 * @retval MCA_EAGAIN (a new target is being written just now: keep the last one this tick)
 */
int mca_dds_bridge_stream_target(mca_dds_bridge_t *bridge, int arm, mca_ros2_target_t *out);

/**
 * The latest accepted message of streamed bodies (mca/ros2.h, mca_msgs/TrackedBodies): a seqlock read,
 * never waits, no system call. Context: rt.
 * @retval MCA_OK @retval MCA_EINVAL (no bridge, no ROS 2 topics or no streamed bodies)
 * @retval MCA_EAGAIN (being written just now: keep the last one this tick)
 */
int mca_dds_bridge_tracks(mca_dds_bridge_t *bridge, mca_ros2_tracks_t *out);

/** Topic names (also in docs/dds.md). */
#define MCA_DDS_TOPIC_JOINT_STATE "mca/joint_state"
#define MCA_DDS_TOPIC_JOINT_COMMAND "mca/joint_command"
#define MCA_DDS_TOPIC_DISTANCES "mca/distances"
#define MCA_DDS_TOPIC_STATUS "mca/controller_status"
#define MCA_DDS_TOPIC_PAIR_DISTANCES "mca/pair_distances"

#ifdef __cplusplus
}
#endif
#endif
