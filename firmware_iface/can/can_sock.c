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
    /* the kernel's count of frames it dropped from this socket's queue, with every frame: a gap in the
     * stream that the link would otherwise only see as a skipped rolling counter */
    if (setsockopt(s, SOL_SOCKET, SO_RXQ_OVFL, &on, sizeof(on)) < 0) {
        int e = errno;
        close(s);
        return fail(err, errlen, MCA_EIO, "can: SO_RXQ_OVFL on %s", iface, e);
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

int mca_can_sock_recv_batch(int fd, mca_can_frame_t *f, int max, int *bad) {
    if (fd < 0 || !f || max < 1 || max > MCA_CAN_RX_BATCH) {
        return MCA_EINVAL;
    }
    struct canfd_frame cf[MCA_CAN_RX_BATCH];
    struct iovec iov[MCA_CAN_RX_BATCH];
    union {
        char buf[CMSG_SPACE(sizeof(struct timespec)) + CMSG_SPACE(sizeof(uint32_t))];
        struct cmsghdr align;
    } ctl[MCA_CAN_RX_BATCH];
    struct mmsghdr mm[MCA_CAN_RX_BATCH];
    memset(mm, 0, sizeof(mm[0]) * (size_t)max);
    for (int i = 0; i < max; i++) {
        iov[i] = (struct iovec){.iov_base = &cf[i], .iov_len = sizeof(cf[i])};
        mm[i].msg_hdr.msg_iov = &iov[i];
        mm[i].msg_hdr.msg_iovlen = 1;
        mm[i].msg_hdr.msg_control = ctl[i].buf;
        mm[i].msg_hdr.msg_controllen = sizeof(ctl[i].buf);
    }
    const int got = recvmmsg(fd, mm, (unsigned)max, MSG_DONTWAIT, NULL);
    if (got < 0) {
        return (errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR) ? MCA_EAGAIN : MCA_EIO;
    }
    if (got == 0) {
        return MCA_EAGAIN;
    }
    /* once per batch: the clock offset for the kernel's stamps, and the read time (the fallback) */
    struct timespec mono;
    clock_gettime(CLOCK_MONOTONIC, &mono);
    int64_t off = 0;
    int have_off = 0, n = 0, n_bad = 0;
    for (int i = 0; i < got; i++) {
        const unsigned nb = mm[i].msg_len;
        if (nb != CAN_MTU && nb != CANFD_MTU) {
            n_bad++; /* not a CAN frame: the caller reports it like an error frame */
            continue;
        }
        mca_can_frame_t *o = &f[n++];
        o->can_id = cf[i].can_id;
        o->fd = nb == CANFD_MTU;
        o->len = cf[i].len > 64 ? 64 : cf[i].len;
        memcpy(o->data, cf[i].data, o->len);
        /* Fallback when the kernel gave no stamp (cmsg missing or truncated): the read time, flagged as
         * such (kstamp = 0) so the backend can count it instead of passing it off as a kernel stamp. */
        o->stamp_ns = ts_ns(&mono);
        o->kstamp = 0;
        o->rxq_drops = 0;
        const struct msghdr *msg = &mm[i].msg_hdr;
        if (msg->msg_flags & MSG_CTRUNC) {
            continue;
        }
        for (struct cmsghdr *c = CMSG_FIRSTHDR(msg); c; c = CMSG_NXTHDR((struct msghdr *)msg, c)) {
            if (c->cmsg_level == SOL_SOCKET && c->cmsg_type == SCM_TIMESTAMPNS &&
                c->cmsg_len >= CMSG_LEN(sizeof(struct timespec))) {
                struct timespec k;
                memcpy(&k, CMSG_DATA(c), sizeof(k));
                if (!have_off) {
                    off = mono_minus_real_ns();
                    have_off = 1;
                }
                o->stamp_ns = ts_ns(&k) + off;
                o->kstamp = 1;
            } else if (c->cmsg_level == SOL_SOCKET && c->cmsg_type == SO_RXQ_OVFL &&
                       c->cmsg_len >= CMSG_LEN(sizeof(uint32_t))) {
                memcpy(&o->rxq_drops, CMSG_DATA(c), sizeof(o->rxq_drops));
            }
        }
    }
    if (bad) {
        *bad = n_bad;
    }
    return n;
}

int mca_can_sock_recv(int fd, mca_can_frame_t *f) {
    int bad = 0;
    const int n = mca_can_sock_recv_batch(fd, f, 1, &bad);
    if (n < 0) {
        return n;
    }
    return n == 1 ? MCA_OK : MCA_EIO; /* one datagram that was not a CAN frame */
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
