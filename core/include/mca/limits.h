/* SPDX-License-Identifier: MIT */
/** @file mca/limits.h
 * Compile-time maximums. Every array on the 1 kHz path is sized from these, so nothing is
 * allocated after start-up.
 */
#ifndef MCA_LIMITS_H
#define MCA_LIMITS_H

/** Most revolute joints in one arm (PA10+ has 8). */
#define MCA_MAX_DOF 8
/** Kinematic points of one arm: root, each joint origin, tool tip. */
#define MCA_MAX_POINTS (MCA_MAX_DOF + 2)
/** Links (line segments between consecutive points) of one arm. */
#define MCA_MAX_LINKS (MCA_MAX_POINTS - 1)
/** Most arms one controller drives (the scheme adds collision rows per pair). */
#define MCA_MAX_ARMS 4
/** Task-space dimension of the end-effector constraint (position only). */
#define MCA_TASK_DIM 3

/** Extra QP variables per arm under path-time scaling (mca-ts): the path rate and the tracking slack's
 *  positive and negative parts (3 + 3: the slack's cost is exact, L1, see mca_scheme_add_timescale). */
#define MCA_TS_VARS (1 + 2 * MCA_TASK_DIM)
/** Collision rows per link under mca-ts and in braking: one per each of the link's nearest witness pairs
 *  against the other arms (mca_scheme_near_rows). */
#define MCA_NEAR_PAIRS 6
/** Fixed bodies of a cell (tables, fixtures, cups: mca/bodyrows.h). */
#define MCA_MAX_BODIES 16
/** Collision rows per link against the fixed bodies and its arm's own links (self pairs): one per each of
 *  the link's nearest witness pairs against the bodies not allowed to it and its self pairs, both kinds in
 *  one list (mca_body_rows). */
#define MCA_BODY_PAIRS 6
/** QP sizes: phi = all joint velocities (and the mca-ts variables), one 3-row equality per arm, and per
 *  link of every arm up to MCA_NEAR_PAIRS rows against the other arms (mca-ts; the paper's componentwise
 *  form needs 3) and MCA_BODY_PAIRS against the fixed bodies. */
#define MCA_QP_MAX_VARS (MCA_MAX_ARMS * (MCA_MAX_DOF + MCA_TS_VARS))
#define MCA_QP_MAX_EQ (MCA_MAX_ARMS * MCA_TASK_DIM)
#define MCA_QP_MAX_INEQ (MCA_MAX_ARMS * MCA_MAX_LINKS * (MCA_NEAR_PAIRS + MCA_BODY_PAIRS))
/** Primal-dual vector length h = vars + eq + ineq. */
#define MCA_QP_MAX_H (MCA_QP_MAX_VARS + MCA_QP_MAX_EQ + MCA_QP_MAX_INEQ)

#endif
