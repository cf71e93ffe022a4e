/* SPDX-License-Identifier: MIT */
/* The recording of a run (mca/tick_rec.h): a header, then one fixed-size record per tick. Non-rt. */
#include "mca/tick_rec.h"

#include <errno.h>
#include <stdlib.h>
#include <string.h>

#include "mca/err.h"
#include "mca/errbuf.h" /* mca_errbuf_printf */

int mca_tick_rec_write_header(FILE *f, const mca_tick_rec_header_t *h) {
    mca_tick_rec_header_t w = *h;
    memcpy(w.magic, MCA_TICK_REC_MAGIC, sizeof w.magic);
    w.version = MCA_TICK_REC_VERSION;
    w.header_size = (uint32_t)sizeof w;
    w.rec_size = (uint32_t)sizeof(mca_tick_rec_t);
    return fwrite(&w, sizeof w, 1, f) == 1 ? 0 : -1;
}

int mca_tick_rec_write(FILE *f, const mca_tick_rec_t *r) {
    return fwrite(r, sizeof *r, 1, f) == 1 ? 0 : -1;
}

int mca_tick_rec_read(const char *path, mca_tick_rec_file_t *out, char *err, size_t errlen) {
    memset(out, 0, sizeof *out);
    FILE *f = fopen(path, "rb");
    if (!f) {
        mca_errbuf_printf(err, errlen, "%s: %s", path, strerror(errno));
        return MCA_ENOENT;
    }
    int rc = MCA_OK;
    mca_tick_rec_header_t *h = &out->header;
    if (fread(h, sizeof *h, 1, f) != 1 || memcmp(h->magic, MCA_TICK_REC_MAGIC, sizeof h->magic) != 0) {
        mca_errbuf_printf(err, errlen, "%s: not a recording (mcad --record)", path);
        rc = MCA_EPARSE;
    } else if (h->version != MCA_TICK_REC_VERSION || h->header_size != sizeof *h ||
               h->rec_size != sizeof(mca_tick_rec_t) || h->n_arms < 1 || h->n_arms > MCA_MAX_ARMS) {
        mca_errbuf_printf(
            err, errlen,
            "%s: recording version %u, header %u and record %u bytes, %u arms (this build reads "
            "version %u, %zu and %zu bytes, 1..%d arms)",
            path, h->version, h->header_size, h->rec_size, h->n_arms, MCA_TICK_REC_VERSION, sizeof *h,
            sizeof(mca_tick_rec_t), MCA_MAX_ARMS);
        rc = MCA_EPARSE;
    }
    long end = -1;
    if (rc == MCA_OK &&
        (fseek(f, 0, SEEK_END) != 0 || (end = ftell(f)) < 0 || fseek(f, (long)sizeof *h, SEEK_SET) != 0)) {
        mca_errbuf_printf(err, errlen, "%s: %s", path, strerror(errno));
        rc = MCA_EIO;
    }
    if (rc == MCA_OK) {
        out->n = ((size_t)end - sizeof *h) / sizeof(mca_tick_rec_t);
        out->rec = malloc(out->n ? out->n * sizeof(mca_tick_rec_t) : 1);
        if (!out->rec) {
            rc = MCA_ENOMEM;
        } else if (fread(out->rec, sizeof(mca_tick_rec_t), out->n, f) != out->n) {
            mca_errbuf_printf(err, errlen, "%s: short read", path);
            rc = MCA_EIO;
        }
    }
    fclose(f);
    if (rc != MCA_OK) {
        mca_tick_rec_free(out);
    }
    return rc;
}

void mca_tick_rec_free(mca_tick_rec_file_t *f) {
    if (f) {
        free(f->rec);
        f->rec = NULL;
        f->n = 0;
    }
}
