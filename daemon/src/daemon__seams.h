/* SPDX-License-Identifier: MIT */
/* Test seams and the virtual-time driver's read-outs (daemon_seams.c): what a caller that steps the daemon
 * itself (mca-sim, the bench, the tests) reads of it and does to it (mca/daemon.h: mca_daemon_tick_info,
 * _controller, _positions, _inject_fault, _last_command, _arm), and the test build's hooks
 * (mca/daemon_test.h, MCA_TEST_HOOKS only: mca_daemon_request_stall, mca_daemon_swap_arm). Private to
 * mca_daemon.
 *
 * Calling context: the thread that steps the daemon, never while the loop thread runs (the read-outs read
 * the loop's live data; mca_daemon_inject_fault is rt safe); mca_daemon_request_stall from any thread
 * (an atomic; mcad-test's SIGUSR1). */
#ifndef MCA_DAEMON__SEAMS_H
#define MCA_DAEMON__SEAMS_H

#include "daemon__state.h"
#ifdef MCA_TEST_HOOKS
#include "mca/daemon_test.h"
#endif

#endif
