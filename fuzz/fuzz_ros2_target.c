/* SPDX-License-Identifier: MIT */
/* Fuzz target: a streamed target as it arrives from the network (issue 14's ROS 2 input, issue 16). Byte 0:
 * bit 0 the type (0 geometry_msgs/TwistStamped, 1 PoseStamped), bit 1 the byte order (1: big-endian, so
 * swapped); the rest: the CDR payload (XCDR1, no encapsulation header). Cyclone's own receive path runs on
 * it: dds_stream_normalize (the check of untrusted CDR every received sample gets) and, when that accepts
 * it, dds_stream_read_sample into the type idlc generated from dds/ros2_msgs.idl; then mcad's check
 * (mca_ros2_target_check). An accepted target must be finite, in the world frame, within the speed limit
 * (twist) or the workspace box (pose). */
#include <math.h>
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h> /* abort, malloc, free */
#include <string.h>

#include <dds/ddsi/ddsi_cdrstream.h>
#include <dds/ddsi/ddsi_serdata_default.h>

#include "mca/err.h"
#include "mca/ros2.h"
#include "ros2_msgs.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

/* The sertype Cyclone builds from a topic descriptor, reduced to what normalize and read use. */
static void sertype_of(struct ddsi_sertype_default *st, const dds_topic_descriptor_t *d) {
    memset(st, 0, sizeof *st);
    st->c.type_name = (char *)d->m_typename;
    st->encoding_format = CDR_ENC_FORMAT_PLAIN;
    st->write_encoding_version = CDR_ENC_VERSION_1;
    st->type.size = d->m_size;
    st->type.align = d->m_align;
    st->type.flagset = d->m_flagset;
    st->type.ops.nops = d->m_nops;
    st->type.ops.ops = (uint32_t *)d->m_ops;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    if (size < 1 || size > 65536) {
        return 0;
    }
    const int pose = data[0] & 1, bswap = (data[0] >> 1) & 1;
    static mca_ros2_config_t cfg;
    static struct ddsi_sertype_default st_twist, st_pose;
    static int ready;
    if (!ready) {
        mca_ros2_config_default(&cfg);
        cfg.n_arms = 2;
        cfg.stream[0] = MCA_ROS2_STREAM_TWIST;
        cfg.stream[1] = MCA_ROS2_STREAM_POSE;
        cfg.stream_max_speed = 0.25;
        for (int i = 0; i < 3; i++) {
            cfg.box_lo[i] = -1.0;
            cfg.box_hi[i] = 1.5;
        }
        sertype_of(&st_twist, &geometry_msgs_msg_dds__TwistStamped__desc);
        sertype_of(&st_pose, &geometry_msgs_msg_dds__PoseStamped__desc);
        ready = 1;
    }
    const struct ddsi_sertype_default *st = pose ? &st_pose : &st_twist;
    const uint32_t n = (uint32_t)(size - 1);
    void *buf = malloc(n ? n : 1); /* normalize works in place, as on a received datagram */
    if (!buf) {
        return 0;
    }
    memcpy(buf, data + 1, n);
    uint32_t actual = 0;
    if (dds_stream_normalize(buf, n, bswap, CDR_ENC_VERSION_1, st, false, &actual)) {
        if (actual > n) {
            abort();
        }
        void *sample = calloc(1, st->type.size);
        if (sample) {
            dds_istream_t is;
            dds_istream_init(&is, actual, buf, CDR_ENC_VERSION_1);
            dds_stream_read_sample(&is, sample, st);
            double x[3];
            int finite;
            const char *frame;
            if (pose) {
                const geometry_msgs_msg_dds__PoseStamped_ *m = sample;
                x[0] = m->pose.position.x, x[1] = m->pose.position.y, x[2] = m->pose.position.z;
                finite = isfinite(m->pose.orientation.x) && isfinite(m->pose.orientation.y) &&
                         isfinite(m->pose.orientation.z) && isfinite(m->pose.orientation.w);
                frame = m->header.frame_id;
            } else {
                const geometry_msgs_msg_dds__TwistStamped_ *m = sample;
                x[0] = m->twist.linear.x, x[1] = m->twist.linear.y, x[2] = m->twist.linear.z;
                finite = isfinite(m->twist.angular.x) && isfinite(m->twist.angular.y) &&
                         isfinite(m->twist.angular.z);
                frame = m->header.frame_id;
            }
            char why[128];
            if (mca_ros2_target_check(&cfg, pose, frame, x, finite, why, sizeof why) == MCA_OK) {
                /* the promises of an accepted target */
                if (!isfinite(x[0]) || !isfinite(x[1]) || !isfinite(x[2]) || frame == NULL ||
                    strcmp(frame, "world")) {
                    abort();
                }
                if (!pose && sqrt(x[0] * x[0] + x[1] * x[1] + x[2] * x[2]) > cfg.stream_max_speed) {
                    abort();
                }
                for (int i = 0; pose && i < 3; i++) {
                    if (x[i] < cfg.box_lo[i] || x[i] > cfg.box_hi[i]) {
                        abort();
                    }
                }
            } else if (strlen(why) == 0) {
                abort(); /* a rejection names its reason */
            }
            dds_istream_fini(&is);
            dds_stream_free_sample(sample, st->type.ops.ops);
            free(sample);
        }
    }
    free(buf);
    return 0;
}
