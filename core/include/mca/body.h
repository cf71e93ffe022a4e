/* SPDX-License-Identifier: MIT */
/** @file mca/body.h
 * Fixed bodies of a cell and their signed distance to a link capsule, with witness points and the normal a
 * collision row n^T J_P qdot <= bound needs. Library mca_body: no libccd, no allocation, no locks, no
 * printing, bounded time; every function here is real-time safe (context: rt).
 *
 * Body kinds (world frame):
 *  - plane:    the half-space {x : n . (x - point) <= 0}; n is the outward normal (normalised here);
 *  - sphere:   centre, radius;
 *  - capsule:  segment a-b swept by a radius (mca_capsule_t, the link's own type);
 *  - box:      centre, half extents along the box axes, rotation R (world <- box: the columns are the box
 *              axes; orthonormal within 1e-9);
 *  - cylinder: capped, solid: centre, axis (normalised here), half length along the axis, radius.
 *
 * Every result satisfies p - q = d n: p on the capsule's surface, q on the body's, n the unit normal from
 * the body toward the capsule (the direction the capsule must move to get away), d the signed distance
 * between the surfaces (negative = penetration). Algorithms and measured error bounds: docs/segdist.md,
 * "Fixed bodies".
 */
#ifndef MCA_BODY_H
#define MCA_BODY_H

#ifdef __cplusplus
extern "C" {
#endif

/** A capsule: segment a-b (a link axis) swept by a radius. */
typedef struct mca_capsule {
    double a[3], b[3]; /**< axis end points (world) */
    double radius;     /**< >= 0; 0 is a plain segment */
} mca_capsule_t;

typedef enum mca_body_kind {
    MCA_BODY_PLANE = 0,
    MCA_BODY_SPHERE = 1,
    MCA_BODY_CAPSULE = 2,
    MCA_BODY_BOX = 3,
    MCA_BODY_CYLINDER = 4,
} mca_body_kind_t;

/** Half-space {x : normal . (x - point) <= 0}. */
typedef struct mca_body_plane {
    double point[3];  /**< a point on the boundary plane */
    double normal[3]; /**< outward normal, any length > 0 (normalised by the distance functions) */
} mca_body_plane_t;

typedef struct mca_body_sphere {
    double centre[3];
    double radius; /**< >= 0 */
} mca_body_sphere_t;

typedef struct mca_body_box {
    double centre[3];
    double half[3]; /**< half extents along the box axes, >= 0 */
    double R[3][3]; /**< world <- box rotation; R[i][j] = world component i of box axis j */
} mca_body_box_t;

/** Capped solid cylinder. */
typedef struct mca_body_cylinder {
    double centre[3];
    double axis[3];  /**< axis direction, any length > 0 (normalised by the distance functions) */
    double half_len; /**< half length along the axis, >= 0 */
    double radius;   /**< >= 0 */
} mca_body_cylinder_t;

/** One fixed body: the kind tags the union. */
typedef struct mca_body {
    mca_body_kind_t kind;
    union {
        mca_body_plane_t plane;
        mca_body_sphere_t sphere;
        mca_capsule_t capsule;
        mca_body_box_t box;
        mca_body_cylinder_t cylinder;
    } u;
} mca_body_t;

/** Capsule-body distance. p - q = d n in every case. */
typedef struct mca_body_dist {
    double d;         /**< signed surface distance [m]; < 0 = penetration (see exact) */
    double p[3];      /**< witness on the capsule's surface: p = p_axis - radius n */
    double p_axis[3]; /**< the same witness on the capsule's axis (where the link Jacobian is taken) */
    double q[3];      /**< witness on the body: on its surface when d >= 0; when d < 0, on the body's
                           supporting plane with normal n (the surface for plane, sphere, capsule and a box
                           face) */
    double n[3];      /**< unit normal from the body toward the capsule (escape direction of the capsule) */
    int exact;        /**< 1: d is the signed distance up to rounding (docs/segdist.md); 0: the capsule's
                           axis enters a cylinder and d is a lower bound (the capsule is no deeper than -d;
                           moving it by -d along n separates it) */
    int iterations;   /**< root-finder steps of the cylinder (each one point-cylinder distance); 0 for the
                           closed forms */
} mca_body_dist_t;

/** Cap on the 1-D root finder of the capsule-cylinder distance (never reached: bisection after 40). */
#define MCA_BODY_CYL_MAX_ITER 100
/** The capsule-cylinder root finder stops when its bracket on the axis parameter is this narrow. */
#define MCA_BODY_CYL_TOL_T 1e-14

/**
 * Capsule against a half-space: closed form (the lower end point; the midpoint when both are equally low).
 * Exact, also when penetrating.
 * @param[in] cap capsule; @param[in] pl plane; @param[out] out result (untouched on error)
 * @retval MCA_OK
 * @retval MCA_EINVAL NULL, non-finite or too large (> MCA_SEGDIST_MAX_COORD) input, negative radius, zero
 *         normal
 */
int mca_capsule_plane_distance(const mca_capsule_t *cap, const mca_body_plane_t *pl, mca_body_dist_t *out);

/**
 * Capsule against a sphere: closed form (point-segment through mca_segdist_closed). Exact, also when
 * penetrating. @retval MCA_OK, MCA_EINVAL (as mca_capsule_plane_distance; negative radius)
 */
int mca_capsule_sphere_distance(const mca_capsule_t *cap, const mca_body_sphere_t *sp, mca_body_dist_t *out);

/**
 * Capsule against capsule: closed form (mca_segdist_closed); crossing axes escape along u x v. Exact, also
 * when penetrating. p, p_axis belong to @p cap, q to @p other. @retval MCA_OK, MCA_EINVAL
 */
int mca_capsule_capsule_distance(const mca_capsule_t *cap, const mca_capsule_t *other, mca_body_dist_t *out);

/**
 * Capsule against a box: exact finite algorithm. The squared distance from the axis point a + t u to the box
 * is a convex piecewise quadratic in t with at most 6 breaks (where a coordinate crosses a face plane); each
 * piece's minimum is solved in closed form. An axis that enters the box gets its exact penetration depth
 * from the separating-axis theorem (3 face normals, 3 edge-axis cross products). Exact, also when
 * penetrating. @retval MCA_OK, MCA_EINVAL (also R not orthonormal within 1e-9, negative half extent)
 */
int mca_capsule_box_distance(const mca_capsule_t *cap, const mca_body_box_t *box, mca_body_dist_t *out);

/**
 * Capsule against a capped cylinder. The distance from the axis point a + t u to the solid cylinder is
 * convex and C^1 in t outside the cylinder; its derivative is bracketed and its root found by Illinois
 * regula falsi (bisection after 40 steps) until the bracket is MCA_BODY_CYL_TOL_T wide: d within
 * MCA_BODY_CYL_TOL_T |b - a| plus rounding. An axis that enters the cylinder gets the shallowest of the cap
 * and radial escapes: exact = 0, d a lower bound. @retval MCA_OK, MCA_EINVAL
 */
int mca_capsule_cylinder_distance(const mca_capsule_t *cap, const mca_body_cylinder_t *cyl,
                                  mca_body_dist_t *out);

/**
 * Dispatcher: the function of @p body's kind. @retval MCA_OK, MCA_EINVAL (also an unknown kind)
 */
int mca_capsule_body_distance(const mca_capsule_t *cap, const mca_body_t *body, mca_body_dist_t *out);

#ifdef __cplusplus
}
#endif
#endif
