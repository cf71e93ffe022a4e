/* SPDX-License-Identifier: MIT */
/* The cell's arms: each names its hardware (a backend of the registry, which reads its own keys), its
 * model and path come from the scenario or the cell (see cell__load.h). Start-up only. */
#include <stdio.h>
#include <string.h>

#include "mca/chain.h"
#include "mca/err.h"
#include "mca/errbuf.h" /* mca_errbuf_at */
#include "mca/scenario.h"
#include "mca/yaml_marks.h"

#include "daemon__backends.h"
#include "cell__load.h"

/* 1e-12 made a stop last for ever; a real joint brakes at 0.5-50 rad/s^2 */
static const mca_range_t r_dec_limit = {"dec_limit", 0.05, 100.0, 0, 0, "rad/s^2"};
/* longest brake from a joint's velocity limit at dec_limit */
#define CELL_MAX_STOP_S 60.0
static const mca_range_t r_arm_priority = {"priority", 0.0, 1000.0, 1, 0, ""};

int mcad_cell_read_arms(const mca_check_ctx_t ctx, const struct raw_cell *raw, mca_cell_t *cell) {
    int rc = MCA_OK;
    mca_scenario_t *scn = &cell->scn;
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
        ca->backend = mca_backend_id(be);
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
out:
    return rc;
}
