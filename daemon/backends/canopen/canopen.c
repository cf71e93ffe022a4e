/* SPDX-License-Identifier: MIT */
/* The canopen backend: CiA 402 drives, one node per joint, one bus per arm (mca/canopen.h, docs/canopen.md),
 * a cell arm's
 *
 *     backend: canopen
 *     interface: can0
 *     canopen: {first_node: 1, sync_us: 4000, mode: csv}   # optional, each key too
 *
 * Its bus is its own: no arm of any backend beside it (one SYNC producer and NMT master). Calling context:
 * read and open at start-up (daemon__backends.h); the arm's read and write on the RT thread
 * (mca/canopen.h). */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "mca/canopen.h"
#include "mca/err.h"
#include "mca/yaml_load.h" /* MCA_YAML_OPT */

#include "canopen_cell.h"
#include "daemon__backends.h"

/* The canopen: section of a cell arm (NULL: key not in the file). */
typedef struct co_keys {
    int *first_node;
    int *sync_us;
    char *mode;
    double *pos_scale, *vel_scale;
    int *heartbeat_timeout_ms, *pdo_timeout_syncs;
} co_keys_t;

static const cyaml_schema_field_t co_fields[] = {
    CYAML_FIELD_INT_PTR("first_node", MCA_YAML_OPT, co_keys_t, first_node),
    CYAML_FIELD_INT_PTR("sync_us", MCA_YAML_OPT, co_keys_t, sync_us),
    CYAML_FIELD_STRING_PTR("mode", MCA_YAML_OPT, co_keys_t, mode, 3, 3),
    CYAML_FIELD_FLOAT_PTR("pos_scale", MCA_YAML_OPT, co_keys_t, pos_scale),
    CYAML_FIELD_FLOAT_PTR("vel_scale", MCA_YAML_OPT, co_keys_t, vel_scale),
    CYAML_FIELD_INT_PTR("heartbeat_timeout_ms", MCA_YAML_OPT, co_keys_t, heartbeat_timeout_ms),
    CYAML_FIELD_INT_PTR("pdo_timeout_syncs", MCA_YAML_OPT, co_keys_t, pdo_timeout_syncs),
    CYAML_FIELD_END,
};

static int canopen_read(const mca_check_ctx_t *c, mca_cell_t *cell, int a, const mca_backend_keys_t *k) {
    mca_canopen_cell_t *own = mca_canopen_cell(&cell->arm[a]);
    if (!k->interface) {
        MCA_BE_FAIL(MCA_EPARSE, MCA_BE_LINE("arms[%d].interface", a),
                    "arms[%d].interface: required with backend canopen", a);
    }
    const co_keys_t *rco = k->section;
    if (rco) {
        if (rco->first_node && (*rco->first_node < 1 || *rco->first_node > 127)) {
            MCA_BE_FAIL(MCA_ECONFIG, MCA_BE_LINE("arms[%d].canopen.first_node", a),
                        "arms[%d].canopen.first_node: 1..127 (got %d)", a, *rco->first_node);
        }
        if (rco->sync_us && *rco->sync_us < 100) {
            MCA_BE_FAIL(MCA_ECONFIG, MCA_BE_LINE("arms[%d].canopen.sync_us", a),
                        "arms[%d].canopen.sync_us: >= 100 (got %d)", a, *rco->sync_us);
        }
        if (rco->mode && strcmp(rco->mode, "csv") != 0 && strcmp(rco->mode, "csp") != 0) {
            MCA_BE_FAIL(MCA_ECONFIG, MCA_BE_LINE("arms[%d].canopen.mode", a),
                        "arms[%d].canopen.mode: csv or csp (got '%s')", a, rco->mode);
        }
        const int pos_bad = rco->pos_scale && !(*rco->pos_scale > 0 && isfinite(*rco->pos_scale));
        if (pos_bad || (rco->vel_scale && !(*rco->vel_scale > 0 && isfinite(*rco->vel_scale)))) {
            MCA_BE_FAIL(MCA_ECONFIG,
                        MCA_BE_LINE("arms[%d].canopen.%s", a, pos_bad ? "pos_scale" : "vel_scale"),
                        "arms[%d].canopen: pos_scale and vel_scale must be > 0", a);
        }
        const int hb_bad = rco->heartbeat_timeout_ms &&
                           (*rco->heartbeat_timeout_ms <= 100 || *rco->heartbeat_timeout_ms > 60000);
        if (hb_bad ||
            (rco->pdo_timeout_syncs && (*rco->pdo_timeout_syncs < 1 || *rco->pdo_timeout_syncs > 100000))) {
            MCA_BE_FAIL(
                MCA_ECONFIG,
                MCA_BE_LINE("arms[%d].canopen.%s", a, hb_bad ? "heartbeat_timeout_ms" : "pdo_timeout_syncs"),
                "arms[%d].canopen: heartbeat_timeout_ms 101..60000 (the drives beat every 100 ms), "
                "pdo_timeout_syncs 1..100000",
                a);
        }
    }
    own->first_node = rco && rco->first_node ? *rco->first_node : 1;
    own->sync_us = rco && rco->sync_us ? (uint32_t)*rco->sync_us : 4000;
    own->mode = rco && rco->mode && strcmp(rco->mode, "csp") == 0 ? 8 : 9;
    own->pos_scale = rco && rco->pos_scale ? *rco->pos_scale : 1e6;
    own->vel_scale = rco && rco->vel_scale ? *rco->vel_scale : 1e6;
    own->hb_timeout_ms = rco && rco->heartbeat_timeout_ms ? *rco->heartbeat_timeout_ms : 350;
    own->pdo_timeout = rco && rco->pdo_timeout_syncs ? *rco->pdo_timeout_syncs : 5;
    int rc = mca_backend_bus_keys(c, cell, a, k);
    if (rc != MCA_OK) {
        return rc;
    }
    return mca_backend_bus_check(c, cell, a);
}

static int canopen_open(mca_arm_t **arm, const mca_backend_open_args_t *o, char *err, size_t errlen) {
    const mca_cell_arm_t *ca = &o->cell->arm[o->arm];
    const mca_canopen_cell_t *own = mca_canopen_cell_c(ca);
    /* joint j = CiA 402 drive own->first_node + j on ca->interface (docs/canopen.md) */
    mca_co_master_config_t cc;
    mca_co_master_config_default(&cc, o->chain->dof, (uint8_t)own->first_node);
    snprintf(cc.iface, sizeof cc.iface, "%s", ca->interface);
    cc.mode = own->mode;
    cc.sync_period_us = own->sync_us;
    cc.hb_timeout_ms = (uint16_t)own->hb_timeout_ms;
    cc.pdo_timeout_cycles = own->pdo_timeout;
    for (int j = 0; j < cc.n; j++) {
        cc.drive[j].pos_scale = own->pos_scale;
        cc.drive[j].vel_scale = own->vel_scale;
    }
    return mca_canopen_backend_open(arm, &cc, (uint32_t)(o->cell->rt.period_ns / 1000), err, errlen);
}

static void canopen_describe(const mca_cell_arm_t *ca, int n_joints, char *buf, size_t len) {
    const mca_canopen_cell_t *own = mca_canopen_cell_c(ca);
    snprintf(buf, len, " %s nodes %d..%d sync %u us %s", ca->interface, own->first_node,
             own->first_node + n_joints - 1, own->sync_us, own->mode == 8 ? "csp" : "csv");
}

const mca_backend_def_t mca_backend_canopen = {
    .name = "canopen",
    .bus = MCA_BUS_OWNED,
    .section = "canopen",
    .section_fields = co_fields,
    .section_size = sizeof(co_keys_t),
    .read = canopen_read,
    .open = canopen_open,
    .fault_detail = mca_canopen_backend_fault,
    .describe = canopen_describe,
};
