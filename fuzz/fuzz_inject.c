/* SPDX-License-Identifier: MIT */
/* Fuzz target: the fault-injection text (mca_sim_inject_parse: "KIND@CYCLE[+CYCLES][:JOINT]", taken by
 * mca-armsim --inject, mca-simarm-trace and the tests). First byte: the joint count (0..9, so 0 and
 * MCA_MAX_DOF + 1 are tried too); the rest: the text, NUL-terminated here. A parsed injection must obey
 * the syntax's promises. */
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h> /* abort, malloc, free */
#include <string.h>

#include "mca/err.h"
#include "mca/sim_arm.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    if (size < 1) {
        return 0;
    }
    const int n = data[0] % (MCA_MAX_DOF + 2);
    char *text = malloc(size); /* size - 1 characters + NUL: ASan sees any read past the end */
    if (!text) {
        return 0;
    }
    memcpy(text, data + 1, size - 1);
    text[size - 1] = '\0';
    mca_sim_inject_t in;
    if (mca_sim_inject_parse(text, n, &in) == MCA_OK) {
        if (in.kind < MCA_SIM_INJ_ACTUATOR || in.kind > MCA_SIM_INJ_DROP_RX) {
            abort();
        }
        if (in.kind == MCA_SIM_INJ_ACTUATOR && (in.joint < 0 || in.joint >= n)) {
            abort();
        }
        (void)mca_sim_inject_kind_name(in.kind);
    }
    free(text);
    return 0;
}
