/* SPDX-License-Identifier: MIT */
/* Cell configuration files of mcad (see mca/cell.h, docs/daemon.md). Start-up only. */
#include "mca/cell.h"

#include <cyaml/cyaml.h>
#include <math.h>
#include <pthread.h> /* pthread_once: the arm schema, built once from the backend registry */
#include <stddef.h>  /* offsetof */
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "mca/chain.h"
#include "mca/err.h"
#include "mca/errbuf.h" /* mca_errbuf_printf, mca_errbuf_at */
#include "mca/scenario.h"
#include "mca/scheme.h"
#include "mca/urdf.h"
#include "mca/yaml_load.h"
#include "mca/yaml_marks.h"

#include "cell__load.h"
#include "daemon__backends.h"

/* ---------------------------------------------------------------- schema */

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

static const cyaml_schema_field_t tracks_fields[] = {
    CYAML_FIELD_STRING_PTR("topic", OPT, struct raw_tracks, topic, 1, 31),
    CYAML_FIELD_INT_PTR("max_bodies", OPT, struct raw_tracks, max_bodies),
    CYAML_FIELD_FLOAT_PTR("max_age", OPT, struct raw_tracks, max_age),
    CYAML_FIELD_FLOAT_PTR("lost_after", OPT, struct raw_tracks, lost_after),
    CYAML_FIELD_FLOAT_PTR("approach_speed_near", OPT, struct raw_tracks, approach_near),
    CYAML_FIELD_FLOAT_PTR("approach_speed_far", OPT, struct raw_tracks, approach_far),
    CYAML_FIELD_FLOAT_PTR("approach_switch", OPT, struct raw_tracks, approach_switch),
    CYAML_FIELD_FLOAT_PTR("reaction_time", OPT, struct raw_tracks, reaction_time),
    CYAML_FIELD_FLOAT_PTR("latency", OPT, struct raw_tracks, latency),
    CYAML_FIELD_FLOAT_PTR("intrusion", OPT, struct raw_tracks, intrusion),
    CYAML_FIELD_FLOAT_PTR("uncertainty_sensor", OPT, struct raw_tracks, z_d),
    CYAML_FIELD_FLOAT_PTR("uncertainty_arm", OPT, struct raw_tracks, z_r),
    CYAML_FIELD_END,
};

static const cyaml_schema_field_t cell_fields[] = {
    CYAML_FIELD_STRING_PTR("name", CYAML_FLAG_POINTER, struct raw_cell, name, 1, 63),
    CYAML_FIELD_MAPPING("task", CYAML_FLAG_DEFAULT, struct raw_cell, task, task_fields),
    CYAML_FIELD_STRING_PTR("scheme", OPT, struct raw_cell, scheme, 1, 15),
    MCA_YAML_THRESHOLD_FIELDS(struct raw_cell),
    CYAML_FIELD_MAPPING_PTR("solver", OPT, struct raw_cell, solver, solver_fields),
    CYAML_FIELD_SEQUENCE("arms", CYAML_FLAG_POINTER, struct raw_cell, arms, &arm_entry, 1, MCA_MAX_ARMS),
    MCA_YAML_BODIES_FIELD(struct raw_cell, bodies),
    MCA_YAML_SELF_FIELD(struct raw_cell, self_pairs),
    CYAML_FIELD_MAPPING_PTR("dds", OPT, struct raw_cell, dds, dds_fields),
    CYAML_FIELD_MAPPING_PTR("rt", OPT, struct raw_cell, rt, rt_fields),
    CYAML_FIELD_MAPPING_PTR("streamed_bodies", OPT, struct raw_cell, tracks, tracks_fields),
    CYAML_FIELD_FLOAT_PTR("stop_after", OPT, struct raw_cell, stop_after),
    CYAML_FIELD_INT_PTR("debug_stall_after_ticks", OPT, struct raw_cell, debug_stall_after_ticks),
    CYAML_FIELD_INT_PTR("debug_kill_after_ticks", OPT, struct raw_cell, debug_kill_after_ticks),
    CYAML_FIELD_BOOL_PTR("debug_start_in_fault", OPT, struct raw_cell, debug_start_in_fault),
    CYAML_FIELD_END,
};

static const cyaml_schema_value_t cell_schema = {
    CYAML_VALUE_MAPPING(CYAML_FLAG_POINTER, struct raw_cell, cell_fields),
};

static const mca_range_t r_stop_after = {"stop_after", 0.0, 86400.0, 0, 0, "s"};

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

    if ((rc = mcad_cell_read_task(ctx, raw, cell)) != MCA_OK) {
        goto out;
    }
    if ((rc = mcad_cell_read_solver(ctx, raw, cell)) != MCA_OK) {
        goto out;
    }
    if ((rc = mcad_cell_read_arms(ctx, raw, cell)) != MCA_OK) {
        goto out;
    }
    /* fixed bodies: the scenario's, and the cell's over them (a body of the same name replaces it), with the
     * scenario's one check against the cell's arms */
    if ((rc = mca_scenario_bodies_apply(&ctx, raw->bodies, raw->bodies_count, &cell->scn)) != MCA_OK ||
        (rc = mca_scenario_self_apply(&ctx, raw->self_pairs, raw->self_pairs_count, &cell->scn)) != MCA_OK) {
        goto out;
    }
    if ((rc = mcad_cell_read_dds(ctx, raw, cell)) != MCA_OK) {
        goto out;
    }
    if ((rc = mcad_cell_read_tracks(ctx, raw, cell)) != MCA_OK) {
        goto out;
    }
    if ((rc = mcad_cell_read_rt(ctx, raw, cell)) != MCA_OK) {
        goto out;
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
    if (cell->tracks.enabled) {
        cfg->max_tracks = cell->tracks.max_bodies;
        cfg->ssm = cell->tracks.ssm;
    }
    return MCA_OK;
}
