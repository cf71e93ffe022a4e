/* SPDX-License-Identifier: MIT */
/* The types mca-record knows: every type mcad writes or reads on DDS (dds/ros2_msgs.idl, dds/mca_dds.idl),
 * each with its DDS type name, the idlc descriptor (to create a reader of that exact type: no type lookup,
 * the same type identifiers as mcad's), its ROS 2 name and its ROS 2 message definition (the .msg text and,
 * after it, the text of every message it uses: what ROS 2 bags store as an MCAP schema of encoding
 * "ros2msg"). Context: non-rt. */
#ifndef MCA_RECORD_MSGDEFS_H
#define MCA_RECORD_MSGDEFS_H

#include <stddef.h>

#include <dds/dds.h>

typedef struct rec_type {
    const dds_topic_descriptor_t
        *desc;            /**< idlc's descriptor (m_typename: "sensor_msgs::msg::dds_::JointState_") */
    const char *ros_name; /**< "sensor_msgs/msg/JointState"; mcad's own: "mca_dds/msg/JointState" */
} rec_type_t;

/** The known type of DDS type name name, or NULL. */
const rec_type_t *rec_type_find(const char *dds_name);

/** All known types: *n of them. */
const rec_type_t *rec_types(size_t *n);

/** The full ros2msg definition of ROS 2 type ros_name (malloc'd, the caller frees), NULL if unknown. */
char *rec_msgdef_full(const char *ros_name);

#endif
