/* SPDX-License-Identifier: MIT */
/** @file mca/chain.h
 * Serial robot arm model (filled from a URDF at start-up by the model library, mca/urdf.h) and its
 * kinematics: forward kinematics of every joint frame, the link segments, the end-effector position and
 * the 3 x n positional Jacobian of any point on any link (the paper's J_P).
 *
 * Geometry convention
 *  - Points: point[0] is the arm's root (base link origin), point[1..dof] are the joint origins,
 *    point[dof+1] is the tool tip (end effector). n_points = dof + 2.
 *  - Link k (k = 0..dof) is the segment point[k] -> point[k+1], a capsule of radius
 *    chain->link_radius[k]. Link k is moved by joints 0..k-1 (link 0 never moves).
 *    A link may have zero length (coincident joint origins); it is then a sphere.
 *  - Everything is expressed in the world frame: world <- chain->base <- root link.
 *
 * Context: loading (mca_chain_load_urdf(), mca/urdf.h, mca_model) is start-up only: it allocates in urdfdom.
 * mca_fk() and mca_jacobian_point() are real-time safe: no allocation, no I/O, bounded time.
 */
#ifndef MCA_CHAIN_H
#define MCA_CHAIN_H

#include <stddef.h>

#include "mca/limits.h"

#ifdef __cplusplus
extern "C" {
#endif

/** Rigid transform: x_parent = R * x_child + p. R is row-major. */
typedef struct mca_pose {
    double R[3][3];
    double p[3];
} mca_pose_t;

/** Largest joint velocity limit a URDF may give [rad/s] (velocity="1e300" switched the velocity
 *  bounds off); real revolute joints move at well under 10 rad/s. */
#define MCA_JOINT_VEL_MAX 100.0

typedef struct mca_joint_model {
    char name[64];
    mca_pose_t origin; /**< previous joint frame (or root link) -> this joint frame at q = 0 */
    double axis[3];    /**< unit rotation axis in this joint's frame */
    double lower;      /**< position limit [rad]; -INFINITY when continuous */
    double upper;      /**< position limit [rad]; +INFINITY when continuous */
    double vel_limit;  /**< |qdot| limit [rad/s], in (0, MCA_JOINT_VEL_MAX] */
    int continuous;    /**< 1 when the joint has no position limits */
} mca_joint_model_t;

typedef struct mca_chain {
    char name[64];      /**< URDF robot name */
    char source[256];   /**< file it was loaded from (for messages) */
    char root_link[64]; /**< URDF root link (the frame base places in the world; ROS 2 TF names it) */
    int dof;            /**< number of revolute joints, 1..MCA_MAX_DOF */
    mca_joint_model_t joint[MCA_MAX_DOF];
    mca_pose_t tool;                   /**< last joint frame -> tool tip (fixed joints folded in) */
    double link_radius[MCA_MAX_LINKS]; /**< capsule radius of link k [m] */
    mca_pose_t base;                   /**< world <- root link; identity after loading */
} mca_chain_t;

/** Kinematic state of one arm at one configuration (all world frame). */
typedef struct mca_kin {
    int dof;
    int n_points;                    /**< dof + 2 */
    double point[MCA_MAX_POINTS][3]; /**< root, joint origins, tool tip */
    double axis[MCA_MAX_DOF][3];     /**< joint axes (unit) */
    mca_pose_t frame[MCA_MAX_DOF];   /**< world <- joint frame */
    double ee[3];                    /**< tool tip = point[dof + 1] */
} mca_kin_t;

/** Set the world <- root pose of an arm (its base placement). */
void mca_chain_set_base(mca_chain_t *chain, const double xyz[3], const double rpy[3]);

/** Pose from translation and URDF roll-pitch-yaw (R = Rz(yaw) Ry(pitch) Rx(roll)). */
void mca_pose_from_xyz_rpy(mca_pose_t *pose, const double xyz[3], const double rpy[3]);

/**
 * Forward kinematics of every joint frame, point and the tool tip (real-time safe).
 * @retval MCA_OK, MCA_EINVAL (NULL or non-finite q)
 */
int mca_fk(const mca_chain_t *chain, const double *q, mca_kin_t *kin);

/**
 * Positional Jacobian of a world point x rigidly attached to link @p link (real-time safe):
 * column j = axis_j x (x - origin_j) for joints j < link, zero otherwise.
 * @param[out] J 3 x MCA_MAX_DOF, columns >= dof are zero
 * @retval MCA_OK, MCA_EINVAL (link out of range)
 */
int mca_jacobian_point(const mca_kin_t *kin, int link, const double x[3], double J[3][MCA_MAX_DOF]);

/** End-effector Jacobian: mca_jacobian_point(kin, dof, kin->ee, J). */
int mca_jacobian_ee(const mca_kin_t *kin, double J[3][MCA_MAX_DOF]);

/* ---- Small helpers (real-time safe) ---- */

/** pose = identity. */
void mca_pose_identity(mca_pose_t *pose);

/** out = a * b (out may alias a or b). */
void mca_pose_mul(mca_pose_t *out, const mca_pose_t *a, const mca_pose_t *b);

/** out = pose applied to point x: R x + p (out may alias x). */
void mca_pose_apply(double out[3], const mca_pose_t *pose, const double x[3]);

/**
 * Clamp q (chain->dof entries) into the position limits; continuous joints are left alone.
 * @return number of joints clamped (>= 0), or MCA_EINVAL (NULL or non-finite q; q unchanged)
 */
int mca_chain_clamp_q(const mca_chain_t *chain, double *q);

#ifdef __cplusplus
}
#endif
#endif
