/* SPDX-License-Identifier: MIT */
/* QP assembly of the MCA scheme, paper (19)-(28); see mca/scheme.h and docs/scheme.md. */
#include "mca/scheme.h"

#include <math.h>
#include <string.h>

#include "mca/err.h"
#include "mca/vec3.h"
#include "scheme__rows.h"

void mca_scheme_default_params(mca_scheme_params_t *p) {
    memset(p, 0, sizeof *p);
    p->collision = 1;
    p->form = MCA_FORM_NORMAL;
    p->d1 = 0.05;
    p->d2 = 0.12;
    p->K = 20.0;
    p->epsilon = 5.0;
    p->v_normal = 0.5;
    p->v_floor = 0.0;
    p->big = 1e6;
}

double mca_brake_s(double d, double d1, double d2) {
    if (d >= d2) {
        return 1.0;
    }
    if (d <= d1) {
        return 0.0;
    }
    const double s = sin(0.5 * M_PI * (d - d1) / (d2 - d1));
    return s * s;
}

void mca_diamond_rows(const double r[3], const double J[3][MCA_MAX_DOF], int dof,
                      double rows[3][MCA_MAX_DOF]) {
    for (int i = 0; i < 3; i++) {
        for (int j = 0; j < MCA_MAX_DOF; j++) {
            rows[i][j] = j < dof ? r[i] * J[i][j] : 0.0;
        }
    }
}

int mca_joint_bounds(const mca_chain_t *chain, const double *q, double epsilon, double *lb, double *ub) {
    if (!chain || !q || !lb || !ub || !(epsilon > 0.0)) {
        return MCA_EINVAL;
    }
    int rc = MCA_OK;
    for (int j = 0; j < chain->dof; j++) {
        const mca_joint_model_t *jm = &chain->joint[j];
        if (!isfinite(q[j])) {
            return MCA_EINVAL;
        }
        double lo = -jm->vel_limit;
        double hi = jm->vel_limit;
        if (!jm->continuous) {
            lo = fmax(lo, epsilon * (jm->lower - q[j]));
            hi = fmin(hi, epsilon * (jm->upper - q[j]));
        }
        lb[j] = lo;
        ub[j] = hi;
        if (lo > hi) {
            rc = MCA_EINFEASIBLE;
        }
    }
    return rc;
}

void mca_scheme_state_reset(mca_scheme_state_t *st) {
    memset(st, 0, sizeof *st);
}

int mca_scheme_rows_per_link(const mca_scheme_params_t *p) {
    if (!p->collision) {
        return 0;
    }
    return p->form == MCA_FORM_COMPONENTWISE ? 3 : 1;
}

/* Joint velocity of arm a from phi (NULL phi = 0). */
static double phi_at(const double *phi, int off, int j) {
    return phi ? phi[off + j] : 0.0;
}

int mca_scheme_assemble(const mca_scheme_params_t *p, int n_arms, const mca_chain_t *const chain[],
                        const mca_kin_t kin[], const double *const q[], const double r_d[][3],
                        const double rdot_d[][3], const mca_link_critical_t crit[][MCA_MAX_LINKS],
                        const double *phi_prev, mca_scheme_state_t *st, mca_qp_t *qp,
                        mca_scheme_info_t *info) {
    if (!p || !chain || !kin || !q || !r_d || !rdot_d || !st || !qp || n_arms < 1 || n_arms > MCA_MAX_ARMS ||
        (p->collision && !crit)) {
        return MCA_EINVAL;
    }
    const int rpl = mca_scheme_rows_per_link(p);
    int var_off[MCA_MAX_ARMS], row_off[MCA_MAX_ARMS];
    int n = 0, n_ineq = 0;
    for (int a = 0; a < n_arms; a++) {
        if (!chain[a] || !q[a] || chain[a]->dof < 1 || chain[a]->dof > MCA_MAX_DOF) {
            return MCA_EINVAL;
        }
        var_off[a] = n;
        row_off[a] = n_ineq;
        n += chain[a]->dof;
        n_ineq += (rpl + (rpl ? p->body_pairs : 0)) * (chain[a]->dof + 1);
    }
    int rc = mca_qp_reset(qp, n, MCA_TASK_DIM * n_arms, n_ineq);
    if (rc != MCA_OK) {
        return rc;
    }
    int bounds_rc = MCA_OK;
    int active = 0;
    double brake = 1.0;
    for (int a = 0; a < n_arms; a++) {
        const mca_chain_t *ch = chain[a];
        const mca_kin_t *kn = &kin[a];
        const int dof = ch->dof, vo = var_off[a];
        double J[3][MCA_MAX_DOF];
        /* (22): J qdot = rdot_d + K (r_d - r); the feedback term stops Euler drift accumulating. */
        rc = mca_jacobian_ee(kn, J);
        if (rc != MCA_OK) {
            return rc;
        }
        for (int i = 0; i < 3; i++) {
            for (int j = 0; j < dof; j++) {
                qp->G[3 * a + i][vo + j] = J[i][j];
            }
            qp->alpha[3 * a + i] = rdot_d[a][i] + p->K * (r_d[a][i] - kn->ee[i]);
        }
        /* (19)-(20) */
        rc = mca_joint_bounds(ch, q[a], p->epsilon, &qp->lb[vo], &qp->ub[vo]);
        if (rc == MCA_EINVAL) {
            return rc;
        }
        if (rc != MCA_OK) {
            bounds_rc = rc;
        }
        if (!rpl) {
            continue;
        }
        for (int k = row_off[a] + rpl * (dof + 1); k < row_off[a] + (rpl + p->body_pairs) * (dof + 1); k++) {
            qp->beta[k] = p->big; /* the fixed bodies' slots (mca_body_rows), inactive until filled */
        }
        /* (10)-(14)/(28): one fixed block of rows per link. */
        for (int l = 0; l <= dof; l++) {
            const int r0 = row_off[a] + rpl * l;
            const mca_link_critical_t *c = &crit[a][l];
            for (int k = 0; k < rpl; k++) {
                qp->beta[r0 + k] = p->big; /* U rows already zero: inactive */
            }
            if (!c->valid || c->d >= p->d2) {
                st->in_band[a][l] = 0;
                continue;
            }
            if (l > 0 && crit[a][l - 1].valid && crit[a][l - 1].d < p->d2 &&
                mca_v3_dist(crit[a][l - 1].p, c->p) < 1e-12 && mca_v3_dist(crit[a][l - 1].e, c->e) < 1e-12) {
                /* same critical pair as the previous link (a zero-length link next to its neighbour):
                 * a duplicate row adds nothing and makes the QP degenerate */
                st->in_band[a][l] = 0;
                continue;
            }
            const double s = mca_brake_s(c->d, p->d1, p->d2);
            brake = fmin(brake, s);
            double Jp[3][MCA_MAX_DOF];
            rc = mca_jacobian_point(kn, l, c->p, Jp);
            if (rc != MCA_OK) {
                return rc;
            }
            double r_pe[3];
            mca_v3_sub(r_pe, c->e, c->p);
            if (p->form == MCA_FORM_NORMAL) {
                const double nrm = mca_v3_norm(r_pe);
                if (!(nrm > 1e-12)) {
                    continue; /* axes touch: no direction; the distance fault handles it */
                }
                for (int j = 0; j < dof; j++) {
                    qp->U[r0][vo + j] = (r_pe[0] * Jp[0][j] + r_pe[1] * Jp[1][j] + r_pe[2] * Jp[2][j]) / nrm;
                }
                qp->beta[r0] = s * p->v_normal;
                active++;
            } else {
                double rows[3][MCA_MAX_DOF];
                mca_diamond_rows(r_pe, Jp, dof, rows);
                if (!st->in_band[a][l]) {
                    /* (12): the approach rate when the link enters the band (d falls below d2), from the
                     * previous tick's velocity, kept while the link stays inside. */
                    for (int i = 0; i < 3; i++) {
                        double v = 0.0;
                        for (int j = 0; j < dof; j++) {
                            v += rows[i][j] * phi_at(phi_prev, vo, j);
                        }
                        st->captured[a][l][i] = fmax(v, 0.0);
                    }
                    st->in_band[a][l] = 1;
                }
                const double rn = mca_v3_norm(r_pe);
                for (int i = 0; i < 3; i++) {
                    if (!(fabs(r_pe[i]) > 1e-6 * rn)) {
                        continue; /* no extent along this axis: a zero row, left inactive */
                    }
                    for (int j = 0; j < dof; j++) {
                        qp->U[r0 + i][vo + j] = rows[i][j];
                    }
                    const double floor = p->v_floor * fabs(r_pe[i]);
                    qp->beta[r0 + i] = s * fmax(st->captured[a][l][i], floor);
                    active++;
                }
            }
        }
    }
    if (info) {
        info->active_rows = active;
        info->brake = brake;
        info->rows_per_link = rpl;
        for (int a = 0; a < MCA_MAX_ARMS; a++) {
            info->var_off[a] = a < n_arms ? var_off[a] : n;
            info->row_off[a] = a < n_arms ? row_off[a] : n_ineq;
            info->body_off[a] = a < n_arms && rpl ? row_off[a] + rpl * (chain[a]->dof + 1) : info->row_off[a];
        }
    }
    return bounds_rc;
}

/* Same critical pair (P and E) as any row of the previous link: a duplicate row adds nothing and makes the
 * QP degenerate. */
static int repeats_previous(const mca_link_critical_t near[][MCA_NEAR_PAIRS], int l,
                            const mca_link_critical_t *c) {
    if (l == 0) {
        return 0;
    }
    for (int k = 0; k < MCA_NEAR_PAIRS; k++) {
        const mca_link_critical_t *o = &near[l - 1][k];
        if (o->valid && mca_v3_dist(o->p, c->p) < 1e-12 && mca_v3_dist(o->e, c->e) < 1e-12) {
            return 1;
        }
    }
    return 0;
}

/* Two rows of one arm whose unit normals differ by less than this are one row: parallel to 1e-7 they made
 * the active set degenerate, and the PDNN met its residual 1e-9 some 1e-5 away from the optimum (OSQP gave
 * up on them). Keeping the tighter of the two misses the other by at most this times the arm's speed. */
#define MCA_ROW_PARALLEL 1e-3

/* Row r of arm a (columns vo..vo+dof-1) against the rows kept before it: when one of them is parallel to
 * it, the tighter bound of the two stays in the kept row and 1 is returned (row r is to be dropped). */
int mca__scheme_merge_parallel(mca_qp_t *qp, int vo, int dof, int r, const int *kept, double *kept_norm,
                               int n_kept) {
    double nr = 0.0;
    for (int j = 0; j < dof; j++) {
        nr += qp->U[r][vo + j] * qp->U[r][vo + j];
    }
    nr = sqrt(nr);
    kept_norm[n_kept] = nr;
    if (!(nr > 0.0)) {
        return 0;
    }
    for (int k = 0; k < n_kept; k++) {
        const int o = kept[k];
        const double no = kept_norm[k];
        double dot = 0.0;
        for (int j = 0; j < dof; j++) {
            dot += qp->U[r][vo + j] * qp->U[o][vo + j];
        }
        /* |u/|u| - v/|v||^2 = 2 - 2 cos */
        if (!(2.0 - 2.0 * dot / (nr * no) < MCA_ROW_PARALLEL * MCA_ROW_PARALLEL)) {
            continue;
        }
        if (qp->beta[r] / nr < qp->beta[o] / no) {
            for (int j = 0; j < dof; j++) {
                qp->U[o][vo + j] = qp->U[r][vo + j];
            }
            qp->beta[o] = qp->beta[r];
            kept_norm[k] = nr;
        }
        return 1;
    }
    return 0;
}

double mca_scheme_rows_d1(const mca_scheme_params_t *p) {
    return fmin(p->d1 + p->d1_margin, 0.5 * (p->d1 + p->d2));
}

double mca_scheme_stop_time(const mca_chain_t *chain, double dec) {
    double t_stop = 0.0;
    if (dec > 0.0) {
        for (int j = 0; j < chain->dof; j++) {
            t_stop = fmax(t_stop, chain->joint[j].vel_limit / dec);
        }
    }
    return t_stop;
}

double mca_scheme_row_bound(const mca_scheme_params_t *p, double d, double t_stop) {
    const double d1m = mca_scheme_rows_d1(p);
    double bound = p->big;
    if (d < p->d2) {
        bound = mca_brake_s(d, d1m, p->d2) * p->v_normal;
    }
    if (t_stop > 0.0) {
        bound = fmin(bound, fmax(0.0, d - d1m) / (2.0 * t_stop)); /* invariant: docs/scheme.md §10 */
    }
    return bound;
}

double mca_scheme_row_share(const double *priority, int a, int b) {
    const double pa = priority ? priority[a] : 1.0, pb = priority ? priority[b] : 1.0;
    return pa + pb > 0.0 ? 2.0 * pa / (pa + pb) : 1.0;
}

int mca_scheme_near_rows(mca_qp_t *qp, mca_scheme_info_t *si, int n_arms, const mca_chain_t *const chain[],
                         const mca_kin_t kin[],
                         const mca_link_critical_t near[][MCA_MAX_LINKS][MCA_NEAR_PAIRS],
                         const mca_scheme_params_t *p, const double *dec, const double *priority) {
    if (!qp || !si || !chain || !kin || !near || !p || n_arms < 1 || n_arms > MCA_MAX_ARMS) {
        return MCA_EINVAL;
    }
    int n_ineq = 0;
    for (int a = 0; a < n_arms; a++) {
        si->row_off[a] = n_ineq;
        si->body_off[a] = n_ineq + MCA_NEAR_PAIRS * (chain[a]->dof + 1);
        n_ineq += (MCA_NEAR_PAIRS + p->body_pairs) * (chain[a]->dof + 1);
    }
    if (n_ineq > MCA_QP_MAX_INEQ) {
        return MCA_ERANGE;
    }
    /* Only the QP's columns are ever read, and of an inactive row (beta = big) not even those: a row is
     * cleared when it gets written (touching all ~100 slot rows each tick was a tenth of mca-ts's extra). */
    const size_t row_bytes = sizeof(double) * (size_t)qp->n;
    for (int i = 0; i < n_ineq; i++) {
        qp->beta[i] = p->big;
    }
    qp->n_ineq = n_ineq;
    si->rows_per_link = MCA_NEAR_PAIRS;
    si->active_rows = 0;
    si->brake = 1.0;
    for (int a = n_arms; a < MCA_MAX_ARMS; a++) {
        si->row_off[a] = si->body_off[a] = n_ineq;
    }
    const double d1m = mca_scheme_rows_d1(p); /* the rows aim above d1 */
    for (int a = 0; a < n_arms; a++) {
        const int dof = chain[a]->dof, vo = si->var_off[a];
        int kept[MCA_NEAR_PAIRS * MCA_MAX_LINKS], n_kept = 0; /* arm a's active rows so far */
        double kept_norm[MCA_NEAR_PAIRS * MCA_MAX_LINKS];
        const double t_stop = mca_scheme_stop_time(chain[a], dec ? dec[a] : 0.0);
        for (int l = 0; l <= dof; l++) {
            for (int k = 0; k < MCA_NEAR_PAIRS; k++) {
                const mca_link_critical_t *c = &near[a][l][k];
                const int r = si->row_off[a] + MCA_NEAR_PAIRS * l + k;
                if (!c->valid) {
                    break; /* a list's pairs come first, nearest first: the rest is empty */
                }
                if (repeats_previous(near[a], l, c)) {
                    continue;
                }
                double r_pe[3];
                mca_v3_sub(r_pe, c->e, c->p);
                const double nrm = mca_v3_norm(r_pe);
                if (!(nrm > 1e-12)) {
                    continue; /* axes touch: no direction; the distance fault handles it */
                }
                if (c->d < p->d2) {
                    si->brake = fmin(si->brake, mca_brake_s(c->d, d1m, p->d2));
                }
                const double bound = mca_scheme_row_bound(p, c->d, t_stop);
                if (!(bound < p->big)) {
                    continue; /* beyond d2 with no stop bound: inactive */
                }
                const double share = mca_scheme_row_share(priority, a, c->other_arm);
                double Jp[3][MCA_MAX_DOF];
                const int rc = mca_jacobian_point(&kin[a], l, c->p, Jp);
                if (rc != MCA_OK) {
                    return rc;
                }
                double reach =
                    0.0; /* the fastest approach the joint limits allow: a row above it never binds */
                memset(qp->U[r], 0, row_bytes);
                for (int j = 0; j < dof; j++) {
                    const double u = (r_pe[0] * Jp[0][j] + r_pe[1] * Jp[1][j] + r_pe[2] * Jp[2][j]) / nrm;
                    qp->U[r][vo + j] = u;
                    reach += fabs(u) * chain[a]->joint[j].vel_limit;
                }
                if (share * bound >= reach) {
                    continue; /* inactive: the same QP, fewer rows to iterate */
                }
                qp->beta[r] = share * bound;
                if (mca__scheme_merge_parallel(qp, vo, dof, r, kept, kept_norm, n_kept)) {
                    qp->beta[r] = p->big;
                    continue;
                }
                kept[n_kept++] = r;
                si->active_rows++;
            }
        }
    }
    return MCA_OK;
}

int mca_scheme_prune_rows(mca_qp_t *qp, double big, mca_scheme_info_t *si) {
    int dropped = 0;
    for (int i = 0; i < qp->n_ineq; i++) {
        if (!(qp->beta[i] < big)) {
            continue;
        }
        double reach = 0.0; /* the largest U_i phi over the box (+inf where a bound is infinite) */
        for (int j = 0; j < qp->n; j++) {
            const double u = qp->U[i][j];
            if (u > 0.0) {
                reach += u * qp->ub[j];
            } else if (u < 0.0) {
                reach += u * qp->lb[j];
            }
        }
        if (reach < qp->beta[i]) {
            memset(qp->U[i], 0, sizeof(double) * (size_t)qp->n);
            qp->beta[i] = big;
            dropped++;
        }
    }
    if (si) {
        si->active_rows -= dropped;
    }
    return dropped;
}

int mca_scheme_compact_rows(mca_qp_t *qp, double big, mca_scheme_info_t *si, int *src) {
    int off[MCA_MAX_ARMS];
    for (int a = 0; a < MCA_MAX_ARMS; a++) {
        off[a] = si->row_off[a];
        si->row_off[a] = -1;
    }
    const size_t row_bytes = sizeof(double) * (size_t)qp->n;
    int n = 0, a = 0;
    for (int i = 0; i < qp->n_ineq; i++) {
        while (a < MCA_MAX_ARMS && i >= off[a]) {
            si->row_off[a++] = n; /* arm a's rows start here (empty arms: at the next kept row) */
        }
        if (!(qp->beta[i] < big)) {
            continue;
        }
        if (n != i) {
            memcpy(qp->U[n], qp->U[i], row_bytes);
            qp->beta[n] = qp->beta[i];
        }
        src[n++] = i;
    }
    for (; a < MCA_MAX_ARMS; a++) {
        si->row_off[a] = n;
    }
    qp->n_ineq = n;
    return n;
}

int mca_scheme_add_timescale(mca_qp_t *qp, int n_arms, const double rdot_d[][3], const double *target,
                             const double *sigma_lo, const double *sigma_hi, const double slack_lo[][3],
                             const double slack_hi[][3], const mca_timescale_weights_t *w, const int *mode,
                             int ts_off[], double sigma_scale[]) {
    if (!qp || !rdot_d || !target || !sigma_lo || !sigma_hi || !slack_lo || !slack_hi || !w || !ts_off ||
        !sigma_scale || !mode || !(w->w_sigma > 0.0) || !(w->w_slack > 0.0) || !(w->w_tube > 0.0) ||
        !(w->w_path >= 0.0) || n_arms < 1 || qp->n_eq != MCA_TASK_DIM * n_arms) {
        return MCA_EINVAL;
    }
    if (qp->n + MCA_TS_VARS * n_arms > MCA_QP_MAX_VARS) {
        return MCA_ERANGE;
    }
    for (int a = 0; a < n_arms; a++) {
        for (int i = 0; i < MCA_TASK_DIM; i++) {
            if (!(slack_lo[a][i] <= 0.0) || !(slack_hi[a][i] >= 0.0) ||
                (mode[a] == MCA_TRACK_ELASTIC && (slack_lo[a][i] > -INFINITY || slack_hi[a][i] < INFINITY))) {
                return MCA_EINVAL;
            }
        }
    }
    for (int a = 0; a < n_arms; a++) {
        const int o = qp->n;
        /* u = m (sigma - target), m = sqrt(w_sigma). (Scaling m with |rdot|, so that the column has the same
         * length at any path speed, was tried: no fewer unsafe runs in the sweep and more deadlocks.) */
        const double m = sqrt(w->w_sigma);
        const double sw = sqrt(mode[a] == MCA_TRACK_ELASTIC ? w->w_slack : w->w_tube), re = 1.0 / sw;
        const double k = mode[a] == MCA_TRACK_PATH_FIRST ? w->w_path / sw : 0.0;
        const double rs = 1.0 / m;
        sigma_scale[a] = m;
        ts_off[a] = o;
        qp->n += MCA_TS_VARS;
        for (int i = 0; i < MCA_TASK_DIM; i++) {
            const int row = MCA_TASK_DIM * a + i;
            const int yp = o + 1 + i, yn = o + 1 + MCA_TASK_DIM + i;
            /* the assembly wrote alpha = rdot + K (r_d - r): the path term now runs at the target rate */
            qp->alpha[row] += (target[a] - 1.0) * rdot_d[a][i];
            qp->G[row][o] = -rdot_d[a][i] * rs;
            qp->G[row][yp] = -re;
            if (mode[a] == MCA_TRACK_ELASTIC) {
                /* elastic tracking (an L2 slack, no tube): y_p = s is the whole slack, y_n a fixed 0 that
                 * enters no row, so the QP and the PDNN's answer are those of the 4-variable layout */
                qp->G[row][yn] = 0.0;
                qp->lb[yp] = -INFINITY;
                qp->ub[yp] = INFINITY;
                qp->lb[yn] = qp->ub[yn] = 0.0;
                continue;
            }
            qp->G[row][yn] = re;
            /* the parts start at k (their shift makes the L1 weight); the tube bounds their growth */
            qp->lb[yp] = k;
            qp->ub[yp] = k + sw * slack_hi[a][i];
            qp->lb[yn] = k;
            qp->ub[yn] = k - sw * slack_lo[a][i];
        }
        for (int kk = 0; kk < qp->n_ineq; kk++) {
            for (int v = 0; v < MCA_TS_VARS; v++) {
                qp->U[kk][o + v] = 0.0;
            }
        }
        qp->lb[o] = (sigma_lo[a] - target[a]) / rs;
        qp->ub[o] = (sigma_hi[a] - target[a]) / rs;
    }
    return MCA_OK;
}

double mca_scheme_ts_slack(const double *phi, int ts_off, int i, const mca_timescale_weights_t *w, int mode) {
    const double s = sqrt(mode == MCA_TRACK_ELASTIC ? w->w_slack : w->w_tube);
    return (phi[ts_off + 1 + i] - phi[ts_off + 1 + MCA_TASK_DIM + i]) / s;
}

void mca_scheme_tube_bounds(const double err[3], double radius, double K, double dt, double lo[3],
                            double hi[3]) {
    for (int i = 0; i < 3; i++) {
        if (!(radius < INFINITY)) {
            lo[i] = -INFINITY;
            hi[i] = INFINITY;
            continue;
        }
        /* never below MCA_TUBE_FLOOR: at rest on a tube of 0 the standing-still point sat on three edges at
         * once, a vertex the PDNN and its polish could not resolve beside two near-parallel rows
         * (jaco-mico:132 of seed 1: 24306 ticks unconverged); a micrometre keeps it inside */
        const double R = fmax(fmax(radius / sqrt(3.0), fabs(err[i])), MCA_TUBE_FLOOR);
        const double keep = (1.0 - K * dt) * err[i];
        /* rounding must not put 0 outside: standing still is the point the feasibility argument needs */
        lo[i] = fmin(0.0, (keep - R) / dt);
        hi[i] = fmax(0.0, (keep + R) / dt);
    }
}
