/* SPDX-License-Identifier: MIT */
/* The cell's DDS section and its ROS 2 topics (see cell__load.h). Start-up only. */
#include <ctype.h>
#include <stdbool.h>
#include <stdio.h>

#include "mca/err.h"
#include "mca/errbuf.h" /* mca_errbuf_at */
#include "mca/ros2.h"   /* mca_ros2_name_ok */
#include "mca/scenario.h"
#include "mca/yaml_marks.h"

#include "cell__load.h"

static const mca_range_t r_dds_domain = {"domain", 0, 230, 0, 1, ""};
static const mca_range_t r_publish_divisor = {"publish_divisor", 1, 100000, 0, 1, "ticks"};
static const mca_range_t r_dds_priority = {"priority", 0, 98, 0, 1, "(0 = SCHED_OTHER)"};

/* The default ROS 2 namespace of a cell: its name with every other character as one '_' ("monitor-vs-mcad"
 * -> "monitor_vs_mcad"), "cell_" in front when it does not start with a letter. */
static void ros2_name_from(char *out, size_t len, const char *name) {
    size_t n = 0;
    if (!isalpha((unsigned char)name[0]) && len > 5) {
        n = (size_t)snprintf(out, len, "cell_");
    }
    for (const char *c = name; *c && n + 1 < len; c++) {
        const int ok = isalnum((unsigned char)*c);
        if (ok) {
            out[n++] = *c;
        } else if (n > 0 && out[n - 1] != '_') {
            out[n++] = '_';
        }
    }
    while (n > 0 && out[n - 1] == '_') {
        n--;
    }
    out[n] = '\0';
    if (n == 0) {
        snprintf(out, len, "cell");
    }
}

int mcad_cell_read_dds(const mca_check_ctx_t ctx, const struct raw_cell *raw, mca_cell_t *cell) {
    int rc = MCA_OK;
    /* DDS */
    cell->dds.enabled = 1;
    cell->dds.domain = 0;
    cell->dds.publish_divisor = 1;
    if (raw->dds) {
        const struct raw_dds *d = raw->dds;
        if (d->enabled) {
            cell->dds.enabled = *d->enabled;
        }
        if (d->domain) {
            CHECK(&r_dds_domain, (double)*d->domain, "dds.domain");
            cell->dds.domain = (uint32_t)*d->domain;
        }
        if (d->config && d->config[0]) {
            if ((rc = mca_config_find(&ctx, "dds.config", d->config, cell->dds.config,
                                      sizeof cell->dds.config)) != MCA_OK) {
                goto out;
            }
        }
        if (d->publish_divisor) {
            CHECK(&r_publish_divisor, (double)*d->publish_divisor, "dds.publish_divisor");
            cell->dds.publish_divisor = (uint32_t)*d->publish_divisor;
        }
        if (d->priority) {
            CHECK(&r_dds_priority, *d->priority, "dds.priority");
            cell->dds.priority = *d->priority;
        }
    }
    if (cell->stream.enabled &&
        !(cell->dds.enabled &&
          (!raw->dds || !raw->dds->ros2 || !raw->dds->ros2->enabled || *raw->dds->ros2->enabled))) {
        FAIL(MCA_ECONFIG, LINE("task.stream"),
             "task.stream: the targets come over ROS 2: needs dds.enabled and dds.ros2.enabled");
    }
    /* ROS 2 topics: on with DDS unless switched off; every topic on unless switched off */
    mca_cell_ros2_t *r2 = &cell->dds.ros2;
    r2->enabled = r2->joint_states = r2->robot_description = r2->tf_static = r2->markers = r2->diagnostics =
        1;
    ros2_name_from(r2->ns, sizeof r2->ns, cell->name);
    snprintf(r2->world_frame, sizeof r2->world_frame, "world");
    if (raw->dds && raw->dds->ros2) {
        const struct raw_ros2 *rr = raw->dds->ros2;
        bool *const flag_src[] = {rr->enabled,   rr->joint_states, rr->robot_description,
                                  rr->tf_static, rr->markers,      rr->diagnostics};
        int *const flag_dst[] = {&r2->enabled,   &r2->joint_states, &r2->robot_description,
                                 &r2->tf_static, &r2->markers,      &r2->diagnostics};
        for (size_t k = 0; k < sizeof flag_src / sizeof flag_src[0]; k++) {
            if (flag_src[k]) {
                *flag_dst[k] = *flag_src[k];
            }
        }
        if (rr->ns) {
            if (!mca_ros2_name_ok(rr->ns)) {
                FAIL(MCA_ECONFIG, LINE("dds.ros2.namespace"),
                     "dds.ros2.namespace: '%s' is not a ROS 2 name (a letter, then letters, digits and "
                     "single '_')",
                     rr->ns);
            }
            snprintf(r2->ns, sizeof r2->ns, "%s", rr->ns);
        }
        if (rr->world_frame) {
            if (!mca_ros2_name_ok(rr->world_frame)) {
                FAIL(MCA_ECONFIG, LINE("dds.ros2.world_frame"),
                     "dds.ros2.world_frame: '%s' is not a frame name (a letter, then letters, digits and "
                     "single '_')",
                     rr->world_frame);
            }
            snprintf(r2->world_frame, sizeof r2->world_frame, "%s", rr->world_frame);
        }
    }
out:
    return rc;
}
