/* SPDX-License-Identifier: MIT */
/* Cost of the kinematics one arm needs per 1 ms control cycle: mca_fk plus one point Jacobian
 * per link (the scheme's critical points) plus the end-effector Jacobian.
 * Usage: bench_kin [ROBOTS_DIR]   Prints the median over repeated batches, and its ratio to 1 ms. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

#include "mca/chain.h"
#include "mca/err.h"
#include "mca/urdf.h"

#define BATCH 2000
#define N_BATCH 51

static double now_ns(void) {
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec * 1e9 + (double)ts.tv_nsec;
}

static int cmp_double(const void *a, const void *b) {
    const double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

static volatile double sink; /* keeps the work from being optimised away */

static int bench_robot(const char *dir, const char *file) {
    char path[512], err[512];
    snprintf(path, sizeof(path), "%s/%s", dir, file);
    mca_chain_t c;
    int rc = mca_chain_load_urdf(&c, path, "tool_tip", err, sizeof(err));
    if (rc != MCA_OK) {
        fprintf(stderr, "bench_kin: %s\n", err);
        return 1;
    }
    const double xyz[3] = {0.1, 0.2, 0.0}, rpy[3] = {0.0, 0.0, 0.5};
    mca_chain_set_base(&c, xyz, rpy);
    double q[MCA_MAX_DOF];
    double t_fk[N_BATCH], t_all[N_BATCH];
    mca_kin_t kin;
    double J[3][MCA_MAX_DOF];
    for (int b = 0; b < N_BATCH; b++) {
        double acc = 0.0;
        const double t0 = now_ns();
        for (int i = 0; i < BATCH; i++) {
            for (int j = 0; j < c.dof; j++) {
                q[j] = 0.3 + 1e-4 * (i + j);
            }
            mca_fk(&c, q, &kin);
            acc += kin.ee[0];
        }
        const double t1 = now_ns();
        for (int i = 0; i < BATCH; i++) {
            for (int j = 0; j < c.dof; j++) {
                q[j] = 0.3 + 1e-4 * (i + j);
            }
            mca_fk(&c, q, &kin);
            for (int l = 0; l <= c.dof; l++) {
                mca_jacobian_point(&kin, l, kin.point[l + 1], J);
                acc += J[0][0];
            }
            mca_jacobian_ee(&kin, J);
            acc += J[1][0];
        }
        const double t2 = now_ns();
        sink = acc;
        t_fk[b] = (t1 - t0) / BATCH;
        t_all[b] = (t2 - t1) / BATCH;
    }
    qsort(t_fk, N_BATCH, sizeof(double), cmp_double);
    qsort(t_all, N_BATCH, sizeof(double), cmp_double);
    const double fk = t_fk[N_BATCH / 2], all = t_all[N_BATCH / 2];
    printf("%-10s dof %d: mca_fk %7.1f ns | fk + %d point Jacobians + EE Jacobian %7.1f ns = %.5f of a 1 ms "
           "cycle\n",
           c.name, c.dof, fk, c.dof + 1, all, all / 1e6);
    return 0;
}

int main(int argc, char **argv) {
    const char *dir = argc > 1 ? argv[1] : MCA_ROBOTS_DIR;
    int bad = 0;
    bad |= bench_robot(dir, "jaco2.urdf");
    bad |= bench_robot(dir, "mico2.urdf");
    bad |= bench_robot(dir, "pa10plus.urdf");
    return bad;
}
