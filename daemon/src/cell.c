/* SPDX-License-Identifier: MIT */
/* Cell configuration files of mcad (see mca/cell.h, docs/daemon.md). Start-up only. */
#include "mca/cell.h"

#include <cyaml/cyaml.h>
#include <ctype.h>
#include <math.h>
#include <pthread.h> /* pthread_once: the arm schema, built once from the backend registry */
#include <stddef.h>  /* offsetof */
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "mca/chain.h"
#include "mca/err.h"
#include "mca/errbuf.h" /* mca_errbuf_printf, mca_errbuf_at */
#include "mca/scenario.h"
#include "mca/scheme.h"
#include "mca/ros2.h" /* mca_ros2_name_ok */
#include "mca/urdf.h"
#include "mca/yaml_load.h"
#include "mca/yaml_marks.h"

#include "daemon__backends.h"

/* ---------------------------------------------------------------- schema */

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

struct raw_cell {
    char *name;
    struct raw_task task;
    char *scheme;
    double *d1, *d2;
    struct raw_solver *solver;
    struct raw_arm *arms;
    unsigned arms_count;
    struct raw_dds *dds;
    struct raw_rt *rt;
    double *stop_after;
    long long *debug_stall_after_ticks;
    long long *debug_kill_after_ticks;
    bool *debug_start_in_fault;
};

#define OPT MCA_YAML_OPT

/* The keys of a cell arm that are the cell's; each backend's own section is added from the registry
 * (arm_schema_init). */
static const cyaml_schema_field_t arm_cell_fields[] = {
    MCA_YAML_ARM_FIELDS(struct raw_arm, model, OPT),
    CYAML_FIELD_STRING_PTR("backend", CYAML_FLAG_POINTER, struct raw_arm, backend, 1, 31),
    CYAML_FIELD_STRING_PTR("interface", OPT, struct raw_arm, interface, 1, 31),
    CYAML_FIELD_INT_PTR("id_base", OPT, struct raw_arm, id_base),
    CYAML_FIELD_FLOAT_PTR("dec_limit", OPT, struct raw_arm, dec_limit),
    CYAML_FIELD_FLOAT_PTR("priority", OPT, struct raw_arm, priority),
    CYAML_FIELD_STRING_PTR("stream", OPT, struct raw_arm, stream, 1, 15),
    CYAML_FIELD_END,
};

#define N_ARM_CELL_FIELDS (sizeof arm_cell_fields / sizeof arm_cell_fields[0] - 1)
static cyaml_schema_field_t arm_fields[N_ARM_CELL_FIELDS + MCA_BACKEND_MAX + 1];
static pthread_once_t arm_schema_once = PTHREAD_ONCE_INIT;

/* arm_fields: the cell's keys, then one optional mapping per backend that has a section, its schema the
 * backend's (the cell reader knows no backend's keys), then the end. */
static void arm_schema_init(void) {
    size_t n = 0;
    for (; n < N_ARM_CELL_FIELDS; n++) {
        arm_fields[n] = arm_cell_fields[n];
    }
    const mca_backend_def_t *be;
    for (size_t i = 0; (be = mca_backend_at(i)) != NULL; i++) {
        if (be->section) {
            arm_fields[n++] = (cyaml_schema_field_t){
                .key = be->section,
                .data_offset = (uint32_t)(offsetof(struct raw_arm, section) + i * sizeof(void *)),
                .value = {.type = CYAML_MAPPING,
                          .flags = (enum cyaml_flag)(OPT),
                          .data_size = (uint32_t)be->section_size,
                          .mapping = {.fields = be->section_fields}},
            };
        }
    }
    arm_fields[n] = (cyaml_schema_field_t)CYAML_FIELD_END;
}

static const cyaml_schema_value_t arm_entry = {
    CYAML_VALUE_MAPPING(CYAML_FLAG_DEFAULT, struct raw_arm, arm_fields),
};

static const cyaml_schema_field_t stream_fields[] = {
    CYAML_FIELD_FLOAT_PTR("max_speed", OPT, struct raw_stream, max_speed),
    CYAML_FIELD_FLOAT_PTR("pose_gain", OPT, struct raw_stream, pose_gain),
    CYAML_FIELD_FLOAT_PTR("hold_after", OPT, struct raw_stream, hold_after),
    CYAML_FIELD_FLOAT_PTR("brake_after", OPT, struct raw_stream, brake_after),
    CYAML_FIELD_SEQUENCE("workspace_min", CYAML_FLAG_POINTER | CYAML_FLAG_FLOW, struct raw_stream, box_min,
                         &mca_yaml_float_entry, 3, 3),
    CYAML_FIELD_SEQUENCE("workspace_max", CYAML_FLAG_POINTER | CYAML_FLAG_FLOW, struct raw_stream, box_max,
                         &mca_yaml_float_entry, 3, 3),
    CYAML_FIELD_END,
};

static const cyaml_schema_field_t task_fields[] = {
    CYAML_FIELD_STRING_PTR("scenario", OPT, struct raw_task, scenario, 1, 400),
    CYAML_FIELD_FLOAT_PTR("duration", OPT, struct raw_task, duration),
    CYAML_FIELD_MAPPING_PTR("stream", OPT, struct raw_task, stream, stream_fields),
    CYAML_FIELD_END,
};

static const cyaml_schema_field_t solver_fields[] = {
    MCA_YAML_GAIN_FIELDS(struct raw_solver, gain),
    CYAML_FIELD_INT_PTR("pdnn_max_steps", OPT, struct raw_solver, pdnn_max_steps),
    CYAML_FIELD_FLOAT_PTR("pdnn_tol", OPT, struct raw_solver, pdnn_tol),
    CYAML_FIELD_FLOAT_PTR("eq_tol", OPT, struct raw_solver, eq_tol),
    CYAML_FIELD_FLOAT_PTR("fault_residual", OPT, struct raw_solver, fault_residual),
    CYAML_FIELD_FLOAT_PTR("deadlock_time", OPT, struct raw_solver, deadlock_time),
    CYAML_FIELD_FLOAT_PTR("back_off_time", OPT, struct raw_solver, back_off_time),
    CYAML_FIELD_END,
};

static const cyaml_schema_field_t ros2_fields[] = {
    CYAML_FIELD_BOOL_PTR("enabled", OPT, struct raw_ros2, enabled),
    CYAML_FIELD_STRING_PTR("namespace", OPT, struct raw_ros2, ns, 1, 31),
    CYAML_FIELD_STRING_PTR("world_frame", OPT, struct raw_ros2, world_frame, 1, 31),
    CYAML_FIELD_BOOL_PTR("joint_states", OPT, struct raw_ros2, joint_states),
    CYAML_FIELD_BOOL_PTR("robot_description", OPT, struct raw_ros2, robot_description),
    CYAML_FIELD_BOOL_PTR("tf_static", OPT, struct raw_ros2, tf_static),
    CYAML_FIELD_BOOL_PTR("markers", OPT, struct raw_ros2, markers),
    CYAML_FIELD_BOOL_PTR("diagnostics", OPT, struct raw_ros2, diagnostics),
    CYAML_FIELD_END,
};

static const cyaml_schema_field_t dds_fields[] = {
    CYAML_FIELD_MAPPING_PTR("ros2", OPT, struct raw_dds, ros2, ros2_fields),
    CYAML_FIELD_BOOL_PTR("enabled", OPT, struct raw_dds, enabled),
    CYAML_FIELD_INT_PTR("domain", OPT, struct raw_dds, domain),
    CYAML_FIELD_STRING_PTR("config", OPT, struct raw_dds, config, 0, 400),
    CYAML_FIELD_INT_PTR("publish_divisor", OPT, struct raw_dds, publish_divisor),
    CYAML_FIELD_INT_PTR("priority", OPT, struct raw_dds, priority),
    CYAML_FIELD_END,
};

static const cyaml_schema_field_t rt_fields[] = {
    CYAML_FIELD_INT_PTR("period_us", OPT, struct raw_rt, period_us),
    CYAML_FIELD_INT_PTR("priority", OPT, struct raw_rt, priority),
    CYAML_FIELD_INT_PTR("cpu", OPT, struct raw_rt, cpu),
    CYAML_FIELD_INT_PTR("overrun_limit", OPT, struct raw_rt, overrun_limit),
    CYAML_FIELD_INT_PTR("pdnn_budget_us", OPT, struct raw_rt, pdnn_budget_us),
    CYAML_FIELD_INT_PTR("lost_feedback_cycles", OPT, struct raw_rt, lost_feedback_cycles),
    CYAML_FIELD_BOOL_PTR("lock_memory", OPT, struct raw_rt, lock_memory),
    CYAML_FIELD_BOOL_PTR("dma_latency", OPT, struct raw_rt, dma_latency),
    CYAML_FIELD_END,
};

static const cyaml_schema_field_t cell_fields[] = {
    CYAML_FIELD_STRING_PTR("name", CYAML_FLAG_POINTER, struct raw_cell, name, 1, 63),
    CYAML_FIELD_MAPPING("task", CYAML_FLAG_DEFAULT, struct raw_cell, task, task_fields),
    CYAML_FIELD_STRING_PTR("scheme", OPT, struct raw_cell, scheme, 1, 15),
    MCA_YAML_THRESHOLD_FIELDS(struct raw_cell),
    CYAML_FIELD_MAPPING_PTR("solver", OPT, struct raw_cell, solver, solver_fields),
    CYAML_FIELD_SEQUENCE("arms", CYAML_FLAG_POINTER, struct raw_cell, arms, &arm_entry, 1, MCA_MAX_ARMS),
    CYAML_FIELD_MAPPING_PTR("dds", OPT, struct raw_cell, dds, dds_fields),
    CYAML_FIELD_MAPPING_PTR("rt", OPT, struct raw_cell, rt, rt_fields),
    CYAML_FIELD_FLOAT_PTR("stop_after", OPT, struct raw_cell, stop_after),
    CYAML_FIELD_INT_PTR("debug_stall_after_ticks", OPT, struct raw_cell, debug_stall_after_ticks),
    CYAML_FIELD_INT_PTR("debug_kill_after_ticks", OPT, struct raw_cell, debug_kill_after_ticks),
    CYAML_FIELD_BOOL_PTR("debug_start_in_fault", OPT, struct raw_cell, debug_start_in_fault),
    CYAML_FIELD_END,
};

static const cyaml_schema_value_t cell_schema = {
    CYAML_VALUE_MAPPING(CYAML_FLAG_POINTER, struct raw_cell, cell_fields),
};

/* ---------------------------------------------------------------- messages */

/* Fail with "FILE:LINE: message"; LINE(...) is the line of a printf-formatted field path in the cell's
 * marks ("arms[1].canopen.sync_us"), or of its nearest enclosing node when it is absent (a missing field). */
#define LINE(...) mca_yaml_marks_line_of(&marks, __VA_ARGS__)
#define FAIL(code, line, ...)                                                                                \
    do {                                                                                                     \
        mca_errbuf_at(err, errlen, path, (line), __VA_ARGS__);                                               \
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

/* Ranges of the cell's own numbers (keys shared with scenarios use mca_scenario_range()); docs/daemon.md
 * lists them. What a real cell can need: */
static const mca_range_t r_pdnn_max_steps = {"pdnn_max_steps", 1, 20000, 0, 1,
                                             "steps"}; /* 2000 ~ 1 ms here */
static const mca_range_t r_pdnn_tol = {"pdnn_tol", 0.0, 1e-2, 1, 0, ""};
static const mca_range_t r_eq_tol = {"eq_tol", 0.0, 0.1, 1, 0, "m"};
static const mca_range_t r_fault_residual = {"fault_residual", 0.0, 1e-2, 1, 0, ""};
static const mca_range_t r_deadlock_time = {"deadlock_time", 0.0, 60.0, 1, 0, "s"};
static const mca_range_t r_back_off_time = {"back_off_time", 0.0, 60.0, 1, 0, "s"};
/* 1e-12 made a stop last for ever; a real joint brakes at 0.5-50 rad/s^2 */
static const mca_range_t r_dec_limit = {"dec_limit", 0.05, 100.0, 0, 0, "rad/s^2"};
/* longest brake from a joint's velocity limit at dec_limit */
#define CELL_MAX_STOP_S 60.0
static const mca_range_t r_arm_priority = {"priority", 0.0, 1000.0, 1, 0, ""};
static const mca_range_t r_dds_domain = {"domain", 0, 230, 0, 1, ""};
static const mca_range_t r_publish_divisor = {"publish_divisor", 1, 100000, 0, 1, "ticks"};
static const mca_range_t r_rt_priority = {"priority", 0, 99, 0, 1, "(0 = SCHED_OTHER)"};
static const mca_range_t r_dds_priority = {"priority", 0, 98, 0, 1, "(0 = SCHED_OTHER)"};
/* overruns: real arms need 3-10; arms in virtual time (the sim backend, lockstep emulators on an emulated
 * CPU) tolerate any stall, so up to the longest task's tick count (an hour of periods) */
static const mca_range_t r_overrun_limit = {"overrun_limit", 1, MCA_SCENARIO_MAX_TICKS, 0, 1, "periods"};
#define CELL_MAX_OVERRUN_S 3600.0
/* the PDNN's time per tick: from 10 us up to 1 s (an emulated CPU; a real loop wants half its period) */
static const mca_range_t r_pdnn_budget_us = {"pdnn_budget_us", 10, 1000000, 0, 1, "us"};
/* lost feedback: the arm is blind while these pass; at most 1000 cycles and 1 s */
static const mca_range_t r_lost_feedback_cycles = {"lost_feedback_cycles", 1, 1000, 0, 1, "cycles"};
#define CELL_MAX_LOST_FEEDBACK_S 1.0
static const mca_range_t r_stop_after = {"stop_after", 0.0, 86400.0, 0, 0, "s"};

/* The default ROS 2 namespace of a cell: its name with every other character as one '_' ("monitor-vs-mcad"
 * -> "monitor_vs_mcad"), "cell_" in front when it does not start with a letter. */
static void ros2_name_from(char *out, size_t len, const char *name) {
    size_t n = 0;
    if (!isalpha((unsigned char)name[0]) && len > 5) {
        n = (size_t)snprintf(out, len, "cell_");
    }
    for (const char *c = name; *c && n + 1 < len; c++) {
        const int ok = isalnum((unsigned char)*c);
        if (ok) {
            out[n++] = *c;
        } else if (n > 0 && out[n - 1] != '_') {
            out[n++] = '_';
        }
    }
    while (n > 0 && out[n - 1] == '_') {
        n--;
    }
    out[n] = '\0';
    if (n == 0) {
        snprintf(out, len, "cell");
    }
}

/* ---------------------------------------------------------------- load */

int mca_cell_load(const char *path, mca_cell_t *out, char *err, size_t errlen) {
    if (!path || !out) {
        mca_errbuf_printf(err, errlen, "cell: NULL argument");
        return MCA_EINVAL;
    }
    struct raw_cell *raw = NULL;
    mca_yaml_marks_t marks;
    pthread_once(&arm_schema_once, arm_schema_init);
    int rc = mca_yaml_load(path, "cell", &cell_schema, (void **)&raw, &marks, err, errlen);
    if (rc != MCA_OK) {
        return rc;
    }
    const mca_check_ctx_t ctx = {.file = path, .marks = &marks, .err = err, .errlen = errlen};
    mca_cell_t *cell = calloc(1, sizeof *cell);
    if (!cell) {
        rc = MCA_ENOMEM;
        mca_errbuf_printf(err, errlen, "%s:0: out of memory", path);
        goto out;
    }
    snprintf(cell->name, sizeof cell->name, "%s", raw->name);
    snprintf(cell->source, sizeof cell->source, "%s", path);
#ifndef MCA_TEST_HOOKS
    {
        /* production holds no test hooks. The keys stay in the schema so that the error names
         * the line (not a generic unknown key), before anything else is checked. */
        const char *hook = raw->debug_stall_after_ticks  ? "debug_stall_after_ticks"
                           : raw->debug_kill_after_ticks ? "debug_kill_after_ticks"
                           : raw->debug_start_in_fault   ? "debug_start_in_fault"
                                                         : NULL;
        if (hook) {
            FAIL(MCA_ENOTSUP, LINE("%s", hook),
                 "%s: test hook: this mcad is the production build, which takes no debug_* keys (only the "
                 "test build mcad-test does); remove the line",
                 hook);
        }
    }
#endif

    /* task: a scenario file, or inline (arms carry urdf/base/q0/path themselves) */
    mca_scenario_t *scn = &cell->scn;
    if (raw->task.scenario) {
        char sp[512];
        if ((rc = mca_config_find(&ctx, "task.scenario", raw->task.scenario, sp, sizeof sp)) != MCA_OK) {
            goto out;
        }
        char serr[512];
        int src = mca_scenario_load(sp, scn, serr, sizeof serr);
        if (src != MCA_OK) {
            FAIL(src, LINE("task.scenario"), "task.scenario: %s", serr);
        }
    } else {
        mca_scenario_defaults(scn);
        snprintf(scn->name, sizeof scn->name, "%s", raw->name);
        snprintf(scn->source, sizeof scn->source, "%s", path);
        scn->n_arms = 0;
        if (!raw->task.duration) {
            FAIL(MCA_EPARSE, LINE("task.duration"),
                 "task: an inline task needs 'duration' (or give 'scenario')");
        }
    }
    if (raw->task.duration) {
        CHECK(mca_scenario_range("duration"), *raw->task.duration, "task.duration");
        scn->duration = *raw->task.duration;
    }
    if (raw->task.stream) {
        const struct raw_stream *rs = raw->task.stream;
        mca_cell_stream_t *cs = &cell->stream;
        cs->enabled = 1;
        cs->max_speed = 0.25;
        cs->pose_gain = 2.0;
        cs->hold_after = 0.1;
        cs->brake_after = 1.0;
        const struct {
            const char *key;
            const double *v;
            double *dst, lo, hi;
        } nums[] = {
            {"max_speed", rs->max_speed, &cs->max_speed, 1e-3, 2.0},
            {"pose_gain", rs->pose_gain, &cs->pose_gain, 0.1, 50.0},
            {"hold_after", rs->hold_after, &cs->hold_after, 0.002, 10.0},
            {"brake_after", rs->brake_after, &cs->brake_after, 0.002, 60.0},
        };
        for (size_t k = 0; k < sizeof nums / sizeof nums[0]; k++) {
            if (nums[k].v) {
                if (!(*nums[k].v >= nums[k].lo && *nums[k].v <= nums[k].hi)) {
                    FAIL(MCA_ECONFIG, LINE("task.stream.%s", nums[k].key),
                         "task.stream.%s: %g outside %g..%g", nums[k].key, *nums[k].v, nums[k].lo,
                         nums[k].hi);
                }
                *nums[k].dst = *nums[k].v;
            }
        }
        if (cs->hold_after > cs->brake_after) {
            FAIL(MCA_ECONFIG, LINE("task.stream.hold_after"),
                 "task.stream.hold_after: %g s after brake_after %g s", cs->hold_after, cs->brake_after);
        }
        for (int i = 0; i < 3; i++) {
            CHECK(mca_scenario_range("base_xyz"), rs->box_min[i], "task.stream.workspace_min[%d]", i);
            CHECK(mca_scenario_range("base_xyz"), rs->box_max[i], "task.stream.workspace_max[%d]", i);
            if (!(rs->box_min[i] < rs->box_max[i])) {
                FAIL(MCA_ECONFIG, LINE("task.stream.workspace_max[%d]", i),
                     "task.stream.workspace_max[%d]: %g not above workspace_min %g", i, rs->box_max[i],
                     rs->box_min[i]);
            }
            cs->box_lo[i] = rs->box_min[i];
            cs->box_hi[i] = rs->box_max[i];
        }
    }

    cell->scheme = MCA_SCHEME_MCA_TS; /* the default for cells */
    if (raw->scheme && mca_scheme_from_name(raw->scheme, &cell->scheme) != MCA_OK) {
        FAIL(MCA_ECONFIG, LINE("scheme"), "scheme: unknown scheme '%s' (known: mca-ts, mca, mvn, apf)",
             raw->scheme);
    }
    {
        /* d1, d2 and the scheme's gains: the scenario's checks (its values stay where the cell gives none) */
        const mca_param_keys_t keys = {.solver = "solver.",
                                       .d1 = raw->d1,
                                       .d2 = raw->d2,
                                       .gain = raw->solver ? &raw->solver->gain : NULL};
        if ((rc = mca_scenario_params_apply(&ctx, &keys, &scn->params, &scn->has_form)) != MCA_OK) {
            goto out;
        }
    }
    cell->pdnn_max_steps = 0;
    cell->pdnn_tol = cell->eq_tol = cell->fault_residual = -1.0;
    cell->deadlock_time = cell->back_off_time = -1.0;
    if (raw->solver) {
        const struct raw_solver *s = raw->solver;
        if (s->deadlock_time) {
            CHECK(&r_deadlock_time, *s->deadlock_time, "solver.deadlock_time");
            cell->deadlock_time = *s->deadlock_time;
        }
        if (s->back_off_time) {
            CHECK(&r_back_off_time, *s->back_off_time, "solver.back_off_time");
            cell->back_off_time = *s->back_off_time;
        }
        if (s->pdnn_max_steps) {
            CHECK(&r_pdnn_max_steps, *s->pdnn_max_steps, "solver.pdnn_max_steps");
            cell->pdnn_max_steps = *s->pdnn_max_steps;
        }
        if (s->pdnn_tol) {
            CHECK(&r_pdnn_tol, *s->pdnn_tol, "solver.pdnn_tol");
            cell->pdnn_tol = *s->pdnn_tol;
        }
        if (s->eq_tol) {
            CHECK(&r_eq_tol, *s->eq_tol, "solver.eq_tol");
            cell->eq_tol = *s->eq_tol;
        }
        if (s->fault_residual) {
            CHECK(&r_fault_residual, *s->fault_residual, "solver.fault_residual");
            cell->fault_residual = *s->fault_residual;
        }
    }

    /* arms: the cell names the hardware; model and path come from the scenario arm of the same name,
     * and any model field given in the cell overrides it */
    if (raw->task.scenario && raw->arms_count != (unsigned)scn->n_arms) {
        FAIL(MCA_ECONFIG, LINE("arms"), "arms: %u arms but scenario '%s' has %d", raw->arms_count,
             scn->source, scn->n_arms);
    }
    mca_scenario_arm_t sarm[MCA_MAX_ARMS];
    memcpy(sarm, scn->arm, sizeof sarm);
    for (unsigned a = 0; a < raw->arms_count; a++) {
        const struct raw_arm *ra = &raw->arms[a];
        const int ai = (int)a;
        mca_cell_arm_t *ca = &cell->arm[a];
        mca_scenario_arm_t *sa = &scn->arm[a];
        for (unsigned b = 0; b < a; b++) {
            if (strcmp(raw->arms[b].model.name, ra->model.name) == 0) {
                FAIL(MCA_ECONFIG, LINE("arms[%d].name", ai), "arms[%d].name: '%s' used twice", ai,
                     ra->model.name);
            }
        }
        if (raw->task.scenario) {
            int found = -1;
            char names[160] = "";
            for (int s = 0; s < scn->n_arms; s++) {
                if (strcmp(sarm[s].name, ra->model.name) == 0) {
                    found = s;
                }
                if (s) {
                    strncat(names, ", ", sizeof names - strlen(names) - 1);
                }
                strncat(names, sarm[s].name, sizeof names - strlen(names) - 1);
            }
            if (found < 0) {
                FAIL(MCA_ECONFIG, LINE("arms[%d].name", ai),
                     "arms[%d].name: no arm '%s' in scenario %s (it has: %s)", ai, ra->model.name,
                     scn->source, names);
            }
            *sa = sarm[found];
        } else {
            memset(sa, 0, sizeof *sa);
            snprintf(sa->name, sizeof sa->name, "%s", ra->model.name);
            if (!ra->model.urdf || !ra->model.base_xyz || !ra->model.q0) {
                FAIL(MCA_EPARSE, LINE("arms[%d]", ai),
                     "arms[%d]: an inline task needs urdf, base_xyz and q0 for every arm", ai);
            }
            sa->path.kind = MCA_PATH_HOLD;
            sa->path.relative = 1;
        }
        /* backend: the registry's, by name; its keys read and checked by it */
        const mca_backend_def_t *be = mca_backend_find(ra->backend);
        if (!be) {
            char known[128];
            mca_backend_names(known, sizeof known);
            FAIL(MCA_ECONFIG, LINE("arms[%d].backend", ai),
                 "arms[%d].backend: unknown backend '%s' (known: %s)", ai, ra->backend, known);
        }
        ca->backend = be->id;
        /* a backend's own section belongs to it alone */
        const void *own = NULL;
        const mca_backend_def_t *owner;
        for (size_t i = 0; (owner = mca_backend_at(i)) != NULL; i++) {
            if (owner == be) {
                own = ra->section[i];
            } else if (ra->section[i]) {
                FAIL(MCA_EPARSE, LINE("arms[%d].%s", ai, owner->section), "arms[%d].%s: only with backend %s",
                     ai, owner->section, owner->name);
            }
        }
        const mca_backend_keys_t bkeys = {.interface = ra->interface, .id_base = ra->id_base, .section = own};
        if ((rc = be->read(&ctx, cell, ai, &bkeys)) != MCA_OK) {
            goto out;
        }
        /* the model keys the cell gives over its scenario's: the scenario's one check */
        if ((rc = mca_scenario_arm_apply(&ctx, ai, &ra->model, sa)) != MCA_OK) {
            goto out;
        }
        if (ra->stream && !raw->task.stream) {
            FAIL(MCA_EPARSE, LINE("arms[%d].stream", ai),
                 "arms[%d].stream: only in a streamed task (task.stream)", ai);
        }
        if (raw->task.stream) {
            /* the arm follows its ROS 2 topic: the path from the scenario or the cell is replaced */
            ca->stream = MCA_CELL_STREAM_TWIST;
            if (ra->stream && strcmp(ra->stream, "pose") == 0) {
                ca->stream = MCA_CELL_STREAM_POSE;
            } else if (ra->stream && strcmp(ra->stream, "twist") != 0) {
                FAIL(MCA_ECONFIG, LINE("arms[%d].stream", ai), "arms[%d].stream: '%s' (known: twist, pose)",
                     ai, ra->stream);
            }
            memset(&sa->path, 0, sizeof sa->path);
            sa->path.kind = MCA_PATH_STREAM;
            memcpy(sa->path.box_lo, cell->stream.box_lo, sizeof sa->path.box_lo);
            memcpy(sa->path.box_hi, cell->stream.box_hi, sizeof sa->path.box_hi);
        }
        /* the model: DOF must match q0, q0 within the joint limits (the scenario's check) */
        if ((rc = mca_scenario_arm_model(&ctx, ai, sa)) != MCA_OK) {
            goto out;
        }
        const mca_chain_t *chain = &sa->chain;
        const double dec = ra->dec_limit ? *ra->dec_limit : 10.0;
        CHECK(&r_dec_limit, dec, "arms[%d].dec_limit", ai);
        for (int j = 0; j < chain->dof; j++) {
            /* a stop has a bounded duration: from the joint's velocity limit to rest */
            const double stop_s = chain->joint[j].vel_limit / dec;
            if (!(stop_s <= CELL_MAX_STOP_S)) {
                FAIL(MCA_ECONFIG, LINE("arms[%d].dec_limit", ai),
                     "arms[%d].dec_limit: %g rad/s^2 brakes joint '%s' from its velocity limit %g rad/s in "
                     "%.3g s, "
                     "more than %g s",
                     ai, dec, chain->joint[j].name, chain->joint[j].vel_limit, stop_s, CELL_MAX_STOP_S);
            }
        }
        for (int j = 0; j < MCA_MAX_DOF; j++) {
            ca->dec_limit[j] = dec;
        }
        ca->priority = 0.0;
        if (ra->priority) {
            CHECK(&r_arm_priority, *ra->priority, "arms[%d].priority", ai);
            ca->priority = *ra->priority;
        }
    }
    scn->n_arms = (int)raw->arms_count;

    /* DDS */
    cell->dds.enabled = 1;
    cell->dds.domain = 0;
    cell->dds.publish_divisor = 1;
    if (raw->dds) {
        const struct raw_dds *d = raw->dds;
        if (d->enabled) {
            cell->dds.enabled = *d->enabled;
        }
        if (d->domain) {
            CHECK(&r_dds_domain, (double)*d->domain, "dds.domain");
            cell->dds.domain = (uint32_t)*d->domain;
        }
        if (d->config && d->config[0]) {
            if ((rc = mca_config_find(&ctx, "dds.config", d->config, cell->dds.config,
                                      sizeof cell->dds.config)) != MCA_OK) {
                goto out;
            }
        }
        if (d->publish_divisor) {
            CHECK(&r_publish_divisor, (double)*d->publish_divisor, "dds.publish_divisor");
            cell->dds.publish_divisor = (uint32_t)*d->publish_divisor;
        }
        if (d->priority) {
            CHECK(&r_dds_priority, *d->priority, "dds.priority");
            cell->dds.priority = *d->priority;
        }
    }
    if (cell->stream.enabled &&
        !(cell->dds.enabled &&
          (!raw->dds || !raw->dds->ros2 || !raw->dds->ros2->enabled || *raw->dds->ros2->enabled))) {
        FAIL(MCA_ECONFIG, LINE("task.stream"),
             "task.stream: the targets come over ROS 2: needs dds.enabled and dds.ros2.enabled");
    }
    /* ROS 2 topics: on with DDS unless switched off; every topic on unless switched off */
    mca_cell_ros2_t *r2 = &cell->dds.ros2;
    r2->enabled = r2->joint_states = r2->robot_description = r2->tf_static = r2->markers = r2->diagnostics =
        1;
    ros2_name_from(r2->ns, sizeof r2->ns, cell->name);
    snprintf(r2->world_frame, sizeof r2->world_frame, "world");
    if (raw->dds && raw->dds->ros2) {
        const struct raw_ros2 *rr = raw->dds->ros2;
        bool *const flag_src[] = {rr->enabled,   rr->joint_states, rr->robot_description,
                                  rr->tf_static, rr->markers,      rr->diagnostics};
        int *const flag_dst[] = {&r2->enabled,   &r2->joint_states, &r2->robot_description,
                                 &r2->tf_static, &r2->markers,      &r2->diagnostics};
        for (size_t k = 0; k < sizeof flag_src / sizeof flag_src[0]; k++) {
            if (flag_src[k]) {
                *flag_dst[k] = *flag_src[k];
            }
        }
        if (rr->ns) {
            if (!mca_ros2_name_ok(rr->ns)) {
                FAIL(MCA_ECONFIG, LINE("dds.ros2.namespace"),
                     "dds.ros2.namespace: '%s' is not a ROS 2 name (a letter, then letters, digits and "
                     "single '_')",
                     rr->ns);
            }
            snprintf(r2->ns, sizeof r2->ns, "%s", rr->ns);
        }
        if (rr->world_frame) {
            if (!mca_ros2_name_ok(rr->world_frame)) {
                FAIL(MCA_ECONFIG, LINE("dds.ros2.world_frame"),
                     "dds.ros2.world_frame: '%s' is not a frame name (a letter, then letters, digits and "
                     "single '_')",
                     rr->world_frame);
            }
            snprintf(r2->world_frame, sizeof r2->world_frame, "%s", rr->world_frame);
        }
    }

    /* real time */
    mca_cell_rt_t *rt = &cell->rt;
    rt->period_ns = 1000000;
    rt->priority = 80;
    rt->cpu = -1;
    rt->overrun_limit = 10;
    rt->lost_feedback_cycles = 10;
    rt->lock_memory = 1;
    rt->dma_latency = 1;
    if (raw->rt) {
        const struct raw_rt *r = raw->rt;
        if (r->period_us) {
            /* the loop period is the controller's dt: the scenario's dt range, in us */
            const mca_range_t *dt = mca_scenario_range("dt");
            const mca_range_t r_period_us = {"period_us", llround(dt->lo * 1e6), llround(dt->hi * 1e6), 0, 1,
                                             "us"};
            CHECK(&r_period_us, (double)*r->period_us, "rt.period_us");
            rt->period_ns = *r->period_us * 1000;
        }
        if (r->priority) {
            CHECK(&r_rt_priority, *r->priority, "rt.priority");
            rt->priority = *r->priority;
        }
        if (r->cpu) {
            const long ncpu = sysconf(_SC_NPROCESSORS_CONF);
            if (*r->cpu < -1 || (ncpu > 0 && *r->cpu >= ncpu)) {
                FAIL(MCA_ECONFIG, LINE("rt.cpu"), "rt.cpu: must be -1 (none) or 0..%ld (got %d)", ncpu - 1,
                     *r->cpu);
            }
            rt->cpu = *r->cpu;
        }
        const double period_s = (double)rt->period_ns * 1e-9;
        if (r->overrun_limit) {
            CHECK(&r_overrun_limit, *r->overrun_limit, "rt.overrun_limit");
            if (*r->overrun_limit * period_s > CELL_MAX_OVERRUN_S) {
                FAIL(MCA_ECONFIG, LINE("rt.overrun_limit"),
                     "rt.overrun_limit: %d periods of %g s are %g s of overruns, more than %g s",
                     *r->overrun_limit, period_s, *r->overrun_limit * period_s, CELL_MAX_OVERRUN_S);
            }
            rt->overrun_limit = *r->overrun_limit;
        }
        if (r->pdnn_budget_us) {
            CHECK(&r_pdnn_budget_us, (double)*r->pdnn_budget_us, "rt.pdnn_budget_us");
            rt->pdnn_budget_ns = *r->pdnn_budget_us * 1000;
        }
        if (r->lost_feedback_cycles) {
            CHECK(&r_lost_feedback_cycles, *r->lost_feedback_cycles, "rt.lost_feedback_cycles");
            if (*r->lost_feedback_cycles * period_s > CELL_MAX_LOST_FEEDBACK_S + 1e-12) {
                FAIL(MCA_ECONFIG, LINE("rt.lost_feedback_cycles"),
                     "rt.lost_feedback_cycles: %d cycles of %g s are %g s without feedback, more than %g s",
                     *r->lost_feedback_cycles, period_s, *r->lost_feedback_cycles * period_s,
                     CELL_MAX_LOST_FEEDBACK_S);
            }
            rt->lost_feedback_cycles = *r->lost_feedback_cycles;
        }
        if (r->lock_memory) {
            rt->lock_memory = *r->lock_memory;
        }
        if (r->dma_latency) {
            rt->dma_latency = *r->dma_latency;
        }
    }
    if (rt->pdnn_budget_ns == 0) {
        rt->pdnn_budget_ns = rt->period_ns / 2; /* the default: half the period */
    }
    if (cell->dds.priority > 0 && cell->dds.priority >= rt->priority) {
        /* the publisher must never delay the loop it publishes for (also when both share a CPU) */
        FAIL(MCA_ECONFIG, LINE("dds.priority"), "dds.priority: %d must be below rt.priority (%d%s)",
             cell->dds.priority, rt->priority, rt->priority == 0 ? ", SCHED_OTHER" : "");
    }
    /* the controller's prediction uses the loop period */
    scn->params.dt = (double)rt->period_ns * 1e-9;
    {
        /* the task's tick count at this period (the scenario checked it at its own dt) */
        char why[160];
        if (mca_scenario_check_duration(scn->duration, scn->params.dt, why, sizeof why) != MCA_OK) {
            FAIL(MCA_ECONFIG, LINE("%s", raw->task.duration ? "task.duration" : "task.scenario"),
                 "task.duration: %s", why);
        }
    }

    if (raw->stop_after) {
        CHECK(&r_stop_after, *raw->stop_after, "stop_after");
        cell->stop_after = *raw->stop_after;
    }
#ifdef MCA_TEST_HOOKS
    if (raw->debug_stall_after_ticks) {
        if (*raw->debug_stall_after_ticks < 0) {
            FAIL(MCA_ECONFIG, LINE("debug_stall_after_ticks"), "debug_stall_after_ticks: must be >= 0");
        }
        cell->debug_stall_after_ticks = (uint64_t)*raw->debug_stall_after_ticks;
    }
    if (raw->debug_kill_after_ticks) {
        if (*raw->debug_kill_after_ticks < 0) {
            FAIL(MCA_ECONFIG, LINE("debug_kill_after_ticks"), "debug_kill_after_ticks: must be >= 0");
        }
        cell->debug_kill_after_ticks = (uint64_t)*raw->debug_kill_after_ticks;
    }
    cell->debug_start_in_fault = raw->debug_start_in_fault && *raw->debug_start_in_fault;
#endif
    *out = *cell;
out:
    free(cell);
    mca_yaml_marks_free(&marks);
    mca_yaml_free(&cell_schema, raw);
    return rc;
}

int mca_cell_from_scenario(mca_cell_t *cell, const mca_scenario_t *scn, mca_scheme_kind_t scheme) {
    if (!cell || !scn || !(scn->params.dt > 0.0) || !(scn->params.dt < 10.0)) {
        return MCA_EINVAL;
    }
    memset(cell, 0, sizeof *cell);
    snprintf(cell->name, sizeof cell->name, "%s", scn->name);
    snprintf(cell->source, sizeof cell->source, "%s", scn->source);
    cell->scn = *scn;
    cell->scheme = scheme;
    for (int a = 0; a < scn->n_arms; a++) {
        cell->arm[a].backend = MCA_CELL_BACKEND_SIM;
        for (int j = 0; j < MCA_MAX_DOF; j++) {
            cell->arm[a].dec_limit[j] = 10.0;
        }
    }
    cell->pdnn_tol = cell->eq_tol = cell->fault_residual = -1.0;
    cell->deadlock_time = cell->back_off_time = -1.0;
    cell->dds.enabled = 0;
    cell->dds.publish_divisor = 1;
    cell->rt.period_ns = llround(scn->params.dt * 1e9);
    if (cell->rt.period_ns <= 0 || fabs((double)cell->rt.period_ns * 1e-9 - scn->params.dt) > 1e-15) {
        return MCA_EINVAL;
    }
    cell->rt.cpu = -1;
    cell->rt.overrun_limit = 10;
    cell->rt.pdnn_budget_ns = cell->rt.period_ns / 2;
    cell->rt.lost_feedback_cycles = 10;
    return MCA_OK;
}

int mca_cell_controller_config(const mca_cell_t *cell, mca_controller_config_t *cfg, char *err,
                               size_t errlen) {
    if (!cell || !cfg) {
        mca_errbuf_printf(err, errlen, "cell: NULL argument");
        return MCA_EINVAL;
    }
    int rc = mca_controller_config_from_scenario(cfg, &cell->scn, cell->scheme, err, errlen);
    if (rc != MCA_OK) {
        return rc;
    }
    if (cell->pdnn_max_steps > 0) {
        cfg->pdnn.max_steps = cell->pdnn_max_steps;
    }
    /* one budget everywhere: the time budget's steps, in virtual time too (mca-sim, the sweep) */
    cfg->pdnn_budget_steps = mca_pdnn_budget_steps(cell->rt.pdnn_budget_ns);
    if (cell->pdnn_tol > 0.0) {
        cfg->pdnn.tol = cell->pdnn_tol;
    }
    if (cell->eq_tol > 0.0) {
        cfg->eq_tol = cell->eq_tol;
    }
    if (cell->fault_residual > 0.0) {
        cfg->fault_residual = cell->fault_residual;
    }
    cfg->dt = (double)cell->rt.period_ns * 1e-9;
    for (int a = 0; a < cfg->n_arms; a++) {
        /* the stoppability bound (mca-ts) assumes the least deceleration of the arm's joints */
        double dec = INFINITY;
        for (int j = 0; j < cfg->chain[a].dof; j++) {
            dec = fmin(dec, cell->arm[a].dec_limit[j]);
        }
        cfg->ts.dec_limit[a] = isfinite(dec) && dec > 0.0 ? dec : 0.0;
        if (cell->arm[a].priority > 0.0) {
            cfg->ts.priority[a] = cell->arm[a].priority;
        }
    }
    if (cell->deadlock_time > 0.0) {
        cfg->ts.deadlock_time = cell->deadlock_time;
    }
    if (cell->back_off_time > 0.0) {
        cfg->ts.back_off_time = cell->back_off_time;
    }
    return MCA_OK;
}
