/* SPDX-License-Identifier: MIT */
/** @file mca/prefix.h
 * Where the running program is installed (mca_model, start-up only): an install to any prefix finds its own
 * files (etc/mca, share/mca, libexec/mca) relative to its executable, not at the prefix the build was
 * configured with (docs/install.md).
 */
#ifndef MCA_PREFIX_H
#define MCA_PREFIX_H

#include <stddef.h>

#ifdef __cplusplus
extern "C" {
#endif

/**
 * The install prefix of the running program: the parent of its executable's folder (/proc/self/exe:
 * PREFIX/sbin/mcad and PREFIX/bin/mca-sim give PREFIX; "/" gives ""). Start-up only (a readlink, never on
 * the loop's path).
 * @param[out] out  the prefix without a trailing '/' (unchanged on error)
 * @retval MCA_OK
 * @retval MCA_ENOENT  /proc/self/exe unreadable
 * @retval MCA_ERANGE  the prefix does not fit in len
 */
int mca_exe_prefix(char *out, size_t len);

/**
 * The prefix's etc folder, as GNUInstallDirs places it: "/etc" for the prefix "/usr" (a Debian package),
 * PREFIX/etc otherwise.
 * @retval MCA_OK, MCA_ERANGE (does not fit in len)
 */
int mca_prefix_sysconfdir(const char *prefix, char *out, size_t len);

#ifdef __cplusplus
}
#endif

#endif
