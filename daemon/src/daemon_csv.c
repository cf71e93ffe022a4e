/* SPDX-License-Identifier: MIT */
/* The per-tick CSV and recording (daemon__csv.h): opened at start-up, a row pushed each tick (RT thread),
 * written by the service thread (mca/tick_csv.h, mca/tick_rec.h). */
#include "daemon__csv.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "mca/err.h"
#include "mca/errbuf.h"   /* mca_errbuf_printf */
#include "mca/tick_rec.h" /* the recording's format */

/* Start-up: the recording's file and header: the arms, the period and the sample the handshake took. */
static int rec_open(mca_daemon_t *d, char *err, size_t errlen) {
    d->rec = fopen(d->opts.record_path, "wb");
    mca_tick_rec_header_t h;
    memset(&h, 0, sizeof h);
    h.n_arms = (uint32_t)d->n_arms;
    h.period_ns = d->cell.rt.period_ns;
    for (int a = 0; a < d->n_arms; a++) {
        h.dof[a] = (uint32_t)d->dof[a];
        for (int j = 0; j < d->dof[a]; j++) {
            h.q0[a][j] = d->q[a][j];
            h.v0[a][j] = d->have_fb[a] ? d->fb[a].velocity[j] : NAN;
        }
    }
    if (!d->rec || mca_tick_rec_write_header(d->rec, &h) != 0) {
        mca_errbuf_printf(err, errlen, "%s: cannot write the recording", d->opts.record_path);
        return MCA_EIO;
    }
    return MCA_OK;
}

/* Start-up: the ring (pre-faulted), then the CSV file and its header, the recording and its header. */
int mcad_csv_open(mca_daemon_t *d, char *err, size_t errlen) {
    const mca_daemon_opts_t *opts = &d->opts;
    const size_t sz = MCA_RING_STORAGE_SIZE(sizeof(mca_daemon_csv_rec_t), MCA_DAEMON_CSV_CAPACITY);
    d->csv_storage = aligned_alloc(64, sz);
    if (!d->csv_storage) {
        mca_errbuf_printf(err, errlen, "out of memory for the CSV ring");
        return MCA_ENOMEM;
    }
    int rc = mca_ring_init(&d->csv_ring, d->csv_storage, sz, sizeof(mca_daemon_csv_rec_t),
                           MCA_DAEMON_CSV_CAPACITY);
    memset(d->csv_storage, 0, sz); /* pre-fault */
    if (rc == MCA_OK && opts->csv_path) {
        d->csv = fopen(opts->csv_path, "w");
        if (!d->csv) {
            mca_errbuf_printf(err, errlen, "%s: cannot write the CSV file", opts->csv_path);
            return MCA_EIO;
        }
        /* mca-sim's columns, plus the daemon state and the commands, numbers exact */
        d->csv_layout =
            (mca_tick_csv_layout_t){.n_arms = d->n_arms,
                                    .exact = 1,
                                    .daemon_cols = 1,
                                    .body_cols = mca_controller_get_config(d->ctrl)->n_bodies +
                                                     mca_controller_get_config(d->ctrl)->max_tracks >
                                                 0,
                                    .self_cols = mca_controller_has_self(mca_controller_get_config(d->ctrl))};
        for (int a = 0; a < d->n_arms; a++) {
            d->csv_layout.dof[a] = d->dof[a];
        }
        mca_tick_csv_header(d->csv, &d->csv_layout);
    }
    if (rc == MCA_OK && opts->record_path) {
        rc = rec_open(d, err, errlen);
    }
    return rc;
}

void mcad_push_csv(mca_daemon_t *d, double t, int state, int64_t stamp_ns) {
    if (!d->csv_storage) {
        return;
    }
    mca_daemon_csv_rec_t *r = &d->csv_rec;
    r->t = t;
    r->state = state;
    memcpy(r->q, d->q, sizeof r->q);
    for (int a = 0; a < d->n_arms; a++) {
        for (int j = 0; j < d->dof[a]; j++) {
            r->qdot_cmd[a][j] = d->cmd[a].velocity[j];
        }
    }
    r->info = d->info;
    r->cmd_gap_ns = d->cmd_gap_ns;
    r->wake_ns = stamp_ns;
    r->fresh = 0;
    for (int a = 0; a < d->n_arms; a++) {
        /* the controller's measured velocities (mca_controller_set_velocity): the feedback's, once there is
         * one */
        for (int j = 0; j < d->dof[a]; j++) {
            r->v[a][j] = d->have_fb[a] ? d->fb[a].velocity[j] : NAN;
        }
        r->fresh |= d->lost[a] == 0 ? 1u << a : 0u;
        r->arm_state[a] = (int32_t)d->fb[a].state;
        r->fault_code[a] = d->fb[a].fault_code;
        r->fb_stamp_ns[a] = d->fb[a].stamp_ns;
    }
    mca_ring_push(&d->csv_ring, r);
}

/* Service thread: one record of the recording, the ring's row as it came (no number formatted). */
static void rec_write(mca_daemon_t *d, const mca_daemon_csv_rec_t *r) {
    mca_tick_rec_t w;
    memset(&w, 0, sizeof w);
    w.t = r->t;
    w.stamp_ns = r->wake_ns;
    w.state = r->state;
    w.fresh = r->fresh;
    memcpy(w.arm_state, r->arm_state, sizeof w.arm_state);
    memcpy(w.fault_code, r->fault_code, sizeof w.fault_code);
    memcpy(w.fb_stamp_ns, r->fb_stamp_ns, sizeof w.fb_stamp_ns);
    memcpy(w.q, r->q, sizeof w.q);
    memcpy(w.v, r->v, sizeof w.v);
    memcpy(w.qdot_cmd, r->qdot_cmd, sizeof w.qdot_cmd);
    mca_tick_rec_write(d->rec, &w);
}

static void csv_write(mca_daemon_t *d, const mca_daemon_csv_rec_t *r) {
    const mca_tick_csv_row_t row = {.t = r->t,
                                    .q = r->q,
                                    .info = &r->info,
                                    .state = r->state,
                                    .qdot_cmd = r->qdot_cmd,
                                    .cmd_gap_ns = r->cmd_gap_ns,
                                    .wake_ns = r->wake_ns};
    mca_tick_csv_row(d->csv, &d->csv_layout, &row);
}

/* Service thread: every row the loop pushed, written and flushed. @return rows written */
int mcad_csv_drain(mca_daemon_t *d) {
    int rows = 0;
    while (mca_ring_pop(&d->csv_ring, &d->csv_out) == MCA_OK) {
        if (d->csv) {
            csv_write(d, &d->csv_out);
        }
        if (d->rec) {
            rec_write(d, &d->csv_out);
        }
        rows++;
    }
    if (rows && d->csv) {
        fflush(d->csv); /* a killed mcad leaves its CSV up to the last drain */
    }
    if (rows && d->rec) {
        fflush(d->rec); /* and its recording (mca_tick_rec_read leaves a cut record out) */
    }
    return rows;
}
