/* SPDX-License-Identifier: MIT */
/* Uses the installed headers and libraries: loads an installed URDF (urdfdom through mca::core), a segment
 * distance against its closed form, S(d) of eq. (13) and a DDS pair fill (mca::dds).
 * usage: consumer URDF  -> prints "consumer: ok ..." and exits 0 */
#include <math.h>
#include <stdio.h>

#include "mca/chain.h"
#include "mca/dds_bridge.h"
#include "mca/err.h"
#include "mca/scheme.h"
#include "mca/segdist.h"
#include "mca/urdf.h"

int main(int argc, char **argv) {
    static mca_chain_t chain;
    char err[256];
    if (argc < 2 || mca_chain_load_urdf(&chain, argv[1], NULL, err, sizeof err) != MCA_OK) {
        fprintf(stderr, "consumer: %s\n", argc < 2 ? "usage: consumer URDF" : err);
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
    printf("consumer: ok: %s, %d joints, segment distance %.3f, S = %.3f, DDS ring %u\n", chain.name,
           chain.dof, r.d, s, cfg.ring_capacity);
    return 0;
}
