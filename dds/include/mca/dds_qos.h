/* SPDX-License-Identifier: MIT */
/** @file mca/dds_qos.h
 * Shared Cyclone DDS set-up for mca publishers and subscribers (bridge, mca-monitor, tests), so both
 * ends use the same QoS (docs/dds.md). Context of every function: init / non-rt.
 */
#ifndef MCA_DDS_QOS_H
#define MCA_DDS_QOS_H

#include <stddef.h>
#include <stdio.h>

#include <dds/dds.h>

#include "mca/dds_log.h" /* mca_dds_log_fn */

#ifdef __cplusplus
extern "C" {
#endif

/** Largest domain id accepted (Cyclone's default port mapping ends at 232). */
#define MCA_DDS_MAX_DOMAIN 230

/** QoS of the 1 kHz streams (joint state, command, distances): reliable, keep-last 16, volatile.
 *  Caller frees with dds_delete_qos(). */
dds_qos_t *mca_dds_qos_stream(void);

/** QoS of the controller status: reliable, transient-local, keep-last 1 (late joiners get the current
 *  status). Caller frees with dds_delete_qos(). */
dds_qos_t *mca_dds_qos_status(void);

/**
 * A Cyclone DDS return code as an MCA code: the boundary where DDS codes stop (no mca_dds function returns a
 * dds_return_t mixed with MCA codes). BAD_PARAMETER -> MCA_EINVAL, OUT_OF_RESOURCES -> MCA_ENOMEM, TIMEOUT
 * -> MCA_ETIMEDOUT, UNSUPPORTED -> MCA_ENOTSUP, PRECONDITION_NOT_MET, ILLEGAL_OPERATION, NOT_ENABLED,
 * ALREADY_DELETED -> MCA_ESTATE, NO_DATA, TRY_AGAIN -> MCA_EAGAIN, any other error -> MCA_EIO; OK and a
 * handle (> 0) -> MCA_OK. Context: any.
 */
int mca_dds_rc(dds_return_t rc);

/**
 * Create a participant on domain_id. With config_path non-NULL the domain is first created from that
 * Cyclone XML file (its handle in *domain, to dds_delete() after the participant); otherwise
 * CYCLONEDDS_URI or the defaults apply and *domain is 0.
 * @param[out] participant  the participant's handle (unchanged on error)
 * @param[out] err          why it failed (Cyclone's reason included), errlen bytes; may be NULL
 * @retval MCA_OK
 * @retval MCA_EINVAL  NULL argument, domain id out of range
 * @retval MCA_ENOENT  config_path cannot be read
 * @retval MCA_EIO     Cyclone refused the config or the participant
 * @retval MCA_ENOMEM
 */
int mca_dds_open_participant(uint32_t domain_id, const char *config_path, dds_entity_t *participant,
                             dds_entity_t *domain, char *err, size_t errlen);

/** Publisher / subscriber of participant pp in DDS partition name (NULL = default partition), its handle in
 *  *out. @retval MCA_OK, else Cyclone's refusal through mca_dds_rc (err says why; may be NULL). */
int mca_dds_create_publisher(dds_entity_t pp, const char *partition, dds_entity_t *out, char *err,
                             size_t errlen);
int mca_dds_create_subscriber(dds_entity_t pp, const char *partition, dds_entity_t *out, char *err,
                              size_t errlen);

/**
 * Cyclone's warnings and errors (process-wide) into a bounded queue in memory instead of straight to stderr
 * from whichever thread hits them: the DDS publisher thread writing to a stderr nobody drains (a full pipe,
 * a slow journald) stalled publishing for 6 s while a link was down (one warning per failed send;
 * tests/dds/test_netns_faults.py). The sink never waits (a busy queue or a full one counts the message as
 * lost). Context: init. @param on 1: capture, 0: Cyclone's default sink (stderr) again.
 */
void mca_dds_log_capture(int on);

/** Hand the captured messages to @p log at @p level, one line each (a repeated one with "(and N times
 *  more)"), then how many were lost since the last drain; NULL log: they are dropped. The library prints
 *  nothing. Context: non-rt, one drainer at a time. @return messages drained */
int mca_dds_log_drain(int level, mca_dds_log_fn log, void *arg);

#ifdef __cplusplus
}
#endif
#endif
