/* SPDX-License-Identifier: MIT */
/* Controller tick cost: mca_controller_tick driven over a real task, or over synthetic cells of 2-4 arms with
 * 4-8 joints, in virtual time (joint velocities integrated by Euler steps, no sleeping between ticks).
 *
 *   bench_tick task --scenario FILE [--ticks N] [--out JSON] [--qp-dir DIR] [--qp-every E] [--qp-block L]
 *   bench_tick scaling --urdf-dir DIR [--ticks N] [--out JSON] [--quick] [--gap M]
 *   bench_tick steps --scenario FILE [--scheme mca|mca-ts] [--form normal|componentwise] [--every E]
 *                    [--steps S]
 *   bench_tick pair --scenario FILE --scenario-b FILE [--pairs P] [--ticks N] [--out JSON]
 *   task and pair: [--no-split] (the tick alone: for callgrind, --toggle-collect=mca_controller_tick)
 *   common: [--fifo PRIO] (SCHED_FIFO + mlockall for the measuring thread; fewer preemptions on a busy host)
 *
 * Per tick it records the tick's own compute_ns (CLOCK_MONOTONIC inside mca_controller_tick), then, OUTSIDE
 * the tick, re-runs each stage on the same data to split the time: forward kinematics of every arm, all
 * arm-pair link distances, the QP assembly (Jacobians at the critical points + rows), and the PDNN solve of
 * the controller's very QP from a copy of the solver state the tick started from (same warm start: its step
 * count must equal the tick's; mismatches are counted). --qp-dir writes blocks of L consecutive converged
 * QPs (mca_qp_dump_json) every E ticks with DIR/pdnn.csv: file, block, idx, warm ns, steps, and for the first
 * QP of a block the COLD solve time (fresh solver state) for the OSQP comparison in bench/report.py.
 * steps: the wall time of one PDNN step on the QPs a task really builds (the calibration of the controller's
 * step budget, MCA_PDNN_STEP_NS): every E-th tick's QP as the solver got it (mca-ts: the active rows only) is
 * solved again from cold with a tolerance nothing meets, so it runs S steps (or stops for lack of progress),
 * 3 times; the least time, set-up included, is divided by its steps. One line of text.
 * pair: the whole-cell row (docs/benchmarks.md): the task of --scenario and of --scenario-b (the same task
 * with bodies and self pairs), each run whole, alternating A B A B ..., P pairs (default 5); one run object
 * per task run. Every run counts the body and self rows that reached the PDNN per tick. Output: one JSON
 * document (--out, default stdout). Not a test: the figures depend on the machine. */
#include <errno.h>
#include <math.h>
#include <sched.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <time.h>

#include "mca/armdist.h"
#include "mca/controller.h"
#include "mca/err.h"
#include "mca/pdnn.h"
#include "mca/qp_dump.h"
#include "mca/scenario.h"
#include "mca/scheme.h"

/* The stage split re-runs the tick's stages on the state the tick started from: the one reader of the
 * controller's private state outside core (its struct, not its API). */
#include "controller__state.h"
#include "mca/urdf.h"

enum { ST_TICK, ST_FK, ST_DIST, ST_ASM, ST_PDNN, ST_N };
static const char *const st_name[ST_N] = {"tick", "fk", "distances", "assembly", "pdnn"};

typedef struct run_stats {
    int64_t *v[ST_N];
    int *steps, *active, *exact; /* exact: the polish's exact solves */
    int *body_rows, *self_rows;  /* rows of bodies, of self pairs that went to the PDNN */
    int n, cap;
    int faults, resets, step_mismatch, capped;
} run_stats_t;

static int64_t now_ns(void) {
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (int64_t)ts.tv_sec * 1000000000LL + ts.tv_nsec;
}

static int cmp_i64(const void *a, const void *b) {
    const int64_t x = *(const int64_t *)a, y = *(const int64_t *)b;
    return (x > y) - (x < y);
}

static int cmp_int(const void *a, const void *b) {
    const int x = *(const int *)a, y = *(const int *)b;
    return (x > y) - (x < y);
}

static int stats_alloc(run_stats_t *s, int cap) {
    memset(s, 0, sizeof *s);
    s->cap = cap;
    for (int k = 0; k < ST_N; k++) {
        s->v[k] = calloc((size_t)cap, sizeof(int64_t));
        if (!s->v[k]) {
            return MCA_ENOMEM;
        }
    }
    s->steps = calloc((size_t)cap, sizeof(int));
    s->active = calloc((size_t)cap, sizeof(int));
    s->exact = calloc((size_t)cap, sizeof(int));
    s->body_rows = calloc((size_t)cap, sizeof(int));
    s->self_rows = calloc((size_t)cap, sizeof(int));
    return s->steps && s->active && s->exact && s->body_rows && s->self_rows ? MCA_OK : MCA_ENOMEM;
}

static void stats_free(run_stats_t *s) {
    for (int k = 0; k < ST_N; k++) {
        free(s->v[k]);
    }
    free(s->steps);
    free(s->active);
    free(s->exact);
    free(s->body_rows);
    free(s->self_rows);
}

/* percentile p in [0, 1] of a sorted array: nearest rank */
static int64_t pct_i64(const int64_t *v, int n, double p) {
    if (n <= 0) {
        return 0;
    }
    int i = (int)ceil(p * n) - 1;
    return v[i < 0 ? 0 : (i >= n ? n - 1 : i)];
}

static int pct_int(const int *v, int n, double p) {
    if (n <= 0) {
        return 0;
    }
    int i = (int)ceil(p * n) - 1;
    return v[i < 0 ? 0 : (i >= n ? n - 1 : i)];
}

/* "name": {p50, p99, max, mean, ticks with any} of one per-tick count (sorts it) */
static void count_json(FILE *f, const char *name, int *v, int n) {
    double mean = 0.0;
    int any = 0;
    for (int i = 0; i < n; i++) {
        mean += v[i];
        any += v[i] > 0;
    }
    qsort(v, (size_t)n, sizeof(int), cmp_int);
    fprintf(f, ", \"%s\": {\"p50\": %d, \"p99\": %d, \"max\": %d, \"mean\": %.3f, \"ticks_any\": %d}", name,
            pct_int(v, n, 0.5), pct_int(v, n, 0.99), n ? v[n - 1] : 0, n ? mean / n : 0.0, any);
}

/* Print the stats of one run as a JSON object (sorts the arrays). */
static void stats_json(FILE *f, run_stats_t *s, const char *name, const mca_controller_config_t *cfg,
                       const mca_qp_t *qp) {
    fprintf(f, "{\"name\": \"%s\", \"n_arms\": %d, \"dof\": [", name, cfg->n_arms);
    int links = 0;
    for (int a = 0; a < cfg->n_arms; a++) {
        fprintf(f, "%s%d", a ? ", " : "", cfg->chain[a].dof);
        links += cfg->chain[a].dof + 1;
    }
    fprintf(f, "], \"links\": %d, \"d2\": %g, \"n_vars\": %d, \"n_eq\": %d, \"n_ineq\": %d, ", links,
            cfg->sp.d2, qp->n, qp->n_eq, qp->n_ineq);
    fprintf(f, "\"ticks\": %d, \"faults\": %d, \"resets\": %d, \"step_mismatch\": %d, \"capped\": %d", s->n,
            s->faults, s->resets, s->step_mismatch, s->capped);
    for (int k = 0; k < ST_N; k++) {
        double mean = 0.0;
        for (int i = 0; i < s->n; i++) {
            mean += (double)s->v[k][i];
        }
        mean = s->n ? mean / s->n : 0.0;
        qsort(s->v[k], (size_t)s->n, sizeof(int64_t), cmp_i64);
        fprintf(f,
                ", \"%s_ns\": {\"p50\": %lld, \"p99\": %lld, \"p999\": %lld, \"max\": %lld, \"mean\": %.1f, "
                "\"min\": %lld}",
                st_name[k], (long long)pct_i64(s->v[k], s->n, 0.5), (long long)pct_i64(s->v[k], s->n, 0.99),
                (long long)pct_i64(s->v[k], s->n, 0.999), (long long)(s->n ? s->v[k][s->n - 1] : 0), mean,
                (long long)(s->n ? s->v[k][0] : 0));
    }
    double ms = 0.0, ma = 0.0;
    for (int i = 0; i < s->n; i++) {
        ms += s->steps[i];
        ma += s->active[i];
    }
    qsort(s->steps, (size_t)s->n, sizeof(int), cmp_int);
    qsort(s->active, (size_t)s->n, sizeof(int), cmp_int);
    qsort(s->exact, (size_t)s->n, sizeof(int), cmp_int);
    fprintf(f, ", \"exact_solves\": {\"p50\": %d, \"p99\": %d, \"max\": %d}", pct_int(s->exact, s->n, 0.5),
            pct_int(s->exact, s->n, 0.99), s->n ? s->exact[s->n - 1] : 0);
    count_json(f, "body_rows", s->body_rows, s->n);
    count_json(f, "self_rows", s->self_rows, s->n);
    fprintf(f,
            ", \"steps\": {\"p50\": %d, \"p99\": %d, \"max\": %d, \"mean\": %.2f}, \"active_rows\": "
            "{\"p50\": %d, "
            "\"max\": %d, \"mean\": %.3f}}",
            pct_int(s->steps, s->n, 0.5), pct_int(s->steps, s->n, 0.99), s->n ? s->steps[s->n - 1] : 0,
            s->n ? ms / s->n : 0.0, pct_int(s->active, s->n, 0.5), s->n ? s->active[s->n - 1] : 0,
            s->n ? ma / s->n : 0.0);
}

/* Scratch outside the controller (static: large). */
static mca_pdnn_t shadow;
static mca_pdnn_t cold;
static mca_scheme_state_t sstate_copy;
static mca_qp_t qp_scratch;
static mca_kin_t kin_scratch[MCA_MAX_ARMS];
static mca_arm_distances_t dist_scratch;

typedef struct qp_dump {
    const char *dir;
    FILE *csv;
    int every, block_len;
    int block, idx; /* current block, index inside it (-1: none open) */
    int written;
} qp_dump_t;

/* Where a task run stands between calls of drive() (the scaling sweep runs its cells round-robin). */
typedef struct drive_state {
    double q0[MCA_MAX_ARMS][MCA_MAX_DOF];
    double q[MCA_MAX_ARMS][MCA_MAX_DOF];
    double t;
    int since_reset;
    int k; /* ticks driven so far */
} drive_state_t;

static void drive_start(drive_state_t *ds, const double q0[MCA_MAX_ARMS][MCA_MAX_DOF]) {
    memset(ds, 0, sizeof *ds);
    memcpy(ds->q0, q0, sizeof ds->q0);
    memcpy(ds->q, q0, sizeof ds->q);
}

/* The body and self rows of this tick's QP as the PDNN got it: the active rows kept by the compaction (both
 * schemes compact when the cell has body slots), each named by its slot of the full layout (row_key) and
 * the slot's witness (a self pair's has its other link). */
static void count_body_rows(const mca_controller_t *ctrl, int *body, int *self) {
    const mca_controller_config_t *cfg = &ctrl->cfg;
    const int bp = cfg->sp.body_pairs;
    *body = *self = 0;
    if (bp <= 0 || cfg->scheme == MCA_SCHEME_MVN || cfg->scheme == MCA_SCHEME_APF) {
        return;
    }
    const int rpl = cfg->scheme == MCA_SCHEME_MCA_TS ? MCA_NEAR_PAIRS : mca_scheme_rows_per_link(&cfg->sp);
    int b0[MCA_MAX_ARMS], off = 0;
    for (int a = 0; a < cfg->n_arms; a++) {
        b0[a] = off + rpl * (cfg->chain[a].dof + 1);
        off += (rpl + bp) * (cfg->chain[a].dof + 1);
    }
    for (int i = 0; i < ctrl->n_row_key && i < ctrl->qp.n_ineq; i++) {
        const int slot = ctrl->row_key[i];
        for (int a = 0; a < cfg->n_arms; a++) {
            const int r = slot - b0[a];
            if (r >= 0 && r < bp * (cfg->chain[a].dof + 1)) {
                const mca_body_witness_t *w = &ctrl->body_near[a][r / bp][r % bp];
                *self += w->link >= 0;
                *body += w->link < 0;
            }
        }
    }
}

/* Run `ticks` more ticks of ctrl (integrating qdot by Euler steps); on a fault the task restarts from q0. */
static int drive(mca_controller_t *ctrl, drive_state_t *ds, int ticks, run_stats_t *s, qp_dump_t *dump,
                 int split) {
    const mca_controller_config_t *cfg = mca_controller_get_config(ctrl);
    const int na = cfg->n_arms;
    const double dt = cfg->dt;
    double(*q)[MCA_MAX_DOF] = ds->q;
    static double qd[MCA_MAX_ARMS][MCA_MAX_DOF];
    const double *qp_[MCA_MAX_ARMS];
    double *qdp[MCA_MAX_ARMS];
    for (int a = 0; a < MCA_MAX_ARMS; a++) {
        qp_[a] = q[a];
        qdp[a] = qd[a];
    }
    const mca_chain_t *chains[MCA_MAX_ARMS];
    for (int a = 0; a < na; a++) {
        chains[a] = &cfg->chain[a];
    }
    static double phi_prev[MCA_QP_MAX_VARS], phi[MCA_QP_MAX_VARS];
    mca_tick_info_t info;
    double t = ds->t;
    int since_reset = ds->since_reset;
    const int k_end = ds->k + ticks;
    for (int k = ds->k; k < k_end; k++, t += dt) {
        if (k % 500 == 499) {
            /* ~10 ms of busy work, then 2 ms asleep: a SCHED_FIFO thread busy for 950 ms of a second is
             * throttled for the rest (sched_rt_runtime_us), which would show up as a 50 ms "tick" */
            const struct timespec nap = {0, 2000000};
            nanosleep(&nap, NULL);
        }
        /* the state the tick starts from, for the out-of-tick re-runs (the solver's state is large: not
         * copied without them, which under callgrind took most of the run) */
        if (split) {
            memcpy(&shadow, &ctrl->pdnn, sizeof shadow);
            memcpy(&sstate_copy, &ctrl->sstate, sizeof sstate_copy);
        }
        const int has_prev = ctrl->has_prev;
        memcpy(phi_prev, ctrl->phi_prev, sizeof phi_prev);

        const int rc = mca_controller_tick(ctrl, t, qp_, qdp, &info);
        if (rc != MCA_OK && rc != MCA_EFAULT) {
            fprintf(stderr, "bench_tick: tick failed: %s\n", mca_strerror(rc));
            return rc;
        }
        if (info.fault) {
            /* a faulted tick stops early: not a representative cost; restart the task from q0 */
            if (s->faults++ == 0) {
                char why[192];
                fprintf(stderr, "bench_tick: first fault at tick %d: %s\n", k,
                        mca_ctrl_fault_format(&info.fault_why, why, sizeof why));
            }
            s->resets++;
            mca_controller_reset(ctrl);
            memcpy(ds->q, ds->q0, sizeof ds->q);
            t = -dt;
            since_reset = 0;
            if (dump && dump->idx >= 0) {
                dump->idx = -1;
            }
            continue;
        }
        since_reset++;
        const int i = s->n;
        if (i < s->cap) {
            s->v[ST_TICK][i] = info.compute_ns;
            s->steps[i] = info.pdnn_steps;
            s->exact[i] = info.pdnn_exact_solves;
            s->active[i] = info.active_rows;
            s->capped += !info.pdnn_converged;
            count_body_rows(ctrl, &s->body_rows[i], &s->self_rows[i]);
            if (!split) {
                s->n++;
            } else {

                int64_t t0 = now_ns();
                for (int a = 0; a < na; a++) {
                    mca_fk(&cfg->chain[a], q[a], &kin_scratch[a]);
                }
                int64_t t1 = now_ns();
                for (int a = 0; a < na; a++) {
                    for (int b = a + 1; b < na; b++) {
                        mca_arm_distances(&cfg->chain[a], mca_controller_kin(ctrl, a), &cfg->chain[b],
                                          mca_controller_kin(ctrl, b), cfg->dist_method, &dist_scratch);
                    }
                }
                int64_t t2 = now_ns();
                double rdot0[MCA_MAX_ARMS][3] = {{0}};
                mca_scheme_assemble(&cfg->sp, na, chains, ctrl->kin, qp_, (const double(*)[3])info.ee_desired,
                                    (const double(*)[3])rdot0,
                                    (const mca_link_critical_t(*)[MCA_MAX_LINKS])ctrl->crit,
                                    has_prev ? phi_prev : NULL, &sstate_copy, &qp_scratch, NULL);
                int64_t t3 = now_ns();
                mca_pdnn_result_t pr;
                mca_pdnn_solve(&shadow, &ctrl->qp, &cfg->pdnn, phi, &pr);
                int64_t t4 = now_ns();
                s->v[ST_FK][i] = t1 - t0;
                s->v[ST_DIST][i] = t2 - t1;
                s->v[ST_ASM][i] = t3 - t2;
                s->v[ST_PDNN][i] = t4 - t3;
                s->step_mismatch += pr.steps != info.pdnn_steps;
                s->n++;

                if (dump && dump->dir) {
                    if (dump->idx < 0 && since_reset > 1 && k % dump->every == 0) {
                        dump->idx = 0;
                        dump->block++;
                    }
                    if (dump->idx >= 0 && !info.pdnn_converged) {
                        dump->idx = -1; /* only converged answers are compared */
                    }
                    if (dump->idx >= 0) {
                        char path[1024], file[64], tag[96];
                        snprintf(file, sizeof file, "qp_%04d_%02d.json", dump->block, dump->idx);
                        snprintf(path, sizeof path, "%s/%s", dump->dir, file);
                        snprintf(tag, sizeof tag, "tick %d active %d", k, info.active_rows);
                        const double *cphi;
                        const mca_qp_t *cqp = mca_controller_last_qp(ctrl, &cphi);
                        long long cold_ns = -1;
                        int cold_steps = -1;
                        if (dump->idx == 0) {
                            mca_pdnn_init(&cold);
                            const int64_t c0 = now_ns();
                            mca_pdnn_solve(&cold, cqp, &cfg->pdnn, phi, &pr);
                            cold_ns = now_ns() - c0;
                            cold_steps = pr.steps;
                        }
                        if (mca_qp_dump_json(cqp, cphi, info.pdnn_steps, info.pdnn_residual, tag, path) ==
                            MCA_OK) {
                            fprintf(dump->csv, "%s,%d,%d,%lld,%d,%lld,%d,%d\n", file, dump->block, dump->idx,
                                    (long long)s->v[ST_PDNN][i], info.pdnn_steps, cold_ns, cold_steps,
                                    info.active_rows);
                            dump->written++;
                        }
                        if (++dump->idx >= dump->block_len) {
                            dump->idx = -1;
                        }
                    }
                }
            }
        }
        for (int a = 0; a < na; a++) {
            for (int j = 0; j < cfg->chain[a].dof; j++) {
                q[a][j] += qd[a][j] * dt;
            }
        }
    }
    ds->t = t;
    ds->since_reset = since_reset;
    ds->k = k_end;
    return MCA_OK;
}

/* ---- synthetic cells ------------------------------------------------------------------------------------
 */

/* Keep the first k joints of a chain; the others are frozen at 0 and folded into the tool pose. */
static void truncate_chain(mca_chain_t *c, int k) {
    if (k >= c->dof) {
        return;
    }
    mca_pose_t tool = c->tool, tmp;
    double rmax = 0.0;
    for (int j = c->dof - 1; j >= k; j--) {
        mca_pose_mul(&tmp, &c->joint[j].origin, &tool);
        tool = tmp;
    }
    for (int l = k; l <= c->dof; l++) {
        rmax = fmax(rmax, c->link_radius[l]);
    }
    c->tool = tool;
    c->link_radius[k] = rmax;
    for (int l = k + 1; l < MCA_MAX_LINKS; l++) {
        c->link_radius[l] = 0.0;
    }
    c->dof = k;
}

/* n arms on a circle around the origin, each facing the centre, q0 reaching inwards; small circles as
 * paths (relative to the start) with phases spread so that neighbours approach each other. */
static int synth_config(mca_controller_config_t *cfg, double q0[MCA_MAX_ARMS][MCA_MAX_DOF],
                        const mca_chain_t *base, int n_arms, int dof, double gap, double d2) {
    mca_controller_default_config(cfg);
    cfg->n_arms = n_arms;
    cfg->sp.d2 = d2;
    mca_chain_t c = *base;
    truncate_chain(&c, dof);
    /* the PA10+ reference pose of task 1, truncated */
    static const double qref[8] = {0.0, 0.7853981633974483, 0.0, -1.5707963267948966,
                                   0.0, 0.7853981633974483, 0.0, 0.7853981633974483};
    double q[MCA_MAX_DOF] = {0};
    for (int j = 0; j < dof; j++) {
        q[j] = qref[j];
    }
    mca_kin_t kin;
    const double zero[3] = {0, 0, 0};
    mca_chain_set_base(&c, zero, zero);
    if (mca_fk(&c, q, &kin) != MCA_OK) {
        return MCA_EINVAL;
    }
    /* face the centre with the end effector; the base sits `gap` beyond the arm's farthest capsule surface
     * along that direction, so that no two arms overlap at q0 */
    const double face = atan2(kin.ee[1], kin.ee[0]);
    double reach = 0.0;
    for (int k = 1; k < kin.n_points; k++) {
        const double r = c.link_radius[k - 1 < MCA_MAX_LINKS ? k - 1 : 0];
        reach = fmax(reach, kin.point[k][0] * cos(face) + kin.point[k][1] * sin(face) + r);
    }
    const double rb = reach + gap;
    for (int a = 0; a < n_arms; a++) {
        const double th = 2.0 * M_PI * a / n_arms;
        const double xyz[3] = {rb * cos(th), rb * sin(th), 0.0};
        const double rpy[3] = {0.0, 0.0, th + M_PI - face};
        cfg->chain[a] = c;
        mca_chain_set_base(&cfg->chain[a], xyz, rpy);
        memcpy(q0[a], q, sizeof q);
        mca_path_t *p = &cfg->path[a];
        memset(p, 0, sizeof *p);
        p->kind = MCA_PATH_CIRCLE;
        p->relative = 1;
        p->radius = 0.08;
        p->period = 2.0;
        p->turns = 1.0;
        /* in the plane spanned by the radial direction and z; u points outwards, so the circle takes the end
         * effector up to 2 R towards the centre (and the other arms) and back */
        p->u[0] = cos(th);
        p->u[1] = sin(th);
        p->v[2] = 1.0;
    }
    return MCA_OK;
}

/* steps mode: ns per PDNN step (the step count the cap and budget count) over every E-th tick's QP. */
static int run_step_cost(mca_controller_t *ctrl, const double q0[MCA_MAX_ARMS][MCA_MAX_DOF], int ticks,
                         int every, int steps, FILE *of, const char *name) {
    const mca_controller_config_t *cfg = mca_controller_get_config(ctrl);
    const int na = cfg->n_arms;
    static double q[MCA_MAX_ARMS][MCA_MAX_DOF], qd[MCA_MAX_ARMS][MCA_MAX_DOF], phi[MCA_QP_MAX_VARS];
    const double *qs[MCA_MAX_ARMS];
    double *qds[MCA_MAX_ARMS];
    for (int a = 0; a < MCA_MAX_ARMS; a++) {
        qs[a] = q[a];
        qds[a] = qd[a];
    }
    memcpy(q, q0, sizeof q);
    double *ns = calloc((size_t)ticks / (size_t)every + 1, sizeof *ns);
    if (!ns) {
        return MCA_ENOMEM;
    }
    mca_pdnn_params_t prm = cfg->pdnn;
    prm.tol = 1e-300; /* never met: the solve runs to its cap */
    prm.max_steps = steps;
    int n = 0, faults = 0, max_n = 0, max_ineq = 0;
    mca_tick_info_t info;
    for (int k = 0; k < ticks; k++) {
        if (mca_controller_tick(ctrl, k * cfg->dt, qs, qds, &info) != MCA_OK) {
            faults++;
            mca_controller_reset(ctrl); /* the task again from q0 */
            memcpy(q, q0, sizeof q);
            continue;
        }
        if (k % every == 0) {
            const double *cphi;
            const mca_qp_t *qp = mca_controller_last_qp(ctrl, &cphi);
            mca_pdnn_result_t pr;
            int64_t best = INT64_MAX;
            for (int r = 0; r < 3; r++) {
                /* the least of 3: the CPU's cost, not a stall of the host (that is the wall clock's part) */
                mca_pdnn_init(&cold);
                const int64_t t0 = now_ns();
                mca_pdnn_solve(&cold, qp, &prm, phi, &pr);
                const int64_t t1 = now_ns();
                best = t1 - t0 < best ? t1 - t0 : best;
            }
            if (pr.steps >= steps / 2) {
                ns[n++] = (double)best / pr.steps;
                max_n = qp->n > max_n ? qp->n : max_n;
                max_ineq = qp->n_ineq > max_ineq ? qp->n_ineq : max_ineq;
            }
        }
        for (int a = 0; a < na; a++) {
            for (int j = 0; j < cfg->chain[a].dof; j++) {
                q[a][j] += qd[a][j] * cfg->dt;
            }
        }
    }
    int64_t *v = calloc((size_t)n + 1, sizeof *v);
    if (!v) {
        free(ns);
        return MCA_ENOMEM;
    }
    for (int i = 0; i < n; i++) {
        v[i] = (int64_t)llround(ns[i]);
    }
    qsort(v, (size_t)n, sizeof *v, cmp_i64);
    fprintf(
        of,
        "%s %s form %s: %d QPs (n <= %d, n_ineq <= %d, %d faults restarted), ns per step p50 %lld p99 %lld "
        "p99.9 %lld max %lld\n",
        name, mca_scheme_name(cfg->scheme), cfg->sp.form == MCA_FORM_NORMAL ? "normal" : "componentwise", n,
        max_n, max_ineq, faults, (long long)pct_i64(v, n, 0.5), (long long)pct_i64(v, n, 0.99),
        (long long)pct_i64(v, n, 0.999), (long long)(n ? v[n - 1] : 0));
    free(v);
    free(ns);
    return MCA_OK;
}

/* One whole task of a scenario (the paper's scheme) from a fresh controller, its stats as JSON: the run
 * object (rt < 0), or task mode's document around it. */
static int task_run(const char *scenario, int ticks, mca_controller_config_t *cfg, mca_controller_t *ctrl,
                    int split, qp_dump_t *dump, FILE *of, int rt) {
    static mca_scenario_t scn;
    static double q0[MCA_MAX_ARMS][MCA_MAX_DOF];
    char err[1024] = "";
    int rc;
    if ((rc = mca_scenario_load(scenario, &scn, err, sizeof err)) != MCA_OK ||
        (rc = mca_controller_config_from_scenario(cfg, &scn, MCA_SCHEME_MCA, err, sizeof err)) != MCA_OK) {
        fprintf(stderr, "bench_tick: %s\n", err);
        return rc;
    }
    memset(q0, 0, sizeof q0);
    for (int a = 0; a < scn.n_arms; a++) {
        memcpy(q0[a], scn.arm[a].q0, sizeof q0[a]);
    }
    if (ticks <= 0) {
        ticks = (int)llround(scn.duration / cfg->dt);
    }
    if ((rc = mca_controller_init(ctrl, cfg)) != MCA_OK) {
        fprintf(stderr, "bench_tick: controller init: %s\n", mca_strerror(rc));
        return rc;
    }
    run_stats_t s;
    if ((rc = stats_alloc(&s, ticks)) != MCA_OK) {
        stats_free(&s);
        return rc;
    }
    static drive_state_t ds;
    drive_start(&ds, (const double(*)[MCA_MAX_DOF])q0);
    rc = drive(ctrl, &ds, ticks, &s, dump, split);
    if (rt >= 0) {
        fprintf(of,
                "{\"mode\": \"task\", \"scenario\": \"%s\", \"sched_fifo\": %d, \"qp_dumped\": %d, \"run\": ",
                scn.name, rt, dump ? dump->written : 0);
    }
    stats_json(of, &s, scn.name, mca_controller_get_config(ctrl), mca_controller_last_qp(ctrl, NULL));
    if (rt >= 0) {
        fprintf(of, "}\n");
    }
    stats_free(&s);
    return rc;
}

static int set_fifo(int prio) {
    if (prio <= 0) {
        return 0;
    }
    struct sched_param sp = {.sched_priority = prio};
    if (sched_setscheduler(0, SCHED_FIFO, &sp) != 0) {
        fprintf(stderr, "bench_tick: SCHED_FIFO %d refused (%s): running SCHED_OTHER\n", prio,
                strerror(errno));
        return 0;
    }
    if (mlockall(MCL_CURRENT | MCL_FUTURE) != 0) {
        fprintf(stderr, "bench_tick: mlockall failed (%s)\n", strerror(errno));
    }
    return 1;
}

static void usage(FILE *f) {
    fprintf(f,
            "usage: bench_tick task --scenario FILE [--ticks N] [--out JSON] [--qp-dir DIR] [--qp-every E]\n"
            "                       [--qp-block L] [--fifo PRIO]\n"
            "       bench_tick scaling --urdf-dir DIR [--ticks N] [--out JSON] [--quick] [--gap M]\n"
            "                          [--fifo PRIO]\n"
            "       bench_tick steps --scenario FILE [--scheme mca|mca-ts] [--form normal|componentwise]\n"
            "                        [--every E] [--steps S] [--ticks N] [--fifo PRIO]\n"
            "       bench_tick pair --scenario FILE --scenario-b FILE [--pairs P] [--ticks N] [--out JSON]\n"
            "                       [--fifo PRIO]\n"
            "       task, pair: [--no-split] (the tick alone, for callgrind)\n");
}

static int parse_pos(const char *opt, const char *v, int *out) {
    char *end;
    errno = 0;
    const long x = v ? strtol(v, &end, 10) : 0;
    if (!v || errno || *end || x < 1 || x > 10000000) {
        fprintf(stderr, "bench_tick: %s: bad value '%s'\n", opt, v ? v : "(none)");
        return -1;
    }
    *out = (int)x;
    return 0;
}

int main(int argc, char **argv) {
    if (argc < 2 || !strcmp(argv[1], "-h") || !strcmp(argv[1], "--help")) {
        usage(argc < 2 ? stderr : stdout);
        return argc < 2 ? 2 : 0;
    }
    const char *mode = argv[1];
    if (strcmp(mode, "task") && strcmp(mode, "scaling") && strcmp(mode, "steps") && strcmp(mode, "pair")) {
        fprintf(stderr, "bench_tick: unknown mode '%s'\n", mode);
        usage(stderr);
        return 2;
    }
    const char *scenario = NULL, *scenario_b = NULL, *out = NULL, *urdf_dir = NULL;
    int ticks = 0, fifo = 0, quick = 0, split = 1, pairs = 5;
    double gap = 0.22;
    int every = 20, steps = 1000, form = -1;
    mca_scheme_kind_t scheme = MCA_SCHEME_MCA;
    qp_dump_t dump = {.dir = NULL, .every = 1000, .block_len = 10, .block = -1, .idx = -1};
    for (int i = 2; i < argc; i++) {
        const char *a = argv[i], *v = i + 1 < argc ? argv[i + 1] : NULL;
        if (!strcmp(a, "--quick")) {
            quick = 1;
            continue;
        }
        if (!strcmp(a, "--no-split")) {
            split = 0;
            continue;
        }
        i++;
        if (!strcmp(a, "--scenario") && v) {
            scenario = v;
        } else if (!strcmp(a, "--scenario-b") && v) {
            scenario_b = v;
        } else if (!strcmp(a, "--pairs")) {
            if (parse_pos(a, v, &pairs)) {
                return 2;
            }
        } else if (!strcmp(a, "--out") && v) {
            out = v;
        } else if (!strcmp(a, "--urdf-dir") && v) {
            urdf_dir = v;
        } else if (!strcmp(a, "--scheme") && v) {
            if (mca_scheme_from_name(v, &scheme) != MCA_OK) {
                fprintf(stderr, "bench_tick: --scheme: unknown '%s'\n", v);
                return 2;
            }
        } else if (!strcmp(a, "--form") && v) {
            form = !strcmp(v, "normal")          ? MCA_FORM_NORMAL
                   : !strcmp(v, "componentwise") ? MCA_FORM_COMPONENTWISE
                                                 : -2;
            if (form == -2) {
                fprintf(stderr, "bench_tick: --form: unknown '%s'\n", v);
                return 2;
            }
        } else if (!strcmp(a, "--every")) {
            if (parse_pos(a, v, &every)) {
                return 2;
            }
        } else if (!strcmp(a, "--steps")) {
            if (parse_pos(a, v, &steps)) {
                return 2;
            }
        } else if (!strcmp(a, "--qp-dir") && v) {
            dump.dir = v;
        } else if (!strcmp(a, "--gap") && v) {
            char *end;
            gap = strtod(v, &end);
            if (*end || !(gap > 0.0 && gap < 2.0)) {
                fprintf(stderr, "bench_tick: --gap: bad value '%s'\n", v);
                return 2;
            }
        } else if (!strcmp(a, "--ticks")) {
            if (parse_pos(a, v, &ticks)) {
                return 2;
            }
        } else if (!strcmp(a, "--fifo")) {
            if (parse_pos(a, v, &fifo)) {
                return 2;
            }
        } else if (!strcmp(a, "--qp-every")) {
            if (parse_pos(a, v, &dump.every)) {
                return 2;
            }
        } else if (!strcmp(a, "--qp-block")) {
            if (parse_pos(a, v, &dump.block_len)) {
                return 2;
            }
        } else {
            fprintf(stderr, "bench_tick: unknown option or missing value: '%s'\n", a);
            usage(stderr);
            return 2;
        }
    }
    FILE *of = stdout;
    if (out && !(of = fopen(out, "w"))) {
        fprintf(stderr, "bench_tick: %s: %s\n", out, strerror(errno));
        return 1;
    }
    const int rt = set_fifo(fifo);
    mca_controller_config_t *cfg = calloc(1, sizeof *cfg);
    mca_controller_t *ctrl = calloc(1, mca_controller_size());
    static double q0[MCA_MAX_ARMS][MCA_MAX_DOF];
    char err[1024] = "";
    int rc = MCA_OK;
    if (!cfg || !ctrl) {
        return 1;
    }
    if (!strcmp(mode, "steps")) {
        static mca_scenario_t scn;
        if (!scenario) {
            fprintf(stderr, "bench_tick: steps needs --scenario FILE\n");
            return 2;
        }
        if ((rc = mca_scenario_load(scenario, &scn, err, sizeof err)) != MCA_OK ||
            (rc = mca_controller_config_from_scenario(cfg, &scn, scheme, err, sizeof err)) != MCA_OK) {
            fprintf(stderr, "bench_tick: %s\n", err);
            return 1;
        }
        if (form >= 0) {
            cfg->sp.form = (mca_collision_form_t)form;
        }
        for (int a = 0; a < scn.n_arms; a++) {
            memcpy(q0[a], scn.arm[a].q0, sizeof q0[a]);
        }
        if (ticks <= 0) {
            ticks = (int)llround(scn.duration / cfg->dt);
        }
        if ((rc = mca_controller_init(ctrl, cfg)) != MCA_OK ||
            (rc = run_step_cost(ctrl, (const double(*)[MCA_MAX_DOF])q0, ticks, every, steps, of, scn.name)) !=
                MCA_OK) {
            fprintf(stderr, "bench_tick: %s\n", mca_strerror(rc));
            return 1;
        }
    } else if (!strcmp(mode, "task") || !strcmp(mode, "pair")) {
        const int pair = !strcmp(mode, "pair");
        if (!scenario || (pair && !scenario_b)) {
            fprintf(stderr, "bench_tick: %s needs --scenario FILE%s\n", mode,
                    pair ? " --scenario-b FILE" : "");
            return 2;
        }
        if (dump.dir) {
            char p[1024];
            if (mkdir(dump.dir, 0755) != 0 && errno != EEXIST) {
                fprintf(stderr, "bench_tick: --qp-dir %s: %s\n", dump.dir, strerror(errno));
                return 1;
            }
            snprintf(p, sizeof p, "%s/pdnn.csv", dump.dir);
            if (!(dump.csv = fopen(p, "w"))) {
                fprintf(stderr, "bench_tick: %s: %s\n", p, strerror(errno));
                return 1;
            }
            fprintf(dump.csv, "file,block,idx,warm_ns,steps,cold_ns,cold_steps,active_rows\n");
        }
        if (pair) {
            fprintf(of, "{\"mode\": \"pair\", \"sched_fifo\": %d, \"runs\": [\n", rt);
        }
        /* pair: A B A B ..., each run the whole task from a fresh controller */
        for (int r = 0; r < (pair ? 2 * pairs : 1) && rc == MCA_OK; r++) {
            if (pair) {
                fprintf(of, "%s{\"pair\": %d, \"which\": \"%s\", \"run\": ", r ? ",\n" : "", r / 2,
                        r % 2 ? "b" : "a");
            }
            rc = task_run(r % 2 ? scenario_b : scenario, ticks, cfg, ctrl, split, dump.dir ? &dump : NULL, of,
                          pair ? -1 : rt);
            if (pair) {
                fprintf(of, "}");
            }
        }
        if (pair) {
            fprintf(of, "]}\n");
        }
        if (dump.csv) {
            fclose(dump.csv);
        }
        if (rc != MCA_OK) {
            return 1;
        }
    } else {
        if (!urdf_dir) {
            fprintf(stderr, "bench_tick: scaling needs --urdf-dir DIR (config/robots)\n");
            return 2;
        }
        static mca_chain_t pa10;
        char path[1024];
        snprintf(path, sizeof path, "%s/pa10plus.urdf", urdf_dir);
        if ((rc = mca_chain_load_urdf(&pa10, path, "tool_tip", err, sizeof err)) != MCA_OK) {
            fprintf(stderr, "bench_tick: %s\n", err);
            return 1;
        }
        if (ticks <= 0) {
            ticks = quick ? 300 : 2000;
        }
        /* sweeps: arms x dof at d2 0.12; then d2 (more critical points inside the band) at 2 x 8 */
        typedef struct cfgdef {
            const char *sweep;
            int arms, dof;
            double d2;
        } cfgdef_t;
        cfgdef_t defs[64];
        int nd = 0;
        for (int arms = 2; arms <= MCA_MAX_ARMS; arms++) {
            for (int dof = 4; dof <= 8; dof++) {
                if (!quick || dof == 4 || dof == 8) {
                    defs[nd++] = (cfgdef_t){"arms_dof", arms, dof, 0.12};
                }
            }
        }
        static const double d2s[] = {0.2, 0.3, 0.45, 0.7, 1.0};
        for (int k = 0; k < (int)(sizeof d2s / sizeof d2s[0]); k++) {
            if (!quick || k == 4) {
                defs[nd++] = (cfgdef_t){"d2", 2, 8, d2s[k]};
            }
        }
        /* every cell keeps its own controller and task state; the cells run round-robin in `rounds` slices
         * (100 ticks each by default) so that a change of the host's load touches all of them alike */
        const int rounds = quick ? 1 : 20;
        mca_controller_t **cc = calloc((size_t)nd, sizeof *cc);
        drive_state_t *dss = calloc((size_t)nd, sizeof *dss);
        run_stats_t *ss = calloc((size_t)nd, sizeof *ss);
        if (!cc || !dss || !ss) {
            return 1;
        }
        for (int c = 0; c < nd; c++) {
            /* default gap 0.22 m: the circles (2 R = 0.16 m inwards) bring neighbouring arms inside d2 = 0.12
             */
            cc[c] = calloc(1, mca_controller_size());
            if (!cc[c] || stats_alloc(&ss[c], ticks) != MCA_OK) {
                return 1;
            }
            if ((rc = synth_config(cfg, q0, &pa10, defs[c].arms, defs[c].dof, gap, defs[c].d2)) != MCA_OK ||
                (rc = mca_controller_init(cc[c], cfg)) != MCA_OK) {
                fprintf(stderr, "bench_tick: config %d arms %d dof: %s\n", defs[c].arms, defs[c].dof,
                        mca_strerror(rc));
                return 1;
            }
            drive_start(&dss[c], (const double(*)[MCA_MAX_DOF])q0);
        }
        for (int r = 0; r < rounds; r++) {
            for (int c = 0; c < nd; c++) {
                const int n = ticks * (r + 1) / rounds - ticks * r / rounds;
                if ((rc = drive(cc[c], &dss[c], n, &ss[c], NULL, 1)) != MCA_OK) {
                    return 1;
                }
            }
        }
        fprintf(of,
                "{\"mode\": \"scaling\", \"sched_fifo\": %d, \"ticks_per_config\": %d, \"rounds\": %d, "
                "\"runs\": [\n",
                rt, ticks, rounds);
        for (int c = 0; c < nd; c++) {
            char name[64];
            snprintf(name, sizeof name, "%s:%dx%d:d2=%g", defs[c].sweep, defs[c].arms, defs[c].dof,
                     defs[c].d2);
            stats_json(of, &ss[c], name, &cc[c]->cfg, &cc[c]->qp);
            fprintf(of, "%s\n", c + 1 < nd ? "," : "");
            stats_free(&ss[c]);
            free(cc[c]);
        }
        free(cc);
        free(dss);
        free(ss);
        fprintf(of, "]}\n");
    }
    if (of != stdout) {
        fclose(of);
    }
    free(ctrl);
    free(cfg);
    return rc == MCA_OK ? 0 : 1;
}
