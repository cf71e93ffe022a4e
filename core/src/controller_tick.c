/* SPDX-License-Identifier: MIT */
/* One controller tick for N arms (FK, distances, QP, PDNN, faults): the pipeline; see mca/controller.h. */
#include "mca/controller.h"

#include <math.h>
#include <string.h>

#include "mca/err.h"
#include "mca/vec3.h"

#include "controller__common.h"
#include "controller__dist.h"
#include "controller__solve.h"
#include "controller__ts.h"

/* APF baseline (40)-(46) for every arm. */
static int apf_tick(mca_controller_t *ctrl, const double r_d[][3], const double rdot_d[][3],
                    double *const qdot[MCA_MAX_ARMS]) {
    const mca_controller_config_t *cfg = &ctrl->cfg;
    int off = 0;
    for (int a = 0; a < cfg->n_arms; a++) {
        const int dof = cfg->chain[a].dof;
        double J[3][MCA_MAX_DOF], v_att[3], qd[MCA_MAX_DOF];
        int rc = mca_jacobian_ee(&ctrl->kin[a], J);
        if (rc != MCA_OK) {
            return rc;
        }
        mca_apf_attractive(&cfg->apf, ctrl->kin[a].ee, r_d[a], rdot_d[a], v_att);
        rc = mca_apf_pinv_apply(J, dof, cfg->apf.damping, v_att, qd);
        if (rc != MCA_OK) {
            return rc;
        }
        /* (45): repulsion on every link whose critical point is inside the influence distance. */
        for (int l = 0; l <= dof; l++) {
            const mca_link_critical_t *c = &ctrl->crit[a][l];
            if (!c->valid || c->d >= cfg->apf.d || l == 0) {
                continue;
            }
            double dir[3], Jp[3][MCA_MAX_DOF], qr[MCA_MAX_DOF];
            mca_v3_sub(dir, c->p, c->e); /* obstacle -> critical point */
            const double nrm = mca_v3_norm(dir);
            if (!(nrm > 1e-12)) {
                continue;
            }
            const double sp = mca_apf_rep_speed(&cfg->apf, c->d);
            double v_rep[3];
            for (int i = 0; i < 3; i++) {
                v_rep[i] = sp * dir[i] / nrm;
            }
            rc = mca_jacobian_point(&ctrl->kin[a], l, c->p, Jp);
            if (rc != MCA_OK) {
                return rc;
            }
            /* a link moved by few joints has a rank-deficient J_P: the damped pseudoinverse handles it */
            rc = mca_apf_pinv_apply(Jp, dof, fmax(cfg->apf.damping, 1e-6), v_rep, qr);
            if (rc != MCA_OK) {
                continue;
            }
            for (int j = 0; j < dof; j++) {
                qd[j] += qr[j];
            }
        }
        for (int j = 0; j < dof; j++) {
            /* respect the joint velocity limits as the QP's bounds would */
            const double vl = cfg->chain[a].joint[j].vel_limit;
            double v = qd[j];
            if (vl > 0.0) {
                v = fmax(-vl, fmin(vl, v));
            }
            qdot[a][j] = v;
            ctrl->phi[off + j] = v;
        }
        off += dof;
    }
    return MCA_OK;
}

int mca_controller_tick(mca_controller_t *ctrl, double t, const double *const q[MCA_MAX_ARMS],
                        double *const qdot[MCA_MAX_ARMS], mca_tick_info_t *info_out) {
    const int64_t t_enter = now_ns();
    if (!ctrl || !q || !qdot) {
        return MCA_EINVAL;
    }
    mca_tick_info_t scratch;
    mca_tick_info_t *info = info_out ? info_out : &scratch;
    const mca_controller_config_t *cfg = &ctrl->cfg;
    const int na = cfg->n_arms;
    info->t = t;
    info->n_arms = na;
    info->brake = 1.0;
    info->active_rows = 0;
    info->binding_rows = 0;
    info->pdnn_steps = 0;
    info->pdnn_exact_solves = 0;
    info->pdnn_residual = 0.0;
    info->pdnn_converged = 0;
    info->pdnn_budget_hit = MCA_BUDGET_NONE;
    info->eq_residual = 0.0;
    info->slack = 0.0;
    info->brake_fallback = 0;
    info->task_t = ctrl && ctrl->started ? t - ctrl->t_start : 0.0;
    info->min_distance = INFINITY;
    info->body_distance = info->body_margin = INFINITY;
    info->body_arm = info->body_link = info->body_index = info->body_kind = -1;
    for (int a = 0; a < MCA_MAX_ARMS; a++) {
        info->ee_error[a] = 0.0;
        info->path_error[a] = 0.0;
        for (int l = 0; l < MCA_MAX_LINKS; l++) {
            info->link_distance[a][l] = INFINITY;
        }
    }
    for (int a = 0; a < na; a++) {
        if (!q[a] || !qdot[a]) {
            zero_cmd(ctrl, qdot);
            raise_fault(ctrl, MCA_CTRL_FAULT_INPUT,
                        (mca_ctrl_fault_why_t){.why = MCA_WHY_NULL_JOINTS, .i = {a}});
            goto fault;
        }
    }
    if (ctrl->fault != MCA_CTRL_FAULT_NONE) {
        /* latched: command zero, but keep reporting the distances (the arms are still braking) */
        int ok = 1;
        for (int a = 0; a < na && ok; a++) {
            ok = mca_fk(&cfg->chain[a], q[a], &ctrl->kin[a]) == MCA_OK;
        }
        if (ok) {
            mca_ctrl__distances(ctrl, info);
        }
        goto fault;
    }

    /* 1. kinematics */
    for (int a = 0; a < na; a++) {
        if (mca_fk(&cfg->chain[a], q[a], &ctrl->kin[a]) != MCA_OK) {
            raise_fault(ctrl, MCA_CTRL_FAULT_NAN,
                        (mca_ctrl_fault_why_t){.why = MCA_WHY_NONFINITE_Q, .i = {a}});
            goto fault;
        }
    }
    if (!ctrl->started) {
        for (int a = 0; a < na; a++) {
            mca_path_anchor(&ctrl->cfg.path[a], ctrl->kin[a].ee);
        }
        ctrl->t_start = t;
        ctrl->started = 1;
    }
    info->task_t = t - ctrl->t_start;

    /* 2. desired paths (mca-ts: at each arm's path clock) */
    const int ts = cfg->scheme == MCA_SCHEME_MCA_TS;
    double r_d[MCA_MAX_ARMS][3], rdot_d[MCA_MAX_ARMS][3];
    for (int a = 0; a < na; a++) {
        mca_path_eval(&cfg->path[a], ts ? ctrl->tau[a] : info->task_t, r_d[a], rdot_d[a]);
        mca_v3_set(info->ee[a], ctrl->kin[a].ee);
        mca_v3_set(info->ee_desired[a], r_d[a]);
        info->ee_error[a] = mca_v3_dist(r_d[a], ctrl->kin[a].ee);
        info->path_error[a] = mca_path_distance(&cfg->path[a], ctrl->kin[a].ee);
        info->tube[a] = INFINITY;
        mca_ctrl__exact_check(ctrl, a, ts ? ctrl->tau[a] : info->task_t);
    }
    info->exact_met = ctrl->exact_met;
    info->exact_missed = ctrl->exact_missed;
    info->exact_error_max = ctrl->exact_error_max;

    /* 3. distances */
    if (mca_ctrl__distances(ctrl, info) != MCA_OK) {
        raise_fault(ctrl, MCA_CTRL_FAULT_NAN, (mca_ctrl_fault_why_t){.why = MCA_WHY_DISTANCES});
        goto fault;
    }
    const double d1 = cfg->sp.d1;
    if (cfg->fault_distance && info->min_distance < d1) {
        raise_fault(ctrl, MCA_CTRL_FAULT_DISTANCE, why_distance(MCA_WHY_BELOW_D1, info, d1));
        goto fault;
    }
    if (cfg->fault_distance && cfg->body_rows && info->body_margin < 0.0) {
        raise_fault(ctrl, MCA_CTRL_FAULT_DISTANCE, why_clearance(MCA_WHY_BELOW_CLEARANCE, info));
        goto fault;
    }
    if (cfg->fault_distance && cfg->self_rows && info->self_distance < d1) {
        raise_fault(ctrl, MCA_CTRL_FAULT_DISTANCE, why_self(MCA_WHY_SELF_BELOW_D1, info, d1));
        goto fault;
    }

    /* 4. scheme */
    if (cfg->scheme == MCA_SCHEME_APF) {
        if (apf_tick(ctrl, (const double(*)[3])r_d, (const double(*)[3])rdot_d, qdot) != MCA_OK) {
            raise_fault(ctrl, MCA_CTRL_FAULT_NAN, (mca_ctrl_fault_why_t){.why = MCA_WHY_APF_SINGULAR});
            goto fault;
        }
    } else {
        const mca_chain_t *chains[MCA_MAX_ARMS];
        for (int a = 0; a < na; a++) {
            chains[a] = &cfg->chain[a];
        }
        mca_scheme_info_t si;
        mca_scheme_params_t sp = cfg->sp;
        sp.collision = cfg->sp.collision && !ts; /* mca-ts builds its own rows (mca_scheme_near_rows) */
        int rc = mca_scheme_assemble(&sp, na, chains, ctrl->kin, q, (const double(*)[3])r_d,
                                     (const double(*)[3])rdot_d,
                                     (const mca_link_critical_t(*)[MCA_MAX_LINKS])ctrl->crit,
                                     ctrl->has_prev ? ctrl->phi_prev : NULL, &ctrl->sstate, &ctrl->qp, &si);
        if (rc == MCA_EINFEASIBLE) {
            raise_fault(ctrl, MCA_CTRL_FAULT_INFEASIBLE, (mca_ctrl_fault_why_t){.why = MCA_WHY_BOUNDS});
            goto fault;
        }
        if (rc != MCA_OK) {
            raise_fault(ctrl, MCA_CTRL_FAULT_INPUT,
                        (mca_ctrl_fault_why_t){.why = MCA_WHY_ASSEMBLY, .i = {rc}});
            goto fault;
        }
        if (sp.collision) {
            /* the paper's scheme: the fixed bodies' rows in their slots, no stop bound */
            rc = mca_body_rows(&ctrl->qp, &si, na, chains, ctrl->kin, cfg->body, mca_ctrl__row_bodies(cfg),
                               mca_ctrl__row_self(cfg), &sp, NULL, &ctrl->body_cache, ctrl->body_near);
            if (rc != MCA_OK) {
                raise_fault(ctrl, MCA_CTRL_FAULT_INPUT,
                            (mca_ctrl_fault_why_t){.why = MCA_WHY_ASSEMBLY, .i = {rc}});
                goto fault;
            }
            if (sp.body_pairs > 0) {
                /* a cell's body slots are mostly empty: only the active rows go to the PDNN, as under mca-ts
                 * (the same QP; the paper's tasks have no slots, so their QP stays the paper's, row for row)
                 */
                mca_ctrl__compact_rows(&ctrl->qp, sp.big, &si, &ctrl->pdnn, ctrl->row_key, &ctrl->n_row_key);
            }
        }
        info->brake = si.brake;
        int ts_off[MCA_MAX_ARMS] = {0};
        double target[MCA_MAX_ARMS], lo[MCA_MAX_ARMS], hi[MCA_MAX_ARMS]; /* mca-ts: the rates' plan */
        if (ts) {
            mca_ctrl__ts_plan(ctrl, info->task_t, target, lo, hi);
            mca_ctrl__accel_box(ctrl, &si,
                                na); /* first: the lists keep the pairs this box can bring to a bound */
            const mca_timescale_weights_t w = {cfg->ts.w_sigma, cfg->ts.w_slack, cfg->ts.w_path,
                                               cfg->ts.w_tube};
            double slack_lo[MCA_MAX_ARMS][3], slack_hi[MCA_MAX_ARMS][3];
            int mode[MCA_MAX_ARMS];
            for (int a = 0; a < na; a++) {
                mode[a] = !cfg->path[a].path_first ? MCA_TRACK_ELASTIC
                          : ctrl->giving_way[a]    ? MCA_TRACK_TUBE
                                                   : MCA_TRACK_PATH_FIRST;
                ctrl->track_mode[a] = mode[a];
                if (mode[a] == MCA_TRACK_ELASTIC) {
                    for (int i = 0; i < 3; i++) {
                        slack_lo[a][i] = -INFINITY;
                        slack_hi[a][i] = INFINITY;
                    }
                    continue;
                }
                double err[3];
                mca_v3_sub(err, r_d[a], ctrl->kin[a].ee);
                info->tube[a] = mca_path_tolerance(&cfg->path[a], ctrl->tau[a]);
                mca_scheme_tube_bounds(err, info->tube[a], cfg->sp.K, cfg->dt, slack_lo[a], slack_hi[a]);
                ctrl->at_tube_edge[a] = 0;
                for (int i = 0; i < 3; i++) {
                    ctrl->at_tube_edge[a] |= fabs(err[i]) >= MCA_TUBE_EDGE * info->tube[a] / sqrt(3.0);
                }
                mca_ctrl__tube_keep_brake(ctrl, &si, a, rdot_d[a], lo[a], hi[a], slack_lo[a], slack_hi[a]);
            }
            /* the path rates' columns before the rows: the rows are written at the QP's full width */
            rc = mca_scheme_add_timescale(&ctrl->qp, na, (const double(*)[3])rdot_d, target, lo, hi,
                                          (const double(*)[3])slack_lo, (const double(*)[3])slack_hi, &w,
                                          mode, ts_off, ctrl->ts_scale);
            if (rc != MCA_OK) {
                raise_fault(ctrl, MCA_CTRL_FAULT_INPUT,
                            (mca_ctrl_fault_why_t){.why = MCA_WHY_ASSEMBLY, .i = {rc}});
                goto fault;
            }
            mca_ctrl__near_links(ctrl, &ctrl->qp, &si, cfg->ts.dec_limit, cfg->ts.priority);
            rc = mca_scheme_near_rows(&ctrl->qp, &si, na, chains, ctrl->kin,
                                      (const mca_link_critical_t(*)[MCA_MAX_LINKS][MCA_NEAR_PAIRS])ctrl->near,
                                      &cfg->sp, cfg->ts.dec_limit, cfg->ts.priority);
            if (rc == MCA_OK) {
                rc = mca_body_rows(&ctrl->qp, &si, na, chains, ctrl->kin, cfg->body,
                                   mca_ctrl__row_bodies(cfg), mca_ctrl__row_self(cfg), &cfg->sp,
                                   cfg->ts.dec_limit, &ctrl->body_cache, ctrl->body_near);
            }
            if (rc != MCA_OK) {
                raise_fault(ctrl, MCA_CTRL_FAULT_INPUT,
                            (mca_ctrl_fault_why_t){.why = MCA_WHY_ASSEMBLY, .i = {rc}});
                goto fault;
            }
            info->brake = si.brake;
            mca_scheme_prune_rows(&ctrl->qp, cfg->sp.big, &si); /* rows the box cannot reach */
            mca_ctrl__compact_rows(&ctrl->qp, cfg->sp.big, &si, &ctrl->pdnn, ctrl->row_key, &ctrl->n_row_key);
        }
        info->active_rows = si.active_rows;
        mca_pdnn_result_t pr = {0};
        const mca_pdnn_params_t prm = mca_ctrl__pdnn_params(cfg, t_enter);
        rc = mca_pdnn_solve(&ctrl->pdnn, &ctrl->qp, &prm, ctrl->phi, &pr);
        info->pdnn_steps = pr.steps;
        info->pdnn_exact_solves = pr.polish_tries;
        info->pdnn_residual = pr.residual;
        info->pdnn_converged = pr.converged;
        if (rc == MCA_EINVAL) {
            raise_fault(ctrl, MCA_CTRL_FAULT_NAN, (mca_ctrl_fault_why_t){.why = MCA_WHY_PDNN_INPUT});
            goto fault;
        }
        /* out of budget (time or steps) before the cap: no fault by itself, a repaired answer below */
        const int hit = mca_ctrl__budget_hit(cfg, rc, &pr);
        info->pdnn_budget_hit = hit;
        const int short_answer = rc != MCA_OK && !(pr.residual <= cfg->fault_residual);
        const mca_qp_t *qp = &ctrl->qp;
        for (int j = 0; j < qp->n; j++) {
            if (!isfinite(ctrl->phi[j])) {
                raise_fault(ctrl, MCA_CTRL_FAULT_NAN, (mca_ctrl_fault_why_t){.why = MCA_WHY_PDNN_OUTPUT});
                goto fault;
            }
        }
        double eq = 0.0;
        for (int i = 0; i < qp->n_eq; i++) {
            double s = -qp->alpha[i];
            for (int j = 0; j < qp->n; j++) {
                s += qp->G[i][j] * ctrl->phi[j];
            }
            eq = fmax(eq, fabs(s));
        }
        info->eq_residual = eq;
        if (ts) {
            /* Tracking is elastic here, so only the hard rows decide: an answer that misses the PDNN's
             * tolerance is still used when it keeps every collision row (the box holds by projection). */
            if (short_answer) {
                mca_ctrl__repair_capped(ctrl, &si, na, ts_off,
                                        target); /* at the cap and at the budget alike */
            }
            mca_ctrl__ts_advance(ctrl, info, ts_off, (const double(*)[3])rdot_d, target, lo, hi);
        } else if (short_answer && hit != MCA_BUDGET_NONE && !(eq > cfg->eq_tol) &&
                   mca_ctrl__repair_scaled(ctrl) >= 0.0) {
            /* mca out of budget: the scaled iterate unless the equality residual says the QP is infeasible
             * as at the cap; at the cap itself the paper's faults below (its figures do not move) */
        } else if (short_answer) {
            /* an infeasible QP (tracking against avoidance) never converges: name it as the paper does */
            if (eq > cfg->eq_tol) {
                raise_fault(ctrl, MCA_CTRL_FAULT_FAKE_ATTRACTOR,
                            (mca_ctrl_fault_why_t){.why = MCA_WHY_TRACKING,
                                                   .i = {pr.steps},
                                                   .x = {pr.residual, eq, info->min_distance}});
            } else {
                raise_fault(ctrl, MCA_CTRL_FAULT_NOT_CONVERGED,
                            (mca_ctrl_fault_why_t){.why = MCA_WHY_NOT_CONVERGED,
                                                   .i = {pr.steps},
                                                   .x = {pr.residual, cfg->fault_residual}});
            }
            goto fault;
        }
        if (!ts && eq > cfg->eq_tol) { /* a repaired mca answer had eq <= eq_tol */
            raise_fault(ctrl, MCA_CTRL_FAULT_FAKE_ATTRACTOR,
                        (mca_ctrl_fault_why_t){.why = MCA_WHY_EQ_RESIDUAL, .x = {eq, cfg->eq_tol}});
            goto fault;
        }
        for (int i = 0; i < qp->n_ineq; i++) {
            if (qp->beta[i] < cfg->sp.big) {
                double s = 0.0;
                for (int j = 0; j < qp->n; j++) {
                    s += qp->U[i][j] * ctrl->phi[j];
                }
                info->binding_rows += s >= qp->beta[i] - 1e-9;
            }
        }
        int off = 0;
        for (int a = 0; a < na; a++) {
            for (int j = 0; j < cfg->chain[a].dof; j++) {
                qdot[a][j] = ctrl->phi[off + j];
            }
            off += cfg->chain[a].dof;
        }
    }

    /* 5. the distance must not cross d1 before the next tick: linear prediction from the last two ticks */
    if (cfg->fault_distance && ctrl->has_prev && isfinite(info->min_distance) &&
        isfinite(ctrl->min_distance_prev)) {
        const double pred = 2.0 * info->min_distance - ctrl->min_distance_prev;
        if (pred < d1) {
            raise_fault(ctrl, MCA_CTRL_FAULT_DISTANCE, why_distance(MCA_WHY_BELOW_D1_NEXT, info, d1));
            goto fault;
        }
    }
    if (cfg->fault_distance && cfg->body_rows && ctrl->has_prev && isfinite(info->body_margin) &&
        isfinite(ctrl->body_margin_prev) && 2.0 * info->body_margin - ctrl->body_margin_prev < 0.0) {
        raise_fault(ctrl, MCA_CTRL_FAULT_DISTANCE, why_clearance(MCA_WHY_BELOW_CLEARANCE_NEXT, info));
        goto fault;
    }
    if (cfg->fault_distance && cfg->self_rows && ctrl->has_prev && isfinite(info->self_distance) &&
        isfinite(ctrl->self_distance_prev) && 2.0 * info->self_distance - ctrl->self_distance_prev < d1) {
        raise_fault(ctrl, MCA_CTRL_FAULT_DISTANCE, why_self(MCA_WHY_SELF_BELOW_D1_NEXT, info, d1));
        goto fault;
    }
    memcpy(ctrl->phi_prev, ctrl->phi, sizeof ctrl->phi_prev);
    ctrl->min_distance_prev = info->min_distance;
    ctrl->body_margin_prev = info->body_margin;
    ctrl->self_distance_prev = info->self_distance;
    ctrl->has_prev = 1;
    ctrl->ticks++;
    info->fault = MCA_CTRL_FAULT_NONE;
    info->fault_why = (mca_ctrl_fault_why_t){0};
    mca_ctrl__fill_path_info(ctrl, info);
    for (int a = 0; a < na; a++) {
        /* streamed references move at the rate the tick chose (the commanded motion follows them) */
        mca_path_stream_advance(&ctrl->cfg.path[a], ctrl->sigma[a], cfg->dt);
    }
    ctrl->has_v_meas = 0;
    info->compute_ns = now_ns() - t_enter;
    return MCA_OK;

fault:
    zero_cmd(ctrl, qdot);
    memset(ctrl->phi, 0, sizeof ctrl->phi);
    memset(ctrl->phi_prev, 0, sizeof ctrl->phi_prev);
    ctrl->pdnn.h = 0;
    ctrl->ticks++;
    info->fault = ctrl->fault;
    info->fault_why = ctrl->fault_why;
    if (ctrl->started) {
        mca_ctrl__fill_path_info(ctrl, info);
    }
    ctrl->has_v_meas = 0;
    info->compute_ns = now_ns() - t_enter;
    return MCA_EFAULT;
}
