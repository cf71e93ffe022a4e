/* SPDX-License-Identifier: MIT */
/* The virtual-time driver (daemon_drive.c, mca/daemon_drive.h): a caller that steps the daemon itself
 * (mca-sim, the tests) opens it with its settings (mcad_drive_t in daemon__state.h), schedules a stop or a
 * fault, steps it and reads it out; and the test build's hooks (mca/daemon_test.h, MCA_TEST_HOOKS only:
 * mca_daemon_request_stall, mca_daemon_swap_arm). Private to mca_daemon; mcad calls none of it.
 *
 * Calling context: mca_drive_open and mcad_open start-up; mca_drive_step rt (the schedule, then mcad_step);
 * the rest the driving thread between steps, never while the loop thread runs; mca_daemon_request_stall
 * any thread (an atomic: mcad-test's SIGUSR1). */
#ifndef MCA_DAEMON__DRIVE_H
#define MCA_DAEMON__DRIVE_H

#include "daemon__state.h"
#include "mca/daemon_drive.h"
#ifdef MCA_TEST_HOOKS
#include "mca/daemon_test.h"
#endif

/* mca_daemon_open with a driver's settings (NULL: none, mcad's); daemon.c. */
int mcad_open(mca_daemon_t **out, const mca_cell_t *cell, const mca_daemon_opts_t *opts,
              const mcad_drive_t *drive, char *err, size_t errlen);

#endif
