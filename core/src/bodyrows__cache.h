/* SPDX-License-Identifier: MIT */
/* The bodies' distance cache's bounds, shared by core/src/body_cache.c and core/src/bodyrows.c (internal).
 * Context: rt (no allocation). */
#ifndef MCA_BODYROWS__CACHE_H
#define MCA_BODYROWS__CACHE_H

#include "mca/bodyrows.h"

/* Every link's move from its cached reference (the larger of its axis ends' moves; INFINITY: no usable
 * reference) of arm a: the update's own when the poses are the ones it saw. */
void mca_body__cache_moves(const mca_body_cache_t *c, const mca_chain_t *ch, const mca_kin_t *kn, int a,
                           double move[MCA_MAX_LINKS]);

/* ok[k]: the cache's distances are to body k as it is now. */
void mca_body__cache_bodies(const mca_body_cache_t *c, const mca_fixed_body_t *bodies, int n_bodies,
                            int ok[MCA_MAX_BODIES]);

/* A lower bound on the surface distance of link l (moved by `move` from its reference) to body k;
 * -INFINITY when the cache knows none. */
double mca_body__cache_bound(const mca_body_cache_t *c, int ok, int a, int l, int k, double move);

/* The same for the self pair (l, q) of arm a. */
double mca_body__cache_self_bound(const mca_body_cache_t *c, int a, int l, int q, double move_l,
                                  double move_q);

#endif
