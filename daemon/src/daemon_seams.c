/* SPDX-License-Identifier: MIT */
/* Test seams and the virtual-time driver's read-outs (daemon__seams.h): what mca-sim, the bench and the tests
 * see of and do to a daemon they step themselves, and the test build's hooks (MCA_TEST_HOOKS). */
#include "daemon__seams.h"

#ifdef MCA_TEST_HOOKS
void mca_daemon_request_stall(mca_daemon_t *d) {
    atomic_store(&d->stall_request, 1);
}
#endif

const mca_tick_info_t *mca_daemon_tick_info(const mca_daemon_t *d) {
    return &d->info;
}

const mca_controller_t *mca_daemon_controller(const mca_daemon_t *d) {
    return &d->ctrl;
}

const double *mca_daemon_positions(const mca_daemon_t *d, int a) {
    return a >= 0 && a < d->n_arms ? d->q[a] : NULL;
}

void mca_daemon_inject_fault(mca_daemon_t *d, int ctrl_fault, double t) {
    mca_controller_raise_fault(&d->ctrl, ctrl_fault, t);
}

const mca_arm_command_t *mca_daemon_last_command(const mca_daemon_t *d, int a) {
    return a >= 0 && a < d->n_arms ? &d->cmd[a] : NULL;
}

mca_arm_t *mca_daemon_arm(mca_daemon_t *d, int a) {
    return a >= 0 && a < d->n_arms ? d->arm[a] : NULL;
}

#ifdef MCA_TEST_HOOKS
mca_arm_t *mca_daemon_swap_arm(mca_daemon_t *d, int a, mca_arm_t *arm) {
    if (!d || !arm || a < 0 || a >= d->n_arms) {
        return NULL;
    }
    mca_arm_t *old = d->arm[a];
    d->arm[a] = arm;
    return old;
}
#endif
