/* SPDX-License-Identifier: MIT */
/* Fuzz target: cell YAML (mca_cell_load, then mca_cell_controller_config as `mcad --check` does). The
 * input is the cell file; its relative paths reach the shipped scenarios, robots and DDS configs. */
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h> /* abort */
#include <string.h>

#include "fuzz_file.h"
#include "mca/cell.h"
#include "mca/controller.h"
#include "mca/err.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    static mca_cell_t cell;             /* large: kept off the stack */
    static mca_controller_config_t cfg; /* ditto */
    char err[512];
    const char *path = fuzz_write("cells", "in.yaml", data, size);
    err[0] = '\0';
    int rc = mca_cell_load(path, &cell, err, sizeof err);
    if (rc != MCA_OK && err[0] == '\0') {
        abort(); /* every refusal names its reason */
    }
    if (rc == MCA_OK) {
        mca_cell_controller_config(&cell, &cfg, err, sizeof err);
    }
    return 0;
}
