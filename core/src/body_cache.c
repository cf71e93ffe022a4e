/* SPDX-License-Identifier: MIT */
/* The bodies' distance cache (mca/bodyrows.h, mca_body_cache_t): per link a reference pose and its exact
 * distances to every body and self partner, whose bounds let the nearest searches and the rows skip far
 * pairs. */
#include <math.h>
#include <string.h>

#include "bodyrows__cache.h"
#include "mca/err.h"
#include "mca/vec3.h"

/* How far link l's axis moved from its cached reference: the larger of its two ends' moves (every point of
 * the segment moved by at most that); INFINITY without a usable reference (none, another radius, NaN). */
static double cache_move(const mca_body_cache_t *c, const mca_chain_t *ch, const mca_kin_t *kn, int a,
                         int l) {
    if (!c || !c->valid[a][l] || c->radius[a][l] != ch->link_radius[l]) {
        return INFINITY;
    }
    const double s0 = mca_v3_dist(kn->point[l], c->a[a][l]), s1 = mca_v3_dist(kn->point[l + 1], c->b[a][l]);
    return s0 >= 0.0 && s1 >= 0.0 ? (s0 > s1 ? s0 : s1) : INFINITY;
}

/* Every link's move (cache_move) of arm a: the update's own when the poses are the ones it saw. */
void mca_body__cache_moves(const mca_body_cache_t *c, const mca_chain_t *ch, const mca_kin_t *kn, int a,
                           double move[MCA_MAX_LINKS]) {
    const int same = c && memcmp(c->seen[a], kn->point, sizeof(double) * 3 * (size_t)(ch->dof + 2)) == 0;
    for (int l = 0; l <= ch->dof; l++) {
        move[l] = same ? c->move[a][l] : cache_move(c, ch, kn, a, l);
    }
}

/* ok[k]: the cache's distances are to body k as it is now. */
void mca_body__cache_bodies(const mca_body_cache_t *c, const mca_fixed_body_t *bodies, int n_bodies,
                            int ok[MCA_MAX_BODIES]) {
    for (int k = 0; k < n_bodies && k < MCA_MAX_BODIES; k++) {
        ok[k] = c && k < c->n_bodies && !c->stale[k] &&
                memcmp(&c->body[k], &bodies[k].body, sizeof(mca_body_t)) == 0;
    }
}

/* A lower bound on the surface distance of link l (moved by `move` from its reference) to body k;
 * -INFINITY when the cache knows none (1e-12 below: rounding never makes it exceed the distance). */
double mca_body__cache_bound(const mca_body_cache_t *c, int ok, int a, int l, int k, double move) {
    return ok ? c->d[a][l][k] - move - 1e-12 : -INFINITY;
}

/* The same for the self pair (l, q) of arm a. */
double mca_body__cache_self_bound(const mca_body_cache_t *c, int a, int l, int q, double move_l,
                                  double move_q) {
    return c ? c->ds[a][l][q] - move_l - move_q - 1e-12 : -INFINITY;
}

static double cache_distance(const mca_capsule_t *cap, const mca_body_t *body) {
    mca_body_dist_t r;
    return mca_capsule_body_distance(cap, body, &r) == MCA_OK && r.d == r.d ? r.d : -INFINITY;
}

int mca_body_cache_update(mca_body_cache_t *c, int n_arms, const mca_chain_t *const chain[],
                          const mca_kin_t kin[], const mca_fixed_body_t *bodies, int n_bodies,
                          const mca_self_pairs_t *self) {
    if (!c || n_arms < 0 || n_arms > MCA_MAX_ARMS || n_bodies < 0 || n_bodies > MCA_MAX_BODIES ||
        (n_arms > 0 && (!chain || !kin)) || (n_bodies > 0 && !bodies)) {
        return MCA_EINVAL;
    }
    int remeasure[MCA_MAX_BODIES], any_remeasure = 0;
    for (int k = 0; k < n_bodies; k++) {
        const int same = k < c->n_bodies && memcmp(&c->body[k], &bodies[k].body, sizeof(mca_body_t)) == 0;
        remeasure[k] = same && c->stale[k]; /* held still since it changed: measure it from every reference */
        any_remeasure |= remeasure[k];
        c->stale[k] = !same;
        if (!same) {
            memcpy(&c->body[k], &bodies[k].body, sizeof(mca_body_t));
        }
    }
    c->n_bodies = n_bodies;
    for (int a = 0; a < n_arms; a++) {
        const mca_chain_t *ch = chain[a];
        if (!ch || ch->dof < 1 || ch->dof > MCA_MAX_DOF) {
            return MCA_EINVAL;
        }
        int fresh[MCA_MAX_LINKS];
        memcpy(c->seen[a], kin[a].point, sizeof(double) * 3 * (size_t)(ch->dof + 2));
        for (int l = 0; l <= ch->dof; l++) {
            c->move[a][l] = cache_move(c, ch, &kin[a], a, l);
            fresh[l] = !(c->move[a][l] <= MCA_BODY_CACHE_REFRESH);
            if (fresh[l]) {
                mca_v3_set(c->a[a][l], kin[a].point[l]);
                mca_v3_set(c->b[a][l], kin[a].point[l + 1]);
                c->radius[a][l] = ch->link_radius[l];
                c->valid[a][l] = 1;
                c->move[a][l] = 0.0;
            }
            const mca_capsule_t ref = {{c->a[a][l][0], c->a[a][l][1], c->a[a][l][2]},
                                       {c->b[a][l][0], c->b[a][l][1], c->b[a][l][2]},
                                       c->radius[a][l]};
            for (int k = 0; k < n_bodies && (fresh[l] || any_remeasure); k++) {
                if (fresh[l] || remeasure[k]) {
                    c->d[a][l][k] = c->stale[k] ? -INFINITY : cache_distance(&ref, &bodies[k].body);
                }
            }
        }
        for (int l = 1; l <= ch->dof; l++) {
            for (int q = 0; q < l; q++) {
                if (!fresh[l] && !fresh[q]) {
                    continue;
                }
                c->ds[a][l][q] = -INFINITY;
                if (self && (self[a][l] & (1u << q))) {
                    const mca_capsule_t rl = {{c->a[a][l][0], c->a[a][l][1], c->a[a][l][2]},
                                              {c->b[a][l][0], c->b[a][l][1], c->b[a][l][2]},
                                              c->radius[a][l]};
                    const mca_body_t rq = {.kind = MCA_BODY_CAPSULE,
                                           .u.capsule = {{c->a[a][q][0], c->a[a][q][1], c->a[a][q][2]},
                                                         {c->b[a][q][0], c->b[a][q][1], c->b[a][q][2]},
                                                         c->radius[a][q]}};
                    c->ds[a][l][q] = cache_distance(&rl, &rq);
                }
            }
        }
    }
    return MCA_OK;
}
