/* SPDX-License-Identifier: MIT */
/* The cell loader's sections (cell.c reads the file, cell_*.c each check and copy one section of it into
 * mca_cell_t): the file as libcyaml loaded it (struct raw_*, every key optional but name, task and arms),
 * the messages' macros and one parser per section. Each section's ranges of the cell's own numbers sit
 * beside its parser (keys shared with scenarios use mca_scenario_range()); docs/daemon.md lists them.
 * Private to mca_daemon.
 *
 * Calling context: start-up only (mca_cell_load), any thread; allocates nothing itself (libcyaml and the
 * scenario loader do). Each parser runs in the order mca_cell_load calls them (task, solver, arms, dds,
 * rt: a later section reads what an earlier one set) and returns MCA_OK, or an MCA_E* code with
 * "FILE:LINE: FIELD: reason" in ctx.err. */
#ifndef MCA_CELL__LOAD_H
#define MCA_CELL__LOAD_H

#include <stdbool.h>

#include "mca/cell.h"
#include "mca/scenario.h" /* mca_check_ctx_t, mca_arm_keys_t, mca_body_keys_t */

#include "daemon__backends.h" /* MCA_BACKEND_MAX */

struct raw_arm {
    mca_arm_keys_t model; /* the scenario's arm keys, each optional here (the scenario gives the rest) */
    char *backend;
    char *interface;
    long long *id_base;
    double *dec_limit;
    double *priority;
    void *section[MCA_BACKEND_MAX]; /* backend i's own section (mca_backend_at(i)->section), as loaded */
    char *stream;
};

struct raw_stream {
    double *max_speed, *pose_gain, *hold_after, *brake_after;
    double *box_min;
    unsigned box_min_count;
    double *box_max;
    unsigned box_max_count;
};

struct raw_task {
    char *scenario;
    double *duration;
    struct raw_stream *stream;
};

struct raw_solver {
    mca_gain_keys_t gain;
    int *pdnn_max_steps;
    double *pdnn_tol, *eq_tol, *fault_residual;
    double *deadlock_time, *back_off_time;
};

struct raw_ros2 {
    bool *enabled;
    char *ns;
    char *world_frame;
    bool *joint_states, *robot_description, *tf_static, *markers, *diagnostics;
};

struct raw_dds {
    struct raw_ros2 *ros2;
    bool *enabled;
    long long *domain;
    char *config;
    long long *publish_divisor;
    int *priority;
};

struct raw_rt {
    long long *period_us;
    int *priority;
    int *cpu;
    int *overrun_limit;
    long long *pdnn_budget_us;
    int *lost_feedback_cycles;
    bool *lock_memory;
    bool *dma_latency;
};

struct raw_tracks {
    char *topic;
    long long *max_bodies;
    double *max_age, *lost_after, *approach_near, *approach_far, *approach_switch;
    double *reaction_time, *latency, *intrusion, *z_d, *z_r;
};

struct raw_cell {
    char *name;
    struct raw_task task;
    char *scheme;
    double *d1, *d2;
    struct raw_solver *solver;
    struct raw_arm *arms;
    unsigned arms_count;
    mca_body_keys_t *bodies;
    unsigned bodies_count;
    char **self_pairs;
    unsigned self_pairs_count;
    struct raw_dds *dds;
    struct raw_rt *rt;
    struct raw_tracks *tracks;
    double *stop_after;
    long long *debug_stall_after_ticks;
    long long *debug_kill_after_ticks;
    bool *debug_start_in_fault;
};

/* Fail with "FILE:LINE: message"; LINE(...) is the line of a printf-formatted field path in the cell's
 * marks ("arms[1].canopen.sync_us"), or of its nearest enclosing node when it is absent (a missing field). */
#define LINE(...) mca_yaml_marks_line_of(ctx.marks, __VA_ARGS__)
#define FAIL(code, line, ...)                                                                                \
    do {                                                                                                     \
        mca_errbuf_at(ctx.err, ctx.errlen, ctx.file, (line), __VA_ARGS__);                                   \
        rc = (code);                                                                                         \
        goto out;                                                                                            \
    } while (0)

/* Range check of one loaded value (ranges: mca_range_t), the one check the scenario reader uses
 * too; the field is printf-formatted and is also the node whose line is reported:
 * "FILE:LINE: FIELD: must be in [LO, HI] UNIT (got V)". */
#define CHECK(range, v, ...)                                                                                 \
    do {                                                                                                     \
        if ((rc = mca_check_range(&ctx, (range), (v), __VA_ARGS__)) != MCA_OK) {                             \
            goto out;                                                                                        \
        }                                                                                                    \
    } while (0)

/* Start-up: task: a scenario file or an inline task (duration), and task.stream. */
int mcad_cell_read_task(const mca_check_ctx_t ctx, const struct raw_cell *raw, mca_cell_t *cell);
/* Start-up: scheme, d1, d2 and the scheme's gains (the scenario's checks), solver. */
int mcad_cell_read_solver(const mca_check_ctx_t ctx, const struct raw_cell *raw, mca_cell_t *cell);
/* Start-up: arms: backend (its own section read by it), model keys over the scenario's, stream, dec_limit,
 * priority; sets scn->n_arms. */
int mcad_cell_read_arms(const mca_check_ctx_t ctx, const struct raw_cell *raw, mca_cell_t *cell);
/* Start-up: dds and dds.ros2 (the namespace defaults to the cell's name). */
int mcad_cell_read_dds(const mca_check_ctx_t ctx, const struct raw_cell *raw, mca_cell_t *cell);
/* Start-up: streamed_bodies, refused unless dds.config is a DDS Security configuration (after dds). */
int mcad_cell_read_tracks(const mca_check_ctx_t ctx, const struct raw_cell *raw, mca_cell_t *cell);
/* Start-up: rt (period, priority, cpu, limits, the PDNN budget), dds.priority below rt.priority, the
 * controller's dt and the task's tick count at it. */
int mcad_cell_read_rt(const mca_check_ctx_t ctx, const struct raw_cell *raw, mca_cell_t *cell);

#endif
