/* SPDX-License-Identifier: MIT */
/** @file mca/dds_log.h
 * How the DDS library hands its lines to whoever logs: it prints nothing itself (mcad and the programs
 * log, with their own name and syslog level prefix). Context: the callback is called from the thread that
 * called the library function that takes it.
 */
#ifndef MCA_DDS_LOG_H
#define MCA_DDS_LOG_H

#include "mca/log.h"

#ifdef __cplusplus
extern "C" {
#endif

/** Where a library's line goes: the one sink type of mca/log.h (@p level syslog's, @p text one line without
 *  a level, a program's name or the newline); the caller prints it as it logs. */
typedef mca_log_fn mca_dds_log_fn;

#ifdef __cplusplus
}
#endif
#endif
