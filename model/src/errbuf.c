/* SPDX-License-Identifier: MIT */
/* The caller's error buffer; see mca/errbuf.h. */
#include "mca/errbuf.h"

#include <stdio.h>

void mca_errbuf_vprintf(char *err, size_t errlen, const char *fmt, va_list ap) {
    if (!err || !errlen) {
        return;
    }
    vsnprintf(err, errlen, fmt, ap);
}

void mca_errbuf_printf(char *err, size_t errlen, const char *fmt, ...) {
    va_list ap;
    va_start(ap, fmt);
    mca_errbuf_vprintf(err, errlen, fmt, ap);
    va_end(ap);
}

void mca_errbuf_at(char *err, size_t errlen, const char *file, int line, const char *fmt, ...) {
    if (!err || !errlen) {
        return;
    }
    const int n = snprintf(err, errlen, "%s:%d: ", file, line);
    if (n < 0 || (size_t)n >= errlen) {
        return; /* the prefix alone fills the buffer: it stays cut there */
    }
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(err + n, errlen - (size_t)n, fmt, ap);
    va_end(ap);
}
