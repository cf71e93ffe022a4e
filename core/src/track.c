/* SPDX-License-Identifier: MIT */
/* Streamed bodies: growth of stale tracks and the protective separation distance; see mca/track.h and
 * docs/scheme.md, "Streamed bodies". */
#include "mca/track.h"

#include <math.h>
#include <string.h>

#include "mca/err.h"
#include "mca/vec3.h"

void mca_ssm_default(mca_ssm_params_t *p) {
    p->max_age = 0.1;
    p->lost_after = 0.5;
    p->approach_near = 2.0;
    p->approach_far = 1.6;
    p->approach_switch = 0.5;
    p->reaction_time = 0.01;
    p->latency = 0.03;
    p->intrusion = 0.0;
    p->z_d = 0.05;
    p->z_r = 0.005;
}

int mca_ssm_check(const mca_ssm_params_t *p) {
    if (!p) {
        return MCA_EINVAL;
    }
    const double nonneg[] = {p->max_age,         p->reaction_time, p->latency, p->intrusion,
                             p->approach_switch, p->z_d,           p->z_r};
    for (size_t k = 0; k < sizeof nonneg / sizeof nonneg[0]; k++) {
        if (!isfinite(nonneg[k]) || !(nonneg[k] >= 0.0)) {
            return MCA_EINVAL;
        }
    }
    if (!isfinite(p->lost_after) || !(p->lost_after > p->max_age) || !isfinite(p->approach_near) ||
        !(p->approach_near > 0.0) || !isfinite(p->approach_far) || !(p->approach_far > 0.0)) {
        return MCA_EINVAL;
    }
    return MCA_OK;
}

double mca_track_growth(const mca_ssm_params_t *p, double age) {
    const double tau = age - p->max_age;
    if (!(tau > 0.0)) {
        return 0.0;
    }
    /* the switch comes after approach_switch of growth (ISO 13855: 2.0 m/s while S <= 0.5 m); beyond it
     * 1.6 m/s continues from there, never below ISO's own 1.6 m/s T */
    const double t_switch = p->approach_switch / p->approach_near;
    return tau <= t_switch ? p->approach_near * tau : p->approach_switch + p->approach_far * (tau - t_switch);
}

double mca_track_growth_rate(const mca_ssm_params_t *p, double age) {
    const double tau = age - p->max_age;
    if (!(tau > 0.0)) {
        return 0.0;
    }
    return tau <= p->approach_switch / p->approach_near ? p->approach_near : p->approach_far;
}

void mca_ssm_terms(const mca_ssm_params_t *p, double body_speed, double arm_speed, double t_stop,
                   mca_ssm_terms_t *out) {
    const double t_r = p->reaction_time + p->latency;
    out->s_h = body_speed * (t_r + t_stop);
    out->s_r = arm_speed * t_r;
    out->s_s = 0.5 * arm_speed * t_stop;
    out->c = p->intrusion;
    out->z_d = p->z_d;
    out->z_r = p->z_r;
    out->s_p = out->s_h + out->s_r + out->s_s + out->c + out->z_d + out->z_r;
}

double mca_chain_point_speed(const mca_chain_t *chain) {
    /* from the tool tip inwards: len = the links beyond joint j's origin (joint j + 1's origin is in joint
     * j's frame) */
    double v = 0.0, len = mca_v3_norm(chain->tool.p);
    for (int j = chain->dof - 1; j >= 0; j--) {
        v += chain->joint[j].vel_limit * len;
        len += mca_v3_norm(chain->joint[j].origin.p);
    }
    return v;
}

int mca_track_body(const mca_ssm_params_t *p, const mca_track_t *tr, double now, double arm_speed,
                   double t_stop, mca_fixed_body_t *out, mca_ssm_terms_t *terms) {
    if (!p || !tr || !out || (tr->kind != MCA_BODY_SPHERE && tr->kind != MCA_BODY_CAPSULE)) {
        return MCA_EINVAL;
    }
    for (int i = 0; i < 3; i++) {
        if (!isfinite(tr->a[i]) || !isfinite(tr->b[i]) || !isfinite(tr->v[i])) {
            return MCA_EINVAL;
        }
    }
    if (!isfinite(tr->radius) || !(tr->radius >= 0.0) || !isfinite(tr->stamp) || !isfinite(now)) {
        return MCA_EINVAL;
    }
    const double age = fmax(0.0, now - tr->stamp);
    const int stale = age > p->max_age;
    const double moved = fmin(age, p->max_age); /* dead reckoning while fresh, frozen once stale */
    const double grow = mca_track_growth(p, age);
    mca_ssm_terms_t t;
    mca_ssm_terms(p, stale ? p->approach_near : mca_v3_norm(tr->v), arm_speed, t_stop, &t);
    memset(out, 0, sizeof *out);
    out->name[0] = 't';
    out->name[1] = (char)('0' + (int)(tr->id % 10u));
    out->body.kind = (mca_body_kind_t)tr->kind;
    if (tr->kind == MCA_BODY_SPHERE) {
        mca_v3_axpy(out->body.u.sphere.centre, tr->a, moved, tr->v);
        out->body.u.sphere.radius = tr->radius + grow;
    } else {
        mca_v3_axpy(out->body.u.capsule.a, tr->a, moved, tr->v);
        mca_v3_axpy(out->body.u.capsule.b, tr->b, moved, tr->v);
        out->body.u.capsule.radius = tr->radius + grow;
    }
    out->clearance = t.s_p;
    if (stale) {
        out->grow = mca_track_growth_rate(p, age);
    } else {
        mca_v3_set(out->v, tr->v);
    }
    if (terms) {
        *terms = t;
    }
    return MCA_OK;
}
