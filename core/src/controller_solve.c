/* SPDX-License-Identifier: MIT */
/* The solve's budget, the repair of a short answer and the compact row layout (see controller__solve.h). */
#include <math.h>
#include <string.h>

#include "mca/controller.h"
#include "mca/err.h"

#include "controller__solve.h"

/* The largest lambda in [0, 1] for which arm a's joint velocities x0 + lambda dir keep every collision row
 * (-1 when x0 itself breaks one). */
static double rows_lambda(const mca_qp_t *qp, const mca_scheme_info_t *si, int a, int dof, const double *x0,
                          const double *dir, double big) {
    const int vo = si->var_off[a];
    double lambda = 1.0;
    const int end = a + 1 < MCA_MAX_ARMS ? si->row_off[a + 1] : qp->n_ineq;
    for (int i = si->row_off[a]; i < end; i++) {
        if (!(qp->beta[i] < big)) {
            continue;
        }
        double s0 = 0.0, sd = 0.0;
        for (int j = 0; j < dof; j++) {
            s0 += qp->U[i][vo + j] * x0[j];
            sd += qp->U[i][vo + j] * dir[j];
        }
        if (s0 > qp->beta[i] + 1e-12) {
            return -1.0;
        }
        if (sd > 0.0) {
            lambda = fmin(lambda, (qp->beta[i] - s0) / sd);
        }
    }
    return fmax(lambda, 0.0);
}

/* mca-ts, an answer that missed the PDNN's tolerance (its iterate lies in the joint box by projection):
 * per arm, the point nearest the iterate on the way from the box centre c (the velocity the arm has now)
 * that keeps every collision row, a command the arm can follow. When c itself breaks a row, the arm slows
 * down along its present direction as fast as its deceleration allows (the smallest uniform factor it can
 * follow in one tick, as the braking fallback). Scaling the iterate into the rows instead leaves the
 * acceleration box: with rate-limited arms the sweep had twice the runs below d1 that way (17 against 8 of
 * 196 tasks), with arms that follow any command fewer. Tracking, elastic, gives. An arm with a path tube
 * takes no step towards the unfinished iterate: one keep-direction braking step with the path rate that fits
 * it (mca_ctrl__tube_keep_brake; the tube admits it), so it stops on its path instead of drifting off it. */
void mca_ctrl__repair_capped(mca_controller_t *ctrl, const mca_scheme_info_t *si, int na, const int ts_off[],
                             const double target[]) {
    const mca_controller_config_t *cfg = &ctrl->cfg;
    const mca_qp_t *qp = &ctrl->qp;
    for (int a = 0; a < na; a++) {
        const int vo = si->var_off[a], dof = cfg->chain[a].dof;
        if (ctrl->track_mode[a] != MCA_TRACK_ELASTIC) {
            memcpy(&ctrl->phi[vo], ctrl->keep_q[a], sizeof(double) * (size_t)dof);
            ctrl->phi[ts_off[a]] = ctrl->ts_scale[a] * (ctrl->keep_sigma[a] - target[a]);
            continue;
        }
        double c[MCA_MAX_DOF], dir[MCA_MAX_DOF];
        for (int j = 0; j < dof; j++) {
            c[j] = fmax(qp->lb[vo + j], fmin(qp->ub[vo + j], ctrl->box_center[vo + j]));
            dir[j] = ctrl->phi[vo + j] - c[j];
        }
        double lambda = rows_lambda(qp, si, a, dof, c, dir, cfg->sp.big);
        /* and inside the box: a capped PDNN's phi may lie outside it (the network's iterate is not
         * projected), and the rows mca_scheme_prune_rows dropped hold only inside it */
        for (int j = 0; j < dof && lambda > 0.0; j++) {
            const double lo = qp->lb[vo + j], hi = qp->ub[vo + j];
            if (c[j] + lambda * dir[j] > hi) {
                lambda = dir[j] > 0.0 ? fmax(0.0, (hi - c[j]) / dir[j]) : lambda;
            } else if (c[j] + lambda * dir[j] < lo) {
                lambda = dir[j] < 0.0 ? fmax(0.0, (lo - c[j]) / dir[j]) : lambda;
            }
        }
        if (lambda >= 0.0) {
            for (int j = 0; j < dof; j++) {
                ctrl->phi[vo + j] = c[j] + lambda * dir[j];
            }
            continue;
        }
        double dec[MCA_MAX_DOF];
        for (int j = 0; j < dof; j++) {
            dec[j] = cfg->ts.dec_limit[a];
        }
        mca_brake_scale_arm(&ctrl->box_center[vo], dec, cfg->dt, dof, &ctrl->phi[vo]);
    }
}

/* mca, an answer stopped by its budget (not its cap): the iterate scaled by the largest lambda in [0, 1] for
 * which lambda phi keeps every collision row and the joint box. 0 keeps the rows (every mca bound is >= 0)
 * and the box wherever the box holds 0 (a joint inside its limits). The arms slow down along the
 * direction the solver was heading; tracking is given up for the tick, never a row. Returns lambda, or -1
 * when no lambda in [0, 1] keeps them all (the caller faults as at the cap). */
double mca_ctrl__repair_scaled(mca_controller_t *ctrl) {
    const mca_qp_t *qp = &ctrl->qp;
    const double big = ctrl->cfg.sp.big;
    double lo = 0.0, hi = 1.0;
    for (int i = 0; i < qp->n_ineq; i++) {
        if (!(qp->beta[i] < big)) {
            continue;
        }
        double s = 0.0;
        for (int j = 0; j < qp->n; j++) {
            s += qp->U[i][j] * ctrl->phi[j];
        }
        if (s > 0.0) {
            hi = fmin(hi, qp->beta[i] / s);
        } else if (s < 0.0) {
            lo = fmax(lo, qp->beta[i] / s);
        } else if (qp->beta[i] < 0.0) {
            return -1.0;
        }
    }
    for (int j = 0; j < qp->n; j++) {
        const double p = ctrl->phi[j];
        if (p > 0.0) {
            hi = fmin(hi, qp->ub[j] / p);
            lo = fmax(lo, qp->lb[j] / p);
        } else if (p < 0.0) {
            hi = fmin(hi, qp->lb[j] / p);
            lo = fmax(lo, qp->ub[j] / p);
        } else if (qp->lb[j] > 0.0 || qp->ub[j] < 0.0) {
            return -1.0;
        }
    }
    if (!(lo <= hi)) {
        return -1.0;
    }
    for (int j = 0; j < qp->n; j++) {
        ctrl->phi[j] *= hi;
    }
    return hi;
}

int mca_pdnn_budget_steps(int64_t budget_ns) {
    if (budget_ns <= 0) {
        return 0;
    }
    const int64_t k = budget_ns / MCA_PDNN_STEP_NS;
    return k < 1 ? 1 : k > 1000000000 ? 1000000000 : (int)k;
}

/* The step budget that applies below the step cap (0: none). Not under the paper's scheme mca: its cap is its
 * step limit, so its figures (the negative task's fault at its cap) stay as published; the wall clock still
 * bounds it in mcad. With the budget at 714 steps the negative task's fault moved by a tick (a repaired
 * budget tick first) and three arms' changed kind and time. */
int mca_controller_step_budget(const mca_controller_config_t *cfg) {
    const int steps = cfg->pdnn_budget_steps;
    return cfg->scheme != MCA_SCHEME_MCA && steps > 0 && steps < cfg->pdnn.max_steps ? steps : 0;
}

/* The solver's parameters for a solve in the tick that began at t_enter: the step cap or the step budget,
 * the smaller, and with a time budget the deadline (mcad's rt.pdnn_budget_us). */
mca_pdnn_params_t mca_ctrl__pdnn_params(const mca_controller_config_t *cfg, int64_t t_enter) {
    mca_pdnn_params_t prm = cfg->pdnn;
    if (mca_controller_step_budget(cfg) > 0) {
        prm.max_steps = mca_controller_step_budget(cfg);
    }
    prm.deadline_ns = cfg->pdnn_budget_ns > 0 ? t_enter + cfg->pdnn_budget_ns : 0;
    return prm;
}

/* Whether a solve that did not converge stopped at the budget (time, or steps below the cap) rather than at
 * its cap or for lack of progress. */
int mca_ctrl__budget_hit(const mca_controller_config_t *cfg, int rc, const mca_pdnn_result_t *pr) {
    if (rc == MCA_ETIMEDOUT) {
        return MCA_BUDGET_TIME;
    }
    const int steps = mca_controller_step_budget(cfg);
    return rc == MCA_ENOTCONV && steps > 0 && pr->steps >= steps ? MCA_BUDGET_STEPS : MCA_BUDGET_NONE;
}

/* mca-ts and braking: only the active rows go to the PDNN (mca_scheme_compact_rows); each keeps its
 * slot of the full layout (arm, link, list entry) in @p key, and its dual from the last solve where that
 * slot was active then too. */
void mca_ctrl__compact_rows(mca_qp_t *qp, double big, mca_scheme_info_t *si, mca_pdnn_t *pdnn, int *key,
                            int *n_key) {
    int src[MCA_QP_MAX_INEQ], pos[MCA_QP_MAX_INEQ], old_of_new[MCA_QP_MAX_INEQ];
    const int n_slots = qp->n_ineq;
    for (int k = 0; k < n_slots; k++) {
        pos[k] = -1;
    }
    for (int i = 0; i < *n_key; i++) {
        if (key[i] >= 0 && key[i] < n_slots) {
            pos[key[i]] = i;
        }
    }
    const int n = mca_scheme_compact_rows(qp, big, si, src);
    for (int i = 0; i < n; i++) {
        old_of_new[i] = pos[src[i]];
        key[i] = src[i];
    }
    *n_key = n;
    mca_pdnn_remap_ineq(pdnn, n, old_of_new);
}
