/* SPDX-License-Identifier: MIT */
/* The back-off, the wording of a death and the thinning of the log shared by every supervisor of a process
 * with a DDS participant (dds__supervise.h). */
#include "dds__supervise.h"

#include <stdio.h>
#include <string.h>   /* sigabbrev_np */
#include <sys/wait.h> /* WIFSIGNALED, ... */

#include "mca/dds_bridge.h" /* MCA_DDS_BRIDGE_BACKOFF_S, _MAX_S, _LOG_ALL, _LOG_EVERY */

double mca_dds_backoff_s(int quick_deaths) {
    double delay = MCA_DDS_BRIDGE_BACKOFF_S;
    for (int k = 1; k < quick_deaths && delay < MCA_DDS_BRIDGE_BACKOFF_MAX_S; k++) {
        delay *= 2.0;
    }
    return delay > MCA_DDS_BRIDGE_BACKOFF_MAX_S ? MCA_DDS_BRIDGE_BACKOFF_MAX_S : delay;
}

void mca_dds_describe_status(int status, char *buf, size_t len) {
    if (WIFSIGNALED(status)) {
        const int sig = WTERMSIG(status);
        const char *abbrev = sigabbrev_np(sig);
        snprintf(buf, len, "signal %d (SIG%s)%s", sig, abbrev != NULL ? abbrev : "?",
                 WCOREDUMP(status) ? ", core dumped" : "");
    } else if (WIFEXITED(status)) {
        snprintf(buf, len, "exit status %d", WEXITSTATUS(status));
    } else {
        snprintf(buf, len, "wait status 0x%x", (unsigned)status);
    }
}

int mca_dds_log_this_death(int quick_deaths) {
    return quick_deaths <= MCA_DDS_BRIDGE_LOG_ALL || quick_deaths % MCA_DDS_BRIDGE_LOG_EVERY == 0;
}
