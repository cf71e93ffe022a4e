/* SPDX-License-Identifier: MIT */
/* Uses the installed headers and libraries: loads an installed URDF through the model library
 * (mca_chain_load_urdf, mca::model), loads an installed scenario (two arms; their URDFs found next to it)
 * into a controller config, runs controller ticks through the real-time core (mca_controller_create and
 * mca_controller_tick, mca::core), checks a segment distance against its closed form and S(d) of eq. (13),
 * and fills a DDS config (mca::dds).
 * usage: consumer URDF SCENARIO  -> prints "consumer: ok ..." and exits 0 */
#include <math.h>
#include <stddef.h> /* max_align_t */
#include <stdio.h>

#include "mca/chain.h"
#include "mca/controller.h"
#include "mca/dds_bridge.h"
#include "mca/err.h"
#include "mca/scenario.h"
#include "mca/scheme.h"
#include "mca/segdist.h"
#include "mca/urdf.h"

#define TICKS 20

int main(int argc, char **argv) {
    static mca_chain_t chain;
    static mca_scenario_t scn;
    static mca_controller_config_t ccfg;
    /* the controller in static storage: its documented bound, aligned as malloc's (not on the stack) */
    static _Alignas(max_align_t) unsigned char ctrl_mem[MCA_CONTROLLER_SIZE_MAX];
    mca_controller_t *ctrl = NULL;
    char err[512];
    if (argc < 3) {
        fprintf(stderr, "consumer: usage: consumer URDF SCENARIO\n");
        return 1;
    }
    if (mca_chain_load_urdf(&chain, argv[1], NULL, err, sizeof err) != MCA_OK) {
        fprintf(stderr, "consumer: %s\n", err);
        return 1;
    }
    /* the model library: scenario -> config (each arm's URDF loaded); the core: init and ticks */
    if (mca_scenario_load(argv[2], &scn, err, sizeof err) != MCA_OK ||
        mca_controller_config_from_scenario(&ccfg, &scn, MCA_SCHEME_MCA, err, sizeof err) != MCA_OK) {
        fprintf(stderr, "consumer: %s\n", err);
        return 1;
    }
    if (scn.n_arms != 2 || mca_controller_create(ctrl_mem, sizeof ctrl_mem, &ccfg, &ctrl) != MCA_OK) {
        fprintf(stderr, "consumer: %s: %d arms, controller init failed\n", argv[2], scn.n_arms);
        return 1;
    }
    double q[MCA_MAX_ARMS][MCA_MAX_DOF] = {{0}}, qdot[MCA_MAX_ARMS][MCA_MAX_DOF] = {{0}};
    const double *qp[MCA_MAX_ARMS] = {q[0], q[1]};
    double *qdp[MCA_MAX_ARMS] = {qdot[0], qdot[1]};
    for (int a = 0; a < scn.n_arms; a++) {
        for (int j = 0; j < ccfg.chain[a].dof; j++) {
            q[a][j] = scn.arm[a].q0[j];
        }
    }
    mca_tick_info_t info;
    double moved = 0.0;
    for (int k = 0; k < TICKS; k++) {
        const int rc = mca_controller_tick(ctrl, k * ccfg.dt, qp, qdp, &info);
        if (rc != MCA_OK) {
            fprintf(stderr, "consumer: tick %d: %s (fault %s)\n", k, mca_strerror(rc),
                    mca_ctrl_fault_name(info.fault));
            return 1;
        }
        for (int a = 0; a < scn.n_arms; a++) {
            for (int j = 0; j < ccfg.chain[a].dof; j++) {
                if (!isfinite(qdot[a][j])) {
                    fprintf(stderr, "consumer: tick %d: non-finite command\n", k);
                    return 1;
                }
                q[a][j] += qdot[a][j] * ccfg.dt;
                moved += fabs(qdot[a][j]) * ccfg.dt;
            }
        }
    }
    if (!(info.min_distance > ccfg.sp.d1) || !isfinite(info.min_distance)) {
        fprintf(stderr, "consumer: distance %g after %d ticks, d1 %g\n", info.min_distance, TICKS,
                ccfg.sp.d1);
        return 1;
    }
    /* two parallel unit segments 0.5 apart: distance 0.5 */
    const double p0[3] = {0, 0, 0}, p1[3] = {1, 0, 0}, q0[3] = {0, 0.5, 0}, q1[3] = {1, 0.5, 0};
    mca_segdist_t r;
    if (mca_segdist_closed(p0, p1, q0, q1, &r) != MCA_OK || fabs(r.d - 0.5) > 1e-12) {
        fprintf(stderr, "consumer: segment distance %g, expected 0.5\n", r.d);
        return 1;
    }
    const double s = mca_brake_s(0.085, 0.05, 0.12); /* halfway: sin^2(pi/4) = 0.5 */
    if (fabs(s - 0.5) > 1e-12) {
        fprintf(stderr, "consumer: S(d) %g, expected 0.5\n", s);
        return 1;
    }
    mca_dds_config_t cfg;
    mca_dds_config_default(&cfg);
    printf("consumer: ok: %s, %d joints; %s: %d ticks of 2 arms, min distance %.4f m, joints moved %.2e rad; "
           "segment distance %.3f, S = %.3f, DDS ring %u\n",
           chain.name, chain.dof, scn.name, TICKS, info.min_distance, moved, r.d, s, cfg.ring_capacity);
    return 0;
}
