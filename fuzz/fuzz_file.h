/* SPDX-License-Identifier: MIT */
/* Fuzz helper: the parsers under test read files, so each input is written to a file in a private
 * directory made once per process (mkdtemp under $TMPDIR), laid out like config/ so that relative paths
 * in the input ("../scenarios/x.yaml", "../robots/jaco2.urdf", "../dds/loopback.xml") reach the real
 * files of the source tree (MCA_FUZZ_CONFIG_DIR): cells/ and scenarios/ hold the input, robots/ and dds/
 * are symbolic links. */
#ifndef MCA_FUZZ_FILE_H
#define MCA_FUZZ_FILE_H

#include <stddef.h>
#include <stdint.h>
#include <stdio.h>  /* fopen, fwrite, snprintf */
#include <stdlib.h> /* getenv, mkdtemp, abort */
#include <string.h>
#include <sys/stat.h> /* mkdir */
#include <unistd.h>   /* symlink */

#ifndef MCA_FUZZ_CONFIG_DIR
#error "MCA_FUZZ_CONFIG_DIR must name the config directory of the source tree"
#endif

static char fuzz_dir[512];

/* atexit: remove what fuzz_dir_init() and fuzz_write() made (the links, the inputs, the directories). */
static void fuzz_dir_cleanup(void) {
    static const char *const names[] = {"robots",
                                        "dds",
                                        "scenarios-src",
                                        "cells/in.yaml",
                                        "scenarios/in.yaml",
                                        "robots-in.urdf",
                                        "scenarios/cross_circles.yaml",
                                        "scenarios/hui.yaml",
                                        "scenarios/cup_stacking.yaml",
                                        "scenarios/negative.yaml",
                                        "scenarios/three_arms.yaml"};
    char p[700];
    for (size_t i = 0; i < sizeof names / sizeof names[0]; i++) {
        snprintf(p, sizeof p, "%s/%s", fuzz_dir, names[i]);
        unlink(p);
    }
    snprintf(p, sizeof p, "%s/cells", fuzz_dir);
    rmdir(p);
    snprintf(p, sizeof p, "%s/scenarios", fuzz_dir);
    rmdir(p);
    rmdir(fuzz_dir);
}

static void fuzz_dir_init(void) {
    if (fuzz_dir[0]) {
        return;
    }
    const char *tmp = getenv("TMPDIR");
    snprintf(fuzz_dir, sizeof fuzz_dir, "%s/mca-fuzz-XXXXXX", tmp && *tmp ? tmp : "/tmp");
    if (!mkdtemp(fuzz_dir)) {
        abort();
    }
    atexit(fuzz_dir_cleanup);
    static const char *const links[] = {"robots", "dds", "scenarios-src"};
    static const char *const targets[] = {"robots", "dds", "scenarios"};
    char a[600], b[600];
    for (int i = 0; i < 3; i++) {
        snprintf(a, sizeof a, "%s/%s", MCA_FUZZ_CONFIG_DIR, targets[i]);
        snprintf(b, sizeof b, "%s/%s", fuzz_dir, links[i]);
        if (symlink(a, b) != 0) {
            abort();
        }
    }
    snprintf(b, sizeof b, "%s/cells", fuzz_dir);
    mkdir(b, 0700);
    snprintf(b, sizeof b, "%s/scenarios", fuzz_dir);
    mkdir(b, 0700);
    /* the shipped scenarios, so that a cell's "../scenarios/NAME.yaml" loads */
    static const char *const scn[] = {"cross_circles", "hui", "cup_stacking", "negative", "three_arms"};
    for (size_t i = 0; i < sizeof scn / sizeof scn[0]; i++) {
        snprintf(a, sizeof a, "%s/scenarios/%s.yaml", MCA_FUZZ_CONFIG_DIR, scn[i]);
        snprintf(b, sizeof b, "%s/scenarios/%s.yaml", fuzz_dir, scn[i]);
        if (symlink(a, b) != 0) {
            abort();
        }
    }
}

/* Write data to SUBDIR/NAME inside the private directory; @return the path (static storage). */
static const char *fuzz_write(const char *subdir, const char *name, const uint8_t *data, size_t size) {
    static char path[700];
    fuzz_dir_init();
    if (subdir && *subdir) {
        snprintf(path, sizeof path, "%s/%s/%s", fuzz_dir, subdir, name);
    } else {
        snprintf(path, sizeof path, "%s/%s", fuzz_dir, name);
    }
    FILE *f = fopen(path, "wb");
    if (!f) {
        abort();
    }
    if (size && fwrite(data, 1, size, f) != size) {
        abort();
    }
    fclose(f);
    return path;
}

#endif
