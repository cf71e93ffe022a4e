/* SPDX-License-Identifier: MIT */
/*
 * mca-stopcheck: stops that keep the distance, checked along a whole task.
 *
 *   mca-stopcheck --scenario FILE [--scheme mca-ts|mca|mvn] [--every S] [--dec X[,X...]] [--json OUT]
 *
 * For each deceleration limit X (rad/s^2, every joint) the task runs once, arms integrated exactly as
 * commanded (q += qdot dt). Every S seconds (0.02) a copy of the controller and of the arms branches off
 * and brakes through mca_controller_brake() until every joint is at rest, as mcad does on SIGTERM or a
 * fault. Reported per X: branches, the least distance over the task and over every brake, the largest
 * per-tick velocity change as a fraction of X dt (<= 1 is within the limit), the longest stop, and how
 * many braking ticks needed the keep-direction fallback. Exit 1 when any tick (task or brake) is below d1
 * or any velocity change exceeds X dt, 0 otherwise, 2 on bad input.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "mca/controller.h"
#include "mca/err.h"
#include "mca/scenario.h"

typedef struct stop_figures {
    double dec;
    int branches;
    int below_d1;        /* branches with a tick below d1 */
    double min_task;     /* least distance along the task */
    double min_brake;    /* least distance over all brakes */
    double max_dv_ratio; /* largest |v_k - v_{k-1}| / (dec dt) while braking */
    double max_stop_s;   /* longest stop */
    long fallback_ticks; /* braking ticks that used the keep-direction fallback */
    long brake_ticks;
    int task_fault;      /* the task's own fault (the last branch then starts from it) */
    int below_clear;     /* branches with a tick inside a fixed body's clearance */
    double margin_task;  /* least fixed-body margin d - clearance along the task (+INF: no bodies) */
    double margin_brake; /* the same over all brakes */
    double task_end;
} stop_figures_t;

static void usage(void) {
    fprintf(stderr, "usage: mca-stopcheck --scenario FILE [--scheme mca-ts|mca|mvn] [--every S] "
                    "[--dec X[,X...]] [--json OUT]\n");
}

/* Brake the copy until rest; figures into f. */
static void branch(mca_controller_t *c, double t, double q[MCA_MAX_ARMS][MCA_MAX_DOF],
                   const double v0[MCA_MAX_ARMS][MCA_MAX_DOF], double dec, stop_figures_t *f) {
    const mca_controller_config_t *cfg = mca_controller_get_config(c);
    const double dt = cfg->dt, d1 = cfg->sp.d1;
    double v[MCA_MAX_ARMS][MCA_MAX_DOF], cmd[MCA_MAX_ARMS][MCA_MAX_DOF], decs[MCA_MAX_ARMS][MCA_MAX_DOF];
    const double *qp[MCA_MAX_ARMS], *vp[MCA_MAX_ARMS], *dp[MCA_MAX_ARMS];
    double *cp[MCA_MAX_ARMS];
    for (int a = 0; a < MCA_MAX_ARMS; a++) {
        for (int j = 0; j < MCA_MAX_DOF; j++) {
            v[a][j] = v0[a][j];
            decs[a][j] = dec;
        }
        qp[a] = q[a];
        vp[a] = v[a];
        dp[a] = decs[a];
        cp[a] = cmd[a];
    }
    /* the longest stop the limit allows, with a margin: a brake that lasts longer is reported as such */
    const int max_ticks = (int)(20.0 / (dec * dt)) + 1000;
    mca_tick_info_t info;
    int k, below = 0, inside = 0;
    for (k = 0; k < max_ticks; k++) {
        const int rest = mca_controller_brake(c, t + k * dt, qp, vp, dp, cp, &info);
        if (rest < 0) {
            break;
        }
        f->brake_ticks++;
        f->fallback_ticks += info.brake_fallback;
        if (isfinite(info.min_distance)) {
            f->min_brake = fmin(f->min_brake, info.min_distance);
            below |= info.min_distance < d1;
        }
        f->margin_brake = fmin(f->margin_brake, info.body_margin);
        inside |= info.body_margin < 0.0;
        for (int a = 0; a < cfg->n_arms; a++) {
            for (int j = 0; j < cfg->chain[a].dof; j++) {
                f->max_dv_ratio = fmax(f->max_dv_ratio, fabs(cmd[a][j] - v[a][j]) / (dec * dt));
                v[a][j] = cmd[a][j];
                q[a][j] += cmd[a][j] * dt;
            }
        }
        if (rest == 1) {
            break;
        }
    }
    /* the pose it came to rest in */
    if (mca_controller_observe(c, t + (k + 1) * dt, qp, &info) == MCA_OK && isfinite(info.min_distance)) {
        f->min_brake = fmin(f->min_brake, info.min_distance);
        below |= info.min_distance < d1;
    }
    f->margin_brake = fmin(f->margin_brake, info.body_margin);
    inside |= info.body_margin < 0.0;
    f->max_stop_s = fmax(f->max_stop_s, (k + 1) * dt);
    f->below_d1 += below;
    f->below_clear += inside;
    f->branches++;
}

static int run(const mca_scenario_t *scn, mca_scheme_kind_t scheme, double every, double dec,
               stop_figures_t *f, void *mem, mca_controller_t *copy) {
    mca_controller_config_t *cfg = malloc(sizeof *cfg);
    char err[512];
    if (!cfg) {
        return MCA_ENOMEM;
    }
    int rc = mca_controller_config_from_scenario(cfg, scn, scheme, err, sizeof err);
    if (rc != MCA_OK) {
        fprintf(stderr, "mca-stopcheck: %s\n", err);
        free(cfg);
        return rc;
    }
    for (int a = 0; a < cfg->n_arms; a++) {
        cfg->ts.dec_limit[a] = dec;
    }
    mca_controller_t *ctrl;
    rc = mca_controller_create(mem, mca_controller_size(), cfg, &ctrl);
    if (rc != MCA_OK) {
        fprintf(stderr, "mca-stopcheck: controller init: %s\n", mca_strerror(rc));
        free(cfg);
        return rc;
    }
    const double dt = cfg->dt;
    double end = scn->duration;
    if (scheme == MCA_SCHEME_MCA_TS) {
        end *= 2.0; /* room for path time lost; the run ends when every path clock has */
    }
    double q[MCA_MAX_ARMS][MCA_MAX_DOF] = {{0}}, qd[MCA_MAX_ARMS][MCA_MAX_DOF] = {{0}},
           qb[MCA_MAX_ARMS][MCA_MAX_DOF];
    const double *qp[MCA_MAX_ARMS];
    double *qdp[MCA_MAX_ARMS];
    for (int a = 0; a < MCA_MAX_ARMS; a++) {
        qp[a] = q[a];
        qdp[a] = qd[a];
        for (int j = 0; a < cfg->n_arms && j < cfg->chain[a].dof; j++) {
            q[a][j] = scn->arm[a].q0[j];
        }
    }
    memset(f, 0, sizeof *f);
    f->dec = dec;
    f->min_task = f->min_brake = INFINITY;
    f->margin_task = f->margin_brake = INFINITY;
    const long n = lround(end / dt), step = lround(every / dt) > 0 ? lround(every / dt) : 1;
    mca_tick_info_t info;
    long k;
    for (k = 0; k <= n; k++) {
        const double t = k * dt;
        double v_last[MCA_MAX_ARMS][MCA_MAX_DOF];
        memcpy(v_last, qd, sizeof v_last);
        if (k > 0 && k % step == 0) {
            /* the stop request arrives before this tick: brake from the last command */
            mca_controller_copy(copy, ctrl);
            memcpy(qb, q, sizeof qb);
            branch(copy, t, qb, (const double(*)[MCA_MAX_DOF])v_last, dec, f);
        }
        const int trc = mca_controller_tick(ctrl, t, qp, qdp, &info);
        if (isfinite(info.min_distance)) {
            f->min_task = fmin(f->min_task, info.min_distance);
        }
        f->margin_task = fmin(f->margin_task, info.body_margin);
        if (trc != MCA_OK) {
            /* a fault brakes from the last command, exactly as a stop */
            f->task_fault = info.fault;
            char why[192];
            fprintf(stderr, "mca-stopcheck: dec %.3g: task fault at t = %.3f s: %s\n", dec, t,
                    mca_ctrl_fault_format(&info.fault_why, why, sizeof why));
            mca_controller_copy(copy, ctrl);
            memcpy(qb, q, sizeof qb);
            branch(copy, t, qb, (const double(*)[MCA_MAX_DOF])v_last, dec, f);
            break;
        }
        if (scheme == MCA_SCHEME_MCA_TS && info.paths_done && t >= scn->duration) {
            break;
        }
        for (int a = 0; a < cfg->n_arms; a++) {
            for (int j = 0; j < cfg->chain[a].dof; j++) {
                q[a][j] += qd[a][j] * dt;
            }
        }
    }
    f->task_end = k * dt;
    free(cfg);
    return MCA_OK;
}

int main(int argc, char **argv) {
    const char *scenario = NULL, *json = NULL, *scheme_name = "mca-ts", *decs = "0.5,2,5";
    double every = 0.02;
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        const char *v = i + 1 < argc ? argv[i + 1] : NULL;
        if (!strcmp(a, "--scenario") && v) {
            scenario = v;
        } else if (!strcmp(a, "--scheme") && v) {
            scheme_name = v;
        } else if (!strcmp(a, "--every") && v) {
            every = atof(v);
        } else if (!strcmp(a, "--dec") && v) {
            decs = v;
        } else if (!strcmp(a, "--json") && v) {
            json = v;
        } else {
            usage();
            return 2;
        }
        i++;
    }
    mca_scheme_kind_t scheme;
    if (!scenario || mca_scheme_from_name(scheme_name, &scheme) != MCA_OK || scheme == MCA_SCHEME_APF ||
        !(every > 0.0)) {
        usage();
        return 2;
    }
    static mca_scenario_t scn;
    char err[512];
    if (mca_scenario_load(scenario, &scn, err, sizeof err) != MCA_OK) {
        fprintf(stderr, "mca-stopcheck: %s\n", err);
        return 2;
    }
    /* the controller's storage and its braking copy's (mca_controller_create) */
    void *ctrl = malloc(mca_controller_size());
    mca_controller_t *copy = malloc(mca_controller_size());
    if (!ctrl || !copy) {
        return 2;
    }
    stop_figures_t fig[8];
    int n_fig = 0, bad = 0;
    char buf[128];
    snprintf(buf, sizeof buf, "%s", decs);
    for (char *tok = strtok(buf, ","); tok && n_fig < 8; tok = strtok(NULL, ",")) {
        const double dec = atof(tok);
        if (!(dec > 0.0)) {
            fprintf(stderr, "mca-stopcheck: --dec: '%s' is not a positive number\n", tok);
            return 2;
        }
        if (run(&scn, scheme, every, dec, &fig[n_fig], ctrl, copy) != MCA_OK) {
            return 2;
        }
        const stop_figures_t *f = &fig[n_fig++];
        const int fail = f->below_d1 > 0 || f->min_task < scn.params.d1 || f->max_dv_ratio > 1.0 + 1e-9 ||
                         f->below_clear > 0 || f->margin_task < 0.0;
        bad |= fail;
        printf("%s %s dec %.3g: %d stops, %d below d1; min distance task %.4f m, brakes %.4f m (d1 %.3f); "
               "max |dv| / (dec dt) %.4f; longest stop %.3f s; fallback %ld of %ld braking ticks; task fault "
               "%s%s\n",
               scn.name, scheme_name, dec, f->branches, f->below_d1, f->min_task, f->min_brake, scn.params.d1,
               f->max_dv_ratio, f->max_stop_s, f->fallback_ticks, f->brake_ticks,
               mca_ctrl_fault_name(f->task_fault), fail ? "  FAIL" : "");
        if (scn.n_bodies > 0) {
            printf(
                "%s %s dec %.3g: fixed bodies: %d stops inside a clearance; least margin task %.4f m, brakes "
                "%.4f m\n",
                scn.name, scheme_name, dec, f->below_clear, f->margin_task, f->margin_brake);
        }
    }
    if (json) {
        FILE *out = fopen(json, "w");
        if (!out) {
            fprintf(stderr, "mca-stopcheck: --json %s: cannot write\n", json);
            return 2;
        }
        fprintf(out, "{\"scenario\":\"%s\",\"scheme\":\"%s\",\"d1\":%.9g,\"every\":%.6g,\"runs\":[", scn.name,
                scheme_name, scn.params.d1, every);
        for (int i = 0; i < n_fig; i++) {
            const stop_figures_t *f = &fig[i];
            fprintf(out,
                    "%s{\"dec\":%.6g,\"stops\":%d,\"below_d1\":%d,\"min_distance_task\":%.9g,"
                    "\"min_distance_brake\":%.9g,\"max_dv_ratio\":%.9g,\"longest_stop_s\":%.6g,"
                    "\"fallback_ticks\":%ld,\"brake_ticks\":%ld,\"task_fault\":\"%s\",\"task_end_s\":%.6g,"
                    "\"below_clearance\":%d,\"body_margin_task\":%.9g,\"body_margin_brake\":%.9g}",
                    i ? "," : "", f->dec, f->branches, f->below_d1, f->min_task,
                    isfinite(f->min_brake) ? f->min_brake : -1.0, f->max_dv_ratio, f->max_stop_s,
                    f->fallback_ticks, f->brake_ticks, mca_ctrl_fault_name(f->task_fault), f->task_end,
                    f->below_clear, isfinite(f->margin_task) ? f->margin_task : -1.0,
                    isfinite(f->margin_brake) ? f->margin_brake : -1.0);
        }
        fprintf(out, "]}\n");
        fclose(out);
    }
    free(ctrl);
    free(copy);
    return bad ? 1 : 0;
}
