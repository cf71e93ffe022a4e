/* SPDX-License-Identifier: MIT */
/* The per-tick CSV (daemon__csv.h): opened at start-up, a row pushed each tick (RT thread), written by the
 * service thread (mca/tick_csv.h). */
#include "daemon__csv.h"

#include <stdlib.h>
#include <string.h>

#include "mca/err.h"
#include "mca/errbuf.h" /* mca_errbuf_printf */

/* Start-up: the CSV file, its ring (pre-faulted) and its header. */
int mcad_csv_open(mca_daemon_t *d, char *err, size_t errlen) {
    const mca_daemon_opts_t *opts = &d->opts;
    int rc = MCA_OK;
    d->csv = fopen(opts->csv_path, "w");
    const size_t sz = MCA_RING_STORAGE_SIZE(sizeof(mca_daemon_csv_rec_t), MCA_DAEMON_CSV_CAPACITY);
    d->csv_storage = aligned_alloc(64, sz);
    if (!d->csv || !d->csv_storage) {
        mca_errbuf_printf(err, errlen, "%s: cannot write the CSV file", opts->csv_path);
        rc = MCA_EIO;
    } else {
        rc = mca_ring_init(&d->csv_ring, d->csv_storage, sz, sizeof(mca_daemon_csv_rec_t),
                           MCA_DAEMON_CSV_CAPACITY);
        memset(d->csv_storage, 0, sz); /* pre-fault */
        /* mca-sim's columns, plus the daemon state and the commands, numbers exact */
        d->csv_layout = (mca_tick_csv_layout_t){.n_arms = d->n_arms, .exact = 1, .daemon_cols = 1};
        for (int a = 0; a < d->n_arms; a++) {
            d->csv_layout.dof[a] = d->dof[a];
        }
        mca_tick_csv_header(d->csv, &d->csv_layout);
    }
    return rc;
}

void mcad_push_csv(mca_daemon_t *d, double t, int state, int64_t stamp_ns) {
    if (!d->csv) {
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
    mca_ring_push(&d->csv_ring, r);
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
        csv_write(d, &d->csv_out);
        rows++;
    }
    if (rows) {
        fflush(d->csv); /* a killed mcad leaves its CSV up to the last drain */
    }
    return rows;
}
