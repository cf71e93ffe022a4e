/* SPDX-License-Identifier: MIT */
/* Scenario (task) files and the controller config made from one; see mca/scenario.h and docs/scheme.md. */
#include "mca/scenario.h"

#include <cyaml/cyaml.h>
#include <limits.h> /* PATH_MAX */
#include <math.h>
#include <stdarg.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <threads.h> /* call_once */
#include <unistd.h>  /* access */

#include "mca/err.h"
#include "mca/errbuf.h" /* mca_errbuf_printf, mca_errbuf_at */
#include "mca/prefix.h" /* mca_exe_prefix, mca_prefix_sysconfdir */
#include "mca/scheme.h"
#include "mca/urdf.h"
#include "mca/vec3.h"
#include "mca/yaml_load.h" /* mca_yaml_load, mca_scenario_path_fields */
#include "mca/yaml_marks.h"

/* ---------------------------------------------------------------- YAML (start-up only) */

struct raw_arm {
    mca_arm_keys_t model;
};

struct raw_sphere {
    double radius, speed;
    double *start, *end; /* 3 each */
    double *t0, *rate, *latency, *loss;
    int *seed;
};

struct raw_scn {
    char *name;
    double duration;
    double *dt, *d1, *d2;
    mca_gain_keys_t gain;
    double *sample_times;
    unsigned sample_times_count;
    struct raw_arm *arms;
    unsigned arms_count;
    mca_body_keys_t *bodies;
    unsigned bodies_count;
    char **self_pairs;
    unsigned self_pairs_count;
    struct raw_sphere *sim_sphere;
};

static const cyaml_strval_t kind_strings[] = {
    {"hold", MCA_PATH_HOLD},
    {"circle", MCA_PATH_CIRCLE},
    {"waypoints", MCA_PATH_WAYPOINTS},
};

static const cyaml_strval_t tracking_strings[] = {
    {"path_first", MCA_PATH_TRACKING_PATH_FIRST},
    {"elastic", MCA_PATH_TRACKING_ELASTIC},
};

static const cyaml_schema_value_t point_entry = {
    CYAML_VALUE_SEQUENCE_FIXED(CYAML_FLAG_FLOW, double, &mca_yaml_float_entry, 3)};

#define OPT MCA_YAML_OPT

static const cyaml_schema_value_t int_entry = {CYAML_VALUE_INT(CYAML_FLAG_DEFAULT, int)};

const cyaml_schema_field_t mca_scenario_path_fields[] = {
    CYAML_FIELD_ENUM("kind", CYAML_FLAG_DEFAULT, mca_path_keys_t, kind, kind_strings,
                     CYAML_ARRAY_LEN(kind_strings)),
    CYAML_FIELD_BOOL_PTR("relative", OPT, mca_path_keys_t, relative),
    CYAML_FIELD_FLOAT_PTR("t0", OPT, mca_path_keys_t, t0),
    CYAML_FIELD_FLOAT_PTR("radius", OPT, mca_path_keys_t, radius),
    CYAML_FIELD_FLOAT_PTR("period", OPT, mca_path_keys_t, period),
    CYAML_FIELD_FLOAT_PTR("turns", OPT, mca_path_keys_t, turns),
    CYAML_FIELD_SEQUENCE("u", OPT | CYAML_FLAG_FLOW, mca_path_keys_t, u, &mca_yaml_float_entry, 3, 3),
    CYAML_FIELD_SEQUENCE("v", OPT | CYAML_FLAG_FLOW, mca_path_keys_t, v, &mca_yaml_float_entry, 3, 3),
    CYAML_FIELD_SEQUENCE("points", OPT, mca_path_keys_t, points, &point_entry, 1, MCA_PATH_MAX_POINTS),
    CYAML_FIELD_SEQUENCE("durations", OPT | CYAML_FLAG_FLOW, mca_path_keys_t, durations,
                         &mca_yaml_float_entry, 1, MCA_PATH_MAX_POINTS),
    CYAML_FIELD_FLOAT_PTR("tolerance", OPT, mca_path_keys_t, tolerance),
    CYAML_FIELD_SEQUENCE("tolerances", OPT | CYAML_FLAG_FLOW, mca_path_keys_t, tolerances,
                         &mca_yaml_float_entry, 1, MCA_PATH_MAX_POINTS),
    CYAML_FIELD_SEQUENCE("exact", OPT | CYAML_FLAG_FLOW, mca_path_keys_t, exact, &int_entry, 1,
                         MCA_PATH_MAX_POINTS),
    CYAML_FIELD_FLOAT_PTR("exact_tolerance", OPT, mca_path_keys_t, exact_tolerance),
    CYAML_FIELD_ENUM("tracking", CYAML_FLAG_OPTIONAL, mca_path_keys_t, tracking, tracking_strings,
                     CYAML_ARRAY_LEN(tracking_strings)),
    CYAML_FIELD_END,
};

static const cyaml_strval_t body_kind_strings[] = {
    {"plane", MCA_BODY_PLANE}, {"sphere", MCA_BODY_SPHERE},     {"capsule", MCA_BODY_CAPSULE},
    {"box", MCA_BODY_BOX},     {"cylinder", MCA_BODY_CYLINDER},
};

static const cyaml_schema_value_t allow_entry = {CYAML_VALUE_STRING(CYAML_FLAG_POINTER, char, 1, 47)};
const cyaml_schema_value_t mca_scenario_self_entry = {CYAML_VALUE_STRING(CYAML_FLAG_POINTER, char, 1, 47)};

#define BODY_XYZ(key, m)                                                                                     \
    CYAML_FIELD_SEQUENCE(key, OPT | CYAML_FLAG_FLOW, mca_body_keys_t, m, &mca_yaml_float_entry, 3, 3)

static const cyaml_schema_field_t body_fields[] = {
    CYAML_FIELD_STRING_PTR("name", CYAML_FLAG_POINTER, mca_body_keys_t, name, 1, 31),
    CYAML_FIELD_ENUM("kind", CYAML_FLAG_DEFAULT, mca_body_keys_t, kind, body_kind_strings,
                     CYAML_ARRAY_LEN(body_kind_strings)),
    CYAML_FIELD_FLOAT_PTR("clearance", OPT, mca_body_keys_t, clearance),
    CYAML_FIELD_SEQUENCE("allow", OPT | CYAML_FLAG_FLOW, mca_body_keys_t, allow, &allow_entry, 0,
                         MCA_SCENARIO_MAX_ALLOW),
    BODY_XYZ("point", point),
    BODY_XYZ("normal", normal),
    BODY_XYZ("centre", centre),
    BODY_XYZ("a", a),
    BODY_XYZ("b", b),
    BODY_XYZ("half_extents", half_extents),
    BODY_XYZ("rpy", rpy),
    BODY_XYZ("axis", axis),
    CYAML_FIELD_FLOAT_PTR("radius", OPT, mca_body_keys_t, radius),
    CYAML_FIELD_FLOAT_PTR("half_length", OPT, mca_body_keys_t, half_length),
    CYAML_FIELD_END,
};

const cyaml_schema_value_t mca_scenario_body_entry = {
    CYAML_VALUE_MAPPING(CYAML_FLAG_DEFAULT, mca_body_keys_t, body_fields),
};

/* a scenario arm is the model keys alone, every one given (a cell may leave them to its scenario) */
static const cyaml_schema_field_t arm_fields[] = {
    MCA_YAML_ARM_FIELDS(struct raw_arm, model, CYAML_FLAG_POINTER),
    CYAML_FIELD_END,
};

static const cyaml_schema_value_t arm_entry = {
    CYAML_VALUE_MAPPING(CYAML_FLAG_DEFAULT, struct raw_arm, arm_fields),
};

static const cyaml_schema_field_t sphere_fields[] = {
    CYAML_FIELD_FLOAT("radius", CYAML_FLAG_DEFAULT, struct raw_sphere, radius),
    CYAML_FIELD_FLOAT("speed", CYAML_FLAG_DEFAULT, struct raw_sphere, speed),
    CYAML_FIELD_SEQUENCE_FIXED("start", CYAML_FLAG_POINTER | CYAML_FLAG_FLOW, struct raw_sphere, start,
                               &mca_yaml_float_entry, 3),
    CYAML_FIELD_SEQUENCE_FIXED("end", CYAML_FLAG_POINTER | CYAML_FLAG_FLOW, struct raw_sphere, end,
                               &mca_yaml_float_entry, 3),
    CYAML_FIELD_FLOAT_PTR("t0", OPT, struct raw_sphere, t0),
    CYAML_FIELD_FLOAT_PTR("rate", OPT, struct raw_sphere, rate),
    CYAML_FIELD_FLOAT_PTR("latency", OPT, struct raw_sphere, latency),
    CYAML_FIELD_FLOAT_PTR("loss", OPT, struct raw_sphere, loss),
    CYAML_FIELD_INT_PTR("seed", OPT, struct raw_sphere, seed),
    CYAML_FIELD_END,
};

static const cyaml_schema_field_t scn_fields[] = {
    CYAML_FIELD_STRING_PTR("name", CYAML_FLAG_POINTER, struct raw_scn, name, 1, 63),
    CYAML_FIELD_FLOAT("duration", CYAML_FLAG_DEFAULT, struct raw_scn, duration),
    CYAML_FIELD_FLOAT_PTR("dt", OPT, struct raw_scn, dt),
    MCA_YAML_THRESHOLD_FIELDS(struct raw_scn),
    MCA_YAML_GAIN_FIELDS(struct raw_scn, gain),
    CYAML_FIELD_SEQUENCE("sample_times", OPT | CYAML_FLAG_FLOW, struct raw_scn, sample_times,
                         &mca_yaml_float_entry, 1, 16),
    CYAML_FIELD_SEQUENCE("arms", CYAML_FLAG_POINTER, struct raw_scn, arms, &arm_entry, 1, MCA_MAX_ARMS),
    MCA_YAML_BODIES_FIELD(struct raw_scn, bodies),
    MCA_YAML_SELF_FIELD(struct raw_scn, self_pairs),
    CYAML_FIELD_MAPPING_PTR("simulated_sphere", OPT, struct raw_scn, sim_sphere, sphere_fields),
    CYAML_FIELD_END,
};

static const cyaml_schema_value_t scn_schema = {
    CYAML_VALUE_MAPPING(CYAML_FLAG_POINTER, struct raw_scn, scn_fields),
};

/* "FILE:LINE: message" and MCA_ECONFIG */
#define FAIL_AT(line, ...)                                                                                   \
    do {                                                                                                     \
        mca_errbuf_at(err, errlen, path, (line), __VA_ARGS__);                                               \
        rc = MCA_ECONFIG;                                                                                    \
        goto out;                                                                                            \
    } while (0)

/* ---------------------------------------------------------------- ranges */

/* What a real cell can need; docs/scheme.md section 3 lists them. Times up to an hour (the longest task),
 * distances and placements within 100 m of the world origin, gains and speeds far above the paper's. */
static const mca_range_t scn_ranges[] = {
    {"duration", 0.0, 3600.0, 1, 0, "s"},
    {"dt", 1e-4, 0.1, 0, 0, "s"},
    {"d1", 0.0, 1.0, 0, 0, "m"},
    {"d2", 0.0, 2.0, 1, 0, "m"},
    {"K", 0.0, 1000.0, 0, 0, "1/s"},
    {"epsilon", 0.0, 1000.0, 1, 0, "1/s"},
    {"v_normal", 0.0, 10.0, 1, 0, "m/s"},
    {"v_floor", 0.0, 10.0, 0, 0, "m/s"},
    {"sample_times", 0.0, 3600.0, 0, 0, "s"},
    {"base_xyz", -100.0, 100.0, 0, 0, "m"},
    {"base_rpy", -2.0 * M_PI, 2.0 * M_PI, 0, 0, "rad"},
    {"t0", 0.0, 3600.0, 0, 0, "s"},
    {"radius", 0.0, 10.0, 1, 0, "m"},
    {"period", 0.0, 3600.0, 1, 0, "s"},
    {"turns", 0.0, 1000.0, 1, 0, ""},
    {"points", -100.0, 100.0, 0, 0, "m"},
    {"durations", 0.0, 3600.0, 1, 0, "s"},
    {"tolerance", 0.0, 10.0, 0, 0, "m"},
    {"exact_tolerance", 0.0, 1.0, 1, 0, "m"},
    /* fixed bodies (a table needs less clearance than an arm; a cup or a post fits in 10 m) */
    {"clearance", 0.0, 1.0, 0, 0, "m"},
    {"position", -100.0, 100.0, 0, 0, "m"},
    {"direction", -100.0, 100.0, 0, 0, ""},
    {"half_extents", 0.0, 10.0, 0, 0, "m"},
    {"half_length", 0.0, 10.0, 0, 0, "m"},
    {"body_radius", 0.0, 10.0, 0, 0, "m"},
    /* a simulated streamed sphere: what the DDS bridge takes of a track (radius, speed), a camera's rate */
    {"sphere.radius", 0.0, 2.0, 1, 0, "m"},
    {"sphere.speed", 0.0, 10.0, 1, 0, "m/s"},
    {"sphere.rate", 0.0, 1000.0, 1, 0, "1/s"},
    {"sphere.latency", 0.0, 10.0, 0, 0, "s"},
    {"sphere.loss", 0.0, 0.5, 0, 0, ""},
    {"sphere.seed", 0.0, 2147483647.0, 0, 1, ""},
};

int mca_range_check(const mca_range_t *r, double v, char *why, size_t whylen) {
    if (!r) {
        mca_errbuf_printf(why, whylen, "no range");
        return MCA_EINVAL;
    }
    if (isfinite(v) && (r->lo_open ? v > r->lo : v >= r->lo) && v <= r->hi) {
        return MCA_OK;
    }
    const char *sp = r->unit[0] ? " " : "";
    if (r->integer) {
        mca_errbuf_printf(why, whylen, "must be in %.0f..%.0f%s%s (got %.15g)", r->lo, r->hi, sp, r->unit, v);
    } else {
        mca_errbuf_printf(why, whylen, "must be in %c%.6g, %.6g]%s%s (got %.15g)", r->lo_open ? '(' : '[',
                          r->lo, r->hi, sp, r->unit, v);
    }
    return MCA_ECONFIG;
}

const mca_range_t *mca_scenario_range(const char *key) {
    for (size_t i = 0; key && i < sizeof scn_ranges / sizeof scn_ranges[0]; i++) {
        if (strcmp(scn_ranges[i].key, key) == 0) {
            return &scn_ranges[i];
        }
    }
    return NULL;
}

int mca_scenario_check_duration(double duration, double dt, char *why, size_t whylen) {
    int rc = mca_range_check(mca_scenario_range("duration"), duration, why, whylen);
    if (rc != MCA_OK) {
        return rc;
    }
    if (!(dt > 0.0) || !(duration / dt <= (double)MCA_SCENARIO_MAX_TICKS)) {
        mca_errbuf_printf(why, whylen, "%.15g s at a tick of %g s is %.0f ticks, more than %d", duration, dt,
                          duration / dt, MCA_SCENARIO_MAX_TICKS);
        return MCA_ECONFIG;
    }
    return MCA_OK;
}

int mca_check_range(const mca_check_ctx_t *c, const mca_range_t *r, double v, const char *fmt, ...) {
    char why[160];
    if (mca_range_check(r, v, why, sizeof why) == MCA_OK) {
        return MCA_OK;
    }
    char field[MCA_YAML_MARKS_PATH_MAX];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(field, sizeof field, fmt, ap);
    va_end(ap);
    mca_errbuf_at(c->err, c->errlen, c->file, mca_yaml_marks_line_of(c->marks, "%s", field), "%s: %s", field,
                  why);
    return MCA_ECONFIG;
}

int mca_check_fail(const mca_check_ctx_t *c, int rc, const char *node, const char *fmt, ...) {
    char msg[512];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    mca_errbuf_at(c->err, c->errlen, c->file, mca_yaml_marks_line_of(c->marks, "%s", node), "%s", msg);
    return rc;
}

/* Range check of a scenario key (mca_scenario_range(key)) in a loader with `ctx`, `rc` and `out:`. */
#define CHECK_AT(key, v, ...)                                                                                \
    do {                                                                                                     \
        if ((rc = mca_check_range(&ctx, mca_scenario_range(key), (v), __VA_ARGS__)) != MCA_OK) {             \
            goto out;                                                                                        \
        }                                                                                                    \
    } while (0)

int mca_scenario_params_apply(const mca_check_ctx_t *c, const mca_param_keys_t *k, mca_scenario_params_t *p,
                              int *has_form) {
    const char *sv = k->solver ? k->solver : "";
    const mca_gain_keys_t *g = k->gain;
    const struct {
        const char *key, *at; /* range key; "" or the solver's prefix */
        const double *v;
        double *dst;
    } num[] = {
        {"d1", "", k->d1, &p->d1},
        {"d2", "", k->d2, &p->d2},
        {"K", sv, g ? g->K : NULL, &p->K},
        {"epsilon", sv, g ? g->epsilon : NULL, &p->epsilon},
        {"v_normal", sv, g ? g->v_normal : NULL, &p->v_normal},
        {"v_floor", sv, g ? g->v_floor : NULL, &p->v_floor},
    };
    for (size_t i = 0; i < sizeof num / sizeof num[0]; i++) {
        if (num[i].v) {
            int rc =
                mca_check_range(c, mca_scenario_range(num[i].key), *num[i].v, "%s%s", num[i].at, num[i].key);
            if (rc != MCA_OK) {
                return rc;
            }
            *num[i].dst = *num[i].v;
        }
        if (i == 1 && !(isfinite(p->d1) && isfinite(p->d2) && p->d1 >= 0.0 && p->d1 < p->d2)) {
            /* right after d1 and d2: the band S(d) brakes in must not be empty */
            return mca_check_fail(c, MCA_ECONFIG, k->d1 ? "d1" : "d2",
                                  "d1/d2: need 0 <= d1 < d2 (got d1 = %g, d2 = %g)", p->d1, p->d2);
        }
    }
    if (g && g->form) {
        p->form = *g->form;
        if (has_form) {
            *has_form = 1;
        }
    }
    return MCA_OK;
}

static int unit3(double out[3], const double *in) {
    const double n = mca_v3_norm(in);
    if (!(n > 1e-9) || !isfinite(n)) {
        return -1;
    }
    for (int i = 0; i < 3; i++) {
        out[i] = in[i] / n;
    }
    return 0;
}

/* The path starts at the end effector's start position (p[0], set by mca_path_anchor) and then visits the
 * file's points; one duration per point. */
static int waypoints(const mca_check_ctx_t *c, const char *at, const mca_path_keys_t *k, mca_path_t *np) {
    char f[MCA_YAML_MARKS_PATH_MAX];
    snprintf(f, sizeof f, "%s.points", at);
    if (!k->points || k->points_count < 1) {
        return mca_check_fail(c, MCA_ECONFIG, f, "%s: waypoints need points", f);
    }
    if (k->points_count + 1 > MCA_PATH_MAX_POINTS) {
        return mca_check_fail(c, MCA_ECONFIG, f, "%s: at most %d points", f, MCA_PATH_MAX_POINTS - 1);
    }
    if (!k->durations || k->durations_count != k->points_count) {
        snprintf(f, sizeof f, "%s.durations", at);
        return mca_check_fail(c, MCA_ECONFIG, f, "%s: need one duration per point (%u points, %u durations)",
                              f, k->points_count, k->durations ? k->durations_count : 0u);
    }
    np->n_points = (int)k->points_count + 1;
    for (unsigned i = 0; i < k->points_count; i++) {
        int rc;
        for (int j = 0; j < 3; j++) {
            rc = mca_check_range(c, mca_scenario_range("points"), k->points[i][j], "%s.points[%u][%d]", at, i,
                                 j);
            if (rc != MCA_OK) {
                return rc;
            }
            np->p[i + 1][j] = k->points[i][j];
        }
        rc = mca_check_range(c, mca_scenario_range("durations"), k->durations[i], "%s.durations[%u]", at, i);
        if (rc != MCA_OK) {
            return rc;
        }
        np->dur[i] = k->durations[i];
    }
    if (k->tolerances) {
        if (k->tolerances_count != k->points_count) {
            snprintf(f, sizeof f, "%s.tolerances", at);
            return mca_check_fail(c, MCA_ECONFIG, f,
                                  "%s: need one tolerance per point (%u points, %u tolerances)", f,
                                  k->points_count, k->tolerances_count);
        }
        for (unsigned i = 0; i < k->tolerances_count; i++) {
            int rc = mca_check_range(c, mca_scenario_range("tolerance"), k->tolerances[i],
                                     "%s.tolerances[%u]", at, i);
            if (rc != MCA_OK) {
                return rc;
            }
            np->seg_tol[i] = k->tolerances[i];
        }
    }
    for (unsigned i = 0; k->exact && i < k->exact_count; i++) {
        if (k->exact[i] < 0 || k->exact[i] >= (int)k->points_count) {
            snprintf(f, sizeof f, "%s.exact[%u]", at, i);
            return mca_check_fail(c, MCA_ECONFIG, f, "%s: %d is not a point's index (0..%u)", f, k->exact[i],
                                  k->points_count - 1);
        }
        np->exact[k->exact[i] + 1] = 1; /* p[0] is the start */
    }
    return MCA_OK;
}

/* A path at node `at` ("arms[1].path"): *pp unchanged on error. */
static int path_apply(const mca_check_ctx_t *c, const char *at, const mca_path_keys_t *k, mca_path_t *pp) {
    mca_path_t np;
    memset(&np, 0, sizeof np);
    np.kind = k->kind;
    np.relative = 1;
    np.t0 = k->t0 ? *k->t0 : 0.0;
    char f[MCA_YAML_MARKS_PATH_MAX];
    int rc = mca_check_range(c, mca_scenario_range("t0"), np.t0, "%s.t0", at);
    const double tol = k->tolerance ? *k->tolerance : MCA_PATH_DEFAULT_TOL;
    np.exact_tol = k->exact_tolerance ? *k->exact_tolerance : MCA_PATH_DEFAULT_EXACT_TOL;
    if (rc == MCA_OK) {
        rc = mca_check_range(c, mca_scenario_range("tolerance"), tol, "%s.tolerance", at);
    }
    if (rc == MCA_OK) {
        rc =
            mca_check_range(c, mca_scenario_range("exact_tolerance"), np.exact_tol, "%s.exact_tolerance", at);
    }
    for (int i = 0; i < MCA_PATH_MAX_POINTS; i++) {
        np.seg_tol[i] = tol;
    }
    /* path first unless the file asks for the elastic tracking (hold: nothing to keep) */
    np.path_first = k->tracking == MCA_PATH_TRACKING_PATH_FIRST ||
                    (k->tracking == MCA_PATH_TRACKING_DEFAULT && k->kind != MCA_PATH_HOLD);
    if (rc == MCA_OK && k->tracking == MCA_PATH_TRACKING_ELASTIC &&
        (k->tolerance || k->tolerances || k->exact || k->exact_tolerance)) {
        snprintf(f, sizeof f, "%s.tracking", at);
        rc = mca_check_fail(c, MCA_ECONFIG, f,
                            "%s: elastic tracking has no tube (tolerance, exact): drop one", f);
    }
    if (rc == MCA_OK && k->kind != MCA_PATH_WAYPOINTS && (k->tolerances || k->exact)) {
        snprintf(f, sizeof f, "%s.%s", at, k->tolerances ? "tolerances" : "exact");
        rc = mca_check_fail(c, MCA_ECONFIG, f, "%s: waypoints only", f);
    }
    if (rc == MCA_OK && k->kind == MCA_PATH_WAYPOINTS) {
        np.relative = k->relative ? (*k->relative ? 1 : 0) : 1;
        rc = waypoints(c, at, k, &np);
    }
    if (rc != MCA_OK || k->kind != MCA_PATH_CIRCLE) {
        if (rc == MCA_OK) {
            *pp = np;
        }
        return rc;
    }
    if (!k->radius || !k->period) {
        snprintf(f, sizeof f, "%s.%s", at, k->radius ? "period" : "radius");
        return mca_check_fail(c, MCA_ECONFIG, f, "%s: circle needs %s > 0", f,
                              k->radius ? "period" : "radius");
    }
    if (!k->u || !k->v) {
        snprintf(f, sizeof f, "%s.%s", at, k->u ? "v" : "u");
        return mca_check_fail(c, MCA_ECONFIG, f, "%s.u/v: circle needs in-plane vectors u and v", at);
    }
    np.radius = *k->radius;
    np.period = *k->period;
    np.turns = k->turns ? *k->turns : 1.0;
    if ((rc = mca_check_range(c, mca_scenario_range("radius"), np.radius, "%s.radius", at)) != MCA_OK ||
        (rc = mca_check_range(c, mca_scenario_range("period"), np.period, "%s.period", at)) != MCA_OK ||
        (rc = mca_check_range(c, mca_scenario_range("turns"), np.turns, "%s.turns", at)) != MCA_OK) {
        return rc;
    }
    double v[3];
    if (unit3(np.u, k->u) != 0) {
        snprintf(f, sizeof f, "%s.u", at);
        return mca_check_fail(c, MCA_ECONFIG, f, "%s: zero vector", f);
    }
    mca_v3_axpy(v, k->v, -mca_v3_dot(k->v, np.u), np.u); /* Gram-Schmidt: v orthogonal to u */
    if (unit3(np.v, v) != 0) {
        snprintf(f, sizeof f, "%s.v", at);
        return mca_check_fail(c, MCA_ECONFIG, f, "%s: parallel to u", f);
    }
    *pp = np;
    return MCA_OK;
}

/* The base placement where given (3 values each, or NULL). */
static int place_apply(const mca_check_ctx_t *c, int arm, const double *xyz, const double *rpy,
                       mca_scenario_arm_t *sa) {
    for (int i = 0; i < 3; i++) {
        int rc;
        if (xyz) {
            if ((rc = mca_check_range(c, mca_scenario_range("base_xyz"), xyz[i], "arms[%d].base_xyz[%d]", arm,
                                      i)) != MCA_OK) {
                return rc;
            }
            sa->base_xyz[i] = xyz[i];
        }
        if (rpy) {
            if ((rc = mca_check_range(c, mca_scenario_range("base_rpy"), rpy[i], "arms[%d].base_rpy[%d]", arm,
                                      i)) != MCA_OK) {
                return rc;
            }
            sa->base_rpy[i] = rpy[i];
        }
    }
    return MCA_OK;
}

#ifdef MCA_SEARCH_PATH
#define CONFIG_SEARCH_PATH MCA_SEARCH_PATH
#else
#define CONFIG_SEARCH_PATH "/etc/mca:/usr/share/mca"
#endif

/* The search path without MCA_PATH: the running program's own prefix first (an install to any prefix finds
 * its files), then the build's, each folder once. Made once, at the first lookup (start-up). */
static char search_path[3 * PATH_MAX];
static once_flag search_path_once = ONCE_FLAG_INIT;

static void search_path_add(const char *dir, size_t n) {
    const size_t have = strlen(search_path);
    for (const char *p = search_path; *p;) {
        const size_t m = strcspn(p, ":");
        if (m == n && strncmp(p, dir, n) == 0) {
            return;
        }
        p += m + (p[m] == ':');
    }
    if (n > 0 && have + n + 2 <= sizeof search_path) {
        snprintf(search_path + have, sizeof search_path - have, "%s%.*s", have ? ":" : "", (int)n, dir);
    }
}

static void search_path_init(void) {
    char prefix[PATH_MAX], etc[PATH_MAX], dir[PATH_MAX + 16];
    if (mca_exe_prefix(prefix, sizeof prefix) == MCA_OK &&
        mca_prefix_sysconfdir(prefix, etc, sizeof etc) == MCA_OK) {
        snprintf(dir, sizeof dir, "%s/mca", etc);
        search_path_add(dir, strlen(dir));
        snprintf(dir, sizeof dir, "%s/share/mca", prefix);
        search_path_add(dir, strlen(dir));
    }
    for (const char *p = CONFIG_SEARCH_PATH; *p;) {
        const size_t n = strcspn(p, ":");
        search_path_add(p, n);
        p += n + (p[n] == ':');
    }
}

const char *mca_config_search_path(void) {
    const char *env = getenv("MCA_PATH");
    if (env && env[0]) {
        return env;
    }
    call_once(&search_path_once, search_path_init);
    return search_path;
}

static int readable(const char *p) {
    return access(p, R_OK) == 0;
}

void mca_config_resolve(char *out, size_t outlen, const char *base_file, const char *rel) {
    char abs_base[4096];
    if (realpath(base_file, abs_base)) {
        base_file = abs_base;
    }
    if (rel[0] == '/') {
        snprintf(out, outlen, "%s", rel);
        return;
    }
    const char *slash = strrchr(base_file, '/');
    if (slash) {
        snprintf(out, outlen, "%.*s/%s", (int)(slash - base_file), base_file, rel);
    } else {
        snprintf(out, outlen, "%s", rel);
    }
    if (readable(out)) {
        return;
    }
    const char *tail = rel;
    while (strncmp(tail, "../", 3) == 0 || strncmp(tail, "./", 2) == 0) {
        tail += tail[1] == '/' ? 2 : 3;
    }
    const char *path = mca_config_search_path();
    while (*path) {
        const size_t n = strcspn(path, ":");
        char cand[4096];
        if (n > 0 && (size_t)snprintf(cand, sizeof cand, "%.*s/%s", (int)n, path, tail) < sizeof cand &&
            readable(cand) && strlen(cand) < outlen) {
            memcpy(out, cand, strlen(cand) + 1);
            return;
        }
        path += n + (path[n] == ':');
    }
}

int mca_config_find(const mca_check_ctx_t *c, const char *field, const char *rel, char *out, size_t outlen) {
    mca_config_resolve(out, outlen, c->file, rel);
    if (readable(out)) {
        return MCA_OK;
    }
    return mca_check_fail(c, MCA_ENOENT, field, "%s: file '%s' not found (nor in the search path %s)", field,
                          out, mca_config_search_path());
}

int mca_scenario_arm_apply(const mca_check_ctx_t *c, int arm, const mca_arm_keys_t *k,
                           mca_scenario_arm_t *sa) {
    int rc;
    if (k->urdf || k->tip_link) {
        sa->chain.dof = 0; /* another model: mca_scenario_arm_model() loads it */
    }
    if (k->urdf) {
        char f[32];
        snprintf(f, sizeof f, "arms[%d].urdf", arm);
        if ((rc = mca_config_find(c, f, k->urdf, sa->urdf, sizeof sa->urdf)) != MCA_OK) {
            return rc;
        }
    }
    if (k->tip_link) {
        snprintf(sa->tip_link, sizeof sa->tip_link, "%s", k->tip_link);
    }
    rc = place_apply(c, arm, k->base_xyz, k->base_rpy, sa);
    if (rc != MCA_OK) {
        return rc;
    }
    if (k->q0) {
        sa->n_q0 = (int)k->q0_count;
        for (unsigned j = 0; j < k->q0_count; j++) {
            sa->q0[j] = k->q0[j];
        }
    }
    if (k->path) {
        char at[32];
        snprintf(at, sizeof at, "arms[%d].path", arm);
        rc = path_apply(c, at, k->path, &sa->path);
    }
    return rc;
}

int mca_scenario_arm_model(const mca_check_ctx_t *c, int arm, mca_scenario_arm_t *sa) {
    char f[40], why[400];
    mca_chain_t *chain = &sa->chain;
    if (chain->dof == 0) {
        int rc = mca_chain_load_urdf(chain, sa->urdf, sa->tip_link[0] ? sa->tip_link : NULL, why, sizeof why);
        if (rc != MCA_OK) {
            chain->dof = 0;
            snprintf(f, sizeof f, "arms[%d].urdf", arm);
            return mca_check_fail(c, rc, f, "%s: %s", f, why);
        }
    }
    snprintf(f, sizeof f, "arms[%d].q0", arm);
    if (sa->n_q0 != chain->dof) {
        return mca_check_fail(c, MCA_ECONFIG, f, "%s: %d values but %s has %d joints (DOF mismatch)", f,
                              sa->n_q0, sa->urdf, chain->dof);
    }
    for (int j = 0; j < chain->dof; j++) {
        const mca_joint_model_t *jm = &chain->joint[j];
        if (!isfinite(sa->q0[j]) || (!jm->continuous && (sa->q0[j] < jm->lower || sa->q0[j] > jm->upper))) {
            snprintf(f, sizeof f, "arms[%d].q0[%d]", arm, j);
            return mca_check_fail(c, MCA_ECONFIG, f, "%s: %g outside joint '%s' limits [%g, %g]", f,
                                  sa->q0[j], jm->name, jm->lower, jm->upper);
        }
    }
    return MCA_OK;
}

/* ---------------------------------------------------------------- fixed bodies */

/* An allow entry "ARM", "ARM.base", "ARM.tool" or "ARM.N" against the arms arm[0..n): *arm its index, *link
 * the link (-1: every link). @return 0, -1 (no such arm), -2 (no such link) */
static int allow_parse(const char *s, const mca_scenario_arm_t *arm, int n, int *ai, int *link) {
    const char *dot = strrchr(s, '.');
    size_t len = strlen(s);
    *link = -1;
    char *end = NULL;
    const char *tail = dot ? dot + 1 : "";
    long num = dot && *tail ? strtol(tail, &end, 10) : -1;
    const int has_link = dot && (strcmp(tail, "base") == 0 || strcmp(tail, "tool") == 0 || (end && !*end));
    if (has_link) {
        len = (size_t)(dot - s);
    }
    for (int a = 0; a < n; a++) {
        if (strlen(arm[a].name) == len && strncmp(arm[a].name, s, len) == 0) {
            *ai = a;
            if (!has_link) {
                return 0;
            }
            const int dof = arm[a].chain.dof;
            if (strcmp(tail, "base") == 0) {
                *link = 0;
            } else if (strcmp(tail, "tool") == 0) {
                *link = dof;
            } else if (num >= 0 && (dof == 0 || num <= dof)) {
                *link = (int)num;
            } else {
                return -2;
            }
            return 0;
        }
    }
    return -1;
}

/* "a, b, c": the arms' names (messages) */
static void arm_names(const mca_scenario_t *scn, char *out, size_t len) {
    out[0] = 0;
    for (int a = 0; a < scn->n_arms; a++) {
        const size_t n = strlen(out);
        snprintf(out + n, len - n, "%s%s", a ? ", " : "", scn->arm[a].name);
    }
}

/* Each kind's keys (and no other): what bodies[i] gives is checked against this. */
static const struct {
    int kind;
    const char *keys; /* required, then optional after '|' */
} kind_keys[] = {
    {MCA_BODY_PLANE, "point normal|"},
    {MCA_BODY_SPHERE, "centre radius|"},
    {MCA_BODY_CAPSULE, "a b radius|"},
    {MCA_BODY_BOX, "centre half_extents|rpy"},
    {MCA_BODY_CYLINDER, "centre half_length radius|axis"},
};

/* One body's geometry keys: every key given is one of its kind's, every required one given. */
static int body_keys_check(const mca_check_ctx_t *c, int i, const mca_body_keys_t *k) {
    const struct {
        const char *key;
        int given;
    } given[] = {
        {"point", k->point != NULL},   {"normal", k->normal != NULL},
        {"centre", k->centre != NULL}, {"a", k->a != NULL},
        {"b", k->b != NULL},           {"half_extents", k->half_extents != NULL},
        {"rpy", k->rpy != NULL},       {"axis", k->axis != NULL},
        {"radius", k->radius != NULL}, {"half_length", k->half_length != NULL},
    };
    const char *keys = "";
    for (size_t j = 0; j < sizeof kind_keys / sizeof kind_keys[0]; j++) {
        if (kind_keys[j].kind == k->kind) {
            keys = kind_keys[j].keys;
        }
    }
    const char *bar = strchr(keys, '|');
    const char *kind = mca_body_kind_name(k->kind);
    char f[64];
    for (size_t g = 0; g < sizeof given / sizeof given[0]; g++) {
        const size_t kl = strlen(given[g].key);
        int in = 0, required = 0;
        for (const char *p = keys; *p;) {
            const size_t n = strcspn(p, " |");
            if (n == kl && strncmp(p, given[g].key, kl) == 0) {
                in = 1;
                required = p < bar;
            }
            p += n;
            p += *p != 0;
        }
        snprintf(f, sizeof f, "bodies[%d].%s", i, given[g].key);
        if (given[g].given && !in) {
            return mca_check_fail(c, MCA_ECONFIG, f, "%s: not a key of a %s (its keys: %.*s%s%s)", f, kind,
                                  (int)(bar - keys), keys, bar[1] ? ", optional " : "", bar + 1);
        }
        if (required && !given[g].given) {
            return mca_check_fail(c, MCA_ECONFIG, f, "%s: a %s needs %.*s", f, kind, (int)(bar - keys), keys);
        }
    }
    return MCA_OK;
}

/* 3 numbers of bodies[i].key in the range `range`, into out (left alone when v is NULL). */
static int body_xyz(const mca_check_ctx_t *c, int i, const char *key, const char *range, const double *v,
                    double out[3]) {
    for (int j = 0; v && j < 3; j++) {
        const int rc = mca_check_range(c, mca_scenario_range(range), v[j], "bodies[%d].%s[%d]", i, key, j);
        if (rc != MCA_OK) {
            return rc;
        }
        out[j] = v[j];
    }
    return MCA_OK;
}

/* A direction (normal, axis): not zero. */
static int body_dir(const mca_check_ctx_t *c, int i, const char *key, const double *v, double out[3]) {
    int rc = body_xyz(c, i, key, "direction", v, out);
    if (rc == MCA_OK && v && !(mca_v3_norm(out) > 1e-9)) {
        char f[64];
        snprintf(f, sizeof f, "bodies[%d].%s", i, key);
        rc = mca_check_fail(c, MCA_ECONFIG, f, "%s: zero vector", f);
    }
    return rc;
}

static int body_num(const mca_check_ctx_t *c, int i, const char *key, const char *range, const double *v,
                    double *out) {
    if (!v) {
        return MCA_OK;
    }
    *out = *v;
    return mca_check_range(c, mca_scenario_range(range), *v, "bodies[%d].%s", i, key);
}

/* bodies[i] into *sb (a fresh body). */
static int body_apply(const mca_check_ctx_t *c, int i, const mca_body_keys_t *k, const mca_scenario_t *scn,
                      mca_scenario_body_t *sb) {
    memset(sb, 0, sizeof *sb);
    snprintf(sb->fb.name, sizeof sb->fb.name, "%s", k->name);
    sb->clearance = -1.0;
    int rc = body_keys_check(c, i, k);
    if (rc == MCA_OK) {
        rc = body_num(c, i, "clearance", "clearance", k->clearance, &sb->clearance);
    }
    if (rc != MCA_OK) {
        return rc;
    }
    mca_body_t *b = &sb->fb.body;
    b->kind = (mca_body_kind_t)k->kind;
    switch (b->kind) {
    case MCA_BODY_PLANE:
        if ((rc = body_xyz(c, i, "point", "position", k->point, b->u.plane.point)) == MCA_OK) {
            rc = body_dir(c, i, "normal", k->normal, b->u.plane.normal);
        }
        break;
    case MCA_BODY_SPHERE:
        if ((rc = body_xyz(c, i, "centre", "position", k->centre, b->u.sphere.centre)) == MCA_OK) {
            rc = body_num(c, i, "radius", "body_radius", k->radius, &b->u.sphere.radius);
        }
        break;
    case MCA_BODY_CAPSULE:
        if ((rc = body_xyz(c, i, "a", "position", k->a, b->u.capsule.a)) == MCA_OK &&
            (rc = body_xyz(c, i, "b", "position", k->b, b->u.capsule.b)) == MCA_OK) {
            rc = body_num(c, i, "radius", "body_radius", k->radius, &b->u.capsule.radius);
        }
        break;
    case MCA_BODY_BOX: {
        double rpy[3] = {0.0, 0.0, 0.0}, zero[3] = {0.0, 0.0, 0.0};
        if ((rc = body_xyz(c, i, "centre", "position", k->centre, b->u.box.centre)) == MCA_OK &&
            (rc = body_xyz(c, i, "half_extents", "half_extents", k->half_extents, b->u.box.half)) == MCA_OK &&
            (rc = body_xyz(c, i, "rpy", "base_rpy", k->rpy, rpy)) == MCA_OK) {
            mca_pose_t pose;
            mca_pose_from_xyz_rpy(&pose, zero, rpy);
            memcpy(b->u.box.R, pose.R, sizeof b->u.box.R); /* world <- box, its columns the box axes */
        }
        break;
    }
    case MCA_BODY_CYLINDER:
        b->u.cylinder.axis[2] = 1.0;
        if ((rc = body_xyz(c, i, "centre", "position", k->centre, b->u.cylinder.centre)) == MCA_OK &&
            (rc = body_dir(c, i, "axis", k->axis, b->u.cylinder.axis)) == MCA_OK &&
            (rc = body_num(c, i, "half_length", "half_length", k->half_length, &b->u.cylinder.half_len)) ==
                MCA_OK) {
            rc = body_num(c, i, "radius", "body_radius", k->radius, &b->u.cylinder.radius);
        }
        break;
    }
    if (rc != MCA_OK) {
        return rc;
    }
    sb->fb.clearance = sb->clearance >= 0.0 ? sb->clearance : 0.0;
    char f[64];
    snprintf(f, sizeof f, "bodies[%d]", i);
    if (mca_body_check(&sb->fb) != MCA_OK) {
        return mca_check_fail(c, MCA_ECONFIG, f, "%s: not a usable %s", f, mca_body_kind_name(k->kind));
    }
    for (unsigned j = 0; k->allow && j < k->allow_count; j++) {
        int ai, link;
        const int r = allow_parse(k->allow[j], scn->arm, scn->n_arms, &ai, &link);
        snprintf(f, sizeof f, "bodies[%d].allow[%u]", i, j);
        if (r == -1) {
            char names[160];
            arm_names(scn, names, sizeof names);
            return mca_check_fail(c, MCA_ECONFIG, f,
                                  "%s: no arm '%s' (arms: %s; write ARM, ARM.base, ARM.tool or ARM.N)", f,
                                  k->allow[j], names);
        }
        if (r == -2) {
            return mca_check_fail(c, MCA_ECONFIG, f, "%s: '%s': arm '%s' has links 0..%d (base, tool)", f,
                                  k->allow[j], scn->arm[ai].name, scn->arm[ai].chain.dof);
        }
        snprintf(sb->allow[sb->n_allow++], sizeof sb->allow[0], "%s", k->allow[j]);
    }
    return MCA_OK;
}

int mca_scenario_bodies_apply(const mca_check_ctx_t *c, const mca_body_keys_t *k, unsigned count,
                              mca_scenario_t *scn) {
    for (unsigned i = 0; k && i < count; i++) {
        mca_scenario_body_t sb;
        int rc = body_apply(c, (int)i, &k[i], scn, &sb);
        if (rc != MCA_OK) {
            return rc;
        }
        for (unsigned j = 0; j < i; j++) {
            if (strcmp(k[j].name, k[i].name) == 0) {
                char f[64];
                snprintf(f, sizeof f, "bodies[%u].name", i);
                return mca_check_fail(c, MCA_ECONFIG, f, "%s: '%s' used twice", f, k[i].name);
            }
        }
        int at = scn->n_bodies;
        for (int b = 0; b < scn->n_bodies; b++) {
            if (strcmp(scn->body[b].fb.name, sb.fb.name) == 0) {
                at = b; /* a cell's body of its scenario's name replaces it */
            }
        }
        if (at >= MCA_MAX_BODIES) {
            char f[64];
            snprintf(f, sizeof f, "bodies[%u]", i);
            return mca_check_fail(c, MCA_ECONFIG, f, "%s: more than %d bodies", f, MCA_MAX_BODIES);
        }
        scn->body[at] = sb;
        scn->n_bodies += at == scn->n_bodies;
    }
    return MCA_OK;
}

int mca_scenario_bodies_resolve(const mca_scenario_t *scn, mca_fixed_body_t out[MCA_MAX_BODIES], char *err,
                                size_t errlen) {
    for (int k = 0; k < scn->n_bodies && k < MCA_MAX_BODIES; k++) {
        const mca_scenario_body_t *sb = &scn->body[k];
        out[k] = sb->fb;
        out[k].clearance = sb->clearance >= 0.0 ? sb->clearance : scn->params.d1;
        memset(out[k].allow, 0, sizeof out[k].allow);
        for (int j = 0; j < sb->n_allow; j++) {
            int ai, link;
            if (allow_parse(sb->allow[j], scn->arm, scn->n_arms, &ai, &link) != 0) {
                mca_errbuf_printf(err, errlen, "%s: bodies '%s': allow '%s' is no link of the arms",
                                  scn->source, sb->fb.name, sb->allow[j]);
                return MCA_ECONFIG;
            }
            const int dof = scn->arm[ai].chain.dof;
            out[k].allow[ai] |= link < 0 ? (dof > 0 ? (1u << (dof + 1)) - 1u : ~0u) : 1u << link;
        }
    }
    return MCA_OK;
}

/* A scenario's parameters are the scheme's (mca_scheme_params_t) and the tick period: these two move
 * them each way, so that the defaults are the scheme's own (mca_scheme_default_params), not a copy. */
static void params_from_scheme(mca_scenario_params_t *p, const mca_scheme_params_t *sp) {
    p->form = (int)sp->form;
    p->d1 = sp->d1;
    p->d2 = sp->d2;
    p->K = sp->K;
    p->epsilon = sp->epsilon;
    p->v_normal = sp->v_normal;
    p->v_floor = sp->v_floor;
}

static void params_to_scheme(mca_scheme_params_t *sp, const mca_scenario_params_t *p) {
    sp->form = (mca_collision_form_t)p->form;
    sp->d1 = p->d1;
    sp->d2 = p->d2;
    sp->K = p->K;
    sp->epsilon = p->epsilon;
    sp->v_normal = p->v_normal;
    sp->v_floor = p->v_floor;
}

void mca_scenario_defaults(mca_scenario_t *scn) {
    memset(scn, 0, sizeof *scn);
    mca_scheme_params_t sp;
    mca_scheme_default_params(&sp);
    params_from_scheme(&scn->params, &sp);
    scn->params.dt = MCA_CONTROLLER_DT;
}

/* simulated_sphere: a tracked sphere on a straight line, for mca-sim (mca_sim_sphere_t). */
static int sim_sphere_apply(const mca_check_ctx_t *c, const struct raw_sphere *k, mca_sim_sphere_t *s) {
    *s = (mca_sim_sphere_t){.enabled = 1, .t0 = 0.0, .rate = 30.0, .latency = 0.03, .loss = 0.0, .seed = 1};
    s->line = mca_yaml_marks_line_of(c->marks, "simulated_sphere");
    int rc;
    if ((rc =
             mca_check_range(c, mca_scenario_range("sphere.radius"), k->radius, "simulated_sphere.radius")) ||
        (rc = mca_check_range(c, mca_scenario_range("sphere.speed"), k->speed, "simulated_sphere.speed"))) {
        return rc;
    }
    s->radius = k->radius;
    s->speed = k->speed;
    for (int j = 0; j < 3; j++) {
        if ((rc = mca_check_range(c, mca_scenario_range("position"), k->start[j],
                                  "simulated_sphere.start[%d]", j)) ||
            (rc = mca_check_range(c, mca_scenario_range("position"), k->end[j], "simulated_sphere.end[%d]",
                                  j))) {
            return rc;
        }
        s->start[j] = k->start[j];
        s->end[j] = k->end[j];
    }
    double d[3];
    mca_v3_sub(d, s->end, s->start);
    if (!(mca_v3_norm(d) > 1e-6)) {
        return mca_check_fail(c, MCA_ECONFIG, "simulated_sphere.end",
                              "simulated_sphere.end: the same point as start (a line needs two)");
    }
    const struct {
        const char *key, *range;
        const double *v;
        double *dst;
    } opt[] = {
        {"t0", "t0", k->t0, &s->t0},
        {"rate", "sphere.rate", k->rate, &s->rate},
        {"latency", "sphere.latency", k->latency, &s->latency},
        {"loss", "sphere.loss", k->loss, &s->loss},
    };
    for (size_t i = 0; i < sizeof opt / sizeof opt[0]; i++) {
        if (opt[i].v) {
            if ((rc = mca_check_range(c, mca_scenario_range(opt[i].range), *opt[i].v, "simulated_sphere.%s",
                                      opt[i].key))) {
                return rc;
            }
            *opt[i].dst = *opt[i].v;
        }
    }
    if (k->seed) {
        if ((rc = mca_check_range(c, mca_scenario_range("sphere.seed"), (double)*k->seed,
                                  "simulated_sphere.seed"))) {
            return rc;
        }
        s->seed = (unsigned)*k->seed;
    }
    return MCA_OK;
}

int mca_scenario_load(const char *path, mca_scenario_t *scn_out, char *err, size_t errlen) {
    if (!path || !scn_out) {
        mca_errbuf_printf(err, errlen, "scenario: NULL argument");
        return MCA_EINVAL;
    }
    struct raw_scn *raw = NULL;
    mca_yaml_marks_t marks;
    int rc = mca_yaml_load(path, "scenario", &scn_schema, (void **)&raw, &marks, err, errlen);
    if (rc != MCA_OK) {
        return rc;
    }
    const mca_check_ctx_t ctx = {.file = path, .marks = &marks, .err = err, .errlen = errlen};

    mca_scenario_t scn;
    mca_scenario_defaults(&scn);
    snprintf(scn.name, sizeof scn.name, "%s", raw->name);
    snprintf(scn.source, sizeof scn.source, "%s", path);
    scn.duration = raw->duration;
    mca_scenario_params_t *p = &scn.params;
    if (raw->dt) {
        CHECK_AT("dt", *raw->dt, "dt");
        p->dt = *raw->dt;
    }
    {
        char why[160];
        if (mca_scenario_check_duration(scn.duration, p->dt, why, sizeof why) != MCA_OK) {
            FAIL_AT(mca_yaml_marks_line_of(&marks, "duration"), "duration: %s", why);
        }
    }
    {
        const mca_param_keys_t keys = {.solver = "", .d1 = raw->d1, .d2 = raw->d2, .gain = &raw->gain};
        if ((rc = mca_scenario_params_apply(&ctx, &keys, p, &scn.has_form)) != MCA_OK) {
            goto out;
        }
    }
    scn.n_sample_times = (int)raw->sample_times_count;
    for (unsigned i = 0; i < raw->sample_times_count; i++) {
        CHECK_AT("sample_times", raw->sample_times[i], "sample_times[%u]", i);
        scn.sample_times[i] = raw->sample_times[i];
    }

    scn.n_arms = (int)raw->arms_count;
    for (unsigned a = 0; a < raw->arms_count; a++) {
        const mca_arm_keys_t *ra = &raw->arms[a].model;
        mca_scenario_arm_t *sa = &scn.arm[a];
        snprintf(sa->name, sizeof sa->name, "%s", ra->name);
        if ((rc = mca_scenario_arm_apply(&ctx, (int)a, ra, sa)) != MCA_OK ||
            (rc = mca_scenario_arm_model(&ctx, (int)a, sa)) != MCA_OK) {
            goto out;
        }
    }
    /* the bodies after the arms: their allow lists name links */
    if ((rc = mca_scenario_bodies_apply(&ctx, raw->bodies, raw->bodies_count, &scn)) != MCA_OK ||
        (rc = mca_scenario_self_apply(&ctx, raw->self_pairs, raw->self_pairs_count, &scn)) != MCA_OK) {
        goto out;
    }
    if (raw->sim_sphere && (rc = sim_sphere_apply(&ctx, raw->sim_sphere, &scn.sim_sphere)) != MCA_OK) {
        goto out;
    }
    *scn_out = scn;
out:
    mca_yaml_marks_free(&marks);
    mca_yaml_free(&scn_schema, raw);
    return rc;
}

/* ---------------------------------------------------------------- scenario -> controller config */

/* Schemes with collision rows (and the distance fault); as in controller.c. */
static int uses_rows(mca_scheme_kind_t scheme) {
    return scheme == MCA_SCHEME_MCA || scheme == MCA_SCHEME_MCA_TS;
}

int mca_controller_config_from_scenario(mca_controller_config_t *cfg, const mca_scenario_t *scn,
                                        mca_scheme_kind_t scheme, char *err, size_t errlen) {
    if (!cfg || !scn || scn->n_arms < 1 || scn->n_arms > MCA_MAX_ARMS) {
        if (err && errlen) {
            snprintf(err, errlen, "controller: bad scenario");
        }
        return MCA_EINVAL;
    }
    mca_controller_default_config(cfg);
    cfg->n_arms = scn->n_arms;
    cfg->scheme = scheme;
    for (int a = 0; a < scn->n_arms; a++) {
        const mca_scenario_arm_t *sa = &scn->arm[a];
        if (sa->chain.dof > 0) {
            cfg->chain[a] = sa->chain; /* loaded and checked with the file */
        } else {
            /* a scenario made in code: its model was never loaded */
            int rc = mca_chain_load_urdf(&cfg->chain[a], sa->urdf, sa->tip_link[0] ? sa->tip_link : NULL, err,
                                         errlen);
            if (rc != MCA_OK) {
                return rc;
            }
        }
        if (sa->n_q0 != cfg->chain[a].dof) {
            if (err && errlen) {
                snprintf(err, errlen, "%s: arms[%d].q0 has %d values but %s has %d joints", scn->source, a,
                         sa->n_q0, sa->urdf, cfg->chain[a].dof);
            }
            return MCA_EINVAL;
        }
        mca_chain_set_base(&cfg->chain[a], sa->base_xyz, sa->base_rpy);
        cfg->path[a] = sa->path;
    }
    cfg->sp.collision = uses_rows(scheme);
    params_to_scheme(&cfg->sp, &scn->params);
    if (scn->n_bodies < 0 || scn->n_bodies > MCA_MAX_BODIES) {
        mca_errbuf_printf(err, errlen, "%s: %d bodies", scn->source, scn->n_bodies);
        return MCA_EINVAL;
    }
    int rc = mca_scenario_bodies_resolve(scn, cfg->body, err, errlen);
    if (rc != MCA_OK) {
        return rc;
    }
    cfg->n_bodies = scn->n_bodies;
    for (int a = 0; a < scn->n_arms; a++) {
        const int dof = cfg->chain[a].dof;
        for (int l = 0; l < MCA_MAX_LINKS; l++) {
            /* pairs of links the arm has (a cell may have changed its model) */
            cfg->self[a][l] = l <= dof ? scn->arm[a].self[l] & ((1u << l) - 1u) : 0u;
        }
    }
    cfg->dt = scn->params.dt;
    /* The baselines are run to show what happens without the scheme: no distance fault for them. */
    cfg->fault_distance = uses_rows(scheme);
    return MCA_OK;
}
