/* SPDX-License-Identifier: MIT */
/* ROS 2 topics of the DDS bridge (mca/ros2.h, docs/ros2.md). Every sample is built in scratch memory
 * allocated at create; the publisher thread formats the diagnostics' numbers (non-rt). */
#include "ros2_pub.h"

#include <ctype.h>
#include <math.h>
#include <pthread.h>
#include <stdarg.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "mca/dds_qos.h"
#include "mca/err.h"
#include "mca_msgs.h"  /* idlc output of dds/mca_msgs.idl: mca_msgs/TrackedBodies */
#include "ros2_msgs.h" /* idlc output of dds/ros2_msgs.idl */

/* visualization_msgs/Marker types and actions, diagnostic_msgs/DiagnosticStatus levels */
enum {
    MARKER_CUBE = 1,
    MARKER_SPHERE = 2,
    MARKER_CYLINDER = 3,
    MARKER_SPHERE_LIST = 7,
    MARKER_LINE_LIST = 5,
    MARKER_TEXT = 9,
    MARKER_ADD = 0
};
enum { DIAG_OK = 0, DIAG_WARN = 1, DIAG_ERROR = 2 };

#define MAX_MARKERS (MCA_MAX_ARMS * MCA_MAX_LINKS * 2 + MCA_MAX_PAIRS * 2 + MCA_MAX_BODIES * 3)
#define N_KV 32
#define URDF_MAX (4 * 1024 * 1024)

typedef sensor_msgs_msg_dds__JointState_ JointState;
typedef visualization_msgs_msg_dds__Marker_ Marker;
typedef visualization_msgs_msg_dds__MarkerArray_ MarkerArray;
typedef diagnostic_msgs_msg_dds__KeyValue_ KeyValue;

struct mca_ros2_pub;
typedef struct stream_in {
    struct mca_ros2_pub *r;
    int arm;
    dds_entity_t reader;
} stream_in_t;

struct mca_ros2_pub {
    mca_ros2_config_t cfg;
    mca_dds_mailbox_t *box; /* MCA_MAX_ARMS, the bridge's (shared with the loop, outlives a publisher) */
    stream_in_t in[MCA_MAX_ARMS];
    mca_dds_trackbox_t *tracks; /* the bridge's (shared with the loop) */
    dds_entity_t tracks_reader;
    /* rejections: counted and described by the listener, read by the publisher thread (both non-rt) */
    pthread_mutex_t reject_lock;
    uint64_t rejected;
    char last_reject[160];
    int64_t realtime_offset_ns; /* CLOCK_REALTIME - CLOCK_MONOTONIC at create */
    dds_entity_t w_joints[MCA_MAX_ARMS], w_desc[MCA_MAX_ARMS], w_tf, w_markers, w_diag;
    char *joint_ptr[MCA_MAX_ARMS][MCA_MAX_DOF];
    char arm_frame[MCA_MAX_ARMS][MCA_ROS2_NAME_MAX + 1 + 64 + 1];
    char ns_links[MCA_MAX_ARMS][MCA_ROS2_NAME_MAX + 8];
    Marker marker[MAX_MARKERS];
    geometry_msgs_msg_dds__Point_ pts[MAX_MARKERS][2];
    char text[MCA_MAX_PAIRS][48];
    char hardware_id[MCA_ROS2_NAME_MAX + 1];
    char diag_name[MCA_ROS2_NAME_MAX + 16];
    char diag_message[256];
    KeyValue kv[N_KV];
    char kv_value[N_KV][168];
};

void mca_ros2_config_default(mca_ros2_config_t *cfg) {
    if (cfg == NULL) {
        return;
    }
    memset(cfg, 0, sizeof *cfg);
    cfg->joint_states = cfg->robot_description = cfg->tf_static = cfg->markers = cfg->diagnostics = 1;
    snprintf(cfg->world_frame, sizeof cfg->world_frame, "world");
}

int mca_ros2_name_ok(const char *s) {
    if (s == NULL || !isalpha((unsigned char)s[0])) {
        return 0;
    }
    for (const char *c = s; *c; c++) {
        if (!(isalnum((unsigned char)*c) || *c == '_') || (c[0] == '_' && c[1] == '_')) {
            return 0;
        }
    }
    return s[strlen(s) - 1] != '_';
}

int mca_ros2_config_check(const mca_ros2_config_t *cfg, char *err, size_t errlen) {
    char dummy[8];
    if (err == NULL) {
        err = dummy;
        errlen = sizeof dummy;
    }
    if (cfg == NULL) {
        snprintf(err, errlen, "ros2: no configuration");
        return MCA_EINVAL;
    }
    if (!mca_ros2_name_ok(cfg->cell)) {
        snprintf(err, errlen,
                 "ros2.namespace: '%s' is not a ROS 2 name (a letter, then letters, digits, '_')", cfg->cell);
        return MCA_EINVAL;
    }
    if (cfg->world_frame[0] == '\0' || strchr(cfg->world_frame, ' ') != NULL) {
        snprintf(err, errlen, "ros2.world_frame: '%s' is not a frame name", cfg->world_frame);
        return MCA_EINVAL;
    }
    if (cfg->n_arms < 1 || cfg->n_arms > MCA_MAX_ARMS) {
        snprintf(err, errlen, "ros2: %u arms (1..%d)", cfg->n_arms, MCA_MAX_ARMS);
        return MCA_EINVAL;
    }
    if (cfg->tracks &&
        (!mca_ros2_name_ok(cfg->tracks_topic) || cfg->max_tracks < 1 || cfg->max_tracks > MCA_MAX_TRACKS)) {
        snprintf(err, errlen, "streamed_bodies: topic '%s' or max_bodies %u (1..%d)", cfg->tracks_topic,
                 cfg->max_tracks, MCA_MAX_TRACKS);
        return MCA_EINVAL;
    }
    for (uint32_t a = 0; a < cfg->n_arms; a++) {
        if (cfg->stream[a] < MCA_ROS2_STREAM_NONE || cfg->stream[a] > MCA_ROS2_STREAM_POSE) {
            snprintf(err, errlen, "arms[%u].stream: kind %d", a, cfg->stream[a]);
            return MCA_EINVAL;
        }
        if (cfg->stream[a] != MCA_ROS2_STREAM_NONE) {
            const int box_ok = cfg->box_lo[0] < cfg->box_hi[0] && cfg->box_lo[1] < cfg->box_hi[1] &&
                               cfg->box_lo[2] < cfg->box_hi[2];
            if (!(cfg->stream_max_speed > 0.0 && cfg->stream_max_speed < 10.0) || !box_ok) {
                snprintf(err, errlen, "task.stream: max_speed %g m/s (0..10) or an empty workspace box",
                         cfg->stream_max_speed);
                return MCA_EINVAL;
            }
        }
        const mca_ros2_arm_t *arm = &cfg->arm[a];
        if (!mca_ros2_name_ok(arm->name)) {
            snprintf(err, errlen,
                     "arms[%u].name: '%s' is not a ROS 2 name (a letter, then letters, digits, '_')", a,
                     arm->name);
            return MCA_EINVAL;
        }
        for (uint32_t b = 0; b < a; b++) {
            if (strcmp(cfg->arm[b].name, arm->name) == 0) {
                snprintf(err, errlen, "arms[%u].name: '%s' again (arm %u): ROS 2 topics need distinct names",
                         a, arm->name, b);
                return MCA_EINVAL;
            }
        }
        if (arm->n_dof < 1 || arm->n_dof > MCA_MAX_DOF || arm->n_links > MCA_MAX_LINKS) {
            snprintf(err, errlen, "arms[%u]: %u joints, %u links", a, arm->n_dof, arm->n_links);
            return MCA_EINVAL;
        }
        for (uint32_t l = 0; l < arm->n_links; l++) {
            if (!(arm->link_radius[l] >= 0.0 && arm->link_radius[l] < 10.0)) {
                snprintf(err, errlen, "arms[%u]: link %u radius %g", a, l, arm->link_radius[l]);
                return MCA_EINVAL;
            }
        }
    }
    return MCA_OK;
}

static builtin_interfaces_msg_dds__Time_ ros_time(const mca_ros2_pub_t *r, int64_t mono_ns) {
    const int64_t ns = mono_ns + r->realtime_offset_ns;
    builtin_interfaces_msg_dds__Time_ t = {(int32_t)(ns / 1000000000LL), (uint32_t)(ns % 1000000000LL)};
    return t;
}

static int64_t clock_ns(clockid_t c) {
    struct timespec ts;
    clock_gettime(c, &ts);
    return (int64_t)ts.tv_sec * 1000000000LL + ts.tv_nsec;
}

static void quat_from_R(const double R[3][3], double q[4]) {
    /* (x, y, z, w), Shepperd's method: divide by the largest of the four candidates */
    const double tr = R[0][0] + R[1][1] + R[2][2];
    if (tr > 0.0) {
        const double s = sqrt(tr + 1.0) * 2.0;
        q[3] = 0.25 * s;
        q[0] = (R[2][1] - R[1][2]) / s;
        q[1] = (R[0][2] - R[2][0]) / s;
        q[2] = (R[1][0] - R[0][1]) / s;
    } else if (R[0][0] > R[1][1] && R[0][0] > R[2][2]) {
        const double s = sqrt(1.0 + R[0][0] - R[1][1] - R[2][2]) * 2.0;
        q[3] = (R[2][1] - R[1][2]) / s;
        q[0] = 0.25 * s;
        q[1] = (R[0][1] + R[1][0]) / s;
        q[2] = (R[0][2] + R[2][0]) / s;
    } else if (R[1][1] > R[2][2]) {
        const double s = sqrt(1.0 + R[1][1] - R[0][0] - R[2][2]) * 2.0;
        q[3] = (R[0][2] - R[2][0]) / s;
        q[0] = (R[0][1] + R[1][0]) / s;
        q[1] = 0.25 * s;
        q[2] = (R[1][2] + R[2][1]) / s;
    } else {
        const double s = sqrt(1.0 + R[2][2] - R[0][0] - R[1][1]) * 2.0;
        q[3] = (R[1][0] - R[0][1]) / s;
        q[0] = (R[0][2] + R[2][0]) / s;
        q[1] = (R[1][2] + R[2][1]) / s;
        q[2] = 0.25 * s;
    }
}

static char *read_text(const char *path, char *err, size_t errlen) {
    FILE *f = fopen(path, "rb");
    if (f == NULL) {
        snprintf(err, errlen, "ros2: robot_description: cannot read '%s'", path);
        return NULL;
    }
    char *buf = malloc(URDF_MAX + 1);
    const size_t n = buf ? fread(buf, 1, URDF_MAX, f) : 0;
    const int too_long = buf && n == URDF_MAX && fgetc(f) != EOF;
    fclose(f);
    if (buf == NULL || too_long) {
        snprintf(err, errlen, "ros2: robot_description: '%s' %s", path,
                 buf ? "is longer than 4 MiB" : "does not fit in memory");
        free(buf);
        return NULL;
    }
    buf[n] = '\0';
    return buf;
}

static dds_entity_t make_writer(dds_entity_t pp, const dds_topic_descriptor_t *desc, const char *name,
                                const dds_qos_t *qos, char *err, size_t errlen) {
    const dds_entity_t t = dds_create_topic(pp, desc, name, qos, NULL);
    const dds_entity_t w = t > 0 ? dds_create_writer(pp, t, qos, NULL) : t;
    if (w < 0) {
        snprintf(err, errlen, "ros2: cannot create topic/writer '%s': %s", name, dds_strretcode(w));
    }
    return w;
}

static int write_description_and_tf(mca_ros2_pub_t *r, dds_entity_t pp, const dds_qos_t *latched, char *err,
                                    size_t errlen) {
    const mca_ros2_config_t *c = &r->cfg;
    char name[160];
    for (uint32_t a = 0; a < c->n_arms && c->robot_description; a++) {
        snprintf(name, sizeof name, "rt/%s/%s/robot_description", c->cell, c->arm[a].name);
        r->w_desc[a] = make_writer(pp, &std_msgs_msg_dds__String__desc, name, latched, err, errlen);
        if (r->w_desc[a] < 0) {
            return MCA_EIO;
        }
        char *text = read_text(c->arm[a].urdf_path, err, errlen);
        if (text == NULL) {
            return MCA_ENOENT;
        }
        const std_msgs_msg_dds__String_ msg = {.data = text};
        const dds_return_t rc = dds_write(r->w_desc[a], &msg);
        free(text); /* the writer keeps its own serialized copy for late joiners */
        if (rc < 0) {
            snprintf(err, errlen, "ros2: %s: %s", name, dds_strretcode(rc));
            return MCA_EIO;
        }
    }
    if (!c->tf_static) {
        return MCA_OK;
    }
    r->w_tf = make_writer(pp, &tf2_msgs_msg_dds__TFMessage__desc, "rt/tf_static", latched, err, errlen);
    if (r->w_tf < 0) {
        return MCA_EIO;
    }
    geometry_msgs_msg_dds__TransformStamped_ tf[MCA_MAX_ARMS];
    const builtin_interfaces_msg_dds__Time_ now = ros_time(r, clock_ns(CLOCK_MONOTONIC));
    for (uint32_t a = 0; a < c->n_arms; a++) {
        const mca_pose_t *b = &c->arm[a].base;
        double q[4];
        quat_from_R(b->R, q);
        tf[a] = (geometry_msgs_msg_dds__TransformStamped_){
            .header = {.stamp = now, .frame_id = r->cfg.world_frame},
            .child_frame_id = r->arm_frame[a],
            .transform = {.translation = {b->p[0], b->p[1], b->p[2]}, .rotation = {q[0], q[1], q[2], q[3]}},
        };
    }
    const tf2_msgs_msg_dds__TFMessage_ msg = {
        .transforms = {._maximum = c->n_arms, ._length = c->n_arms, ._buffer = tf, ._release = false}};
    const dds_return_t rc = dds_write(r->w_tf, &msg);
    if (rc < 0) {
        snprintf(err, errlen, "ros2: /tf_static: %s", dds_strretcode(rc));
        return MCA_EIO;
    }
    return MCA_OK;
}

static void init_marker(Marker *m, const char *frame, const char *ns, int32_t id, int32_t type) {
    memset(m, 0, sizeof *m);
    m->header.frame_id = (char *)frame;
    m->ns = (char *)ns;
    m->id = id;
    m->type = type;
    m->action = MARKER_ADD;
    m->pose.orientation.w = 1.0;
    m->texture_resource = m->text = m->mesh_resource = m->mesh_file.filename = "";
    m->texture.header.frame_id = m->texture.format = "";
}

static void reject(mca_ros2_pub_t *r, int arm, const char *fmt, ...) __attribute__((format(printf, 3, 4)));
static void reject(mca_ros2_pub_t *r, int arm, const char *fmt, ...) {
    pthread_mutex_lock(&r->reject_lock);
    r->rejected++;
    char name[MCA_ROS2_NAME_MAX + 1];
    /* not formatted from r into r (-Wrestrict); arm -1: the streamed bodies */
    memcpy(name, arm >= 0 ? r->cfg.arm[arm].name : r->cfg.tracks_topic, sizeof name);
    const int n = snprintf(r->last_reject, sizeof r->last_reject, "%s: ", name);
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(r->last_reject + n, sizeof r->last_reject - (size_t)n, fmt, ap);
    va_end(ap);
    pthread_mutex_unlock(&r->reject_lock);
}

static void accept_target(mca_ros2_pub_t *r, int arm, const double x[3]) {
    mca_dds_mailbox_t *b = &r->box[arm];
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    const uint32_t s0 = atomic_load_explicit(&b->seq, memory_order_relaxed);
    atomic_store_explicit(&b->seq, s0 + 1u, memory_order_relaxed);
    atomic_thread_fence(memory_order_release); /* odd seq visible before the fields change */
    for (int i = 0; i < 3; i++) {
        atomic_store_explicit(&b->x[i], x[i], memory_order_relaxed);
    }
    atomic_store_explicit(&b->recv_ns, (int64_t)ts.tv_sec * 1000000000LL + ts.tv_nsec, memory_order_relaxed);
    atomic_store_explicit(&b->accepted, atomic_load_explicit(&b->accepted, memory_order_relaxed) + 1u,
                          memory_order_relaxed);
    atomic_store_explicit(&b->seq, s0 + 2u, memory_order_release);
}

static int finite3(double a, double b, double c) {
    return isfinite(a) && isfinite(b) && isfinite(c);
}

int mca_ros2_target_check(const mca_ros2_config_t *c, int arm, const char *frame_id, const double x[3],
                          int finite, char *why, size_t len) {
    char dummy[8];
    if (why == NULL || len == 0) {
        why = dummy;
        len = sizeof dummy;
    }
    if (c == NULL || x == NULL || arm < 0 || arm >= MCA_MAX_ARMS || c->stream[arm] == MCA_ROS2_STREAM_NONE) {
        snprintf(why, len, "no stream");
        return MCA_EINVAL;
    }
    if (!finite || !finite3(x[0], x[1], x[2])) {
        snprintf(why, len, "not a number (NaN or infinity) in the target");
        return MCA_ERANGE;
    }
    if (frame_id == NULL || strcmp(frame_id, c->world_frame) != 0) {
        snprintf(why, len, "frame_id '%.40s' is not the cell's '%s'", frame_id ? frame_id : "",
                 c->world_frame);
        return MCA_ERANGE;
    }
    if (c->stream[arm] == MCA_ROS2_STREAM_TWIST) {
        const double v = sqrt(x[0] * x[0] + x[1] * x[1] + x[2] * x[2]);
        if (!(v <= c->stream_max_speed)) {
            snprintf(why, len, "speed %.3g m/s above the limit %.3g m/s", v, c->stream_max_speed);
            return MCA_ERANGE;
        }
    } else {
        for (int i = 0; i < 3; i++) {
            if (!(x[i] >= c->box_lo[i] && x[i] <= c->box_hi[i])) {
                snprintf(why, len, "target (%.3g, %.3g, %.3g) m outside the workspace box", x[0], x[1], x[2]);
                return MCA_ERANGE;
            }
        }
    }
    return MCA_OK;
}

/* Check one received message; accept it into the arm's mailbox or count why not. */
static void check_target(mca_ros2_pub_t *r, int arm, const std_msgs_msg_dds__Header_ *h, const double x[3],
                         int finite) {
    char why[120];
    if (mca_ros2_target_check(&r->cfg, arm, h->frame_id, x, finite, why, sizeof why) == MCA_OK) {
        accept_target(r, arm, x);
    } else {
        reject(r, arm, "%s", why);
    }
}

/* Cyclone listener (its receive thread, non-rt): every new sample of one arm's stream. */
static void on_target(dds_entity_t reader, void *arg) {
    stream_in_t *in = arg;
    mca_ros2_pub_t *r = in->r;
    void *buf[1] = {NULL};
    dds_sample_info_t info[1];
    while (dds_take(reader, buf, info, 1, 1) > 0) {
        if (info[0].valid_data) {
            if (r->cfg.stream[in->arm] == MCA_ROS2_STREAM_TWIST) {
                const geometry_msgs_msg_dds__TwistStamped_ *m = buf[0];
                const geometry_msgs_msg_dds__Vector3_ *l = &m->twist.linear, *w = &m->twist.angular;
                const double x[3] = {l->x, l->y, l->z};
                check_target(r, in->arm, &m->header, x,
                             finite3(l->x, l->y, l->z) && finite3(w->x, w->y, w->z));
            } else {
                const geometry_msgs_msg_dds__PoseStamped_ *m = buf[0];
                const geometry_msgs_msg_dds__Point_ *p = &m->pose.position;
                const geometry_msgs_msg_dds__Quaternion_ *o = &m->pose.orientation;
                const double x[3] = {p->x, p->y, p->z};
                check_target(r, in->arm, &m->header, x,
                             finite3(p->x, p->y, p->z) && finite3(o->x, o->y, o->z) && isfinite(o->w));
            }
        }
        dds_return_loan(reader, buf, 1);
        buf[0] = NULL;
    }
}

static int create_stream_reader(mca_ros2_pub_t *r, dds_entity_t pp, int a, char *err, size_t errlen) {
    const mca_ros2_config_t *c = &r->cfg;
    if (c->stream[a] == MCA_ROS2_STREAM_NONE) {
        return MCA_OK;
    }
    const int twist = c->stream[a] == MCA_ROS2_STREAM_TWIST;
    char name[160];
    snprintf(name, sizeof name, "rt/%s/%s/%s", c->cell, c->arm[a].name,
             twist ? "target_twist" : "target_pose");
    dds_qos_t *q = dds_create_qos();
    dds_listener_t *l = dds_create_listener(&r->in[a]);
    if (q == NULL || l == NULL) {
        dds_delete_qos(q);
        dds_delete_listener(l);
        return MCA_ENOMEM;
    }
    /* best effort, keep-last 1: matches reliable and best-effort publishers; only the latest target counts */
    dds_qset_reliability(q, DDS_RELIABILITY_BEST_EFFORT, 0);
    dds_qset_history(q, DDS_HISTORY_KEEP_LAST, 1);
    r->in[a] = (stream_in_t){.r = r, .arm = a};
    dds_lset_data_available(l, on_target);
    const dds_entity_t t = dds_create_topic(
        pp, twist ? &geometry_msgs_msg_dds__TwistStamped__desc : &geometry_msgs_msg_dds__PoseStamped__desc,
        name, q, NULL);
    r->in[a].reader = t > 0 ? dds_create_reader(pp, t, q, l) : t;
    dds_delete_qos(q);
    dds_delete_listener(l);
    if (r->in[a].reader < 0) {
        snprintf(err, errlen, "ros2: cannot create topic/reader '%s': %s", name,
                 dds_strretcode(r->in[a].reader));
        return MCA_EIO;
    }
    return MCA_OK;
}

int mca_ros2_tracks_check(const mca_ros2_config_t *c, const char *frame_id, const mca_ros2_tracks_t *t,
                          int finite, char *why, size_t len) {
    char dummy[8];
    if (why == NULL || len == 0) {
        why = dummy;
        len = sizeof dummy;
    }
    if (c == NULL || t == NULL || !c->tracks) {
        snprintf(why, len, "no streamed bodies");
        return MCA_EINVAL;
    }
    if (!finite) {
        snprintf(why, len, "not a number (NaN or infinity) in the bodies");
        return MCA_ERANGE;
    }
    if (frame_id == NULL || strcmp(frame_id, c->world_frame) != 0) {
        snprintf(why, len, "frame_id '%.40s' is not the cell's '%s'", frame_id ? frame_id : "",
                 c->world_frame);
        return MCA_ERANGE;
    }
    if (t->n > c->max_tracks) {
        snprintf(why, len, "%u bodies, more than the %u taken", t->n, c->max_tracks);
        return MCA_ERANGE;
    }
    for (uint32_t k = 0; k < t->n; k++) {
        const mca_track_t *b = &t->body[k];
        const double v = sqrt(b->v[0] * b->v[0] + b->v[1] * b->v[1] + b->v[2] * b->v[2]);
        int far = 0;
        for (int i = 0; i < 3; i++) {
            far |= !(fabs(b->a[i]) <= 100.0) || !(fabs(b->b[i]) <= 100.0);
        }
        if (b->kind != MCA_BODY_SPHERE && b->kind != MCA_BODY_CAPSULE) {
            snprintf(why, len, "body %u: shape %d (1 sphere, 2 capsule)", b->id, b->kind);
            return MCA_ERANGE;
        }
        if (!(b->radius >= 0.0 && b->radius <= 2.0) || !(v <= 10.0) || far ||
            !(b->stamp >= 0.0 && b->stamp <= 10.0)) {
            snprintf(why, len, "body %u: radius %.3g m, speed %.3g m/s, %s, seen %.3g s before sending",
                     b->id, b->radius, v, far ? "beyond 100 m" : "within 100 m", b->stamp);
            return MCA_ERANGE;
        }
    }
    return MCA_OK;
}

static void accept_tracks(mca_ros2_pub_t *r, const mca_ros2_tracks_t *t) {
    mca_dds_trackbox_t *b = r->tracks;
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    const uint32_t s0 = atomic_load_explicit(&b->seq, memory_order_relaxed);
    atomic_store_explicit(&b->seq, s0 + 1u, memory_order_relaxed);
    atomic_thread_fence(memory_order_release); /* odd seq visible before the fields change */
    atomic_store_explicit(&b->n, t->n, memory_order_relaxed);
    for (uint32_t k = 0; k < t->n; k++) {
        const mca_track_t *tr = &t->body[k];
        const double x[MCA_DDS_TRACK_NUMS] = {tr->a[0],   tr->a[1], tr->a[2], tr->b[0], tr->b[1], tr->b[2],
                                              tr->radius, tr->v[0], tr->v[1], tr->v[2], tr->stamp};
        atomic_store_explicit(&b->id[k], tr->id, memory_order_relaxed);
        atomic_store_explicit(&b->kind[k], tr->kind, memory_order_relaxed);
        for (int i = 0; i < MCA_DDS_TRACK_NUMS; i++) {
            atomic_store_explicit(&b->x[k][i], x[i], memory_order_relaxed);
        }
    }
    atomic_store_explicit(&b->recv_ns, (int64_t)ts.tv_sec * 1000000000LL + ts.tv_nsec, memory_order_relaxed);
    atomic_store_explicit(&b->accepted, atomic_load_explicit(&b->accepted, memory_order_relaxed) + 1u,
                          memory_order_relaxed);
    atomic_store_explicit(&b->seq, s0 + 2u, memory_order_release);
}

int mca_dds_trackbox_read(const mca_dds_trackbox_t *b, mca_ros2_tracks_t *out) {
    for (int tries = 0; tries < 4; tries++) {
        const uint32_t s0 = atomic_load_explicit(&b->seq, memory_order_acquire);
        if (s0 & 1u) {
            continue;
        }
        const uint32_t n = atomic_load_explicit(&b->n, memory_order_relaxed);
        out->n = n <= MCA_MAX_TRACKS ? n : MCA_MAX_TRACKS;
        for (uint32_t k = 0; k < out->n; k++) {
            mca_track_t *tr = &out->body[k];
            double x[MCA_DDS_TRACK_NUMS];
            for (int i = 0; i < MCA_DDS_TRACK_NUMS; i++) {
                x[i] = atomic_load_explicit(&b->x[k][i], memory_order_relaxed);
            }
            tr->id = atomic_load_explicit(&b->id[k], memory_order_relaxed);
            tr->kind = atomic_load_explicit(&b->kind[k], memory_order_relaxed);
            for (int i = 0; i < 3; i++) {
                tr->a[i] = x[i];
                tr->b[i] = x[3 + i];
                tr->v[i] = x[7 + i];
            }
            tr->radius = x[6];
            tr->stamp = x[10];
        }
        out->recv_ns = atomic_load_explicit(&b->recv_ns, memory_order_relaxed);
        out->accepted = atomic_load_explicit(&b->accepted, memory_order_relaxed);
        atomic_thread_fence(memory_order_acquire); /* the fields read before seq is read again */
        if (atomic_load_explicit(&b->seq, memory_order_relaxed) == s0) {
            return MCA_OK;
        }
    }
    return MCA_EAGAIN;
}

static double ros_time_s(const builtin_interfaces_msg_dds__Time_ *t) {
    return (double)t->sec + 1e-9 * (double)t->nanosec;
}

/* Cyclone listener (its receive thread, non-rt): every new message of streamed bodies. */
static void on_tracks(dds_entity_t reader, void *arg) {
    mca_ros2_pub_t *r = arg;
    void *buf[1] = {NULL};
    dds_sample_info_t info[1];
    while (dds_take(reader, buf, info, 1, 1) > 0) {
        if (info[0].valid_data) {
            const mca_msgs_msg_dds__TrackedBodies_ *m = buf[0];
            mca_ros2_tracks_t t = {.n = m->bodies._length};
            int finite = 1;
            const double sent = ros_time_s(&m->header.stamp);
            for (uint32_t k = 0; k < t.n && k < MCA_MAX_TRACKS; k++) {
                const mca_msgs_msg_dds__TrackedBody_ *s = &m->bodies._buffer[k];
                mca_track_t *b = &t.body[k];
                b->id = s->id;
                b->kind = s->shape == 1 ? MCA_BODY_SPHERE : s->shape == 2 ? MCA_BODY_CAPSULE : -1;
                const double x[] = {s->a.x, s->a.y, s->a.z, s->b.x, s->b.y, s->b.z};
                const double v[] = {s->velocity.x, s->velocity.y, s->velocity.z};
                for (int i = 0; i < 3; i++) {
                    b->a[i] = x[i];
                    b->b[i] = s->shape == 2 ? x[3 + i] : x[i];
                    b->v[i] = v[i];
                    finite &= isfinite(x[i]) && isfinite(x[3 + i]) && isfinite(v[i]);
                }
                b->radius = s->radius;
                b->stamp = sent - ros_time_s(&s->stamp);
                finite &= isfinite(b->radius);
            }
            char why[160];
            if (mca_ros2_tracks_check(&r->cfg, m->header.frame_id, &t, finite, why, sizeof why) == MCA_OK) {
                accept_tracks(r, &t);
            } else {
                reject(r, -1, "%s", why);
            }
        }
        dds_return_loan(reader, buf, 1);
        buf[0] = NULL;
    }
}

static int create_tracks_reader(mca_ros2_pub_t *r, dds_entity_t pp, char *err, size_t errlen) {
    if (!r->cfg.tracks) {
        return MCA_OK;
    }
    char name[160];
    snprintf(name, sizeof name, "rt/%s/%s", r->cfg.cell, r->cfg.tracks_topic);
    dds_qos_t *q = dds_create_qos();
    dds_listener_t *l = dds_create_listener(r);
    if (q == NULL || l == NULL) {
        dds_delete_qos(q);
        dds_delete_listener(l);
        return MCA_ENOMEM;
    }
    /* as the targets: best effort, keep-last 1, only the latest picture counts */
    dds_qset_reliability(q, DDS_RELIABILITY_BEST_EFFORT, 0);
    dds_qset_history(q, DDS_HISTORY_KEEP_LAST, 1);
    dds_lset_data_available(l, on_tracks);
    const dds_entity_t t = dds_create_topic(pp, &mca_msgs_msg_dds__TrackedBodies__desc, name, q, NULL);
    r->tracks_reader = t > 0 ? dds_create_reader(pp, t, q, l) : t;
    dds_delete_qos(q);
    dds_delete_listener(l);
    if (r->tracks_reader < 0) {
        snprintf(err, errlen, "ros2: cannot create topic/reader '%s': %s", name,
                 dds_strretcode(r->tracks_reader));
        return MCA_EIO;
    }
    return MCA_OK;
}

/* Readers first: their listeners use r, which is freed after. */
static void delete_readers(mca_ros2_pub_t *r) {
    if (r->tracks_reader > 0) {
        dds_delete(r->tracks_reader);
        r->tracks_reader = 0;
    }
    for (int a = 0; a < MCA_MAX_ARMS; a++) {
        if (r->in[a].reader > 0) {
            dds_delete(r->in[a].reader);
            r->in[a].reader = 0;
        }
    }
}

int mca_dds_mailbox_read(const mca_dds_mailbox_t *b, int kind, mca_ros2_target_t *out) {
    for (int tries = 0; tries < 4; tries++) {
        const uint32_t s0 = atomic_load_explicit(&b->seq, memory_order_acquire);
        if (s0 & 1u) {
            continue;
        }
        for (int i = 0; i < 3; i++) {
            out->x[i] = atomic_load_explicit(&b->x[i], memory_order_relaxed);
        }
        out->recv_ns = atomic_load_explicit(&b->recv_ns, memory_order_relaxed);
        out->accepted = atomic_load_explicit(&b->accepted, memory_order_relaxed);
        atomic_thread_fence(memory_order_acquire); /* the fields read before seq is read again */
        if (atomic_load_explicit(&b->seq, memory_order_relaxed) == s0) {
            out->kind = kind;
            return MCA_OK;
        }
    }
    return MCA_EAGAIN;
}

int mca_ros2_pub_create(mca_ros2_pub_t **out, dds_entity_t pp, const mca_ros2_config_t *cfg,
                        mca_dds_mailbox_t *box, mca_dds_trackbox_t *tracks, char *err, size_t errlen) {
    char dummy[8];
    if (err == NULL) {
        err = dummy;
        errlen = sizeof dummy;
    }
    if (out == NULL || box == NULL || tracks == NULL) {
        return MCA_EINVAL;
    }
    int rc = mca_ros2_config_check(cfg, err, errlen);
    if (rc != MCA_OK) {
        return rc;
    }
    mca_ros2_pub_t *r = calloc(1, sizeof *r);
    if (r == NULL) {
        return MCA_ENOMEM;
    }
    pthread_mutex_init(&r->reject_lock, NULL);
    r->cfg = *cfg;
    r->box = box; /* not cleared: a restarted publisher keeps the last target and its age */
    r->tracks = tracks;
    const mca_ros2_config_t *c = &r->cfg;
    r->realtime_offset_ns = clock_ns(CLOCK_REALTIME) - clock_ns(CLOCK_MONOTONIC);
    for (uint32_t a = 0; a < c->n_arms; a++) {
        for (uint32_t j = 0; j < c->arm[a].n_dof; j++) {
            r->joint_ptr[a][j] = r->cfg.arm[a].joint_name[j];
        }
        snprintf(r->arm_frame[a], sizeof r->arm_frame[a], "%s/%s", cfg->arm[a].name, cfg->arm[a].root_link);
        snprintf(r->ns_links[a], sizeof r->ns_links[a], "%s/links", cfg->arm[a].name);
    }
    snprintf(r->hardware_id, sizeof r->hardware_id, "%s", cfg->cell);
    snprintf(r->diag_name, sizeof r->diag_name, "mcad: %s", cfg->cell);
    for (int k = 0; k < N_KV; k++) {
        r->kv[k].value = r->kv_value[k];
    }

    dds_qos_t *stream =
        mca_dds_qos_stream(); /* reliable, volatile: rclpy's default and sensor-data QoS match */
    dds_qos_t *latched = mca_dds_qos_status(); /* reliable, transient-local, keep-last 1 */
    char name[160];
    rc = stream && latched ? MCA_OK : MCA_ENOMEM;
    for (uint32_t a = 0; a < c->n_arms && c->joint_states && rc == MCA_OK; a++) {
        snprintf(name, sizeof name, "rt/%s/%s/joint_states", c->cell, c->arm[a].name);
        r->w_joints[a] = make_writer(pp, &sensor_msgs_msg_dds__JointState__desc, name, stream, err, errlen);
        rc = r->w_joints[a] < 0 ? MCA_EIO : MCA_OK;
    }
    if (rc == MCA_OK && c->markers) {
        snprintf(name, sizeof name, "rt/%s/distance_markers", c->cell);
        r->w_markers =
            make_writer(pp, &visualization_msgs_msg_dds__MarkerArray__desc, name, stream, err, errlen);
        rc = r->w_markers < 0 ? MCA_EIO : MCA_OK;
    }
    if (rc == MCA_OK && c->diagnostics) {
        r->w_diag = make_writer(pp, &diagnostic_msgs_msg_dds__DiagnosticArray__desc, "rt/diagnostics", stream,
                                err, errlen);
        rc = r->w_diag < 0 ? MCA_EIO : MCA_OK;
    }
    if (rc == MCA_OK) {
        rc = write_description_and_tf(r, pp, latched, err, errlen);
    }
    for (uint32_t a = 0; a < c->n_arms && rc == MCA_OK; a++) {
        rc = create_stream_reader(r, pp, (int)a, err, errlen);
    }
    if (rc == MCA_OK) {
        rc = create_tracks_reader(r, pp, err, errlen);
    }
    dds_delete_qos(stream);
    dds_delete_qos(latched);
    if (rc != MCA_OK) {
        delete_readers(r);
        pthread_mutex_destroy(&r->reject_lock);
        free(r); /* the writers are the participant's: deleted with it */
        return rc;
    }
    *out = r;
    return MCA_OK;
}

static void write_counted(dds_entity_t w, const void *msg, int *samples, uint64_t *errors) {
    if (dds_write(w, msg) < 0) {
        (*errors)++;
    } else {
        (*samples)++;
    }
}

/* zone colours: > d2 free (green), d1..d2 braking (amber), < d1 violated (red) */
static std_msgs_msg_dds__ColorRGBA_ zone_color(double d, double d1, double d2) {
    if (!(d < d2)) {
        return (std_msgs_msg_dds__ColorRGBA_){0.2f, 0.75f, 0.3f, 0.6f};
    }
    if (d >= d1) {
        return (std_msgs_msg_dds__ColorRGBA_){1.0f, 0.6f, 0.0f, 0.8f};
    }
    return (std_msgs_msg_dds__ColorRGBA_){1.0f, 0.0f, 0.0f, 0.9f};
}

/* the marker's z axis along u (any length > 0) */
static void orient_z(Marker *m, const double u_in[3]) {
    const double len = sqrt(u_in[0] * u_in[0] + u_in[1] * u_in[1] + u_in[2] * u_in[2]);
    if (len < 1e-12) {
        return; /* a point: any orientation */
    }
    const double u[3] = {u_in[0] / len, u_in[1] / len, u_in[2] / len};
    if (u[2] < -1.0 + 1e-12) {
        m->pose.orientation =
            (geometry_msgs_msg_dds__Quaternion_){1.0, 0.0, 0.0, 0.0}; /* half turn about x */
        return;
    }
    /* rotation z -> u: axis z x u, quaternion (z x u, 1 + z.u) normalised */
    const double x = -u[1], y = u[0], w = 1.0 + u[2];
    const double n = sqrt(x * x + y * y + w * w);
    m->pose.orientation = (geometry_msgs_msg_dds__Quaternion_){x / n, y / n, 0.0, w / n};
}

/* cylinder along p0 -> p1: pose at the middle, z axis along the segment */
static void cylinder_pose(Marker *m, const double p0[3], const double p1[3]) {
    const double u[3] = {p1[0] - p0[0], p1[1] - p0[1], p1[2] - p0[2]};
    m->pose.position =
        (geometry_msgs_msg_dds__Point_){0.5 * (p0[0] + p1[0]), 0.5 * (p0[1] + p1[1]), 0.5 * (p0[2] + p1[2])};
    m->scale.z = sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
    orient_z(m, u);
}

/* the quaternion of a rotation matrix (R[i][j]: world component i of axis j) */
static geometry_msgs_msg_dds__Quaternion_ quat_of(const double R[3][3]) {
    const double tr = R[0][0] + R[1][1] + R[2][2];
    double x, y, z, w;
    if (tr > 0.0) {
        const double k = 0.5 / sqrt(tr + 1.0);
        w = 0.25 / k;
        x = (R[2][1] - R[1][2]) * k;
        y = (R[0][2] - R[2][0]) * k;
        z = (R[1][0] - R[0][1]) * k;
    } else if (R[0][0] > R[1][1] && R[0][0] > R[2][2]) {
        const double k = 2.0 * sqrt(1.0 + R[0][0] - R[1][1] - R[2][2]);
        w = (R[2][1] - R[1][2]) / k;
        x = 0.25 * k;
        y = (R[0][1] + R[1][0]) / k;
        z = (R[0][2] + R[2][0]) / k;
    } else if (R[1][1] > R[2][2]) {
        const double k = 2.0 * sqrt(1.0 + R[1][1] - R[0][0] - R[2][2]);
        w = (R[0][2] - R[2][0]) / k;
        x = (R[0][1] + R[1][0]) / k;
        y = 0.25 * k;
        z = (R[1][2] + R[2][1]) / k;
    } else {
        const double k = 2.0 * sqrt(1.0 + R[2][2] - R[0][0] - R[1][1]);
        w = (R[1][0] - R[0][1]) / k;
        x = (R[0][2] + R[2][0]) / k;
        y = (R[1][2] + R[2][1]) / k;
        z = 0.25 * k;
    }
    return (geometry_msgs_msg_dds__Quaternion_){x, y, z, w};
}

/* The cell's fixed bodies as shapes (namespace "bodies", id = the body's index; a capsule's end caps id +
 * 100): a plane as a 2 m x 2 m slab 2 mm thick under its boundary, grey, half transparent. Returns markers
 * made. */
static uint32_t body_markers(mca_ros2_pub_t *r, uint32_t nm) {
    const mca_ros2_config_t *c = &r->cfg;
    const std_msgs_msg_dds__ColorRGBA_ grey = {0.6f, 0.6f, 0.65f, 0.5f};
    const uint32_t first = nm;
    for (uint32_t k = 0; k < c->n_bodies && k < MCA_MAX_BODIES; k++) {
        const mca_body_t *b = &c->body[k];
        Marker *m = &r->marker[nm];
        switch (b->kind) {
        case MCA_BODY_PLANE: {
            const double *n = b->u.plane.normal;
            const double len = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
            init_marker(m, c->world_frame, "bodies", (int32_t)k, MARKER_CUBE);
            orient_z(m, n);
            m->pose.position = (geometry_msgs_msg_dds__Point_){b->u.plane.point[0] - 0.001 * n[0] / len,
                                                               b->u.plane.point[1] - 0.001 * n[1] / len,
                                                               b->u.plane.point[2] - 0.001 * n[2] / len};
            m->scale.x = m->scale.y = 2.0;
            m->scale.z = 0.002;
            break;
        }
        case MCA_BODY_SPHERE:
            init_marker(m, c->world_frame, "bodies", (int32_t)k, MARKER_SPHERE);
            m->pose.position = (geometry_msgs_msg_dds__Point_){b->u.sphere.centre[0], b->u.sphere.centre[1],
                                                               b->u.sphere.centre[2]};
            m->scale.x = m->scale.y = m->scale.z = 2.0 * b->u.sphere.radius;
            break;
        case MCA_BODY_BOX:
            init_marker(m, c->world_frame, "bodies", (int32_t)k, MARKER_CUBE);
            m->pose.position =
                (geometry_msgs_msg_dds__Point_){b->u.box.centre[0], b->u.box.centre[1], b->u.box.centre[2]};
            m->pose.orientation = quat_of(b->u.box.R);
            m->scale.x = 2.0 * b->u.box.half[0];
            m->scale.y = 2.0 * b->u.box.half[1];
            m->scale.z = 2.0 * b->u.box.half[2];
            break;
        case MCA_BODY_CYLINDER: {
            const mca_body_cylinder_t *cy = &b->u.cylinder;
            init_marker(m, c->world_frame, "bodies", (int32_t)k, MARKER_CYLINDER);
            m->pose.position = (geometry_msgs_msg_dds__Point_){cy->centre[0], cy->centre[1], cy->centre[2]};
            orient_z(m, cy->axis);
            m->scale.x = m->scale.y = 2.0 * cy->radius;
            m->scale.z = 2.0 * cy->half_len;
            break;
        }
        case MCA_BODY_CAPSULE: {
            const mca_capsule_t *cp = &b->u.capsule;
            init_marker(m, c->world_frame, "bodies", (int32_t)k, MARKER_CYLINDER);
            cylinder_pose(m, cp->a, cp->b);
            m->scale.x = m->scale.y = 2.0 * cp->radius;
            m->color = grey;
            nm++;
            m = &r->marker[nm];
            init_marker(m, c->world_frame, "bodies", (int32_t)(k + 100), MARKER_SPHERE_LIST);
            r->pts[nm][0] = (geometry_msgs_msg_dds__Point_){cp->a[0], cp->a[1], cp->a[2]};
            r->pts[nm][1] = (geometry_msgs_msg_dds__Point_){cp->b[0], cp->b[1], cp->b[2]};
            m->points = (dds_sequence_geometry_msgs_msg_dds__Point_){2, 2, r->pts[nm], false};
            m->scale.x = m->scale.y = m->scale.z = 2.0 * cp->radius;
            break;
        }
        default:
            continue;
        }
        m->color = grey;
        nm++;
    }
    return nm - first;
}

int mca_ros2_pub_snapshot(mca_ros2_pub_t *r, const mca_dds_snapshot_t *s, uint64_t *errors) {
    const mca_ros2_config_t *c = &r->cfg;
    const builtin_interfaces_msg_dds__Time_ stamp = ros_time(r, s->stamp_ns);
    const uint32_t n_arms = s->n_arms < c->n_arms ? s->n_arms : c->n_arms;
    int samples = 0;
    for (uint32_t a = 0; a < n_arms && c->joint_states; a++) {
        const mca_dds_arm_snapshot_t *as = &s->arm[a];
        const uint32_t n = as->n_dof < c->arm[a].n_dof ? as->n_dof : c->arm[a].n_dof;
        const JointState js = {
            .header = {.stamp = stamp, .frame_id = ""},
            .name = {._maximum = n, ._length = n, ._buffer = r->joint_ptr[a], ._release = false},
            .position = {._maximum = n, ._length = n, ._buffer = (double *)as->position, ._release = false},
            .velocity = {._maximum = n, ._length = n, ._buffer = (double *)as->velocity, ._release = false},
            .effort = {._maximum = n, ._length = n, ._buffer = (double *)as->effort, ._release = false},
        };
        write_counted(r->w_joints[a], &js, &samples, errors);
    }
    if (!c->markers) {
        return samples;
    }
    /* each link's zone: its closest distance to any other arm, against that pair's thresholds */
    double link_d[MCA_MAX_ARMS][MCA_MAX_LINKS];
    double d1 = 0.0, d2 = 0.0;
    for (uint32_t a = 0; a < MCA_MAX_ARMS; a++) {
        for (int l = 0; l < MCA_MAX_LINKS; l++) {
            link_d[a][l] = INFINITY;
        }
    }
    for (uint32_t k = 0; k < s->n_pairs; k++) {
        const mca_dds_pair_snapshot_t *p = &s->pair[k];
        d1 = p->d1;
        d2 = p->d2;
        for (uint32_t l = 0; l < p->n_links_a && p->arm_a < MCA_MAX_ARMS; l++) {
            link_d[p->arm_a][l] = fmin(link_d[p->arm_a][l], p->link_distance_a[l]);
        }
        for (uint32_t l = 0; l < p->n_links_b && p->arm_b < MCA_MAX_ARMS; l++) {
            link_d[p->arm_b][l] = fmin(link_d[p->arm_b][l], p->link_distance_b[l]);
        }
    }
    uint32_t nm = 0;
    for (uint32_t a = 0; a < n_arms; a++) {
        const mca_dds_arm_snapshot_t *as = &s->arm[a];
        const uint32_t n_links = as->n_points >= 2 ? as->n_points - 1 : 0;
        for (uint32_t l = 0; l < n_links && l < c->arm[a].n_links; l++) {
            const double rad = c->arm[a].link_radius[l];
            const double dia = rad > 0.002 ? 2.0 * rad : 0.004; /* a bare axis still shows */
            const std_msgs_msg_dds__ColorRGBA_ col = zone_color(link_d[a][l], d1, d2);
            Marker *cyl = &r->marker[nm++];
            init_marker(cyl, c->world_frame, r->ns_links[a], (int32_t)(2 * l), MARKER_CYLINDER);
            cylinder_pose(cyl, as->point[l], as->point[l + 1]);
            cyl->scale.x = cyl->scale.y = dia;
            cyl->color = col;
            Marker *caps = &r->marker[nm];
            init_marker(caps, c->world_frame, r->ns_links[a], (int32_t)(2 * l + 1), MARKER_SPHERE_LIST);
            for (int e = 0; e < 2; e++) {
                const double *p = as->point[l + (uint32_t)e];
                r->pts[nm][e] = (geometry_msgs_msg_dds__Point_){p[0], p[1], p[2]};
            }
            caps->points = (dds_sequence_geometry_msgs_msg_dds__Point_){2, 2, r->pts[nm], false};
            caps->scale.x = caps->scale.y = caps->scale.z = dia;
            caps->color = col;
            nm++;
        }
    }
    for (uint32_t k = 0; k < s->n_pairs; k++) {
        const mca_dds_pair_snapshot_t *p = &s->pair[k];
        const std_msgs_msg_dds__ColorRGBA_ col = zone_color(p->min_distance, p->d1, p->d2);
        Marker *line = &r->marker[nm];
        init_marker(line, c->world_frame, "closest_points", (int32_t)k, MARKER_LINE_LIST);
        r->pts[nm][0] = (geometry_msgs_msg_dds__Point_){p->p[0], p->p[1], p->p[2]};
        r->pts[nm][1] = (geometry_msgs_msg_dds__Point_){p->e[0], p->e[1], p->e[2]};
        line->points = (dds_sequence_geometry_msgs_msg_dds__Point_){2, 2, r->pts[nm], false};
        line->scale.x = 0.005;
        line->color = (std_msgs_msg_dds__ColorRGBA_){col.r, col.g, col.b, 1.0f};
        nm++;
        Marker *txt = &r->marker[nm++];
        init_marker(txt, c->world_frame, "distances", (int32_t)k, MARKER_TEXT);
        txt->pose.position = (geometry_msgs_msg_dds__Point_){
            0.5 * (p->p[0] + p->e[0]), 0.5 * (p->p[1] + p->e[1]), 0.5 * (p->p[2] + p->e[2]) + 0.05};
        txt->scale.z = 0.04;
        txt->color = (std_msgs_msg_dds__ColorRGBA_){1.0f, 1.0f, 1.0f, 1.0f};
        /* %.17g: a subscriber reads the distance back exactly */
        char text[sizeof r->text[k]];
        snprintf(text, sizeof text, "%s-%s %.17g m", c->arm[p->arm_a % MCA_MAX_ARMS].name,
                 c->arm[p->arm_b % MCA_MAX_ARMS].name, p->min_distance);
        memcpy(r->text[k], text, sizeof text);
        txt->text = r->text[k];
    }
    nm += body_markers(r, nm);
    /* each body's closest link: a line from the body (Q) to the link's axis (P), in the body's margin colour
     * (namespace "body_closest", id = the body's index) */
    for (uint32_t i = 0; i < s->n_named && i < MCA_DDS_MAX_PAIR_ENTRIES; i++) {
        const mca_dds_named_pair_t *e = &s->named[i];
        if ((e->kind != MCA_DDS_PAIR_ARM_BODY && e->kind != MCA_DDS_PAIR_ARM_TRACK) || e->body < 0) {
            continue;
        }
        Marker *line = &r->marker[nm];
        init_marker(line, c->world_frame, "body_closest", (int32_t)e->body, MARKER_LINE_LIST);
        r->pts[nm][0] = (geometry_msgs_msg_dds__Point_){e->q[0], e->q[1], e->q[2]};
        r->pts[nm][1] = (geometry_msgs_msg_dds__Point_){e->p[0], e->p[1], e->p[2]};
        line->points = (dds_sequence_geometry_msgs_msg_dds__Point_){2, 2, r->pts[nm], false};
        line->scale.x = 0.004;
        const std_msgs_msg_dds__ColorRGBA_ col =
            zone_color(e->distance, e->clearance, e->clearance + (d2 > d1 ? d2 - d1 : 0.05));
        line->color = (std_msgs_msg_dds__ColorRGBA_){col.r, col.g, col.b, 1.0f};
        nm++;
    }
    for (uint32_t m = 0; m < nm; m++) {
        r->marker[m].header.stamp = stamp;
    }
    const MarkerArray ma = {
        .markers = {._maximum = nm, ._length = nm, ._buffer = r->marker, ._release = false}};
    write_counted(r->w_markers, &ma, &samples, errors);
    return samples;
}

static const char *state_name(int32_t s) {
    const char *name = mca_dds_state_name(s);
    return name ? name : "unknown";
}

int mca_ros2_pub_status(mca_ros2_pub_t *r, const mca_dds_ControllerStatus *st,
                        const mca_ros2_bridge_health_t *h, uint64_t *errors) {
    if (!r->cfg.diagnostics) {
        return 0;
    }
    int n = 0;
#define KV(k, ...)                                                                                           \
    do {                                                                                                     \
        r->kv[n].key = k;                                                                                    \
        snprintf(r->kv_value[n], sizeof r->kv_value[n], __VA_ARGS__);                                        \
        n++;                                                                                                 \
    } while (0)
    const builtin_interfaces_msg_dds__Time_ stamp = ros_time(r, st->stamp_ns);
    KV("state", "%s", state_name(st->state));
    KV("tick", "%llu", (unsigned long long)st->tick);
    KV("fault_code", "%d", st->fault_code);
    KV("fault", "%s", st->fault_text);
    KV("ticks", "%llu", (unsigned long long)st->ticks);
    KV("overruns", "%llu", (unsigned long long)st->overruns);
    KV("skipped_periods", "%llu", (unsigned long long)st->skipped_periods);
    KV("pdnn_budget_hits", "%llu", (unsigned long long)st->pdnn_budget_hits);
    KV("compute_p50_us", "%.1f", (double)st->compute_p50_ns / 1e3);
    KV("compute_p99_us", "%.1f", (double)st->compute_p99_ns / 1e3);
    KV("compute_max_us", "%.1f", (double)st->compute_max_ns / 1e3);
    KV("jitter_p50_us", "%.1f", (double)st->jitter_p50_ns / 1e3);
    KV("jitter_p99_us", "%.1f", (double)st->jitter_p99_ns / 1e3);
    KV("jitter_p999_us", "%.1f", (double)st->jitter_p999_ns / 1e3);
    KV("jitter_max_us", "%.1f", (double)st->jitter_max_ns / 1e3);
    KV("pdnn_steps", "%u", st->pdnn_steps);
    KV("pdnn_residual", "%.3g", st->pdnn_residual);
    KV("min_distance_so_far_m", "%.17g", st->min_distance_so_far);
    const builtin_interfaces_msg_dds__Time_ t_min = ros_time(r, st->min_distance_stamp_ns);
    KV("min_distance_stamp", "%d.%09u", t_min.sec, t_min.nanosec);
    KV("snapshots_dropped", "%llu", (unsigned long long)st->snapshots_dropped);
    KV("dds_bridge_restarts", "%llu", (unsigned long long)h->restarts);
    KV("dds_bridge_deaths", "%llu", (unsigned long long)h->deaths);
    /* this publisher was started after that many quick deaths in a row, that long after the last one */
    KV("dds_bridge_deaths_in_a_row", "%u", h->deaths_in_a_row);
    KV("dds_bridge_backoff_s", "%.1f", h->backoff_s);
    KV("dds_bridge_last_death", "%s", h->last_death);
    KV("dds_bridge_since_last_death_s", "%.1f", h->since_death_s);
    int streams = 0;
    uint64_t accepted = 0;
    for (uint32_t a = 0; a < r->cfg.n_arms; a++) {
        streams += r->cfg.stream[a] != MCA_ROS2_STREAM_NONE;
        accepted += atomic_load_explicit(&r->box[a].accepted, memory_order_relaxed);
    }
    if (r->cfg.tracks) {
        KV("tracks_accepted", "%llu",
           (unsigned long long)atomic_load_explicit(&r->tracks->accepted, memory_order_relaxed));
    }
    if (streams || r->cfg.tracks) {
        pthread_mutex_lock(&r->reject_lock);
        KV("stream_accepted", "%llu", (unsigned long long)accepted);
        KV("stream_rejected", "%llu", (unsigned long long)r->rejected);
        char last[sizeof r->last_reject];
        memcpy(last, r->last_reject, sizeof last);
        KV("stream_last_reject", "%s", last);
        pthread_mutex_unlock(&r->reject_lock);
    }
#undef KV
    const int fault = st->state == MCA_DDS_STATE_FAULT;
    /* a bridge that died lately (a peer that crashes it may still be there: it is restarted with a capped
     * back-off, and publishes nothing while down) is a warning; the controller itself is not affected */
    const int bridge_dying = h->since_death_s >= 0.0 && h->since_death_s < MCA_DDS_BRIDGE_STABLE_S;
    char bridge_note[96] = "";
    if (bridge_dying) {
        snprintf(bridge_note, sizeof bridge_note,
                 "; dds bridge restarted %llu times, last death %.1f s ago (%s)",
                 (unsigned long long)h->restarts, h->since_death_s, h->last_death);
    }
    snprintf(r->diag_message, sizeof r->diag_message, "%s%s%s%s", state_name(st->state),
             st->fault_text[0] ? ": " : "", st->fault_text, bridge_note);
    diagnostic_msgs_msg_dds__DiagnosticStatus_ ds = {
        .level = (uint8_t)(fault                                                ? DIAG_ERROR
                           : st->state == MCA_DDS_STATE_BRAKING || bridge_dying ? DIAG_WARN
                                                                                : DIAG_OK),
        .name = r->diag_name,
        .message = r->diag_message,
        .hardware_id = r->hardware_id,
        .values = {._maximum = (uint32_t)n, ._length = (uint32_t)n, ._buffer = r->kv, ._release = false},
    };
    const diagnostic_msgs_msg_dds__DiagnosticArray_ da = {
        .header = {.stamp = stamp, .frame_id = ""},
        .status = {._maximum = 1, ._length = 1, ._buffer = &ds, ._release = false},
    };
    int samples = 0;
    write_counted(r->w_diag, &da, &samples, errors);
    return samples;
}

int mca_ros2_pub_matched(const mca_ros2_pub_t *r, uint32_t n) {
    dds_entity_t w[2 * MCA_MAX_ARMS + 3];
    int nw = 0;
    for (uint32_t a = 0; a < r->cfg.n_arms; a++) {
        w[nw++] = r->w_joints[a];
        w[nw++] = r->w_desc[a];
    }
    w[nw++] = r->w_tf;
    w[nw++] = r->w_markers;
    w[nw++] = r->w_diag;
    for (int k = 0; k < nw; k++) {
        dds_publication_matched_status_t st;
        if (w[k] > 0 &&
            (dds_get_publication_matched_status(w[k], &st) != DDS_RETCODE_OK || st.current_count < n)) {
            return 0;
        }
    }
    return 1;
}

void mca_ros2_pub_destroy(mca_ros2_pub_t *r, dds_duration_t timeout) {
    if (r == NULL) {
        return;
    }
    delete_readers(r); /* no listener runs after this */
    const dds_entity_t w[] = {r->w_markers, r->w_diag};
    for (size_t k = 0; k < sizeof w / sizeof w[0]; k++) {
        if (w[k] > 0) {
            dds_wait_for_acks(w[k], timeout);
        }
    }
    for (uint32_t a = 0; a < r->cfg.n_arms; a++) {
        if (r->w_joints[a] > 0) {
            dds_wait_for_acks(r->w_joints[a], timeout);
        }
    }
    pthread_mutex_destroy(&r->reject_lock);
    free(r);
}
