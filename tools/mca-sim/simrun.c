/* SPDX-License-Identifier: MIT */
/* Virtual-time runner of a scenario through mca_controller_tick; see simrun.h. */
#include "simrun.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "mca/arm.h"
#include "mca/err.h"
#include "mca/sim_backend.h"

const char *mca_simrun_scheme_name(mca_scheme_kind_t s) {
    return mca_scheme_name(s);
}

void mca_simrun_default_opts(mca_simrun_opts_t *o) {
    memset(o, 0, sizeof *o);
    o->scheme = MCA_SCHEME_MCA;
    o->form = -1;
    o->overtime = -1.0;
    o->use_backend = 1;
    o->dump_every = 1;
    o->settle = 0.2;
    o->v_floor = -1.0;
}

static int cmp_i64(const void *a, const void *b) {
    const int64_t x = *(const int64_t *)a, y = *(const int64_t *)b;
    return (x > y) - (x < y);
}

static void csv_header(FILE *f, const mca_controller_config_t *cfg) {
    fprintf(f, "t");
    for (int a = 0; a < cfg->n_arms; a++) {
        for (int j = 0; j < cfg->chain[a].dof; j++) {
            fprintf(f, ",q%d_%d", a, j);
        }
    }
    for (int a = 0; a < cfg->n_arms; a++) {
        fprintf(f, ",ee%d_x,ee%d_y,ee%d_z,rd%d_x,rd%d_y,rd%d_z,err%d_x,err%d_y,err%d_z,err%d", a, a, a, a, a,
                a, a, a, a, a);
    }
    fprintf(f, ",min_d,arm_a,link_a,arm_b,link_b,p_x,p_y,p_z,e_x,e_y,e_z,brake,active_rows,binding_rows,"
               "pdnn_steps,pdnn_residual,eq_residual,compute_ns,fault");
    /* three or more arms: the distance of every pair too (min_d is only the smallest of them) */
    for (int a = 0; cfg->n_arms >= 3 && a < cfg->n_arms; a++) {
        for (int b = a + 1; b < cfg->n_arms; b++) {
            fprintf(f, ",d_%d_%d", a, b);
        }
    }
    fprintf(f, "\n");
}

static void csv_row(FILE *f, const mca_controller_config_t *cfg, const mca_controller_t *ctrl, double t,
                    double q[][MCA_MAX_DOF], const mca_tick_info_t *in) {
    fprintf(f, "%.4f", t);
    for (int a = 0; a < cfg->n_arms; a++) {
        for (int j = 0; j < cfg->chain[a].dof; j++) {
            fprintf(f, ",%.9g", q[a][j]);
        }
    }
    for (int a = 0; a < cfg->n_arms; a++) {
        fprintf(f, ",%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.4g,%.4g,%.4g,%.4g", in->ee[a][0], in->ee[a][1],
                in->ee[a][2], in->ee_desired[a][0], in->ee_desired[a][1], in->ee_desired[a][2],
                in->ee_desired[a][0] - in->ee[a][0], in->ee_desired[a][1] - in->ee[a][1],
                in->ee_desired[a][2] - in->ee[a][2], in->ee_error[a]);
    }
    fprintf(f, ",%.9g,%d,%d,%d,%d,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%d,%d,%d,%.3g,%.3g,%lld,%d",
            in->min_distance, in->min_arm_a, in->min_link_a, in->min_arm_b, in->min_link_b, in->min_p[0],
            in->min_p[1], in->min_p[2], in->min_e[0], in->min_e[1], in->min_e[2], in->brake, in->active_rows,
            in->binding_rows, in->pdnn_steps, in->pdnn_residual, in->eq_residual, (long long)in->compute_ns,
            in->fault);
    for (int a = 0; cfg->n_arms >= 3 && a < cfg->n_arms; a++) {
        for (int b = a + 1; b < cfg->n_arms; b++) {
            fprintf(f, ",%.9g", ctrl->dist[a][b].min.d);
        }
    }
    fprintf(f, "\n");
}

int mca_simrun(const mca_scenario_t *scn, const mca_simrun_opts_t *o, mca_simrun_result_t *r, char *err,
               size_t errlen) {
    memset(r, 0, sizeof *r);
    snprintf(r->scheme, sizeof r->scheme, "%s", mca_simrun_scheme_name(o->scheme));
    mca_controller_config_t *cfg = calloc(1, sizeof *cfg);
    mca_controller_t *ctrl = calloc(1, sizeof *ctrl);
    mca_arm_t *arm[MCA_MAX_ARMS] = {0};
    int64_t *cns = NULL, *cpu = NULL;
    FILE *csv = NULL;
    int rc = MCA_OK;
    if (!cfg || !ctrl) {
        rc = MCA_ENOMEM;
        goto out;
    }
    rc = mca_controller_config_from_scenario(cfg, scn, o->scheme, err, errlen);
    if (rc != MCA_OK) {
        goto out;
    }
    if (o->form >= 0) {
        cfg->sp.form = (mca_collision_form_t)o->form;
    }
    if (o->v_normal > 0.0) {
        cfg->sp.v_normal = o->v_normal;
    }
    if (o->v_floor >= 0.0) {
        cfg->sp.v_floor = o->v_floor;
    }
    if (o->dist_lsdm) {
        cfg->dist_method = MCA_DIST_LSDM;
    }
    if (o->pdnn_max_steps > 0) {
        cfg->pdnn.max_steps = o->pdnn_max_steps;
    }
    for (int a = 0; a < cfg->n_arms; a++) {
        mca_sim_arm_config_t sc; /* the stoppability bound uses the (simulated) arm's deceleration */
        mca_sim_arm_config_from_chain(&sc, &cfg->chain[a]);
        cfg->ts.dec_limit[a] = sc.dec_limit[0];
        for (int j = 1; j < cfg->chain[a].dof; j++) {
            cfg->ts.dec_limit[a] = fmin(cfg->ts.dec_limit[a], sc.dec_limit[j]);
        }
    }
    rc = mca_controller_init(ctrl, cfg);
    if (rc != MCA_OK) {
        snprintf(err, errlen, "%s: controller init failed: %s", scn->source, mca_strerror(rc));
        goto out;
    }
    const int na = cfg->n_arms;
    const double dt = cfg->dt;
    const double duration = o->duration > 0.0 ? o->duration : scn->duration;
    const int n_ticks = (int)llround(duration / dt) + 1;
    const double overtime =
        o->scheme == MCA_SCHEME_MCA_TS ? (o->overtime < 0.0 ? duration : o->overtime) : 0.0;
    const int n_ticks_ts = n_ticks + (int)llround(overtime / dt);
    const int max_ticks = n_ticks_ts + (int)llround((o->settle + 5.0) / dt);
    double nominal_end = 0.0;
    for (int a = 0; a < cfg->n_arms; a++) {
        nominal_end = fmax(nominal_end, mca_path_end_time(&cfg->path[a]));
    }
    nominal_end = fmin(nominal_end, duration);
    cns = calloc((size_t)max_ticks, sizeof *cns);
    cpu = calloc((size_t)max_ticks, sizeof *cpu);
    if (!cns || !cpu) {
        rc = MCA_ENOMEM;
        goto out;
    }
    double q[MCA_MAX_ARMS][MCA_MAX_DOF] = {{0}}, qd[MCA_MAX_ARMS][MCA_MAX_DOF] = {{0}};
    const double *qp_[MCA_MAX_ARMS];
    double *qdp[MCA_MAX_ARMS];
    for (int a = 0; a < MCA_MAX_ARMS; a++) {
        qp_[a] = q[a];
        qdp[a] = qd[a];
    }
    mca_arm_command_t cmd[MCA_MAX_ARMS];
    memset(cmd, 0, sizeof cmd);
    for (int a = 0; a < na; a++) {
        const int dof = cfg->chain[a].dof;
        for (int j = 0; j < dof; j++) {
            q[a][j] = scn->arm[a].q0[j];
        }
        if (o->use_backend) {
            mca_sim_arm_config_t sc;
            mca_sim_arm_config_from_chain(&sc, &cfg->chain[a]);
            for (int j = 0; j < dof; j++) {
                sc.q0[j] = q[a][j];
            }
            sc.dt = dt;
            rc = mca_sim_backend_open(&arm[a], &sc, err, errlen);
            if (rc != MCA_OK) {
                goto out;
            }
            mca_arm_feedback_t fb;
            if (mca_arm_read(arm[a], &fb) == MCA_OK) {
                for (int j = 0; j < dof; j++) {
                    q[a][j] = fb.position[j];
                }
            }
        }
        cmd[a].n = dof;
        for (int j = 0; j < dof; j++) {
            cmd[a].flags[j] = MCA_ACT_SERVO_ENABLE | MCA_ACT_BRAKE_RELEASE;
        }
    }
    if (o->csv_path) {
        csv = fopen(o->csv_path, "w");
        if (!csv) {
            snprintf(err, errlen, "%s: cannot write", o->csv_path);
            rc = MCA_EIO;
            goto out;
        }
        csv_header(csv, cfg);
    }
    r->min_distance = INFINITY;
    r->min_distance_after_fault = INFINITY;
    r->n_samples = scn->n_sample_times;
    for (int i = 0; i < scn->n_sample_times; i++) {
        r->sample_t[i] = scn->sample_times[i];
        r->sample_d[i] = NAN;
    }
    double steps_sum = 0.0;
    int steps_n = 0, stopped_ticks = 0;
    mca_tick_info_t info;
    int k;
    for (k = 0; k < max_ticks; k++) {
        const double t = k * dt;
        if (!r->fault && k >= n_ticks &&
            (o->scheme != MCA_SCHEME_MCA_TS || info.paths_done || k >= n_ticks_ts)) {
            break;
        }
        struct timespec c0, c1;
        clock_gettime(CLOCK_THREAD_CPUTIME_ID, &c0);
        const int trc = mca_controller_tick(ctrl, t, qp_, qdp, &info);
        clock_gettime(CLOCK_THREAD_CPUTIME_ID, &c1);
        cpu[k] = (int64_t)(c1.tv_sec - c0.tv_sec) * 1000000000LL + (c1.tv_nsec - c0.tv_nsec);
        cns[k] = info.compute_ns;
        if (trc != MCA_OK && trc != MCA_EFAULT) {
            snprintf(err, errlen, "tick failed: %s", mca_strerror(trc));
            rc = trc;
            goto out;
        }
        if (!r->fault && !r->completed && info.paths_done) {
            r->completed = 1;
            r->path_time_lost_s = fmax(0.0, info.task_t - nominal_end);
        }
        if (!r->completed) {
            r->path_time_lost_s = fmax(0.0, info.task_t - nominal_end);
        }
        r->deadlocks = info.deadlocks;
        r->max_slack = fmax(r->max_slack, info.slack);
        if (info.min_distance < r->min_distance) {
            r->min_distance = info.min_distance;
            r->min_distance_t = t;
        }
        for (int i = 0; i < r->n_samples; i++) {
            if (fabs(t - r->sample_t[i]) < 0.5 * dt) {
                r->sample_d[i] = info.min_distance;
            }
        }
        if (info.fault && !r->fault) {
            if (o->dump_dir && o->scheme != MCA_SCHEME_APF &&
                (info.fault == MCA_CTRL_FAULT_NOT_CONVERGED || info.fault == MCA_CTRL_FAULT_FAKE_ATTRACTOR)) {
                /* the QP that failed, for a look with OSQP (phi is zeroed after a fault: none written) */
                char path[1024];
                snprintf(path, sizeof path, "%s/%s-%s-fault-%06d.json.fault", o->dump_dir, scn->name,
                         r->scheme, k);
                mca_qp_dump_json(mca_controller_last_qp(ctrl, NULL), NULL, info.pdnn_steps,
                                 info.pdnn_residual, "fault", path);
            }
            r->fault = info.fault;
            r->fault_t = t;
            r->fault_distance = info.min_distance;
            memcpy(r->fault_text, info.fault_text, sizeof r->fault_text);
        }
        if (r->fault) {
            r->min_distance_after_fault = fmin(r->min_distance_after_fault, info.min_distance);
        } else {
            for (int a = 0; a < na; a++) {
                r->max_err = fmax(r->max_err, info.ee_error[a]);
                if (info.binding_rows == 0) {
                    r->max_err_free = fmax(r->max_err_free, info.ee_error[a]);
                }
                if (info.brake >= 1.0) {
                    r->max_err_nobrake = fmax(r->max_err_nobrake, info.ee_error[a]);
                }
            }
            r->binding_ticks += info.binding_rows > 0;
            if (o->scheme != MCA_SCHEME_APF) {
                r->pdnn_steps_max = info.pdnn_steps > r->pdnn_steps_max ? info.pdnn_steps : r->pdnn_steps_max;
                r->pdnn_residual_max = fmax(r->pdnn_residual_max, info.pdnn_residual);
                r->eq_residual_max = fmax(r->eq_residual_max, info.eq_residual);
                steps_sum += info.pdnn_steps;
                steps_n++;
            }
        }
        if (csv) {
            csv_row(csv, cfg, ctrl, t, q, &info);
        }
        /* the ticks --dump-every picks: every Nth, and every N/5th with binding rows */
        const int every = o->dump_every > 0 ? o->dump_every : 1;
        const int every_b = every / 5 > 0 ? every / 5 : 1;
        const int picked = k % every == 0 || (info.binding_rows > 0 && k % every_b == 0);
        if (!info.fault && o->scheme != MCA_SCHEME_APF && !info.pdnn_converged) {
            r->pdnn_capped++;
            r->dump_skipped_capped += o->dump_dir != NULL && picked;
        }
        /* only converged answers are dumped: at the step cap the controller accepts residuals up to
         * fault_residual, whose phi may differ from the exact solution by more than the check's 1e-6 */
        if (o->dump_dir && !info.fault && info.pdnn_converged && o->scheme != MCA_SCHEME_APF &&
            (o->dump_max <= 0 || r->dumped < o->dump_max)) {
            if (picked) {
                char path[1024], tag[128];
                snprintf(path, sizeof path, "%s/%s-%s-%06d.json", o->dump_dir, scn->name, r->scheme, k);
                snprintf(tag, sizeof tag, "%s %s t=%.3f binding=%d", scn->name, r->scheme, t,
                         info.binding_rows);
                const double *phi;
                const mca_qp_t *qpp = mca_controller_last_qp(ctrl, &phi);
                if (mca_qp_dump_json(qpp, phi, info.pdnn_steps, info.pdnn_residual, tag, path) == MCA_OK) {
                    r->dumped++;
                    r->dumped_binding += info.binding_rows > 0;
                }
            }
        }
        /* apply the command */
        int moving = 0;
        for (int a = 0; a < na; a++) {
            const int dof = cfg->chain[a].dof;
            if (o->use_backend) {
                cmd[a].frame_id++;
                for (int j = 0; j < dof; j++) {
                    cmd[a].velocity[j] = qd[a][j];
                    cmd[a].position_ref[j] = q[a][j];
                }
                mca_arm_write(arm[a], &cmd[a]);
                mca_arm_feedback_t fb;
                const int frc = mca_arm_read(arm[a], &fb);
                if (frc == MCA_OK || frc == MCA_EFAULT) {
                    for (int j = 0; j < dof; j++) {
                        q[a][j] = fb.position[j];
                        moving |= fabs(fb.velocity[j]) > 1e-9;
                    }
                }
            } else {
                for (int j = 0; j < dof; j++) {
                    q[a][j] += qd[a][j] * dt;
                }
            }
        }
        if (r->fault) {
            if (!moving && !r->stopped) {
                r->stopped = 1;
                r->stop_t = t + dt;
            }
            if (r->stopped && ++stopped_ticks > (int)llround(o->settle / dt)) {
                k++;
                break;
            }
        }
    }
    r->ticks = k;
    r->pdnn_steps_mean = steps_n ? steps_sum / steps_n : 0.0;
    qsort(cns, (size_t)k, sizeof *cns, cmp_i64);
    if (k > 0) {
        r->compute_p50 = cns[k / 2];
        r->compute_p99 = cns[(int)(0.99 * (k - 1))];
        r->compute_max = cns[k - 1];
        qsort(cpu, (size_t)k, sizeof *cpu, cmp_i64);
        r->cpu_p50 = cpu[k / 2];
        r->cpu_p99 = cpu[(int)(0.99 * (k - 1))];
        r->cpu_max = cpu[k - 1];
    }
out:
    if (csv) {
        fclose(csv);
    }
    for (int a = 0; a < MCA_MAX_ARMS; a++) {
        mca_arm_close(arm[a]);
    }
    free(cns);
    free(cpu);
    free(ctrl);
    free(cfg);
    return rc;
}
