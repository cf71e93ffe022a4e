/* SPDX-License-Identifier: MIT */
/* Raw CAN FD sockets (see mca/can_sock.h). */
#include "mca/can_sock.h"

#include <errno.h>
#include <fcntl.h>     /* fcntl, O_NONBLOCK */
#include <net/if.h>    /* struct ifreq, if_nametoindex */
#include <stdio.h>     /* snprintf */
#include <string.h>    /* memset, memcpy, strerror */
#include <sys/ioctl.h> /* SIOCGIFMTU */
#include <sys/socket.h>
#include <time.h>   /* clock_gettime */
#include <unistd.h> /* close */

#include <linux/can.h>
#include <linux/can/raw.h>

#include "mca/can_proto.h"
#include "mca/err.h"

static int fail(char *err, size_t errlen, int rc, const char *fmt, const char *iface, int e) {
    if (err && errlen) {
        char what[160];
        snprintf(what, sizeof(what), fmt, iface);
        snprintf(err, errlen, "%s: %s", what, strerror(e));
    }
    return rc;
}

int mca_can_sock_open(int *fd, const char *iface, uint32_t id_base, uint32_t err_mask, char *err,
                      size_t errlen) {
    if (!fd || !iface || !iface[0] || strlen(iface) >= IFNAMSIZ || id_base % MCA_CAN_ID_BLOCK != 0 ||
        id_base > MCA_CAN_ID_BASE_MAX) {
        if (err && errlen) {
            snprintf(err, errlen, "can: bad interface name or id base 0x%x (multiple of 0x%x, <= 0x%x)",
                     (unsigned)id_base, MCA_CAN_ID_BLOCK, MCA_CAN_ID_BASE_MAX);
        }
        return MCA_EINVAL;
    }
    int s = socket(PF_CAN, SOCK_RAW, CAN_RAW);
    if (s < 0) {
        int e = errno;
        return fail(err, errlen, e == EAFNOSUPPORT ? MCA_ENOTSUP : MCA_EIO,
                    "can: socket(PF_CAN) for %s (kernel without SocketCAN?)", iface, e);
    }
    struct ifreq ifr;
    memset(&ifr, 0, sizeof(ifr));
    memcpy(ifr.ifr_name, iface, strlen(iface));
    unsigned idx = if_nametoindex(iface);
    if (idx == 0) {
        int e = errno;
        close(s);
        return fail(err, errlen, MCA_ENOENT, "can: interface %s", iface, e);
    }
    if (ioctl(s, SIOCGIFMTU, &ifr) < 0) {
        int e = errno;
        close(s);
        return fail(err, errlen, MCA_EIO, "can: SIOCGIFMTU %s", iface, e);
    }
    if (ifr.ifr_mtu < (int)CANFD_MTU) {
        close(s);
        return fail(err, errlen, MCA_ENOTSUP, "can: %s is not CAN FD capable (mtu < 72)", iface,
                    EPROTONOSUPPORT);
    }
    int on = 1;
    if (setsockopt(s, SOL_CAN_RAW, CAN_RAW_FD_FRAMES, &on, sizeof(on)) < 0) {
        int e = errno;
        close(s);
        return fail(err, errlen, MCA_ENOTSUP, "can: CAN_RAW_FD_FRAMES on %s", iface, e);
    }
    /* Only this arm's id block (standard ids, data frames): the kernel drops the rest of the bus. */
    struct can_filter flt = {
        .can_id = id_base,
        .can_mask = (CAN_SFF_MASK & ~(MCA_CAN_ID_BLOCK - 1u)) | CAN_EFF_FLAG | CAN_RTR_FLAG,
    };
    if (setsockopt(s, SOL_CAN_RAW, CAN_RAW_FILTER, &flt, sizeof(flt)) < 0) {
        int e = errno;
        close(s);
        return fail(err, errlen, MCA_EIO, "can: CAN_RAW_FILTER on %s", iface, e);
    }
    can_err_mask_t em = err_mask & CAN_ERR_MASK;
    if (setsockopt(s, SOL_CAN_RAW, CAN_RAW_ERR_FILTER, &em, sizeof(em)) < 0) {
        int e = errno;
        close(s);
        return fail(err, errlen, MCA_EIO, "can: CAN_RAW_ERR_FILTER on %s", iface, e);
    }
    if (setsockopt(s, SOL_SOCKET, SO_TIMESTAMPNS, &on, sizeof(on)) < 0) {
        int e = errno;
        close(s);
        return fail(err, errlen, MCA_EIO, "can: SO_TIMESTAMPNS on %s", iface, e);
    }
    int fl = fcntl(s, F_GETFL, 0);
    if (fl < 0 || fcntl(s, F_SETFL, fl | O_NONBLOCK) < 0) {
        int e = errno;
        close(s);
        return fail(err, errlen, MCA_EIO, "can: O_NONBLOCK on %s", iface, e);
    }
    struct sockaddr_can addr;
    memset(&addr, 0, sizeof(addr));
    addr.can_family = AF_CAN;
    addr.can_ifindex = (int)idx;
    if (bind(s, (struct sockaddr *)&addr, sizeof(addr)) < 0) {
        int e = errno;
        close(s);
        return fail(err, errlen, MCA_EIO, "can: bind to %s", iface, e);
    }
    *fd = s;
    return MCA_OK;
}

static int64_t ts_ns(const struct timespec *t) {
    return (int64_t)t->tv_sec * 1000000000 + t->tv_nsec;
}

/* CLOCK_MONOTONIC - CLOCK_REALTIME now, for moving the kernel's CLOCK_REALTIME receive stamps onto the
 * controller's clock. The monotonic read is bracketed by two realtime reads and the tightest of three
 * brackets is kept: a preemption between two unbracketed reads (seen in an emulated guest) would shift
 * the stamp by the time lost, up to making a round trip negative. */
static int64_t mono_minus_real_ns(void) {
    int64_t best_gap = INT64_MAX, off = 0;
    for (int i = 0; i < 3; i++) {
        struct timespec r0, m, r1;
        clock_gettime(CLOCK_REALTIME, &r0);
        clock_gettime(CLOCK_MONOTONIC, &m);
        clock_gettime(CLOCK_REALTIME, &r1);
        const int64_t gap = ts_ns(&r1) - ts_ns(&r0);
        if (gap < best_gap) {
            best_gap = gap;
            off = ts_ns(&m) - (ts_ns(&r0) + gap / 2);
        }
        if (gap < 2000) { /* within 2 us: good enough, no more reads */
            break;
        }
    }
    return off;
}

int mca_can_sock_recv(int fd, mca_can_frame_t *f) {
    if (fd < 0 || !f) {
        return MCA_EINVAL;
    }
    struct canfd_frame cf;
    struct iovec iov = {.iov_base = &cf, .iov_len = sizeof(cf)};
    union {
        char buf[CMSG_SPACE(sizeof(struct timespec))];
        struct cmsghdr align;
    } ctl;
    struct msghdr msg;
    memset(&msg, 0, sizeof(msg));
    msg.msg_iov = &iov;
    msg.msg_iovlen = 1;
    msg.msg_control = ctl.buf;
    msg.msg_controllen = sizeof(ctl.buf);
    ssize_t nb = recvmsg(fd, &msg, MSG_DONTWAIT);
    if (nb < 0) {
        return (errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR) ? MCA_EAGAIN : MCA_EIO;
    }
    if (nb != (ssize_t)CAN_MTU && nb != (ssize_t)CANFD_MTU) {
        return MCA_EIO;
    }
    f->can_id = cf.can_id;
    f->fd = nb == (ssize_t)CANFD_MTU;
    f->len = cf.len > 64 ? 64 : cf.len;
    memcpy(f->data, cf.data, f->len);
    struct timespec mono;
    clock_gettime(CLOCK_MONOTONIC, &mono);
    /* Fallback when the kernel gave no stamp (cmsg missing or truncated): the read time, flagged as
     * such (kstamp = 0) so the backend can count it instead of passing it off as a kernel stamp. */
    f->stamp_ns = ts_ns(&mono);
    f->kstamp = 0;
    if (!(msg.msg_flags & MSG_CTRUNC)) {
        for (struct cmsghdr *c = CMSG_FIRSTHDR(&msg); c; c = CMSG_NXTHDR(&msg, c)) {
            if (c->cmsg_level == SOL_SOCKET && c->cmsg_type == SCM_TIMESTAMPNS &&
                c->cmsg_len >= CMSG_LEN(sizeof(struct timespec))) {
                struct timespec k;
                memcpy(&k, CMSG_DATA(c), sizeof(k));
                f->stamp_ns = ts_ns(&k) + mono_minus_real_ns();
                f->kstamp = 1;
            }
        }
    }
    return MCA_OK;
}

int mca_can_sock_send(int fd, uint32_t can_id, const uint8_t *data, size_t len, int fd_frame, int brs) {
    if (fd < 0 || (!data && len) || len > (fd_frame ? 64u : 8u)) {
        return MCA_EINVAL;
    }
    struct canfd_frame cf;
    memset(&cf, 0, sizeof(cf));
    cf.can_id = can_id;
    cf.len = (uint8_t)len;
    if (len) {
        memcpy(cf.data, data, len);
    }
    size_t mtu = CAN_MTU;
    if (fd_frame) {
        mtu = CANFD_MTU;
        cf.flags = brs ? CANFD_BRS : 0;
#ifdef CANFD_FDF
        cf.flags |= CANFD_FDF;
#endif
    }
    ssize_t nb = send(fd, &cf, mtu, MSG_DONTWAIT);
    if (nb < 0) {
        return (errno == EAGAIN || errno == EWOULDBLOCK || errno == ENOBUFS) ? MCA_EAGAIN : MCA_EIO;
    }
    return nb == (ssize_t)mtu ? MCA_OK : MCA_EIO;
}

void mca_can_sock_close(int fd) {
    if (fd >= 0) {
        close(fd);
    }
}
