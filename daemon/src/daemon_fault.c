/* SPDX-License-Identifier: MIT */
/* Faults and braking (daemon__fault.h): the latch every fault goes through and the braking tick (RT thread);
 * the fault's text, made off the RT path (service thread, shut-down). */
#include "daemon__fault.h"

#include <math.h>
#include <string.h>

#include "mca/err.h"

#include "daemon__backends.h"     /* mca_backend_get */
#include "daemon__plausibility.h" /* mcad_fb_fault_what */

/* Latch a fault (the first one wins) as a code and numbers: @p detail, @p arm_code and @p count as the
 * fault kind needs them (see struct mca_daemon), @p ctrl_why the controller's cause (CONTROLLER only).
 * No text is made here: the log record carries the code, mcad_fault_describe() makes the text off the rt
 * path. */
void mcad_latch_fault(mca_daemon_t *d, int fault, int code, double t, int arm, int detail, int arm_code,
                      int count, const mca_ctrl_fault_why_t *ctrl_why) {
    if (d->fault != MCA_DAEMON_FAULT_NONE) {
        return;
    }
    d->fault = fault;
    d->fault_arm = arm;
    d->fault_code = code;
    d->fault_t = t;
    d->fault_detail = detail;
    d->fault_arm_code = arm_code;
    d->fault_count = count;
    d->ctrl_why = ctrl_why ? *ctrl_why : (mca_ctrl_fault_why_t){0};
    d->stop_pending = 0;
    atomic_store_explicit(&d->fault_latched, 1, memory_order_release);
    atomic_store(&d->state, MCA_DAEMON_BRAKING);
    mca_rtlog_code(&d->log, MCA_LOG_ERR, LOGC_FAULT, 1, t, 0, 0, 0, NULL);
}

int mcad_ctrl_fault_code(int f) {
    switch (f) {
    case MCA_CTRL_FAULT_NAN:
    case MCA_CTRL_FAULT_INPUT:
        return MCA_EINVAL;
    case MCA_CTRL_FAULT_NOT_CONVERGED:
        return MCA_ENOTCONV;
    case MCA_CTRL_FAULT_INFEASIBLE:
    case MCA_CTRL_FAULT_FAKE_ATTRACTOR:
        return MCA_EINFEASIBLE;
    default:
        return MCA_EFAULT;
    }
}

/* What an arm's link did not take, and why (non-rt): the lost-feedback fault and the summary say it alike. */
void mcad_link_ignored_text(const mca_arm_stats_t *st, char *buf, size_t len) {
    snprintf(
        buf, len,
        "ignored %llu length, %llu counter, %llu id, %llu implausible; %llu bus errors, %llu dropped by the "
        "kernel",
        (unsigned long long)st->rx_bad_length, (unsigned long long)st->rx_bad_counter,
        (unsigned long long)st->rx_unknown_id, (unsigned long long)st->rx_implausible,
        (unsigned long long)st->bus_errors, (unsigned long long)st->rx_dropped);
}

/* The text of a latched fault (non-rt: summary, log drainer, DDS publisher). */
void mcad_fault_describe(const mca_daemon_t *d, int fault, int arm, int detail, int arm_code, int count,
                         const mca_ctrl_fault_why_t *ctrl_why, char *buf, size_t len) {
    const char *name = arm >= 0 && arm < d->n_arms ? d->cell.scn.arm[arm].name : "?";
    switch (fault) {
    case MCA_DAEMON_FAULT_CONTROLLER:
        mca_ctrl_fault_format(ctrl_why, buf, len);
        break;
    case MCA_DAEMON_FAULT_STREAM_STALE:
        snprintf(buf, len, "arm %s: no target on its stream for %.3f s (task.stream.brake_after)", name,
                 d->cell.stream.brake_after);
        break;
    case MCA_DAEMON_FAULT_TRACKS_LOST:
        snprintf(buf, len,
                 "streamed bodies lost: no message on /%s/%s for %.3f s (streamed_bodies.lost_after %.3f s)",
                 d->cell.dds.ros2.ns, d->cell.tracks.topic, d->tracks_lost_age,
                 d->cell.tracks.ssm.lost_after);
        break;
    case MCA_DAEMON_FAULT_OVERRUN:
        snprintf(buf, len, "consecutive overruns: %d periods missed in a row (rt.overrun_limit %d)", count,
                 d->cell.rt.overrun_limit);
        break;
    case MCA_DAEMON_FAULT_LOST_FEEDBACK:
        if (d->have_fault_link) {
            char ign[160];
            mcad_link_ignored_text(&d->fault_link, ign, sizeof ign);
            snprintf(buf, len, "lost feedback: arm %s, no new feedback for %d cycles (link: %llu taken; %s)",
                     name, count, (unsigned long long)d->fault_link.feedback_received, ign);
        } else {
            snprintf(buf, len, "lost feedback: arm %s, no new feedback for %d cycles", name, count);
        }
        break;
    case MCA_DAEMON_FAULT_BUS:
        snprintf(buf, len, "arm %s link is bus-off: lost feedback (%d cycles)", name, count);
        break;
    case MCA_DAEMON_FAULT_ARM:
        if (detail == ARM_FAULT_NOT_SERVO) {
            snprintf(buf, len, "arm %s does not servo: state %s", name, mca_arm_state_name(arm_code));
        } else {
            char co[200] = "";
            const mca_backend_def_t *be =
                arm >= 0 && arm < d->n_arms ? mca_backend_get(d->cell.arm[arm].backend) : NULL;
            if (be && be->fault_detail) {
                /* what the fault is about (CANopen: which drive and why, the master's first latched fault,
                 * written once by the loop) */
                co[0] = ' ';
                co[1] = '(';
                if (be->fault_detail(d->arm[arm], co + 2, sizeof co - 3) == MCA_OK) {
                    strcat(co, ")");
                } else {
                    co[0] = 0;
                }
            }
            snprintf(buf, len, "arm %s %s%s%s", name,
                     detail == ARM_FAULT_REPORTS ? "reports FAULT " : "brakes on its own: ",
                     mca_arm_fault_name(arm_code), co);
        }
        break;
    case MCA_DAEMON_FAULT_FEEDBACK:
        if (detail == FB_DETAIL_LINK) {
            snprintf(buf, len, "arm %s link refuses its feedback: %s", name, mca_arm_fault_name(arm_code));
            break;
        }
        snprintf(buf, len, "arm %s sends implausible feedback (%s): %s", name,
                 mca_feedback_fault_name(detail),
                 detail > 0 && detail <= MCA_FB_VELOCITY ? mcad_fb_fault_what[detail] : "?");
        break;
    default:
        snprintf(buf, len, "%s", fault ? "?" : "");
        break;
    }
}

static void fault_text_of(const mca_daemon_t *d, char *buf, size_t len) {
    mcad_fault_describe(d, d->fault, d->fault_arm, d->fault_detail, d->fault_arm_code, d->fault_count,
                        &d->ctrl_why, buf, len);
}

/* The DDS publisher (another process) cannot call mcad_fault_describe(): the service thread hands it the
 * latched fault's text once, as soon as it sees the latch (not as a side effect of formatting its log line,
 * which a full log ring may drop). */
void mcad_fault_text_to_dds(mca_daemon_t *d) {
    if (d->dds && !d->fault_text_handed && atomic_load_explicit(&d->fault_latched, memory_order_acquire)) {
        char txt[256];
        fault_text_of(d, txt, sizeof txt);
        mca_dds_bridge_fault_text(d->dds, d->fault_code, txt);
        d->fault_text_handed = 1;
    }
}

/* mca_rtlog_code() records (the drainer, non-rt) */
void mcad_log_format(void *arg, const mca_rtlog_rec_t *rec, char *buf, size_t len) {
    const mca_daemon_t *d = arg;
    if (rec->code == LOGC_FAULT) {
        char txt[256];
        fault_text_of(d, txt, sizeof txt);
        snprintf(buf, len, "fault at t = %.3f s: braking both arms: %s", rec->arg[0], txt);
    } else if (rec->code == LOGC_ARM_FAULT_TOO) {
        char txt[192];
        mcad_fault_describe(d, MCA_DAEMON_FAULT_ARM, (int)rec->arg[1],
                            rec->arg[3] != 0.0 ? ARM_FAULT_REPORTS : ARM_FAULT_BRAKES, (int)rec->arg[2], 0,
                            NULL, txt, sizeof txt);
        snprintf(buf, len, "also at t = %.3f s, while braking: %s", rec->arg[0], txt);
    } else {
        snprintf(buf, len, "code %d", rec->code);
    }
}

/* Keep-direction scale-down: each arm's whole velocity vector times one factor, so that no joint changes
 * by more than dec dt (reaches 0 within ceil(max_j |v_j| / (dec_j dt)) ticks). @return 1 when all are 0. */
static int brake_scale_down(mca_daemon_t *d) {
    const double dt = (double)d->cell.rt.period_ns * 1e-9;
    int all_zero = 1;
    for (int a = 0; a < d->n_arms; a++) {
        mca_brake_scale_arm(d->vcmd[a], d->dec[a], dt, d->dof[a], d->qdot[a]);
        for (int j = 0; j < d->dof[a]; j++) {
            d->qdot[a][j] = fabs(d->qdot[a][j]) <= 1e-9 ? 0.0 : d->qdot[a][j];
            all_zero &= d->qdot[a][j] == 0.0;
        }
    }
    return all_zero;
}

/* One braking tick: mca_controller_brake (velocities closest to zero inside last command +- dec dt, the
 * joint limits and the collision rows; its own fallback keeps each arm's direction) until the deadline
 * set when braking began (max_j |v_j| / dec_j, plus half of that and 20 periods), then the keep-direction
 * scale-down alone: a stop never lasts for ever. Measures the distances (as mca_controller_observe).
 * @return 1 when every command is zero. */
int mcad_brake_tick(mca_daemon_t *d, double t, const double *const qp[MCA_MAX_ARMS]) {
    const double dt = (double)d->cell.rt.period_ns * 1e-9;
    if (!d->brake_active) {
        double tmax = 0.0;
        for (int a = 0; a < d->n_arms; a++) {
            for (int j = 0; j < d->dof[a]; j++) {
                const double v = fabs(d->vcmd[a][j]);
                tmax = isfinite(v) ? fmax(tmax, v / d->dec[a][j]) : tmax;
            }
        }
        d->brake_active = 1;
        d->brake_t0 = t;
        d->brake_deadline = t + 1.5 * tmax + 20.0 * dt;
        d->brake_rest_t = -1.0;
    }
    const double *vl[MCA_MAX_ARMS], *dl[MCA_MAX_ARMS];
    double *qd[MCA_MAX_ARMS];
    for (int a = 0; a < MCA_MAX_ARMS; a++) {
        vl[a] = d->vcmd[a];
        dl[a] = d->dec[a];
        qd[a] = d->qdot[a];
    }
    int done, fallback = 0;
    if (t < d->brake_deadline) {
        const int rc = mca_controller_brake(d->ctrl, t, qp, vl, dl, qd, &d->info);
        if (rc < 0) {
            done = brake_scale_down(d);
            fallback = 1;
        } else {
            done = rc;
            fallback = d->info.brake_fallback;
        }
    } else {
        if (d->brake_forced++ == 0) {
            LOGN(d, MCA_LOG_WARNING,
                 "braking not at rest %.3f s after it began (t = %.3f s): forcing the keep-direction "
                 "scale-down",
                 2, t - d->brake_t0, t, 0, 0, NULL);
        }
        mca_controller_observe(d->ctrl, t, qp, &d->info);
        done = brake_scale_down(d);
        fallback = 1;
    }
    d->info.brake_fallback = fallback;
    if (fallback) {
        d->brake_fallback++;
        if (!d->brake_fallback_logged) {
            d->brake_fallback_logged = 1;
            LOGN(d, MCA_LOG_WARNING,
                 "braking at t = %.3f s: no braking QP answer: each arm keeps its direction (whole velocity "
                 "scaled down)",
                 1, t, 0, 0, 0, NULL);
        }
    }
    for (int a = 0; a < d->n_arms; a++) {
        for (int j = 0; j < d->dof[a]; j++) {
            const double dv = fabs(d->qdot[a][j] - d->vcmd[a][j]) / (d->dec[a][j] * dt);
            if (isfinite(dv)) {
                d->brake_max_dv = fmax(d->brake_max_dv, dv);
            }
        }
    }
    return done;
}
