/* SPDX-License-Identifier: MIT */
/* Summary (daemon__summary.h): the run's figures from the loop's data (RT thread once a second, or after the
 * loop), their read-out and print-out (service thread). */
#include "daemon__summary.h"

#include <math.h>
#include <string.h>

#include "mca/err.h"

#include "daemon__log.h"   /* mcad_log: the caller's sink */
#include "daemon__fault.h" /* mcad_fault_describe, mcad_link_ignored_text */

/* Figures from the loop's own data: call from the loop, or once it has ended (rt safe: no formatting). */
void mcad_compute_summary(const mca_daemon_t *d, mca_daemon_summary_t *s) {
    memset(s, 0, sizeof *s);
    /* the configuration the controller runs (the cell's before it was created: an open that failed) */
    const mca_controller_config_t *cc = d->ctrl ? mca_controller_get_config(d->ctrl) : &d->ccfg;
    s->state = mca_daemon_state(d);
    s->ticks = mca_daemon_ticks(d);
    s->overruns = d->overruns;
    s->pdnn_budget_time = d->budget_hits[0];
    s->pdnn_budget_steps = d->budget_hits[1];
    s->pdnn_budget_us = (double)cc->pdnn_budget_ns * 1e-3;
    s->pdnn_step_budget = mca_controller_step_budget(cc);
    s->pdnn_max_steps = cc->pdnn.max_steps;
    s->skipped_periods = d->skipped;
    s->stalls = d->stalls;
    s->stall_max_ns = d->stall_max_ns;
    s->jitter_p50_ns = mca_hist_percentile(&d->jitter, 0.5);
    s->jitter_p99_ns = mca_hist_percentile(&d->jitter, 0.99);
    s->jitter_p999_ns = mca_hist_percentile(&d->jitter, 0.999);
    s->jitter_max_ns = d->jitter.max_ns;
    s->compute_p50_ns = mca_hist_percentile(&d->compute, 0.5);
    s->compute_p99_ns = mca_hist_percentile(&d->compute, 0.99);
    s->compute_max_ns = d->compute.max_ns;
    s->ctrl_p50_ns = mca_hist_percentile(&d->ctrl_time, 0.5);
    s->ctrl_p99_ns = mca_hist_percentile(&d->ctrl_time, 0.99);
    s->ctrl_max_ns = d->ctrl_time.max_ns;
    s->dds_ab_block = d->dds ? d->opts.dds_ab_block : 0;
    for (int k = 0; k < 2; k++) {
        s->dds_ab_n[k] = d->compute_ab[k].count;
        s->dds_ab_p50_ns[k] = mca_hist_percentile(&d->compute_ab[k], 0.5);
        s->dds_ab_p99_ns[k] = mca_hist_percentile(&d->compute_ab[k], 0.99);
        s->dds_ab_mean_ns[k] = mca_hist_mean(&d->compute_ab[k]);
        s->dds_ab_short_n[k] = d->compute_ab_short_n[k];
        s->dds_ab_short_mean_ns[k] =
            d->compute_ab_short_n[k] ? d->compute_ab_short_sum_ns[k] / (double)d->compute_ab_short_n[k] : 0.0;
    }
    s->min_distance = d->min_d;
    s->min_distance_t = d->min_d_t;
    s->body_margin = d->body_margin;
    s->body_distance = d->body_d;
    s->body_t = d->body_t;
    memcpy(s->body_pair, d->body_pair, sizeof s->body_pair);
    s->self_distance = d->self_d;
    s->self_t = d->self_t;
    memcpy(s->self_pair, d->self_pair, sizeof s->self_pair);
    {
        const int k = d->body_pair[2];
        const mca_fixed_body_t *fb = k >= 0 && k < cc->n_bodies ? &cc->body[k] : NULL;
        memcpy(s->body_name, fb ? fb->name : "", fb ? sizeof s->body_name : 1);
        s->body_kind = fb ? (int)fb->body.kind : -1;
    }
    memcpy(s->kind_min, d->kind_min, sizeof s->kind_min);
    memcpy(s->kind_min_t, d->kind_min_t, sizeof s->kind_min_t);
    s->n_fixed_bodies = d->cell.scn.n_bodies;
    for (int k = 0; k < s->n_fixed_bodies && k < MCA_MAX_BODIES; k++) {
        s->fixed_min[k] = d->fixed_min[k];
        s->fixed_min_t[k] = d->fixed_min_t[k];
        s->fixed_min_link[k][0] = d->fixed_min_link[k][0];
        s->fixed_min_link[k][1] = d->fixed_min_link[k][1];
        memcpy(s->fixed_name[k], cc->body[k].name, sizeof s->fixed_name[k]);
    }
    s->fault = d->fault;
    s->ctrl_fault = d->ctrl_fault;
    s->fault_arm = d->fault ? d->fault_arm : -1;
    s->feedback_fault = d->fault == MCA_DAEMON_FAULT_FEEDBACK ? d->feedback_fault : MCA_FB_OK;
    s->n_arms = d->n_arms;
    for (int a = 0; a < d->n_arms; a++) {
        s->implausible_samples += d->implausible[a];
        memcpy(s->arm_name[a], d->cell.scn.arm[a].name, sizeof s->arm_name[a]);
        mca_arm_stats(d->arm[a], &s->link[a]);
    }
    /* the record, not the text (this runs in the loop once a second): mca_daemon_summary() makes the text */
    s->fault_detail = d->fault_detail;
    s->fault_arm_code = d->fault_arm_code;
    s->fault_count = d->fault_count;
    s->ctrl_why = d->ctrl_why;
    s->fault_t = d->fault_t;
    s->log_dropped = mca_rtlog_dropped(&d->log);
    if (d->csv_storage) {
        mca_ring_stats_t rs;
        mca_ring_stats(&d->csv_ring, &rs);
        s->csv_dropped = rs.dropped;
    }
    s->brake_t = d->brake_active ? d->brake_t0 : -1.0;
    s->stop_duration_s = d->brake_active && d->brake_rest_t >= 0.0 ? d->brake_rest_t - d->brake_t0 : -1.0;
    s->brake_fallback_ticks = d->brake_fallback;
    s->brake_forced_ticks = d->brake_forced;
    s->max_dv_over_dt_dec = d->brake_max_dv;
    s->deadlock = d->deadlock;
    s->deadlock_arm = d->deadlock_arm;
    s->deadlocks = d->deadlocks;
    s->sched_fifo = d->sched_fifo;
    s->mem_locked = d->mem_locked;
    s->dma_latency_held = d->dma_fd >= 0 || (d->sched_fifo && d->cell.rt.dma_latency && !d->opts.no_rt);
}

void mca_daemon_summary(mca_daemon_t *d, mca_daemon_summary_t *s) {
    if (d->thread_started && !mca_daemon_finished(d)) {
        /* the loop runs: take its newest published figures (no reads of its live data) */
        while (mca_ring_pop(&d->sum_ring, &d->sum_main) == MCA_OK) {
        }
        *s = d->sum_main;
        s->state = mca_daemon_state(d);
        s->ticks = mca_daemon_ticks(d);
    } else {
        mcad_compute_summary(d, s);
    }
    if (s->fault) {
        mcad_fault_describe(d, s->fault, s->fault_arm, s->fault_detail, s->fault_arm_code, s->fault_count,
                            &s->ctrl_why, s->fault_text, sizeof s->fault_text);
    }
}

void mca_daemon_log_summary(const mca_daemon_summary_t *s, mca_log_fn fn, void *arg) {
    mcad_logf(fn, arg, 6,
              "summary: state %s, ticks %llu, overruns %llu (skipped periods %llu), SCHED_FIFO %s, "
              "memory locked %s",
              mca_daemon_state_name(s->state), (unsigned long long)s->ticks, (unsigned long long)s->overruns,
              (unsigned long long)s->skipped_periods, s->sched_fifo ? "yes" : "no",
              s->mem_locked ? "yes" : "no");
    mcad_logf(fn, arg, 6,
              "summary: loop stalls (> %d periods between two ticks' commands) %llu, the longest %.1f "
              "ms",
              MCA_DAEMON_STALL_PERIODS, (unsigned long long)s->stalls, (double)s->stall_max_ns / 1e6);
    mcad_logf(fn, arg, 6, "summary: wake-up jitter p50 %.1f us, p99 %.1f us, p99.9 %.1f us, max %.1f us",
              (double)s->jitter_p50_ns / 1e3, (double)s->jitter_p99_ns / 1e3, (double)s->jitter_p999_ns / 1e3,
              (double)s->jitter_max_ns / 1e3);
    mcad_logf(fn, arg, 6,
              "summary: compute time (whole tick) p50 %.1f us, p99 %.1f us, max %.1f us; controller "
              "tick p50 %.1f us, p99 %.1f us, max %.1f us",
              (double)s->compute_p50_ns / 1e3, (double)s->compute_p99_ns / 1e3,
              (double)s->compute_max_ns / 1e3, (double)s->ctrl_p50_ns / 1e3, (double)s->ctrl_p99_ns / 1e3,
              (double)s->ctrl_max_ns / 1e3);
    char steps[64];
    if (s->pdnn_step_budget > 0) {
        snprintf(steps, sizeof steps, "%d steps (cap %d)", s->pdnn_step_budget, s->pdnn_max_steps);
    } else {
        snprintf(steps, sizeof steps, "the cap %d steps", s->pdnn_max_steps);
    }
    mcad_logf(fn, arg, s->pdnn_budget_time + s->pdnn_budget_steps ? 5 : 6,
              "summary: PDNN out of its budget (%.3g us, %s): %llu ticks by the clock, %llu by steps "
              "(no faults: short answers repaired)",
              s->pdnn_budget_us, steps, (unsigned long long)s->pdnn_budget_time,
              (unsigned long long)s->pdnn_budget_steps);
    if (s->dds_ab_block && s->dds_ab_n[0] && s->dds_ab_n[1] && s->dds_ab_p50_ns[0] && s->dds_ab_p99_ns[0]) {
        mcad_logf(
            fn, arg, 6,
            "summary: dds on/off (blocks of %u ticks): whole tick publishing off p50 %.1f us, "
            "p99 %.1f us, mean %.2f us (%llu ticks); on p50 %.1f us, p99 %.1f us, mean %.2f us (%llu ticks); "
            "ratio on/off p50 %.3f, p99 %.3f, mean %.3f",
            s->dds_ab_block, (double)s->dds_ab_p50_ns[0] / 1e3, (double)s->dds_ab_p99_ns[0] / 1e3,
            s->dds_ab_mean_ns[0] / 1e3, (unsigned long long)s->dds_ab_n[0], (double)s->dds_ab_p50_ns[1] / 1e3,
            (double)s->dds_ab_p99_ns[1] / 1e3, s->dds_ab_mean_ns[1] / 1e3, (unsigned long long)s->dds_ab_n[1],
            (double)s->dds_ab_p50_ns[1] / (double)s->dds_ab_p50_ns[0],
            (double)s->dds_ab_p99_ns[1] / (double)s->dds_ab_p99_ns[0],
            s->dds_ab_mean_ns[1] / s->dds_ab_mean_ns[0]);
        if (s->dds_ab_short_n[0] && s->dds_ab_short_n[1] && s->dds_ab_short_mean_ns[0] > 0.0) {
            mcad_logf(fn, arg, 6,
                      "summary: dds on/off, ticks shorter than half a period: off mean %.2f us (%llu "
                      "ticks), "
                      "on mean %.2f us (%llu ticks); ratio on/off mean %.3f",
                      s->dds_ab_short_mean_ns[0] / 1e3, (unsigned long long)s->dds_ab_short_n[0],
                      s->dds_ab_short_mean_ns[1] / 1e3, (unsigned long long)s->dds_ab_short_n[1],
                      s->dds_ab_short_mean_ns[1] / s->dds_ab_short_mean_ns[0]);
        }
    }
    if (isfinite(s->min_distance)) {
        mcad_logf(fn, arg, 6, "summary: minimum distance %.4f m at t = %.3f s", s->min_distance,
                  s->min_distance_t);
    } else {
        mcad_logf(fn, arg, 6, "summary: minimum distance n/a");
    }
    if (s->body_pair[0] >= 0) {
        mcad_logf(fn, arg, 6,
                  "summary: fixed bodies: least margin %.4f m (distance %.4f m) at t = %.3f s, arm %d "
                  "link %d against %s '%s'",
                  s->body_margin, s->body_distance, s->body_t, s->body_pair[0], s->body_pair[1],
                  mca_body_kind_name(s->body_kind), s->body_name);
    }
    if (s->self_pair[0] >= 0) {
        mcad_logf(fn, arg, 6, "summary: self pairs: least distance %.4f m at t = %.3f s, arm %d links %d-%d",
                  s->self_distance, s->self_t, s->self_pair[0], s->self_pair[1], s->self_pair[2]);
    }
    {
        /* every kind of pair, then each fixed body: where each came closest */
        char kinds[256];
        int len = 0;
        for (int k = 0; k < MCA_DDS_PAIR_KINDS && len < (int)sizeof kinds; k++) {
            len +=
                isfinite(s->kind_min[k])
                    ? snprintf(kinds + len, sizeof kinds - (size_t)len, "%s%s %.4f m at t = %.3f s",
                               len ? ", " : "", mca_dds_pair_kind_name(k), s->kind_min[k], s->kind_min_t[k])
                    : snprintf(kinds + len, sizeof kinds - (size_t)len, "%s%s n/a", len ? ", " : "",
                               mca_dds_pair_kind_name(k));
        }
        mcad_logf(fn, arg, 6, "summary: least distance per kind: %s", kinds);
    }
    for (int k = 0; k < s->n_fixed_bodies && k < MCA_MAX_BODIES; k++) {
        if (s->fixed_min_link[k][0] >= 0) {
            mcad_logf(fn, arg, 6,
                      "summary: body '%.32s': least distance %.4f m at t = %.3f s, arm %d link %d",
                      s->fixed_name[k], s->fixed_min[k], s->fixed_min_t[k], s->fixed_min_link[k][0],
                      s->fixed_min_link[k][1]);
        } else {
            mcad_logf(fn, arg, 6, "summary: body '%.32s': every link allowed, none measured",
                      s->fixed_name[k]);
        }
    }
    if (s->brake_t >= 0.0) {
        mcad_logf(fn, arg, s->brake_fallback_ticks ? 4 : 6,
                  "summary: braking from t = %.3f s, %s %.3f s, keep-direction fallback ticks %llu "
                  "(past the deadline %llu), max |dv|/(dec dt) %.4f",
                  s->brake_t, s->stop_duration_s >= 0.0 ? "at rest after" : "not at rest after",
                  s->stop_duration_s >= 0.0 ? s->stop_duration_s : 0.0,
                  (unsigned long long)s->brake_fallback_ticks, (unsigned long long)s->brake_forced_ticks,
                  s->max_dv_over_dt_dec);
    }
    if (s->deadlocks || s->deadlock) {
        mcad_logf(fn, arg, 6, "summary: deadlocks %d (state now %s)", s->deadlocks,
                  s->deadlock == MCA_DEADLOCK_BACK_OFF ? "back-off"
                  : s->deadlock == MCA_DEADLOCK_WAIT   ? "wait"
                                                       : "none");
    }
    if (s->fault) {
        mcad_logf(fn, arg, 3, "summary: faults: 1 (at t = %.3f s: %s)", s->fault_t, s->fault_text);
    } else {
        mcad_logf(fn, arg, 6, "summary: faults: none");
    }
    for (int a = 0; a < s->n_arms && a < MCA_MAX_ARMS; a++) {
        /* what each link took and why it ignored the rest: a field diagnosis starts here */
        const mca_arm_stats_t *st = &s->link[a];
        const int unusual =
            st->rx_bad_length || st->rx_bad_counter || st->rx_implausible || st->bus_errors || st->rx_dropped;
        char ign[160];
        mcad_link_ignored_text(st, ign, sizeof ign);
        mcad_logf(fn, arg, unusual ? 4 : 6,
                  "summary: arm %.32s link: commands sent %llu, feedback taken %llu; %s", s->arm_name[a],
                  (unsigned long long)st->commands_sent, (unsigned long long)st->feedback_received, ign);
    }
    if (s->implausible_samples) {
        mcad_logf(fn, arg, 4, "summary: implausible feedback samples dropped %llu",
                  (unsigned long long)s->implausible_samples);
    }
    if (s->log_dropped || s->csv_dropped) {
        mcad_logf(fn, arg, 4, "summary: dropped log records %llu, CSV rows %llu",
                  (unsigned long long)s->log_dropped, (unsigned long long)s->csv_dropped);
    }
}
