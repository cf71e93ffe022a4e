/* SPDX-License-Identifier: MIT */
/** @file mca/scenario.h
 * Task (scenario) files (mca_model, start-up only) and the controller config made from one.
 *
 * A scenario names the arms (URDF, tip link, base placement, initial joints), one desired path per arm
 * (mca_path_t, mca/path.h: evaluated by the real-time core), the duration and the scheme parameters
 * (d1, d2, K, epsilon, ...). It is a YAML file parsed with libcyaml; see the files in config/scenarios/ and
 * docs/scheme.md for the format. mca_controller_config_from_scenario() turns a loaded scenario into the
 * core's mca_controller_config_t (loading each arm's URDF through mca/urdf.h).
 */
#ifndef MCA_SCENARIO_H
#define MCA_SCENARIO_H

#include <stdbool.h>
#include <stddef.h>

#include "mca/controller.h"
#include "mca/limits.h"
#include "mca/path.h"
#include "mca/yaml_marks.h"

#ifdef __cplusplus
extern "C" {
#endif

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
    /** The URDF's chain to tip_link as mca_scenario_arm_model() loaded and checked it (base not applied;
     *  dof 0: not loaded, or urdf/tip_link changed since): loaded once per file, then copied. */
    mca_chain_t chain;
    mca_self_pairs_t self; /**< the arm's self pairs (mca/bodyrows.h; `self_pairs:`), none by default */
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

/** Most entries in one body's allow list. */
#define MCA_SCENARIO_MAX_ALLOW 16

/** One fixed body of a scenario or cell (the `bodies:` list; docs/scheme.md section 3). Its allow list
 *  names links by arm name, resolved against the arms' order when the controller's config is made. */
typedef struct mca_scenario_body {
    mca_fixed_body_t fb; /**< name, kind, geometry; fb.allow empty (the list below is resolved later) */
    double clearance;    /**< [m]; < 0: not given, the task's d1 (after any cell override of d1) */
    int n_allow;
    char allow[MCA_SCENARIO_MAX_ALLOW][48]; /**< "ARM" (every link), "ARM.base", "ARM.tool", "ARM.N" */
} mca_scenario_body_t;

/** A simulated streamed body (`simulated_sphere:`, docs/scheme.md section 14): a sphere a virtual tracker
 * sees moving on a straight line, sampled at `rate`, each sample reaching the controller `latency` after it
 * was taken, a fraction `loss` of them lost (seeded). mca-sim feeds it through the daemon's track input
 *  (mca_drive_put_tracks); mcad refuses a task that declares one (its tracks come over DDS Security only). */
typedef struct mca_sim_sphere {
    int enabled;
    int line;                /**< the key's line in the file (for mcad's refusal) */
    double radius;           /**< [m] */
    double start[3], end[3]; /**< the line, world frame [m] */
    double speed;            /**< along it [m/s] */
    double t0;               /**< it leaves start at this task time; before it stands at start [s] (0) */
    double rate;             /**< samples per second (30, a camera) */
    double latency;          /**< a sample's age when it reaches the controller [s] (0.03) */
    double loss;             /**< fraction of samples lost (0) */
    unsigned seed;           /**< of the losses (1) */
} mca_sim_sphere_t;

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
    int n_bodies; /**< fixed bodies (tables, fixtures, cups) */
    mca_scenario_body_t body[MCA_MAX_BODIES];
    mca_sim_sphere_t sim_sphere; /**< a simulated streamed sphere (mca-sim only) */
} mca_scenario_t;

/**
 * Allowed range of one number in a scenario or cell file (values that switched supervision off, or
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

/**
 * Where a reader's values stand and where its message goes: the scenario and the cell readers check the
 * keys they share through the functions below, so that a value has one range, one check and one message
 * ("FILE:LINE: FIELD: reason", LINE that of FIELD's node, or of its nearest enclosing node when absent).
 */
typedef struct mca_check_ctx {
    const char *file;              /**< the file, first in every message */
    const mca_yaml_marks_t *marks; /**< its nodes' lines (empty: every line is 0) */
    char *err;                     /**< the caller's message buffer (may be NULL) */
    size_t errlen;
} mca_check_ctx_t;

/**
 * Range check of v, the value of the printf-formatted field ("arms[1].base_xyz[2]").
 * @retval MCA_OK
 * @retval MCA_ECONFIG  "FILE:LINE: FIELD: must be in [LO, HI] UNIT (got V)" in c->err
 */
__attribute__((format(printf, 4, 5))) int mca_check_range(const mca_check_ctx_t *c, const mca_range_t *r,
                                                          double v, const char *fmt, ...);

/**
 * "FILE:LINE: message" in c->err, LINE that of node (a path as in mca_yaml_marks_line_or_parent()).
 * @return rc, for `return mca_check_fail(...)`
 */
__attribute__((format(printf, 4, 5))) int mca_check_fail(const mca_check_ctx_t *c, int rc, const char *node,
                                                         const char *fmt, ...);

/** The scheme's gains and form as a file gives them (NULL where it does not): a scenario's top level, a
 * cell's `solver:` section; both read them with MCA_YAML_GAIN_FIELDS (mca/yaml_load.h). */
typedef struct mca_gain_keys {
    double *K, *epsilon, *v_normal, *v_floor;
    mca_collision_form_t *form;
} mca_gain_keys_t;

/** The scheme parameters as a file gives them; NULL where it does not (the value in place stays). */
typedef struct mca_param_keys {
    const char *solver; /**< where K, epsilon, v_normal, v_floor and form stand: "" or "solver." */
    const double *d1, *d2;
    const mca_gain_keys_t *gain; /**< NULL: no gains given */
} mca_param_keys_t;

/**
 * Check and set the given parameters (ranges of mca_scenario_range(), then 0 <= d1 < d2); *has_form = 1 when
 * the form is given. The one check of d1, d2, K, epsilon, v_normal, v_floor for scenario and cell files.
 * @retval MCA_OK, MCA_ECONFIG (c->err names the field; p may be partly set)
 */
int mca_scenario_params_apply(const mca_check_ctx_t *c, const mca_param_keys_t *k, mca_scenario_params_t *p,
                              int *has_form);

/** A path as a file gives it (NULL where it does not): what libcyaml reads for a path: mapping of scenario
 *  and cell files alike (the schema: mca_scenario_path_fields, mca/yaml_load.h). */
typedef struct mca_path_keys {
    mca_path_kind_t kind;
    bool *relative; /**< waypoints only (hold and circle are relative) */
    double *t0, *radius, *period, *turns;
    double *u;
    unsigned u_count;
    double *v;
    unsigned v_count;
    double (*points)[3];
    unsigned points_count;
    double *durations;
    unsigned durations_count;
    double *tolerance;  /**< the path tube [m] (MCA_PATH_DEFAULT_TOL) */
    double *tolerances; /**< waypoints: one per point, the segment that ends there (over tolerance) */
    unsigned tolerances_count;
    int *exact; /**< waypoints: indices into points of the exact ones (grasp, release) */
    unsigned exact_count;
    double *exact_tolerance; /**< [m] (MCA_PATH_DEFAULT_EXACT_TOL) */
    int tracking;            /**< mca_path_tracking_key_t: 0 when the file does not say */
} mca_path_keys_t;

/** A path's `tracking` key: how mca-ts keeps it (docs/scheme.md sections 10 and 11). */
typedef enum mca_path_tracking_key {
    MCA_PATH_TRACKING_DEFAULT = 0,    /**< key absent: path first (hold and stream paths: elastic) */
    MCA_PATH_TRACKING_PATH_FIRST = 1, /**< the path first, within its tube (tolerance, default 0) */
    MCA_PATH_TRACKING_ELASTIC = 2,    /**< the L2 slack of before: passes by leaving the path */
} mca_path_tracking_key_t;

/** A path's tube when the file gives no tolerance [m]: it waits rather than leave it. Circle and waypoint
 *  paths are kept path first unless the file says `tracking: elastic` (mca_path_t.path_first 0). */
#define MCA_PATH_DEFAULT_TOL 0.0
/** How near an exact waypoint the tool tip must be [m]. */
#define MCA_PATH_DEFAULT_EXACT_TOL 0.001

/** One arm's model as a file gives it (NULL where it does not): every arm of a scenario, and a cell's arm
 * over its scenario's; both read it with MCA_YAML_ARM_FIELDS (mca/yaml_load.h). */
typedef struct mca_arm_keys {
    char *name;
    char *urdf;
    char *tip_link;
    double *base_xyz;
    unsigned base_xyz_count;
    double *base_rpy;
    unsigned base_rpy_count;
    double *q0;
    unsigned q0_count;
    mca_path_keys_t *path;
} mca_arm_keys_t;

/**
 * Check and set what k gives of arm `arm` over *sa: the one check of an arm for scenario and cell files. The
 * urdf is resolved against c->file (mca_config_resolve()) and must be readable; base_xyz and base_rpy in
 * their ranges; q0 copied (its count is checked against the URDF later); a path: hold and circle are relative
 * to the start, a circle needs radius, period, u and v (u not zero, v not parallel to u; made orthonormal),
 * waypoints need points (at most MCA_PATH_MAX_POINTS - 1) and one duration per point; every number in its
 * range. The name is the caller's (a cell matches it to its scenario's arms).
 * @retval MCA_OK, MCA_ENOENT (urdf not found), MCA_ECONFIG (c->err names the field; *sa may be partly set)
 */
int mca_scenario_arm_apply(const mca_check_ctx_t *c, int arm, const mca_arm_keys_t *k,
                           mca_scenario_arm_t *sa);

/**
 * Check an arm's model against its start: load its URDF (to tip_link) into sa->chain unless it is loaded
 * already, then q0 has one value per joint and each within the joint's limits. The one model check of
 * scenario and cell files (both call it at load, the cell after its overrides, which reload the URDF only
 * when they name another urdf or tip_link).
 * @retval MCA_OK, the URDF's error ("FILE:LINE: arms[A].urdf: the URDF's reason"), MCA_ECONFIG
 *         ("FILE:LINE: arms[A].q0: 7 values but X.urdf has 8 joints (DOF mismatch)", "arms[A].q0[J]: V
 *         outside joint 'NAME' limits [LO, HI]")
 */
int mca_scenario_arm_model(const mca_check_ctx_t *c, int arm, mca_scenario_arm_t *sa);

/**
 * mca_config_resolve() `rel` against c->file into out, and require it readable.
 * @retval MCA_OK
 * @retval MCA_ENOENT  "FILE:LINE: FIELD: file 'OUT' not found (nor in the search path P)" in c->err, LINE
 * that of the node `field`
 */
int mca_config_find(const mca_check_ctx_t *c, const char *field, const char *rel, char *out, size_t outlen);

/** The data search path after a file's own folder: $MCA_PATH (':'-separated), else the running program's
 *  prefix's etc/mca and share/mca (mca/prefix.h: PREFIX/sbin/mcad -> PREFIX/etc/mca:PREFIX/share/mca,
 * /etc/mca for the prefix /usr), then the build's (the configured prefix's etc/mca and share/mca, /etc/mca,
 *  /usr/share/mca), each folder once. Start-up only (the first call reads /proc/self/exe). */
const char *mca_config_search_path(void);

/**
 * Resolve `rel`, a path written in the file `base_file`: absolute as it stands; else against base_file's own
 * folder (made absolute); when nothing is there, against each folder of mca_config_search_path() with the
 * leading "../" and "./" dropped ("../robots/x.urdf" -> /usr/share/mca/robots/x.urdf), so that a copied cell
 * or scenario still finds the shipped files. out is the file-relative path when no candidate exists (the
 * error names it).
 */
void mca_config_resolve(char *out, size_t outlen, const char *base_file, const char *rel);

/** One fixed body as a file gives it (NULL where it does not): the `bodies:` entries of scenario and cell
 *  files alike (the schema: mca_scenario_body_fields, mca/yaml_load.h). */
typedef struct mca_body_keys {
    char *name;
    int kind; /**< mca_body_kind_t */
    double *clearance;
    char **allow;
    unsigned allow_count;
    double *point, *normal, *centre, *a, *b, *half_extents, *rpy, *axis; /**< 3 values each */
    unsigned point_count, normal_count, centre_count, a_count, b_count, half_extents_count, rpy_count,
        axis_count;
    double *radius, *half_length;
} mca_body_keys_t;

/**
 * Check and add the bodies a file gives (k[0..count), at node "bodies") to scn: each kind's keys and no other
 * (plane: point, normal; sphere: centre, radius; capsule: a, b, radius; box: centre, half_extents, rpy
 * (optional); cylinder: centre, axis (optional, default z), half_length, radius), every number in its range,
 * normals and axes not zero, clearance in [0, 1] m; the allow list: "ARM" (every link), "ARM.base" (link 0),
 * "ARM.tool" (its last link) or "ARM.N" (link N), ARM one of scn's arms (their models loaded). A body named
 * as one scn has already replaces it (a cell over its scenario's); more than MCA_MAX_BODIES is an error.
 * The one check of bodies for scenario and cell files.
 * @retval MCA_OK, MCA_ECONFIG (c->err: "FILE:LINE: bodies[I].FIELD: reason"; scn may be partly changed)
 */
int mca_scenario_bodies_apply(const mca_check_ctx_t *c, const mca_body_keys_t *k, unsigned count,
                              mca_scenario_t *scn);

/**
 * Apply the self pairs a file gives (k[0..count), at node "self_pairs", after the arms: their models loaded),
 * in order: "ARM" adds the arm's default list (the file beside its URDF, ROBOT.self.yaml, made by
 * tools/selfpairs), "ARM.L-M" adds the pair of links L and M (numbers, base, tool; not adjacent), a leading
 * '-' takes them out ("-ARM" every pair of the arm). A cell's entries apply after its scenario's. The one
 * check of self pairs for scenario and cell files.
 * @retval MCA_OK, MCA_ECONFIG (c->err: "FILE:LINE: self_pairs[I]: reason", or the list file's own
 *         "FILE:LINE: pairs[I]: reason")
 */
int mca_scenario_self_apply(const mca_check_ctx_t *c, char *const *k, unsigned count, mca_scenario_t *scn);

/**
 * The controller's bodies from a scenario's: clearance (d1 where not given) and each allow entry resolved to
 * link bits of the arm of that name in scn's order.
 * @retval MCA_OK, MCA_ECONFIG (err: an allow entry names no arm of scn, or a link it does not have: a cell
 *         that changed an arm's model)
 */
int mca_scenario_bodies_resolve(const mca_scenario_t *scn, mca_fixed_body_t out[MCA_MAX_BODIES], char *err,
                                size_t errlen);

/** Defaults: the scheme's (mca_scheme_default_params: d1 0.05, d2 0.12, K 20, epsilon 5, normal form,
 *  v_normal 0.5, v_floor 0) and dt MCA_CONTROLLER_DT (0.001). */
void mca_scenario_defaults(mca_scenario_t *scn);

/**
 * Parse a scenario YAML file (start-up only; allocates inside libcyaml and frees before returning).
 * @param[out] scn  filled on success (unchanged on error)
 * @param[out] err  message naming the file, the line when known, and the field at fault
 * @retval MCA_OK, MCA_ENOENT (file missing), MCA_EPARSE (bad YAML, unknown/missing field, empty or
 *         comment-only file: "FILE:0: (document): empty document ..."),
 *         MCA_ERANGE (value out of range: too many arms/points, d1 >= d2, non-positive duration, ...)
 */
int mca_scenario_load(const char *path, mca_scenario_t *scn, char *err, size_t errlen);

/**
 * Fill a config from a loaded scenario: loads each arm's URDF (start-up only), sets base placements,
 * copies paths and the scenario's parameters.
 * @retval MCA_OK, MCA_ENOENT/MCA_EPARSE/MCA_ERANGE from the URDF (err names the file), MCA_EINVAL
 *         (q0 count differs from the chain's dof)
 */
int mca_controller_config_from_scenario(mca_controller_config_t *cfg, const mca_scenario_t *scn,
                                        mca_scheme_kind_t scheme, char *err, size_t errlen);

#ifdef __cplusplus
}
#endif
#endif
