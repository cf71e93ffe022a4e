/* SPDX-License-Identifier: MIT */
/* The snapshot's named pairs of every kind (mca/dds_bridge.h, mca/pair_distances): filled on the rt side from
 * the controller's distances, one numbering of the kinds shared with the IDL. */
#include <string.h>

#include "mca/dds_bridge.h"
#include "mca/err.h"
#include "mca_dds.h" /* idlc output: mca_dds_PAIR_* */

/* The wire's kind is an int32 (as ControllerStatus.state): the IDL's enumerators must have the C values. */
_Static_assert(MCA_DDS_PAIR_ARM_ARM == (int)mca_dds_PAIR_ARM_ARM &&
                   MCA_DDS_PAIR_ARM_BODY == (int)mca_dds_PAIR_ARM_BODY &&
                   MCA_DDS_PAIR_SELF == (int)mca_dds_PAIR_SELF &&
                   MCA_DDS_PAIR_ARM_TRACK == (int)mca_dds_PAIR_ARM_TRACK,
               "mca_dds_pair_kind_t and the IDL's PairKind must agree");
_Static_assert(MCA_DDS_MAX_PAIR_ENTRIES == mca_dds_MAX_PAIR_ENTRIES && MCA_MAX_BODIES == mca_dds_MAX_BODIES,
               "the snapshot's and the IDL's sizes must agree");
_Static_assert(sizeof(((mca_dds_PairDistance *)0)->name) == MCA_DDS_NAME_MAX + 1, "name is string<32>");

const char *mca_dds_pair_kind_name(int kind) {
    static const char *const names[] = {
        [MCA_DDS_PAIR_ARM_ARM] = "arm-arm",
        [MCA_DDS_PAIR_ARM_BODY] = "arm-body",
        [MCA_DDS_PAIR_SELF] = "self",
        [MCA_DDS_PAIR_ARM_TRACK] = "arm-track",
    };
    _Static_assert(sizeof names / sizeof names[0] == MCA_DDS_PAIR_KINDS, "a name per kind");
    return kind >= 0 && kind < MCA_DDS_PAIR_KINDS ? names[kind] : NULL;
}

static mca_dds_named_pair_t *entry(mca_dds_snapshot_t *s, int kind, int arm, int link, int other_arm,
                                   int other_link, double d, double clearance, const double p[3],
                                   const double q[3]) {
    mca_dds_named_pair_t *e = &s->named[s->n_named++];
    e->kind = kind;
    e->arm = (int16_t)arm;
    e->link = (int16_t)link;
    e->other_arm = (int16_t)other_arm;
    e->other_link = (int16_t)other_link;
    e->body = -1;
    e->name[0] = '\0';
    e->distance = d;
    e->clearance = clearance;
    memcpy(e->p, p, sizeof e->p);
    memcpy(e->q, q, sizeof e->q);
    return e;
}

int mca_dds_named_fill(mca_dds_snapshot_t *s, const mca_controller_config_t *cfg,
                       const mca_arm_distances_t (*dist)[MCA_MAX_ARMS], const mca_pair_nearest_t *pn) {
    if (s == NULL || cfg == NULL || dist == NULL) {
        return MCA_EINVAL;
    }
    s->n_named = 0;
    const int na = cfg->n_arms < MCA_MAX_ARMS ? cfg->n_arms : MCA_MAX_ARMS;
    for (int a = 0; a < na; a++) {
        for (int b = a + 1; b < na; b++) {
            const mca_link_pair_t *m = &dist[a][b].min;
            entry(s, MCA_DDS_PAIR_ARM_ARM, a, m->link, b, m->other_link, m->d, cfg->sp.d1, m->p, m->e);
        }
    }
    if (pn == NULL) {
        return MCA_OK;
    }
    const int nb = pn->n_bodies < MCA_MAX_BODIES ? pn->n_bodies : MCA_MAX_BODIES;
    for (int k = 0; k < nb; k++) {
        const mca_body_nearest_t *bn = &pn->body[k];
        if (!bn->valid) {
            continue;
        }
        mca_dds_named_pair_t *e =
            entry(s, k < pn->n_fixed ? MCA_DDS_PAIR_ARM_BODY : MCA_DDS_PAIR_ARM_TRACK, bn->arm, bn->link, -1,
                  -1, bn->d, cfg->body[k].clearance, bn->p, bn->q);
        e->body = (int16_t)k;
        _Static_assert(sizeof cfg->body[k].name <= sizeof e->name, "a body's name fits");
        memcpy(e->name, cfg->body[k].name, sizeof cfg->body[k].name);
        e->name[sizeof cfg->body[k].name - 1] = '\0';
    }
    for (int a = 0; a < na; a++) {
        const mca_self_nearest_t *sn = &pn->self[a];
        if (sn->valid) {
            entry(s, MCA_DDS_PAIR_SELF, a, sn->link, a, sn->other, sn->d, cfg->sp.d1, sn->p, sn->q);
        }
    }
    return MCA_OK;
}
