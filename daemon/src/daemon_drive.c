/* SPDX-License-Identifier: MIT */
/* The virtual-time driver (daemon__drive.h, mca/daemon_drive.h): open with the driver's settings, the
 * schedule of a stop and a fault, the step and the read-outs; and the test build's hooks (MCA_TEST_HOOKS). */
#include "daemon__drive.h"

#include <math.h>
#include <stdio.h>

#include "mca/err.h"
#include "mca/errbuf.h" /* mca_errbuf_printf */

#include "daemon__tick.h" /* mcad_step */

int mca_drive_open(mca_daemon_t **d, const mca_cell_t *cell, const mca_drive_opts_t *opts, char *err,
                   size_t errlen) {
    if (!d || !cell || !opts) {
        return MCA_EINVAL;
    }
    for (int a = 0; a < MCA_MAX_ARMS; a++) {
        if (((opts->ideal_arms >> a) & 1u) &&
            (a >= cell->scn.n_arms || cell->arm[a].backend != MCA_CELL_BACKEND_SIM)) {
            mca_errbuf_printf(err, errlen, "%s: arm %d: an ideal arm must be a sim backend arm of the cell",
                              cell->source, a);
            return MCA_EINVAL;
        }
    }
    mca_daemon_opts_t o = opts->daemon;
    o.no_rt = 1; /* no loop thread: nothing real-time to set up */
    o.dds_ab_block = 0;
    const mcad_drive_t drive = {.driven = 1,
                                .virtual_time = !opts->wall_clock,
                                .ideal_arms = opts->ideal_arms,
                                .controller_config = opts->controller_config,
                                .controller_config_arg = opts->controller_config_arg};
    return mcad_open(d, cell, &o, &drive, err, errlen);
}

/* The tick index of task time t: the schedule acts before the first tick at or after it. */
static long long tick_of(const mca_daemon_t *d, double t) {
    return llround(t / d->ccfg.dt);
}

int mca_drive_step(mca_daemon_t *d, double t, int64_t stamp_ns) {
    mcad_drive_t *v = &d->drive;
    const long long k = v->stop_k >= 0 || v->fault_k >= 0 ? tick_of(d, t) : -1;
    if (v->stop_k >= 0 && !(v->fired & MCA_DRIVE_STOPPED) && k >= v->stop_k) {
        mca_daemon_request_stop(d); /* as SIGTERM */
        v->fired |= MCA_DRIVE_STOPPED;
    }
    if (v->fault_k >= 0 && !(v->fired & MCA_DRIVE_FAULTED) && k >= v->fault_k) {
        mca_controller_raise_fault(d->ctrl, v->fault_kind, t); /* "injected fault KIND at t = T s" */
        v->fired |= MCA_DRIVE_FAULTED;
    }
    return mcad_step(d, t, stamp_ns);
}

void mca_drive_stop_at(mca_daemon_t *d, double t) {
    d->drive.stop_k = t >= 0.0 ? tick_of(d, t) : -1;
    d->drive.fired &= ~(unsigned)MCA_DRIVE_STOPPED;
}

void mca_drive_fault_at(mca_daemon_t *d, int ctrl_fault, double t) {
    d->drive.fault_k = t >= 0.0 && ctrl_fault > 0 ? tick_of(d, t) : -1;
    d->drive.fault_kind = ctrl_fault;
    d->drive.fired &= ~(unsigned)MCA_DRIVE_FAULTED;
}

unsigned mca_drive_fired(const mca_daemon_t *d) {
    return d->drive.fired;
}

const mca_tick_info_t *mca_drive_tick_info(const mca_daemon_t *d) {
    return &d->info;
}

const mca_controller_t *mca_drive_controller(const mca_daemon_t *d) {
    return d->ctrl;
}

const double *mca_drive_positions(const mca_daemon_t *d, int a) {
    return a >= 0 && a < d->n_arms ? d->q[a] : NULL;
}

const mca_arm_command_t *mca_drive_last_command(const mca_daemon_t *d, int a) {
    return a >= 0 && a < d->n_arms ? &d->cmd[a] : NULL;
}

mca_arm_t *mca_drive_arm(mca_daemon_t *d, int a) {
    return a >= 0 && a < d->n_arms ? d->arm[a] : NULL;
}

void mca_drive_put_tracks(mca_daemon_t *d, const mca_ros2_tracks_t *t) {
    if (d && t) {
        d->drive.tracks = *t;
        d->drive.tracks_on = 1;
    }
}

#ifdef MCA_TEST_HOOKS
void mca_daemon_request_stall(mca_daemon_t *d) {
    atomic_store(&d->stall_request, 1);
}

mca_arm_t *mca_daemon_swap_arm(mca_daemon_t *d, int a, mca_arm_t *arm) {
    if (!d || !arm || a < 0 || a >= d->n_arms) {
        return NULL;
    }
    mca_arm_t *old = d->arm[a];
    d->arm[a] = arm;
    return old;
}
#endif
