/* SPDX-License-Identifier: MIT */
/* mca-ts's path time: the acceleration box, the tube, each arm's rate and clock, deadlock and back-off, the
 * exact waypoints (see controller__ts.h). */
#include <math.h>
#include <string.h>

#include "mca/controller.h"
#include "mca/vec3.h"

#include "controller__ts.h"

/* mca-ts: commands the arm can follow. Each joint's command stays within dec_limit dt of the last one, the
 * rate an arm at its limits follows exactly, so the rows hold for the arm and not only for the command.
 * Where the last command lies beyond a joint-limit bound by more than that, the joint limit wins. */
void mca_ctrl__accel_box(mca_controller_t *ctrl, const mca_scheme_info_t *si, int na) {
    const mca_controller_config_t *cfg = &ctrl->cfg;
    mca_qp_t *qp = &ctrl->qp;
    for (int a = 0; a < na; a++) {
        const double step = cfg->ts.dec_limit[a] * cfg->dt;
        if (!(step > 0.0)) {
            continue;
        }
        for (int j = 0; j < cfg->chain[a].dof; j++) {
            const int k = si->var_off[a] + j;
            const double v = ctrl->has_v_meas ? ctrl->v_meas[k] : ctrl->has_prev ? ctrl->phi_prev[k] : 0.0;
            ctrl->box_center[k] = v;
            double lo = fmax(qp->lb[k], v - step), hi = fmin(qp->ub[k], v + step);
            if (lo > hi) {
                lo = hi = v - step > qp->ub[k] ? qp->ub[k] : qp->lb[k];
            }
            qp->lb[k] = lo;
            qp->ub[k] = hi;
        }
    }
}

/* mca-ts: the tube also admits the slack of one braking step along the arm's present direction (the
 * keep-direction stop, inside the acceleration box) with the path rate that fits it best. Standing still is
 * a point of the tube only once the arm is slow enough to stop in one tick; before that, this step is what
 * the stoppability bound keeps inside the rows, and with it the QP keeps an answer while the arm brakes on a
 * curved path (a tube of 0 alone made the box, the rows and the tube disjoint: the PDNN at its cap).
 * Runs after mca_ctrl__accel_box, before mca_scheme_add_timescale (alpha is still rdot + K err). */
void mca_ctrl__tube_keep_brake(mca_controller_t *ctrl, const mca_scheme_info_t *si, int a,
                               const double rdot[3], double sig_lo, double sig_hi, double lo[3],
                               double hi[3]) {
    const mca_controller_config_t *cfg = &ctrl->cfg;
    const mca_qp_t *qp = &ctrl->qp;
    const int vo = si->var_off[a], dof = cfg->chain[a].dof;
    double c[MCA_MAX_DOF], qb[MCA_MAX_DOF], dec[MCA_MAX_DOF];
    for (int j = 0; j < dof; j++) {
        c[j] = fmax(qp->lb[vo + j], fmin(qp->ub[vo + j], ctrl->box_center[vo + j]));
        dec[j] = cfg->ts.dec_limit[a];
    }
    mca_brake_scale_arm(c, dec, cfg->dt, dof, qb);
    double v[3]; /* J qb - K err: the path velocity the step needs */
    for (int i = 0; i < 3; i++) {
        const int row = MCA_TASK_DIM * a + i;
        v[i] = -(qp->alpha[row] - rdot[i]);
        for (int j = 0; j < dof; j++) {
            v[i] += qp->G[row][vo + j] * qb[j];
        }
    }
    const double r2 = mca_v3_dot(rdot, rdot);
    const double sigma = fmax(sig_lo, fmin(sig_hi, r2 > 1e-12 ? mca_v3_dot(v, rdot) / r2 : 0.0));
    memcpy(ctrl->keep_q[a], qb, sizeof(double) * (size_t)dof);
    ctrl->keep_sigma[a] = sigma;
    int can_stop = 1; /* 0 inside the box: standing still is a point of the tube already */
    for (int j = 0; j < dof; j++) {
        can_stop &= qp->lb[vo + j] <= 0.0 && qp->ub[vo + j] >= 0.0;
    }
    for (int i = 0; i < 3 && !can_stop; i++) {
        const double e = v[i] - sigma * rdot[i];
        lo[i] = fmin(lo[i], e);
        hi[i] = fmax(hi[i], e);
    }
}

/* Held and deadlocked are judged on the path rate averaged over this time [s], not on one tick's: two arms
 * pressed against each other's rows chatter (sigma 0 for a few hundred ticks, then one tick at 1.25), and
 * each spike reset the hold and the deadlock timers, so 11 of 16 crossing tasks at tolerance 5 cm crawled
 * for the rest of the run (0.005 s of path time per s) without ever being declared deadlocked. */
#define MCA_TS_RATE_AVG_S 0.1

/* Back-offs of one arm in a row before another blocked arm backs off instead. */
#define MCA_TS_BACK_OFFS_PER_ARM 2

/* Catching up: the rate an arm aims at grows with its lag behind task time (1/s per s of lag). */
#define MCA_TS_CATCH_UP_GAIN 1.0

/* Coordination gates: an arm slows at this path-rate deceleration [1/s^2] to stop this far [cells] before a
 * gated cell of its path time (from sigma_max 1.5: 0.28 s of path time). */
#define MCA_TS_GATE_DEC 4.0
#define MCA_TS_GATE_ROOM 0.25

/* mca-ts, before the solve: each arm's target rate and rate bounds from the deadlock state and the gates. */
void mca_ctrl__ts_plan(mca_controller_t *ctrl, double task_t, double target[], double lo[], double hi[]) {
    const mca_timescale_params_t *tp = &ctrl->cfg.ts;
    const int na = ctrl->cfg.n_arms;
    if (ctrl->deadlock == MCA_DEADLOCK_BACK_OFF && task_t >= ctrl->deadlock_until) {
        ctrl->deadlock = MCA_DEADLOCK_WAIT;
        for (int a = 0; a < na; a++) {
            ctrl->wait_tau[a] = ctrl->tau[a];
        }
        ctrl->deadlock_until = task_t + 4.0 * tp->back_off_time + tp->deadlock_time;
    }
    if (ctrl->deadlock == MCA_DEADLOCK_WAIT) {
        /* the others have moved on (each advanced by the back-off time, or finished), or time is up */
        int moved = 1;
        for (int a = 0; a < na; a++) {
            if (a != ctrl->deadlock_arm && ctrl->tau[a] < ctrl->path_end[a] &&
                ctrl->tau[a] - ctrl->wait_tau[a] < tp->back_off_time) {
                moved = 0;
            }
        }
        if (moved || task_t >= ctrl->deadlock_until) {
            ctrl->deadlock = MCA_DEADLOCK_NONE;
            ctrl->deadlock_arm = -1;
            ctrl->back_offs = 0;
            ctrl->stall_time = 0.0;
        }
    }
    for (int a = 0; a < na; a++) {
        const double lag = fmax(0.0, task_t - ctrl->tau[a]);
        /* a stream does not catch up: the operator's motion resumes at the operator's speed */
        target[a] = ctrl->cfg.path[a].kind == MCA_PATH_STREAM
                        ? 1.0
                        : fmin(tp->sigma_max, 1.0 + MCA_TS_CATCH_UP_GAIN * lag);
        lo[a] = 0.0;
        hi[a] = tp->sigma_max;
        if (a == ctrl->deadlock_arm && ctrl->deadlock == MCA_DEADLOCK_BACK_OFF) {
            target[a] = -1.0;
            lo[a] = ctrl->tau[a] > 0.0 ? -1.0 : 0.0;
            hi[a] = 0.0;
        } else if (a == ctrl->deadlock_arm && ctrl->deadlock == MCA_DEADLOCK_WAIT) {
            target[a] = lo[a] = hi[a] = 0.0;
        }
        /* sigma's own stop bound: no faster than the arm can still stop on its curved path */
        /* (never lower than the arm can slow to in this tick: where the prediction missed, the arm slows as
         * fast as it can on its path instead of leaving it) */
        const double lim =
            fmax(mca_path_rate_at(&ctrl->rate[a], ctrl->tau[a]),
                 ctrl->sigma[a] - mca_path_rate_decel(&ctrl->rate[a], ctrl->tau[a]) * ctrl->cfg.dt);
        if (lim < hi[a]) {
            hi[a] = fmax(lo[a], lim);
            target[a] = fmin(target[a], hi[a]);
        }
        if (ctrl->coord.n_pairs > 0 && hi[a] > 0.0) {
            const double ahead = tp->sigma_max * tp->sigma_max / (2.0 * MCA_TS_GATE_DEC);
            const double gate = mca_coord_gate(&ctrl->coord, a, ctrl->tau, ahead);
            if (gate < INFINITY) {
                const double room = fmax(0.0, gate - MCA_TS_GATE_ROOM * MCA_COORD_CELL_S - ctrl->tau[a]);
                const double cap = sqrt(2.0 * MCA_TS_GATE_DEC * room);
                if (cap < hi[a]) {
                    hi[a] = fmax(lo[a], cap);
                    target[a] = fmin(target[a], hi[a]);
                }
            }
        }
    }
}

/* mca-ts, path first: an arm held on its path (sigma below deadlock_sigma while its path moves) for half the
 * deadlock time gives way: its slack loses the exact weight and it may slide past within its tube (a tube
 * of 0 leaves no room: it waits, and a deadlock is resolved by backing off). At speed again it keeps its
 * path first. */
static void give_way(mca_controller_t *ctrl, int a, double rate, double speed) {
    const mca_timescale_params_t *tp = &ctrl->cfg.ts;
    if (!ctrl->cfg.path[a].path_first) {
        return;
    }
    if (ctrl->at_tube_edge[a]) {
        /* at the tube's edge: sliding on would creep out (what the arm does not follow of each command
         * accumulates, and the tube only stops a first-order error from growing: 8.3 cm seen in a 5 cm tube).
         * The exact weight takes it back while it is held; held long enough, it gives way again. */
        ctrl->held_time[a] = 0.0;
        ctrl->giving_way[a] = 0;
    } else if (rate < tp->deadlock_sigma && speed > 1e-6 && ctrl->tau[a] < ctrl->path_end[a]) {
        ctrl->held_time[a] += ctrl->cfg.dt;
        ctrl->giving_way[a] |= ctrl->held_time[a] >= 0.5 * tp->deadlock_time;
    } else if (rate > 0.9 || speed <= 1e-6) {
        /* moving again: the exact weight takes it back onto its path (the tube's L2 alone would keep it
         * where the multiplier puts it, and what the arm does not follow of each command would creep out) */
        ctrl->held_time[a] = 0.0;
        ctrl->giving_way[a] = 0;
    }
}

/* mca-ts, after the solve: read each arm's rate, advance its clock, watch for a deadlock. */
void mca_ctrl__ts_advance(mca_controller_t *ctrl, mca_tick_info_t *info, const int ts_off[],
                          const double rdot_d[][3], const double target[], const double lo[],
                          const double hi[]) {
    const mca_controller_config_t *cfg = &ctrl->cfg;
    const mca_timescale_params_t *tp = &cfg->ts;
    const int na = cfg->n_arms;
    const mca_timescale_weights_t w = {tp->w_sigma, tp->w_slack, tp->w_path, tp->w_tube};
    int unfinished = 0, progressing = 0, victim = -1, other = -1;
    double slack = 0.0;
    for (int a = 0; a < na; a++) {
        double sigma = target[a] + ctrl->phi[ts_off[a]] / ctrl->ts_scale[a];
        sigma = fmax(lo[a], fmin(hi[a], sigma));
        const double speed = mca_v3_norm(rdot_d[a]);
        for (int i = 0; i < MCA_TASK_DIM; i++) {
            slack = fmax(slack, fabs(mca_scheme_ts_slack(ctrl->phi, ts_off[a], i, &w, ctrl->track_mode[a])));
        }
        ctrl->sigma[a] = sigma;
        ctrl->rate_avg[a] += (sigma - ctrl->rate_avg[a]) * fmin(1.0, cfg->dt / MCA_TS_RATE_AVG_S);
        const double rate = ctrl->rate_avg[a];
        give_way(ctrl, a, rate, speed);
        if (ctrl->deadlock == MCA_DEADLOCK_BACK_OFF && a == ctrl->deadlock_arm && speed < 1e-6 &&
            ctrl->tau[a] > 0.0) {
            /* backing through a dwell moves nothing: its path time does not count towards the back-off (an
             * arm that backed off into its pick dwell stayed in the other's way: pnp-jaco-mico:1) */
            ctrl->deadlock_until += cfg->dt;
        }
        ctrl->tau[a] = fmax(0.0, fmin(ctrl->path_end[a], ctrl->tau[a] + sigma * cfg->dt));
        if (ctrl->tau[a] < ctrl->path_end[a]) {
            unfinished++;
            /* an arm whose path does not move here (a dwell, the start of a circle) is not held up */
            if (rate >= tp->deadlock_sigma || speed < 1e-6) {
                progressing++;
            } else {
                if (victim < 0 || tp->priority[a] <= tp->priority[victim]) {
                    victim = a; /* the lowest priority of the blocked arms (the last one on a tie) */
                }
                if (a != ctrl->deadlock_arm && (other < 0 || tp->priority[a] <= tp->priority[other])) {
                    other = a; /* the same among the blocked arms that have not backed off */
                }
            }
        }
    }
    info->slack = slack;
    if (ctrl->deadlock != MCA_DEADLOCK_BACK_OFF && unfinished > 0 && progressing == 0) {
        ctrl->stall_time += cfg->dt;
        if (ctrl->stall_time >= tp->deadlock_time && victim >= 0) {
            /* waiting and the others still blocked: the same arm backs off further (paths that keep the
             * tool tips on them free no room otherwise), twice; then another blocked arm takes its turn
             * (backing off along its own path had put the first one in the others' way again: pick and
             * place, an arm backed off into its pick area, across the other's transfer) */
            int arm = victim;
            if (ctrl->deadlock == MCA_DEADLOCK_WAIT) {
                arm = ctrl->back_offs < MCA_TS_BACK_OFFS_PER_ARM || other < 0 ? ctrl->deadlock_arm : other;
            }
            ctrl->back_offs = arm == ctrl->deadlock_arm ? ctrl->back_offs + 1 : 1;
            ctrl->deadlock_arm = arm;
            ctrl->deadlock = MCA_DEADLOCK_BACK_OFF;
            ctrl->deadlock_until = info->task_t + tp->back_off_time;
            ctrl->deadlocks++;
            ctrl->stall_time = 0.0;
        }
    } else if (progressing > 0) {
        ctrl->stall_time = 0.0;
    }
}

/* Exact waypoints of arm a at path time tau: each is checked from the first tick whose clock has reached it
 * to the end of the dwell that follows it (a point without a dwell: that one tick). */
void mca_ctrl__exact_check(mca_controller_t *ctrl, int a, double tau) {
    const mca_path_t *path = &ctrl->cfg.path[a];
    if (path->kind != MCA_PATH_WAYPOINTS) {
        return;
    }
    for (int i = ctrl->exact_next[a]; i < path->n_points; i++) {
        ctrl->exact_next[a] = i;
        if (!path->exact[i]) {
            continue;
        }
        const double t_at = mca_path_point_time(path, i);
        if (tau < t_at) {
            return;
        }
        double x[3];
        mca_path_point(path, i, x);
        const double e = mca_v3_dist(x, ctrl->kin[a].ee);
        ctrl->exact_error_max = fmax(ctrl->exact_error_max, e);
        ctrl->exact_bad[a] |= e > path->exact_tol;
        if (mca_path_dwell(path, i) && tau < mca_path_point_time(path, i + 1)) {
            return; /* held: checked again next tick */
        }
        ctrl->exact_met += !ctrl->exact_bad[a];
        ctrl->exact_missed += ctrl->exact_bad[a];
        ctrl->exact_bad[a] = 0;
    }
    ctrl->exact_next[a] = path->n_points;
}

/* Path-time figures of the tick report (the schemes without path-time scaling run on task time). */
void mca_ctrl__fill_path_info(mca_controller_t *ctrl, mca_tick_info_t *info) {
    const int ts = ctrl->cfg.scheme == MCA_SCHEME_MCA_TS;
    int done = 1;
    for (int a = 0; a < ctrl->cfg.n_arms; a++) {
        if (!ts) {
            ctrl->tau[a] = fmin(info->task_t, ctrl->path_end[a]);
            ctrl->sigma[a] = 1.0;
        }
        info->tau[a] = ctrl->tau[a];
        info->sigma[a] = ctrl->sigma[a];
        done &= ctrl->tau[a] >= ctrl->path_end[a];
    }
    info->paths_done = done;
    info->deadlock = ctrl->deadlock;
    info->deadlock_arm = ctrl->deadlock_arm;
    info->deadlocks = ctrl->deadlocks;
}
