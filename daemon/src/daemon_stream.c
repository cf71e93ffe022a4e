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

/* streamed_bodies: the bridge's latest accepted message (a seqlock read, no wait), each body's age on the
 * controller's clock (since it was received, plus how old it was when sent), into the controller's rows.
 * The controller checks each body again (the bridge is another process); a message it refuses is no message.
 * Silence for lost_after, counted from the first tick when nothing came yet, is the named fault: every arm
 * stops on its path (mcad_brake_tick), the tracks still growing in the braking QP's rows. */
void mcad_stream_bodies(mca_daemon_t *d, double t, int64_t now_ns) {
    if (d->tracks_since_ns == 0) {
        d->tracks_since_ns = now_ns;
    }
    mca_ros2_tracks_t tk;
    int rc;
    if (d->drive.tracks_on) {
        tk = d->drive.tracks; /* a driver's (mca_drive_put_tracks): mcad never sets it */
        rc = MCA_OK;
    } else {
        rc = mca_dds_bridge_tracks(d->dds, &tk);
    }
    if (rc == MCA_OK && tk.accepted > 0 && tk.accepted != d->tracks.accepted) {
        mca_track_t body[MCA_MAX_TRACKS];
        const double since = (double)(now_ns - tk.recv_ns) * 1e-9;
        for (uint32_t k = 0; k < tk.n; k++) {
            body[k] = tk.body[k];
            body[k].stamp = t - since - tk.body[k].stamp;
        }
        if (mca_controller_set_tracks(d->ctrl, body, (int)tk.n, t) == MCA_OK) {
            d->tracks = tk;
        } else {
            d->tracks_bad++;
        }
    } else if (d->tracks.accepted > 0) {
        /* no new message: the same tracks, older (they grow once stale) */
        mca_track_t body[MCA_MAX_TRACKS];
        const double since = (double)(now_ns - d->tracks.recv_ns) * 1e-9;
        for (uint32_t k = 0; k < d->tracks.n; k++) {
            body[k] = d->tracks.body[k];
            body[k].stamp = t - since - d->tracks.body[k].stamp;
        }
        (void)mca_controller_set_tracks(d->ctrl, body, (int)d->tracks.n, t);
    }
    const int64_t last_ns = d->tracks.accepted > 0 ? d->tracks.recv_ns : d->tracks_since_ns;
    const double silence = (double)(now_ns - last_ns) * 1e-9;
    if (silence > d->cell.tracks.ssm.lost_after && d->fault == MCA_DAEMON_FAULT_NONE) {
        d->tracks_lost_age = silence;
        mcad_latch_fault(d, MCA_DAEMON_FAULT_TRACKS_LOST, MCA_ETIMEDOUT, t, -1, 0, 0, 0, NULL);
    }
}
