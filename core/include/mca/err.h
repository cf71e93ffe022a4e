/* SPDX-License-Identifier: MIT */
/** @file mca/err.h
 * Return codes shared by every mca module: 0 is success, small negatives name the cause.
 * A function that returns an error leaves its outputs and the objects it was given unchanged
 * unless its own documentation says otherwise.
 */
#ifndef MCA_ERR_H
#define MCA_ERR_H

#ifdef __cplusplus
extern "C" {
#endif

enum mca_retcode {
    MCA_OK = 0,
    MCA_EINVAL = -1,      /**< bad argument (NULL, out of range, NaN) */
    MCA_ENOENT = -2,      /**< file or named element not found */
    MCA_EPARSE = -3,      /**< malformed input file */
    MCA_ERANGE = -4,      /**< value outside a compile-time maximum (e.g. too many joints) */
    MCA_ENOMEM = -5,      /**< allocation failed (start-up only) */
    MCA_EIO = -6,         /**< I/O or socket error */
    MCA_ETIMEDOUT = -7,   /**< a deadline passed (lost feedback, watchdog) */
    MCA_ENOTCONV = -8,    /**< an iterative solver hit its cap before its tolerance */
    MCA_EINFEASIBLE = -9, /**< constraints cannot all be met */
    MCA_ESTATE = -10,     /**< call not allowed in the current state */
    MCA_ENOTSUP = -11,    /**< not supported by this backend or build */
    MCA_EAGAIN = -12,     /**< nothing available now; try again (non-blocking I/O, empty ring) */
    MCA_EFAULT = -13,     /**< the arm or the controller is in fault */
    MCA_ECONFIG = -14,    /**< a cell or scenario value not allowed (the message names file:line: field) */
};

/** Short constant text for a return code ("invalid argument", ...); never NULL. */
const char *mca_strerror(int rc);

#ifdef __cplusplus
}
#endif
#endif
