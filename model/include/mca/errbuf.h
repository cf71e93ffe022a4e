/* SPDX-License-Identifier: MIT */
/** @file mca/errbuf.h
 * Filling the caller's error buffer (mca_model, start-up only): every loader that takes `char *err, size_t
 * errlen` writes its message through these, so that a NULL or empty buffer and a cut message are handled
 * the same way everywhere (one helper, not one copy per file).
 */
#ifndef MCA_ERRBUF_H
#define MCA_ERRBUF_H

#include <stdarg.h>
#include <stddef.h>

#ifdef __cplusplus
extern "C" {
#endif

/** printf into err (cut at errlen, always terminated); nothing when err is NULL or errlen 0. */
__attribute__((format(printf, 3, 4))) void mca_errbuf_printf(char *err, size_t errlen, const char *fmt, ...);

/** As mca_errbuf_printf with a va_list. */
__attribute__((format(printf, 3, 0))) void mca_errbuf_vprintf(char *err, size_t errlen, const char *fmt,
                                                              va_list ap);

/** "FILE:LINE: message" into err: the prefix of every cell and scenario error that names a line. */
__attribute__((format(printf, 5, 6))) void mca_errbuf_at(char *err, size_t errlen, const char *file, int line,
                                                         const char *fmt, ...);

#ifdef __cplusplus
}
#endif
#endif
