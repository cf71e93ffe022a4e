/* SPDX-License-Identifier: MIT */
/* The registry of mcad's arm backends (daemon__backends.h, docs/daemon.md "Backends"): each backend is a
 * folder of its own, daemon/backends/NAME/, defining `const mca_backend_def_t mca_backend_NAME`, and its name
 * on the one line MCA_BACKENDS below. Its place on that line is its id (mca_cell_arm_t.backend): the registry
 * assigns the ids, so no two backends can share one and none is picked by hand.
 *
 * A static const table, not backends registering themselves from constructors: the backends' arm code lives
 * in static libraries (mca_sim, mca_arm_can, mca_canopen), whose objects the linker leaves out when nothing
 * names them, so a constructor there could silently not run. One table, in one place, read-only. */
#include "daemon__backends.h"

#include <stdio.h>
#include <string.h>

#include "mca/can_proto.h" /* MCA_CAN_ID_BLOCK, MCA_CAN_ID_BASE_MAX */
#include "mca/err.h"
#include "mca/errbuf.h"     /* mca_errbuf_at */
#include "mca/yaml_marks.h" /* mca_yaml_marks_load, mca_yaml_marks_line_of */

/* Every backend, in id order; the sim first (MCA_CELL_BACKEND_SIM). Adding a backend: its folder, its name
 * here. */
#define MCA_BACKENDS(X) X(sim) X(socketcan) X(canopen) X(replay)

#define MCA_BACKEND_DECL(name) extern const mca_backend_def_t mca_backend_##name;
MCA_BACKENDS(MCA_BACKEND_DECL)

#define MCA_BACKEND_ENTRY(name) &mca_backend_##name,
static const mca_backend_def_t *const backends[] = {MCA_BACKENDS(MCA_BACKEND_ENTRY)};
#define N_BACKENDS (sizeof backends / sizeof backends[0])
_Static_assert(N_BACKENDS <= MCA_BACKEND_MAX, "raise MCA_BACKEND_MAX");

#define MCA_BACKEND_INDEX(name) MCA_BACKEND_INDEX_##name,
enum { MCA_BACKENDS(MCA_BACKEND_INDEX) };
_Static_assert((int)MCA_BACKEND_INDEX_sim == (int)MCA_CELL_BACKEND_SIM,
               "the sim is the registry's first backend");

int mca_backend_bus_keys(const mca_check_ctx_t *c, mca_cell_t *cell, int a, const mca_backend_keys_t *k) {
    mca_cell_arm_t *ca = &cell->arm[a];
    if (k->interface) {
        snprintf(ca->interface, sizeof ca->interface, "%s", k->interface);
    }
    if (!k->id_base) {
        return MCA_OK;
    }
    if (*k->id_base < 0 || *k->id_base > (long long)MCA_CAN_ID_BASE_MAX ||
        *k->id_base % MCA_CAN_ID_BLOCK != 0) {
        MCA_BE_FAIL(MCA_ECONFIG, MCA_BE_LINE("arms[%d].id_base", a),
                    "arms[%d].id_base: must be a multiple of 0x%x in 0..0x%x (got 0x%llx)", a,
                    MCA_CAN_ID_BLOCK, MCA_CAN_ID_BASE_MAX, *k->id_base);
    }
    ca->id_base = (uint32_t)*k->id_base;
    return MCA_OK;
}

/* A bus with a canopen arm on it is that arm's alone (one SYNC producer and NMT master), whichever backend
 * the other arm has; two id-block arms (socketcan) on one bus need two id blocks (each would take the other's
 * frames). The error is always arm a's. */
int mca_backend_bus_check(const mca_check_ctx_t *c, const mca_cell_t *cell, int a) {
    const mca_cell_arm_t *ca = &cell->arm[a];
    const mca_backend_def_t *ba = mca_backend_get(ca->backend);
    for (int b = 0; b < a && ba && ba->bus != MCA_BUS_NONE; b++) {
        const mca_cell_arm_t *cb = &cell->arm[b];
        const mca_backend_def_t *bb = mca_backend_get(cb->backend);
        if (!bb || bb->bus == MCA_BUS_NONE || strcmp(cb->interface, ca->interface) != 0) {
            continue;
        }
        if (ba->bus == MCA_BUS_OWNED || bb->bus == MCA_BUS_OWNED) {
            MCA_BE_FAIL(MCA_ECONFIG, MCA_BE_LINE("arms[%d].interface", a),
                        "arms[%d].interface: %s is already arms[%d]'s (one bus per canopen arm)", a,
                        ca->interface, b);
        }
        if (cb->id_base == ca->id_base) {
            MCA_BE_FAIL(MCA_ECONFIG, MCA_BE_LINE("arms[%d].id_base", a),
                        "arms[%d].id_base: 0x%x on %s is already arms[%d]'s (one id block per arm and bus)",
                        a, ca->id_base, ca->interface, b);
        }
    }
    return MCA_OK;
}

const mca_backend_def_t *mca_backend_find(const char *name) {
    for (size_t i = 0; name && i < N_BACKENDS; i++) {
        if (strcmp(backends[i]->name, name) == 0) {
            return backends[i];
        }
    }
    return NULL;
}

const mca_backend_def_t *mca_backend_get(mca_cell_backend_t id) {
    return (int)id >= 0 && (size_t)id < N_BACKENDS ? backends[id] : NULL;
}

mca_cell_backend_t mca_backend_id(const mca_backend_def_t *be) {
    for (size_t i = 0; be && i < N_BACKENDS; i++) {
        if (backends[i] == be) {
            return (mca_cell_backend_t)i;
        }
    }
    return MCA_CELL_BACKEND_NONE;
}

mca_cell_backend_t mca_cell_backend_id(const char *name) {
    return mca_backend_id(mca_backend_find(name));
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
