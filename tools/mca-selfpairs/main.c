/* SPDX-License-Identifier: MIT */
/* mca-selfpairs: the default self pairs of a robot (docs/scheme.md, "Self pairs"), in the manner of MoveIt's
 * SRDF disabled pairs: sample the joint space uniformly within the joint limits with the project's own
 * kinematics (mca_fk, the links as the controller's capsules) and keep each pair of links that is neither
 * adjacent, nor apart by more than the margin in every sample (never near), nor below d1 in every sample (a
 * pair joined by the build, such as links on both sides of a zero-length link: always in contact, nothing
 * to keep), nor rigid (its distance varies by less than 1 mm over the samples: no joint moves it). With
 * --emit it writes the list file shipped beside the URDF; without, a table per pair.
 * --near D prints the samples where a kept pair is below D (for finding a path that folds the arm). */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "mca/body.h"
#include "mca/chain.h"
#include "mca/err.h"
#include "mca/urdf.h"

/* A pair whose distance varies less than this over the samples is rigid [m]. */
#define RIGID_M 1e-3

static uint64_t rng_state = 1;

static double uniform(void) { /* splitmix64: the same samples on every machine for one seed */
    uint64_t z = (rng_state += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    z ^= z >> 31;
    return (double)(z >> 11) * 0x1.0p-53;
}

static double pair_distance(const mca_chain_t *ch, const mca_kin_t *k, int l, int q) {
    const mca_capsule_t a = {{k->point[l][0], k->point[l][1], k->point[l][2]},
                             {k->point[l + 1][0], k->point[l + 1][1], k->point[l + 1][2]},
                             ch->link_radius[l]};
    const mca_body_t b = {.kind = MCA_BODY_CAPSULE,
                          .u.capsule = {{k->point[q][0], k->point[q][1], k->point[q][2]},
                                        {k->point[q + 1][0], k->point[q + 1][1], k->point[q + 1][2]},
                                        ch->link_radius[q]}};
    mca_body_dist_t r;
    return mca_capsule_body_distance(&a, &b, &r) == MCA_OK ? r.d : NAN;
}

static void usage(void) {
    fprintf(stderr, "usage: mca-selfpairs --urdf FILE [--tip LINK] [--samples N] [--seed S] [--margin M] "
                    "[--d1 D] [--emit] [--near D]\n");
}

int main(int argc, char **argv) {
    const char *urdf = NULL, *tip = NULL;
    long samples = 200000;
    unsigned long long seed = 1;
    double margin = 0.12, d1 = 0.05, near = -1.0;
    int emit = 0;
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i], *v = i + 1 < argc ? argv[i + 1] : NULL;
        if (!strcmp(a, "--emit")) {
            emit = 1;
            continue;
        }
        if (!v) {
            usage();
            return 2;
        }
        i++;
        if (!strcmp(a, "--urdf")) {
            urdf = v;
        } else if (!strcmp(a, "--tip")) {
            tip = v;
        } else if (!strcmp(a, "--samples")) {
            samples = strtol(v, NULL, 10);
        } else if (!strcmp(a, "--seed")) {
            seed = strtoull(v, NULL, 10);
        } else if (!strcmp(a, "--margin")) {
            margin = strtod(v, NULL);
        } else if (!strcmp(a, "--d1")) {
            d1 = strtod(v, NULL);
        } else if (!strcmp(a, "--near")) {
            near = strtod(v, NULL);
        } else {
            usage();
            return 2;
        }
    }
    if (!urdf || samples < 1 || !(margin > 0.0) || !(d1 >= 0.0)) {
        usage();
        return 2;
    }
    mca_chain_t ch;
    char err[512];
    if (mca_chain_load_urdf(&ch, urdf, tip, err, sizeof err) != MCA_OK) {
        fprintf(stderr, "mca-selfpairs: %s\n", err);
        return 2;
    }
    rng_state = seed;
    const int nl = ch.dof + 1;
    double dmin[MCA_MAX_LINKS][MCA_MAX_LINKS], dmax[MCA_MAX_LINKS][MCA_MAX_LINKS];
    long below[MCA_MAX_LINKS][MCA_MAX_LINKS];
    for (int l = 0; l < nl; l++) {
        for (int q = 0; q < nl; q++) {
            dmin[l][q] = INFINITY;
            dmax[l][q] = -INFINITY;
            below[l][q] = 0;
        }
    }
    for (long s = 0; s < samples; s++) {
        double qv[MCA_MAX_DOF];
        for (int j = 0; j < ch.dof; j++) {
            const double lo = ch.joint[j].continuous ? -M_PI : ch.joint[j].lower;
            const double hi = ch.joint[j].continuous ? M_PI : ch.joint[j].upper;
            qv[j] = lo + (hi - lo) * uniform();
        }
        mca_kin_t k;
        if (mca_fk(&ch, qv, &k) != MCA_OK) {
            fprintf(stderr, "mca-selfpairs: forward kinematics failed\n");
            return 2;
        }
        for (int l = 2; l < nl; l++) {
            for (int q = 0; q + 1 < l; q++) {
                const double d = pair_distance(&ch, &k, l, q);
                dmin[l][q] = fmin(dmin[l][q], d);
                dmax[l][q] = fmax(dmax[l][q], d);
                below[l][q] += d < d1;
                if (near >= 0.0 && d < near) {
                    printf("near %d %d %.4f q", l, q, d);
                    for (int j = 0; j < ch.dof; j++) {
                        printf(" %.4f", qv[j]);
                    }
                    printf(" ee %.4f %.4f %.4f\n", k.ee[0], k.ee[1], k.ee[2]);
                }
            }
        }
    }
    if (near >= 0.0) {
        return 0;
    }
    if (emit) {
        printf(
            "# Self pairs of %s (links 0..%d: base .. tool; mca/bodyrows.h, docs/scheme.md \"Self pairs\"):\n"
            "# the pairs of links that are not adjacent, come within %.3f m of each other somewhere in the "
            "joint\n"
            "# space, are not below d1 = %.3f m everywhere (joined by the build) and not rigid, from %ld "
            "uniform samples\n"
            "# of the joint limits (seed %llu). A scenario or cell turns them on with `self_pairs: [ARM]`.\n"
            "# Generated by: build/tools/mca-selfpairs/mca-selfpairs --urdf %s%s%s --samples %ld --seed %llu "
            "--margin %g --d1 %g --emit\n",
            ch.name, ch.dof, margin, d1, samples, seed, urdf, tip ? " --tip " : "", tip ? tip : "", samples,
            seed, margin, d1);
        printf("robot: %s\nmargin: %g\npairs:\n", ch.name, margin);
    } else {
        printf("pair  min_d   max_d   below_d1  verdict\n");
    }
    for (int l = 2; l < nl; l++) {
        for (int q = 0; q + 1 < l; q++) {
            const char *verdict = dmin[l][q] >= margin                ? "never near"
                                  : below[l][q] == samples            ? "always in contact"
                                  : dmax[l][q] - dmin[l][q] < RIGID_M ? "rigid"
                                                                      : "kept";
            if (emit) {
                if (verdict[0] == 'k') {
                    printf("  - [%d, %d]   # min %.3f m, below d1 in %.2f %% of samples\n", l, q, dmin[l][q],
                           100.0 * (double)below[l][q] / (double)samples);
                } else {
                    printf("  # [%d, %d] left out: %s (min %.3f m, max %.3f m)\n", l, q, verdict, dmin[l][q],
                           dmax[l][q]);
                }
            } else {
                printf("%d-%d  %.4f  %.4f  %.4f  %s\n", l, q, dmin[l][q], dmax[l][q],
                       (double)below[l][q] / (double)samples, verdict);
            }
        }
    }
    return 0;
}
