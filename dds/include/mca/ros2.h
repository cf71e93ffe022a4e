/* SPDX-License-Identifier: MIT */
/** @file mca/ros2.h
 * ROS 2-native topics of the DDS bridge (docs/ros2.md): the standard ROS 2 message types under ROS 2's DDS
 * naming (topic rt/<name>, type <pkg>::msg::dds_::<Type>_, dds/ros2_msgs.idl), written by the bridge's
 * publisher thread from the same snapshots as the mca/ topics. No ROS library is linked.
 *
 *   /<cell>/<arm>/joint_states        sensor_msgs/msg/JointState         every published snapshot
 *   /<cell>/<arm>/robot_description   std_msgs/msg/String (URDF text)    once, transient-local
 *   /tf_static                        tf2_msgs/msg/TFMessage             once, transient-local: world ->
 *                                                                        <arm>/<URDF root link> per arm
 *   /<cell>/distance_markers          visualization_msgs/msg/MarkerArray every published snapshot
 *   /diagnostics                      diagnostic_msgs/msg/DiagnosticArray with every mca/controller_status
 *
 * Stamps are ROS time (CLOCK_REALTIME): the snapshot's CLOCK_MONOTONIC stamp plus the offset between the
 * two clocks taken once when the bridge starts, so that samples of one tick carry one stamp.
 */
#ifndef MCA_ROS2_H
#define MCA_ROS2_H

#include <stddef.h>
#include <stdint.h>

#include "mca/chain.h" /* mca_pose_t */
#include "mca/limits.h"

#ifdef __cplusplus
extern "C" {
#endif

/** Longest ROS 2 name part (cell, arm) accepted, bytes without NUL. */
#define MCA_ROS2_NAME_MAX 31

/** One arm as ROS 2 sees it. */
typedef struct mca_ros2_arm {
    char name[MCA_ROS2_NAME_MAX + 1]; /**< topic namespace /<cell>/<name>/ and TF prefix <name>/ */
    uint32_t n_dof;
    char joint_name[MCA_MAX_DOF][64]; /**< URDF joint names, in the order of the snapshot's joints */
    char root_link[64];               /**< URDF root link: TF child frame <name>/<root_link> */
    char urdf_path[512];              /**< robot_description is this file's text (read at create) */
    mca_pose_t base;                  /**< world <- root link */
    uint32_t n_links;                 /**< capsules (n_dof + 1) */
    double link_radius[MCA_MAX_LINKS];
} mca_ros2_arm_t;

/** What to publish (every topic optional, all on by default). */
typedef struct mca_ros2_config {
    int enabled;
    char cell[MCA_ROS2_NAME_MAX + 1]; /**< topic namespace /<cell>/ */
    char world_frame[32];             /**< frame of markers and of the TF parents ("world") */
    int joint_states, robot_description, tf_static, markers, diagnostics;
    uint32_t n_arms;
    mca_ros2_arm_t arm[MCA_MAX_ARMS];
} mca_ros2_config_t;

/** Off, every topic selected, world frame "world", no arms. Context: any. */
void mca_ros2_config_default(mca_ros2_config_t *cfg);

/**
 * Check names against ROS 2's rules (a letter first, then letters, digits and '_'), counts and radii.
 * @param[out] err  "ros2.FIELD: reason" on error
 * @retval MCA_OK @retval MCA_EINVAL
 */
int mca_ros2_config_check(const mca_ros2_config_t *cfg, char *err, size_t errlen);

#ifdef __cplusplus
}
#endif
#endif
