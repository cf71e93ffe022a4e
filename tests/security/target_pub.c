/* SPDX-License-Identifier: MIT */
/* mca-target-pub: streams one ROS 2 target (geometry_msgs/TwistStamped or PoseStamped), or one tracked
 * sphere (mca_msgs/TrackedBodies: --sphere X,Y,Z,R, stamped as it is sent), on a DDS topic with
 * Debian's libddsc, the same Cyclone as mcad, so that the DDS Security test (tests/security) can command
 * mcad as any identity: the Cyclone XML given (with MCA_SECURITY_DIR / MCA_DDS_IDENTITY) decides who it is.
 *
 * It reports each step on stdout, one line each, for the test to read:
 *   target_pub: participant ok | participant refused
 *   target_pub: writer ok | writer refused: <reason>
 *   target_pub: matched <n> reader(s) after <s> s | matched no reader in <s> s
 *   target_pub: sent <n> samples in <s> s, <e> write errors
 * Cyclone's own messages (a security plugin's refusal) go to stderr as Cyclone writes them.
 * Exit status: 0 sent to a matched reader, 3 participant refused, 4 writer refused (its participant stays for
 * the duration), 5 never matched a reader (it still sends for the duration), 2 usage. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include <dds/dds.h>

#include "mca/dds_qos.h" /* mca_dds_open_participant */
#include "mca/err.h"     /* MCA_OK */
#include "mca_msgs.h"    /* mca_msgs_msg_dds__TrackedBodies_ */
#include "ros2_msgs.h"   /* geometry_msgs_msg_dds__TwistStamped_, ..PoseStamped_ */

static double now_s(void) {
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + (double)ts.tv_nsec * 1e-9;
}

static void sleep_s(double s) {
    struct timespec ts = {(time_t)s, (long)((s - (double)(time_t)s) * 1e9)};
    nanosleep(&ts, NULL);
}

static int usage(void) {
    fprintf(stderr,
            "usage: mca-target-pub --topic NAME (--twist VX,VY,VZ | --pose X,Y,Z | --sphere X,Y,Z,R) "
            "[--domain N]\n"
            "                      [--config XML]\n"
            "                      [--frame ID] [--hz F] [--duration S] [--match-timeout S]\n"
            "  --topic          DDS topic, e.g. rt/stream_sim/left/target_twist\n"
            "  --twist / --pose linear velocity (m/s) / position (m) to send, in --frame (default world)\n"
            "  --duration       seconds of sending (default 1.5), after a reader matched or the timeout\n"
            "  --match-timeout  seconds to wait for a matching reader before sending (default 5)\n");
    return 2;
}

static int parse_n(const char *s, double *v, int n) {
    char *end;
    for (int i = 0; i < n; i++) {
        v[i] = strtod(s, &end);
        if (end == s || (i < n - 1 && *end != ',') || (i == n - 1 && *end != '\0')) {
            return -1;
        }
        s = end + 1;
    }
    return 0;
}

int main(int argc, char **argv) {
    const char *topic = NULL, *config = NULL, *frame = "world";
    unsigned domain = 0;
    double v[4] = {0, 0, 0, 0}, hz = 50.0, duration = 1.5, match_timeout = 5.0;
    int sphere = 0;
    int twist = -1;
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i], *val = i + 1 < argc ? argv[i + 1] : NULL;
        if (val == NULL) {
            return usage();
        }
        i++;
        if (!strcmp(a, "--topic")) {
            topic = val;
        } else if (!strcmp(a, "--config")) {
            config = val;
        } else if (!strcmp(a, "--frame")) {
            frame = val;
        } else if (!strcmp(a, "--domain")) {
            domain = (unsigned)strtoul(val, NULL, 10);
        } else if (!strcmp(a, "--hz")) {
            hz = strtod(val, NULL);
        } else if (!strcmp(a, "--duration")) {
            duration = strtod(val, NULL);
        } else if (!strcmp(a, "--match-timeout")) {
            match_timeout = strtod(val, NULL);
        } else if (!strcmp(a, "--twist") || !strcmp(a, "--pose")) {
            twist = !strcmp(a, "--twist");
            if (parse_n(val, v, 3) != 0) {
                return usage();
            }
        } else if (!strcmp(a, "--sphere")) {
            sphere = 1;
            twist = 0;
            if (parse_n(val, v, 4) != 0) {
                return usage();
            }
        } else {
            return usage();
        }
    }
    if (topic == NULL || twist < 0 || !(hz > 0.0) || !(duration >= 0.0)) {
        return usage();
    }
    setvbuf(stdout, NULL, _IOLBF, 0);

    dds_entity_t domain_h = 0, pp = 0;
    char err[320] = "";
    if (mca_dds_open_participant(domain, config, &pp, &domain_h, err, sizeof err) != MCA_OK) {
        printf("target_pub: participant refused (%s)\n", err);
        dds_delete(DDS_CYCLONEDDS_HANDLE);
        return 3;
    }
    printf("target_pub: participant ok\n");
    const dds_topic_descriptor_t *desc = sphere  ? &mca_msgs_msg_dds__TrackedBodies__desc
                                         : twist ? &geometry_msgs_msg_dds__TwistStamped__desc
                                                 : &geometry_msgs_msg_dds__PoseStamped__desc;
    dds_qos_t *q = dds_create_qos();
    dds_qset_reliability(q, DDS_RELIABILITY_RELIABLE, DDS_MSECS(10)); /* rclpy's default profile */
    dds_qset_history(q, DDS_HISTORY_KEEP_LAST, 10);
    const dds_entity_t t = dds_create_topic(pp, desc, topic, q, NULL);
    const dds_entity_t w = t > 0 ? dds_create_writer(pp, t, q, NULL) : t;
    dds_delete_qos(q);
    if (w < 0) {
        printf("target_pub: writer refused: %s\n", dds_strretcode(w));
        sleep_s(duration); /* the participant stays as long as a sending one would */
        /* all of Cyclone, domain included: its threads must be gone before exit() runs OpenSSL's clean-up
         * (with the domain left, a receive thread decrypting a sample crashed in EVP_CipherInit_ex) */
        dds_delete(DDS_CYCLONEDDS_HANDLE);
        return 4;
    }
    printf("target_pub: writer ok\n");
    dds_set_status_mask(w, DDS_PUBLICATION_MATCHED_STATUS);

    const double t0 = now_s();
    dds_publication_matched_status_t st = {0};
    while (now_s() - t0 < match_timeout) {
        if (dds_get_publication_matched_status(w, &st) == DDS_RETCODE_OK && st.current_count > 0) {
            break;
        }
        sleep_s(0.01);
    }
    const int matched = st.current_count > 0;
    if (matched) {
        printf("target_pub: matched %u reader(s) after %.2f s\n", st.current_count, now_s() - t0);
    } else {
        printf("target_pub: matched no reader in %.2f s\n", now_s() - t0);
    }

    geometry_msgs_msg_dds__TwistStamped_ tw;
    geometry_msgs_msg_dds__PoseStamped_ po;
    memset(&tw, 0, sizeof tw);
    memset(&po, 0, sizeof po);
    tw.header.frame_id = (char *)frame;
    po.header.frame_id = (char *)frame;
    tw.twist.linear.x = v[0];
    tw.twist.linear.y = v[1];
    tw.twist.linear.z = v[2];
    po.pose.position.x = v[0];
    po.pose.position.y = v[1];
    po.pose.position.z = v[2];
    po.pose.orientation.w = 1.0;
    mca_msgs_msg_dds__TrackedBody_ body;
    memset(&body, 0, sizeof body);
    body.id = 1;
    body.shape = 1;
    body.a.x = body.b.x = v[0];
    body.a.y = body.b.y = v[1];
    body.a.z = body.b.z = v[2];
    body.radius = v[3];
    mca_msgs_msg_dds__TrackedBodies_ tb;
    memset(&tb, 0, sizeof tb);
    tb.header.frame_id = (char *)frame;
    tb.bodies._buffer = &body;
    tb.bodies._length = tb.bodies._maximum = 1;
    const double t1 = now_s();
    unsigned sent = 0, errors = 0;
    for (double next = t1; now_s() - t1 < duration; next += 1.0 / hz) {
        struct timespec rt;
        clock_gettime(CLOCK_REALTIME, &rt);
        tw.header.stamp.sec = po.header.stamp.sec = (int32_t)rt.tv_sec;
        tw.header.stamp.nanosec = po.header.stamp.nanosec = (uint32_t)rt.tv_nsec;
        tb.header.stamp = body.stamp = tw.header.stamp; /* the body seen as it is sent */
        const dds_return_t rc = dds_write(w, sphere  ? (const void *)&tb
                                             : twist ? (const void *)&tw
                                                     : (const void *)&po);
        sent++;
        errors += rc != DDS_RETCODE_OK;
        const double wait = next + 1.0 / hz - now_s();
        if (wait > 0) {
            sleep_s(wait);
        }
    }
    printf("target_pub: sent %u samples in %.2f s, %u write errors\n", sent, now_s() - t1, errors);
    dds_delete(DDS_CYCLONEDDS_HANDLE);
    return matched ? 0 : 5;
}
