/* SPDX-License-Identifier: MIT */
/* Fuzz target: scenario YAML (mca_scenario_load). The input is the scenario file; its relative URDF paths
 * ("../robots/jaco2.urdf") reach the shipped robots. */
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h> /* abort */

#include "fuzz_file.h"
#include "mca/err.h"
#include "mca/scenario.h"

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
    return 0;
}
