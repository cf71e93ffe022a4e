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
 * In (a cell's `stream` task, per arm one of):
 *   /<cell>/<arm>/target_twist        geometry_msgs/msg/TwistStamped     tool-tip velocity (linear part)
 *   /<cell>/<arm>/target_pose         geometry_msgs/msg/PoseStamped      tool-tip position target
 *   /<cell>/<topic>                   mca_msgs/msg/TrackedBodies         streamed bodies (a person, a foreign
 *                                                                        machine: streamed_bodies, DDS
 * Security cells only; docs/dds.md) read best-effort, keep-last 1 (matches reliable and best-effort
 * publishers). Each message is checked where it arrives (a Cyclone thread, non-rt): NaN or infinity, a
 * frame_id other than the world frame, a linear speed above stream_max_speed, a position outside the
 * workspace box are rejected and counted (the count and the last reason go out on /diagnostics); an accepted
 * one replaces the arm's target in a seqlock mailbox that the loop reads without waiting
 * (mca_dds_bridge_stream_target).
 *
 * Stamps are ROS time (CLOCK_REALTIME): the snapshot's CLOCK_MONOTONIC stamp plus the offset between the
 * two clocks taken once when the bridge starts, so that samples of one tick carry one stamp.
 */
#ifndef MCA_ROS2_H
#define MCA_ROS2_H

#include <stddef.h>
#include <stdint.h>

#include "mca/chain.h" /* mca_pose_t */
#include "mca/body.h"  /* mca_body_t: the fixed bodies drawn */
#include "mca/limits.h"
#include "mca/track.h" /* mca_track_t, MCA_MAX_TRACKS */

#ifdef __cplusplus
extern "C" {
#endif

/** Longest ROS 2 name part (cell, arm) accepted, bytes without NUL. */
#define MCA_ROS2_NAME_MAX 31

/** What an arm's stream carries. */
typedef enum mca_ros2_stream_kind {
    MCA_ROS2_STREAM_NONE = 0,
    MCA_ROS2_STREAM_TWIST = 1, /**< geometry_msgs/TwistStamped on /<cell>/<arm>/target_twist */
    MCA_ROS2_STREAM_POSE = 2,  /**< geometry_msgs/PoseStamped on /<cell>/<arm>/target_pose */
} mca_ros2_stream_kind_t;

/** The latest accepted target of one arm's stream. */
typedef struct mca_ros2_target {
    int kind;          /**< mca_ros2_stream_kind_t */
    double x[3];       /**< twist: linear velocity [m/s]; pose: position [m]; world frame */
    int64_t recv_ns;   /**< CLOCK_MONOTONIC when it was accepted */
    uint64_t accepted; /**< targets accepted so far (0: none yet, x is zero) */
} mca_ros2_target_t;

/** The latest accepted message of streamed bodies. */
typedef struct mca_ros2_tracks {
    uint32_t n;                       /**< bodies in it */
    mca_track_t body[MCA_MAX_TRACKS]; /**< stamp: how old each was when the message was sent [s] (its header
                                           stamp minus the body's own, >= 0) */
    int64_t recv_ns;                  /**< CLOCK_MONOTONIC when it was accepted */
    uint64_t accepted;                /**< messages accepted so far (0: none yet) */
} mca_ros2_tracks_t;

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
    int stream[MCA_MAX_ARMS];    /**< mca_ros2_stream_kind_t of each arm (NONE: no subscription) */
    double stream_max_speed;     /**< twists faster than this are rejected [m/s] */
    double box_lo[3], box_hi[3]; /**< workspace box (world): pose targets outside are rejected */
    uint32_t n_arms;
    mca_ros2_arm_t arm[MCA_MAX_ARMS];
    int tracks;                               /**< 1: read streamed bodies (mca_msgs/TrackedBodies) */
    char tracks_topic[MCA_ROS2_NAME_MAX + 1]; /**< on /<cell>/<tracks_topic> */
    uint32_t max_tracks; /**< a message with more bodies is rejected (<= MCA_MAX_TRACKS) */
    uint32_t n_bodies;   /**< the cell's fixed bodies, drawn among the markers (their shapes, namespace
                              "bodies", and a line to each one's closest link, "body_closest") */
    mca_body_t body[MCA_MAX_BODIES];
} mca_ros2_config_t;

/** 1 when s is a ROS 2 name token: a letter, then letters, digits and single '_', not ending in '_'.
 *  Context: any. */
int mca_ros2_name_ok(const char *s);

/** Off, every topic selected, world frame "world", no arms. Context: any. */
void mca_ros2_config_default(mca_ros2_config_t *cfg);

/**
 * Check names against ROS 2's rules (a letter first, then letters, digits and '_'), counts and radii.
 * @param[out] err  "ros2.FIELD: reason" on error
 * @retval MCA_OK @retval MCA_EINVAL
 */
int mca_ros2_config_check(const mca_ros2_config_t *cfg, char *err, size_t errlen);

/**
 * The check every received target goes through before it can reach the loop: non-finite numbers (finite =
 * 0: the caller saw NaN or infinity anywhere in the message), a frame_id other than cfg->world_frame (NULL
 * counts as ""), for a twist arm a speed |x| above stream_max_speed, for a pose arm a position outside the
 * box. Context: any (no allocation). @param[out] why the reason on rejection
 * @retval MCA_OK accept @retval MCA_ERANGE reject @retval MCA_EINVAL NULL cfg or x, arm without a stream
 */
int mca_ros2_target_check(const mca_ros2_config_t *cfg, int arm, const char *frame_id, const double x[3],
                          int finite, char *why, size_t len);

/**
 * The check every received message of streamed bodies goes through before it can reach the loop: finite
 * numbers (finite = 0: the caller saw NaN or infinity anywhere), the world frame, at most max_tracks bodies,
 * each a sphere or capsule with a radius in 0..2 m, a speed up to 10 m/s, within 100 m of the world's origin
 * and seen 0..10 s before the message was sent (body[k].stamp). Context: any (no allocation).
 * @retval MCA_OK accept @retval MCA_ERANGE reject (why says why) @retval MCA_EINVAL NULL, no tracks
 */
int mca_ros2_tracks_check(const mca_ros2_config_t *cfg, const char *frame_id, const mca_ros2_tracks_t *t,
                          int finite, char *why, size_t len);

#ifdef __cplusplus
}
#endif
#endif
