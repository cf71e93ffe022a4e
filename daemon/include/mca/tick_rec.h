/* SPDX-License-Identifier: MIT */
/** @file mca/tick_rec.h
 * The recording of a run (mcad --record FILE): what the controller read each tick, bit for bit, and what it
 * commanded, so that the run can be played into the loop again (the replay backend, docs/daemon.md
 * "Recording and replay"). Binary, in the host's byte order and this header's struct layout: one
 * mca_tick_rec_header_t (the arms, the period and the sample the start-up handshake took), then one
 * mca_tick_rec_t per tick. A reader checks the magic, the version and both struct sizes.
 *
 * Context: non-rt (writes and reads a FILE; the reader allocates at open). mcad's real-time loop only fills
 * the record's data and pushes it into its CSV ring; the service thread writes it.
 */
#ifndef MCA_TICK_REC_H
#define MCA_TICK_REC_H

#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#include "mca/limits.h" /* MCA_MAX_ARMS, MCA_MAX_DOF */

#ifdef __cplusplus
extern "C" {
#endif

#define MCA_TICK_REC_MAGIC "mca-rec\n" /**< 8 bytes, no terminator in the file */
#define MCA_TICK_REC_VERSION 1u

/** The file's first bytes. */
typedef struct mca_tick_rec_header {
    char magic[8];        /**< MCA_TICK_REC_MAGIC */
    uint32_t version;     /**< MCA_TICK_REC_VERSION */
    uint32_t header_size; /**< sizeof(mca_tick_rec_header_t) */
    uint32_t rec_size;    /**< sizeof(mca_tick_rec_t) */
    uint32_t n_arms;
    uint32_t dof[MCA_MAX_ARMS];
    int64_t period_ns;
    /** the feedback the start-up handshake took (the coordination plan starts from it) */
    double q0[MCA_MAX_ARMS][MCA_MAX_DOF];
    double v0[MCA_MAX_ARMS][MCA_MAX_DOF];
} mca_tick_rec_header_t;

/** One tick: the feedback the controller read (after the daemon's checks), then what the tick sent. */
typedef struct mca_tick_rec {
    double t;         /**< the tick's task time [s] */
    int64_t stamp_ns; /**< the tick's wake-up (virtual time: the virtual clock) */
    int32_t state;    /**< mca_daemon_state_t after the tick */
    uint32_t fresh;   /**< bit a: arm a's feedback of this tick was new and taken (else a lost cycle) */
    int32_t arm_state[MCA_MAX_ARMS];            /**< mca_arm_state_t of the feedback */
    uint32_t fault_code[MCA_MAX_ARMS];          /**< enum mca_arm_fault of the feedback */
    int64_t fb_stamp_ns[MCA_MAX_ARMS];          /**< the feedback's receive stamp */
    double q[MCA_MAX_ARMS][MCA_MAX_DOF];        /**< positions the controller read [rad] */
    double v[MCA_MAX_ARMS][MCA_MAX_DOF];        /**< measured velocities it read [rad/s] */
    double qdot_cmd[MCA_MAX_ARMS][MCA_MAX_DOF]; /**< the velocities commanded this tick [rad/s] */
} mca_tick_rec_t;

/** Write the header (magic, version and sizes filled in here). @retval 0 or -1 (errno) */
int mca_tick_rec_write_header(FILE *f, const mca_tick_rec_header_t *h);

/** Write one record. @retval 0 or -1 (errno) */
int mca_tick_rec_write(FILE *f, const mca_tick_rec_t *r);

/** A recording read whole into memory. */
typedef struct mca_tick_rec_file {
    mca_tick_rec_header_t header;
    size_t n;            /**< records */
    mca_tick_rec_t *rec; /**< n of them */
} mca_tick_rec_file_t;

/**
 * Read a recording. A last record cut short (a killed mcad) is left out.
 * @retval MCA_OK       *out filled (mca_tick_rec_free() it)
 * @retval MCA_ENOENT   cannot open (err says why)
 * @retval MCA_EPARSE   not a recording of this version and layout (err says what differs)
 * @retval MCA_ENOMEM
 */
int mca_tick_rec_read(const char *path, mca_tick_rec_file_t *out, char *err, size_t errlen);

/** Free what mca_tick_rec_read() allocated (NULL-safe). */
void mca_tick_rec_free(mca_tick_rec_file_t *f);

#ifdef __cplusplus
}
#endif
#endif
