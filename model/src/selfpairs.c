/* SPDX-License-Identifier: MIT */
/* The self pairs of scenario and cell files (`self_pairs:`) and the default lists shipped beside each URDF
 * (config/robots/ROBOT.self.yaml, made by tools/selfpairs/mca-selfpairs); see mca/scenario.h and
 * docs/scheme.md, "Self pairs". Start-up only. */
#include <cyaml/cyaml.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "mca/err.h"
#include "mca/scenario.h"
#include "mca/yaml_load.h"

/* ---------------------------------------------------------------- the default list file */

struct raw_list {
    char *robot;
    double margin;
    int (*pairs)[2];
    unsigned pairs_count;
};

static const cyaml_schema_value_t link_entry = {CYAML_VALUE_INT(CYAML_FLAG_DEFAULT, int)};
static const cyaml_schema_value_t pair_entry = {
    CYAML_VALUE_SEQUENCE_FIXED(CYAML_FLAG_FLOW, int, &link_entry, 2)};
static const cyaml_schema_field_t list_fields[] = {
    CYAML_FIELD_STRING_PTR("robot", CYAML_FLAG_POINTER, struct raw_list, robot, 1, 63),
    CYAML_FIELD_FLOAT("margin", CYAML_FLAG_DEFAULT, struct raw_list, margin),
    CYAML_FIELD_SEQUENCE("pairs", CYAML_FLAG_POINTER, struct raw_list, pairs, &pair_entry, 0,
                         MCA_MAX_LINKS *MCA_MAX_LINKS),
    CYAML_FIELD_END,
};
static const cyaml_schema_value_t list_schema = {
    CYAML_VALUE_MAPPING(CYAML_FLAG_POINTER, struct raw_list, list_fields),
};

/* A pair of links of an arm with `dof` joints: both in 0..dof, neither adjacent nor the same (adjacent links
 * meet at their joint: no distance to keep). 0 or a reason. */
static const char *pair_check(int l, int q, int dof) {
    if (l < 0 || q < 0 || l > dof || q > dof) {
        return "no such link";
    }
    if (l == q || l - q == 1 || q - l == 1) {
        return "adjacent or the same link (they meet at a joint)";
    }
    return NULL;
}

static void pair_set(unsigned self[MCA_MAX_LINKS], int l, int q, int on) {
    const int hi = l > q ? l : q, lo = l > q ? q : l;
    if (on) {
        self[hi] |= 1u << lo;
    } else {
        self[hi] &= ~(1u << lo);
    }
}

/* The robot's default list (the file beside its URDF, ".urdf" -> ".self.yaml") into self. */
static int default_list(const mca_check_ctx_t *c, const char *field, const mca_scenario_arm_t *sa,
                        unsigned self[MCA_MAX_LINKS]) {
    char path[600];
    const size_t n = strlen(sa->urdf);
    const size_t stem = n > 5 && strcmp(sa->urdf + n - 5, ".urdf") == 0 ? n - 5 : n;
    snprintf(path, sizeof path, "%.*s.self.yaml", (int)stem, sa->urdf);
    struct raw_list *raw = NULL;
    mca_yaml_marks_t marks;
    char why[512];
    int rc = mca_yaml_load(path, "self-pair list", &list_schema, (void **)&raw, &marks, why, sizeof why);
    if (rc != MCA_OK) {
        return mca_check_fail(c, MCA_ECONFIG, field, "%s: arm '%s': no default self-pair list: %s", field,
                              sa->name, why);
    }
    const mca_check_ctx_t lc = {.file = path, .marks = &marks, .err = c->err, .errlen = c->errlen};
    for (unsigned i = 0; i < raw->pairs_count; i++) {
        const int l = raw->pairs[i][0], q = raw->pairs[i][1];
        const char *bad = pair_check(l, q, sa->chain.dof);
        if (bad) {
            char f[48];
            snprintf(f, sizeof f, "pairs[%u]", i);
            rc = mca_check_fail(&lc, MCA_ECONFIG, f, "%s: [%d, %d]: %s (arm '%s' has links 0..%d)", f, l, q,
                                bad, sa->name, sa->chain.dof);
            break;
        }
        pair_set(self, l, q, 1);
    }
    mca_yaml_marks_free(&marks);
    mca_yaml_free(&list_schema, raw);
    return rc;
}

/* ---------------------------------------------------------------- the key */

/* A link "base", "tool" or N of an arm with dof joints; -1 if none. */
static int link_parse(const char *s, size_t len, int dof) {
    if (len == 4 && strncmp(s, "base", 4) == 0) {
        return 0;
    }
    if (len == 4 && strncmp(s, "tool", 4) == 0) {
        return dof;
    }
    int v = 0;
    for (size_t i = 0; i < len; i++) {
        if (s[i] < '0' || s[i] > '9' || v > MCA_MAX_LINKS) {
            return -1;
        }
        v = v * 10 + (s[i] - '0');
    }
    return len > 0 ? v : -1;
}

int mca_scenario_self_apply(const mca_check_ctx_t *c, char *const *k, unsigned count, mca_scenario_t *scn) {
    for (unsigned i = 0; k && i < count; i++) {
        char f[48];
        snprintf(f, sizeof f, "self_pairs[%u]", i);
        const char *s = k[i];
        const int off = s[0] == '-';
        s += off;
        const char *dot = strchr(s, '.');
        const size_t len = dot ? (size_t)(dot - s) : strlen(s);
        int a = -1;
        for (int j = 0; j < scn->n_arms; j++) {
            if (strlen(scn->arm[j].name) == len && strncmp(scn->arm[j].name, s, len) == 0) {
                a = j;
            }
        }
        if (a < 0) {
            return mca_check_fail(
                c, MCA_ECONFIG, f,
                "%s: '%s': no such arm (write ARM for its default list, ARM.L-M for a pair, "
                "a leading '-' to take them out)",
                f, k[i]);
        }
        mca_scenario_arm_t *sa = &scn->arm[a];
        if (!dot) {
            if (off) {
                memset(sa->self, 0, sizeof sa->self);
            } else {
                const int rc = default_list(c, f, sa, sa->self);
                if (rc != MCA_OK) {
                    return rc;
                }
            }
            continue;
        }
        const char *dash = strchr(dot + 1, '-');
        const int dof = sa->chain.dof;
        const int l = dash ? link_parse(dot + 1, (size_t)(dash - dot - 1), dof) : -1;
        const int q = dash ? link_parse(dash + 1, strlen(dash + 1), dof) : -1;
        const char *bad = l < 0 || q < 0 ? "no such link" : pair_check(l, q, dof);
        if (bad) {
            return mca_check_fail(c, MCA_ECONFIG, f, "%s: '%s': %s (arm '%s' has links 0..%d: base, N, tool)",
                                  f, k[i], bad, sa->name, dof);
        }
        pair_set(sa->self, l, q, !off);
    }
    return MCA_OK;
}
