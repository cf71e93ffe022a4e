/* SPDX-License-Identifier: MIT */
/* One controller tick for N arms (FK, distances, QP, PDNN, faults); see mca/controller.h. */
#include "mca/controller.h"

#include <math.h>
#include <stdio.h>
#include <string.h>
#include <time.h>

#include "mca/err.h"
#include "mca/segdist.h"
#include "mca/vec3.h"

static const char *const fault_names[] = {
    [MCA_CTRL_FAULT_NONE] = "none",
    [MCA_CTRL_FAULT_NAN] = "nan",
    [MCA_CTRL_FAULT_NOT_CONVERGED] = "pdnn-not-converged",
    [MCA_CTRL_FAULT_INFEASIBLE] = "joint-bounds-infeasible",
    [MCA_CTRL_FAULT_DISTANCE] = "distance-below-d1",
    [MCA_CTRL_FAULT_FAKE_ATTRACTOR] = "fake-attractor",
    [MCA_CTRL_FAULT_INPUT] = "bad-input",
};

const char *mca_ctrl_fault_name(int fault) {
    if (fault < 0 || fault >= (int)(sizeof fault_names / sizeof fault_names[0])) {
        return "unknown";
    }
    return fault_names[fault];
}

static const char *const scheme_names[] = {
    [MCA_SCHEME_MCA] = "mca",
    [MCA_SCHEME_MVN] = "mvn",
    [MCA_SCHEME_APF] = "apf",
    [MCA_SCHEME_MCA_TS] = "mca-ts",
};

const char *mca_scheme_name(int scheme) {
    if (scheme < 0 || scheme >= (int)(sizeof scheme_names / sizeof scheme_names[0])) {
        return "unknown";
    }
    return scheme_names[scheme];
}

int mca_scheme_from_name(const char *name, mca_scheme_kind_t *out) {
    for (int k = 0; name && k < (int)(sizeof scheme_names / sizeof scheme_names[0]); k++) {
        if (strcmp(name, scheme_names[k]) == 0) {
            *out = (mca_scheme_kind_t)k;
            return MCA_OK;
        }
    }
    return MCA_EINVAL;
}

void mca_controller_default_config(mca_controller_config_t *cfg) {
    memset(cfg, 0, sizeof *cfg);
    cfg->scheme = MCA_SCHEME_MCA;
    mca_scheme_default_params(&cfg->sp);
    mca_pdnn_default_params(&cfg->pdnn);
    mca_apf_default_params(&cfg->apf);
    cfg->dist_method = MCA_DIST_CLOSED;
    cfg->dt = MCA_CONTROLLER_DT;
    cfg->pdnn.max_steps = 2000; /* ~1 ms worst case here: a tick must fit the 1 kHz period */
    cfg->fault_residual = 1e-6;
    cfg->eq_tol = 1e-4;
    cfg->fault_distance = 1;
    cfg->ts.w_sigma = 1e2;
    cfg->ts.w_slack = 1e3;
    cfg->ts.w_path = 1e4;
    cfg->ts.w_tube = 1e3;
    cfg->ts.sigma_max = 1.5;
    cfg->ts.deadlock_time = 0.5;
    cfg->ts.deadlock_sigma = 0.05;
    cfg->ts.back_off_time = 1.0;
    cfg->ts.d1_margin = 0.005;
    cfg->ts.coordinate = 1;
    for (int a = 0; a < MCA_MAX_ARMS; a++) {
        cfg->ts.priority[a] = 1.0;
    }
}

/* Schemes with collision rows (and the distance fault). */
static int uses_rows(mca_scheme_kind_t scheme) {
    return scheme == MCA_SCHEME_MCA || scheme == MCA_SCHEME_MCA_TS;
}

int mca_controller_init(mca_controller_t *ctrl, const mca_controller_config_t *cfg) {
    if (!ctrl || !cfg || cfg->n_arms < 1 || cfg->n_arms > MCA_MAX_ARMS || !(cfg->dt > 0.0) ||
        !(cfg->sp.d1 >= 0.0) || !(cfg->sp.d1 < cfg->sp.d2) || !(cfg->sp.epsilon > 0.0) ||
        !(cfg->sp.K >= 0.0) || !(cfg->sp.big > 0.0) || cfg->scheme < MCA_SCHEME_MCA ||
        cfg->scheme > MCA_SCHEME_MCA_TS ||
        (cfg->scheme == MCA_SCHEME_MCA_TS &&
         (!(cfg->ts.w_sigma > 0.0) || !(cfg->ts.w_slack > 0.0) || !(cfg->ts.w_path >= 0.0) ||
          !(cfg->ts.w_tube > 0.0) || !(cfg->ts.sigma_max >= 1.0) || !(cfg->ts.deadlock_time > 0.0) ||
          !(cfg->ts.deadlock_sigma >= 0.0) || !(cfg->ts.back_off_time >= 0.0) ||
          !(cfg->ts.d1_margin >= 0.0)))) {
        return MCA_EINVAL;
    }
    for (int a = 0; a < cfg->n_arms; a++) {
        if (cfg->chain[a].dof < 1 || cfg->chain[a].dof > MCA_MAX_DOF) {
            return MCA_EINVAL;
        }
    }
    memset(ctrl, 0, sizeof *ctrl);
    ctrl->cfg = *cfg;
    ctrl->cfg.sp.collision = uses_rows(cfg->scheme);
    if (cfg->scheme == MCA_SCHEME_MCA_TS) {
        /* the stoppability bound bounds the normal approach speed, and must hold before the band */
        ctrl->cfg.sp.form = MCA_FORM_NORMAL;
        ctrl->cfg.sp.d1_margin = cfg->ts.d1_margin;
    }
    for (int a = 0; a < cfg->n_arms; a++) {
        ctrl->path_end[a] = mca_path_end_time(&cfg->path[a]);
    }
    mca_pdnn_init(&ctrl->pdnn);
    mca_pdnn_init(&ctrl->brake_pdnn);
    mca_controller_reset(ctrl);
    return MCA_OK;
}

void mca_controller_reset(mca_controller_t *ctrl) {
    ctrl->started = 0;
    ctrl->t_start = 0.0;
    ctrl->fault = MCA_CTRL_FAULT_NONE;
    ctrl->fault_why = (mca_ctrl_fault_why_t){0};
    ctrl->has_prev = 0;
    ctrl->ticks = 0;
    ctrl->pdnn.h = 0; /* cold start */
    mca_scheme_state_reset(&ctrl->sstate);
    memset(ctrl->phi, 0, sizeof ctrl->phi);
    memset(ctrl->phi_prev, 0, sizeof ctrl->phi_prev);
    for (int a = 0; a < MCA_MAX_ARMS; a++) {
        ctrl->tau[a] = 0.0;
        ctrl->sigma[a] = 1.0;
    }
    ctrl->stall_time = 0.0;
    ctrl->deadlock = MCA_DEADLOCK_NONE;
    ctrl->deadlock_arm = -1;
    ctrl->deadlocks = 0;
    ctrl->back_offs = 0;
    for (int a = 0; a < MCA_MAX_ARMS; a++) {
        ctrl->giving_way[a] = 0;
        ctrl->held_time[a] = 0.0;
        ctrl->rate_avg[a] = 1.0;
        ctrl->at_tube_edge[a] = 0;
        ctrl->exact_next[a] = 0;
        ctrl->exact_bad[a] = 0;
    }
    ctrl->exact_met = ctrl->exact_missed = 0;
    ctrl->exact_error_max = 0.0;
    memset(&ctrl->coord, 0, sizeof ctrl->coord); /* a plan holds for one start */
    ctrl->brake_pdnn.h = 0;
    ctrl->n_row_key = ctrl->n_brake_row_key = 0;
}

int mca_controller_plan(mca_controller_t *ctrl, const double *const q[MCA_MAX_ARMS], mca_coord_work_t *work) {
    if (!ctrl || !q || !work) {
        return MCA_EINVAL;
    }
    const mca_controller_config_t *cfg = &ctrl->cfg;
    memset(&ctrl->coord, 0, sizeof ctrl->coord);
    if (cfg->scheme != MCA_SCHEME_MCA_TS || !cfg->ts.coordinate) {
        return MCA_OK;
    }
    mca_path_t paths[MCA_MAX_ARMS];
    mca_coord_arm_t arms[MCA_MAX_ARMS];
    for (int a = 0; a < cfg->n_arms; a++) {
        mca_kin_t kin;
        if (!q[a] || mca_fk(&cfg->chain[a], q[a], &kin) != MCA_OK) {
            return MCA_EINVAL;
        }
        paths[a] = cfg->path[a];
        mca_path_anchor(&paths[a], kin.ee);
        arms[a] = (mca_coord_arm_t){&cfg->chain[a], &paths[a], q[a], cfg->sp.K};
    }
    /* the predicted arms kept out of each other's bands (d2) where a schedule allows, else nearer */
    return mca_coord_plan(arms, cfg->n_arms, cfg->sp.d2, cfg->sp.d1 + 2.0 * cfg->ts.d1_margin, work,
                          &ctrl->coord);
}

int mca_controller_stream(mca_controller_t *ctrl, int arm, const double v[3]) {
    if (!ctrl || !v || arm < 0 || arm >= ctrl->cfg.n_arms || ctrl->cfg.path[arm].kind != MCA_PATH_STREAM ||
        !isfinite(v[0]) || !isfinite(v[1]) || !isfinite(v[2])) {
        return MCA_EINVAL;
    }
    mca_v3_set(ctrl->cfg.path[arm].stream_v, v);
    return MCA_OK;
}

void mca_controller_clear_fault(mca_controller_t *ctrl) {
    ctrl->fault = MCA_CTRL_FAULT_NONE;
    ctrl->fault_why = (mca_ctrl_fault_why_t){0};
    ctrl->has_prev = 0;
    ctrl->pdnn.h = 0;
    mca_scheme_state_reset(&ctrl->sstate);
    memset(ctrl->phi_prev, 0, sizeof ctrl->phi_prev);
}

const mca_qp_t *mca_controller_last_qp(const mca_controller_t *ctrl, const double **phi) {
    if (phi) {
        *phi = ctrl->phi;
    }
    return &ctrl->qp;
}

static int64_t now_ns(void) {
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (int64_t)ts.tv_sec * 1000000000LL + ts.tv_nsec;
}

/* A distance fault's cause: the pair and how near. */
static mca_ctrl_fault_why_t why_distance(int why, const mca_tick_info_t *info, double d1) {
    return (mca_ctrl_fault_why_t){.why = why,
                                  .i = {info->min_arm_a, info->min_link_a, info->min_arm_b, info->min_link_b},
                                  .x = {info->min_distance, d1}};
}

/* Latch a fault (the first wins) as a code and numbers: no formatting here, on the 1 kHz path. */
static void raise_fault(mca_controller_t *ctrl, int code, mca_ctrl_fault_why_t why) {
    if (ctrl->fault != MCA_CTRL_FAULT_NONE) {
        return;
    }
    ctrl->fault = code;
    ctrl->fault_why = why;
}

const char *mca_ctrl_fault_format(const mca_ctrl_fault_why_t *w, char *buf, size_t len) {
    if (!buf || len == 0) {
        return buf;
    }
    if (!w) {
        buf[0] = 0;
        return buf;
    }
    const int *i = w->i;
    const double *x = w->x;
    switch (w->why) {
    case MCA_WHY_NULL_JOINTS:
        snprintf(buf, len, "NULL joint array for arm %d", i[0]);
        break;
    case MCA_WHY_NONFINITE_Q:
        snprintf(buf, len, "arm %d: non-finite joint position", i[0]);
        break;
    case MCA_WHY_DISTANCES:
        snprintf(buf, len, "distance computation failed");
        break;
    case MCA_WHY_BELOW_D1:
        snprintf(buf, len, "distance %.4f m < d1 %.4f m (arm %d link %d, arm %d link %d)", x[0], x[1], i[0],
                 i[1], i[2], i[3]);
        break;
    case MCA_WHY_BELOW_D1_NEXT:
        snprintf(
            buf, len,
            "distance %.4f m predicted to fall below d1 %.4f m next tick (arm %d link %d, arm %d link %d)",
            x[0], x[1], i[0], i[1], i[2], i[3]);
        break;
    case MCA_WHY_APF_SINGULAR:
        snprintf(buf, len, "APF: singular Jacobian");
        break;
    case MCA_WHY_BOUNDS:
        snprintf(buf, len, "joint bounds contradict (a joint is beyond its limit)");
        break;
    case MCA_WHY_ASSEMBLY:
        snprintf(buf, len, "QP assembly failed: %s", mca_strerror(i[0]));
        break;
    case MCA_WHY_PDNN_INPUT:
        snprintf(buf, len, "PDNN rejected the QP (non-finite data)");
        break;
    case MCA_WHY_PDNN_OUTPUT:
        snprintf(buf, len, "PDNN output not finite");
        break;
    case MCA_WHY_TRACKING:
        snprintf(buf, len,
                 "tracking contradicts avoidance: PDNN residual %.2e after %d steps, ||G phi - alpha|| = "
                 "%.2e m/s, "
                 "min distance %.4f m",
                 x[0], i[0], x[1], x[2]);
        break;
    case MCA_WHY_NOT_CONVERGED:
        snprintf(buf, len, "PDNN residual %.2e after %d steps (fault > %.1e)", x[0], i[0], x[1]);
        break;
    case MCA_WHY_EQ_RESIDUAL:
        snprintf(buf, len,
                 "equality residual ||G phi - alpha|| = %.2e m/s > %.1e: tracking contradicts avoidance",
                 x[0], x[1]);
        break;
    case MCA_WHY_INJECTED:
        snprintf(buf, len, "injected fault %s at t = %.3f s", mca_ctrl_fault_name(i[0]), x[0]);
        break;
    default:
        buf[0] = 0;
        break;
    }
    return buf;
}

void mca_controller_set_velocity(mca_controller_t *ctrl, const double *const v[MCA_MAX_ARMS]) {
    int k = 0, ok = 1;
    for (int a = 0; a < ctrl->cfg.n_arms; a++) {
        for (int j = 0; j < ctrl->cfg.chain[a].dof; j++, k++) {
            ctrl->v_meas[k] = v && v[a] ? v[a][j] : NAN;
            ok &= isfinite(ctrl->v_meas[k]);
        }
    }
    ctrl->has_v_meas = ok;
}

void mca_controller_raise_fault(mca_controller_t *ctrl, int code, double t) {
    raise_fault(ctrl, code, (mca_ctrl_fault_why_t){.why = MCA_WHY_INJECTED, .i = {code}, .x = {t}});
}

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

/* Which witness pairs can bind this QP (near_links): per arm and link, the fastest any point of the link can
 * move with the joint speeds inside the QP's box. A pair whose row bound (mca_scheme_row_bound, times the
 * priority share) is above that speed cannot bind: mca_scheme_prune_rows would drop its row, so it is not
 * listed (no Jacobian, no row). The bound grows with d; its stop part is linear, so per arm, link and other
 * arm a distance below which every pair may bind is known at once; beyond it only pairs inside d2 (the S
 * part) are checked one by one. */
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
static void near_links(mca_controller_t *ctrl, const mca_qp_t *qp, const mca_scheme_info_t *si,
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
static int distances(mca_controller_t *ctrl, mca_tick_info_t *info) {
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
    return MCA_OK;
}

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

static void zero_cmd(const mca_controller_t *ctrl, double *const qdot[MCA_MAX_ARMS]) {
    for (int a = 0; a < ctrl->cfg.n_arms; a++) {
        if (qdot[a]) {
            for (int j = 0; j < ctrl->cfg.chain[a].dof; j++) {
                qdot[a][j] = 0.0;
            }
        }
    }
}

int mca_controller_observe(mca_controller_t *ctrl, double t, const double *const q[MCA_MAX_ARMS],
                           mca_tick_info_t *info) {
    if (!ctrl || !q || !info) {
        return MCA_EINVAL;
    }
    const int na = ctrl->cfg.n_arms;
    for (int a = 0; a < na; a++) {
        if (!q[a] || mca_fk(&ctrl->cfg.chain[a], q[a], &ctrl->kin[a]) != MCA_OK) {
            return MCA_EINVAL;
        }
    }
    info->t = t;
    info->task_t = ctrl->started ? t - ctrl->t_start : 0.0;
    info->n_arms = na;
    for (int a = 0; a < na; a++) {
        mca_v3_set(info->ee[a], ctrl->kin[a].ee);
    }
    return distances(ctrl, info);
}

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
 * it (tube_keep_brake; the tube admits it), so it stops on its path instead of drifting off it. */
static void repair_capped(mca_controller_t *ctrl, const mca_scheme_info_t *si, int na, const int ts_off[],
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
static double repair_scaled(mca_controller_t *ctrl) {
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
static mca_pdnn_params_t pdnn_params(const mca_controller_config_t *cfg, int64_t t_enter) {
    mca_pdnn_params_t prm = cfg->pdnn;
    if (mca_controller_step_budget(cfg) > 0) {
        prm.max_steps = mca_controller_step_budget(cfg);
    }
    prm.deadline_ns = cfg->pdnn_budget_ns > 0 ? t_enter + cfg->pdnn_budget_ns : 0;
    return prm;
}

/* Whether a solve that did not converge stopped at the budget (time, or steps below the cap) rather than at
 * its cap or for lack of progress. */
static int budget_hit(const mca_controller_config_t *cfg, int rc, const mca_pdnn_result_t *pr) {
    if (rc == MCA_ETIMEDOUT) {
        return MCA_BUDGET_TIME;
    }
    const int steps = mca_controller_step_budget(cfg);
    return rc == MCA_ENOTCONV && steps > 0 && pr->steps >= steps ? MCA_BUDGET_STEPS : MCA_BUDGET_NONE;
}

/* mca-ts and braking: only the active rows go to the PDNN (mca_scheme_compact_rows); each keeps its
 * slot of the full layout (arm, link, list entry) in @p key, and its dual from the last solve where that
 * slot was active then too. */
static void compact_rows(mca_qp_t *qp, double big, mca_scheme_info_t *si, mca_pdnn_t *pdnn, int *key,
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

/* mca-ts: commands the arm can follow. Each joint's command stays within dec_limit dt of the last one, the
 * rate an arm at its limits follows exactly, so the rows hold for the arm and not only for the command.
 * Where the last command lies beyond a joint-limit bound by more than that, the joint limit wins. */
static void accel_box(mca_controller_t *ctrl, const mca_scheme_info_t *si, int na) {
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
 * Runs after accel_box, before mca_scheme_add_timescale (alpha is still rdot + K err). */
static void tube_keep_brake(mca_controller_t *ctrl, const mca_scheme_info_t *si, int a, const double rdot[3],
                            double sig_lo, double sig_hi, double lo[3], double hi[3]) {
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

/* Giving way ends where the error reaches this fraction of the tube's per-axis half width. */
#define MCA_TUBE_EDGE 0.8

/* Catching up: the rate an arm aims at grows with its lag behind task time (1/s per s of lag). */
#define MCA_TS_CATCH_UP_GAIN 1.0

/* Coordination gates: an arm slows at this path-rate deceleration [1/s^2] to stop this far [cells] before a
 * gated cell of its path time (from sigma_max 1.5: 0.28 s of path time). */
#define MCA_TS_GATE_DEC 4.0
#define MCA_TS_GATE_ROOM 0.25

/* mca-ts, before the solve: each arm's target rate and rate bounds from the deadlock state and the gates. */
static void ts_plan(mca_controller_t *ctrl, double task_t, double target[], double lo[], double hi[]) {
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
static void ts_advance(mca_controller_t *ctrl, mca_tick_info_t *info, const int ts_off[],
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
static void exact_check(mca_controller_t *ctrl, int a, double tau) {
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
static void fill_path_info(mca_controller_t *ctrl, mca_tick_info_t *info) {
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
            distances(ctrl, info);
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
        exact_check(ctrl, a, ts ? ctrl->tau[a] : info->task_t);
    }
    info->exact_met = ctrl->exact_met;
    info->exact_missed = ctrl->exact_missed;
    info->exact_error_max = ctrl->exact_error_max;

    /* 3. distances */
    if (distances(ctrl, info) != MCA_OK) {
        raise_fault(ctrl, MCA_CTRL_FAULT_NAN, (mca_ctrl_fault_why_t){.why = MCA_WHY_DISTANCES});
        goto fault;
    }
    const double d1 = cfg->sp.d1;
    if (cfg->fault_distance && info->min_distance < d1) {
        raise_fault(ctrl, MCA_CTRL_FAULT_DISTANCE, why_distance(MCA_WHY_BELOW_D1, info, d1));
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
        info->brake = si.brake;
        int ts_off[MCA_MAX_ARMS] = {0};
        double target[MCA_MAX_ARMS], lo[MCA_MAX_ARMS], hi[MCA_MAX_ARMS]; /* mca-ts: the rates' plan */
        if (ts) {
            ts_plan(ctrl, info->task_t, target, lo, hi);
            accel_box(ctrl, &si, na); /* first: the lists keep the pairs this box can bring to a bound */
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
                tube_keep_brake(ctrl, &si, a, rdot_d[a], lo[a], hi[a], slack_lo[a], slack_hi[a]);
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
            near_links(ctrl, &ctrl->qp, &si, cfg->ts.dec_limit, cfg->ts.priority);
            rc = mca_scheme_near_rows(&ctrl->qp, &si, na, chains, ctrl->kin,
                                      (const mca_link_critical_t(*)[MCA_MAX_LINKS][MCA_NEAR_PAIRS])ctrl->near,
                                      &cfg->sp, cfg->ts.dec_limit, cfg->ts.priority);
            if (rc != MCA_OK) {
                raise_fault(ctrl, MCA_CTRL_FAULT_INPUT,
                            (mca_ctrl_fault_why_t){.why = MCA_WHY_ASSEMBLY, .i = {rc}});
                goto fault;
            }
            info->brake = si.brake;
            mca_scheme_prune_rows(&ctrl->qp, cfg->sp.big, &si); /* rows the box cannot reach */
            compact_rows(&ctrl->qp, cfg->sp.big, &si, &ctrl->pdnn, ctrl->row_key, &ctrl->n_row_key);
        }
        info->active_rows = si.active_rows;
        mca_pdnn_result_t pr = {0};
        const mca_pdnn_params_t prm = pdnn_params(cfg, t_enter);
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
        const int hit = budget_hit(cfg, rc, &pr);
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
                repair_capped(ctrl, &si, na, ts_off, target); /* at the cap and at the budget alike */
            }
            ts_advance(ctrl, info, ts_off, (const double(*)[3])rdot_d, target, lo, hi);
        } else if (short_answer && hit != MCA_BUDGET_NONE && !(eq > cfg->eq_tol) &&
                   repair_scaled(ctrl) >= 0.0) {
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
    memcpy(ctrl->phi_prev, ctrl->phi, sizeof ctrl->phi_prev);
    ctrl->min_distance_prev = info->min_distance;
    ctrl->has_prev = 1;
    ctrl->ticks++;
    info->fault = MCA_CTRL_FAULT_NONE;
    info->fault_why = (mca_ctrl_fault_why_t){0};
    fill_path_info(ctrl, info);
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
        fill_path_info(ctrl, info);
    }
    ctrl->has_v_meas = 0;
    info->compute_ns = now_ns() - t_enter;
    return MCA_EFAULT;
}

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
    near_links(ctrl, qp, &si, row_dec, row_priority);
    rc = mca_scheme_near_rows(qp, &si, na, chains, ctrl->kin,
                              (const mca_link_critical_t(*)[MCA_MAX_LINKS][MCA_NEAR_PAIRS])ctrl->near, &sp,
                              row_dec, row_priority);
    if (rc != MCA_OK) {
        return rc;
    }
    mca_scheme_prune_rows(qp, sp.big, &si); /* rows the deceleration box cannot reach */
    compact_rows(qp, sp.big, &si, &ctrl->brake_pdnn, ctrl->brake_row_key, &ctrl->n_brake_row_key);
    mca_pdnn_result_t pr = {0};
    double phi[MCA_QP_MAX_VARS];
    const mca_pdnn_params_t prm = pdnn_params(cfg, t_enter); /* out of time: the keep-direction fallback */
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
