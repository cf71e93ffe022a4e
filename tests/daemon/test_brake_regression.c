/* SPDX-License-Identifier: MIT */
/* Issue 11, the braking bug: mcad used to brake by ramping every joint's last command down at its
 * dec_limit on its own, ignoring the other arm; stopped while two arms approach fast with a low dec_limit
 * the arms coasted below d1. Now every stop brakes through mca_controller_brake (collision rows inside the
 * deceleration box). This test runs the same stop both ways from the same state, in virtual time through
 * mca_drive_step on the sim backend:
 *   new: mca_daemon_request_stop, then mca_drive_step to rest (the daemon's braking);
 *   old: the per-joint ramp re-enacted here (commands written to the same sim arms, distances measured by
 *        mca_controller_observe on a copy of the daemon's controller).
 * and asserts old < d1 <= new, every per-tick velocity change <= dec_limit dt, and the stop's length bound.
 *   test_brake_regression SOURCE_DIR                     the shipped case (ctest)
 *   test_brake_regression SOURCE_DIR SCENARIO SCHEME DEC T...   exploration: one line per stop time
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "mca/cell.h"
#include "mca/daemon.h"
#include "mca/daemon_drive.h"
#include "mca/err.h"
#include "mca/scenario.h"
#include "mca/sim_backend.h"

#include "log_sink.h" /* test_log_line */

typedef struct {
    int ok;            /* 0: the task faulted or stopped before T */
    double d_new;      /* minimum distance while braking, daemon (new) */
    double d_old;      /* the same, old per-joint ramp */
    double dv_new;     /* max |dv| / (dec dt), daemon */
    double t_new;      /* stop length [s], daemon */
    double t_old;      /* stop length [s], ramp */
    double vmax;       /* max |v| / dec at the stop [s] */
    uint64_t fallback; /* keep-direction ticks */
} outcome_t;

static mca_daemon_t *open_at(const mca_cell_t *cell, int k_stop, double dt, int *ok) {
    const mca_drive_opts_t o = {.daemon = {.no_dds = 1, .log = test_log_line, .log_arg = stderr}};
    mca_daemon_t *d = NULL;
    char err[512] = "";
    if (mca_drive_open(&d, cell, &o, err, sizeof err) != MCA_OK) {
        fprintf(stderr, "open: %s\n", err);
        exit(2);
    }
    *ok = 1;
    for (int k = 0; k < k_stop; k++) {
        if (mca_drive_step(d, k * dt, 0) != MCA_DAEMON_RUNNING) {
            *ok = 0;
        }
    }
    mca_daemon_service(d);
    return d;
}

static outcome_t run(const mca_cell_t *cell, double T) {
    outcome_t r = {0};
    const double dt = (double)cell->rt.period_ns * 1e-9;
    const int K = (int)llround(T / dt);
    /* new: the daemon's stop */
    mca_daemon_t *d = open_at(cell, K, dt, &r.ok);
    if (!r.ok) {
        mca_daemon_close(d);
        return r;
    }
    const mca_controller_t *ctrl = mca_drive_controller(d);
    const int na = mca_controller_get_config(ctrl)->n_arms;
    r.vmax = 0.0;
    for (int a = 0; a < na; a++) {
        const mca_arm_command_t *c = mca_drive_last_command(d, a);
        for (int j = 0; j < c->n; j++) {
            r.vmax = fmax(r.vmax, fabs(c->velocity[j]) / cell->arm[a].dec_limit[j]);
        }
    }
    mca_daemon_request_stop(d);
    r.d_new = INFINITY;
    int k = K, st;
    do {
        st = mca_drive_step(d, k * dt, 0);
        r.d_new = fmin(r.d_new, mca_drive_tick_info(d)->min_distance);
        k++;
    } while (st == MCA_DAEMON_BRAKING && k < K + 100000);
    for (int i = 0; i < 50; i++, k++) { /* the arms' own last cycles */
        mca_drive_step(d, k * dt, 0);
        r.d_new = fmin(r.d_new, mca_drive_tick_info(d)->min_distance);
    }
    mca_daemon_service(d);
    mca_daemon_summary_t s;
    mca_daemon_summary(d, &s);
    r.dv_new = s.max_dv_over_dt_dec;
    r.t_new = s.stop_duration_s;
    r.fallback = s.brake_fallback_ticks;
    mca_daemon_close(d);

    /* old: the same state, each joint ramped down on its own */
    d = open_at(cell, K, dt, &r.ok);
    mca_controller_t *obs = malloc(mca_controller_size());
    mca_controller_copy(obs, mca_drive_controller(d));
    double v[MCA_MAX_ARMS][MCA_MAX_DOF] = {{0}}, q[MCA_MAX_ARMS][MCA_MAX_DOF] = {{0}};
    const double *qp[MCA_MAX_ARMS];
    mca_arm_command_t cmd[MCA_MAX_ARMS];
    for (int a = 0; a < MCA_MAX_ARMS; a++) {
        qp[a] = q[a];
    }
    for (int a = 0; a < na; a++) {
        cmd[a] = *mca_drive_last_command(d, a);
        memcpy(v[a], cmd[a].velocity, sizeof v[a]);
        memcpy(q[a], mca_drive_positions(d, a), sizeof q[a]);
    }
    r.d_old = INFINITY;
    int n = 0, moving = 1;
    mca_tick_info_t info;
    memset(&info, 0, sizeof info);
    for (k = K; moving && k < K + 100000; k++, n++) {
        moving = 0;
        for (int a = 0; a < na; a++) {
            mca_arm_t *arm = mca_drive_arm(d, a);
            mca_arm_feedback_t fb;
            if (n > 0 && mca_arm_read(arm, &fb) == MCA_OK) {
                memcpy(q[a], fb.position, sizeof q[a]);
            }
        }
        if (mca_controller_observe(obs, k * dt, qp, &info) == MCA_OK) {
            r.d_old = fmin(r.d_old, info.min_distance);
        }
        for (int a = 0; a < na; a++) {
            mca_arm_t *arm = mca_drive_arm(d, a);
            for (int j = 0; j < cmd[a].n; j++) {
                const double step = cell->arm[a].dec_limit[j] * dt;
                v[a][j] = fabs(v[a][j]) <= step ? 0.0 : v[a][j] - (v[a][j] > 0 ? step : -step);
                cmd[a].velocity[j] = v[a][j];
                cmd[a].position_ref[j] = q[a][j] + v[a][j] * dt;
            }
            cmd[a].frame_id++;
            mca_arm_write(arm, &cmd[a]);
            const mca_sim_arm_t *fw = mca_sim_backend_firmware(arm);
            for (int j = 0; j < fw->cfg.n; j++) {
                moving |= fw->v[j] != 0.0;
            }
        }
        if (!moving) {
            r.t_old = n * dt;
        }
    }
    for (int a = 0; a < na; a++) { /* where the arms came to rest */
        mca_arm_feedback_t fb;
        if (mca_arm_read(mca_drive_arm(d, a), &fb) == MCA_OK) {
            memcpy(q[a], fb.position, sizeof q[a]);
        }
    }
    if (mca_controller_observe(obs, k * dt, qp, &info) == MCA_OK) {
        r.d_old = fmin(r.d_old, info.min_distance);
    }
    free(obs);
    mca_daemon_close(d);
    return r;
}

static mca_cell_t *make_cell(const char *scenario, const char *scheme, double dec) {
    static mca_scenario_t scn;
    char err[512];
    if (mca_scenario_load(scenario, &scn, err, sizeof err) != MCA_OK) {
        fprintf(stderr, "%s\n", err);
        exit(2);
    }
    mca_scheme_kind_t sk;
    if (mca_scheme_from_name(scheme, &sk) != MCA_OK) {
        fprintf(stderr, "unknown scheme %s\n", scheme);
        exit(2);
    }
    mca_cell_t *cell = calloc(1, sizeof *cell);
    if (mca_cell_from_scenario(cell, &scn, sk) != MCA_OK) {
        exit(2);
    }
    for (int a = 0; a < MCA_MAX_ARMS; a++) {
        for (int j = 0; j < MCA_MAX_DOF; j++) {
            cell->arm[a].dec_limit[j] = dec;
        }
    }
    return cell;
}

static void print(double T, const outcome_t *r, double d1) {
    if (!r->ok) {
        printf("T %.3f: the task did not run to T\n", T);
        return;
    }
    printf("T %.3f: max|v|/dec %.3f s; old ramp: min %.5f m%s, %.3f s; new brake: min %.5f m%s, %.3f s, max "
           "|dv|/(dec dt) %.6f, fallback ticks %llu\n",
           T, r->vmax, r->d_old, r->d_old < d1 ? " (BELOW d1)" : "", r->t_old, r->d_new,
           r->d_new < d1 ? " (BELOW d1)" : "", r->t_new, r->dv_new, (unsigned long long)r->fallback);
}

int main(int argc, char **argv) {
    if (argc < 2) {
        fprintf(stderr, "usage: %s SOURCE_DIR [SCENARIO SCHEME DEC T...]\n", argv[0]);
        return 2;
    }
    if (argc >= 6) {
        mca_cell_t *cell = make_cell(argv[2], argv[3], atof(argv[4]));
        for (int i = 5; i < argc; i++) {
            const outcome_t r = run(cell, atof(argv[i]));
            print(atof(argv[i]), &r, cell->scn.params.d1);
        }
        free(cell);
        return 0;
    }
    char path[600];
    snprintf(path, sizeof path, "%s/" REGRESSION_SCENARIO, argv[1]);
    mca_cell_t *cell = make_cell(path, REGRESSION_SCHEME, REGRESSION_DEC);
    const double d1 = cell->scn.params.d1, dt = (double)cell->rt.period_ns * 1e-9;
    const outcome_t r = run(cell, REGRESSION_T);
    print(REGRESSION_T, &r, d1);
    int f = 0;
    if (!r.ok) {
        printf("FAIL: the task did not run to the stop\n");
        f = 1;
    }
    if (!(r.d_old < d1)) {
        printf("FAIL: the old per-joint ramp no longer goes below d1 here: the case does not show the bug\n");
        f = 1;
    }
    if (!(r.d_new >= d1)) {
        printf("FAIL: braking through the controller went below d1 (%.5f m < %.3f m)\n", r.d_new, d1);
        f = 1;
    }
    if (!(r.dv_new <= 1.0 + 1e-9)) {
        printf("FAIL: a per-tick velocity change above dec_limit dt (ratio %.6f)\n", r.dv_new);
        f = 1;
    }
    if (!(r.t_new >= 0.0 && r.t_new <= 1.5 * r.vmax + 20 * dt + r.vmax + 2 * dt)) {
        printf("FAIL: the stop took %.3f s (bound %.3f s)\n", r.t_new, 2.5 * r.vmax + 22 * dt);
        f = 1;
    }
    free(cell);
    if (!f) {
        printf("ok: the old ramp went below d1, the controller's brake kept d1 within the dec limit\n");
    }
    return f;
}
