/* SPDX-License-Identifier: MIT */
/* What every supervisor of a process with a DDS participant does the same way: mcad's supervisor of
 * mca-dds-bridge (dds_bridge.c) and the tools' supervisor of their DDS child (dds_child.c). One back-off, one
 * wording of a death, one thinning of the log, so that a crashing peer (docs/dds.md) is met alike everywhere.
 * Context: non-rt. */
#ifndef MCA_DDS__SUPERVISE_H
#define MCA_DDS__SUPERVISE_H

#include <stddef.h>

/** The delay before the restart that follows the quick_deaths-th death in a row (1..):
 * MCA_DDS_BRIDGE_BACKOFF_S, doubling, at most MCA_DDS_BRIDGE_BACKOFF_MAX_S [s]. There is no last restart. */
double mca_dds_backoff_s(int quick_deaths);

/** A waitpid status in words: "signal 11 (SIGSEGV)", "exit status 1". */
void mca_dds_describe_status(int status, char *buf, size_t len);

/** 1: this death of a series is logged (every one up to MCA_DDS_BRIDGE_LOG_ALL, then every
 *  MCA_DDS_BRIDGE_LOG_EVERY-th): a peer that stays for hours must not fill the journal. */
int mca_dds_log_this_death(int quick_deaths);

#endif
