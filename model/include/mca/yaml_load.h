/* SPDX-License-Identifier: MIT */
/** @file mca/yaml_load.h
 * Loading a YAML file against a libcyaml schema (mca_model, start-up only): the one loader of scenario and
 * cell files, so that both name a syntax, type, unknown-key or missing-key error the same way:
 * "FILE:LINE:COL: FIELD: what (libcyaml's reason)" (FIELD the path, "arms[1].path.radius"; LINE:COL of the
 * node libcyaml was reading, or the unknown key's own line).
 */
#ifndef MCA_YAML_LOAD_H
#define MCA_YAML_LOAD_H

#include <cyaml/cyaml.h>
#include <stddef.h>

#include "mca/limits.h"
#include "mca/yaml_marks.h"

#ifdef __cplusplus
extern "C" {
#endif

/** Deepest nesting of mappings and sequences a cell or scenario file may have (they need 5 or 6): a deeper
 *  file is refused before libcyaml reads it, since libyaml's scanner costs the depth per token (a 25 kB
 *  file of "[[[[..." took 0.6 s). */
#define MCA_YAML_MAX_DEPTH 32

/**
 * Load the file at `path` into *data (allocated by libcyaml; mca_yaml_free) and the line of each of its nodes
 * into *marks (mca/yaml_marks.h; for the caller's own messages: lines are 0 if the file cannot be read
 * again).
 * @param[in] what  the kind of file, for "FILE:0: cannot open WHAT file: reason"
 * @param[out] data   the loaded document (NULL on error)
 * @param[out] marks  the lines (emptied on error; mca_yaml_marks_free after success)
 * @retval MCA_OK, MCA_ENOENT (cannot open), MCA_EPARSE (not YAML, not the schema, nested deeper than
 *         MCA_YAML_MAX_DEPTH: "FILE:LINE: nested deeper than 32 levels", or no document at all: "FILE:0:
 *         (document): empty document (...)" for an empty or comment-only file)
 */
int mca_yaml_load(const char *path, const char *what, const cyaml_schema_value_t *schema, void **data,
                  mca_yaml_marks_t *marks, char *err, size_t errlen);

/** Free what mca_yaml_load loaded (NULL allowed). */
void mca_yaml_free(const cyaml_schema_value_t *schema, void *data);

/* ---- the keys scenario and cell files share: each written once, here, for both schemas ---- */

/** An optional key (a pointer member, NULL when absent). */
#define MCA_YAML_OPT (CYAML_FLAG_OPTIONAL | CYAML_FLAG_POINTER)

/** Entries of number sequences; the collision forms' names ("componentwise", "normal"). */
extern const cyaml_schema_value_t mca_yaml_float_entry;
extern const cyaml_strval_t mca_yaml_form_strings[2];

/** The schema of a path: mapping (into mca_path_keys_t, mca/scenario.h). */
extern const cyaml_schema_field_t mca_scenario_path_fields[];

/** The schema of one fixed body (a `bodies:` entry, into mca_body_keys_t, mca/scenario.h). */
extern const cyaml_schema_value_t mca_scenario_body_entry;

/** libcyaml field of the fixed bodies (mca_body_keys_t *M with unsigned M##_count in struct T), optional at
 * the top level of both kinds of file. */
#define MCA_YAML_BODIES_FIELD(T, M)                                                                          \
    CYAML_FIELD_SEQUENCE("bodies", MCA_YAML_OPT, T, M, &mca_scenario_body_entry, 0, MCA_MAX_BODIES)

/** The self pairs' entries ("ARM", "ARM.L-M", "-ARM", "-ARM.L-M"; mca_scenario_self_apply). */
extern const cyaml_schema_value_t mca_scenario_self_entry;

/** libcyaml field of the self pairs (char **M with unsigned M##_count in struct T), optional at the top level
 * of both kinds of file. */
#define MCA_YAML_SELF_FIELD(T, M)                                                                            \
    CYAML_FIELD_SEQUENCE("self_pairs", MCA_YAML_OPT | CYAML_FLAG_FLOW, T, M, &mca_scenario_self_entry, 0,    \
                         4 * MCA_MAX_LINKS * MCA_MAX_LINKS)

/**
 * libcyaml fields of an arm's model (mca_arm_keys_t M, a member of struct T): name, urdf, tip_link,
 * base_xyz, base_rpy, q0, path. NEED: the flags of urdf, base_xyz, q0 and path, which a scenario must give
 * (CYAML_FLAG_POINTER) and a cell may take from its scenario (MCA_YAML_OPT).
 */
#define MCA_YAML_ARM_FIELDS(T, M, NEED)                                                                      \
    CYAML_FIELD_STRING_PTR("name", CYAML_FLAG_POINTER, T, M.name, 1, 31),                                    \
        CYAML_FIELD_STRING_PTR("urdf", (NEED), T, M.urdf, 1, 400),                                           \
        CYAML_FIELD_STRING_PTR("tip_link", MCA_YAML_OPT, T, M.tip_link, 0, 63),                              \
        CYAML_FIELD_SEQUENCE("base_xyz", (NEED) | CYAML_FLAG_FLOW, T, M.base_xyz, &mca_yaml_float_entry, 3,  \
                             3),                                                                             \
        CYAML_FIELD_SEQUENCE("base_rpy", MCA_YAML_OPT | CYAML_FLAG_FLOW, T, M.base_rpy,                      \
                             &mca_yaml_float_entry, 3, 3),                                                   \
        CYAML_FIELD_SEQUENCE("q0", (NEED) | CYAML_FLAG_FLOW, T, M.q0, &mca_yaml_float_entry, 1,              \
                             MCA_MAX_DOF),                                                                   \
        CYAML_FIELD_MAPPING_PTR("path", (NEED), T, M.path, mca_scenario_path_fields)

/** libcyaml fields of the distance thresholds d1, d2 (double pointers of struct T, at the top level of both
 *  kinds of file). */
#define MCA_YAML_THRESHOLD_FIELDS(T)                                                                         \
    CYAML_FIELD_FLOAT_PTR("d1", MCA_YAML_OPT, T, d1), CYAML_FIELD_FLOAT_PTR("d2", MCA_YAML_OPT, T, d2)

/** libcyaml fields of the scheme's gains (mca_gain_keys_t M, a member of struct T): K, epsilon, v_normal,
 *  v_floor, form. */
#define MCA_YAML_GAIN_FIELDS(T, M)                                                                           \
    CYAML_FIELD_FLOAT_PTR("K", MCA_YAML_OPT, T, M.K),                                                        \
        CYAML_FIELD_FLOAT_PTR("epsilon", MCA_YAML_OPT, T, M.epsilon),                                        \
        CYAML_FIELD_FLOAT_PTR("v_normal", MCA_YAML_OPT, T, M.v_normal),                                      \
        CYAML_FIELD_FLOAT_PTR("v_floor", MCA_YAML_OPT, T, M.v_floor),                                        \
        CYAML_FIELD_ENUM_PTR("form", MCA_YAML_OPT, T, M.form, mca_yaml_form_strings,                         \
                             CYAML_ARRAY_LEN(mca_yaml_form_strings))

#ifdef __cplusplus
}
#endif
#endif
