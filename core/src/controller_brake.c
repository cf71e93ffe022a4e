/* SPDX-License-Identifier: MIT */
/* Braking: the braking QP and its keep-direction fallback (mca_controller_brake); see mca/controller.h. */
#include "mca/controller.h"

#include <math.h>

#include "mca/err.h"

#include "controller__common.h"
#include "controller__dist.h"
#include "controller__solve.h"

/* Braking fallback: every arm's whole velocity vector scaled by one factor, the largest that keeps each
 * joint's change within dec dt, so the arm keeps its direction of motion while it slows. */
void mca_brake_scale_arm(const double *v, const double *dec, double dt, int dof, double *out) {
    double f = 0.0;
    int finite = 1;
    for (int j = 0; j < dof; j++) {
        const double s = fabs(v[j]);
        if (!isfinite(s)) {
            finite = 0;
        } else if (s > 0.0 && dec[j] > 0.0) {
            f = fmax(f, 1.0 - dec[j] * dt / s); /* joint j changes by (1 - f) |v_j| <= dec_j dt */
        }
    }
    for (int j = 0; j < dof; j++) {
        out[j] = finite ? f * v[j] : 0.0;
    }
}

/* The braking QP: min 1/2 |qdot|^2 s.t. the deceleration box around v_last, the joint bounds and one
 * normal-form collision row per link (approach speed <= S(d) v_normal, and <= the stoppability bound
 * under mca-ts). No equality: the task is over. @retval MCA_OK with qdot written, or an error (no answer). */
static int brake_qp(mca_controller_t *ctrl, const double *const q[MCA_MAX_ARMS],
                    const double *const v_last[MCA_MAX_ARMS], const double *const dec[MCA_MAX_ARMS],
                    double *const qdot[MCA_MAX_ARMS], mca_tick_info_t *info, int64_t t_enter) {
    const mca_controller_config_t *cfg = &ctrl->cfg;
    const int na = cfg->n_arms;
    const double dt = cfg->dt;
    mca_scheme_params_t sp = cfg->sp;
    sp.collision = 0; /* the rows: mca_scheme_near_rows below */
    const mca_chain_t *chains[MCA_MAX_ARMS];
    double r_d[MCA_MAX_ARMS][3] = {{0}}, rdot_d[MCA_MAX_ARMS][3] = {{0}};
    for (int a = 0; a < na; a++) {
        chains[a] = &cfg->chain[a];
    }
    mca_scheme_state_t st; /* the normal form keeps no memory */
    mca_scheme_info_t si;
    mca_qp_t *qp = &ctrl->brake_qp;
    int rc = mca_scheme_assemble(&sp, na, chains, ctrl->kin, q, (const double(*)[3])r_d,
                                 (const double(*)[3])rdot_d,
                                 (const mca_link_critical_t(*)[MCA_MAX_LINKS])ctrl->crit, NULL, &st, qp, &si);
    if (rc != MCA_OK) {
        return rc;
    }
    qp->n_eq = 0;
    for (int a = 0; a < na; a++) {
        for (int j = 0; j < cfg->chain[a].dof; j++) {
            const int k = si.var_off[a] + j;
            const double v = v_last[a][j], step = dec[a][j] * dt;
            if (!isfinite(v) || !(step > 0.0)) {
                return MCA_EINVAL;
            }
            qp->lb[k] = fmax(qp->lb[k], v - step);
            qp->ub[k] = fmin(qp->ub[k], v + step);
            if (!(qp->lb[k] <= qp->ub[k])) {
                return MCA_EINFEASIBLE; /* a joint is carried past its limit band faster than it can stop */
            }
        }
    }
    /* every scheme brakes with the near rows (the pairs this box can bring to a bound); the stop bound and
     * priorities are mca-ts's */
    const int ts = cfg->scheme == MCA_SCHEME_MCA_TS;
    const double *row_dec = ts ? cfg->ts.dec_limit : NULL, *row_priority = ts ? cfg->ts.priority : NULL;
    mca_ctrl__near_links(ctrl, qp, &si, row_dec, row_priority);
    rc = mca_scheme_near_rows(qp, &si, na, chains, ctrl->kin,
                              (const mca_link_critical_t(*)[MCA_MAX_LINKS][MCA_NEAR_PAIRS])ctrl->near, &sp,
                              row_dec, row_priority);
    if (rc == MCA_OK) {
        /* and the fixed bodies' (the stop bound is mca-ts's, as the arms') */
        rc = mca_body_rows(qp, &si, na, chains, ctrl->kin, cfg->body, mca_ctrl__row_bodies(cfg),
                           mca_ctrl__row_self(cfg), &sp, row_dec, &ctrl->body_cache, ctrl->body_near);
    }
    if (rc != MCA_OK) {
        return rc;
    }
    mca_scheme_prune_rows(qp, sp.big, &si); /* rows the deceleration box cannot reach */
    mca_ctrl__compact_rows(qp, sp.big, &si, &ctrl->brake_pdnn, ctrl->brake_row_key, &ctrl->n_brake_row_key);
    mca_pdnn_result_t pr = {0};
    double phi[MCA_QP_MAX_VARS];
    const mca_pdnn_params_t prm =
        mca_ctrl__pdnn_params(cfg, t_enter); /* out of time: the keep-direction fallback */
    rc = mca_pdnn_solve(&ctrl->brake_pdnn, qp, &prm, phi, &pr);
    info->pdnn_steps = pr.steps;
    info->pdnn_exact_solves = pr.polish_tries;
    info->pdnn_residual = pr.residual;
    info->pdnn_converged = pr.converged;
    if (rc == MCA_EINVAL || (rc != MCA_OK && !(pr.residual <= cfg->fault_residual))) {
        return rc == MCA_OK ? MCA_ENOTCONV : rc;
    }
    for (int i = 0; i < qp->n_ineq; i++) {
        double s = 0.0;
        for (int j = 0; j < qp->n; j++) {
            s += qp->U[i][j] * phi[j];
        }
        if (!(s <= qp->beta[i] + 1e-6)) {
            return MCA_ENOTCONV;
        }
    }
    for (int a = 0; a < na; a++) {
        for (int j = 0; j < cfg->chain[a].dof; j++) {
            const int k = si.var_off[a] + j;
            /* the PDNN's answer lies in the box up to rounding; clamp so the dec limit holds exactly */
            qdot[a][j] = fmax(qp->lb[k], fmin(qp->ub[k], phi[k]));
        }
    }
    return MCA_OK;
}

int mca_controller_brake(mca_controller_t *ctrl, double t, const double *const q[MCA_MAX_ARMS],
                         const double *const v_last[MCA_MAX_ARMS],
                         const double *const dec_limit[MCA_MAX_ARMS], double *const qdot[MCA_MAX_ARMS],
                         mca_tick_info_t *info) {
    const int64_t t_enter = now_ns();
    if (!ctrl || !q || !v_last || !dec_limit || !qdot || !info) {
        return MCA_EINVAL;
    }
    for (int a = 0; a < ctrl->cfg.n_arms; a++) {
        if (!v_last[a] || !dec_limit[a] || !qdot[a]) {
            return MCA_EINVAL;
        }
    }
    const int rc = mca_controller_observe(ctrl, t, q, info);
    info->brake_fallback = 0;
    if (rc != MCA_OK || brake_qp(ctrl, q, v_last, dec_limit, qdot, info, t_enter) != MCA_OK) {
        /* no distances or no QP answer: keep each arm's direction, slow it as fast as allowed */
        for (int a = 0; a < ctrl->cfg.n_arms; a++) {
            mca_brake_scale_arm(v_last[a], dec_limit[a], ctrl->cfg.dt, ctrl->cfg.chain[a].dof, qdot[a]);
        }
        info->brake_fallback = 1;
        ctrl->brake_pdnn.h = 0;
    }
    int at_rest = 1;
    for (int a = 0; a < ctrl->cfg.n_arms; a++) {
        for (int j = 0; j < ctrl->cfg.chain[a].dof; j++) {
            /* the PDNN's tolerance leaves ~1e-9 where zero is meant: zero when zero is inside the box */
            if (fabs(qdot[a][j]) <= 1e-6 && fabs(v_last[a][j]) <= dec_limit[a][j] * ctrl->cfg.dt) {
                qdot[a][j] = 0.0;
            } else {
                at_rest = 0;
            }
        }
    }
    info->compute_ns = now_ns() - t_enter;
    return at_rest;
}
