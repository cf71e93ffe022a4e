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

#ifdef __cplusplus
extern "C" {
#endif

/** Deepest nesting of mappings and sequences a cell or scenario file may have (they need 5 or 6): a deeper
 *  file is refused before libcyaml reads it, since libyaml's scanner costs the depth per token (a 25 kB
 *  file of "[[[[..." took 0.6 s). */
#define MCA_YAML_MAX_DEPTH 32

/**
 * Load the file at `path` into *data (allocated by libcyaml; mca_yaml_free).
 * @param[in] what  the kind of file, for "FILE:0: cannot open WHAT file: reason"
 * @param[out] data  the loaded document, or NULL for a file without one (empty or only comments: the caller
 *                   says so in its own words)
 * @retval MCA_OK, MCA_ENOENT (cannot open), MCA_EPARSE (not YAML, not the schema, or nested deeper than
 *         MCA_YAML_MAX_DEPTH: "FILE:LINE: nested deeper than 32 levels")
 */
int mca_yaml_load(const char *path, const char *what, const cyaml_schema_value_t *schema, void **data,
                  char *err, size_t errlen);

/** Free what mca_yaml_load loaded (NULL allowed). */
void mca_yaml_free(const cyaml_schema_value_t *schema, void *data);

/** The schema of a path: mapping (into mca_path_keys_t, mca/scenario.h), one for scenario files and
 *  for a cell arm's inline path. */
extern const cyaml_schema_field_t mca_scenario_path_fields[];

#ifdef __cplusplus
}
#endif
#endif
