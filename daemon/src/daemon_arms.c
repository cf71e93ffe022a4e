/* SPDX-License-Identifier: MIT */
/* The arms' I/O and supervision (daemon__arms.h): open and handshake (start-up), feedback in and commands out
 * each tick (RT thread). */
#include "daemon__arms.h"

#include <math.h>
#include <string.h>
#include <time.h>

#include "mca/err.h"
#include "mca/errbuf.h" /* mca_errbuf_printf */

#include "daemon__log.h"      /* mcad_log: the caller's sink */
#include "daemon__backends.h" /* mca_backend_get */
#include "daemon__fault.h"    /* mcad_latch_fault */
#include "daemon__plausibility.h"

int mcad_open_arm(mca_daemon_t *d, int a, char *err, size_t errlen) {
    const mca_cell_arm_t *ca = &d->cell.arm[a];
    const mca_scenario_arm_t *sa = &d->cell.scn.arm[a];
    char berr[256] = "";
    const mca_backend_open_args_t o = {.cell = &d->cell,
                                       .arm = a,
                                       .chain = &d->ccfg.chain[a],
                                       .fb_lo = d->fb_lo[a],
                                       .fb_hi = d->fb_hi[a],
                                       .fb_vmax = d->fb_vmax[a],
                                       .virtual_time = d->drive.virtual_time,
                                       .ideal = (int)((d->drive.ideal_arms >> a) & 1u)};
    const int rc = mca_backend_get(ca->backend)->open(&d->arm[a], &o, berr, sizeof berr);
    if (rc != MCA_OK) {
        if (err && errlen) {
            snprintf(err, errlen, "arm '%s' (%s): cannot open: %s (%s)", sa->name,
                     mca_cell_backend_name(ca->backend), berr[0] ? berr : "-", mca_strerror(rc));
        }
        return rc;
    }
    return MCA_OK;
}

/* Wait (start-up, up to 2 s) until arm a answers. A FAULT latched in the arm (left from an earlier run) is
 * cleared only when the operator asked (opts.clear_faults, mcad --clear-faults); else start-up fails
 * naming the arm and the fault. */
int mcad_handshake(mca_daemon_t *d, int a, char *err, size_t errlen) {
    const int64_t deadline = now_ns() + 2 * NS_PER_S;
    int cleared = 0;
    mca_arm_command_t c;
    memset(&c, 0, sizeof c);
    c.n = d->dof[a];
    /* a backend whose arm names its own joint count (the CAN heartbeat): wait for it, and check it */
    const mca_backend_def_t *be = mca_backend_get(d->cell.arm[a].backend);
    const int can = be->reported_joints != NULL;
    while (now_ns() < deadline) {
        mca_arm_feedback_t fb;
        const int rc = mca_arm_read(d->arm[a], &fb);
        int hb_n = 0;
        const int have_hb = can && be->reported_joints(d->arm[a], &hb_n) == MCA_OK;
        if (have_hb && hb_n != d->dof[a]) {
            /* the arm's own joint count (heartbeat), not the decoder's: the link refuses its feedback */
            snprintf(err, errlen, "arm '%s': its heartbeat names %d joints, the model has %d",
                     d->cell.scn.arm[a].name, hb_n, d->dof[a]);
            return MCA_EINVAL;
        }
        if ((rc == MCA_OK || rc == MCA_EFAULT) && (!can || have_hb)) {
            if (fb.state == MCA_ARM_FAULT && !d->opts.clear_faults) {
                if (err && errlen) {
                    snprintf(
                        err, errlen,
                        "arm '%s' reports FAULT %s at start (latched in its firmware, left from an earlier "
                        "run): not starting; check the arm, then start with --clear-faults to clear it",
                        d->cell.scn.arm[a].name, mca_arm_fault_name(fb.fault_code));
                }
                return MCA_EFAULT;
            }
            if (fb.state == MCA_ARM_FAULT && cleared < 3) {
                mcad_log(d, 5,
                         "arm '%s' reports FAULT (%s) at start: clearing it (--clear-faults: the "
                         "operator asked)",
                         d->cell.scn.arm[a].name, mca_arm_fault_name(fb.fault_code));
                for (int j = 0; j < c.n; j++) {
                    c.flags[j] = MCA_ACT_CLEAR_FAULT;
                }
                cleared++;
            } else if (fb.state == MCA_ARM_READY || fb.state == MCA_ARM_SERVOING) {
                /* the first tick's command starts from this sample: the same plausibility check */
                int joint;
                double value, bound;
                const int kind = mcad_feedback_check(d, a, &fb, 0, &joint, &value, &bound);
                if (kind == MCA_FB_JOINT_COUNT) {
                    snprintf(err, errlen, "arm '%s': answers with %d joints, the model has %d",
                             d->cell.scn.arm[a].name, fb.n, d->dof[a]);
                    return MCA_EINVAL;
                }
                if (kind != MCA_FB_OK) {
                    snprintf(err, errlen,
                             "arm '%s': implausible feedback at start (%s: %s): joint %d: %g (bound %g)",
                             d->cell.scn.arm[a].name, mca_feedback_fault_name(kind), mcad_fb_fault_what[kind],
                             joint, value, bound);
                    return MCA_EINVAL;
                }
                d->fb_frame[a] = fb.frame_id;
                d->fb[a] = fb;
                d->have_fb[a] = 1;
                for (int j = 0; j < fb.n; j++) {
                    d->q[a][j] = fb.position[j];
                }
                return MCA_OK;
            }
        }
        /* keep the arm side's link alive: zero velocity, servo off (brakes hold) */
        c.frame_id = ++d->frame_id;
        mca_arm_write(d->arm[a], &c);
        for (int j = 0; j < c.n; j++) {
            c.flags[j] = 0;
        }
        if (!d->drive.virtual_time) {
            struct timespec ts = {0, d->cell.rt.period_ns};
            nanosleep(&ts, NULL);
        }
    }
    mca_errbuf_printf(err, errlen, "arm '%s' (%s): no answer within 2 s", d->cell.scn.arm[a].name,
                      mca_cell_backend_name(d->cell.arm[a].backend));
    return MCA_ETIMEDOUT;
}

/* An implausible sample of arm a: dropped (the caller keeps the last good one), counted, the first of each
 * arm logged with what failed; a fault of that arm while running or braking (every arm then brakes from the
 * last good state). */
static void feedback_implausible(mca_daemon_t *d, int a, int kind, int joint, double value, double bound,
                                 double t) {
    if (d->implausible[a]++ == 0) {
        if (joint >= 0) {
            LOGN(d, MCA_LOG_ERR, "arm %g joint %g: implausible feedback, dropped: %g (bound %g): %s", 4, a,
                 joint, value, bound, mcad_fb_fault_what[kind]);
        } else {
            LOGN(d, MCA_LOG_ERR, "arm %g: implausible feedback, dropped: %g (bound %g): %s", 3, a, value,
                 bound, 0, mcad_fb_fault_what[kind]);
        }
    }
    const int state = atomic_load_explicit(&d->state, memory_order_relaxed);
    if (state == MCA_DAEMON_RUNNING || state == MCA_DAEMON_BRAKING) {
        if (d->fault == MCA_DAEMON_FAULT_NONE) {
            d->feedback_fault = kind;
        }
        mcad_latch_fault(d, MCA_DAEMON_FAULT_FEEDBACK, MCA_EINVAL, t, a, kind, 0, 0, NULL);
    }
}

/* Read every arm's feedback; checks each sample (mcad_feedback_check), counts lost cycles and latches
 * arm/link faults. */
void mcad_read_feedback(mca_daemon_t *d, double t) {
    const int running = atomic_load_explicit(&d->state, memory_order_relaxed) == MCA_DAEMON_RUNNING;
    for (int a = 0; a < d->n_arms; a++) {
        mca_arm_feedback_t fb;
        const int rc = mca_arm_read(d->arm[a], &fb);
        int joint = -1, kind = MCA_FB_OK;
        double value = 0.0, bound = 0.0;
        if (rc == MCA_OK || rc == MCA_EFAULT) {
            kind = mcad_feedback_check(d, a, &fb, 1, &joint, &value, &bound);
        }
        if (kind != MCA_FB_OK) {
            /* not integrated: q, fb and the frame id stay the last good sample's. Not a lost cycle either:
             * the arm answered, wrongly, and that is its own fault. */
            feedback_implausible(d, a, kind, joint, value, bound, t);
        } else if (rc == MCA_OK || rc == MCA_EFAULT) {
            d->fb[a] = fb;
            d->fb_frame[a] = fb.frame_id;
            d->have_fb[a] = 1;
            d->lost[a] = 0;
            for (int j = 0; j < d->dof[a]; j++) {
                d->q[a][j] = fb.position[j];
            }
            if (running && (fb.state == MCA_ARM_FAULT || fb.state == MCA_ARM_BRAKING)) {
                mcad_latch_fault(d, MCA_DAEMON_FAULT_ARM, MCA_EFAULT, t, a,
                                 fb.state == MCA_ARM_FAULT ? ARM_FAULT_REPORTS : ARM_FAULT_BRAKES,
                                 fb.fault_code, 0, NULL);
            } else if (!running && d->fault != MCA_DAEMON_FAULT_NONE && fb.fault_code != MCA_ARM_FAULT_NONE &&
                       !d->arm_fault_told[a] && !(d->fault == MCA_DAEMON_FAULT_ARM && d->fault_arm == a)) {
                /* the first fault names one cause; an arm's own fault after it may be the root (a drive whose
                 * TPDOs stopped froze the arm and the controller gave up first): logged too, once per arm */
                d->arm_fault_told[a] = 1;
                mca_rtlog_code(&d->log, MCA_LOG_ERR, LOGC_ARM_FAULT_TOO, 4, t, a, fb.fault_code,
                               fb.state == MCA_ARM_FAULT, NULL);
            }
            /* an arm that keeps its brakes on while commanded (commands rejected) is a fault too */
            d->not_servo[a] =
                running && (fb.state == MCA_ARM_READY || fb.state == MCA_ARM_INIT) ? d->not_servo[a] + 1 : 0;
            const int not_servo_limit =
                2 * d->cell.rt.lost_feedback_cycles > 100 ? 2 * d->cell.rt.lost_feedback_cycles : 100;
            if (d->not_servo[a] >= not_servo_limit) {
                mcad_latch_fault(d, MCA_DAEMON_FAULT_ARM, MCA_EFAULT, t, a, ARM_FAULT_NOT_SERVO, fb.state,
                                 d->not_servo[a], NULL);
            }
        } else if (rc == MCA_EIO) {
            /* no new feedback and a link error (error frame, bus-off): a lost cycle, as EAGAIN (a burst
             * becomes a lost-feedback fault). Feedback that came with an error was returned as MCA_OK
             * above (mca/arm.h: a read never discards feedback; the error is reported later). */
            d->lost[a]++;
            if (d->bus_errors[a]++ == 0) {
                LOGN(d, MCA_LOG_WARNING, "arm %g: bus error on its link", 1, a, 0, 0, 0, NULL);
            }
        } else {
            d->lost[a]++;
        }
        if (running && d->lost[a] >= d->cell.rt.lost_feedback_cycles) {
            LOGN(d, MCA_LOG_ERR, "arm %g: no feedback for %g cycles", 2, a, d->lost[a], 0, 0, NULL);
            /* name the cause when the link knows it: a bus-off controller hears nothing */
            mca_arm_stats_t st;
            const int have_st = mca_arm_stats(d->arm[a], &st) == MCA_OK;
            if (have_st && st.link_fault == MCA_ARM_FAULT_BUS) {
                mcad_latch_fault(d, MCA_DAEMON_FAULT_BUS, MCA_EIO, t, a, 0, 0, d->lost[a], NULL);
            } else if (have_st && st.link_fault != MCA_ARM_FAULT_NONE) {
                /* the link refused what came (implausible feedback, another joint count): name it */
                mcad_latch_fault(d, MCA_DAEMON_FAULT_FEEDBACK, MCA_EINVAL, t, a, FB_DETAIL_LINK,
                                 st.link_fault, d->lost[a], NULL);
            } else if (d->fault == MCA_DAEMON_FAULT_NONE) {
                /* frames that came and were not taken show in the link's counters: keep them with the fault
                 */
                d->have_fault_link = have_st;
                if (have_st) {
                    d->fault_link = st;
                }
                mcad_latch_fault(d, MCA_DAEMON_FAULT_LOST_FEEDBACK, MCA_ETIMEDOUT, t, a, 0, 0, d->lost[a],
                                 NULL);
            }
        }
    }
}

void mcad_send_commands(mca_daemon_t *d, int servo) {
    const double dt = (double)d->cell.rt.period_ns * 1e-9;
    d->frame_id++;
    for (int a = 0; a < d->n_arms; a++) {
        mca_arm_command_t *c = &d->cmd[a];
        c->frame_id = d->frame_id;
        c->n = d->dof[a];
        for (int j = 0; j < c->n; j++) {
            const double v = servo ? d->qdot[a][j] : 0.0;
            c->velocity[j] = v;
            c->position_ref[j] = d->q[a][j] + v * dt;
            c->flags[j] = servo ? (MCA_ACT_SERVO_ENABLE | MCA_ACT_BRAKE_RELEASE) : 0;
            d->vcmd[a][j] = v;
        }
        const int rc = mca_arm_write(d->arm[a], c);
        if (rc != MCA_OK && rc != MCA_EAGAIN) {
            LOGN(d, MCA_LOG_WARNING, "arm %g: command not sent (%g)", 2, a, rc, 0, 0, NULL);
        }
    }
    /* the arms' watchdogs count the time between commands: a loop stall is a gap of more than a few periods
     * (an arm's watchdog tripping after it is the loop's stall, not the arm's fault). Logged one by one up
     * to MCA_DAEMON_STALLS_LOGGED, all counted, each tick's gap in the CSV. */
    const int64_t sent = now_ns();
    d->cmd_gap_ns = d->sent_ns ? sent - d->sent_ns : 0;
    d->sent_ns = sent;
    if (!d->drive.virtual_time && d->cmd_gap_ns > MCA_DAEMON_STALL_PERIODS * d->cell.rt.period_ns) {
        d->stalls++;
        d->stall_max_ns = d->cmd_gap_ns > d->stall_max_ns ? d->cmd_gap_ns : d->stall_max_ns;
        if (d->stalls <= MCA_DAEMON_STALLS_LOGGED) {
            LOGN(
                d, MCA_LOG_WARNING,
                "loop stall at t = %.3f s: %.1f ms between two ticks' commands (this tick woke %.1f ms late)",
                3, d->t_tick, (double)d->cmd_gap_ns * 1e-6, (double)d->wake_late_ns * 1e-6, 0, NULL);
        }
    }
}
