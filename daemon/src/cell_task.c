/* SPDX-License-Identifier: MIT */
/* The cell's task, scheme and solver sections (see cell__load.h). Start-up only. */
#include <stdio.h>
#include <string.h>

#include "mca/err.h"
#include "mca/errbuf.h" /* mca_errbuf_at */
#include "mca/scenario.h"
#include "mca/yaml_marks.h"

#include "cell__load.h"

/* Ranges of the cell's own numbers (keys shared with scenarios use mca_scenario_range()); docs/daemon.md
 * lists them. What a real cell can need: */
static const mca_range_t r_pdnn_max_steps = {"pdnn_max_steps", 1, 20000, 0, 1,
                                             "steps"}; /* 2000 ~ 1 ms here */
static const mca_range_t r_pdnn_tol = {"pdnn_tol", 0.0, 1e-2, 1, 0, ""};
static const mca_range_t r_eq_tol = {"eq_tol", 0.0, 0.1, 1, 0, "m"};
static const mca_range_t r_fault_residual = {"fault_residual", 0.0, 1e-2, 1, 0, ""};
static const mca_range_t r_deadlock_time = {"deadlock_time", 0.0, 60.0, 1, 0, "s"};
static const mca_range_t r_back_off_time = {"back_off_time", 0.0, 60.0, 1, 0, "s"};

int mcad_cell_read_task(const mca_check_ctx_t ctx, const struct raw_cell *raw, mca_cell_t *cell) {
    int rc = MCA_OK;
    const char *path = ctx.file;
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
        if (scn->sim_sphere.enabled) {
            /* a simulated tracker is mca-sim's; mcad's tracks come over DDS Security only (streamed_bodies)
             */
            FAIL(
                MCA_ECONFIG, LINE("task.scenario"),
                "task.scenario: %s:%d: simulated_sphere: a simulated streamed body is for mca-sim only; mcad "
                "takes streamed bodies over DDS Security (streamed_bodies:, docs/scheme.md section 14)",
                sp, scn->sim_sphere.line);
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
out:
    return rc;
}

int mcad_cell_read_solver(const mca_check_ctx_t ctx, const struct raw_cell *raw, mca_cell_t *cell) {
    int rc = MCA_OK;
    mca_scenario_t *scn = &cell->scn;
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
out:
    return rc;
}
