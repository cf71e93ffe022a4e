/* SPDX-License-Identifier: MIT */
/* Virtual-time runner of a scenario through mcad's tick (mca/daemon_drive.h); see simrun.h. */
#include "simrun.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "mca/arm.h"
#include "mca/cell.h"
#include "mca/daemon.h"
#include "mca/daemon_drive.h"
#include "mca/err.h"
#include "mca/qp_dump.h"
#include "mca/scenario.h"
#include "mca/sim_backend.h"
#include "mca/tick_csv.h"
#include "mca/track.h"
#include "mca/vec3.h"

void mca_simrun_default_opts(mca_simrun_opts_t *o) {
    memset(o, 0, sizeof *o);
    o->scheme = MCA_SCHEME_MCA;
    o->form = -1;
    o->overtime = -1.0;
    o->use_backend = 1;
    o->dump_every = 1;
    o->settle = 0.2;
    o->v_floor = -1.0;
    o->stop_at = -1.0;
    o->fault_at = -1.0;
    o->pdnn_budget_us = -1;
}

/* The daemon library's lines (mca/log.h) as mcad prints them, "<LEVEL>mcad: TEXT": mca-sim runs the same
 * daemon, and its output reads the same. */
static void daemon_line(void *arg, int level, const char *text) {
    fprintf((FILE *)arg, "<%d>mcad: %s\n", level, text);
}

static int cmp_i64(const void *a, const void *b) {
    const int64_t x = *(const int64_t *)a, y = *(const int64_t *)b;
    return (x > y) - (x < y);
}

/* mca-sim's solver overrides, applied to the controller config the daemon builds from its cell. */
static void apply_overrides(mca_controller_config_t *cfg, void *arg) {
    const mca_simrun_opts_t *o = arg;
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
    if (o->w_tube > 0.0) {
        cfg->ts.w_tube = o->w_tube;
    }
    if (o->w_path > 0.0) {
        cfg->ts.w_path = o->w_path;
    }
    if (o->no_coordinate) {
        cfg->ts.coordinate = 0;
    }
    if (o->no_body_rows) {
        cfg->body_rows = 0;
    }
    if (o->no_self_rows) {
        cfg->self_rows = 0;
    }
    if (o->pdnn_budget_us >= 0) {
        cfg->pdnn_budget_steps = mca_pdnn_budget_steps((int64_t)o->pdnn_budget_us * 1000);
    }
}

/* The simulated sphere where it truly is at task time t, and its velocity: at start until t0, then along the
 * line at speed until end, then at end. */
static void sphere_at(const mca_sim_sphere_t *s, double t, double pos[3], double vel[3]) {
    double dir[3];
    mca_v3_sub(dir, s->end, s->start);
    const double len = mca_v3_norm(dir);
    const double run = fmax(0.0, t - s->t0) * s->speed;
    const double u = fmin(run, len);
    for (int j = 0; j < 3; j++) {
        dir[j] /= len;
        pos[j] = s->start[j] + u * dir[j];
        vel[j] = t >= s->t0 && run < len ? s->speed * dir[j] : 0.0;
    }
}

/* The losses' generator (splitmix64): one draw per sample, seeded, the same on every machine. */
static double sphere_draw(uint64_t *state) {
    uint64_t z = (*state += 0x9e3779b97f4a7c15ULL);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    z ^= z >> 31;
    return (double)(z >> 11) * 0x1.0p-53;
}

/* The simulated tracker (the scenario's simulated_sphere): every sample taken at or before t - latency and
 * not yet delivered reaches the daemon now, as the DDS bridge would hand it over (mca_drive_put_tracks):
 * received at its stamp + latency, sent at once (its age when sent 0: the tracker cannot know the transport's
 * latency, which S_p budgets in T_r). A lost sample is skipped. */
typedef struct sphere_feed {
    long long next; /* the next sample's index */
    uint64_t rng;
    uint64_t accepted;
    mca_track_t last; /* the last sample delivered, stamped on the ticks' clock (as the daemon stamps it) */
} sphere_feed_t;

static void sphere_feed(mca_daemon_t *d, const mca_sim_sphere_t *s, sphere_feed_t *f, double t,
                        mca_simrun_result_t *r) {
    for (;;) {
        const double ts = (double)f->next / s->rate;
        if (ts + s->latency > t + 1e-12) {
            return;
        }
        f->next++;
        if (sphere_draw(&f->rng) < s->loss) {
            r->sphere_lost++;
            continue;
        }
        mca_ros2_tracks_t m = {
            .n = 1, .recv_ns = llround((ts + s->latency) * 1e9), .accepted = ++f->accepted};
        m.body[0] = (mca_track_t){.id = 1, .kind = MCA_BODY_SPHERE, .radius = s->radius, .stamp = 0.0};
        sphere_at(s, ts, m.body[0].a, m.body[0].v);
        memcpy(m.body[0].b, m.body[0].a, sizeof m.body[0].b);
        mca_drive_put_tracks(d, &m);
        f->last = m.body[0];
        f->last.stamp = ts + s->latency;
        r->sphere_sent++;
    }
}

/* With a streamed sphere the tick's least body pair may be the track's: the fixed bodies' pair of least
 * margin (body_*) is measured here over the fixed bodies alone. Each arm's least margin d - S_p to the track
 * as the last delivered sample makes it at t (mca_track_body under the controller's settings: the body the
 * controller holds while the arms may move, and, once they rest and the daemon no longer updates it, where it
 * would be) is counted below S_p with the arm at rest (its true joint velocities, this tick's and the last,
 * all at most MCA_SIMRUN_REST) or moving. And the least distance to the true sphere. */
static void sphere_measure(mca_daemon_t *d, const mca_sim_sphere_t *s, const sphere_feed_t *f, int n_fixed,
                           double t, double task_t, int running, int rest_prev[MCA_MAX_ARMS],
                           mca_simrun_result_t *r) {
    const mca_controller_t *ctrl = mca_drive_controller(d);
    const mca_controller_config_t *cfg = mca_controller_get_config(ctrl);
    const int na = cfg->n_arms;
    const mca_chain_t *chain[MCA_MAX_ARMS];
    mca_kin_t kin[MCA_MAX_ARMS];
    for (int a = 0; a < na; a++) {
        chain[a] = &cfg->chain[a];
        /* where the arm is (its last positions), also once the controller no longer ticks */
        if (mca_fk(chain[a], mca_drive_positions(d, a), &kin[a]) != MCA_OK) {
            kin[a] = *mca_controller_kin(ctrl, a);
        }
    }
    mca_body_nearest_t bn;
    if (n_fixed > 0 && mca_body_nearest(na, chain, kin, cfg->body, n_fixed, NULL, &bn) == MCA_OK &&
        bn.valid) {
        if (bn.margin < r->body_min_margin) {
            r->body_min_margin = bn.margin;
            r->body_min_distance = bn.d;
            r->body_min_t = task_t;
            r->body_min_arm = bn.arm;
            r->body_min_link = bn.link;
            r->body_min_body = bn.body;
            r->body_min_kind = bn.kind;
        }
        r->body_ticks_below += bn.margin < 0.0;
    }
    mca_fixed_body_t track;
    int has_track = 0;
    if (f->accepted > 0) {
        double arm_speed, t_stop;
        mca_controller_ssm_arms(cfg, &arm_speed, &t_stop);
        has_track = mca_track_body(&cfg->ssm, &f->last, t, arm_speed, t_stop, &track, NULL) == MCA_OK;
        r->track_sp_max = has_track ? fmax(r->track_sp_max, track.clearance) : r->track_sp_max;
    }
    mca_fixed_body_t truth = {.clearance = 0.0};
    truth.body.kind = MCA_BODY_SPHERE;
    truth.body.u.sphere.radius = s->radius;
    double v[3];
    sphere_at(s, t, truth.body.u.sphere.centre, v);
    for (int a = 0; a < na; a++) {
        const mca_sim_arm_t *fw = mca_sim_backend_firmware(mca_drive_arm(d, a));
        const mca_arm_command_t *cmd = mca_drive_last_command(d, a);
        double vmax = 0.0;
        for (int j = 0; j < cfg->chain[a].dof; j++) {
            vmax = fmax(vmax, fabs(fw ? fw->v[j] : cmd->velocity[j]));
        }
        const int rest = vmax <= MCA_SIMRUN_REST;
        if (has_track && mca_body_nearest(1, &chain[a], &kin[a], &track, 1, NULL, &bn) == MCA_OK &&
            bn.valid) {
            if (bn.margin < r->track_min_margin) {
                r->track_min_margin = bn.margin;
                r->track_min_t = task_t;
                r->track_min_arm = a;
            }
            if (bn.margin < 0.0) {
                if (rest && rest_prev[a]) {
                    r->track_ticks_rest++;
                } else {
                    r->track_ticks_moving++;
                    r->track_ticks_braking += !running;
                }
            }
        }
        if (mca_body_nearest(1, &chain[a], &kin[a], &truth, 1, NULL, &bn) == MCA_OK && bn.valid) {
            r->sphere_true_min_d = fmin(r->sphere_true_min_d, bn.d);
        }
        rest_prev[a] = rest;
    }
}

int mca_simrun_fault_from_name(const char *name) {
    for (int f = 1; f <= MCA_CTRL_FAULT_LAST; f++) {
        if (strcmp(name, mca_ctrl_fault_name(f)) == 0) {
            return f;
        }
    }
    return -1;
}

/* The run is mcad's pipeline in virtual time: a cell around the scenario (sim backend arms), the daemon
 * opened by its virtual-time driver (mca/daemon_drive.h: no thread, DDS or real-time settings) and
 * mca_drive_step once per tick (the same tick, fault latching and braking through mca_controller_brake as
 * mcad). This function only drives it (the stop and the fault scheduled at their instants, the end of the
 * run) and collects the figures. */
int mca_simrun(const mca_scenario_t *scn, const mca_simrun_opts_t *o, mca_simrun_result_t *r, char *err,
               size_t errlen) {
    memset(r, 0, sizeof *r);
    snprintf(r->scheme, sizeof r->scheme, "%s", mca_scheme_name(o->scheme));
    mca_cell_t *cell = calloc(1, sizeof *cell);
    mca_daemon_t *d = NULL;
    int64_t *cns = NULL, *cpu = NULL, *perr = NULL, *steps = NULL, *all_steps = NULL, *all_exact = NULL;
    FILE *csv = NULL;
    mca_tick_csv_layout_t csv_layout = {.pair_cols = 1}; /* mca-sim's digits; every pair's distance */
    int rc = MCA_OK;
    if (!cell) {
        rc = MCA_ENOMEM;
        goto out;
    }
    rc = mca_cell_from_scenario(cell, scn, o->scheme);
    if (rc != MCA_OK) {
        snprintf(err, errlen, "%s: dt %g s is not a whole number of ns", scn->source, scn->params.dt);
        goto out;
    }
    const mca_sim_sphere_t *sph = scn->sim_sphere.enabled ? &scn->sim_sphere : NULL;
    if (sph) {
        /* mca-sim's tracker is the driver's (mca_drive_put_tracks), not DDS: a cell built here from a
         * scenario, never a cell file, so the DDS Security rule of streamed_bodies does not arise */
        cell->tracks.enabled = 1;
        cell->tracks.max_bodies = 1;
        snprintf(cell->tracks.topic, sizeof cell->tracks.topic, "tracked_bodies");
        mca_ssm_default(&cell->tracks.ssm);
        cell->tracks.ssm.latency = sph->latency;
    }
    for (int a = 0; a < scn->n_arms; a++) {
        if (o->dec_limit > 0.0) {
            for (int j = 0; j < MCA_MAX_DOF; j++) {
                cell->arm[a].dec_limit[j] = o->dec_limit;
            }
        }
    }
    const mca_drive_opts_t dopts = {.daemon = {.no_dds = 1, .log = daemon_line, .log_arg = stderr},
                                    .ideal_arms = o->use_backend ? 0u : (1u << scn->n_arms) - 1u,
                                    .controller_config = apply_overrides,
                                    .controller_config_arg = (void *)o};
    rc = mca_drive_open(&d, cell, &dopts, err, errlen);
    if (rc != MCA_OK) {
        goto out;
    }
    const mca_controller_t *ctrl = mca_drive_controller(d);
    const mca_controller_config_t *cfg = mca_controller_get_config(ctrl);
    const mca_tick_info_t *ip = mca_drive_tick_info(d);
    mca_drive_stop_at(d, o->stop_at);                  /* as SIGTERM; < 0: none */
    mca_drive_fault_at(d, o->fault_kind, o->fault_at); /* "injected fault KIND at t = T s"; < 0: none */
    const int na = cfg->n_arms;
    r->budget_steps = mca_controller_step_budget(cfg);
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
    perr = calloc((size_t)max_ticks, sizeof *perr);
    steps = calloc((size_t)max_ticks, sizeof *steps);
    all_steps = calloc((size_t)max_ticks, sizeof *all_steps);
    all_exact = calloc((size_t)max_ticks, sizeof *all_exact);
    if (!cns || !cpu || !perr || !steps || !all_steps || !all_exact) {
        rc = MCA_ENOMEM;
        goto out;
    }
    if (o->csv_path) {
        csv = fopen(o->csv_path, "w");
        if (!csv) {
            snprintf(err, errlen, "%s: cannot write", o->csv_path);
            rc = MCA_EIO;
            goto out;
        }
        csv_layout.n_arms = na;
        csv_layout.body_cols = cfg->n_bodies > 0;
        csv_layout.self_cols = mca_controller_has_self(cfg);
        for (int a = 0; a < na; a++) {
            csv_layout.dof[a] = cfg->chain[a].dof;
        }
        mca_tick_csv_header(csv, &csv_layout);
    }
    r->min_distance = INFINITY;
    r->min_distance_after_fault = INFINITY;
    r->n_bodies = cfg->n_bodies;
    r->body_min_margin = r->body_min_distance = INFINITY;
    r->body_min_arm = r->body_min_link = r->body_min_body = r->body_min_kind = -1;
    r->has_self = mca_controller_has_self(cfg);
    r->self_min_distance = INFINITY;
    for (int k = 0; k < MCA_DDS_PAIR_KINDS; k++) {
        r->kind_min[k] = INFINITY;
    }
    r->self_min_arm = r->self_min_link = r->self_min_other = -1;
    r->brake_t = -1.0;
    r->stop_duration_s = -1.0;
    const int n_fixed = cfg->n_bodies; /* before the first tick: the tracks come after them */
    r->has_sphere = sph != NULL;
    r->track_min_margin = r->sphere_true_min_d = INFINITY;
    r->track_min_arm = -1;
    sphere_feed_t feed = {.rng = sph ? sph->seed : 0};
    int rest_prev[MCA_MAX_ARMS]; /* the arms start at rest */
    for (int a = 0; a < MCA_MAX_ARMS; a++) {
        rest_prev[a] = 1;
    }
    r->n_samples = scn->n_sample_times;
    for (int i = 0; i < scn->n_sample_times; i++) {
        r->sample_t[i] = scn->sample_times[i];
        r->sample_d[i] = NAN;
    }
    double steps_sum = 0.0;
    int steps_n = 0, stopped_ticks = 0, ended = 0, n_perr = 0;
    int k;
    for (k = 0; k < max_ticks; k++) {
        const double t = k * dt;
        if (!ended && k >= n_ticks && (o->scheme != MCA_SCHEME_MCA_TS || ip->paths_done || k >= n_ticks_ts)) {
            break;
        }
        if (sph) {
            sphere_feed(d, sph, &feed, t, r);
        }
        struct timespec c0, c1;
        clock_gettime(CLOCK_THREAD_CPUTIME_ID, &c0);
        const int state = mca_drive_step(d, t, (int64_t)llround(t * 1e9));
        clock_gettime(CLOCK_THREAD_CPUTIME_ID, &c1);
        r->stop_requested = (mca_drive_fired(d) & MCA_DRIVE_STOPPED) != 0;
        mca_daemon_service(d);
        cpu[k] = (int64_t)(c1.tv_sec - c0.tv_sec) * 1000000000LL + (c1.tv_nsec - c0.tv_nsec);
        cns[k] = ip->compute_ns;
        const int running = state == MCA_DAEMON_RUNNING;
        if (!running && !ended) {
            ended = 1; /* braking from a stop or a fault: the run ends once the arms are at rest */
            mca_daemon_summary_t s;
            mca_daemon_summary(d, &s);
            r->brake_t = s.brake_t >= 0.0 ? s.brake_t : t;
            if (s.fault) {
                r->fault =
                    s.fault == MCA_DAEMON_FAULT_CONTROLLER && ip->fault ? ip->fault : MCA_CTRL_FAULT_INPUT;
                r->fault_t = t;
                r->fault_distance = ip->min_distance;
                snprintf(r->fault_text, sizeof r->fault_text, "%s", s.fault_text);
                if (o->dump_dir && o->scheme != MCA_SCHEME_APF &&
                    (ip->fault == MCA_CTRL_FAULT_NOT_CONVERGED ||
                     ip->fault == MCA_CTRL_FAULT_FAKE_ATTRACTOR)) {
                    /* the QP that failed, for a look with OSQP (phi is zeroed after a fault: none written) */
                    char path[1024];
                    snprintf(path, sizeof path, "%s/%s-%s-fault-%06d.json.fault", o->dump_dir, scn->name,
                             r->scheme, k);
                    mca_qp_dump_json(mca_controller_last_qp(ctrl, NULL), NULL, ip->pdnn_steps,
                                     ip->pdnn_residual, "fault", path);
                }
            }
        }
        if (running && !r->completed && ip->paths_done) {
            r->completed = 1;
            r->path_time_lost_s = fmax(0.0, ip->task_t - nominal_end);
        }
        if (running && !r->completed) {
            r->path_time_lost_s = fmax(0.0, ip->task_t - nominal_end);
        }
        r->deadlocks = ip->deadlocks;
        r->max_slack = fmax(r->max_slack, ip->slack);
        r->arm_ticks_below += ip->min_distance < cfg->sp.d1;
        if (ip->min_distance < r->min_distance) {
            r->min_distance = ip->min_distance;
            r->min_distance_t = t;
        }
        if (sph) {
            sphere_measure(d, sph, &feed, n_fixed, t, ip->task_t, state == MCA_DAEMON_RUNNING, rest_prev, r);
        } else if (ip->body_margin < r->body_min_margin) {
            r->body_min_margin = ip->body_margin;
            r->body_min_distance = ip->body_distance;
            r->body_min_t = ip->task_t;
            r->body_min_arm = ip->body_arm;
            r->body_min_link = ip->body_link;
            r->body_min_body = ip->body_index;
            r->body_min_kind = ip->body_kind;
        }
        r->body_ticks_below += !sph && ip->body_margin < 0.0;
        if (ip->self_distance < r->self_min_distance) {
            r->self_min_distance = ip->self_distance;
            r->self_min_t = ip->task_t;
            r->self_min_arm = ip->self_arm;
            r->self_min_link = ip->self_link;
            r->self_min_other = ip->self_other;
        }
        r->self_ticks_below += ip->self_distance < cfg->sp.d1;
        for (int i = 0; i < r->n_samples; i++) {
            if (fabs(t - r->sample_t[i]) < 0.5 * dt) {
                r->sample_d[i] = ip->min_distance;
            }
        }
        if (ended) {
            /* braking (a stop or a fault): how far the tool tips of path-first arms leave their paths' curves
             */
            for (int a = 0; a < na; a++) {
                const mca_path_t *pa = &cfg->path[a];
                if (pa->path_first && (pa->kind == MCA_PATH_CIRCLE || pa->kind == MCA_PATH_WAYPOINTS)) {
                    r->path_error_brake_max = fmax(r->path_error_brake_max, mca_path_distance(pa, ip->ee[a]));
                }
            }
        }
        if (r->fault) {
            r->min_distance_after_fault = fmin(r->min_distance_after_fault, ip->min_distance);
        } else if (running) {
            for (int a = 0; a < na; a++) {
                r->max_err = fmax(r->max_err, ip->ee_error[a]);
                if (ip->binding_rows == 0) {
                    r->max_err_free = fmax(r->max_err_free, ip->ee_error[a]);
                }
                if (ip->brake >= 1.0) {
                    r->max_err_nobrake = fmax(r->max_err_nobrake, ip->ee_error[a]);
                }
            }
            r->binding_ticks += ip->binding_rows > 0;
            double pe = 0.0;
            for (int a = 0; a < na; a++) {
                pe = fmax(pe, ip->path_error[a]);
            }
            r->path_error_max = fmax(r->path_error_max, pe);
            perr[n_perr++] = (int64_t)llround(pe * 1e9); /* nm, sorted with the other samples */
            r->exact_points = ip->exact_met + ip->exact_missed;
            r->exact_missed = ip->exact_missed;
            r->exact_error_max = ip->exact_error_max;
            if (o->scheme != MCA_SCHEME_APF) {
                r->pdnn_steps_max = ip->pdnn_steps > r->pdnn_steps_max ? ip->pdnn_steps : r->pdnn_steps_max;
                r->pdnn_residual_max = fmax(r->pdnn_residual_max, ip->pdnn_residual);
                r->eq_residual_max = fmax(r->eq_residual_max, ip->eq_residual);
                steps_sum += ip->pdnn_steps;
                steps[steps_n++] = ip->pdnn_steps;
            }
        }
        if (csv) {
            double q[MCA_MAX_ARMS][MCA_MAX_DOF];
            for (int a = 0; a < na; a++) {
                memcpy(q[a], mca_drive_positions(d, a), sizeof q[a]);
            }
            const mca_tick_csv_row_t row = {
                .t = t, .q = q, .info = ip, .dist = mca_controller_distances(ctrl)};
            mca_tick_csv_row(csv, &csv_layout, &row);
        }
        /* the ticks --dump-every picks: every Nth, and every N/5th with binding rows */
        const int every = o->dump_every > 0 ? o->dump_every : 1;
        const int every_b = every / 5 > 0 ? every / 5 : 1;
        const int picked = k % every == 0 || (ip->binding_rows > 0 && k % every_b == 0);
        const int unconverged = running && o->scheme != MCA_SCHEME_APF && !ip->pdnn_converged;
        if (o->scheme != MCA_SCHEME_APF && !r->stopped &&
            (ip->pdnn_steps > 0 || ip->pdnn_exact_solves > 0 || ip->pdnn_converged)) {
            /* a solve ran this tick (running or braking): its steps and exact solves */
            all_steps[r->solves] = ip->pdnn_steps;
            all_exact[r->solves] = ip->pdnn_exact_solves;
            r->solves_unconverged += !ip->pdnn_converged;
            r->solves++;
        }
        if (running && ip->pdnn_budget_hit) {
            r->budget_hits_steps += ip->pdnn_budget_hit == MCA_BUDGET_STEPS;
            r->budget_hits_time += ip->pdnn_budget_hit == MCA_BUDGET_TIME;
        } else if (unconverged) {
            r->pdnn_capped++;
        }
        r->dump_skipped_capped += unconverged && o->dump_dir != NULL && picked && !o->dump_capped;
        if (unconverged && o->dump_dir && o->dump_capped && picked) {
            char path[1024];
            snprintf(path, sizeof path, "%s/%s-%s-%06d.json.capped", o->dump_dir, scn->name, r->scheme, k);
            const double *phi;
            const mca_qp_t *qpp = mca_controller_last_qp(ctrl, &phi);
            mca_qp_dump_json(qpp, phi, ip->pdnn_steps, ip->pdnn_residual, "capped", path);
        }
        /* only converged answers are dumped: at the step cap the controller accepts residuals up to
         * fault_residual, whose phi may differ from the exact solution by more than the check's 1e-6 */
        if (o->dump_dir && running && ip->pdnn_converged && o->scheme != MCA_SCHEME_APF &&
            (o->dump_max <= 0 || r->dumped < o->dump_max)) {
            if (picked) {
                char path[1024], tag[128];
                snprintf(path, sizeof path, "%s/%s-%s-%06d.json", o->dump_dir, scn->name, r->scheme, k);
                snprintf(tag, sizeof tag, "%s %s t=%.3f binding=%d", scn->name, r->scheme, t,
                         ip->binding_rows);
                const double *phi;
                const mca_qp_t *qpp = mca_controller_last_qp(ctrl, &phi);
                if (mca_qp_dump_json(qpp, phi, ip->pdnn_steps, ip->pdnn_residual, tag, path) == MCA_OK) {
                    r->dumped++;
                    r->dumped_binding += ip->binding_rows > 0;
                }
            }
        }
        if (ended) {
            /* at rest: every simulated joint's true velocity zero after this tick's cycle */
            int moving = 0;
            for (int a = 0; a < na; a++) {
                const mca_sim_arm_t *fw = mca_sim_backend_firmware(mca_drive_arm(d, a));
                for (int j = 0; fw && j < fw->cfg.n; j++) {
                    moving |= fabs(fw->v[j]) > 1e-9;
                }
            }
            if (!moving && !r->stopped) {
                r->stopped = 1;
                r->stop_t = t + dt;
                r->stop_duration_s = r->stop_t - r->brake_t;
            }
            /* with a sphere, at rest until the task's duration: the sphere may walk into an arm at rest */
            if (r->stopped && ++stopped_ticks > (int)llround(o->settle / dt) && (!sph || k + 1 >= n_ticks)) {
                k++;
                break;
            }
        }
    }
    r->ticks = k;
    r->end_pair[0] = ip->min_arm_a;
    r->end_pair[1] = ip->min_link_a;
    r->end_pair[2] = ip->min_arm_b;
    r->end_pair[3] = ip->min_link_b;
    r->end_distance = ip->min_distance;
    for (int a = 0; a < na; a++) {
        memcpy(r->end_ee[a], ip->ee[a], sizeof r->end_ee[a]);
        r->end_tau[a] = ip->tau[a];
        r->end_done[a] = ip->tau[a] >= mca_path_end_time(&cfg->path[a]);
    }
    r->coord_pairs = mca_controller_coord(ctrl)->n_pairs;
    r->coord_unplanned = mca_controller_coord(ctrl)->unplanned;
    r->pdnn_steps_mean = steps_n ? steps_sum / steps_n : 0.0;
    r->completed &= r->exact_missed == 0;
    if (n_perr > 0) {
        qsort(perr, (size_t)n_perr, sizeof *perr, cmp_i64);
        r->path_error_p99 = perr[(int)(0.99 * (n_perr - 1))] * 1e-9;
    }
    if (r->solves > 0) {
        qsort(all_steps, (size_t)r->solves, sizeof *all_steps, cmp_i64);
        qsort(all_exact, (size_t)r->solves, sizeof *all_exact, cmp_i64);
        const int n = r->solves;
        r->solve_steps_p50 = (int)all_steps[n / 2];
        r->solve_steps_p999 = (int)all_steps[(int)(0.999 * (n - 1))];
        r->solve_steps_max = (int)all_steps[n - 1];
        r->exact_p50 = (int)all_exact[n / 2];
        r->exact_p999 = (int)all_exact[(int)(0.999 * (n - 1))];
        r->exact_max = (int)all_exact[n - 1];
    }
    if (steps_n > 0) {
        qsort(steps, (size_t)steps_n, sizeof *steps, cmp_i64);
        r->pdnn_steps_p50 = (int)steps[steps_n / 2];
        r->pdnn_steps_p999 = (int)steps[(int)(0.999 * (steps_n - 1))];
    }
    {
        mca_daemon_summary_t s;
        mca_daemon_summary(d, &s);
        r->brake_fallback_ticks = (int)s.brake_fallback_ticks;
        r->brake_forced_ticks = (int)s.brake_forced_ticks;
        r->max_dv_over_dt_dec = s.max_dv_over_dt_dec;
        r->daemon_state = s.state;
        memcpy(r->kind_min, s.kind_min, sizeof r->kind_min);
        memcpy(r->kind_min_t, s.kind_min_t, sizeof r->kind_min_t);
        r->n_fixed_bodies = s.n_fixed_bodies;
        memcpy(r->fixed_min, s.fixed_min, sizeof r->fixed_min);
        memcpy(r->fixed_min_t, s.fixed_min_t, sizeof r->fixed_min_t);
        memcpy(r->fixed_min_link, s.fixed_min_link, sizeof r->fixed_min_link);
    }
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
    mca_daemon_close(d);
    free(cns);
    free(cpu);
    free(perr);
    free(steps);
    free(all_steps);
    free(all_exact);
    free(cell);
    return rc;
}
