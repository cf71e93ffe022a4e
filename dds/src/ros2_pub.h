/* SPDX-License-Identifier: MIT */
/* The bridge's ROS 2 writers (mca/ros2.h). Internal to mca_dds: called by the bridge only, from its
 * create/destroy (init) and its publisher thread (non-rt). */
#ifndef MCA_ROS2_PUB_H
#define MCA_ROS2_PUB_H

#include <dds/dds.h>

#include "mca/dds_bridge.h"
#include "mca/ros2.h"
#include "dds_shm.h" /* mca_dds_mailbox_t */
#include "mca_dds.h" /* mca_dds_ControllerStatus */

typedef struct mca_ros2_pub mca_ros2_pub_t;

/** Writers on participant pp (accepted streamed bodies go to tracks, also not cleared) (default partition, as
 * ROS 2 uses); robot_description and /tf_static are written here, once. Accepted stream targets go to
 * box[arm] (the bridge's, MCA_MAX_ARMS of them; not cleared here: a restarted publisher continues them).
 * @retval MCA_OK, MCA_EINVAL (bad config: err says which field), MCA_ENOENT (URDF unreadable), MCA_EIO
 * (Cyclone refused), MCA_ENOMEM */
int mca_ros2_pub_create(mca_ros2_pub_t **out, dds_entity_t pp, const mca_ros2_config_t *cfg,
                        mca_dds_mailbox_t *box, mca_dds_trackbox_t *tracks, char *err, size_t errlen);

/** Joint states and markers of one snapshot. Returns the samples written; *errors counts failures. */
int mca_ros2_pub_snapshot(mca_ros2_pub_t *r, const mca_dds_snapshot_t *s, uint64_t *errors);

/** The bridge process's own health as its supervisor recorded it (dds_shm.h), for /diagnostics. */
typedef struct mca_ros2_bridge_health {
    uint64_t restarts;        /**< publishers started after a death */
    uint64_t deaths;          /**< publishers that died */
    uint32_t deaths_in_a_row; /**< the series the running publisher was started in (0: none) */
    double backoff_s;         /**< the back-off before this publisher's start */
    double since_death_s;     /**< since the last death [s]; < 0: none */
    const char *last_death;   /**< its cause ("signal 11 (SIGSEGV)"), "" if none */
} mca_ros2_bridge_health_t;

/** /diagnostics from the status just written on mca/controller_status, with the bridge's health: a death
 *  within the last MCA_DDS_BRIDGE_STABLE_S makes the level WARN (the controller's state decides otherwise).
 */
int mca_ros2_pub_status(mca_ros2_pub_t *r, const mca_dds_ControllerStatus *st,
                        const mca_ros2_bridge_health_t *h, uint64_t *errors);

/** Writers matched to at least n readers each (for tests). */
int mca_ros2_pub_matched(const mca_ros2_pub_t *r, uint32_t n);

/** Waits up to timeout for reliable readers' acks of the last samples, then frees (writers die with the
 *  participant). NULL is ignored. */
void mca_ros2_pub_destroy(mca_ros2_pub_t *r, dds_duration_t timeout);

#endif
