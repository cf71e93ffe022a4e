/* SPDX-License-Identifier: MIT */
/* Forward kinematics, point Jacobians and pose helpers of a serial chain (see mca/chain.h).
 * Everything here is real-time safe: no allocation, no I/O, loops bounded by MCA_MAX_DOF. */
#include "mca/chain.h"

#include <math.h>
#include <string.h>

#include "mca/err.h"
#include "mca/vec3.h"

void mca_pose_identity(mca_pose_t *pose) {
    memset(pose, 0, sizeof(*pose));
    pose->R[0][0] = 1.0;
    pose->R[1][1] = 1.0;
    pose->R[2][2] = 1.0;
}

void mca_pose_mul(mca_pose_t *out, const mca_pose_t *a, const mca_pose_t *b) {
    mca_pose_t r; /* local copy so that out may alias a or b */
    for (int i = 0; i < 3; i++) {
        for (int j = 0; j < 3; j++) {
            r.R[i][j] = a->R[i][0] * b->R[0][j] + a->R[i][1] * b->R[1][j] + a->R[i][2] * b->R[2][j];
        }
        r.p[i] = a->R[i][0] * b->p[0] + a->R[i][1] * b->p[1] + a->R[i][2] * b->p[2] + a->p[i];
    }
    *out = r;
}

void mca_pose_apply(double out[3], const mca_pose_t *pose, const double x[3]) {
    double r[3];
    for (int i = 0; i < 3; i++) {
        r[i] = pose->R[i][0] * x[0] + pose->R[i][1] * x[1] + pose->R[i][2] * x[2] + pose->p[i];
    }
    mca_v3_set(out, r);
}

void mca_pose_from_xyz_rpy(mca_pose_t *pose, const double xyz[3], const double rpy[3]) {
    const double cr = cos(rpy[0]), sr = sin(rpy[0]);
    const double cp = cos(rpy[1]), sp = sin(rpy[1]);
    const double cy = cos(rpy[2]), sy = sin(rpy[2]);
    /* R = Rz(yaw) Ry(pitch) Rx(roll), the URDF convention */
    pose->R[0][0] = cy * cp;
    pose->R[0][1] = cy * sp * sr - sy * cr;
    pose->R[0][2] = cy * sp * cr + sy * sr;
    pose->R[1][0] = sy * cp;
    pose->R[1][1] = sy * sp * sr + cy * cr;
    pose->R[1][2] = sy * sp * cr - cy * sr;
    pose->R[2][0] = -sp;
    pose->R[2][1] = cp * sr;
    pose->R[2][2] = cp * cr;
    mca_v3_set(pose->p, xyz);
}

void mca_chain_set_base(mca_chain_t *chain, const double xyz[3], const double rpy[3]) {
    mca_pose_from_xyz_rpy(&chain->base, xyz, rpy);
}

/* Rotation by angle q about the unit axis a (Rodrigues): R = I + s K + (1 - c) K^2. */
static void rot_axis_angle(double R[3][3], const double a[3], double q) {
    const double s = sin(q), c = cos(q), v = 1.0 - c;
    R[0][0] = c + a[0] * a[0] * v;
    R[0][1] = a[0] * a[1] * v - a[2] * s;
    R[0][2] = a[0] * a[2] * v + a[1] * s;
    R[1][0] = a[1] * a[0] * v + a[2] * s;
    R[1][1] = c + a[1] * a[1] * v;
    R[1][2] = a[1] * a[2] * v - a[0] * s;
    R[2][0] = a[2] * a[0] * v - a[1] * s;
    R[2][1] = a[2] * a[1] * v + a[0] * s;
    R[2][2] = c + a[2] * a[2] * v;
}

int mca_fk(const mca_chain_t *chain, const double *q, mca_kin_t *kin) {
    if (!chain || !q || !kin || chain->dof < 1 || chain->dof > MCA_MAX_DOF) {
        return MCA_EINVAL;
    }
    for (int i = 0; i < chain->dof; i++) {
        if (!isfinite(q[i])) {
            return MCA_EINVAL; /* checked first: kin stays unchanged on error */
        }
    }
    const int n = chain->dof;
    kin->dof = n;
    kin->n_points = n + 2;
    mca_v3_set(kin->point[0], chain->base.p);
    mca_pose_t T = chain->base; /* world <- current frame */
    for (int i = 0; i < n; i++) {
        const mca_joint_model_t *jm = &chain->joint[i];
        mca_pose_mul(&T, &T, &jm->origin); /* world <- joint i frame at q_i = 0 */
        mca_pose_t rot;
        rot_axis_angle(rot.R, jm->axis, q[i]);
        rot.p[0] = rot.p[1] = rot.p[2] = 0.0;
        /* world axis: the rotation about the axis leaves it unchanged */
        for (int r = 0; r < 3; r++) {
            kin->axis[i][r] = T.R[r][0] * jm->axis[0] + T.R[r][1] * jm->axis[1] + T.R[r][2] * jm->axis[2];
        }
        mca_pose_mul(&T, &T, &rot);
        kin->frame[i] = T;
        mca_v3_set(kin->point[i + 1], T.p);
    }
    mca_pose_apply(kin->point[n + 1], &T, chain->tool.p);
    mca_v3_set(kin->ee, kin->point[n + 1]);
    return MCA_OK;
}

int mca_jacobian_point(const mca_kin_t *kin, int link, const double x[3], double J[3][MCA_MAX_DOF]) {
    if (!kin || !x || !J || kin->dof < 1 || kin->dof > MCA_MAX_DOF || link < 0 || link > kin->dof) {
        return MCA_EINVAL;
    }
    memset(J, 0, sizeof(double) * 3 * MCA_MAX_DOF);
    /* Link k is moved by joints 0..k-1; joint j sits at point[j + 1]. */
    for (int j = 0; j < link; j++) {
        double r[3], c[3];
        mca_v3_sub(r, x, kin->point[j + 1]);
        mca_v3_cross(c, kin->axis[j], r);
        J[0][j] = c[0];
        J[1][j] = c[1];
        J[2][j] = c[2];
    }
    return MCA_OK;
}

int mca_jacobian_ee(const mca_kin_t *kin, double J[3][MCA_MAX_DOF]) {
    if (!kin) {
        return MCA_EINVAL;
    }
    return mca_jacobian_point(kin, kin->dof, kin->ee, J);
}

int mca_chain_clamp_q(const mca_chain_t *chain, double *q) {
    if (!chain || !q || chain->dof < 1 || chain->dof > MCA_MAX_DOF) {
        return MCA_EINVAL;
    }
    for (int i = 0; i < chain->dof; i++) {
        if (!isfinite(q[i])) {
            return MCA_EINVAL;
        }
    }
    int clamped = 0;
    for (int i = 0; i < chain->dof; i++) {
        const mca_joint_model_t *jm = &chain->joint[i];
        if (jm->continuous) {
            continue;
        }
        if (q[i] < jm->lower) {
            q[i] = jm->lower;
            clamped++;
        } else if (q[i] > jm->upper) {
            q[i] = jm->upper;
            clamped++;
        }
    }
    return clamped;
}
