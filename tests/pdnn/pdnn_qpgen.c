/* SPDX-License-Identifier: MIT */
/* pdnn_qpgen OUTDIR COUNT [SEED]: make COUNT random feasible dual-arm-shaped QPs (tests/pdnn/qpgen.h) in
 * runs of 10 control ticks (a fresh scene solved cold, then 9 small moves solved warm; of every three runs
 * one is in the componentwise form (54 rows), one in the normal form (18 rows) and one componentwise with a
 * row coupling the two arms, so the split and the single-network paths are both checked), solve each with
 * the LVI-PDNN at default parameters and dump it with its answer (mca_qp_dump_json) for
 * tools/qp-check/osqp_check.py. Exit 0 when every solve converged, 1 otherwise, 2 on bad arguments/I/O. */
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "mca/err.h"
#include "mca/pdnn.h"
#include "mca/qp_dump.h"
#include "qpgen.h"

static mca_pdnn_t solver; /* large: keep off the stack */

int main(int argc, char **argv) {
    if (argc < 3 || argc > 4) {
        fprintf(stderr, "usage: %s OUTDIR COUNT [SEED]\n", argv[0]);
        return 2;
    }
    char *end = NULL;
    const long count = strtol(argv[2], &end, 10);
    if (*end != '\0' || count < 1 || count > 1000000) {
        fprintf(stderr, "%s: COUNT must be an integer in [1, 1000000], got '%s'\n", argv[0], argv[2]);
        return 2;
    }
    if (mkdir(argv[1], 0777) != 0 && errno != EEXIST) {
        fprintf(stderr, "%s: cannot create %s: %s\n", argv[0], argv[1], strerror(errno));
        return 2;
    }
    qpgen_rng_t rng = {argc == 4 ? strtoull(argv[3], NULL, 10) : 1};
    mca_pdnn_params_t prm;
    mca_pdnn_default_params(&prm);
    prm.max_steps = 1000000; /* truth for the OSQP check, not the 1 kHz budget (that is bench/pdnn) */
    mca_pdnn_init(&solver);
    qpgen_scene_t sc;
    mca_qp_t qp;
    double phi[MCA_QP_MAX_VARS];
    long failed = 0, active_sum = 0, steps_cold = 0, steps_warm = 0, n_cold = 0;
    int active_max = 0, active_min = QPGEN_NINEQ;
    for (long k = 0; k < count; k++) {
        if (k % 10 == 0) {
            qpgen_scene_random(&sc, &rng, 0.15);
            mca_pdnn_init(&solver);
        } else {
            qpgen_scene_perturb(&sc, &rng, 1e-3);
        }
        if ((k / 10) % 3 == 1) { /* every third run: the normal form, one row per link */
            qpgen_build_normal(&sc, &qp);
        } else {
            qpgen_build(&sc, &qp);
        }
        if ((k / 10) % 3 == 2) { /* every third run: one row couples the arms (one block, not two) */
            qpgen_couple(&sc, &qp, QPGEN_NINEQ - 1);
        }
        mca_pdnn_result_t res;
        const int rc = mca_pdnn_solve(&solver, &qp, &prm, phi, &res);
        if (rc != MCA_OK) {
            fprintf(stderr, "qp %ld: %s (steps %d, residual %.3g)\n", k, mca_strerror(rc), res.steps,
                    res.residual);
            failed++;
        }
        if (res.warm) {
            steps_warm += res.steps;
        } else {
            steps_cold += res.steps;
            n_cold++;
        }
        int active = 0;
        for (int i = 0; i < qp.n_ineq; i++) {
            active += solver.y[qp.n + qp.n_eq + i] > 1e-9;
        }
        active_sum += active;
        active_max = active > active_max ? active : active_max;
        active_min = active < active_min ? active : active_min;
        char path[4096], tag[64];
        snprintf(path, sizeof(path), "%s/qp_%06ld.json", argv[1], k);
        snprintf(tag, sizeof(tag), "pdnn_qpgen seed %s #%ld", argc == 4 ? argv[3] : "1", k);
        if (mca_qp_dump_json(&qp, phi, res.steps, res.residual, tag, path) != MCA_OK) {
            fprintf(stderr, "%s: cannot write %s\n", argv[0], path);
            return 2;
        }
    }
    printf("pdnn_qpgen: %ld QPs, %ld not converged; active inequality rows min/mean/max %d/%.1f/%d; "
           "mean steps cold %.1f warm %.1f\n",
           count, failed, active_min, (double)active_sum / count, active_max,
           n_cold ? (double)steps_cold / n_cold : 0.0,
           count > n_cold ? (double)steps_warm / (count - n_cold) : 0.0);
    return failed ? 1 : 0;
}
