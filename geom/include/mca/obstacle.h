/* SPDX-License-Identifier: MIT */
/** @file mca/obstacle.h
 * Static obstacles (table, boxes, cups) and their distance to link capsules, on libccd.
 *
 * Shapes are convex and given by a pose (world <- shape frame, the shape's centre) and sizes:
 *  - box: half extents along the shape frame's x, y, z;
 *  - cylinder (a cup): axis = the shape frame's z, radius, half height;
 *  - table: a half-space modelled as a large, thick box whose top face is the table top.
 * A capsule is a segment A-B (a link axis) swept by a radius.
 *
 * Algorithms (see docs/segdist.md): separated shapes use a GJK distance loop on libccd's support-function
 * interface (ccd_support_fn, ccd_vec3_t); libccd 2.1 (Debian 12) itself has no distance query for
 * separated shapes (no ccdGJKDist). Overlapping shapes use libccd's ccdMPRPenetration (no allocation).
 * libccd's ccdGJKPenetration / ccdGJKSeparate run EPA, which allocates: never called here.
 * All functions below are real-time safe: no allocation, bounded iterations.
 */
#ifndef MCA_OBSTACLE_H
#define MCA_OBSTACLE_H

#include "mca/body.h" /* mca_capsule_t */
#include "mca/chain.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum mca_obstacle_type {
    MCA_OBST_BOX = 0,
    MCA_OBST_CYLINDER = 1,
} mca_obstacle_type_t;

typedef struct mca_obstacle {
    mca_obstacle_type_t type;
    char name[32];
    mca_pose_t pose;    /**< world <- shape frame (shape centre) */
    double half[3];     /**< box half extents [m] */
    double radius;      /**< cylinder radius [m] */
    double half_height; /**< cylinder half height along its z [m] */
} mca_obstacle_t;

typedef struct mca_obst_dist {
    double d;        /**< surface distance; negative = penetration depth (approximate, MPR tolerance) */
    double p[3];     /**< witness on the capsule AXIS (like mca_link_pair_t.p) */
    double q[3];     /**< witness on the other shape's surface (or the other capsule's axis) */
    double dir[3];   /**< unit escape direction for the capsule (q -> p when separated) */
    int iterations;  /**< GJK iterations (0 when MPR decided) */
    int penetrating; /**< 1 when the axis entered the shape and MPR gave the depth */
} mca_obst_dist_t;

/** GJK parameters: stop when the duality gap is below this [m]; iteration cap. */
#define MCA_GJK_TOL 1e-10
#define MCA_GJK_MAX_ITER 64

/** Box centred at @p pose with half extents @p half (all > 0). @retval MCA_OK, MCA_EINVAL */
int mca_obstacle_box(mca_obstacle_t *obs, const char *name, const mca_pose_t *pose, const double half[3]);

/** Cylinder (cup) centred at @p pose, axis along the pose's z. @retval MCA_OK, MCA_EINVAL */
int mca_obstacle_cylinder(mca_obstacle_t *obs, const char *name, const mca_pose_t *pose, double radius,
                          double height);

/** Table: world-aligned box with its top face at z = @p top_z, centred at (cx, cy), half sizes hx, hy,
 *  and @p thickness below the top (make it large to act as a half-space). @retval MCA_OK, MCA_EINVAL */
int mca_obstacle_table(mca_obstacle_t *obs, const char *name, double top_z, double cx, double cy, double hx,
                       double hy, double thickness);

/**
 * Distance from a capsule to an obstacle (real-time safe).
 * @retval MCA_OK, MCA_EINVAL (NULL, non-finite, negative radius), MCA_ENOTCONV (GJK cap: out holds the
 *         best pair, d is an upper bound)
 */
int mca_capsule_obstacle_distance(const mca_capsule_t *cap, const mca_obstacle_t *obs, mca_obst_dist_t *out);

/**
 * Capsule-capsule distance through the same GJK/MPR path (the libccd-based comparison for the closed form
 * mca_segdist_closed(); p and q on the two axes). @retval as mca_capsule_obstacle_distance()
 */
int mca_capsule_capsule_distance_ccd(const mca_capsule_t *c1, const mca_capsule_t *c2, mca_obst_dist_t *out);

/** Most obstacles one arm is checked against per cycle (fixed arrays, no allocation). */
#define MCA_MAX_OBSTACLES 16

/** One link's closest obstacle. */
typedef struct mca_link_obstacle {
    int link;     /**< link index (capsule point[link] -> point[link + 1], radius chain->link_radius[link]) */
    int obstacle; /**< index into the obstacle array; -1 when there are no obstacles */
    double d;     /**< surface distance (negative = penetration) [m] */
    double p[3];  /**< on the link axis */
    double q[3];  /**< on the obstacle */
    double dir[3]; /**< unit escape direction for the link */
    int penetrating;
} mca_link_obstacle_t;

typedef struct mca_arm_obstacles {
    int n_links;                                 /**< dof + 1 */
    mca_link_obstacle_t per_link[MCA_MAX_LINKS]; /**< closest obstacle of each link */
    mca_link_obstacle_t min;                     /**< the overall closest link-obstacle pair */
    int iterations;                              /**< total GJK iterations */
} mca_arm_obstacles_t;

/**
 * Every link of an arm against every obstacle (real-time safe). Ties keep the lower obstacle index.
 * @retval MCA_OK, MCA_EINVAL (NULL, kin of another chain, bad obstacle), MCA_ERANGE (n_obs >
 * MCA_MAX_OBSTACLES) (a GJK cap hit is not an error here: that pair's d is an upper bound within the GJK
 * tolerance)
 */
int mca_arm_obstacle_distances(const mca_chain_t *chain, const mca_kin_t *kin, const mca_obstacle_t *obs,
                               int n_obs, mca_arm_obstacles_t *out);

/** Closest point of an obstacle's solid to a world point x (exact; inside points map to themselves).
 *  @return distance (0 inside), or -1 on bad input */
double mca_obstacle_point_distance(const mca_obstacle_t *obs, const double x[3], double closest[3]);

#ifdef __cplusplus
}
#endif
#endif
