/* SPDX-License-Identifier: MIT */
/* The running program's install prefix; see mca/prefix.h. */
#include "mca/prefix.h"

#include <limits.h> /* PATH_MAX */
#include <stdio.h>
#include <string.h>
#include <unistd.h> /* readlink */
#include "mca/err.h"

int mca_exe_prefix(char *out, size_t len) {
    char self[PATH_MAX];
    const ssize_t n = readlink("/proc/self/exe", self, sizeof self - 1);
    if (n <= 0) {
        return MCA_ENOENT;
    }
    self[n] = '\0';
    /* drop the program's name, then its folder (sbin, bin) */
    for (int up = 0; up < 2; up++) {
        char *slash = strrchr(self, '/');
        if (!slash) {
            return MCA_ENOENT;
        }
        *slash = '\0';
    }
    if (strlen(self) >= len) {
        return MCA_ERANGE;
    }
    memcpy(out, self, strlen(self) + 1);
    return MCA_OK;
}

int mca_prefix_sysconfdir(const char *prefix, char *out, size_t len) {
    const int n =
        strcmp(prefix, "/usr") == 0 ? snprintf(out, len, "/etc") : snprintf(out, len, "%s/etc", prefix);
    return n >= 0 && (size_t)n < len ? MCA_OK : MCA_ERANGE;
}
