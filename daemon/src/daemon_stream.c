/* SPDX-License-Identifier: MIT */
/* Streamed input (daemon__stream.h): task.stream's targets from the bridge into the controller (RT thread).
 */
#include "daemon__stream.h"

#include <math.h>
#include <string.h>

#include "mca/err.h"

#include "daemon__fault.h" /* mcad_latch_fault */

/* task.stream: each arm's reference velocity from its latest accepted target (a seqlock read, no wait):
 * a twist as it is, a pose target approached at pose_gain x the gap, at most max_speed; no target yet or
 * none for hold_after: hold; none for brake_after: a fault of that arm, every arm brakes. */
void mcad_stream_targets(mca_daemon_t *d, double t, int64_t now_ns) {
    const mca_cell_stream_t *cs = &d->cell.stream;
    for (int a = 0; a < d->n_arms; a++) {
        mca_ros2_target_t tg;
        const int rc = mca_dds_bridge_stream_target(d->dds, a, &tg);
        if (rc == MCA_EAGAIN) {
            continue; /* being written this instant: last tick's velocity stays */
        }
        double v[3] = {0.0, 0.0, 0.0};
        /* The bridge process checked the target (finite, in the box, under max_speed); the loop does not take
         * its word for it: a target from the shared mailbox that is not finite is no target (hold), and no
         * velocity goes beyond max_speed (the bridge is another process) */
        const int finite = isfinite(tg.x[0]) && isfinite(tg.x[1]) && isfinite(tg.x[2]);
        if (rc == MCA_OK && tg.accepted > 0) {
            const double age = (double)(now_ns - tg.recv_ns) * 1e-9;
            if (age > cs->brake_after) {
                mcad_latch_fault(d, MCA_DAEMON_FAULT_STREAM_STALE, MCA_ETIMEDOUT, t, a, 0, 0, 0, NULL);
            } else if (finite && age <= cs->hold_after && tg.kind == MCA_ROS2_STREAM_TWIST) {
                memcpy(v, tg.x, sizeof v);
            } else if (finite && age <= cs->hold_after && d->ctrl.started) {
                /* pose: towards the target from where the reference is now */
                const double *r = d->ctrl.cfg.path[a].stream_r;
                for (int i = 0; i < 3; i++) {
                    v[i] = cs->pose_gain * (tg.x[i] - r[i]);
                }
            }
            const double n = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
            for (int i = 0; i < 3 && n > cs->max_speed; i++) {
                v[i] *= cs->max_speed / n;
            }
        }
        mca_controller_stream(&d->ctrl, a, v);
    }
}
