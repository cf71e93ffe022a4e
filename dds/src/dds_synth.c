/* SPDX-License-Identifier: MIT */
/* Deterministic synthetic snapshots (pattern documented in mca/dds_synth.h). */
#include "mca/dds_synth.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "mca/scheme.h" /* mca_brake_s: S(d) */

void mca_dds_synth_fill(mca_dds_snapshot_t *snap, uint64_t k, int64_t stamp_ns, double *min_so_far,
                        int64_t *min_stamp) {
    static const uint32_t dof[2] = {7, 6};
    snap->tick = k;
    snap->stamp_ns = stamp_ns;
    snap->n_arms = 2;
    snap->n_pairs = 1;
    const double kd = (double)k;
    for (uint32_t i = 0; i < 2; ++i) {
        mca_dds_arm_snapshot_t *a = &snap->arm[i];
        a->n_dof = dof[i];
        for (uint32_t j = 0; j < dof[i]; ++j) {
            a->position[j] = 0.001 * kd + 0.1 * (double)j + (double)i;
            a->velocity[j] = 0.5 * (double)j - 0.25 * (double)i + 1e-6 * kd;
            a->effort[j] = -0.01 * (double)(k % 97) + (double)j;
            a->velocity_setpoint[j] = 0.9 * a->velocity[j];
            a->position_reference[j] = a->position[j] + 0.0005;
        }
    }
    mca_dds_pair_snapshot_t *p = &snap->pair[0];
    const double tri = (double)llabs((long long)(k % 2000) - 1000) / 1000.0;
    const double d = 0.02 + 0.16 * tri;
    p->arm_a = 0;
    p->arm_b = 1;
    p->d1 = 0.05;
    p->d2 = 0.12;
    p->min_distance = d;
    p->p[0] = 0.3 + 0.001 * (double)(k % 100);
    p->p[1] = -0.1;
    p->p[2] = 0.5;
    p->e[0] = p->p[0];
    p->e[1] = p->p[1] + d;
    p->e[2] = p->p[2];
    p->link_a = (int16_t)(k % 8);
    p->link_b = (int16_t)((k / 8) % 7);
    p->n_links_a = dof[0] + 1;
    p->n_links_b = dof[1] + 1;
    for (uint32_t l = 0; l < p->n_links_a; ++l) {
        p->link_distance_a[l] = d + 0.01 * (double)l;
    }
    for (uint32_t l = 0; l < p->n_links_b; ++l) {
        p->link_distance_b[l] = d + 0.02 * (double)l;
    }
    p->brake_factor = mca_brake_s(d, p->d1, p->d2);

    if (d < *min_so_far) {
        *min_so_far = d;
        *min_stamp = stamp_ns;
    }
    mca_dds_status_snapshot_t *st = &snap->status;
    memset(st, 0, sizeof *st);
    st->state = d <= p->d1 ? MCA_DDS_STATE_BRAKING : MCA_DDS_STATE_RUNNING;
    st->ticks = k + 1;
    st->pdnn_steps = (uint32_t)(k % 50);
    st->pdnn_residual = 1e-9 * (double)(k % 7);
    st->min_distance_so_far = *min_so_far;
    st->min_distance_stamp_ns = *min_stamp;
}
