/* SPDX-License-Identifier: MIT */
/* Feedback plausibility (daemon_plausibility.c): is a feedback sample of an arm one the daemon may use
 * (mca_feedback_fault_t, mca/daemon.h)? Private to mca_daemon.
 *
 * Calling context: mcad_feedback_bounds at start-up (mca_daemon_open, before the arms open: the backends
 * get the bounds); mcad_feedback_check on the RT thread (every sample, daemon_arms.c) and at start-up (the
 * handshake's first sample); no allocation, no locks, no I/O. mca_feedback_fault_name and
 * mcad_fb_fault_what: any thread (constant tables). */
#ifndef MCA_DAEMON__PLAUSIBILITY_H
#define MCA_DAEMON__PLAUSIBILITY_H

#include "daemon__state.h"

/* What each check means (mca_feedback_fault_t -> the fault text's words); "" for MCA_FB_OK. */
extern const char *const mcad_fb_fault_what[];

/* Start-up: arm a's bounds (d->fb_lo, fb_hi, fb_vmax) from its model and backend. */
void mcad_feedback_bounds(mca_daemon_t *d, int a);

/* RT and start-up: the check of one sample of arm a (frame ids only when @p frames); mca_feedback_fault_t,
 * *joint, *value and *bound say what failed. */
int mcad_feedback_check(const mca_daemon_t *d, int a, const mca_arm_feedback_t *fb, int frames, int *joint,
                        double *value, double *bound);

#endif
