/* SPDX-License-Identifier: MIT */
/* Fuzz target: scenario YAML (mca_scenario_load). The input is the scenario file; its relative URDF paths
 * ("../robots/jaco2.urdf") reach the shipped robots. The same bytes also go to the node locator
 * (mca_yaml_marks_parse), which mca_scenario_load only reaches for files libcyaml accepted. */
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h> /* abort */
#include <string.h>

#include "fuzz_file.h"
#include "mca/err.h"
#include "mca/scenario.h"
#include "mca/yaml_marks.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    static mca_scenario_t scn; /* large: kept off the stack */
    char err[512];
    const char *path = fuzz_write("scenarios", "in.yaml", data, size);
    err[0] = '\0';
    int rc = mca_scenario_load(path, &scn, err, sizeof err);
    if (rc != MCA_OK && err[0] == '\0') {
        abort(); /* every refusal names its reason */
    }
    mca_yaml_marks_t marks;
    err[0] = '\0';
    rc = mca_yaml_marks_parse((const char *)data, size, &marks, err, sizeof err);
    if (rc != MCA_OK && (err[0] == '\0' || marks.mark || marks.n)) {
        abort();
    }
    for (size_t i = 0; i < marks.n; i++) {
        if (marks.mark[i].line < 1 ||
            strnlen(marks.mark[i].path, MCA_YAML_MARKS_PATH_MAX) >= MCA_YAML_MARKS_PATH_MAX ||
            (i < 256 && mca_yaml_marks_line(&marks, marks.mark[i].path) < 1)) {
            abort();
        }
    }
    (void)mca_yaml_marks_line_or_parent(&marks, "arms[1].path.points[3][2]");
    mca_yaml_marks_free(&marks);
    return 0;
}
