/* SPDX-License-Identifier: MIT */
/** @file mca/path.h
 * Desired end-effector paths and their evaluation (mca_core).
 *
 * Paths are evaluated on the 1 kHz path: mca_path_eval() is real-time safe (no allocation, bounded time).
 * A path may be anchored at the arm's end-effector position at start (frame "start"): its points are then
 * offsets from that position, fixed by mca_path_anchor() when the task starts. Scenario files that describe
 * paths are read by the model library (mca/scenario.h).
 */
#ifndef MCA_PATH_H
#define MCA_PATH_H

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
    /* the path tube (mca-ts): how far the tool tip may leave the path where staying on it would break a
     * hard row. seg_tol[i]: segment i of a waypoint path; seg_tol[0]: the whole path of the other kinds. */
    double seg_tol[MCA_PATH_MAX_POINTS];      /**< [m], >= 0; INFINITY: no tube */
    unsigned char exact[MCA_PATH_MAX_POINTS]; /**< waypoints: 1 for p[i] reached within exact_tol and held
                                                   through a dwell that follows it (grasp, release) */
    double exact_tol;                         /**< [m] */
    int path_first; /**< 1: the task declared a tube (tolerance or exact points): mca-ts keeps this path
                       before its timing (an exact penalty and the tube); 0: elastic tracking, no tube */
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

/**
 * The path tube's radius at path time t (real-time safe): the segment's tolerance; next to an exact waypoint
 * it narrows linearly over the segment to exact_tol at the point (a dwell between exact points: exact_tol
 * throughout). Before the start and after the end: the first / last point's.
 */
double mca_path_tolerance(const mca_path_t *path, double t);

/** Path time at which a waypoint path reaches its point p[i] (t0 + the durations before it). */
double mca_path_point_time(const mca_path_t *path, int i);

/** 1: segment i of a waypoint path stays at its point (a dwell: p[i] equals p[i + 1]). */
int mca_path_dwell(const mca_path_t *path, int i);

/** Point p[i] of a waypoint path in the world frame (after mca_path_anchor). */
void mca_path_point(const mca_path_t *path, int i, double out[3]);

/**
 * Distance of x to the path's curve (real-time safe): waypoints the nearest of their straight segments,
 * circles the whole circle, a stream its reference point, a hold its point. The path error a user sees
 * (mca-sim's and mcad's path_error_max).
 */
double mca_path_distance(const mca_path_t *path, const double x[3]);

/** Stream: move the reference by rate * stream_v * dt, kept inside the box (real-time safe; other kinds:
 *  nothing). */
void mca_path_stream_advance(mca_path_t *path, double rate, double dt);

#ifdef __cplusplus
}
#endif
#endif
