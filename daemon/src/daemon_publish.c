/* SPDX-License-Identifier: MIT */
/* Publishing (daemon__publish.h): the DDS bridge and its ROS 2 topics (start-up, shut-down), one snapshot per
 * publishing tick pushed to the bridge's ring (RT thread). */
#include "daemon__publish.h"

#include <libgen.h> /* dirname */
#include <limits.h> /* PATH_MAX */
#include <math.h>
#include <string.h>
#include <unistd.h>

#include "mca/dds_qos.h"
#include "mca/err.h"
#include "mca/errbuf.h" /* mca_errbuf_printf */
#include "mca/prefix.h" /* mca_exe_prefix */

#include "daemon__log.h" /* mcad_log: the caller's sink */

/* What ROS 2 sees of the cell: names from the scenario and the URDFs, bases, capsule radii. */
static int ros2_config(const mca_daemon_t *d, mca_ros2_config_t *rc2, char *err, size_t errlen) {
    const mca_cell_t *cell = &d->cell;
    mca_ros2_config_default(rc2);
    rc2->enabled = 1;
    snprintf(rc2->cell, sizeof rc2->cell, "%s", cell->dds.ros2.ns);
    snprintf(rc2->world_frame, sizeof rc2->world_frame, "%s", cell->dds.ros2.world_frame);
    rc2->joint_states = cell->dds.ros2.joint_states;
    rc2->robot_description = cell->dds.ros2.robot_description;
    rc2->tf_static = cell->dds.ros2.tf_static;
    rc2->markers = cell->dds.ros2.markers;
    rc2->diagnostics = cell->dds.ros2.diagnostics;
    rc2->n_arms = (uint32_t)d->n_arms;
    rc2->stream_max_speed = cell->stream.max_speed;
    memcpy(rc2->box_lo, cell->stream.box_lo, sizeof rc2->box_lo);
    memcpy(rc2->box_hi, cell->stream.box_hi, sizeof rc2->box_hi);
    rc2->tracks = cell->tracks.enabled;
    snprintf(rc2->tracks_topic, sizeof rc2->tracks_topic, "%s", cell->tracks.topic);
    rc2->max_tracks = (uint32_t)cell->tracks.max_bodies;
    /* the fixed bodies drawn among the markers (the controller's: the cell's after its own were merged) */
    rc2->n_bodies = (uint32_t)d->ccfg.n_bodies;
    for (int k = 0; k < d->ccfg.n_bodies && k < MCA_MAX_BODIES; k++) {
        rc2->body[k] = d->ccfg.body[k].body;
    }
    for (int a = 0; a < d->n_arms; a++) {
        rc2->stream[a] = cell->stream.enabled ? cell->arm[a].stream : MCA_ROS2_STREAM_NONE;
        const mca_chain_t *ch = &d->ccfg.chain[a];
        mca_ros2_arm_t *ra = &rc2->arm[a];
        snprintf(ra->name, sizeof ra->name, "%s", cell->scn.arm[a].name);
        snprintf(ra->urdf_path, sizeof ra->urdf_path, "%s", cell->scn.arm[a].urdf);
        snprintf(ra->root_link, sizeof ra->root_link, "%s", ch->root_link);
        ra->n_dof = (uint32_t)ch->dof;
        for (int j = 0; j < ch->dof; j++) {
            snprintf(ra->joint_name[j], sizeof ra->joint_name[j], "%s", ch->joint[j].name);
        }
        ra->base = ch->base;
        ra->n_links = (uint32_t)ch->dof + 1u;
        for (int l = 0; l <= ch->dof; l++) {
            ra->link_radius[l] = ch->link_radius[l];
        }
    }
    char why[200];
    if (mca_ros2_config_check(rc2, why, sizeof why) != MCA_OK) {
        mca_errbuf_printf(err, errlen,
                          "%s: dds.ros2: %s (ROS 2 topics are named after the cell and its arms)",
                          cell->source, why);
        return MCA_EINVAL;
    }
    return MCA_OK;
}

/* The DDS publisher program: the option's, else next to this executable (the build tree: build/daemon), else
 * this executable's prefix's libexec/mca (an install to any prefix), else the configured install's
 * libexec/mca. Start-up. */
static int find_bridge_exe(const mca_daemon_opts_t *opts, char *out, size_t len) {
    if (opts->dds_bridge_exe != NULL) {
        snprintf(out, len, "%s", opts->dds_bridge_exe);
        return access(out, X_OK) == 0 ? MCA_OK : MCA_ENOENT;
    }
    char self[PATH_MAX];
    const ssize_t n = readlink("/proc/self/exe", self, sizeof self - 1);
    if (n > 0) {
        self[n] = 0;
        snprintf(out, len, "%s/mca-dds-bridge", dirname(self));
        if (access(out, X_OK) == 0) {
            return MCA_OK;
        }
    }
    char prefix[PATH_MAX];
    if (mca_exe_prefix(prefix, sizeof prefix) == MCA_OK) {
        const int w = snprintf(out, len, "%s/libexec/mca/mca-dds-bridge", prefix);
        if (w > 0 && (size_t)w < len && access(out, X_OK) == 0) {
            return MCA_OK;
        }
    }
    snprintf(out, len, "%s/mca-dds-bridge", MCA_LIBEXECDIR);
    return access(out, X_OK) == 0 ? MCA_OK : MCA_ENOENT;
}

/* Cyclone's own messages (mca_dds_log_drain) as the daemon's lines: "dds: TEXT" (arg is the daemon). */
static void cyclone_line(void *arg, int level, const char *text) {
    mcad_log((const mca_daemon_t *)arg, level, "dds: %s", text);
}

/* DDS at start-up: the bridge process (mca-dds-bridge) with the cell's ROS 2 topics. */
int mcad_publish_open(mca_daemon_t *d, char *err, size_t errlen) {
    const mca_cell_t *cell = &d->cell; /* the cell and options as mca_daemon_open took them */
    const mca_daemon_opts_t *opts = &d->opts;
    int rc = MCA_OK;
    mca_dds_config_t dc;
    mca_dds_config_default(&dc);
    dc.domain_id = cell->dds.domain;
    dc.config_path = cell->dds.config[0] ? cell->dds.config : NULL;
    if (cell->dds.ros2.enabled) {
        rc = ros2_config(d, &d->ros2, err, errlen);
        dc.ros2 = &d->ros2;
    }
    if (!d->drive.virtual_time) {
        /* the publisher wakes on the loop's grid, just after a publishing tick has pushed: the push then
         * makes no system call (only a late tick finds the publisher parked and wakes it) */
        dc.wake_period_ns = (uint64_t)cell->dds.publish_divisor * (uint64_t)cell->rt.period_ns;
        dc.wake_offset_ns = MCA_DAEMON_DDS_WAKE_OFFSET_NS;
    }
    dc.sched_priority = opts->no_rt ? 0 : cell->dds.priority;
    /* the publisher is a process of its own: no DDS, and so no peer on the network, in this
     * one */
    char exe[PATH_MAX];
    if (rc == MCA_OK && find_bridge_exe(opts, exe, sizeof exe) != MCA_OK) {
        mca_errbuf_printf(err, errlen,
                          "DDS: the publisher program mca-dds-bridge is neither next to this program nor "
                          "in its prefix's libexec/mca nor in %s (install it, or --no-dds)",
                          MCA_LIBEXECDIR);
        rc = MCA_ENOENT;
    }
    dc.process_exe = exe;
    char why[320] = "";
    rc = rc == MCA_OK ? mca_dds_bridge_create(&d->dds, &dc, why, sizeof why) : rc;
    if (rc != MCA_OK) {
        /* Cyclone's reason (a security file missing, a certificate refused, ...) was captured: say it */
        mca_dds_log_drain(3, cyclone_line, d);
        mca_dds_log_capture(0);
    }
    if (rc != MCA_OK && !(err && err[0])) {
        mca_errbuf_printf(err, errlen, "DDS: cannot create the bridge: %s%s", why[0] ? why : mca_strerror(rc),
                          dc.config_path ? " (check dds.config)" : "");
    }
    if (rc == MCA_OK) {
        mca_dds_stats_t ds;
        mca_dds_bridge_stats(d->dds, &ds);
        if (ds.sched_refused) {
            mcad_log(d, 4,
                     "dds.priority %d (SCHED_FIFO) not permitted: the publisher runs SCHED_OTHER "
                     "and a busy CPU delays its samples",
                     dc.sched_priority);
        }
        if (dc.sched_priority > 0 && !ds.sched_refused) {
            mcad_log(d, 6, "dds bridge: pid %d (%s), SCHED_FIFO %d", (int)ds.pid, exe, dc.sched_priority);
        } else {
            mcad_log(d, 6, "dds bridge: pid %d (%s)", (int)ds.pid, exe);
        }
    }
    return rc;
}

void mcad_fill_snapshot(mca_daemon_t *d, int64_t stamp_ns, int state) {
    mca_dds_snapshot_t *s = &d->snap;
    const mca_tick_info_t *in = &d->info;
    s->tick = atomic_load_explicit(&d->ticks, memory_order_relaxed);
    s->stamp_ns = stamp_ns;
    s->due_ns = stamp_ns - d->wake_late_ns;
    s->n_arms = (uint32_t)d->n_arms;
    for (int a = 0; a < d->n_arms; a++) {
        mca_dds_arm_snapshot_t *as = &s->arm[a];
        as->n_dof = (uint32_t)d->dof[a];
        for (int j = 0; j < d->dof[a]; j++) {
            as->position[j] = d->fb[a].position[j];
            as->velocity[j] = d->fb[a].velocity[j];
            as->effort[j] = d->fb[a].torque[j];
            as->velocity_setpoint[j] = d->cmd[a].velocity[j];
            as->position_reference[j] = d->cmd[a].position_ref[j];
        }
        /* the capsules' axes as the distances of this tick saw them (ROS 2 markers) */
        const mca_kin_t *k = mca_controller_kin(d->ctrl, a);
        as->n_points = (uint32_t)k->n_points;
        memcpy(as->point, k->point, sizeof as->point);
    }
    int np = 0;
    const mca_arm_distances_t(*dist)[MCA_MAX_ARMS] = mca_controller_distances(d->ctrl);
    for (int a = 0; a < d->n_arms; a++) {
        for (int b = a + 1; b < d->n_arms && np < MCA_MAX_PAIRS; b++) {
            /* the bridge's own fill (d1 < d2 holds: the cell loader checked it) */
            mca_dds_pair_fill(&s->pair[np++], &dist[a][b], (uint8_t)a, (uint8_t)b, d->ccfg.sp.d1,
                              d->ccfg.sp.d2);
        }
    }
    s->n_pairs = (uint32_t)np;
    /* every pair of every kind, named (the bodies' closest links as this tick's body_watch found them) */
    mca_dds_named_fill(s, mca_controller_get_config(d->ctrl), dist, &d->pn);
    mca_dds_status_snapshot_t *st = &s->status;
    st->state = (mca_dds_state_t)state;
    st->fault_code = d->fault ? d->fault_code : 0;
    st->fault_text[0] =
        0; /* the publisher gets it from the service thread (mcad_fault_text_to_dds): no text here */
    st->ticks = s->tick;
    st->overruns = d->overruns;
    st->skipped_periods = d->skipped;
    st->pdnn_budget_hits = d->budget_hits[0] + d->budget_hits[1];
    st->compute_p50_ns = d->pct_cache[0];
    st->compute_p99_ns = d->pct_cache[1];
    st->compute_max_ns = d->compute.max_ns;
    st->jitter_p50_ns = d->pct_cache[3];
    st->jitter_p99_ns = d->pct_cache[4];
    st->jitter_p999_ns = d->pct_cache[5];
    st->jitter_max_ns = d->jitter.max_ns;
    st->pdnn_steps = (uint32_t)(in->pdnn_steps > 0 ? in->pdnn_steps : 0);
    st->pdnn_residual = in->pdnn_residual;
    st->min_distance_so_far = isfinite(d->min_d) ? d->min_d : -1.0;
    st->min_distance_stamp_ns = d->min_d_stamp;
}

/* Shut-down: the final status with the run's figures, then the bridge's own summary lines. */
void mcad_dds_log_line(void *arg, int level, const char *text) {
    mcad_log((const mca_daemon_t *)arg, level, "%s", text);
}

void mcad_publish_close(mca_daemon_t *d) {
    /* final status with the run's figures */
    mca_daemon_summary_t s;
    mca_daemon_summary(d, &s);
    const int state = mca_daemon_state(d);
    mcad_fill_snapshot(d, now_ns(), state);
    mca_dds_status_snapshot_t *st = &d->snap.status;
    st->compute_p50_ns = s.compute_p50_ns;
    st->compute_p99_ns = s.compute_p99_ns;
    st->compute_max_ns = s.compute_max_ns;
    st->jitter_p50_ns = s.jitter_p50_ns;
    st->jitter_p99_ns = s.jitter_p99_ns;
    st->jitter_p999_ns = s.jitter_p999_ns;
    st->jitter_max_ns = s.jitter_max_ns;
    st->overruns = s.overruns;
    st->pdnn_budget_hits = s.pdnn_budget_time + s.pdnn_budget_steps;
    st->skipped_periods = s.skipped_periods;
    d->snap.tick = s.ticks;
    st->ticks = s.ticks;
    mca_dds_bridge_push(d->dds, &d->snap); /* the bridge queues every push: the final one goes out */
    mca_dds_stats_t ds;
    mca_dds_bridge_destroy(d->dds, &ds);
    d->dds = NULL;
    mcad_log(d, ds.dropped || ds.write_errors ? 4 : 6,
             "summary: dds: %llu snapshots published, %llu lost to ring overrun (most waiting %llu), %llu "
             "samples, "
             "%llu write errors, longest publish %.1f us; publisher on the grid %llu times, woken by the "
             "loop %llu",
             (unsigned long long)ds.published, (unsigned long long)ds.dropped,
             (unsigned long long)ds.max_pending, (unsigned long long)ds.samples,
             (unsigned long long)ds.write_errors, (double)ds.max_publish_ns / 1e3,
             (unsigned long long)ds.grid_sleeps, (unsigned long long)ds.wakes);
    char row[96] = "";
    if (ds.deaths_in_a_row > 0) {
        snprintf(row, sizeof row, " (%s%u deaths in a row, back-off %.1f s)",
                 ds.down ? "backing off: " : "restarted after ", ds.deaths_in_a_row, ds.backoff_s);
    }
    mcad_log(d, ds.deaths ? 4 : 6,
             "summary: dds bridge: died %llu times, restarted %llu times, %llu stale snapshots skipped at "
             "restarts, %llu killed as hung; at the end %s%s",
             (unsigned long long)ds.deaths, (unsigned long long)ds.restarts, (unsigned long long)ds.stale,
             (unsigned long long)ds.hung, ds.down ? "down" : "up", row);
}
