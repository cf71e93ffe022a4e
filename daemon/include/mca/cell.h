/* SPDX-License-Identifier: MIT */
/** @file mca/cell.h
 * Cell configuration of the controller daemon `mcad` (config/cells/NAME.yaml, format in docs/daemon.md):
 * the arms (model, base placement, initial joints, backend), the task (a scenario file and/or inline
 * paths), the scheme and solver parameters, DDS and real-time settings.
 *
 * mca_cell_load() parses the file with libcyaml against a fixed schema and then checks the meaning
 * (d1 < d2, files exist, q0 length = the URDF's joint count, backend known, period > 0, ...). Every
 * error message starts "FILE:LINE: FIELD: reason" (LINE 0 when no line can be named), so an operator
 * can go straight to the bad line. Nothing is commanded before the cell has loaded without error.
 *
 * Context: start-up only (allocates inside libcyaml and frees before returning, loads URDFs).
 */
#ifndef MCA_CELL_H
#define MCA_CELL_H

#include <stddef.h>
#include <stdint.h>

#include "mca/controller.h"
#include "mca/limits.h"
#include "mca/ros2.h" /* mca_ros2_stream_kind_t: the stream kinds' one numbering */
#include "mca/scenario.h"

#ifdef __cplusplus
extern "C" {
#endif

/** An arm's backend: its place in the backend registry (daemon/src/backends.c, one line per backend), which
 *  assigns the ids, so two backends never share one; mca_cell_backend_id() finds one by its name. The sim is
 *  the first (the default of mca_cell_from_scenario and the virtual-time driver's ideal arms). */
typedef enum mca_cell_backend {
    MCA_CELL_BACKEND_NONE = -1, /**< no backend has this name */
    MCA_CELL_BACKEND_SIM = 0,   /**< in-process simulated arm (mca/sim_backend.h) */
} mca_cell_backend_t;

/** Room for a backend's own settings in each cell arm (mca_cell_arm_t.backend_own). */
#define MCA_CELL_BACKEND_OWN_SIZE 512

/** A backend's own settings in a cell arm: declares `static type *fn(mca_cell_arm_t *)` and
 *  `fn##_c(const mca_cell_arm_t *)`, checked at compile time to fit (and be aligned in) backend_own. */
#define MCA_CELL_BACKEND_OWN(type, fn)                                                                       \
    _Static_assert(sizeof(type) <= MCA_CELL_BACKEND_OWN_SIZE, "raise MCA_CELL_BACKEND_OWN_SIZE");            \
    _Static_assert(_Alignof(type) <= _Alignof(double) && _Alignof(type) <= _Alignof(int64_t),                \
                   "backend_own is aligned for double and int64_t");                                         \
    static inline type *fn(mca_cell_arm_t *ca) {                                                             \
        return (type *)(void *)ca->backend_own.bytes;                                                        \
    }                                                                                                        \
    static inline const type *fn##_c(const mca_cell_arm_t *ca) {                                             \
        return (const type *)(const void *)ca->backend_own.bytes;                                            \
    }

/** What a streamed arm follows (task.stream): the bridge's kinds, so a cell arm's kind is handed to the
 *  bridge (mca_ros2_config_t.stream) as it is. */
typedef enum mca_cell_stream_kind {
    MCA_CELL_STREAM_NONE = MCA_ROS2_STREAM_NONE,
    MCA_CELL_STREAM_TWIST =
        MCA_ROS2_STREAM_TWIST, /**< geometry_msgs/TwistStamped on /<ns>/<arm>/target_twist */
    MCA_CELL_STREAM_POSE = MCA_ROS2_STREAM_POSE, /**< geometry_msgs/PoseStamped on /<ns>/<arm>/target_pose */
} mca_cell_stream_kind_t;

/** A streamed task (task.stream, docs/ros2.md): each arm's tool tip follows a ROS 2 topic. */
typedef struct mca_cell_stream {
    int enabled;
    double max_speed;  /**< twists faster are rejected; pose targets are approached at most this fast [m/s] */
    double pose_gain;  /**< pose: approach velocity = gain x (target - reference), capped [1/s] */
    double hold_after; /**< no accepted target for this long: the reference holds [s] */
    double brake_after;          /**< no accepted target for this long: a named fault, every arm brakes [s] */
    double box_lo[3], box_hi[3]; /**< workspace (world): pose targets outside are rejected, the reference
                                      stops at its walls */
} mca_cell_stream_t;

/** Streamed bodies (streamed_bodies, docs/scheme.md "Streamed bodies"): a person or a foreign machine
 *  tracked elsewhere, spheres or capsules on the DDS topic rt/<ns>/<topic> (mca::msg::TrackedBodies),
 *  taken only in a DDS Security cell (a plain cell that declares them is refused). */
typedef struct mca_cell_tracks {
    int enabled;
    char topic[32];       /**< ROS 2 name under /<ns>/ ("tracked_bodies") */
    int max_bodies;       /**< bodies taken from one sample, 1..MCA_MAX_TRACKS (MCA_MAX_TRACKS) */
    mca_ssm_params_t ssm; /**< growth, loss and S_p's terms (mca_ssm_default) */
} mca_cell_tracks_t;

/** Hardware side of one arm (the model and path live in the cell's scenario). */
typedef struct mca_cell_arm {
    mca_cell_backend_t backend;
    /* the bus keys every CAN backend shares: the registry's bus-clash check compares them across backends */
    char interface[32];            /**< "vcan0", "can0" */
    uint32_t id_base;              /**< the arm's CAN id block (socketcan) */
    double dec_limit[MCA_MAX_DOF]; /**< braking deceleration per joint [rad/s^2] */
    double priority;               /**< mca-ts: higher keeps its path, lower yields first (0: default 1) */
    int stream;                    /**< mca_cell_stream_kind_t (task.stream: twist unless the arm says) */
    /** A backend's own settings: its read keeps them here and its open reads them, as a struct of its own
     *  (MCA_CELL_BACKEND_OWN): a backend adds no field to this struct. */
    union {
        unsigned char bytes[MCA_CELL_BACKEND_OWN_SIZE];
        double align_d;
        int64_t align_i;
    } backend_own;
} mca_cell_arm_t;

/** ROS 2-native topics of the DDS bridge (dds.ros2 in the cell, docs/ros2.md); each on by default. */
typedef struct mca_cell_ros2 {
    int enabled;
    char ns[32];          /**< topic namespace /<ns>/ (default: the cell name, other characters as '_') */
    char world_frame[32]; /**< frame of the markers and of /tf_static's parents ("world") */
    int joint_states, robot_description, tf_static, markers, diagnostics;
} mca_cell_ros2_t;

/** DDS publishing. */
typedef struct mca_cell_dds {
    int enabled;
    uint32_t domain;
    char config[512];         /**< Cyclone XML (absolute), "" = CYCLONEDDS_URI / defaults */
    uint32_t publish_divisor; /**< publish every Nth tick */
    int priority;             /**< SCHED_FIFO priority of the publisher (mca-dds-bridge), below rt.priority;
                               *   0 = SCHED_OTHER */
    mca_cell_ros2_t ros2;
} mca_cell_dds_t;

/** Real-time settings. */
typedef struct mca_cell_rt {
    int64_t period_ns; /**< loop period (1 ms) */
    int priority;      /**< SCHED_FIFO priority 1..99; 0 = SCHED_OTHER */
    int cpu;           /**< CPU to pin the loop to, -1 = none */
    int overrun_limit; /**< consecutive overruns that are a fault */
    /** The PDNN's time per tick (the loader's default: half the period): the controller's pdnn_budget_ns;
     *  running out is a named fault, never an overrun. */
    int64_t pdnn_budget_ns;
    int lost_feedback_cycles; /**< cycles without new feedback from an arm that are a fault */
    int lock_memory;          /**< mlockall + pre-faulting */
    int dma_latency;          /**< hold /dev/cpu_dma_latency at 0 while running */
} mca_cell_rt_t;

typedef struct mca_cell {
    char name[64];
    char source[512];         /**< file it was loaded from */
    mca_scenario_t scn;       /**< task: arms' models, placements, q0, paths, duration, d1, d2, ... */
    mca_cell_stream_t stream; /**< task.stream: the arms follow ROS 2 topics instead of the paths */
    mca_scheme_kind_t scheme;
    mca_cell_arm_t arm[MCA_MAX_ARMS];
    /* solver overrides (< 0 / 0: the controller's default) */
    int pdnn_max_steps;
    double pdnn_tol;
    double eq_tol;
    double fault_residual;
    double deadlock_time; /**< mca-ts: all arms stalled this long is a deadlock [s] (<= 0: default) */
    double
        back_off_time; /**< mca-ts: the yielding arm runs its path backwards this long [s] (<= 0: default) */
    mca_cell_dds_t dds;
    mca_cell_rt_t rt;
    double stop_after;        /**< [s] of running after which the daemon stops by itself; 0 = never */
    mca_cell_tracks_t tracks; /**< streamed_bodies: a tracked person or machine (DDS Security cells only) */
    /* The test build's cell keys (mca/daemon_test.h). Every binary has these fields, so mca_cell_t has one
     * layout whichever library built it; the production build refuses the keys (MCA_ENOTSUP), so they stay
     * 0 there, and only the test build's code reads them. */
    uint64_t debug_stall_after_ticks; /**< the loop stalls after this many ticks; 0 = never */
    int debug_start_in_fault;         /**< sim backend arms start with a latched firmware fault (INJECTED), as
                                           if left from an earlier run (mcad --clear-faults) */
    uint64_t debug_kill_after_ticks;  /**< the daemon dies (SIGKILL, nothing braked) after this many ticks, as
                                           a crash would; 0 = never */
} mca_cell_t;

/**
 * Load and check a cell file; also loads every arm's URDF to check q0 against the joint count.
 * @param[out] cell  filled on success (unchanged on error); large, keep it off small stacks
 * @param[out] err   "FILE:LINE: FIELD: reason"
 * @retval MCA_OK
 * @retval MCA_ENOENT  cell, scenario, URDF or DDS config file missing
 * @retval MCA_EPARSE  YAML syntax, wrong type, unknown key, missing required field, empty or comment-only
 *                     file ("FILE:0: (document): empty document ...")
 * @retval MCA_ERANGE  a value out of range (d1 >= d2, period <= 0, priority, DOF mismatch, ...)
 * @retval MCA_ENOTSUP a debug_* key (a test hook) in the production build ("FILE:LINE: debug_...: test
 *                     hook, only the test build (mcad-test) takes it")
 * @retval MCA_EINVAL  NULL argument
 */
int mca_cell_load(const char *path, mca_cell_t *cell, char *err, size_t errlen);

/**
 * Controller configuration of a loaded cell (loads URDFs: start-up only).
 * @retval MCA_OK or the codes of mca_controller_config_from_scenario()
 */
int mca_cell_controller_config(const mca_cell_t *cell, mca_controller_config_t *cfg, char *err,
                               size_t errlen);

/**
 * A cell around a loaded scenario (mca-sim): every arm on the sim backend with the defaults of a cell file
 * (dec_limit 10 rad/s^2, no lag/latency/noise), period = the scenario's dt, DDS off, no real-time settings.
 * @retval MCA_OK, MCA_EINVAL (NULL, dt not a whole number of ns > 0)
 */
int mca_cell_from_scenario(mca_cell_t *cell, const mca_scenario_t *scn, mca_scheme_kind_t scheme);

/** The backend's name as in cell files: "sim", "socketcan", "canopen" (the backend registry's); "?" for an
 *  id no backend has. */
const char *mca_cell_backend_name(mca_cell_backend_t b);

/** The id of the backend named `name` ("socketcan"), or MCA_CELL_BACKEND_NONE. */
mca_cell_backend_t mca_cell_backend_id(const char *name);

/** Where an arm's backend reaches it, for a summary line (" vcan0 id_base 0x140"; "" for the sim backend);
 *  n_joints: the arm's joint count. */
void mca_cell_backend_describe(const mca_cell_arm_t *ca, int n_joints, char *buf, size_t len);

#ifdef __cplusplus
}
#endif
#endif
