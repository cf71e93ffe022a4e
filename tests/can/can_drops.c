/* SPDX-License-Identifier: MIT */
/* mca-can-drops: the kernel's drop count reaches the reader (SO_RXQ_OVFL through mca_can_sock_recv_batch).
 * A socket opened as the CAN backend opens its own (mca_can_sock_open), its receive buffer at the kernel's
 * minimum, is sent N frames of its id block from a second raw socket without being read; then it is drained,
 * sent one more (the kernel tells the count with the next frame it queues) and drained again.
 * Truth is the sender's count: the frames read plus the kernel's drop count must be N, with drops > 0.
 * Needs a kernel with vcan (the QEMU guest of the vcan suite). Prints one line; exit 0 when it holds.
 * usage: mca-can-drops IFACE [N (500)] */
#include <errno.h>
#include <linux/can.h>
#include <linux/can/raw.h>
#include <net/if.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <unistd.h>

#include "mca/can_proto.h"
#include "mca/can_sock.h"
#include "mca/err.h"

/* One 64-byte CAN FD frame; the sender's own queue full (ENOBUFS): wait and send it again. 0 or -1 (said). */
static int send_frame(int tx, uint32_t id, uint8_t first_byte) {
    struct canfd_frame f = {.can_id = id, .len = 64};
    f.data[0] = first_byte;
    while (write(tx, &f, sizeof f) != (ssize_t)sizeof f) {
        if (errno != ENOBUFS && errno != EAGAIN) {
            fprintf(stderr, "mca-can-drops: write: %s\n", strerror(errno));
            return -1;
        }
        usleep(100); /* the sender's queue, not the reader's */
    }
    return 0;
}

int main(int argc, char **argv) {
    if (argc < 2 || argc > 3) {
        fprintf(stderr, "usage: mca-can-drops IFACE [N]\n");
        return 2;
    }
    const char *iface = argv[1];
    const int n = argc == 3 ? atoi(argv[2]) : 500;
    const uint32_t base = 0x100;
    char err[256] = "";
    int rx;
    if (n < 1 || mca_can_sock_open(&rx, iface, base, 0, err, sizeof err) != MCA_OK) {
        fprintf(stderr, "mca-can-drops: %s\n", err[0] ? err : "bad N");
        return 2;
    }
    int small = 1; /* the kernel rounds it up to its minimum: a few frames */
    setsockopt(rx, SOL_SOCKET, SO_RCVBUF, &small, sizeof small);
    int tx = socket(PF_CAN, SOCK_RAW, CAN_RAW);
    int on = 1;
    struct sockaddr_can addr = {.can_family = AF_CAN, .can_ifindex = (int)if_nametoindex(iface)};
    if (tx < 0 || setsockopt(tx, SOL_CAN_RAW, CAN_RAW_FD_FRAMES, &on, sizeof on) != 0 ||
        bind(tx, (struct sockaddr *)&addr, sizeof addr) != 0) {
        fprintf(stderr, "mca-can-drops: sender socket on %s: %s\n", iface, strerror(errno));
        return 2;
    }
    int sent = 0;
    for (int i = 0; i < n; i++) {
        if (send_frame(tx, base + MCA_CAN_OFF_FEEDBACK, (uint8_t)i) != 0) {
            return 2;
        }
        sent++;
    }
    /* A frame carries the count as it was when the frame was queued: the frames in the full queue say 0,
     * the first one queued after the drops says how many. So: drain, send one more, drain again. */
    int got = 0;
    uint32_t drops = 0;
    for (int round = 0; round < 2; round++) {
        if (round == 1) {
            if (send_frame(tx, base + MCA_CAN_OFF_FEEDBACK, 0) != 0) {
                return 2;
            }
            sent++;
        }
        for (;;) {
            mca_can_frame_t f[MCA_CAN_RX_BATCH];
            int bad = 0;
            const int k = mca_can_sock_recv_batch(rx, f, MCA_CAN_RX_BATCH, &bad);
            if (k < 0) {
                break;
            }
            for (int i = 0; i < k; i++) {
                drops = f[i].rxq_drops > drops ? f[i].rxq_drops : drops;
            }
            got += k + bad;
        }
    }
    const int ok = got + (int)drops == sent && drops > 0;
    printf("drops: sent %d, read %d, the kernel's drop count %u: %s\n", sent, got, drops,
           ok ? "read + dropped = sent" : "MISMATCH (want read + dropped = sent, dropped > 0)");
    return ok ? 0 : 1;
}
