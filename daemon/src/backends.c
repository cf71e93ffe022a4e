/* SPDX-License-Identifier: MIT */
/* The arm backends of mcad: sim, socketcan, canopen here, and those in a folder of their own (replay)
 * (daemon__backends.h, docs/daemon.md).
 *
 * A static const table, not backends registering themselves from constructors: the backends live in static
 * libraries (mca_sim, mca_arm_can, mca_canopen), whose objects the linker leaves out when nothing names
 * them, so a constructor there could silently not run; and the libraries know nothing of cells (the keys
 * and their checks are the daemon's). One table, in one place, read-only: adding a backend is one entry. */
#include "daemon__backends.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#include "mca/arm_can.h"
#include "mca/can_proto.h" /* MCA_CAN_ID_BLOCK, MCA_CAN_ID_BASE_MAX */
#include "mca/canopen.h"
#include "mca/err.h"
#include "mca/errbuf.h" /* mca_errbuf_at */
#include "mca/sim_backend.h"
#include "mca/yaml_load.h"  /* MCA_YAML_OPT */
#include "mca/yaml_marks.h" /* mca_yaml_marks_load, mca_yaml_marks_line_of */

/* The line of a printf-formatted field of the cell (or of its nearest enclosing node). */
#define LINE(...) mca_yaml_marks_line_of(c->marks, __VA_ARGS__)
#define FAIL(code, line, ...)                                                                                \
    do {                                                                                                     \
        mca_errbuf_at(c->err, c->errlen, c->file, (line), __VA_ARGS__);                                      \
        return (code);                                                                                       \
    } while (0)
#define CHECK(range, v, ...)                                                                                 \
    do {                                                                                                     \
        int rc_ = mca_check_range(c, (range), (v), __VA_ARGS__);                                             \
        if (rc_ != MCA_OK) {                                                                                 \
            return rc_;                                                                                      \
        }                                                                                                    \
    } while (0)

/* keys every CAN backend shares: the interface, and an id block when the backend uses one */
static void copy_interface(mca_cell_arm_t *ca, const mca_backend_keys_t *k) {
    if (k->interface) {
        snprintf(ca->interface, sizeof ca->interface, "%s", k->interface);
    }
}

static int read_id_base(const mca_check_ctx_t *c, int a, const mca_backend_keys_t *k, mca_cell_arm_t *ca) {
    if (!k->id_base) {
        return MCA_OK;
    }
    if (*k->id_base < 0 || *k->id_base > (long long)MCA_CAN_ID_BASE_MAX ||
        *k->id_base % MCA_CAN_ID_BLOCK != 0) {
        FAIL(MCA_ECONFIG, LINE("arms[%d].id_base", a),
             "arms[%d].id_base: must be a multiple of 0x%x in 0..0x%x (got 0x%llx)", a, MCA_CAN_ID_BLOCK,
             MCA_CAN_ID_BASE_MAX, *k->id_base);
    }
    ca->id_base = (uint32_t)*k->id_base;
    return MCA_OK;
}

static const mca_backend_def_t *backend_of(const mca_cell_arm_t *ca);

/* Arm a's bus against every earlier arm's (arms 0..a-1 are read), by what the two backends say of their bus,
 * never by which of them comes first: a bus with a canopen arm on it is that arm's alone (one SYNC producer
 * and NMT master), whichever backend the other arm has; two id-block arms (socketcan) on one bus need two
 * id blocks (each would take the other's frames). The error is always arm a's. */
static int bus_check(const mca_check_ctx_t *c, const mca_cell_t *cell, int a) {
    const mca_cell_arm_t *ca = &cell->arm[a];
    const mca_backend_def_t *ba = backend_of(ca);
    for (int b = 0; b < a && ba && ba->bus != MCA_BUS_NONE; b++) {
        const mca_cell_arm_t *cb = &cell->arm[b];
        const mca_backend_def_t *bb = backend_of(cb);
        if (!bb || bb->bus == MCA_BUS_NONE || strcmp(cb->interface, ca->interface) != 0) {
            continue;
        }
        if (ba->bus == MCA_BUS_OWNED || bb->bus == MCA_BUS_OWNED) {
            FAIL(MCA_ECONFIG, LINE("arms[%d].interface", a),
                 "arms[%d].interface: %s is already arms[%d]'s (one bus per canopen arm)", a, ca->interface,
                 b);
        }
        if (cb->id_base == ca->id_base) {
            FAIL(MCA_ECONFIG, LINE("arms[%d].id_base", a),
                 "arms[%d].id_base: 0x%x on %s is already arms[%d]'s (one id block per arm and bus)", a,
                 ca->id_base, ca->interface, b);
        }
    }
    return MCA_OK;
}

/* ---------------------------------------------------------------- sim */

/* The sim: section of a cell arm (NULL: key not in the file). */
typedef struct sim_keys {
    double *lag_tau;
    int *latency_cycles;
    double *noise_pos;
} sim_keys_t;

static const cyaml_schema_field_t sim_fields[] = {
    CYAML_FIELD_FLOAT_PTR("lag_tau", MCA_YAML_OPT, sim_keys_t, lag_tau),
    CYAML_FIELD_INT_PTR("latency_cycles", MCA_YAML_OPT, sim_keys_t, latency_cycles),
    CYAML_FIELD_FLOAT_PTR("noise_pos", MCA_YAML_OPT, sim_keys_t, noise_pos),
    CYAML_FIELD_END,
};

/* Ranges of the sim model's keys (docs/daemon.md) */
static const mca_range_t r_lag_tau = {"lag_tau", 0.0, 1.0, 0, 0, "s"};
static const mca_range_t r_latency_cycles = {"latency_cycles", 0, 64, 0, 1, "cycles"};
static const mca_range_t r_noise_pos = {"noise_pos", 0.0, 0.1, 0, 0, "rad"};

static int sim_read(const mca_check_ctx_t *c, mca_cell_t *cell, int a, const mca_backend_keys_t *k) {
    mca_cell_arm_t *ca = &cell->arm[a];
    copy_interface(ca, k);
    int rc = read_id_base(c, a, k, ca);
    const sim_keys_t *sk = k->section;
    if (rc != MCA_OK || !sk) {
        return rc;
    }
    if (sk->lag_tau) {
        CHECK(&r_lag_tau, *sk->lag_tau, "arms[%d].sim.lag_tau", a);
        ca->sim_lag_tau = *sk->lag_tau;
    }
    if (sk->latency_cycles) {
        CHECK(&r_latency_cycles, *sk->latency_cycles, "arms[%d].sim.latency_cycles", a);
        ca->sim_latency_cycles = *sk->latency_cycles;
    }
    if (sk->noise_pos) {
        CHECK(&r_noise_pos, *sk->noise_pos, "arms[%d].sim.noise_pos", a);
        ca->sim_noise_pos = *sk->noise_pos;
    }
    return MCA_OK;
}

static int sim_open(mca_arm_t **arm, const mca_backend_open_args_t *o, char *err, size_t errlen) {
    const mca_cell_arm_t *ca = &o->cell->arm[o->arm];
    const mca_scenario_arm_t *sa = &o->cell->scn.arm[o->arm];
    mca_sim_arm_config_t sc;
    int rc = mca_sim_arm_config_from_chain(&sc, o->chain);
    if (rc != MCA_OK) {
        return rc;
    }
    for (int j = 0; j < sc.n; j++) {
        sc.q0[j] = sa->q0[j];
        sc.dec_limit[j] = ca->dec_limit[j];
        if (sc.acc_limit[j] < ca->dec_limit[j]) {
            sc.acc_limit[j] = ca->dec_limit[j];
        }
    }
    sc.dt = (double)o->cell->rt.period_ns * 1e-9;
    sc.lag_tau = ca->sim_lag_tau;
    sc.latency_cycles = ca->sim_latency_cycles;
    sc.noise_pos = ca->sim_noise_pos;
    sc.seed = 1 + (uint64_t)o->arm;
    sc.stamp_monotonic = !o->virtual_time;
    if (o->ideal) {
        /* mca-sim --euler: q += v dt with v the command, nothing limited */
        sc.ideal = 1;
        for (int j = 0; j < sc.n; j++) {
            sc.lower[j] = -INFINITY;
            sc.upper[j] = INFINITY;
            sc.vel_limit[j] = 1e300;
        }
    }
#ifdef MCA_TEST_HOOKS
    if (o->cell->debug_start_in_fault) {
        /* test hook: the firmware latches a fault in its first cycle (INIT -> FAULT), as a fault left from an
         * earlier run would be */
        sc.init_cycles = sc.init_cycles > 0 ? sc.init_cycles : 1;
        sc.n_inject = 1;
        sc.inject[0].kind = MCA_SIM_INJ_ACTUATOR;
        sc.inject[0].at_cycle = 0;
        sc.inject[0].joint = 0;
    }
#endif
    return mca_sim_backend_open(arm, &sc, err, errlen);
}

/* 6 sigma of the simulated measurement noise: a noisy sample is not a lie */
static double sim_feedback_margin(const mca_cell_arm_t *ca) {
    return 6.0 * ca->sim_noise_pos;
}

/* ---------------------------------------------------------------- socketcan */

static int socketcan_read(const mca_check_ctx_t *c, mca_cell_t *cell, int a, const mca_backend_keys_t *k) {
    mca_cell_arm_t *ca = &cell->arm[a];
    if (!k->interface) {
        FAIL(MCA_EPARSE, LINE("arms[%d].interface", a), "arms[%d].interface: required with backend socketcan",
             a);
    }
    if (!k->id_base) {
        FAIL(MCA_EPARSE, LINE("arms[%d].id_base", a), "arms[%d].id_base: required with backend socketcan", a);
    }
    copy_interface(ca, k);
    int rc = read_id_base(c, a, k, ca);
    if (rc != MCA_OK) {
        return rc;
    }
    return bus_check(c, cell, a);
}

static int socketcan_open(mca_arm_t **arm, const mca_backend_open_args_t *o, char *err, size_t errlen) {
    const mca_cell_arm_t *ca = &o->cell->arm[o->arm];
    /* the link refuses feedback outside the same bounds the daemon checks (at the decoder) */
    mca_can_options_t co;
    mca_can_options_default(&co);
    for (int j = 0; j < o->chain->dof; j++) {
        co.pos_lo[j] = o->fb_lo[j];
        co.pos_hi[j] = o->fb_hi[j];
        co.vel_max[j] = o->fb_vmax[j]; /* jumps: no faster than the velocity check allows */
    }
    return mca_can_backend_open(arm, ca->interface, ca->id_base, o->chain->dof, &co, err, errlen);
}

/* the arm's heartbeat names its joint count: the handshake waits for it */
static int socketcan_reported_joints(const mca_arm_t *arm, int *n) {
    mca_can_state_msg_t hb;
    const int rc = mca_can_backend_state(arm, &hb);
    if (rc == MCA_OK) {
        *n = hb.n;
    }
    return rc;
}

static void socketcan_describe(const mca_cell_arm_t *ca, int n_joints, char *buf, size_t len) {
    (void)n_joints;
    snprintf(buf, len, " %s id_base 0x%x", ca->interface, ca->id_base);
}

/* ---------------------------------------------------------------- canopen */

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
    mca_cell_arm_t *ca = &cell->arm[a];
    if (!k->interface) {
        FAIL(MCA_EPARSE, LINE("arms[%d].interface", a), "arms[%d].interface: required with backend canopen",
             a);
    }
    const co_keys_t *rco = k->section;
    if (rco) {
        if (rco->first_node && (*rco->first_node < 1 || *rco->first_node > 127)) {
            FAIL(MCA_ECONFIG, LINE("arms[%d].canopen.first_node", a),
                 "arms[%d].canopen.first_node: 1..127 (got %d)", a, *rco->first_node);
        }
        if (rco->sync_us && *rco->sync_us < 100) {
            FAIL(MCA_ECONFIG, LINE("arms[%d].canopen.sync_us", a),
                 "arms[%d].canopen.sync_us: >= 100 (got %d)", a, *rco->sync_us);
        }
        if (rco->mode && strcmp(rco->mode, "csv") != 0 && strcmp(rco->mode, "csp") != 0) {
            FAIL(MCA_ECONFIG, LINE("arms[%d].canopen.mode", a),
                 "arms[%d].canopen.mode: csv or csp (got '%s')", a, rco->mode);
        }
        const int pos_bad = rco->pos_scale && !(*rco->pos_scale > 0 && isfinite(*rco->pos_scale));
        if (pos_bad || (rco->vel_scale && !(*rco->vel_scale > 0 && isfinite(*rco->vel_scale)))) {
            FAIL(MCA_ECONFIG, LINE("arms[%d].canopen.%s", a, pos_bad ? "pos_scale" : "vel_scale"),
                 "arms[%d].canopen: pos_scale and vel_scale must be > 0", a);
        }
        const int hb_bad = rco->heartbeat_timeout_ms &&
                           (*rco->heartbeat_timeout_ms <= 100 || *rco->heartbeat_timeout_ms > 60000);
        if (hb_bad ||
            (rco->pdo_timeout_syncs && (*rco->pdo_timeout_syncs < 1 || *rco->pdo_timeout_syncs > 100000))) {
            FAIL(MCA_ECONFIG,
                 LINE("arms[%d].canopen.%s", a, hb_bad ? "heartbeat_timeout_ms" : "pdo_timeout_syncs"),
                 "arms[%d].canopen: heartbeat_timeout_ms 101..60000 (the drives beat every 100 ms), "
                 "pdo_timeout_syncs 1..100000",
                 a);
        }
    }
    ca->co_first_node = rco && rco->first_node ? *rco->first_node : 1;
    ca->co_sync_us = rco && rco->sync_us ? (uint32_t)*rco->sync_us : 4000;
    ca->co_mode = rco && rco->mode && strcmp(rco->mode, "csp") == 0 ? 8 : 9;
    ca->co_pos_scale = rco && rco->pos_scale ? *rco->pos_scale : 1e6;
    ca->co_vel_scale = rco && rco->vel_scale ? *rco->vel_scale : 1e6;
    ca->co_hb_timeout_ms = rco && rco->heartbeat_timeout_ms ? *rco->heartbeat_timeout_ms : 350;
    ca->co_pdo_timeout = rco && rco->pdo_timeout_syncs ? *rco->pdo_timeout_syncs : 5;
    copy_interface(ca, k);
    int rc = read_id_base(c, a, k, ca);
    if (rc != MCA_OK) {
        return rc;
    }
    return bus_check(c, cell, a);
}

static int canopen_open(mca_arm_t **arm, const mca_backend_open_args_t *o, char *err, size_t errlen) {
    const mca_cell_arm_t *ca = &o->cell->arm[o->arm];
    /* joint j = CiA 402 drive ca->co_first_node + j on ca->interface (docs/canopen.md) */
    mca_co_master_config_t cc;
    mca_co_master_config_default(&cc, o->chain->dof, (uint8_t)ca->co_first_node);
    snprintf(cc.iface, sizeof cc.iface, "%s", ca->interface);
    cc.mode = ca->co_mode;
    cc.sync_period_us = ca->co_sync_us;
    cc.hb_timeout_ms = (uint16_t)ca->co_hb_timeout_ms;
    cc.pdo_timeout_cycles = ca->co_pdo_timeout;
    for (int j = 0; j < cc.n; j++) {
        cc.drive[j].pos_scale = ca->co_pos_scale;
        cc.drive[j].vel_scale = ca->co_vel_scale;
    }
    return mca_canopen_backend_open(arm, &cc, (uint32_t)(o->cell->rt.period_ns / 1000), err, errlen);
}

static void canopen_describe(const mca_cell_arm_t *ca, int n_joints, char *buf, size_t len) {
    snprintf(buf, len, " %s nodes %d..%d sync %u us %s", ca->interface, ca->co_first_node,
             ca->co_first_node + n_joints - 1, ca->co_sync_us, ca->co_mode == 8 ? "csp" : "csv");
}

/* ---------------------------------------------------------------- the table */

/* The backends in a folder of their own (daemon/backends/NAME/NAME.c, each defining mca_backend_NAME and
 * taking its id from MCA_CELL_BACKEND_FOLDER up): adding one is its folder and its name on this line. */
#define MCA_FOLDER_BACKENDS(X) X(replay)

#define MCA_FOLDER_BACKEND_DECL(name) extern const mca_backend_def_t mca_backend_##name;
MCA_FOLDER_BACKENDS(MCA_FOLDER_BACKEND_DECL)

static const mca_backend_def_t builtin[] = {
    {
        .name = "sim",
        .id = MCA_CELL_BACKEND_SIM,
        .section = "sim",
        .section_fields = sim_fields,
        .section_size = sizeof(sim_keys_t),
        .read = sim_read,
        .open = sim_open,
        .feedback_margin = sim_feedback_margin,
    },
    {
        .name = "socketcan",
        .id = MCA_CELL_BACKEND_SOCKETCAN,
        .bus = MCA_BUS_ID_BLOCKS,
        .read = socketcan_read,
        .open = socketcan_open,
        .reported_joints = socketcan_reported_joints,
        .describe = socketcan_describe,
    },
    {
        .name = "canopen",
        .id = MCA_CELL_BACKEND_CANOPEN,
        .bus = MCA_BUS_OWNED,
        .section = "canopen",
        .section_fields = co_fields,
        .section_size = sizeof(co_keys_t),
        .read = canopen_read,
        .open = canopen_open,
        .fault_detail = mca_canopen_backend_fault,
        .describe = canopen_describe,
    },
};

#define MCA_FOLDER_BACKEND_ENTRY(name) &mca_backend_##name,
static const mca_backend_def_t *const backends[] = {&builtin[0], &builtin[1], &builtin[2],
                                                    MCA_FOLDER_BACKENDS(MCA_FOLDER_BACKEND_ENTRY)};
#define N_BACKENDS (sizeof backends / sizeof backends[0])
_Static_assert(N_BACKENDS <= MCA_BACKEND_MAX, "raise MCA_BACKEND_MAX");

const mca_backend_def_t *mca_backend_find(const char *name) {
    for (size_t i = 0; name && i < N_BACKENDS; i++) {
        if (strcmp(backends[i]->name, name) == 0) {
            return backends[i];
        }
    }
    return NULL;
}

const mca_backend_def_t *mca_backend_get(mca_cell_backend_t id) {
    for (size_t i = 0; i < N_BACKENDS; i++) {
        if (backends[i]->id == id) {
            return backends[i];
        }
    }
    return NULL;
}

int mca_backend_check_ids(const mca_cell_t *cell, char *err, size_t errlen) {
    for (int a = 0; a < cell->scn.n_arms && a < MCA_MAX_ARMS; a++) {
        if (mca_backend_get(cell->arm[a].backend)) {
            continue;
        }
        /* the id was set after the file was read (a cell read from a file has a known name): the line is
         * that of the arm's backend key in its file, when the file is still there */
        mca_yaml_marks_t marks = {0};
        const int line = mca_yaml_marks_load(cell->source, &marks, NULL, 0) == MCA_OK
                             ? mca_yaml_marks_line_of(&marks, "arms[%d].backend", a)
                             : 0;
        mca_yaml_marks_free(&marks);
        char known[128];
        mca_backend_names(known, sizeof known);
        mca_errbuf_at(err, errlen, cell->source, line, "arms[%d].backend: unknown backend id %d (known: %s)",
                      a, (int)cell->arm[a].backend, known);
        return MCA_ECONFIG;
    }
    return MCA_OK;
}

static const mca_backend_def_t *backend_of(const mca_cell_arm_t *ca) {
    return mca_backend_get(ca->backend);
}

const mca_backend_def_t *mca_backend_at(size_t i) {
    return i < N_BACKENDS ? backends[i] : NULL;
}

void mca_backend_names(char *buf, size_t len) {
    size_t n = 0;
    if (!buf || !len) {
        return;
    }
    buf[0] = 0;
    for (size_t i = 0; i < N_BACKENDS && n < len; i++) {
        const int w = snprintf(buf + n, len - n, "%s%s", i ? ", " : "", backends[i]->name);
        n += w > 0 ? (size_t)w : 0;
    }
}

const char *mca_cell_backend_name(mca_cell_backend_t b) {
    const mca_backend_def_t *be = mca_backend_get(b);
    return be ? be->name : "?";
}

void mca_cell_backend_describe(const mca_cell_arm_t *ca, int n_joints, char *buf, size_t len) {
    if (!buf || !len) {
        return;
    }
    buf[0] = 0;
    const mca_backend_def_t *be = ca ? mca_backend_get(ca->backend) : NULL;
    if (be && be->describe) {
        be->describe(ca, n_joints, buf, len);
    }
}
