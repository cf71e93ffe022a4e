/* SPDX-License-Identifier: MIT */
/* mca-record's types (msgdefs.h). The ROS 2 definitions are the fields and constants of ROS 2 Jazzy's .msg
 * files (comments left out), type for type as dds/ros2_msgs.idl; tests/record checks each one against
 * rosbags' own ROS 2 Jazzy type store. mcad's own types (dds/mca_dds.idl) get the ROS 2 package name
 * mca_dds: the same fields in the same order (a key is a plain field, sequence<double, 8> is
 * float64[<=8], string<64> is string<=64), so that the CDR a ROS 2 tool decodes with it is what mcad
 * wrote. */
#include "msgdefs.h"

#include <stdlib.h>
#include <string.h>

#include "mca_dds.h"   /* mca_dds_*_desc */
#include "ros2_msgs.h" /* <pkg>_msg_dds__<Type>__desc */

typedef struct msgdef {
    const char *name;     /* "std_msgs/msg/Header" */
    const char *text;     /* its fields and constants, one a line */
    const char *deps[10]; /* the types its fields use */
} msgdef_t;

static const msgdef_t defs[] = {
    {"builtin_interfaces/msg/Time", "int32 sec\nuint32 nanosec\n", {NULL}},
    {"builtin_interfaces/msg/Duration", "int32 sec\nuint32 nanosec\n", {NULL}},
    {"std_msgs/msg/Header",
     "builtin_interfaces/Time stamp\nstring frame_id\n",
     {"builtin_interfaces/msg/Time"}},
    {"std_msgs/msg/String", "string data\n", {NULL}},
    {"std_msgs/msg/ColorRGBA", "float32 r\nfloat32 g\nfloat32 b\nfloat32 a\n", {NULL}},
    {"geometry_msgs/msg/Point", "float64 x\nfloat64 y\nfloat64 z\n", {NULL}},
    {"geometry_msgs/msg/Vector3", "float64 x\nfloat64 y\nfloat64 z\n", {NULL}},
    {"geometry_msgs/msg/Quaternion", "float64 x 0\nfloat64 y 0\nfloat64 z 0\nfloat64 w 1\n", {NULL}},
    {"geometry_msgs/msg/Pose",
     "geometry_msgs/Point position\ngeometry_msgs/Quaternion orientation\n",
     {"geometry_msgs/msg/Point", "geometry_msgs/msg/Quaternion"}},
    {"geometry_msgs/msg/PoseStamped",
     "std_msgs/Header header\ngeometry_msgs/Pose pose\n",
     {"std_msgs/msg/Header", "geometry_msgs/msg/Pose"}},
    {"geometry_msgs/msg/Twist",
     "geometry_msgs/Vector3 linear\ngeometry_msgs/Vector3 angular\n",
     {"geometry_msgs/msg/Vector3"}},
    {"geometry_msgs/msg/TwistStamped",
     "std_msgs/Header header\ngeometry_msgs/Twist twist\n",
     {"std_msgs/msg/Header", "geometry_msgs/msg/Twist"}},
    {"geometry_msgs/msg/Transform",
     "geometry_msgs/Vector3 translation\ngeometry_msgs/Quaternion rotation\n",
     {"geometry_msgs/msg/Vector3", "geometry_msgs/msg/Quaternion"}},
    {"geometry_msgs/msg/TransformStamped",
     "std_msgs/Header header\nstring child_frame_id\ngeometry_msgs/Transform transform\n",
     {"std_msgs/msg/Header", "geometry_msgs/msg/Transform"}},
    {"tf2_msgs/msg/TFMessage",
     "geometry_msgs/TransformStamped[] transforms\n",
     {"geometry_msgs/msg/TransformStamped"}},
    {"sensor_msgs/msg/JointState",
     "std_msgs/Header header\nstring[] name\nfloat64[] position\nfloat64[] velocity\nfloat64[] effort\n",
     {"std_msgs/msg/Header"}},
    {"sensor_msgs/msg/CompressedImage",
     "std_msgs/Header header\nstring format\nuint8[] data\n",
     {"std_msgs/msg/Header"}},
    {"visualization_msgs/msg/UVCoordinate", "float32 u\nfloat32 v\n", {NULL}},
    {"visualization_msgs/msg/MeshFile", "string filename\nuint8[] data\n", {NULL}},
    {"visualization_msgs/msg/Marker",
     "int32 ARROW=0\nint32 CUBE=1\nint32 SPHERE=2\nint32 CYLINDER=3\nint32 LINE_STRIP=4\nint32 LINE_LIST=5\n"
     "int32 CUBE_LIST=6\nint32 SPHERE_LIST=7\nint32 POINTS=8\nint32 TEXT_VIEW_FACING=9\n"
     "int32 MESH_RESOURCE=10\nint32 TRIANGLE_LIST=11\nint32 ARROW_STRIP=12\n"
     "int32 ADD=0\nint32 MODIFY=0\nint32 DELETE=2\nint32 DELETEALL=3\n"
     "std_msgs/Header header\nstring ns\nint32 id\nint32 type\nint32 action\ngeometry_msgs/Pose pose\n"
     "geometry_msgs/Vector3 scale\nstd_msgs/ColorRGBA color\nbuiltin_interfaces/Duration lifetime\n"
     "bool frame_locked\ngeometry_msgs/Point[] points\nstd_msgs/ColorRGBA[] colors\nstring texture_resource\n"
     "sensor_msgs/CompressedImage texture\nvisualization_msgs/UVCoordinate[] uv_coordinates\nstring text\n"
     "string mesh_resource\nvisualization_msgs/MeshFile mesh_file\nbool mesh_use_embedded_materials\n",
     {"std_msgs/msg/Header", "geometry_msgs/msg/Pose", "geometry_msgs/msg/Vector3", "std_msgs/msg/ColorRGBA",
      "builtin_interfaces/msg/Duration", "geometry_msgs/msg/Point", "sensor_msgs/msg/CompressedImage",
      "visualization_msgs/msg/UVCoordinate", "visualization_msgs/msg/MeshFile"}},
    {"visualization_msgs/msg/MarkerArray",
     "visualization_msgs/Marker[] markers\n",
     {"visualization_msgs/msg/Marker"}},
    {"diagnostic_msgs/msg/KeyValue", "string key\nstring value\n", {NULL}},
    {"diagnostic_msgs/msg/DiagnosticStatus",
     "byte OK=0\nbyte WARN=1\nbyte ERROR=2\nbyte STALE=3\nbyte level\nstring name\nstring message\n"
     "string hardware_id\ndiagnostic_msgs/KeyValue[] values\n",
     {"diagnostic_msgs/msg/KeyValue"}},
    {"diagnostic_msgs/msg/DiagnosticArray",
     "std_msgs/Header header\ndiagnostic_msgs/DiagnosticStatus[] status\n",
     {"std_msgs/msg/Header", "diagnostic_msgs/msg/DiagnosticStatus"}},
    /* mcad's own (dds/mca_dds.idl) */
    {"mca_dds/msg/JointState",
     "uint8 arm_id\nuint64 tick\nint64 stamp_ns\nfloat64[<=8] position\nfloat64[<=8] velocity\n"
     "float64[<=8] effort\n",
     {NULL}},
    {"mca_dds/msg/JointCommand",
     "uint8 arm_id\nuint64 tick\nint64 stamp_ns\nfloat64[<=8] velocity_setpoint\n"
     "float64[<=8] position_reference\nstring<=32 frame_id\n",
     {NULL}},
    {"mca_dds/msg/Distances",
     "uint8 pair_id\nuint8 arm_a\nuint8 arm_b\nuint64 tick\nint64 stamp_ns\nfloat64 min_distance\n"
     "float64[3] p\nfloat64[3] e\nint16 link_a\nint16 link_b\nfloat64 d1\nfloat64 d2\nfloat64 brake_factor\n"
     "float64[<=9] link_distance_a\nfloat64[<=9] link_distance_b\n",
     {NULL}},
    {"mca_dds/msg/ControllerStatus",
     "int32 STATE_INIT=0\nint32 STATE_READY=1\nint32 STATE_RUNNING=2\nint32 STATE_BRAKING=3\n"
     "int32 STATE_STOPPED=4\nint32 STATE_FAULT=5\n"
     "uint8 controller_id\nuint64 tick\nint64 stamp_ns\nint32 state\nint32 fault_code\nstring<=64 "
     "fault_text\n"
     "uint64 ticks\nuint64 overruns\nuint64 skipped_periods\nint64 compute_p50_ns\nint64 compute_p99_ns\n"
     "int64 compute_max_ns\nint64 jitter_p50_ns\nint64 jitter_p99_ns\nint64 jitter_p999_ns\n"
     "int64 jitter_max_ns\nuint32 pdnn_steps\nfloat64 pdnn_residual\nfloat64 min_distance_so_far\n"
     "int64 min_distance_stamp_ns\nuint64 snapshots_dropped\nuint64 pdnn_budget_hits\n",
     {NULL}},
};

static const rec_type_t types[] = {
    {&sensor_msgs_msg_dds__JointState__desc, "sensor_msgs/msg/JointState"},
    {&std_msgs_msg_dds__String__desc, "std_msgs/msg/String"},
    {&tf2_msgs_msg_dds__TFMessage__desc, "tf2_msgs/msg/TFMessage"},
    {&visualization_msgs_msg_dds__MarkerArray__desc, "visualization_msgs/msg/MarkerArray"},
    {&diagnostic_msgs_msg_dds__DiagnosticArray__desc, "diagnostic_msgs/msg/DiagnosticArray"},
    {&geometry_msgs_msg_dds__TwistStamped__desc, "geometry_msgs/msg/TwistStamped"},
    {&geometry_msgs_msg_dds__PoseStamped__desc, "geometry_msgs/msg/PoseStamped"},
    {&mca_dds_JointState_desc, "mca_dds/msg/JointState"},
    {&mca_dds_JointCommand_desc, "mca_dds/msg/JointCommand"},
    {&mca_dds_Distances_desc, "mca_dds/msg/Distances"},
    {&mca_dds_ControllerStatus_desc, "mca_dds/msg/ControllerStatus"},
};

const rec_type_t *rec_type_find(const char *dds_name) {
    for (size_t i = 0; i < sizeof types / sizeof types[0]; ++i) {
        if (strcmp(types[i].desc->m_typename, dds_name) == 0) {
            return &types[i];
        }
    }
    return NULL;
}

const rec_type_t *rec_types(size_t *n) {
    *n = sizeof types / sizeof types[0];
    return types;
}

static const msgdef_t *def_find(const char *name) {
    for (size_t i = 0; i < sizeof defs / sizeof defs[0]; ++i) {
        if (strcmp(defs[i].name, name) == 0) {
            return &defs[i];
        }
    }
    return NULL;
}

enum { N_DEFS = sizeof defs / sizeof defs[0] };

/* The dependencies of d, depth first, each once (seen[] over defs). */
static void collect(const msgdef_t *d, int *seen, const msgdef_t **order, size_t *n) {
    for (size_t k = 0; k < sizeof d->deps / sizeof d->deps[0] && d->deps[k] != NULL; ++k) {
        const msgdef_t *dep = def_find(d->deps[k]);
        if (dep == NULL || seen[dep - defs]) {
            continue;
        }
        seen[dep - defs] = 1;
        order[(*n)++] = dep;
        collect(dep, seen, order, n);
    }
}

char *rec_msgdef_full(const char *ros_name) {
    const msgdef_t *top = def_find(ros_name);
    if (top == NULL) {
        return NULL;
    }
    int seen[N_DEFS] = {0};
    const msgdef_t *order[N_DEFS];
    size_t n = 0;
    seen[top - defs] = 1;
    collect(top, seen, order, &n);
    /* as rosbag2 writes it: the type's text, then per dependency a line of 80 '=', "MSG: pkg/Type", its
     * text */
    static const char sep[] =
        "================================================================================\n";
    size_t len = strlen(top->text) + 1;
    for (size_t i = 0; i < n; ++i) {
        len += sizeof sep + strlen("MSG: \n") + strlen(order[i]->name) + strlen(order[i]->text);
    }
    char *out = malloc(len);
    if (out == NULL) {
        return NULL;
    }
    char *p = out;
    p += sprintf(p, "%s", top->text);
    for (size_t i = 0; i < n; ++i) {
        /* "pkg/msg/Type" is written "pkg/Type", as in .msg files and rosbag2 */
        const char *slash = strchr(order[i]->name, '/');
        p += sprintf(p, "%sMSG: %.*s%s\n%s", sep, (int)(slash - order[i]->name + 1), order[i]->name,
                     slash + strlen("/msg/"), order[i]->text);
    }
    return out;
}
