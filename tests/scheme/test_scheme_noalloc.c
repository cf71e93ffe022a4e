/* SPDX-License-Identifier: MIT */
/* No heap allocation inside mca_controller_tick (every scheme, mca-ts with its deadlock back-off) and
 * mca_controller_brake (the braking QP and its fallback): malloc, calloc, realloc, free, posix_memalign,
 * aligned_alloc and C++ operator new/delete are wrapped at link time (-Wl,--wrap) and counted while a
 * tick runs. Runs the cross-circles task (2 x 8-DOF PA10+: MCA with binding collision rows in both forms,
 * MVN, APF, and the NaN, not-converged and fake-attractor faults), the cup-stacking task (6-DOF JACO2 +
 * MICO2: MCA through its binding window at 14.6-15.9 s, MVN, APF) and the paper's LSDM distance path
 * (MCA_DIST_LSDM) on both, for enough ticks to go through every branch; FAILS on any allocation. */
#include <math.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "mca/controller.h"
#include "mca/err.h"
#include "mca/scenario.h"

static int counting;
static long allocs;

void *__real_malloc(size_t n);
void *__real_calloc(size_t a, size_t b);
void *__real_realloc(void *p, size_t n);
void __real_free(void *p);
int __real_posix_memalign(void **p, size_t a, size_t n);
void *__real_aligned_alloc(size_t a, size_t n);
void *__real__Znwm(size_t n);
void *__real__Znam(size_t n);
void __real__ZdlPv(void *p);
void __real__ZdaPv(void *p);

void *__wrap_malloc(size_t n) {
    allocs += counting;
    return __real_malloc(n);
}
void *__wrap_calloc(size_t a, size_t b) {
    allocs += counting;
    return __real_calloc(a, b);
}
void *__wrap_realloc(void *p, size_t n) {
    allocs += counting;
    return __real_realloc(p, n);
}
void __wrap_free(void *p) {
    allocs += counting && p;
    __real_free(p);
}
int __wrap_posix_memalign(void **p, size_t a, size_t n) {
    allocs += counting;
    return __real_posix_memalign(p, a, n);
}
void *__wrap_aligned_alloc(size_t a, size_t n) {
    allocs += counting;
    return __real_aligned_alloc(a, n);
}
void *__wrap__Znwm(size_t n) {
    allocs += counting;
    return __real__Znwm(n);
}
void *__wrap__Znam(size_t n) {
    allocs += counting;
    return __real__Znam(n);
}
void __wrap__ZdlPv(void *p) {
    allocs += counting && p;
    __real__ZdlPv(p);
}
void __wrap__ZdaPv(void *p) {
    allocs += counting && p;
    __real__ZdaPv(p);
}

enum { CROSS_CIRCLES, CUP_STACKING, NEGATIVE, CUP_BODIES, SELF_FOLD, N_SCENARIOS };
static const char *const scenario_file[N_SCENARIOS] = {
    "cross_circles.yaml", "cup_stacking.yaml", "negative.yaml", "cup_stacking_bodies.yaml", "self_fold.yaml"};

struct variant {
    const char *what;
    int scenario;
    mca_dist_method_t dist;
    int need_binding; /* 1: the run must reach binding collision rows (else it proves nothing about them) */
    mca_scheme_kind_t scheme;
    int form;       /* -1: the scenario's */
    double v_floor; /* < 0: keep */
    double eq_tol;  /* <= 0: keep (tiny: forces the fake-attractor branch) */
    int max_steps;  /* <= 0: keep (1: forces the not-converged branch) */
    int nan_at;     /* tick that gets a NaN joint (-1: none) */
    int ticks;
};

static int run(const char *path, const struct variant *v, long *ticks_faulted, long *binding) {
    static mca_scenario_t s;
    static mca_controller_config_t cfg;
    char err[512];
    if (mca_scenario_load(path, &s, err, sizeof err) != MCA_OK ||
        mca_controller_config_from_scenario(&cfg, &s, v->scheme, err, sizeof err) != MCA_OK) {
        fprintf(stderr, "setup: %s\n", err);
        return -1;
    }
    if (v->form >= 0) {
        cfg.sp.form = (mca_collision_form_t)v->form;
    }
    if (v->v_floor >= 0.0) {
        cfg.sp.v_floor = v->v_floor;
    }
    if (v->eq_tol > 0.0) {
        cfg.eq_tol = v->eq_tol;
    }
    if (v->max_steps > 0) {
        cfg.pdnn.max_steps = v->max_steps;
    }
    if (v->max_steps > 0 || v->eq_tol > 0.0) {
        cfg.pdnn.no_polish = 1; /* the polish would finish these exactly at step 0: no fault, no cap */
    }
    cfg.dist_method = v->dist;
    mca_controller_t *c = malloc(mca_controller_size());
    if (!c || mca_controller_init(c, &cfg) != MCA_OK) {
        free(c);
        return -1;
    }
    double q[MCA_MAX_ARMS][MCA_MAX_DOF], qd[MCA_MAX_ARMS][MCA_MAX_DOF];
    const double *qs[MCA_MAX_ARMS];
    double *qds[MCA_MAX_ARMS];
    for (int a = 0; a < MCA_MAX_ARMS; a++) {
        qs[a] = q[a];
        qds[a] = qd[a];
    }
    for (int a = 0; a < s.n_arms; a++) {
        memcpy(q[a], s.arm[a].q0, sizeof q[a]);
    }
    mca_tick_info_t info;
    for (int k = 0; k < v->ticks; k++) {
        const double keep = q[0][0];
        if (k == v->nan_at) {
            q[0][0] = NAN;
        }
        counting = 1;
        const int rc = mca_controller_tick(c, k * cfg.dt, qs, qds, &info);
        counting = 0;
        q[0][0] = keep;
        if (rc != MCA_OK && rc != MCA_EFAULT) {
            free(c);
            return -1;
        }
        *ticks_faulted += rc == MCA_EFAULT;
        *binding += info.binding_rows > 0;
        for (int a = 0; a < s.n_arms; a++) {
            for (int j = 0; j < cfg.chain[a].dof; j++) {
                q[a][j] += qd[a][j] * cfg.dt;
            }
        }
    }
    /* then a stop: the braking QP from the last command to rest, and one fallback tick (NaN input) */
    double vl[MCA_MAX_ARMS][MCA_MAX_DOF], dec[MCA_MAX_ARMS][MCA_MAX_DOF];
    const double *vls[MCA_MAX_ARMS], *ds[MCA_MAX_ARMS];
    for (int a = 0; a < MCA_MAX_ARMS; a++) {
        for (int j = 0; j < MCA_MAX_DOF; j++) {
            vl[a][j] = qd[a][j];
            dec[a][j] = 2.0;
        }
        vls[a] = vl[a];
        ds[a] = dec[a];
    }
    for (int k = 0; k < 2000; k++) {
        if (k == 1999) {
            q[0][0] = NAN;
        }
        counting = 1;
        const int rc = mca_controller_brake(c, (v->ticks + k) * cfg.dt, qs, vls, ds, qds, &info);
        counting = 0;
        if (rc < 0) {
            free(c);
            return -1;
        }
        for (int a = 0; a < s.n_arms; a++) {
            for (int j = 0; j < cfg.chain[a].dof; j++) {
                vl[a][j] = qd[a][j];
                q[a][j] += qd[a][j] * cfg.dt;
            }
        }
    }
    free(c);
    return 0;
}

int main(int argc, char **argv) {
    if (argc != 2) {
        fprintf(stderr, "usage: test_scheme_noalloc SCENARIO_DIR\n");
        return 2;
    }
    char paths[N_SCENARIOS][512];
    for (int i = 0; i < N_SCENARIOS; i++) {
        snprintf(paths[i], sizeof paths[i], "%s/%s", argv[1], scenario_file[i]);
    }
    /* self-check: the wrapping works (else the test could not fail) */
    void *(*volatile m)(size_t) = malloc;
    void (*volatile f)(void *) = free;
    counting = 1;
    void *volatile probe = m(16);
    f(probe);
    counting = 0;
    if (allocs != 2) {
        fprintf(stderr, "FAIL: malloc/free are not wrapped (counted %ld of 2)\n", allocs);
        return 1;
    }
    allocs = 0;
    /* Every branch of the tick: MCA normal form (active rows), componentwise with a floor (binding rows
     * from the start), MVN, APF, a NaN input (latched fault afterwards), the not-converged and the
     * fake-attractor faults (forced by a 1-step cap and a tiny eq_tol); the 6-DOF arms of task 3 (16 000
     * ticks: through the binding window); the LSDM distance path on both tasks. */
    const struct variant vs[] = {
        {"cross_circles mca normal", CROSS_CIRCLES, MCA_DIST_CLOSED, 0, MCA_SCHEME_MCA, MCA_FORM_NORMAL, -1,
         0, 0, -1, 300},
        {"cross_circles mca componentwise", CROSS_CIRCLES, MCA_DIST_CLOSED, 1, MCA_SCHEME_MCA,
         MCA_FORM_COMPONENTWISE, 0.0, 0, 0, -1, 300},
        {"cross_circles mvn", CROSS_CIRCLES, MCA_DIST_CLOSED, 0, MCA_SCHEME_MVN, -1, -1, 0, 0, -1, 200},
        {"cross_circles apf", CROSS_CIRCLES, MCA_DIST_CLOSED, 0, MCA_SCHEME_APF, -1, -1, 0, 0, -1, 200},
        {"cross_circles mca nan", CROSS_CIRCLES, MCA_DIST_CLOSED, 0, MCA_SCHEME_MCA, -1, -1, 0, 0, 50, 100},
        {"cross_circles mca not-converged", CROSS_CIRCLES, MCA_DIST_CLOSED, 0, MCA_SCHEME_MCA, -1, -1, 0, 1,
         -1, 20},
        {"cross_circles mca fake-attractor", CROSS_CIRCLES, MCA_DIST_CLOSED, 0, MCA_SCHEME_MCA, -1, -1, 1e-14,
         0, -1, 20},
        {"cup_stacking mca normal", CUP_STACKING, MCA_DIST_CLOSED, 1, MCA_SCHEME_MCA, -1, -1, 0, 0, -1,
         16000},
        {"cup_stacking mvn", CUP_STACKING, MCA_DIST_CLOSED, 0, MCA_SCHEME_MVN, -1, -1, 0, 0, -1, 200},
        {"cup_stacking apf", CUP_STACKING, MCA_DIST_CLOSED, 0, MCA_SCHEME_APF, -1, -1, 0, 0, -1, 200},
        {"cross_circles mca componentwise lsdm", CROSS_CIRCLES, MCA_DIST_LSDM, 1, MCA_SCHEME_MCA,
         MCA_FORM_COMPONENTWISE, 0.0, 0, 0, -1, 300},
        {"cross_circles mca-ts", CROSS_CIRCLES, MCA_DIST_CLOSED, 0, MCA_SCHEME_MCA_TS, -1, -1, 0, 0, -1,
         3000},
        {"cross_circles mca-ts capped", CROSS_CIRCLES, MCA_DIST_CLOSED, 0, MCA_SCHEME_MCA_TS, -1, -1, 0, 1,
         -1, 300},
        {"negative mca-ts deadlock", NEGATIVE, MCA_DIST_CLOSED, 1, MCA_SCHEME_MCA_TS, -1, -1, 0, 0, -1, 8000},
        {"cup_stacking mca normal lsdm", CUP_STACKING, MCA_DIST_LSDM, 1, MCA_SCHEME_MCA, -1, -1, 0, 0, -1,
         16000},
        /* the fixed bodies' rows (a table and six cylinders), running and braking, both schemes */
        {"cup_stacking_bodies mca-ts", CUP_BODIES, MCA_DIST_CLOSED, 1, MCA_SCHEME_MCA_TS, -1, -1, 0, 0, -1,
         16000},
        {"cup_stacking_bodies mca", CUP_BODIES, MCA_DIST_CLOSED, 1, MCA_SCHEME_MCA, -1, -1, 0, 0, -1, 16000},
        /* the self rows (a PA10+ folding its elbow), through the fold, both schemes */
        {"self_fold mca-ts", SELF_FOLD, MCA_DIST_CLOSED, 1, MCA_SCHEME_MCA_TS, -1, -1, 0, 0, -1, 5000},
        {"self_fold mca", SELF_FOLD, MCA_DIST_CLOSED, 1, MCA_SCHEME_MCA, -1, -1, 0, 0, -1, 5000},
    };
    long faulted = 0, binding = 0, failed = 0;
    for (size_t i = 0; i < sizeof vs / sizeof vs[0]; i++) {
        const long fb = faulted, bb = binding, ab = allocs;
        if (run(paths[vs[i].scenario], &vs[i], &faulted, &binding)) {
            fprintf(stderr, "FAIL: run error in variant %zu (%s)\n", i, vs[i].what);
            return 1;
        }
        printf("%-38s %6d ticks, %5ld with binding rows, %4ld faulted, %ld allocations\n", vs[i].what,
               vs[i].ticks, binding - bb, faulted - fb, allocs - ab);
        /* a capped mca-ts answer is scaled into the rows instead (no fault) */
        const int must_fault = vs[i].nan_at >= 0 || ((vs[i].max_steps > 0 || vs[i].eq_tol > 0.0) &&
                                                     vs[i].scheme != MCA_SCHEME_MCA_TS);
        if (must_fault && faulted == fb) {
            fprintf(stderr, "FAIL: variant %zu (%s) did not fault\n", i, vs[i].what);
            failed++;
        }
        if (vs[i].need_binding && binding == bb) {
            fprintf(stderr, "FAIL: variant %zu (%s) did not reach binding collision rows\n", i, vs[i].what);
            failed++;
        }
    }
    printf("ticks with binding collision rows: %ld, faulted ticks: %ld, allocations during ticks: %ld\n",
           binding, faulted, allocs);
    if (allocs != 0) {
        fprintf(stderr, "FAIL: %ld heap allocations inside mca_controller_tick\n", allocs);
        return 1;
    }
    return failed ? 1 : 0;
}
