/* SPDX-License-Identifier: MIT */
/** @file mca/daemon_test.h
 * Test hooks of the controller daemon: only in the test build (mca_daemon_test, mcad-test; compiled with
 * MCA_TEST_HOOKS, installed nowhere). The production library and mcad have none of this
 * ("production holds no test hooks"): they reject the debug_* cell keys and give SIGUSR1 no power over the
 * loop (docs/daemon.md, "Test hooks").
 *
 * Cell keys of the test build (fields of mca_cell_t in every build; only this one loads them):
 *   debug_stall_after_ticks: N   the loop stops ticking after N ticks (until a stop request)
 *   debug_kill_after_ticks: N    mcad-test SIGKILLs itself after N ticks (a crash: only the arms' own
 *                                watchdogs brake them)
 *   debug_start_in_fault: true   sim backend arms start with a latched firmware fault (INJECTED)
 * mcad-test's SIGUSR1 stalls the loop (mca_daemon_request_stall); exit status 4 when it ended stalled.
 */
#ifndef MCA_DAEMON_TEST_H
#define MCA_DAEMON_TEST_H

#ifndef MCA_TEST_HOOKS
#error "mca/daemon_test.h belongs to the test build (link mca_daemon_test, which defines MCA_TEST_HOOKS)"
#endif

#include "mca/arm.h"
#include "mca/daemon.h"
#include "mca/daemon_drive.h" /* what the tests drive with besides these */
#include "mca/ros2.h"         /* mca_ros2_tracks_t */

#ifdef __cplusplus
extern "C" {
#endif

/** Make the loop stall (stop ticking) until a stop request (any thread). */
void mca_daemon_request_stall(mca_daemon_t *d);

/** Put @p arm in the place of arm a (not while the loop runs), e.g. a proxy around the handle returned
 *  (link fault injection, implausible feedback). The daemon closes @p arm at mca_daemon_close(); the
 *  caller owns the old handle. @return the old handle, NULL (and nothing changed) if a or arm is bad. */
mca_arm_t *mca_daemon_swap_arm(mca_daemon_t *d, int a, mca_arm_t *arm);

#ifdef __cplusplus
}
#endif
#endif
