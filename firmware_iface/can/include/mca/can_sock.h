/* SPDX-License-Identifier: MIT */
/** @file mca/can_sock.h
 * Thin SocketCAN layer shared by the controller backend (mca/arm_can.h) and the firmware emulator
 * (mca-armsim): a raw CAN FD socket, non-blocking, bound to one interface, whose kernel filter passes
 * only one arm's id block (MCA_CAN_ID_BLOCK ids from id_base) plus error frames, with kernel receive
 * time stamps (SO_TIMESTAMPNS, converted to CLOCK_MONOTONIC).
 *
 * Context: mca_can_sock_open/close are start-up/shut-down; recv/send are real-time safe (one
 * non-blocking system call, no allocation).
 */
#ifndef MCA_CAN_SOCK_H
#define MCA_CAN_SOCK_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/** One received frame. */
typedef struct mca_can_frame {
    uint32_t can_id; /**< raw SocketCAN id: 11/29-bit id plus CAN_EFF/RTR/ERR flag bits */
    uint8_t len;     /**< payload bytes (0..64) */
    uint8_t fd;      /**< 1: CAN FD frame, 0: classic CAN */
    uint8_t data[64];
    int64_t stamp_ns; /**< kernel receive time, CLOCK_MONOTONIC [ns] (read time if the kernel gave none) */
    uint8_t kstamp;   /**< 1: stamp_ns is the kernel's (SO_TIMESTAMPNS), 0: user-space read time (fallback) */
    uint32_t rxq_drops; /**< frames the kernel dropped from this socket's queue so far (SO_RXQ_OVFL; a full
                             queue), as of this frame; 0 when the kernel did not say */
} mca_can_frame_t;

/**
 * Open a raw CAN FD socket on @p iface (start-up).
 * @param[out] fd      socket
 * @param[in]  id_base first id of the arm's block; multiple of MCA_CAN_ID_BLOCK, <= MCA_CAN_ID_BASE_MAX
 * @param[in]  err_mask CAN_ERR_* classes to receive as error frames (0: none)
 * @param[out] err     reason on failure, naming the interface and the call (may be NULL)
 * @retval MCA_OK
 * @retval MCA_EINVAL  NULL/empty iface, bad id_base
 * @retval MCA_ENOTSUP the kernel has no SocketCAN or the interface cannot carry CAN FD
 * @retval MCA_ENOENT  no such interface
 * @retval MCA_EIO     another socket error
 */
int mca_can_sock_open(int *fd, const char *iface, uint32_t id_base, uint32_t err_mask, char *err,
                      size_t errlen);

/** Receive one frame without blocking. @retval MCA_OK, MCA_EAGAIN (none queued), MCA_EIO, MCA_EINVAL */
int mca_can_sock_recv(int fd, mca_can_frame_t *f);

/** Most frames one mca_can_sock_recv_batch() call takes. */
#define MCA_CAN_RX_BATCH 16

/**
 * Receive up to @p max (1..MCA_CAN_RX_BATCH) frames without blocking in one system call (recvmmsg); the
 * clocks are read once per batch (the read time, and the offset that moves the kernel's stamps onto
 * CLOCK_MONOTONIC). Fewer than @p max means the socket is empty now: no second call is needed to learn it.
 * @param[out] bad datagrams of the wrong size, dropped (may be NULL)
 * @return frames written to f (0 if every datagram had the wrong size), MCA_EAGAIN (none waiting), MCA_EIO,
 *         MCA_EINVAL
 */
int mca_can_sock_recv_batch(int fd, mca_can_frame_t *f, int max, int *bad);

/**
 * Send one frame without blocking: CAN FD (with bit-rate switch when @p brs) when @p fd_frame, else
 * classic CAN (len <= 8). @p len must be a valid DLC length.
 * @retval MCA_OK, MCA_EAGAIN (tx queue full), MCA_EIO, MCA_EINVAL
 */
int mca_can_sock_send(int fd, uint32_t can_id, const uint8_t *data, size_t len, int fd_frame, int brs);

/** Close (NULL-safe for fd < 0). */
void mca_can_sock_close(int fd);

#ifdef __cplusplus
}
#endif
#endif
