/* SPDX-License-Identifier: MIT */
/* The per-tick outputs (daemon_csv.c): the CSV (--csv) and the recording (--record, mca/tick_rec.h), one
 * record per tick from the loop into one SPSC ring, written by the service thread through mca/tick_csv.h and
 * mca/tick_rec.h. Private to mca_daemon.
 *
 * Calling context: mcad_csv_open at start-up, after the handshake (opens the files, allocates and pre-faults
 * the ring, writes the headers; the recording's holds the handshake's sample); mcad_push_csv on the RT thread
 * (a copy into the ring, no formatting; a full ring drops the row and counts it); mcad_csv_drain on the
 * service thread (mca_daemon_service: ONE thread). */
#ifndef MCA_DAEMON__CSV_H
#define MCA_DAEMON__CSV_H

#include <stddef.h>
#include <stdint.h>

#include "daemon__state.h"

/* Start-up: the ring, d->csv (d->opts.csv_path) and d->rec (d->opts.record_path) with their headers. err
 * says why not. */
int mcad_csv_open(mca_daemon_t *d, char *err, size_t errlen);
/* RT: this tick's row (no-op without --csv and --record). */
void mcad_push_csv(mca_daemon_t *d, double t, int state, int64_t stamp_ns);
/* Service thread (d->csv set): write and flush every row waiting. @return rows written */
int mcad_csv_drain(mca_daemon_t *d);

#endif
