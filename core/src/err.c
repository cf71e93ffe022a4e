/* SPDX-License-Identifier: MIT */
#include "mca/err.h"

const char *mca_strerror(int rc) {
    switch (rc) {
    case MCA_OK:
        return "ok";
    case MCA_EINVAL:
        return "invalid argument";
    case MCA_ENOENT:
        return "not found";
    case MCA_EPARSE:
        return "parse error";
    case MCA_ERANGE:
        return "exceeds a compile-time maximum";
    case MCA_ENOMEM:
        return "out of memory";
    case MCA_EIO:
        return "I/O error";
    case MCA_ETIMEDOUT:
        return "timed out";
    case MCA_ENOTCONV:
        return "solver did not converge";
    case MCA_EINFEASIBLE:
        return "infeasible";
    case MCA_ESTATE:
        return "not allowed in this state";
    case MCA_ENOTSUP:
        return "not supported";
    case MCA_EAGAIN:
        return "try again";
    case MCA_EFAULT:
        return "fault";
    case MCA_ECONFIG:
        return "invalid configuration value";
    default:
        return "unknown error";
    }
}
