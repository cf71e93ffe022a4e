/* SPDX-License-Identifier: MIT */
/* The cell's streamed bodies (streamed_bodies: see cell__load.h, docs/scheme.md "Streamed bodies"): a person
 * or a foreign machine tracked elsewhere, taken over DDS Security only. Start-up only. */
#include <stdio.h>
#include <string.h>

#include "mca/err.h"
#include "mca/errbuf.h" /* mca_errbuf_at */
#include "mca/ros2.h"   /* mca_ros2_name_ok */
#include "mca/scenario.h"
#include "mca/yaml_marks.h"

#include "cell__load.h"

static const mca_range_t r_max_bodies = {"max_bodies", 1, MCA_MAX_TRACKS, 0, 1, ""};
static const mca_range_t r_time = {"time", 0.0, 10.0, 0, 0, "s"};
static const mca_range_t r_lost = {"lost_after", 0.0, 10.0, 1, 0, "s"};
static const mca_range_t r_speed = {"speed", 0.1, 10.0, 0, 0, "m/s"};
static const mca_range_t r_len = {"length", 0.0, 2.0, 0, 0, "m"};

/* 1 when the Cyclone XML at path configures DDS Security (its <Security> element): then only the identities
 * its signed permissions grant may write the tracks (docs/security.md). */
static int dds_config_secure(const char *path) {
    FILE *f = path && path[0] ? fopen(path, "r") : NULL;
    if (!f) {
        return 0;
    }
    static char buf[65536];
    const size_t n = fread(buf, 1, sizeof buf - 1, f);
    fclose(f);
    buf[n] = '\0';
    return strstr(buf, "<Security>") != NULL;
}

int mcad_cell_read_tracks(const mca_check_ctx_t ctx, const struct raw_cell *raw, mca_cell_t *cell) {
    int rc = MCA_OK;
    mca_cell_tracks_t *ct = &cell->tracks;
    mca_ssm_default(&ct->ssm);
    snprintf(ct->topic, sizeof ct->topic, "tracked_bodies");
    ct->max_bodies = MCA_MAX_TRACKS;
    const struct raw_tracks *rt = raw->tracks;
    if (!rt) {
        goto out;
    }
    ct->enabled = 1;
    if (!cell->dds.enabled || !cell->dds.ros2.enabled) {
        FAIL(MCA_ECONFIG, LINE("streamed_bodies"),
             "streamed_bodies: the tracks come over DDS: needs dds.enabled and dds.ros2.enabled");
    }
    if (!dds_config_secure(cell->dds.config)) {
        FAIL(MCA_ECONFIG, LINE("streamed_bodies"),
             "streamed_bodies: a track decides where the arms may go: only a DDS Security cell takes them "
             "(dds.config naming a Cyclone XML with <Security>, e.g. ../dds/secure.xml; docs/security.md)");
    }
    if (rt->topic) {
        /* the shipped governance protects rt/<ns>/tracked_bodies*: a name outside it would go unprotected */
        if (!mca_ros2_name_ok(rt->topic) || strncmp(rt->topic, "tracked_bodies", 14) != 0) {
            FAIL(MCA_ECONFIG, LINE("streamed_bodies.topic"),
                 "streamed_bodies.topic: '%s' is not a ROS 2 name beginning with tracked_bodies (what the "
                 "cell's governance protects: config/security/governance_*.xml)",
                 rt->topic);
        }
        snprintf(ct->topic, sizeof ct->topic, "%s", rt->topic);
    }
    if (rt->max_bodies) {
        CHECK(&r_max_bodies, (double)*rt->max_bodies, "streamed_bodies.max_bodies");
        ct->max_bodies = (int)*rt->max_bodies;
    }
    mca_ssm_params_t *p = &ct->ssm;
    const struct {
        const char *key;
        const double *v;
        double *dst;
        const mca_range_t *r;
    } nums[] = {
        {"max_age", rt->max_age, &p->max_age, &r_time},
        {"lost_after", rt->lost_after, &p->lost_after, &r_lost},
        {"approach_speed_near", rt->approach_near, &p->approach_near, &r_speed},
        {"approach_speed_far", rt->approach_far, &p->approach_far, &r_speed},
        {"approach_switch", rt->approach_switch, &p->approach_switch, &r_len},
        {"reaction_time", rt->reaction_time, &p->reaction_time, &r_time},
        {"latency", rt->latency, &p->latency, &r_time},
        {"intrusion", rt->intrusion, &p->intrusion, &r_len},
        {"uncertainty_sensor", rt->z_d, &p->z_d, &r_len},
        {"uncertainty_arm", rt->z_r, &p->z_r, &r_len},
    };
    for (size_t k = 0; k < sizeof nums / sizeof nums[0]; k++) {
        if (nums[k].v) {
            CHECK(nums[k].r, *nums[k].v, "streamed_bodies.%s", nums[k].key);
            *nums[k].dst = *nums[k].v;
        }
    }
    if (!(p->lost_after > p->max_age)) {
        FAIL(MCA_ECONFIG, LINE("streamed_bodies.lost_after"),
             "streamed_bodies.lost_after: %g s not after max_age %g s (a track grows before the stream is "
             "lost)",
             p->lost_after, p->max_age);
    }
out:
    return rc;
}
