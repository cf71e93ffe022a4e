/* SPDX-License-Identifier: MIT */
/* The socketcan backend: an arm behind SocketCAN CAN FD (mca/arm_can.h), one CAN id block per arm on a
 * shared bus, a cell arm's
 *
 *     backend: socketcan
 *     interface: vcan0
 *     id_base: 0x140
 *
 * Calling context: read and open at start-up (daemon__backends.h); the arm's read and write on the RT thread
 * (mca/arm_can.h). */
#include <stdio.h>

#include "mca/arm_can.h"
#include "mca/err.h"

#include "daemon__backends.h"

static int socketcan_read(const mca_check_ctx_t *c, mca_cell_t *cell, int a, const mca_backend_keys_t *k) {
    if (!k->interface) {
        MCA_BE_FAIL(MCA_EPARSE, MCA_BE_LINE("arms[%d].interface", a),
                    "arms[%d].interface: required with backend socketcan", a);
    }
    if (!k->id_base) {
        MCA_BE_FAIL(MCA_EPARSE, MCA_BE_LINE("arms[%d].id_base", a),
                    "arms[%d].id_base: required with backend socketcan", a);
    }
    int rc = mca_backend_bus_keys(c, cell, a, k);
    if (rc != MCA_OK) {
        return rc;
    }
    return mca_backend_bus_check(c, cell, a);
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

const mca_backend_def_t mca_backend_socketcan = {
    .name = "socketcan",
    .bus = MCA_BUS_ID_BLOCKS,
    .read = socketcan_read,
    .open = socketcan_open,
    .reported_joints = socketcan_reported_joints,
    .describe = socketcan_describe,
};
