/* SPDX-License-Identifier: MIT */
/* Real-time discipline: the distance functions must not allocate. Counts malloc/calloc/realloc calls by
 * interposing them (glibc __libc_* underneath), and documents which libccd entry points do allocate.
 * Under AddressSanitizer (it owns malloc) it exits 77, which ctest shows as skipped (a test must
 * not pass without having run); the normal build's run is the one that counts. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <ccd/ccd.h>

#include "mca/armdist.h"
#include "mca/body.h"
#include "mca/err.h"
#include "mca/obstacle.h"
#include "mca/segdist.h"

#if defined(__SANITIZE_ADDRESS__)
int main(void) {
    printf("SKIP: the allocation counter cannot run under AddressSanitizer (it replaces malloc)\n");
    return 77;
}
#else
extern void *__libc_malloc(size_t);
extern void *__libc_calloc(size_t, size_t);
extern void *__libc_realloc(void *, size_t);
static volatile long n_alloc;
void *malloc(size_t n) {
    n_alloc++;
    return __libc_malloc(n);
}
void *calloc(size_t a, size_t b) {
    n_alloc++;
    return __libc_calloc(a, b);
}
void *realloc(void *p, size_t n) {
    n_alloc++;
    return __libc_realloc(p, n);
}

typedef struct box {
    double h;
    double c[3];
} box_t;
static void box_support(const void *o, const ccd_vec3_t *d, ccd_vec3_t *v) {
    const box_t *b = o;
    for (int i = 0; i < 3; i++) {
        v->v[i] = b->c[i] + (d->v[i] >= 0 ? b->h : -b->h);
    }
}
static void box_center(const void *o, ccd_vec3_t *c) {
    const box_t *b = o;
    memcpy(c->v, b->c, sizeof b->c);
}

static int failures;
static void expect(int cond, const char *what) {
    printf("%s: %s\n", cond ? "ok  " : "FAIL", what);
    failures += !cond;
}

int main(void) {
    long before;
    /* --- mca functions --- */
    const double a[3] = {0, 0, 0}, b[3] = {1, 0, 0}, c[3] = {0.5, -1, 0.3}, d[3] = {0.5, 1, 0.3};
    mca_segdist_t r;
    before = n_alloc;
    mca_segdist_closed(a, b, c, d, &r);
    mca_segdist_lsdm(a, b, c, d, NULL, &r);
    mca_segdist_lsdm_certified(a, b, c, d, NULL, &r);
    expect(n_alloc == before, "mca_segdist_closed / lsdm / lsdm_certified allocate nothing");

    mca_chain_t ca, cb;
    mca_kin_t ka, kb;
    mca_arm_distances_t out;
    memset(&ca, 0, sizeof ca);
    memset(&ka, 0, sizeof ka);
    ca.dof = ka.dof = 3;
    ka.n_points = 5;
    for (int i = 0; i < 5; i++) {
        ka.point[i][2] = 0.3 * i;
    }
    cb = ca;
    kb = ka;
    for (int i = 0; i < 5; i++) {
        kb.point[i][0] = 0.5;
    }
    before = n_alloc;
    int rc1 = mca_arm_distances(&ca, &ka, &cb, &kb, MCA_DIST_CLOSED, &out);
    int rc2 = mca_arm_distances(&ca, &ka, &cb, &kb, MCA_DIST_LSDM, &out);
    expect(n_alloc == before && rc1 == MCA_OK && rc2 == MCA_OK, "mca_arm_distances allocates nothing");

    mca_pose_t pose;
    memset(&pose, 0, sizeof pose);
    pose.R[0][0] = pose.R[1][1] = pose.R[2][2] = 1.0;
    const double half[3] = {0.5, 0.5, 0.5};
    mca_obstacle_t box, cup;
    mca_obstacle_box(&box, "box", &pose, half);
    mca_obstacle_cylinder(&cup, "cup", &pose, 0.2, 0.4);
    mca_capsule_t sep = {{-1, 0, 1}, {1, 0, 1}, 0.1}, pen = {{-1, 0, 0.1}, {1, 0, 0.15}, 0.1};
    mca_obst_dist_t od;
    before = n_alloc;
    mca_capsule_obstacle_distance(&sep, &box, &od);
    mca_capsule_obstacle_distance(&pen, &box, &od);
    mca_capsule_obstacle_distance(&sep, &cup, &od);
    mca_capsule_obstacle_distance(&pen, &cup, &od); /* libccd MPR path */
    expect(od.penetrating == 1, "cup penetration took the MPR path");
    mca_capsule_capsule_distance_ccd(&sep, &pen, &od);
    mca_obstacle_t both[2] = {box, cup};
    mca_arm_obstacles_t ao;
    int rc3 = mca_arm_obstacle_distances(&ca, &ka, both, 2, &ao);
    expect(n_alloc == before && rc3 == MCA_OK,
           "capsule-obstacle / capsule-capsule / arm-obstacles (GJK, SAT, libccd MPR) allocate nothing");

    /* --- mca_body: every kind, separated and penetrating (each branch: segment closed form, box pieces and
     * SAT, cylinder root finder and escapes) --- */
    mca_body_t bodies[5];
    memset(bodies, 0, sizeof bodies);
    bodies[0].kind = MCA_BODY_PLANE;
    bodies[0].u.plane.normal[2] = 1.0;
    bodies[1].kind = MCA_BODY_SPHERE;
    bodies[1].u.sphere.radius = 0.3;
    bodies[2].kind = MCA_BODY_CAPSULE;
    bodies[2].u.capsule = (mca_capsule_t){{0, -1, 0.2}, {0, 1, 0.2}, 0.1};
    bodies[3].kind = MCA_BODY_BOX;
    bodies[3].u.box.half[0] = bodies[3].u.box.half[1] = bodies[3].u.box.half[2] = 0.5;
    bodies[3].u.box.R[0][0] = bodies[3].u.box.R[1][1] = bodies[3].u.box.R[2][2] = 1.0;
    bodies[4].kind = MCA_BODY_CYLINDER;
    bodies[4].u.cylinder.axis[2] = 1.0;
    bodies[4].u.cylinder.half_len = 0.2;
    bodies[4].u.cylinder.radius = 0.2;
    const mca_capsule_t caps[3] = {sep, pen, {{-1, 0.7, 1.2}, {1, -0.3, 0.9}, 0.05}};
    mca_body_dist_t bd;
    int body_ok = 1;
    before = n_alloc;
    for (int k = 0; k < 5; k++) {
        for (int j = 0; j < 3; j++) {
            body_ok &= mca_capsule_body_distance(&caps[j], &bodies[k], &bd) == MCA_OK;
        }
    }
    expect(n_alloc == before && body_ok,
           "mca_capsule_body_distance (plane, sphere, capsule, box, cylinder; separated and penetrating) "
           "allocates nothing");

    /* --- libccd entry points on two overlapping boxes --- */
    box_t b1 = {0.5, {0, 0, 0}}, b2 = {0.5, {0.3, 0.2, 0.1}};
    ccd_t ccd;
    ccd_real_t depth;
    ccd_vec3_t dir, pos, sepv;
    CCD_INIT(&ccd);
    ccd.support1 = ccd.support2 = box_support;
    ccd.center1 = ccd.center2 = box_center;
    long counts[5];
    before = n_alloc;
    ccdGJKIntersect(&b1, &b2, &ccd);
    counts[0] = n_alloc - before;
    before = n_alloc;
    ccdMPRIntersect(&b1, &b2, &ccd);
    counts[1] = n_alloc - before;
    before = n_alloc;
    ccdMPRPenetration(&b1, &b2, &ccd, &depth, &dir, &pos);
    counts[2] = n_alloc - before;
    before = n_alloc;
    ccdGJKPenetration(&b1, &b2, &ccd, &depth, &dir, &pos);
    counts[3] = n_alloc - before;
    before = n_alloc;
    ccdGJKSeparate(&b1, &b2, &ccd, &sepv);
    counts[4] = n_alloc - before;
    printf("libccd allocations: ccdGJKIntersect %ld, ccdMPRIntersect %ld, ccdMPRPenetration %ld, "
           "ccdGJKPenetration %ld, ccdGJKSeparate %ld\n",
           counts[0], counts[1], counts[2], counts[3], counts[4]);
    expect(counts[0] == 0 && counts[1] == 0 && counts[2] == 0,
           "libccd GJK/MPR intersect and MPR penetration: none");
    expect(counts[3] > 0 && counts[4] > 0,
           "libccd EPA paths (GJKPenetration, GJKSeparate) allocate (probe works)");
    return failures ? 1 : 0;
}
#endif
