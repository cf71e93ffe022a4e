/* SPDX-License-Identifier: MIT */
/* A thin C shim over DAQP (https://github.com/darnstrom/daqp, MIT) for bench_pdnn's `daqp` mode. Not built
 * by CMake and no DAQP code in this repository: bench/daqp/build.sh compiles this file together with the
 * C sources of the daqp sdist from PyPI into a shared library outside the repository, which bench_pdnn
 * dlopens (so that bench_pdnn needs neither DAQP's headers nor its struct layout).
 *
 * The QP is mca's: minimize 1/2 x'x s.t. G x = alpha, U x <= beta, lb <= x <= ub. DAQP's form:
 * blower <= [x; A x] <= bupper with H = I, f = NULL; the equality rows are sense ACTIVE|IMMUTABLE.
 * Warm: while n, n_eq, n_ineq stay the same, one workspace is kept; each call writes the new data into it
 * (daqp_update_ldp with M and d, not sense), so that DAQP starts from the previous QP's working set. */
#include <stdlib.h>
#include <string.h>

#include "api.h"
#include "constants.h"
#include "utils.h"

static DAQPWorkspace work;
static DAQPProblem prob;
static double *H, *A, *bu, *bl;
static int *sense;
static int have, cur_n, cur_ne, cur_ni;

static void drop(void) {
    if (have) {
        free_daqp_workspace(&work);
        free_daqp_ldp(&work);
        free(H);
        free(A);
        free(bu);
        free(bl);
        free(sense);
        have = 0;
    }
}

/* G: ne x stride, U: ni x stride (row major, first n columns used). warm 0 forces a fresh workspace.
 * Returns DAQP's exit flag (> 0 solved); x (n), *iter (DAQP's iterations), *cold (1 if set up anew). */
int mca_daqp_solve(int n, int ne, int ni, const double *G, const double *alpha, const double *U,
                   const double *beta, const double *lb, const double *ub, int stride, int warm, double *x,
                   int *iter, int *cold) {
    const int m = n + ne + ni;
    const int fresh = !warm || !have || n != cur_n || ne != cur_ne || ni != cur_ni;
    if (fresh) {
        drop();
        H = calloc((size_t)n * (size_t)n, sizeof(double));
        A = calloc((size_t)(ne + ni) * (size_t)n, sizeof(double));
        bu = calloc((size_t)m, sizeof(double));
        bl = calloc((size_t)m, sizeof(double));
        sense = calloc((size_t)m, sizeof(int));
        for (int i = 0; i < n; i++) {
            H[i * n + i] = 1.0;
        }
        for (int i = 0; i < ne; i++) {
            sense[n + i] = DAQP_ACTIVE + DAQP_IMMUTABLE;
        }
    }
    for (int j = 0; j < n; j++) {
        bl[j] = lb[j] < -DAQP_INF ? -DAQP_INF : lb[j];
        bu[j] = ub[j] > DAQP_INF ? DAQP_INF : ub[j];
    }
    for (int i = 0; i < ne; i++) {
        memcpy(A + (size_t)i * (size_t)n, G + (size_t)i * (size_t)stride, sizeof(double) * (size_t)n);
        bl[n + i] = bu[n + i] = alpha[i];
    }
    for (int i = 0; i < ni; i++) {
        memcpy(A + (size_t)(ne + i) * (size_t)n, U + (size_t)i * (size_t)stride, sizeof(double) * (size_t)n);
        bu[n + ne + i] = beta[i];
        bl[n + ne + i] = -DAQP_INF;
    }
    int flag;
    if (fresh) {
        memset(&work, 0, sizeof work);
        memset(&prob, 0, sizeof prob);
        prob.n = n;
        prob.m = m;
        prob.ms = n;
        prob.H = H;
        prob.f = NULL;
        prob.A = A;
        prob.bupper = bu;
        prob.blower = bl;
        prob.sense = sense;
        flag = setup_daqp(&prob, &work, NULL);
        if (flag < 0) {
            return flag;
        }
        have = 1;
        cur_n = n;
        cur_ne = ne;
        cur_ni = ni;
    } else {
        flag = daqp_update_ldp(DAQP_UPDATE_M + DAQP_UPDATE_d, &work, &prob);
        if (flag < 0) {
            return flag;
        }
    }
    DAQPResult res;
    res.x = x;
    res.lam = NULL; /* the multipliers are not compared */
    daqp_solve(&res, &work);
    *iter = res.iter;
    *cold = fresh;
    return res.exitflag;
}

void mca_daqp_free(void) {
    drop();
}
