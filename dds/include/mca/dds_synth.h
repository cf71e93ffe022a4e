/* SPDX-License-Identifier: MIT */
/** @file mca/dds_synth.h
 * Deterministic synthetic snapshots for tests, the benchmark and demos: every field is a function of
 * the tick number (only stamp_ns is the real time), so a subscriber can recompute what was published.
 * tests/dds/mca_types.py holds an independent Python implementation of the same pattern; keep both in
 * step. Context: rt-safe (no allocation, bounded time).
 *
 * Pattern for tick k (i = arm, j = joint, l = link; arm 0 has 7 joints, arm 1 has 6):
 *   position[j]           = 0.001*k + 0.1*j + i
 *   velocity[j]           = 0.5*j - 0.25*i + 1e-6*k
 *   effort[j]             = -0.01*(k % 97) + j
 *   velocity_setpoint[j]  = 0.9 * velocity[j]
 *   position_reference[j] = position[j] + 0.0005
 *   pair 0 = (arm 0, arm 1), d1 = 0.05, d2 = 0.12:
 *   min_distance = 0.02 + 0.16 * (|k % 2000 - 1000| / 1000.0)    (triangle wave 0.02..0.18 m, 2 s)
 *   p = (0.3 + 0.001*(k % 100), -0.1, 0.5), e = (p.x, p.y + min_distance, p.z)
 *   link_a = k % 8, link_b = (k / 8) % 7
 *   link_distance_a[l] = min_distance + 0.01*l (8 links), link_distance_b[l] = min_distance + 0.02*l (7)
 *   brake_factor = S(min_distance) of eq. (13)
 *   status: state RUNNING (BRAKING when min_distance <= d1), ticks k+1, pdnn_steps k % 50,
 *           pdnn_residual 1e-9*(k % 7), min_distance_so_far = running minimum.
 */
#ifndef MCA_DDS_SYNTH_H
#define MCA_DDS_SYNTH_H

#include "mca/dds_bridge.h"

#ifdef __cplusplus
extern "C" {
#endif

/** Fill snap with the pattern above for tick k. min_so_far/min_stamp carry the running minimum
 *  between calls (start with min_so_far = INFINITY). */
void mca_dds_synth_fill(mca_dds_snapshot_t *snap, uint64_t k, int64_t stamp_ns, double *min_so_far,
                        int64_t *min_stamp);

#ifdef __cplusplus
}
#endif
#endif
