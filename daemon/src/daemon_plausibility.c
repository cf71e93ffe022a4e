/* SPDX-License-Identifier: MIT */
/* Feedback plausibility (daemon__plausibility.h): the bounds of each arm's plausible feedback (start-up) and
 * the one check of a sample (RT thread and start-up). */
#include "daemon__plausibility.h"

#include <math.h>

#include "daemon__backends.h" /* mca_backend_get */

static const char *const fb_fault_names[] = {
    "none",        "joint-count",    "non-finite",    "frame-backwards",
    "frame-ahead", "position-limit", "velocity-limit"};
/* what each check means, for the fault text */
const char *const mcad_fb_fault_what[] = {
    "",
    "joint count differs from the cell",
    "position or velocity NaN/Inf",
    "frame id runs backwards",
    "frame id ahead of every command sent",
    "position outside the joint limits by more than the margin",
    "velocity above 1.5 x the joint's limit",
};

const char *mca_feedback_fault_name(int kind) {
    return kind >= 0 && kind <= MCA_FB_VELOCITY ? fb_fault_names[kind] : "?";
}

/* Bounds of arm a's plausible feedback from its model (start-up): the URDF limits -+ the margin (plus
 * 6 sigma of a sim arm's measurement noise), MCA_FB_VELOCITY_FACTOR x the velocity limit. */
void mcad_feedback_bounds(mca_daemon_t *d, int a) {
    const mca_cell_arm_t *ca = &d->cell.arm[a];
    const mca_backend_def_t *be = mca_backend_get(ca->backend);
    const double margin = MCA_FB_POSITION_MARGIN + (be->feedback_margin ? be->feedback_margin(ca) : 0.0);
    for (int j = 0; j < d->dof[a]; j++) {
        const mca_joint_model_t *jm = &d->ccfg.chain[a].joint[j];
        d->fb_lo[a][j] = jm->lower - margin; /* -inf for a continuous joint */
        d->fb_hi[a][j] = jm->upper + margin;
        d->fb_vmax[a][j] = MCA_FB_VELOCITY_FACTOR * jm->vel_limit;
    }
}

/* The one plausibility check of a feedback sample of arm a (mca_feedback_fault_t, in that order); the
 * frame id only when @p frames (not at start-up: the first sample may answer an earlier run's command).
 * On a failure, *joint (-1: the whole sample), *value and *bound say what failed. */
int mcad_feedback_check(const mca_daemon_t *d, int a, const mca_arm_feedback_t *fb, int frames, int *joint,
                        double *value, double *bound) {
    *joint = -1;
    if (fb->n != d->dof[a]) {
        *value = fb->n;
        *bound = d->dof[a];
        return MCA_FB_JOINT_COUNT;
    }
    if (frames && (int32_t)(fb->frame_id - d->fb_frame[a]) < 0) {
        *value = fb->frame_id;
        *bound = d->fb_frame[a];
        return MCA_FB_FRAME_BACKWARDS;
    }
    if (frames && (int32_t)(fb->frame_id - d->frame_id) > 0) {
        *value = fb->frame_id;
        *bound = d->frame_id;
        return MCA_FB_FRAME_AHEAD;
    }
    for (int j = 0; j < fb->n; j++) {
        if (!isfinite(fb->position[j]) || !isfinite(fb->velocity[j])) {
            *joint = j;
            *value = isfinite(fb->position[j]) ? fb->velocity[j] : fb->position[j];
            *bound = 0.0;
            return MCA_FB_NONFINITE;
        }
    }
    for (int j = 0; j < fb->n; j++) {
        if (fb->position[j] < d->fb_lo[a][j] || fb->position[j] > d->fb_hi[a][j]) {
            *joint = j;
            *value = fb->position[j];
            *bound = fb->position[j] < d->fb_lo[a][j] ? d->fb_lo[a][j] : d->fb_hi[a][j];
            return MCA_FB_POSITION;
        }
    }
    for (int j = 0; j < fb->n; j++) {
        if (fabs(fb->velocity[j]) > d->fb_vmax[a][j]) {
            *joint = j;
            *value = fb->velocity[j];
            *bound = d->fb_vmax[a][j];
            return MCA_FB_VELOCITY;
        }
    }
    return MCA_FB_OK;
}
