/* SPDX-License-Identifier: MIT */
/* The controller's set-up and state (configuration, init, reset, the coordination plan, streamed targets,
 * faults and their text, observe); the tick is controller_tick.c, its rooms controller_*.c. See
 * mca/controller.h. */
#include "mca/controller.h"

#include <math.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "mca/err.h"
#include "mca/vec3.h"

#include "controller__common.h"
#include "controller__dist.h"

/* The size mca/controller.h states: the state fits its bound and is not far below it (the figure to plan
 * for), and malloc's alignment suits it. */
_Static_assert(sizeof(struct mca_controller) <= MCA_CONTROLLER_SIZE_MAX,
               "the controller's state outgrew MCA_CONTROLLER_SIZE_MAX: update it and its docs");
_Static_assert(sizeof(struct mca_controller) > MCA_CONTROLLER_SIZE_MAX / 10 * 9,
               "the controller's state is far below MCA_CONTROLLER_SIZE_MAX: update it and its docs");
_Static_assert(_Alignof(struct mca_controller) <= _Alignof(max_align_t),
               "malloc'd storage must suit the controller's state");

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

int mca_controller_has_self(const mca_controller_config_t *cfg) {
    for (int a = 0; cfg && a < cfg->n_arms && a < MCA_MAX_ARMS; a++) {
        for (int l = 1; l < MCA_MAX_LINKS; l++) {
            if (cfg->self[a][l] & ((1u << l) - 1u)) {
                return 1;
            }
        }
    }
    return 0;
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
    cfg->body_rows = 1;
    mca_ssm_default(&cfg->ssm);
    cfg->self_rows = 1;
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

size_t mca_controller_size(void) {
    return sizeof(struct mca_controller);
}

int mca_controller_create(void *storage, size_t size, const mca_controller_config_t *cfg,
                          mca_controller_t **out) {
    if (out) {
        *out = NULL;
    }
    if (!storage || !out || size < sizeof(struct mca_controller) ||
        (uintptr_t)storage % _Alignof(struct mca_controller) != 0) {
        return MCA_EINVAL;
    }
    const int rc = mca_controller_init(storage, cfg);
    if (rc == MCA_OK) {
        *out = storage;
    }
    return rc;
}

void mca_controller_copy(mca_controller_t *dst, const mca_controller_t *src) {
    if (dst && src && dst != src) {
        memcpy(dst, src, sizeof *dst);
    }
}

const mca_controller_config_t *mca_controller_get_config(const mca_controller_t *ctrl) {
    return &ctrl->cfg;
}

int mca_controller_started(const mca_controller_t *ctrl) {
    return ctrl->started;
}

const mca_kin_t *mca_controller_kin(const mca_controller_t *ctrl, int arm) {
    return arm >= 0 && arm < MCA_MAX_ARMS ? &ctrl->kin[arm] : NULL;
}

const mca_arm_distances_t (*mca_controller_distances(const mca_controller_t *ctrl))[MCA_MAX_ARMS] {
    return (const mca_arm_distances_t(*)[MCA_MAX_ARMS])ctrl->dist;
}

const mca_path_rate_t *mca_controller_path_rate(const mca_controller_t *ctrl, int arm) {
    return arm >= 0 && arm < MCA_MAX_ARMS ? &ctrl->rate[arm] : NULL;
}

const mca_coord_t *mca_controller_coord(const mca_controller_t *ctrl) {
    return &ctrl->coord;
}

int mca_controller_set_pdnn_budget(mca_controller_t *ctrl, int64_t budget_ns) {
    if (!ctrl || budget_ns < 0) {
        return MCA_EINVAL;
    }
    ctrl->cfg.pdnn_budget_ns = budget_ns;
    return MCA_OK;
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
    if (cfg->n_bodies < 0 || cfg->n_bodies > MCA_MAX_BODIES || cfg->max_tracks < 0 ||
        cfg->max_tracks > MCA_MAX_TRACKS || cfg->n_bodies + cfg->max_tracks > MCA_MAX_BODIES ||
        (cfg->max_tracks > 0 && mca_ssm_check(&cfg->ssm) != MCA_OK)) {
        return MCA_EINVAL;
    }
    for (int k = 0; k < cfg->n_bodies; k++) {
        if (mca_body_check(&cfg->body[k]) != MCA_OK) {
            return MCA_EINVAL;
        }
    }
    memset(ctrl, 0, sizeof *ctrl);
    ctrl->cfg = *cfg;
    ctrl->cfg.sp.collision = uses_rows(cfg->scheme);
    /* the fixed bodies' rows keep slots after each arm's own (none without bodies: the layout of before) */
    ctrl->cfg.sp.body_pairs = ((cfg->n_bodies + cfg->max_tracks > 0) && cfg->body_rows) ||
                                      (mca_controller_has_self(cfg) && cfg->self_rows)
                                  ? MCA_BODY_PAIRS
                                  : 0;
    ctrl->n_fixed = cfg->n_bodies;
    mca_controller_ssm_arms(cfg, &ctrl->track_arm_speed, &ctrl->track_stop_time);
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
    memset(ctrl->rate, 0, sizeof ctrl->rate);
    ctrl->brake_pdnn.h = 0;
    ctrl->n_row_key = ctrl->n_brake_row_key = 0;
}

int mca_controller_plan(mca_controller_t *ctrl, const double *const q[MCA_MAX_ARMS], mca_coord_work_t *work) {
    if (!ctrl || !q || !work) {
        return MCA_EINVAL;
    }
    const mca_controller_config_t *cfg = &ctrl->cfg;
    memset(&ctrl->coord, 0, sizeof ctrl->coord);
    memset(ctrl->rate, 0, sizeof ctrl->rate);
    if (cfg->scheme != MCA_SCHEME_MCA_TS) {
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
        if (mca_path_rate_plan(&arms[a], cfg->ts.dec_limit[a], cfg->ts.sigma_max, work->q, &ctrl->rate[a]) !=
            MCA_OK) {
            return MCA_EINVAL;
        }
    }
    if (!cfg->ts.coordinate) {
        return MCA_OK;
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

int mca_controller_stream_target(mca_controller_t *ctrl, int arm, mca_stream_kind_t kind, const double x[3],
                                 const mca_stream_law_t *law) {
    if (!ctrl || !law || (kind != MCA_STREAM_HOLD && !x) || arm < 0 || arm >= ctrl->cfg.n_arms) {
        return MCA_EINVAL;
    }
    double v[3] = {0.0, 0.0, 0.0};
    const int finite = kind != MCA_STREAM_HOLD && isfinite(x[0]) && isfinite(x[1]) && isfinite(x[2]);
    if (finite && kind == MCA_STREAM_TWIST) {
        mca_v3_set(v, x);
    } else if (finite && kind == MCA_STREAM_POSE && ctrl->started) {
        /* towards the target from where the reference is now */
        const double *r = ctrl->cfg.path[arm].stream_r;
        for (int i = 0; i < 3; i++) {
            v[i] = law->pose_gain * (x[i] - r[i]);
        }
    }
    const double n = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    for (int i = 0; i < 3 && n > law->max_speed; i++) {
        v[i] *= law->max_speed / n;
    }
    return mca_controller_stream(ctrl, arm, v);
}

void mca_controller_ssm_arms(const mca_controller_config_t *cfg, double *arm_speed, double *t_stop) {
    *arm_speed = *t_stop = 0.0;
    for (int a = 0; a < cfg->n_arms; a++) {
        /* the fastest arm and the longest stop (dec_limit 0: no braking time known, T_s 0) */
        *arm_speed = fmax(*arm_speed, mca_chain_point_speed(&cfg->chain[a]));
        *t_stop = fmax(*t_stop, mca_scheme_stop_time(&cfg->chain[a], cfg->ts.dec_limit[a]));
    }
}

int mca_controller_set_tracks(mca_controller_t *ctrl, const mca_track_t *tracks, int n, double t) {
    if (!ctrl || n < 0 || n > ctrl->cfg.max_tracks || (n > 0 && !tracks)) {
        return MCA_EINVAL;
    }
    mca_fixed_body_t body[MCA_MAX_TRACKS];
    mca_ssm_terms_t terms[MCA_MAX_TRACKS];
    for (int k = 0; k < n; k++) {
        if (mca_track_body(&ctrl->cfg.ssm, &tracks[k], t, ctrl->track_arm_speed, ctrl->track_stop_time,
                           &body[k], &terms[k]) != MCA_OK) {
            return MCA_EINVAL;
        }
    }
    for (int k = 0; k < n; k++) {
        ctrl->cfg.body[ctrl->n_fixed + k] = body[k];
        ctrl->track_terms[k] = terms[k];
    }
    ctrl->cfg.n_bodies = ctrl->n_fixed + n;
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
    case MCA_WHY_SELF_BELOW_D1:
    case MCA_WHY_SELF_BELOW_D1_NEXT:
        snprintf(buf, len, "distance %.4f m %s d1 %.4f m between links %d and %d of arm %d", x[0],
                 w->why == MCA_WHY_SELF_BELOW_D1 ? "<" : "predicted to fall below", x[1], i[1], i[2], i[0]);
        break;
    case MCA_WHY_BELOW_CLEARANCE:
    case MCA_WHY_BELOW_CLEARANCE_NEXT:
        snprintf(buf, len, "distance %.4f m %s clearance %.4f m of fixed body %d (arm %d link %d)", x[0],
                 w->why == MCA_WHY_BELOW_CLEARANCE ? "<" : "predicted to fall below the", x[1], i[2], i[0],
                 i[1]);
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
    return mca_ctrl__distances(ctrl, info);
}
