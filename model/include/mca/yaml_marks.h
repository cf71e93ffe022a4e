/* SPDX-License-Identifier: MIT */
/**
 * @file yaml_marks.h
 * @brief Where each node of a YAML file is: its path in the document and its line (start-up only).
 *
 * libcyaml keeps no positions once a file is loaded, so a value that parsed but is not allowed could not be
 * reported with its line. mca_yaml_marks_load() parses the file once more with libyaml (the parser libcyaml
 * uses) and records, for every mapping key and every sequence entry of the first document, its path and its
 * 1-based line (the line where the key or the entry starts):
 *
 *     d1: 0.05                 d1                       -> 1
 *     arms:                    arms                     -> 2
 *       - name: a              arms[0], arms[0].name    -> 3
 *         base_xyz: [0, 0, 1]  arms[0].base_xyz, arms[0].base_xyz[0..2] -> 4
 *         path:                arms[0].path             -> 5
 *           points:            arms[0].path.points      -> 6
 *             - [0, 0, 0]      arms[0].path.points[0], arms[0].path.points[0][0..2] -> 7
 *
 * Bounded for hostile input: paths longer than MCA_YAML_MARKS_PATH_MAX - 1 characters are not recorded (nor
 * is anything below them); nesting deeper than MCA_YAML_MARKS_MAX_DEPTH and more than MCA_YAML_MARKS_MAX
 * nodes are errors (reading stops there: libyaml's scanner costs the open depth per token). No global
 * state.
 */
#ifndef MCA_YAML_MARKS_H
#define MCA_YAML_MARKS_H

#include <stddef.h>

#ifdef __cplusplus
extern "C" {
#endif

#define MCA_YAML_MARKS_PATH_MAX 128 /**< path buffer, with its terminating NUL */
#define MCA_YAML_MARKS_MAX_DEPTH 64 /**< deepest nesting of mappings and sequences read */
#define MCA_YAML_MARKS_MAX 65536    /**< most nodes a file may have */

/** One recorded node: "arms[1].path.t0" at line 23. */
typedef struct {
    char path[MCA_YAML_MARKS_PATH_MAX];
    int line; /**< 1-based */
} mca_yaml_mark_t;

/** The marks of one file (malloc'ed; mca_yaml_marks_free). Zero-initialised: empty. */
typedef struct {
    mca_yaml_mark_t *mark;
    size_t n;
    size_t cap;
} mca_yaml_marks_t;

/**
 * Parse the YAML file at `path` and record its marks into `*marks` (any earlier content is replaced; on
 * error `*marks` is left empty). Returns MCA_OK, MCA_EINVAL (NULL argument), MCA_ENOENT (cannot open),
 * MCA_EPARSE (not YAML, or nested deeper than MCA_YAML_MARKS_MAX_DEPTH: the message names the line),
 * MCA_ERANGE (more than MCA_YAML_MARKS_MAX nodes) or MCA_ENOMEM; the message goes to err (may be NULL).
 */
int mca_yaml_marks_load(const char *path, mca_yaml_marks_t *marks, char *err, size_t errlen);

/** As mca_yaml_marks_load, from len bytes of YAML text in memory ("<string>" in messages). */
int mca_yaml_marks_parse(const char *text, size_t len, mca_yaml_marks_t *marks, char *err, size_t errlen);

/** Line of the node at `path` ("arms[1].path.t0", "d1", "arms[0].path.points[2]"); 0 when absent. */
int mca_yaml_marks_line(const mca_yaml_marks_t *marks, const char *path);

/**
 * Line of `path`, or when it is absent (a missing field) of the nearest enclosing path that is present:
 * "arms[1].path.radius", then "arms[1].path", "arms[1]", "arms". 0 when none is.
 */
int mca_yaml_marks_line_or_parent(const mca_yaml_marks_t *marks, const char *path);

/** mca_yaml_marks_line_or_parent of a printf-formatted path ("arms[%d].canopen.sync_us"): what the cell and
 *  scenario loaders call for the line of a field in error. */
__attribute__((format(printf, 2, 3))) int mca_yaml_marks_line_of(const mca_yaml_marks_t *marks,
                                                                 const char *fmt, ...);

/** Free the marks (the struct is left empty and can be loaded again). NULL is allowed. */
void mca_yaml_marks_free(mca_yaml_marks_t *marks);

#ifdef __cplusplus
}
#endif

#endif /* MCA_YAML_MARKS_H */
