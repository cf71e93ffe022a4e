/* SPDX-License-Identifier: MIT */
/* Fuzz target: URDF loading (mca_chain_load_urdf: the depth scan, TinyXML, urdfdom, the chain build).
 * The input is the URDF file; the tip link is the one the shipped robots use ("tool_tip"), then the
 * default (NULL: the last link of the chain). */
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h> /* abort */

#include "fuzz_file.h"
#include "mca/chain.h"
#include "mca/err.h"
#include "mca/urdf.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    static mca_chain_t chain;
    char err[512];
    const char *path = fuzz_write(NULL, "robots-in.urdf", data, size);
    err[0] = '\0';
    int rc = mca_chain_load_urdf(&chain, path, "tool_tip", err, sizeof err);
    if (rc != MCA_OK && err[0] == '\0') {
        abort(); /* every refusal names its reason */
    }
    if (rc != MCA_OK) {
        mca_chain_load_urdf(&chain, path, NULL, err, sizeof err);
    }
    return 0;
}
