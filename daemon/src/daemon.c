/* SPDX-License-Identifier: MIT */
/* The controller daemon's core: arms + controller + DDS, the tick and the real-time loop (mca/daemon.h), in
 * rooms by concern (docs/architecture.md): this file opens and closes a daemon (start-up, shut-down) and
 * drains its rings (service thread), and plans who passes first (start-up); daemon__state.h holds its state.
 */
#include "mca/daemon.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "mca/err.h"
#include "mca/errbuf.h" /* mca_errbuf_printf */
#include "mca/scenario.h"

#include "daemon__log.h" /* mcad_log: the caller's sink */
#include "daemon__arms.h"
#include "daemon__backends.h" /* mca_backend_check_ids */
#include "daemon__csv.h"
#include "daemon__drive.h" /* mcad_open */
#include "daemon__fault.h" /* mcad_log_format */
#include "daemon__loop.h"  /* mcad_pin_non_rt */
#include "daemon__plausibility.h"
#include "daemon__publish.h" /* mcad_dds_log_line */
#include "daemon__state.h"

const char *mca_daemon_state_name(int s) {
    const char *name = mca_dds_state_name(s); /* the states' one set of names (mca/dds_bridge.h) */
    return name ? name : "?";
}

/* mca-ts: each arm's path-rate limit and the order in which arms on fixed paths pass each other, planned
 * from where the arms stand (start-up: the plan's scratch lives only here). */
static int plan(mca_daemon_t *d, char *err, size_t errlen) {
    mca_coord_work_t *work = malloc(sizeof *work);
    if (!work) {
        return MCA_ENOMEM;
    }
    const double *qp[MCA_MAX_ARMS] = {NULL};
    for (int a = 0; a < d->n_arms; a++) {
        qp[a] = d->q[a];
    }
    const int64_t t0 = now_ns();
    const int rc = mca_controller_plan(d->ctrl, qp, work);
    free(work);
    if (rc != MCA_OK) {
        mca_errbuf_printf(err, errlen, "%s: coordination plan failed: %s", d->cell.source, mca_strerror(rc));
        return rc;
    }
    for (int a = 0; a < d->n_arms; a++) {
        const mca_path_rate_t *r = mca_controller_path_rate(d->ctrl, a);
        const double sigma_max = mca_controller_get_config(d->ctrl)->ts.sigma_max;
        if (r->n > 0 && r->least < sigma_max) {
            mcad_log(d, 6,
                     "path rate: arm %d at most %.3f where its path bends most (to stop on it; "
                     "sigma_max %.2f)",
                     a, r->least, sigma_max);
        }
    }
    const mca_coord_t *c = mca_controller_coord(d->ctrl);
    for (int k = 0; k < c->n_pairs; k++) {
        const mca_coord_pair_t *p = &c->pair[k];
        mcad_log(d, 6,
                 "coordination: arms %d and %d kept %.3f m apart%s: %d of %d cells blocked, %d + %d "
                 "gates",
                 p->a, p->b, p->d_block, p->in_tubes ? " less their tubes' shares" : "", p->blocked,
                 p->n_a * p->n_b, p->gates_a, p->gates_b);
    }
    if (c->unplanned > 0) {
        mcad_log(d, 5, "coordination: %d pair(s) without a schedule: left to the back-off", c->unplanned);
    }
    if (c->n_pairs + c->unplanned > 0) {
        mcad_log(d, 6, "coordination planned in %.0f ms", (double)(now_ns() - t0) * 1e-6);
    }
    return MCA_OK;
}

int mca_daemon_open(mca_daemon_t **out, const mca_cell_t *cell, const mca_daemon_opts_t *opts, char *err,
                    size_t errlen) {
    return mcad_open(out, cell, opts, NULL, err, errlen);
}

int mcad_open(mca_daemon_t **out, const mca_cell_t *cell, const mca_daemon_opts_t *opts,
              const mcad_drive_t *drive, char *err, size_t errlen) {
    if (!out || !cell || !opts) {
        return MCA_EINVAL;
    }
    if (err && errlen) {
        err[0] = '\0'; /* the steps below keep the first reason they find: none yet */
    }
    /* every mca_backend_get below may then take its backend as found */
    const int ids = mca_backend_check_ids(cell, err, errlen);
    if (ids != MCA_OK) {
        return ids;
    }
    /* the rings inside have 64-byte aligned members (producer/consumer cache lines) */
    mca_daemon_t *d = aligned_alloc(_Alignof(mca_daemon_t), sizeof *d);
    if (!d) {
        return MCA_ENOMEM;
    }
    memset(d, 0, sizeof *d);
    d->cell = *cell;
    d->opts = *opts;
    if (drive) {
        d->drive = *drive;
    }
    d->drive.stop_k = -1;
    d->drive.fault_k = -1;
    d->drive.fired = 0;
    d->dma_fd = -1;
    atomic_store(&d->state, MCA_DAEMON_INIT);
    mca_rtlog_init(&d->log);
    mca_rtlog_set_formatter(&d->log, mcad_log_format, d);
    mca_ring_init(&d->sum_ring, d->sum_storage, sizeof d->sum_storage, sizeof(mca_daemon_summary_t), 4);
    mca_hist_reset(&d->jitter);
    mca_hist_reset(&d->compute);
    mca_hist_reset(&d->ctrl_time);
    mca_hist_reset(&d->compute_ab[0]);
    mca_hist_reset(&d->compute_ab[1]);
    d->min_d = INFINITY;
    d->min_d_t = 0.0;
    d->body_margin = d->body_d = INFINITY;
    d->body_pair[0] = d->body_pair[1] = d->body_pair[2] = -1;
    d->self_d = INFINITY;
    d->self_pair[0] = d->self_pair[1] = d->self_pair[2] = -1;
    for (int k = 0; k < MCA_DDS_PAIR_KINDS; k++) {
        d->kind_min[k] = INFINITY;
    }
    for (int k = 0; k < MCA_MAX_BODIES; k++) {
        d->fixed_min[k] = INFINITY;
        d->fixed_min_link[k][0] = d->fixed_min_link[k][1] = -1;
    }
    int rc = mca_cell_controller_config(cell, &d->ccfg, err, errlen);
    if (rc == MCA_OK && d->drive.controller_config) {
        d->drive.controller_config(&d->ccfg, d->drive.controller_config_arg);
    }
    if (rc == MCA_OK) {
        /* the controller and its warm-up copy in storage of their own, allocated here once (core never
         * allocates; mca_daemon_start locks it with the rest) */
        const size_t size = mca_controller_size();
        void *mem = malloc(size);
        d->warm_ctrl = malloc(size);
        rc = mem && d->warm_ctrl ? mca_controller_create(mem, size, &d->ccfg, &d->ctrl) : MCA_ENOMEM;
        if (rc != MCA_OK) {
            free(mem);
            mca_errbuf_printf(err, errlen, "%s: controller init failed: %s", cell->source, mca_strerror(rc));
        }
    }
    if (rc != MCA_OK) {
        mca_daemon_close(d);
        return rc;
    }
    d->n_arms = d->ccfg.n_arms;
    for (int a = 0; a < d->n_arms; a++) {
        d->dof[a] = d->ccfg.chain[a].dof;
        d->cmd[a].n = d->dof[a];
        for (int j = 0; j < d->dof[a]; j++) {
            d->dec[a][j] = cell->arm[a].dec_limit[j] > 0.0 ? cell->arm[a].dec_limit[j] : 10.0;
        }
        mcad_feedback_bounds(d, a);
    }
    d->fault_arm = -1;
    d->brake_rest_t = -1.0;
    d->deadlock_arm = -1;
    for (int a = 0; a < d->n_arms && rc == MCA_OK; a++) {
        rc = mcad_open_arm(d, a, err, errlen);
    }
    for (int a = 0; a < d->n_arms && rc == MCA_OK; a++) {
        rc = mcad_handshake(d, a, err, errlen);
    }
    if (rc == MCA_OK) {
        rc = plan(d, err, errlen);
    }
    if (rc == MCA_OK && cell->rt.cpu >= 0 && !d->drive.virtual_time) {
        /* before DDS starts its threads: they, the CSV/log drainer and the supervisor inherit this mask */
        mcad_pin_non_rt(d);
    }
    if (rc == MCA_OK && cell->stream.enabled && (!cell->dds.enabled || opts->no_dds)) {
        mca_errbuf_printf(err, errlen, "%s: task.stream: the targets come over ROS 2, but DDS is off%s",
                          cell->source, opts->no_dds ? " (--no-dds)" : "");
        rc = MCA_EINVAL;
    }
    /* a driver (mca-sim, the tests) may feed the tracks itself (mca_drive_put_tracks); mcad opens through
     * mca_daemon_open, never driven: its tracks come over DDS, and only a DDS Security cell declares them */
    if (rc == MCA_OK && cell->tracks.enabled && !d->drive.driven && (!cell->dds.enabled || opts->no_dds)) {
        mca_errbuf_printf(err, errlen, "%s: streamed_bodies: the tracks come over DDS, but DDS is off%s",
                          cell->source, opts->no_dds ? " (--no-dds)" : "");
        rc = MCA_EINVAL;
    }
    if (rc == MCA_OK && cell->dds.enabled && !opts->no_dds) {
        rc = mcad_publish_open(d, err, errlen);
    }
    if (rc == MCA_OK && (opts->csv_path || opts->record_path)) {
        rc = mcad_csv_open(d, err, errlen);
    }
    if (rc != MCA_OK) {
        mca_daemon_close(d);
        return rc;
    }
    atomic_store(&d->state, MCA_DAEMON_READY);
    *out = d;
    return MCA_OK;
}

int mca_daemon_service(mca_daemon_t *d) {
    /* the fault's text to the DDS publisher as soon as this thread sees the latch, and no later than the
     * drain of the log record that names the fault (latched before that record was pushed) */
    mcad_fault_text_to_dds(d);
    int n = mca_rtlog_drain(&d->log, d->opts.log, d->opts.log_arg);
    mcad_fault_text_to_dds(d);
    if (d->dds) {
        /* the DDS publisher process: its death noticed, logged, a restart after the back-off (never blocks)
         */
        n += mca_dds_bridge_supervise(d->dds, mcad_dds_log_line, d);
    }
    if (d->csv_storage) {
        n += mcad_csv_drain(d);
    }
    return n;
}

void mca_daemon_close(mca_daemon_t *d) {
    if (!d) {
        return;
    }
    if (d->thread_started) {
        mca_daemon_request_stop(d);
        mca_daemon_join(d);
    }
    if (d->dds) {
        mcad_publish_close(d);
    }
    for (int a = 0; a < MCA_MAX_ARMS; a++) {
        mca_arm_close(d->arm[a]);
        d->arm[a] = NULL;
    }
    mca_daemon_service(d);
    if (d->csv) {
        fclose(d->csv);
    }
    if (d->rec) {
        fclose(d->rec);
    }
    free(d->csv_storage);
    free(d->ctrl);
    free(d->warm_ctrl);
    if (d->dma_fd >= 0) {
        close(d->dma_fd);
    }
    free(d);
}
