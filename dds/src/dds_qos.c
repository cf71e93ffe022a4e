/* SPDX-License-Identifier: MIT */
/* QoS and participant set-up shared by every mca DDS endpoint. */
#include "mca/dds_qos.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "mca/err.h"

dds_qos_t *mca_dds_qos_stream(void) {
    dds_qos_t *q = dds_create_qos();
    if (q == NULL) {
        return NULL;
    }
    dds_qset_reliability(q, DDS_RELIABILITY_RELIABLE, DDS_MSECS(100));
    /* keep-last 1 lost samples at 1 kHz here: 16 absorbs a scheduling hiccup of the reader. */
    dds_qset_history(q, DDS_HISTORY_KEEP_LAST, 16);
    dds_qset_durability(q, DDS_DURABILITY_VOLATILE);
    return q;
}

dds_qos_t *mca_dds_qos_status(void) {
    dds_qos_t *q = dds_create_qos();
    if (q == NULL) {
        return NULL;
    }
    dds_qset_reliability(q, DDS_RELIABILITY_RELIABLE, DDS_MSECS(100));
    dds_qset_history(q, DDS_HISTORY_KEEP_LAST, 1);
    dds_qset_durability(q, DDS_DURABILITY_TRANSIENT_LOCAL);
    return q;
}

dds_entity_t mca_dds_open_participant(uint32_t domain_id, const char *config_path, dds_entity_t *domain) {
    if (domain == NULL || domain_id > MCA_DDS_MAX_DOMAIN) {
        fprintf(stderr, "mca dds: domain id %u out of range 0..%d\n", domain_id, MCA_DDS_MAX_DOMAIN);
        return MCA_EINVAL;
    }
    *domain = 0;
    if (config_path != NULL) {
        FILE *f = fopen(config_path, "r");
        if (f == NULL) {
            fprintf(stderr, "mca dds: cannot read config file '%s'\n", config_path);
            return MCA_ENOENT;
        }
        fclose(f);
        const size_t len = strlen(config_path) + sizeof "file://";
        char *uri = malloc(len);
        if (uri == NULL) {
            return MCA_ENOMEM;
        }
        snprintf(uri, len, "file://%s", config_path);
        const dds_entity_t d = dds_create_domain((dds_domainid_t)domain_id, uri);
        free(uri);
        if (d < 0) {
            fprintf(stderr, "mca dds: config '%s' for domain %u rejected: %s\n", config_path, domain_id,
                    dds_strretcode(d));
            return MCA_EIO;
        }
        *domain = d;
    }
    const dds_entity_t p = dds_create_participant((dds_domainid_t)domain_id, NULL, NULL);
    if (p < 0) {
        fprintf(stderr, "mca dds: cannot create participant on domain %u: %s\n", domain_id,
                dds_strretcode(p));
        if (*domain > 0) {
            dds_delete(*domain);
            *domain = 0;
        }
        return MCA_EIO;
    }
    return p;
}

static dds_entity_t create_in_partition(dds_entity_t pp, const char *partition, int publisher) {
    dds_qos_t *q = NULL;
    if (partition != NULL) {
        q = dds_create_qos();
        if (q == NULL) {
            return DDS_RETCODE_OUT_OF_RESOURCES;
        }
        dds_qset_partition1(q, partition);
    }
    const dds_entity_t e = publisher ? dds_create_publisher(pp, q, NULL) : dds_create_subscriber(pp, q, NULL);
    if (q != NULL) {
        dds_delete_qos(q);
    }
    if (e < 0) {
        fprintf(stderr, "mca dds: cannot create %s in partition '%s': %s\n",
                publisher ? "publisher" : "subscriber", partition != NULL ? partition : "",
                dds_strretcode(e));
    }
    return e;
}

dds_entity_t mca_dds_create_publisher(dds_entity_t pp, const char *partition) {
    return create_in_partition(pp, partition, 1);
}

dds_entity_t mca_dds_create_subscriber(dds_entity_t pp, const char *partition) {
    return create_in_partition(pp, partition, 0);
}
