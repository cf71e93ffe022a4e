/* SPDX-License-Identifier: MIT */
/** @file mca/track.h
 * Streamed bodies: a person or a foreign machine tracked by a sensor elsewhere, a sphere or capsule with a
 * velocity and a stamp, kept by the same rows as the fixed bodies (mca/bodyrows.h) with the clearance
 * replaced by the protective separation distance of ISO/TS 15066's speed and separation monitoring,
 *
 *     S_p = S_h + S_r + S_s + C + Z_d + Z_r,
 *
 *     S_h = v_h (T_r + T_s)   the body's travel while the arms react and stop (v_h: its measured speed, or
 *                             the approach speed while the track is stale)
 *     S_r = v_r T_r           the arms' travel during the reaction time T_r = reaction_time + latency
 *     S_s = v_r T_s / 2       the arms' stopping distance (T_s: the scheme's stop time T_a at dec_limit)
 *     C, Z_d, Z_r             intrusion distance, the sensor's and the arms' position uncertainty
 *
 * v_r the fastest any point of the arms can move (each joint's velocity limit times the links beyond it).
 * A track older than max_age grows its radius at the approach speed of ISO 13855 (2.0 m/s for the first
 * 0.5 m of growth, 1.6 m/s beyond) until it is fresh again (docs/scheme.md, "Streamed bodies").
 *
 * Not a safety-rated function (Linux, DDS): it complements a certified safety controller, it does not
 * replace one.
 *
 * Context: rt (no allocation, no locks, no formatting), except mca_ssm_check (start-up).
 */
#ifndef MCA_TRACK_H
#define MCA_TRACK_H

#include <stdint.h>

#include "mca/bodyrows.h"
#include "mca/chain.h"

#ifdef __cplusplus
extern "C" {
#endif

/** Most streamed bodies the controller keeps (they take body slots after the cell's fixed bodies). */
#define MCA_MAX_TRACKS 4

/** One tracked body as it arrived. */
typedef struct mca_track {
    uint32_t id;
    int kind;          /**< MCA_BODY_SPHERE (a = centre) or MCA_BODY_CAPSULE (axis a..b) */
    double a[3], b[3]; /**< world frame [m] */
    double radius;     /**< [m] */
    double v[3];       /**< measured velocity, world frame [m/s] */
    double stamp;      /**< when it was received, on the controller's clock [s] (the age's origin) */
} mca_track_t;

/** Speed and separation monitoring's settings (defaults: mca_ssm_default). */
typedef struct mca_ssm_params {
    double max_age;         /**< a track older than this grows [s] (0.1) */
    double lost_after;      /**< no sample this long: the stream is lost, the arms stop [s] (0.5) */
    double approach_near;   /**< ISO 13855's approach speed for the first approach_switch of growth (2.0) */
    double approach_far;    /**< beyond it [m/s] (1.6) */
    double approach_switch; /**< [m] (0.5) */
    double reaction_time;   /**< the arms' reaction: detection to the first braking command [s] (0.01) */
    double latency;         /**< the stream's latency, sensor to mcad [s] (0.03) */
    double intrusion;       /**< C [m] (0.0: the track's radius covers the body) */
    double z_d;             /**< the sensor's position uncertainty [m] (0.05) */
    double z_r;             /**< the arms' position uncertainty [m] (0.005) */
} mca_ssm_params_t;

/** The terms of S_p for one track (the docs' and the tests' read-out). */
typedef struct mca_ssm_terms {
    double s_h, s_r, s_s, c, z_d, z_r, s_p;
} mca_ssm_terms_t;

/** The defaults above. */
void mca_ssm_default(mca_ssm_params_t *p);

/** Settings usable: finite, non-negative, max_age < lost_after, approach speeds > 0. @retval MCA_OK,
 *  MCA_EINVAL */
int mca_ssm_check(const mca_ssm_params_t *p);

/** The radius a track of this age has grown by: 0 up to max_age, then approach_near for the first
 *  approach_switch metres, approach_far beyond (continuous). */
double mca_track_growth(const mca_ssm_params_t *p, double age);

/** The surface speed of that growth at this age [m/s] (0 while fresh). */
double mca_track_growth_rate(const mca_ssm_params_t *p, double age);

/** S_p's terms for a body moving at body_speed, arms of fastest point speed arm_speed and stop time t_stop.
 */
void mca_ssm_terms(const mca_ssm_params_t *p, double body_speed, double arm_speed, double t_stop,
                   mca_ssm_terms_t *out);

/** The fastest a point of the chain can move with every joint at its velocity limit [m/s]: sum_j
 *  vel_limit_j times the length of the links beyond joint j (an upper bound in any configuration). */
double mca_chain_point_speed(const mca_chain_t *chain);

/**
 * A track at time now as a body of the rows: fresh (age <= max_age), its centre moved on by v age and its
 * own velocity in the rows; stale, its centre where max_age put it, its radius grown (mca_track_growth) and
 * the growth's rate as the body's approach speed. The clearance is S_p (terms, may be NULL).
 * @retval MCA_OK, MCA_EINVAL (NULL, kind not a sphere or capsule, non-finite numbers, radius < 0)
 */
int mca_track_body(const mca_ssm_params_t *p, const mca_track_t *tr, double now, double arm_speed,
                   double t_stop, mca_fixed_body_t *out, mca_ssm_terms_t *terms);

#ifdef __cplusplus
}
#endif
#endif
