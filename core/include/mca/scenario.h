/* SPDX-License-Identifier: MIT */
/** @file mca/scenario.h
 * Task (scenario) files and desired end-effector paths.
 *
 * A scenario names the arms (URDF, tip link, base placement, initial joints), one desired path per arm,
 * the duration and the scheme parameters (d1, d2, K, epsilon, ...). It is a YAML file parsed with libcyaml
 * (start-up only); see the files in config/scenarios/ and docs/scheme.md for the format.
 *
 * Paths are evaluated on the 1 kHz path: mca_path_eval() is real-time safe (no allocation, bounded time).
 * A path may be anchored at the arm's end-effector position at start (frame "start"): its points are then
 * offsets from that position, fixed by mca_path_anchor() when the task starts.
 */
#ifndef MCA_SCENARIO_H
#define MCA_SCENARIO_H

#include <stddef.h>

#include "mca/limits.h"

#ifdef __cplusplus
extern "C" {
#endif

/** Most waypoints of one path. */
#define MCA_PATH_MAX_POINTS 64

typedef enum mca_path_kind {
    MCA_PATH_HOLD = 0,      /**< stay at the start position */
    MCA_PATH_CIRCLE = 1,    /**< circle through the start position, phase 2 pi sin^2(pi t / 2T) */
    MCA_PATH_WAYPOINTS = 2, /**< straight segments between waypoints, quintic timing per segment */
    MCA_PATH_STREAM = 3,    /**< a streamed target (mcad's task kind `stream`): the reference starts at the
                                 anchor and moves with the velocity set each tick (mca_controller_stream), at
                                 the arm's path rate; it never ends */
} mca_path_kind_t;

typedef struct mca_path {
    mca_path_kind_t kind;
    int relative;     /**< 1: points/centre are offsets from the anchor (end effector at start) */
    double anchor[3]; /**< set by mca_path_anchor() (zero until then) */
    double t0;        /**< path time offset: the path starts at task time t0 (holds before) */
    /* circle: r(s) = anchor - R u + R (cos phi u + sin phi v), phi = turns * 2 pi sin^2(pi s / 2T) */
    double radius;
    double u[3];   /**< unit, in-plane: anchor sits at centre + R u */
    double v[3];   /**< unit, in-plane, orthogonal to u */
    double period; /**< T [s] */
    double turns;  /**< full turns in T (1) */
    /* waypoints: p[0] is the start (the anchor, set by mca_path_anchor: offset 0 when relative), then the
     * file's points p[1..n_points-1]; segment i from p[i] to p[i+1] lasts dur[i]; a segment back to the
     * same point is a dwell */
    int n_points;
    double p[MCA_PATH_MAX_POINTS][3];
    double dur[MCA_PATH_MAX_POINTS]; /**< dur[i]: duration of segment i -> i+1 [s] (> 0) */
    /* stream: reference position and velocity; the reference stays inside [box_lo, box_hi] (a component at a
     * wall stops there while the velocity pushes outwards) */
    double stream_r[3], stream_v[3];
    double box_lo[3], box_hi[3];
} mca_path_t;

/** Fix a path's anchor (the end effector's position at task start). Start-up/rt safe. */
void mca_path_anchor(mca_path_t *path, const double ee_start[3]);

/**
 * Desired position and velocity at task time t (real-time safe). Before t0 and after the end the path
 * holds its first/last point with zero velocity.
 * @retval MCA_OK, MCA_EINVAL (NULL or non-finite t)
 */
int mca_path_eval(const mca_path_t *path, double t, double r[3], double rdot[3]);

/** Task time at which the path ends (+INFINITY for a stream). */
double mca_path_end_time(const mca_path_t *path);

/** Stream: move the reference by rate * stream_v * dt, kept inside the box (real-time safe; other kinds:
 *  nothing). */
void mca_path_stream_advance(mca_path_t *path, double rate, double dt);

/** One arm of a scenario. */
typedef struct mca_scenario_arm {
    char name[32];
    char urdf[512];    /**< absolute path (relative paths in the file are resolved against the file) */
    char tip_link[64]; /**< "" = the single leaf link */
    double base_xyz[3];
    double base_rpy[3];
    int n_q0; /**< entries given for q0 (must equal the chain's dof once loaded) */
    double q0[MCA_MAX_DOF];
    mca_path_t path;
} mca_scenario_arm_t;

/** Scheme and fault parameters a scenario may set (defaults in mca_scenario_defaults()). */
typedef struct mca_scenario_params {
    double d1, d2;   /**< inner/outer safety thresholds [m] */
    double K;        /**< position feedback gain [1/s] */
    double epsilon;  /**< joint-limit gain of (19) [1/s] */
    double dt;       /**< tick period [s] (0.001) */
    double v_normal; /**< normal form: allowed approach speed S(d) * v_normal [m/s] */
    double v_floor;  /**< componentwise form: least captured approach rate [m/s] */
    int form;        /**< mca_collision_form_t (0 componentwise, 1 normal) */
} mca_scenario_params_t;

typedef struct mca_scenario {
    char name[64];
    char source[512]; /**< file it was loaded from */
    int n_arms;
    mca_scenario_arm_t arm[MCA_MAX_ARMS];
    double duration; /**< task length [s] */
    int has_form;    /**< 1 when the file set the collision form */
    mca_scenario_params_t params;
    int n_sample_times; /**< instants for the Table-I style report */
    double sample_times[16];
} mca_scenario_t;

/**
 * Allowed range of one number in a scenario or cell file (issue 16: values that switched supervision off, or
 * overflowed the tick count, were accepted). The ranges are what a real cell can need; they are listed in
 * docs/scheme.md section 3 (scenario keys) and docs/daemon.md (cell keys).
 */
typedef struct mca_range {
    const char *key;  /**< field name as written in the file ("dt", "K", ...) */
    double lo, hi;    /**< lo <= v <= hi (lo < v when lo_open) */
    int lo_open;      /**< 1: lo itself is not allowed */
    int integer;      /**< 1: printed as "LO..HI" */
    const char *unit; /**< "s", "m", "1/s", ... ("" for none) */
} mca_range_t;

/** Most ticks of one task: an hour at 1 kHz (duration / dt, bounds what is allocated per tick). */
#define MCA_SCENARIO_MAX_TICKS 3600000

/**
 * Check v against r (NaN and infinities are outside every range).
 * @param[out] why  on MCA_ERANGE: "must be in [LO, HI] UNIT (got V)" (or "LO..HI" for integers)
 * @retval MCA_OK, MCA_ERANGE, MCA_EINVAL (r NULL)
 */
int mca_range_check(const mca_range_t *r, double v, char *why, size_t whylen);

/**
 * The range of a number of a scenario file; cells use the same ranges for the same keys (their d1, d2, the
 * solver's K, epsilon, v_normal, v_floor, task duration, arm placement and inline paths).
 * Keys: duration, dt, d1, d2, K, epsilon, v_normal, v_floor, sample_times, base_xyz, base_rpy, t0, radius,
 * period, turns, points, durations.
 * @return the range, or NULL for a key without one
 */
const mca_range_t *mca_scenario_range(const char *key);

/**
 * Check a task duration against its range and the tick count it makes at tick period dt (at most
 * MCA_SCENARIO_MAX_TICKS).
 * @param[out] why  on MCA_ERANGE, the reason (without the field name)
 * @retval MCA_OK, MCA_ERANGE
 */
int mca_scenario_check_duration(double duration, double dt, char *why, size_t whylen);

/** Defaults: d1 0.05, d2 0.12, K 20, epsilon 5, dt 0.001, normal form, v_normal 0.5. */
void mca_scenario_defaults(mca_scenario_t *scn);

/**
 * Parse a scenario YAML file (start-up only; allocates inside libcyaml and frees before returning).
 * @param[out] scn  filled on success (unchanged on error)
 * @param[out] err  message naming the file, the line when known, and the field at fault
 * @retval MCA_OK, MCA_ENOENT (file missing), MCA_EPARSE (bad YAML, unknown/missing field, empty or
 *         comment-only file: "FILE: empty document ..."),
 *         MCA_ERANGE (value out of range: too many arms/points, d1 >= d2, non-positive duration, ...)
 */
int mca_scenario_load(const char *path, mca_scenario_t *scn, char *err, size_t errlen);

#ifdef __cplusplus
}
#endif
#endif
