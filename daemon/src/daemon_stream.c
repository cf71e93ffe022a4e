/* SPDX-License-Identifier: MIT */
/* Streamed input (daemon__stream.h): task.stream's targets from the bridge into the controller (RT thread).
 */
#include "daemon__stream.h"

#include "mca/err.h"

#include "daemon__fault.h" /* mcad_latch_fault */

/* task.stream: each arm's target from the bridge (a seqlock read, no wait) into the controller's stream law
 * (mca_controller_stream_target: a twist as it is, a pose approached at pose_gain x the gap, at most
 * max_speed); no target yet or none for hold_after: hold; none for brake_after: a fault of that arm, every
 * arm brakes. */
void mcad_stream_targets(mca_daemon_t *d, double t, int64_t now_ns) {
    const mca_cell_stream_t *cs = &d->cell.stream;
    const mca_stream_law_t law = {.pose_gain = cs->pose_gain, .max_speed = cs->max_speed};
    for (int a = 0; a < d->n_arms; a++) {
        mca_ros2_target_t tg;
        const int rc = mca_dds_bridge_stream_target(d->dds, a, &tg);
        if (rc == MCA_EAGAIN) {
            continue; /* being written this instant: last tick's velocity stays */
        }
        /* The bridge process checked the target (finite, in the box, under max_speed); the loop does not take
         * its word for it: the law holds on a target that is not finite and caps the speed (the bridge is
         * another process) */
        mca_stream_kind_t kind = MCA_STREAM_HOLD;
        if (rc == MCA_OK && tg.accepted > 0) {
            const double age = (double)(now_ns - tg.recv_ns) * 1e-9;
            if (age > cs->brake_after) {
                mcad_latch_fault(d, MCA_DAEMON_FAULT_STREAM_STALE, MCA_ETIMEDOUT, t, a, 0, 0, 0, NULL);
            } else if (age <= cs->hold_after) {
                kind = tg.kind == MCA_ROS2_STREAM_TWIST ? MCA_STREAM_TWIST : MCA_STREAM_POSE;
            }
        }
        mca_controller_stream_target(d->ctrl, a, kind, kind == MCA_STREAM_HOLD ? NULL : tg.x, &law);
    }
}
