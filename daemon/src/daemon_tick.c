/* SPDX-License-Identifier: MIT */
/* One tick (daemon__tick.h): mcad_step, from feedback to commands, snapshot and CSV row (RT thread). */
#include "daemon__tick.h"

#include <math.h>

#include "mca/err.h"

#include "daemon__arms.h"
#include "daemon__csv.h"
#include "daemon__fault.h"
#include "daemon__publish.h"
#include "daemon__stream.h"
#include "daemon__summary.h"

/* A running tick whose PDNN ran out of its budget: counted; the first logged with its figures, the ones
 * after it as a count once a second (budget_log_count), so a stalling host does not flood the log ring. */
static void budget_event(mca_daemon_t *d, double t) {
    const int time = d->info.pdnn_budget_hit == MCA_BUDGET_TIME;
    d->budget_hits[time ? 0 : 1]++;
    if (d->budget_hits[0] + d->budget_hits[1] == 1) {
        LOGN(d, MCA_LOG_NOTICE,
             "PDNN out of its budget at t = %.3f s after %g steps, residual %.2e: no fault (an answer short "
             "of "
             "fault_residual is repaired; the ones after it counted once a second): %s",
             3, t, d->info.pdnn_steps, d->info.pdnn_residual, 0,
             time ? "rt.pdnn_budget_us ran out" : "its step budget ran out");
    } else {
        d->budget_unlogged++;
    }
}

static void budget_log_count(mca_daemon_t *d, double t) {
    if (d->budget_unlogged > 0) {
        LOGN(
            d, MCA_LOG_NOTICE,
            "PDNN out of its budget in %g more ticks by t = %.3f s (%g by the clock, %g by steps in all): no "
            "fault",
            4, (double)d->budget_unlogged, t, (double)d->budget_hits[0], (double)d->budget_hits[1], NULL);
        d->budget_unlogged = 0;
    }
}

/* mca-ts: log deadlocks as they start, change and end (the state is in the summary, STATUS and CSV). */
static void deadlock_watch(mca_daemon_t *d, double t) {
    const mca_tick_info_t *in = &d->info;
    if (in->deadlock != d->deadlock) {
        if (in->deadlock == MCA_DEADLOCK_BACK_OFF) {
            LOGN(d, MCA_LOG_NOTICE,
                 "deadlock %g at t = %.3f s: every arm stalled on its path: arm %g backs off along its path",
                 3, in->deadlocks, t, in->deadlock_arm, 0, NULL);
        } else if (in->deadlock == MCA_DEADLOCK_WAIT) {
            LOGN(d, MCA_LOG_NOTICE, "deadlock %g at t = %.3f s: arm %g holds until the others have moved on",
                 3, in->deadlocks, t, in->deadlock_arm, 0, NULL);
        } else {
            LOGN(d, MCA_LOG_NOTICE, "deadlock %g resolved at t = %.3f s (arm %g back on its path)", 3,
                 in->deadlocks, t, d->deadlock_arm, 0, NULL);
        }
    }
    d->deadlock = in->deadlock;
    d->deadlock_arm = in->deadlock ? in->deadlock_arm : -1;
    d->deadlocks = in->deadlocks;
}

/* The fixed bodies' pair of least margin and the self pair of least distance over the run (running, stopped
 * and braking ticks alike). */
static void body_watch(mca_daemon_t *d, double t) {
    if (d->info.body_margin < d->body_margin) {
        d->body_margin = d->info.body_margin;
        d->body_d = d->info.body_distance;
        d->body_t = t;
        d->body_pair[0] = d->info.body_arm;
        d->body_pair[1] = d->info.body_link;
        d->body_pair[2] = d->info.body_index;
    }
    if (d->info.self_distance < d->self_d) {
        d->self_d = d->info.self_distance;
        d->self_t = t;
        d->self_pair[0] = d->info.self_arm;
        d->self_pair[1] = d->info.self_link;
        d->self_pair[2] = d->info.self_other;
    }
    /* every kind and each fixed body (the controller measured each body's closest link with its distances) */
    const mca_controller_config_t *cc = mca_controller_get_config(d->ctrl);
    double least[MCA_DDS_PAIR_KINDS] = {d->info.min_distance, INFINITY, INFINITY, INFINITY};
    d->pn.n_bodies = 0;
    for (int a = 0; a < MCA_MAX_ARMS; a++) {
        d->pn.self[a].valid = 0;
    }
    if ((cc->n_bodies > 0 || mca_controller_has_self(cc)) &&
        mca_controller_pair_nearest(d->ctrl, &d->pn) == MCA_OK) {
        for (int k = 0; k < d->pn.n_bodies; k++) {
            const mca_body_nearest_t *bn = &d->pn.body[k];
            if (!bn->valid) {
                continue;
            }
            const int kind = k < d->pn.n_fixed ? MCA_DDS_PAIR_ARM_BODY : MCA_DDS_PAIR_ARM_TRACK;
            least[kind] = fmin(least[kind], bn->d);
            if (k < d->pn.n_fixed && bn->d < d->fixed_min[k]) {
                d->fixed_min[k] = bn->d;
                d->fixed_min_t[k] = t;
                d->fixed_min_link[k][0] = bn->arm;
                d->fixed_min_link[k][1] = bn->link;
            }
        }
        for (int a = 0; a < d->n_arms; a++) {
            if (d->pn.self[a].valid) {
                least[MCA_DDS_PAIR_SELF] = fmin(least[MCA_DDS_PAIR_SELF], d->pn.self[a].d);
            }
        }
    }
    for (int k = 0; k < MCA_DDS_PAIR_KINDS; k++) {
        if (least[k] < d->kind_min[k]) {
            d->kind_min[k] = least[k];
            d->kind_min_t[k] = t;
        }
    }
}

int mcad_step(mca_daemon_t *d, double t, int64_t stamp_ns) {
    d->t_tick = t;
    int state = atomic_load_explicit(&d->state, memory_order_relaxed);
    if (state == MCA_DAEMON_READY) {
        state = MCA_DAEMON_RUNNING;
        atomic_store(&d->state, state);
        LOGN(d, MCA_LOG_INFO, "running: %g arms, period %g us", 2, d->n_arms,
             (double)d->cell.rt.period_ns / 1e3, 0, 0, NULL);
    }
    if (state == MCA_DAEMON_RUNNING && atomic_load_explicit(&d->stop_request, memory_order_relaxed)) {
        d->stop_pending = 1;
        state = MCA_DAEMON_BRAKING;
        atomic_store(&d->state, state);
        LOGN(d, MCA_LOG_NOTICE, "stop requested at t = %.3f s: braking to zero", 1, t, 0, 0, 0, NULL);
    }
    mcad_read_feedback(d, t);
    if (d->cell.tracks.enabled && (state == MCA_DAEMON_RUNNING || state == MCA_DAEMON_BRAKING)) {
        mcad_stream_bodies(d, t, stamp_ns); /* a lost stream brakes from this tick on */
    }
    if (d->cell.stream.enabled &&
        atomic_load_explicit(&d->state, memory_order_relaxed) == MCA_DAEMON_RUNNING) {
        mcad_stream_targets(d, t, stamp_ns); /* a stale stream brakes from this tick on */
    }
    state = atomic_load_explicit(&d->state, memory_order_relaxed);

    const double *qp[MCA_MAX_ARMS];
    for (int a = 0; a < MCA_MAX_ARMS; a++) {
        qp[a] = d->q[a];
    }
    if (state == MCA_DAEMON_RUNNING) {
        double *qdp[MCA_MAX_ARMS];
        for (int a = 0; a < MCA_MAX_ARMS; a++) {
            qdp[a] = d->qdot[a];
        }
        const double *vm[MCA_MAX_ARMS] = {NULL};
        for (int a = 0; a < d->n_arms; a++) {
            vm[a] = d->have_fb[a] ? d->fb[a].velocity : NULL;
        }
        mca_controller_set_velocity(d->ctrl, vm); /* mca-ts: the next command starts from the real motion */
        const int rc = mca_controller_tick(d->ctrl, t, qp, qdp, &d->info);
        mca_hist_record(&d->ctrl_time, d->info.compute_ns);
        if (d->info.pdnn_budget_hit != MCA_BUDGET_NONE) {
            budget_event(d, t);
        }
        if (isfinite(d->info.min_distance) && d->info.min_distance < d->min_d) {
            d->min_d = d->info.min_distance;
            d->min_d_t = t;
            d->min_d_stamp = stamp_ns;
        }
        body_watch(d, t);
        if (rc != MCA_OK) {
            d->ctrl_fault = d->info.fault;
            mcad_latch_fault(d, MCA_DAEMON_FAULT_CONTROLLER, mcad_ctrl_fault_code(d->info.fault), t, -1,
                             d->info.fault, 0, 0, &d->info.fault_why);
            state = MCA_DAEMON_BRAKING;
        } else {
            mcad_send_commands(d, 1);
        }
        deadlock_watch(d, t);
    } else if (state != MCA_DAEMON_BRAKING && mca_controller_observe(d->ctrl, t, qp, &d->info) == MCA_OK) {
        /* stopped or in fault: the arms may still move, so the distances are still measured (and
         * published). The solver figures stay the last tick's. */
        if (d->info.min_distance < d->min_d) {
            d->min_d = d->info.min_distance;
            d->min_d_t = t;
            d->min_d_stamp = stamp_ns;
        }
        body_watch(d, t);
    }
    if (state == MCA_DAEMON_BRAKING) {
        /* braking measures the distances too (the minimum covers the braking) */
        const int done = mcad_brake_tick(d, t, qp);
        if (isfinite(d->info.min_distance) && d->info.min_distance < d->min_d) {
            d->min_d = d->info.min_distance;
            d->min_d_t = t;
            d->min_d_stamp = stamp_ns;
        }
        body_watch(d, t);
        mcad_send_commands(d, 1);
        if (done) {
            state =
                d->stop_pending && d->fault == MCA_DAEMON_FAULT_NONE ? MCA_DAEMON_STOPPED : MCA_DAEMON_FAULT;
            atomic_store(&d->state, state);
            d->brake_rest_t = t;
            LOGN(d, state == MCA_DAEMON_FAULT ? MCA_LOG_ERR : MCA_LOG_NOTICE,
                 "all joints commanded to zero at t = %.3f s after %.3f s of braking (%g fallback ticks): "
                 "state %s",
                 3, t, t - d->brake_t0, (double)d->brake_fallback, 0, mca_daemon_state_name(state));
        }
    } else if (state == MCA_DAEMON_STOPPED || state == MCA_DAEMON_FAULT) {
        /* zero velocity, servo released: the arms' brakes hold */
        for (int a = 0; a < d->n_arms; a++) {
            for (int j = 0; j < d->dof[a]; j++) {
                d->qdot[a][j] = 0.0;
            }
        }
        mcad_send_commands(d, 0);
    }
    const uint64_t n = atomic_load_explicit(&d->ticks, memory_order_relaxed);
    if (n % 1000 == 0) {
        /* once a second: figures for the DDS status and for the supervisor (STATUS= lines) */
        mcad_compute_summary(d, &d->sum_rt);
        budget_log_count(d, t);
        d->pct_cache[0] = d->sum_rt.compute_p50_ns;
        d->pct_cache[1] = d->sum_rt.compute_p99_ns;
        d->pct_cache[3] = d->sum_rt.jitter_p50_ns;
        d->pct_cache[4] = d->sum_rt.jitter_p99_ns;
        d->pct_cache[5] = d->sum_rt.jitter_p999_ns;
        mca_ring_push(&d->sum_ring, &d->sum_rt);
    }
    if (d->dds && n % d->cell.dds.publish_divisor == 0 && mcad_dds_ab_publishes(d, n)) {
        /* only a tick that publishes fills the snapshot (the bridge queues every push) */
        mcad_fill_snapshot(d, stamp_ns, state);
        mca_dds_bridge_push(d->dds, &d->snap);
    }
    mcad_push_csv(d, t, state, stamp_ns);
    atomic_store_explicit(&d->ticks, n + 1, memory_order_release);
    return state;
}
