/* SPDX-License-Identifier: MIT */
/* The controller's distances and near pairs (see controller__dist.h). */
#include <math.h>
#include <string.h>

#include "mca/controller.h"
#include "mca/err.h"
#include "mca/segdist.h"
#include "mca/vec3.h"

#include "controller__common.h"
#include "controller__dist.h"

/* Insert a witness pair (P on this link, E on link other_link of other_arm, surface distance d) into a
 * link's list of its MCA_NEAR_PAIRS nearest, sorted by d. A pair found twice (a shared joint point of two
 * links of the other arm, the closest points found again at a segment end) is listed once; pairs that are
 * nearly the same give nearly parallel rows, which mca_scheme_near_rows merges. */
static void near_insert(mca_link_critical_t list[MCA_NEAR_PAIRS], int other_arm, int other_link, double d,
                        const double p[3], const double e[3]) {
    if (list[MCA_NEAR_PAIRS - 1].valid && !(d < list[MCA_NEAR_PAIRS - 1].d)) {
        return; /* most candidates: not among the nearest */
    }
    for (int i = 0; i < MCA_NEAR_PAIRS && list[i].valid; i++) {
        if (fabs(list[i].d - d) < 1e-9 && mca_v3_dist(list[i].p, p) < 1e-9 &&
            mca_v3_dist(list[i].e, e) < 1e-9) {
            return;
        }
    }
    int k = MCA_NEAR_PAIRS;
    while (k > 0 && (!list[k - 1].valid || d < list[k - 1].d)) {
        k--;
    }
    if (k >= MCA_NEAR_PAIRS) {
        return;
    }
    memmove(&list[k + 1], &list[k], (size_t)(MCA_NEAR_PAIRS - 1 - k) * sizeof list[0]);
    mca_link_critical_t *c = &list[k];
    c->valid = 1;
    c->other_arm = other_arm;
    c->other_link = other_link;
    c->d = d;
    mca_v3_set(c->p, p);
    mca_v3_set(c->e, e);
}

/* The distance a new witness pair of this d would need to enter the list (INFINITY while it has room). */
static double near_worst(const mca_link_critical_t list[MCA_NEAR_PAIRS]) {
    return list[MCA_NEAR_PAIRS - 1].valid ? list[MCA_NEAR_PAIRS - 1].d : INFINITY;
}

/* Which witness pairs can bind this QP (mca_ctrl__near_links): per arm and link, the fastest any point of the
 * link can move with the joint speeds inside the QP's box. A pair whose row bound (mca_scheme_row_bound,
 * times the priority share) is above that speed cannot bind: mca_scheme_prune_rows would drop its row, so it
 * is not listed (no Jacobian, no row). The bound grows with d; its stop part is linear, so per arm, link and
 * other arm a distance below which every pair may bind is known at once; beyond it only pairs inside d2 (the
 * S part) are checked one by one. */
typedef struct near_reach {
    double speed[MCA_MAX_ARMS][MCA_MAX_LINKS];                  /* |J_p qdot| <= this, p on the link */
    double cut_stop[MCA_MAX_ARMS][MCA_MAX_LINKS][MCA_MAX_ARMS]; /* the stop part binds if d <= this */
    double share[MCA_MAX_ARMS][MCA_MAX_ARMS];
    double t_stop[MCA_MAX_ARMS];
    const mca_scheme_params_t *sp;
} near_reach_t;

/* The larger of x and y; unlike fmax, a NaN is kept (and it is inlined). */
static inline double max_or_nan(double x, double y) {
    return x < y ? y : (isnan(y) ? y : x);
}

/* |J_p qdot| <= sum_j |qdot_j| |p - o_j| (unit axes, revolute joints), and on a segment |p - o_j| is
 * largest at one of its ends. */
static void near_reach_init(near_reach_t *r, const mca_controller_t *ctrl, const mca_qp_t *qp,
                            const mca_scheme_info_t *si, const double *dec, const double *priority) {
    const mca_scheme_params_t *sp = &ctrl->cfg.sp;
    const int na = ctrl->cfg.n_arms;
    const double d1m = mca_scheme_rows_d1(sp);
    r->sp = sp;
    for (int a = 0; a < na; a++) {
        const mca_kin_t *k = &ctrl->kin[a];
        const int dof = ctrl->cfg.chain[a].dof, vo = si->var_off[a];
        r->t_stop[a] = mca_scheme_stop_time(&ctrl->cfg.chain[a], dec ? dec[a] : 0.0);
        for (int b = 0; b < na; b++) {
            r->share[a][b] = mca_scheme_row_share(priority, a, b);
        }
        double qmax[MCA_MAX_DOF], lever[MCA_MAX_POINTS][MCA_MAX_DOF]; /* |point m - joint j's origin| */
        for (int j = 0; j < dof; j++) {
            qmax[j] = max_or_nan(fabs(qp->lb[vo + j]), fabs(qp->ub[vo + j]));
            for (int m = j + 1; m <= dof + 1; m++) {
                lever[m][j] = mca_v3_dist(k->point[m], k->point[j + 1]);
            }
        }
        for (int l = 0; l <= dof; l++) {
            double v = 0.0; /* the link's fastest point (NaN anywhere: NaN, so every pair may bind) */
            for (int j = 0; j < l; j++) {
                v += qmax[j] * max_or_nan(lever[l][j], lever[l + 1][j]);
            }
            r->speed[a][l] = v;
            for (int b = 0; b < na; b++) {
                const double share = r->share[a][b];
                double cs = -INFINITY; /* share (d - d1m) / (2 t_stop) <= v */
                if (!isfinite(v) || !(share > 0.0)) {
                    cs = INFINITY; /* nothing known: every pair may bind */
                } else if (r->t_stop[a] > 0.0) {
                    cs = d1m + 2.0 * r->t_stop[a] * v / share;
                }
                r->cut_stop[a][l][b] = cs;
            }
        }
    }
}

/* Can the row of arm a's link l against arm b at distance d bind? (NaN d: yes.) */
static int near_can_bind(const near_reach_t *r, int a, int l, int b, double d) {
    if (!(d > r->cut_stop[a][l][b])) {
        return 1;
    }
    if (d >= r->sp->d2) {
        return 0; /* the S part is inactive beyond d2, and the stop part is above the speed */
    }
    return !(r->share[a][b] * mca_scheme_row_bound(r->sp, d, r->t_stop[a]) > r->speed[a][l]);
}

/* Can any pair of arm a's link l against arm b bind, dmin the link's nearest pair? */
static int near_link_live(const near_reach_t *r, int a, int l, int b, double dmin) {
    return !(dmin >= r->sp->d2 && dmin > r->cut_stop[a][l][b]);
}

static void near_add(mca_link_critical_t list[MCA_NEAR_PAIRS], const near_reach_t *r, int a, int l, int b,
                     int other_link, double d, const double p[3], const double e[3]) {
    if (near_can_bind(r, a, l, b, d)) {
        near_insert(list, b, other_link, d, p, e);
    }
}

/* Per link of every arm: its MCA_NEAR_PAIRS nearest witness pairs against the other arms' links that can bind
 * the QP in hand (its box: see near_reach_t), for mca-ts's rows and the braking rows. Two segments' distance
 * is the least of their closest points and their four ends' distances to the other segment; each of these
 * moves smoothly, but which one is least can jump (nearly parallel links: the closest points jump from one
 * end to the other). A row on each keeps every one above d1, so the minimum too; a row on the closest
 * points alone lets the far end approach unbounded until it takes over. */
void mca_ctrl__near_links(mca_controller_t *ctrl, const mca_qp_t *qp, const mca_scheme_info_t *si,
                          const double *dec, const double *priority) {
    const int na = ctrl->cfg.n_arms;
    near_reach_t r;
    near_reach_init(&r, ctrl, qp, si, dec, priority);
    for (int a = 0; a < na; a++) {
        for (int l = 0; l < MCA_MAX_LINKS; l++) {
            /* a list's valid pairs are its first ones: clearing stops at the first empty entry (most lists
             * are empty, and this memory is cold at each tick) */
            for (int k = 0; k < MCA_NEAR_PAIRS && ctrl->near[a][l][k].valid; k++) {
                ctrl->near[a][l][k].valid = 0;
            }
        }
    }
    for (int a = 0; a < na; a++) {
        for (int b = a + 1; b < na; b++) {
            const mca_arm_distances_t *ad = &ctrl->dist[a][b];
            /* A link whose nearest pair (mca_arm_distances' a_to_b / b_to_a; finite, as the distances
             * checked every point) is beyond d2 and its cut has no pair that can bind: its list is not
             * looked at (most links, most ticks). */
            int live_a[MCA_MAX_LINKS], live_b[MCA_MAX_LINKS], n_live = 0;
            for (int i = 0; i < ad->n_links_a; i++) {
                live_a[i] = near_link_live(&r, a, i, b, ad->a_to_b[i].d);
                n_live += live_a[i];
            }
            for (int j = 0; j < ad->n_links_b; j++) {
                live_b[j] = near_link_live(&r, b, j, a, ad->b_to_a[j].d);
                n_live += live_b[j];
            }
            if (n_live == 0) {
                continue;
            }
            for (int i = 0; i < ad->n_links_a; i++) {
                for (int j = 0; j < ad->n_links_b; j++) {
                    const mca_link_pair_t *lp = &ad->pair[i][j];
                    if (live_a[i]) {
                        near_add(ctrl->near[a][i], &r, a, i, b, j, lp->d, lp->p, lp->e);
                    }
                    if (live_b[j]) {
                        near_add(ctrl->near[b][j], &r, b, j, a, i, lp->d, lp->e, lp->p);
                    }
                }
            }
            /* the ends: never nearer than their pair's closest points, so only pairs that could enter a list
             */
            const mca_kin_t *ka = &ctrl->kin[a], *kb = &ctrl->kin[b];
            const double *ra = ctrl->cfg.chain[a].link_radius, *rb = ctrl->cfg.chain[b].link_radius;
            for (int i = 0; i < ad->n_links_a; i++) {
                for (int j = 0; j < ad->n_links_b; j++) {
                    if (!live_a[i] && !live_b[j]) {
                        continue;
                    }
                    const double d0 = ad->pair[i][j].d;
                    const int in_a =
                        live_a[i] && d0 < near_worst(ctrl->near[a][i]) && near_can_bind(&r, a, i, b, d0);
                    const int in_b =
                        live_b[j] && d0 < near_worst(ctrl->near[b][j]) && near_can_bind(&r, b, j, a, d0);
                    if (!in_a && !in_b) {
                        continue;
                    }
                    const double *sa[2] = {ka->point[i], ka->point[i + 1]};
                    const double *sb[2] = {kb->point[j], kb->point[j + 1]};
                    for (int end = 0; end < 2; end++) {
                        double h[3];
                        const double da =
                            mca_point_segment_paper(sa[end], sb[0], sb[1], h, NULL) - ra[i] - rb[j];
                        near_add(ctrl->near[a][i], &r, a, i, b, j, da, sa[end], h);
                        near_add(ctrl->near[b][j], &r, b, j, a, i, da, h, sa[end]);
                        const double db =
                            mca_point_segment_paper(sb[end], sa[0], sa[1], h, NULL) - ra[i] - rb[j];
                        near_add(ctrl->near[a][i], &r, a, i, b, j, db, h, sb[end]);
                        near_add(ctrl->near[b][j], &r, b, j, a, i, db, sb[end], h);
                    }
                }
            }
        }
    }
}

/* Per link of every arm: the closest link of any other arm, and the global minimum. */
/* The fixed bodies: each body's closest link and each arm's least self pair (kept for
 * mca_controller_pair_nearest), and the least of them into the tick report: the arm-body pair of least margin
 * (d - clearance; the first in the order body, arm, link on a tie, as mca_body_nearest) and the self pair of
 * least distance. */
static int body_distances(mca_controller_t *ctrl, mca_tick_info_t *info) {
    const mca_chain_t *chains[MCA_MAX_ARMS];
    for (int a = 0; a < ctrl->cfg.n_arms; a++) {
        chains[a] = &ctrl->cfg.chain[a];
    }
    const mca_self_pairs_t *self = mca_controller_has_self(&ctrl->cfg) ? ctrl->cfg.self : NULL;
    mca_body_cache_t *cache = NULL;
    if (ctrl->cfg.n_bodies > 0 || self) {
        cache = &ctrl->body_cache;
        if (mca_body_cache_update(cache, ctrl->cfg.n_arms, chains, ctrl->kin, ctrl->cfg.body,
                                  ctrl->cfg.n_bodies, self) != MCA_OK) {
            return MCA_EINVAL;
        }
    }
    mca_pair_nearest_t *pn = &ctrl->near_kinds;
    pn->n_bodies = ctrl->cfg.n_bodies;
    pn->n_fixed = ctrl->n_fixed;
    const int rc = mca_body_nearest_each(ctrl->cfg.n_arms, chains, ctrl->kin, ctrl->cfg.body,
                                         ctrl->cfg.n_bodies, pn->body);
    const mca_body_nearest_t *bn = NULL;
    for (int k = 0; rc == MCA_OK && k < pn->n_bodies; k++) {
        if (pn->body[k].valid && (bn == NULL || pn->body[k].margin < bn->margin)) {
            bn = &pn->body[k];
        }
    }
    info->body_distance = bn ? bn->d : INFINITY;
    info->body_margin = bn ? bn->margin : INFINITY;
    info->body_arm = bn ? bn->arm : -1;
    info->body_link = bn ? bn->link : -1;
    info->body_index = bn ? bn->body : -1;
    info->body_kind = bn ? bn->kind : -1;
    mca_v3_set(info->body_p, bn ? bn->p : (const double[3]){0.0, 0.0, 0.0});
    mca_v3_set(info->body_q, bn ? bn->q : (const double[3]){0.0, 0.0, 0.0});
    if (rc != MCA_OK) {
        pn->n_bodies = 0;
        return rc;
    }
    /* one arm at a time: each arm's own least self pair, then the least of them (the first arm on a tie) */
    const int has_self = mca_controller_has_self(&ctrl->cfg);
    const mca_self_nearest_t *sn = NULL;
    int rs = MCA_OK;
    for (int a = 0; a < MCA_MAX_ARMS; a++) {
        mca_self_nearest_t *s = &pn->self[a];
        const int r = a < ctrl->cfg.n_arms && has_self
                          ? mca_self_nearest(1, &chains[a], &ctrl->kin[a], &ctrl->cfg.self[a], NULL, s)
                          : mca_self_nearest(0, NULL, NULL, NULL, NULL, s);
        if (s->valid) {
            s->arm = a;
            if (sn == NULL || s->d < sn->d) {
                sn = s;
            }
        }
        rs = rs != MCA_OK ? rs : r;
    }
    info->self_distance = sn ? sn->d : INFINITY;
    info->self_arm = sn ? sn->arm : -1;
    info->self_link = sn ? sn->link : -1;
    info->self_other = sn ? sn->other : -1;
    return rs;
}

int mca_ctrl__distances(mca_controller_t *ctrl, mca_tick_info_t *info) {
    const int na = ctrl->cfg.n_arms;
    for (int a = 0; a < na; a++) {
        for (int l = 0; l < MCA_MAX_LINKS; l++) {
            ctrl->crit[a][l].valid = 0;
            ctrl->crit[a][l].d = INFINITY;
            info->link_distance[a][l] = INFINITY;
        }
    }
    info->min_distance = INFINITY;
    info->min_arm_a = info->min_arm_b = info->min_link_a = info->min_link_b = -1;
    for (int a = 0; a < na; a++) {
        for (int b = a + 1; b < na; b++) {
            mca_arm_distances_t *ad = &ctrl->dist[a][b];
            int rc = mca_arm_distances(&ctrl->cfg.chain[a], &ctrl->kin[a], &ctrl->cfg.chain[b], &ctrl->kin[b],
                                       ctrl->cfg.dist_method, ad);
            if (rc != MCA_OK) {
                return rc;
            }
            for (int side = 0; side < 2; side++) {
                const int me = side ? b : a, other = side ? a : b;
                const mca_link_pair_t *lp = side ? ad->b_to_a : ad->a_to_b;
                const int nl = side ? ad->n_links_b : ad->n_links_a;
                for (int l = 0; l < nl && l < MCA_MAX_LINKS; l++) {
                    mca_link_critical_t *c = &ctrl->crit[me][l];
                    if (!c->valid || lp[l].d < c->d) {
                        c->valid = 1;
                        c->other_arm = other;
                        c->other_link = lp[l].other_link;
                        c->d = lp[l].d;
                        mca_v3_set(c->p, lp[l].p);
                        mca_v3_set(c->e, lp[l].e);
                    }
                }
            }
            if (ad->min.d < info->min_distance) {
                info->min_distance = ad->min.d;
                info->min_arm_a = a;
                info->min_arm_b = b;
                info->min_link_a = ad->min.link;
                info->min_link_b = ad->min.other_link;
                mca_v3_set(info->min_p, ad->min.p);
                mca_v3_set(info->min_e, ad->min.e);
            }
        }
    }
    for (int a = 0; a < na; a++) {
        for (int l = 0; l < MCA_MAX_LINKS; l++) {
            info->link_distance[a][l] = ctrl->crit[a][l].d;
        }
    }
    return body_distances(ctrl, info);
}

int mca_controller_pair_nearest(const mca_controller_t *ctrl, mca_pair_nearest_t *out) {
    if (!ctrl || !out) {
        return MCA_EINVAL;
    }
    *out = ctrl->near_kinds;
    return MCA_OK;
}
