/* SPDX-License-Identifier: MIT */
/* MCAP writer of mca-record (mcap_writer.h). Every integer little-endian, strings and byte arrays with a
 * uint32 length before them, every record opcode (uint8) + length (uint64) + content. */
#include "mcap_writer.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

enum {
    OP_HEADER = 0x01,
    OP_FOOTER = 0x02,
    OP_SCHEMA = 0x03,
    OP_CHANNEL = 0x04,
    OP_MESSAGE = 0x05,
    OP_CHUNK = 0x06,
    OP_MESSAGE_INDEX = 0x07,
    OP_CHUNK_INDEX = 0x08,
    OP_STATISTICS = 0x0B,
    OP_METADATA = 0x0C,
    OP_METADATA_INDEX = 0x0D,
    OP_SUMMARY_OFFSET = 0x0E,
    OP_DATA_END = 0x0F,
};

static const unsigned char magic[8] = {0x89, 'M', 'C', 'A', 'P', '0', '\r', '\n'};

typedef struct buf {
    unsigned char *p;
    size_t n, cap;
    int oom;
} buf_t;

static void buf_put(buf_t *b, const void *src, size_t len) {
    if (b->oom) {
        return;
    }
    if (b->n + len > b->cap) {
        size_t cap = b->cap ? b->cap : 4096;
        while (cap < b->n + len) {
            cap *= 2;
        }
        unsigned char *p = realloc(b->p, cap);
        if (p == NULL) {
            b->oom = 1;
            return;
        }
        b->p = p;
        b->cap = cap;
    }
    if (len > 0) {
        memcpy(b->p + b->n, src, len);
    }
    b->n += len;
}

static void put_le(buf_t *b, uint64_t v, int bytes) {
    unsigned char le[8];
    for (int i = 0; i < bytes; ++i) {
        le[i] = (unsigned char)(v >> (8 * i));
    }
    buf_put(b, le, (size_t)bytes);
}

static void put_u8(buf_t *b, uint8_t v) {
    put_le(b, v, 1);
}
static void put_u16(buf_t *b, uint16_t v) {
    put_le(b, v, 2);
}
static void put_u32(buf_t *b, uint32_t v) {
    put_le(b, v, 4);
}
static void put_u64(buf_t *b, uint64_t v) {
    put_le(b, v, 8);
}

static void put_bytes(buf_t *b, const void *p, size_t len) {
    put_u32(b, (uint32_t)len);
    buf_put(b, p, len);
}

static void put_str(buf_t *b, const char *s) {
    put_bytes(b, s, strlen(s));
}

/* Start a record: opcode and a length to fill in by rec_end; returns where the record starts. */
static size_t rec_begin(buf_t *b, uint8_t op) {
    const size_t at = b->n;
    put_u8(b, op);
    put_u64(b, 0);
    return at;
}

static void rec_end(buf_t *b, size_t at) {
    if (b->oom) {
        return;
    }
    const uint64_t len = (uint64_t)(b->n - at - 9);
    for (int i = 0; i < 8; ++i) {
        b->p[at + 1 + (size_t)i] = (unsigned char)(len >> (8 * i));
    }
}

/* CRC-32 (IEEE 802.3, reflected, as zlib's crc32), table made on first use */
static uint32_t crc_table[256];

static uint32_t crc32_update(uint32_t crc, const unsigned char *p, size_t n) {
    if (crc_table[1] == 0) {
        for (uint32_t i = 0; i < 256; ++i) {
            uint32_t c = i;
            for (int k = 0; k < 8; ++k) {
                c = (c & 1u) ? 0xEDB88320u ^ (c >> 1) : c >> 1;
            }
            crc_table[i] = c;
        }
    }
    crc = ~crc;
    for (size_t i = 0; i < n; ++i) {
        crc = crc_table[(crc ^ p[i]) & 0xFFu] ^ (crc >> 8);
    }
    return ~crc;
}

typedef struct index_entry {
    uint64_t log_time, offset;
} index_entry_t;

typedef struct channel {
    buf_t record;         /* the channel record, repeated in the summary */
    index_entry_t *index; /* this chunk's messages: log time, offset in the chunk's records */
    size_t n_index, cap_index;
    uint64_t count; /* messages in the whole file */
} channel_t;

typedef struct chunk_index {
    uint64_t start, end, offset, length, index_length, size;
    uint16_t *ch;     /* channels with a message index after this chunk */
    uint64_t *ch_off; /* and where it is in the file */
    size_t n_ch;
} chunk_index_t;

struct mcap_writer {
    FILE *f;
    uint64_t pos; /* bytes written to f */
    int error;
    size_t chunk_bytes;
    buf_t schemas; /* schema records, repeated in the summary */
    uint16_t n_schemas;
    channel_t *ch; /* ch[id - 1] */
    uint16_t n_ch;
    buf_t chunk; /* the open chunk's records */
    uint64_t chunk_start, chunk_end;
    size_t chunk_msgs;
    chunk_index_t *chunks;
    size_t n_chunks, cap_chunks;
    uint64_t messages, t_first, t_last;
    buf_t metadata_index; /* metadata index records, for the summary */
    uint32_t n_metadata;
};

static void emit(mcap_writer_t *w, const void *p, size_t n) {
    if (w->error) {
        return;
    }
    if (n > 0 && fwrite(p, 1, n, w->f) != n) {
        w->error = errno ? errno : EIO;
        return;
    }
    w->pos += n;
}

static void emit_buf(mcap_writer_t *w, buf_t *b) {
    if (b->oom) {
        w->error = ENOMEM;
    }
    emit(w, b->p, b->n);
    b->n = 0;
}

mcap_writer_t *mcap_writer_open(const char *path, const char *profile, const char *library,
                                size_t chunk_bytes) {
    mcap_writer_t *w = calloc(1, sizeof *w);
    if (w == NULL) {
        return NULL;
    }
    w->f = fopen(path, "wb");
    if (w->f == NULL) {
        const int e = errno;
        free(w);
        errno = e;
        return NULL;
    }
    w->chunk_bytes = chunk_bytes > 0 ? chunk_bytes : 1u << 20;
    buf_t b = {0};
    const size_t at = rec_begin(&b, OP_HEADER);
    put_str(&b, profile);
    put_str(&b, library);
    rec_end(&b, at);
    emit(w, magic, sizeof magic);
    emit_buf(w, &b);
    free(b.p);
    return w;
}

uint16_t mcap_writer_schema(mcap_writer_t *w, const char *name, const char *encoding, const void *data,
                            size_t len) {
    if (w->n_schemas == UINT16_MAX) {
        return 0;
    }
    const uint16_t id = (uint16_t)(w->n_schemas + 1);
    const size_t start = w->schemas.n;
    const size_t at = rec_begin(&w->schemas, OP_SCHEMA);
    put_u16(&w->schemas, id);
    put_str(&w->schemas, name);
    put_str(&w->schemas, encoding);
    put_bytes(&w->schemas, data, len);
    rec_end(&w->schemas, at);
    if (w->schemas.oom) {
        return 0;
    }
    emit(w, w->schemas.p + start, w->schemas.n - start);
    w->n_schemas = id;
    return w->error ? 0 : id;
}

uint16_t mcap_writer_channel(mcap_writer_t *w, uint16_t schema_id, const char *topic, const char *encoding,
                             size_t n_meta, const char *const *keys, const char *const *values) {
    if (w->n_ch == UINT16_MAX) {
        return 0;
    }
    channel_t *ch = realloc(w->ch, (size_t)(w->n_ch + 1) * sizeof *ch);
    if (ch == NULL) {
        return 0;
    }
    w->ch = ch;
    channel_t *c = &w->ch[w->n_ch];
    memset(c, 0, sizeof *c);
    const uint16_t id = (uint16_t)(w->n_ch + 1);
    buf_t *b = &c->record;
    const size_t at = rec_begin(b, OP_CHANNEL);
    put_u16(b, id);
    put_u16(b, schema_id);
    put_str(b, topic);
    put_str(b, encoding);
    size_t meta = 0;
    for (size_t i = 0; i < n_meta; ++i) {
        meta += 8 + strlen(keys[i]) + strlen(values[i]);
    }
    put_u32(b, (uint32_t)meta);
    for (size_t i = 0; i < n_meta; ++i) {
        put_str(b, keys[i]);
        put_str(b, values[i]);
    }
    rec_end(b, at);
    if (b->oom) {
        free(b->p);
        return 0;
    }
    w->n_ch = id;
    emit(w, b->p, b->n);
    return w->error ? 0 : id;
}

static int write_chunk(mcap_writer_t *w) {
    if (w->chunk_msgs == 0 || w->error) {
        return w->error ? -1 : 0;
    }
    if (w->n_chunks == w->cap_chunks) {
        const size_t cap = w->cap_chunks ? 2 * w->cap_chunks : 64;
        chunk_index_t *p = realloc(w->chunks, cap * sizeof *p);
        if (p == NULL) {
            w->error = ENOMEM;
            return -1;
        }
        w->chunks = p;
        w->cap_chunks = cap;
    }
    chunk_index_t *ci = &w->chunks[w->n_chunks];
    memset(ci, 0, sizeof *ci);
    ci->start = w->chunk_start;
    ci->end = w->chunk_end;
    ci->offset = w->pos;
    ci->size = w->chunk.n;
    buf_t b = {0};
    const size_t at = rec_begin(&b, OP_CHUNK);
    put_u64(&b, w->chunk_start);
    put_u64(&b, w->chunk_end);
    put_u64(&b, w->chunk.n);
    put_u32(&b, crc32_update(0, w->chunk.p, w->chunk.n));
    put_str(&b, ""); /* no compression */
    put_u64(&b, w->chunk.n);
    const uint64_t len = (uint64_t)(b.n - at - 9) + w->chunk.n;
    for (int i = 0; i < 8; ++i) {
        b.p[at + 1 + (size_t)i] = (unsigned char)(len >> (8 * i));
    }
    emit_buf(w, &b);
    emit_buf(w, &w->chunk);
    ci->length = w->pos - ci->offset;
    /* the message indexes, one per channel with messages in this chunk, in channel order */
    const uint64_t index_start = w->pos;
    ci->ch = malloc((size_t)w->n_ch * sizeof *ci->ch);
    ci->ch_off = malloc((size_t)w->n_ch * sizeof *ci->ch_off);
    if ((ci->ch == NULL || ci->ch_off == NULL) && w->n_ch > 0) {
        w->error = ENOMEM;
    }
    for (uint16_t k = 0; k < w->n_ch && !w->error; ++k) {
        channel_t *c = &w->ch[k];
        if (c->n_index == 0) {
            continue;
        }
        ci->ch[ci->n_ch] = (uint16_t)(k + 1);
        ci->ch_off[ci->n_ch] = w->pos;
        ci->n_ch++;
        const size_t ra = rec_begin(&b, OP_MESSAGE_INDEX);
        put_u16(&b, (uint16_t)(k + 1));
        put_u32(&b, (uint32_t)(c->n_index * 16));
        for (size_t i = 0; i < c->n_index; ++i) {
            put_u64(&b, c->index[i].log_time);
            put_u64(&b, c->index[i].offset);
        }
        rec_end(&b, ra);
        emit_buf(w, &b);
        c->n_index = 0;
    }
    free(b.p);
    ci->index_length = w->pos - index_start;
    w->n_chunks++;
    w->chunk_msgs = 0;
    w->chunk.n = 0;
    return w->error ? -1 : 0;
}

/* -1 with errno = the writer's first error */
static int failed(const mcap_writer_t *w) {
    errno = w->error;
    return -1;
}

int mcap_writer_message(mcap_writer_t *w, uint16_t ch, uint32_t sequence, uint64_t log_time,
                        uint64_t publish_time, const void *data, size_t len) {
    if (w->error) {
        return failed(w);
    }
    if (ch == 0 || ch > w->n_ch) {
        errno = EINVAL;
        return -1;
    }
    channel_t *c = &w->ch[ch - 1];
    if (c->n_index == c->cap_index) {
        const size_t cap = c->cap_index ? 2 * c->cap_index : 256;
        index_entry_t *p = realloc(c->index, cap * sizeof *p);
        if (p == NULL) {
            w->error = ENOMEM;
            return failed(w);
        }
        c->index = p;
        c->cap_index = cap;
    }
    c->index[c->n_index].log_time = log_time;
    c->index[c->n_index].offset = w->chunk.n;
    c->n_index++;
    const size_t at = rec_begin(&w->chunk, OP_MESSAGE);
    put_u16(&w->chunk, ch);
    put_u32(&w->chunk, sequence);
    put_u64(&w->chunk, log_time);
    put_u64(&w->chunk, publish_time);
    buf_put(&w->chunk, data, len);
    rec_end(&w->chunk, at);
    if (w->chunk.oom) {
        w->error = ENOMEM;
        return failed(w);
    }
    if (w->chunk_msgs == 0 || log_time < w->chunk_start) {
        w->chunk_start = log_time;
    }
    if (w->chunk_msgs == 0 || log_time > w->chunk_end) {
        w->chunk_end = log_time;
    }
    if (w->messages == 0 || log_time < w->t_first) {
        w->t_first = log_time;
    }
    if (w->messages == 0 || log_time > w->t_last) {
        w->t_last = log_time;
    }
    w->chunk_msgs++;
    w->messages++;
    c->count++;
    if (w->chunk.n >= w->chunk_bytes && write_chunk(w) != 0) {
        return failed(w);
    }
    return 0;
}

int mcap_writer_flush(mcap_writer_t *w) {
    if (write_chunk(w) != 0) {
        return failed(w);
    }
    if (fflush(w->f) != 0) {
        w->error = errno;
        return failed(w);
    }
    return 0;
}

uint64_t mcap_writer_messages(const mcap_writer_t *w) {
    return w->messages;
}

uint64_t mcap_writer_channel_messages(const mcap_writer_t *w, uint16_t ch) {
    return ch >= 1 && ch <= w->n_ch ? w->ch[ch - 1].count : 0;
}

uint64_t mcap_writer_bytes(const mcap_writer_t *w) {
    return w->pos + w->chunk.n;
}

int mcap_writer_metadata(mcap_writer_t *w, const char *name, size_t n, const char *const *keys,
                         const char *const *values) {
    if (write_chunk(w) != 0) { /* a metadata record stands between chunks, not in one */
        return -1;
    }
    buf_t b = {0};
    const size_t at = rec_begin(&b, OP_METADATA);
    put_str(&b, name);
    size_t map = 0;
    for (size_t i = 0; i < n; ++i) {
        map += 8 + strlen(keys[i]) + strlen(values[i]);
    }
    put_u32(&b, (uint32_t)map);
    for (size_t i = 0; i < n; ++i) {
        put_str(&b, keys[i]);
        put_str(&b, values[i]);
    }
    rec_end(&b, at);
    const uint64_t offset = w->pos, length = b.n;
    emit_buf(w, &b);
    free(b.p);
    const size_t ix = rec_begin(&w->metadata_index, OP_METADATA_INDEX);
    put_u64(&w->metadata_index, offset);
    put_u64(&w->metadata_index, length);
    put_str(&w->metadata_index, name);
    rec_end(&w->metadata_index, ix);
    w->n_metadata++;
    if (w->metadata_index.oom) {
        w->error = ENOMEM;
    }
    return w->error ? failed(w) : 0;
}

/* One summary offset record for the group [start, end) of records with opcode op. */
static void summary_offset(buf_t *b, uint8_t op, uint64_t start, uint64_t end) {
    const size_t at = rec_begin(b, OP_SUMMARY_OFFSET);
    put_u8(b, op);
    put_u64(b, start);
    put_u64(b, end - start);
    rec_end(b, at);
}

int mcap_writer_close(mcap_writer_t *w) {
    write_chunk(w);
    buf_t b = {0};
    size_t at = rec_begin(&b, OP_DATA_END);
    put_u32(&b, 0); /* no data section CRC */
    rec_end(&b, at);
    emit_buf(w, &b);

    /* summary: built in b, file offsets = summary_start + offset in b */
    const uint64_t s0 = w->pos;
    buf_put(&b, w->schemas.p, w->schemas.n);
    const uint64_t s_ch = s0 + b.n;
    for (uint16_t k = 0; k < w->n_ch; ++k) {
        buf_put(&b, w->ch[k].record.p, w->ch[k].record.n);
    }
    const uint64_t s_stat = s0 + b.n;
    at = rec_begin(&b, OP_STATISTICS);
    put_u64(&b, w->messages);
    put_u16(&b, w->n_schemas);
    put_u32(&b, w->n_ch);
    put_u32(&b, 0); /* attachments */
    put_u32(&b, w->n_metadata);
    put_u32(&b, (uint32_t)w->n_chunks);
    put_u64(&b, w->messages ? w->t_first : 0);
    put_u64(&b, w->messages ? w->t_last : 0);
    put_u32(&b, (uint32_t)w->n_ch * 10u);
    for (uint16_t k = 0; k < w->n_ch; ++k) {
        put_u16(&b, (uint16_t)(k + 1));
        put_u64(&b, w->ch[k].count);
    }
    rec_end(&b, at);
    const uint64_t s_ci = s0 + b.n;
    for (size_t i = 0; i < w->n_chunks; ++i) {
        const chunk_index_t *ci = &w->chunks[i];
        at = rec_begin(&b, OP_CHUNK_INDEX);
        put_u64(&b, ci->start);
        put_u64(&b, ci->end);
        put_u64(&b, ci->offset);
        put_u64(&b, ci->length);
        put_u32(&b, (uint32_t)(ci->n_ch * 10));
        for (size_t k = 0; k < ci->n_ch; ++k) {
            put_u16(&b, ci->ch[k]);
            put_u64(&b, ci->ch_off[k]);
        }
        put_u64(&b, ci->index_length);
        put_str(&b, "");
        put_u64(&b, ci->size); /* compressed = uncompressed */
        put_u64(&b, ci->size);
        rec_end(&b, at);
    }
    const uint64_t s_mi = s0 + b.n;
    buf_put(&b, w->metadata_index.p, w->metadata_index.n);
    const uint64_t s_end = s0 + b.n;
    if (w->n_schemas > 0) {
        summary_offset(&b, OP_SCHEMA, s0, s_ch);
    }
    if (w->n_ch > 0) {
        summary_offset(&b, OP_CHANNEL, s_ch, s_stat);
    }
    summary_offset(&b, OP_STATISTICS, s_stat, s_ci);
    if (w->n_chunks > 0) {
        summary_offset(&b, OP_CHUNK_INDEX, s_ci, s_mi);
    }
    if (w->n_metadata > 0) {
        summary_offset(&b, OP_METADATA_INDEX, s_mi, s_end);
    }
    /* footer: the summary CRC covers the summary and the footer up to its summary_offset_start field */
    put_u8(&b, OP_FOOTER);
    put_u64(&b, 8 + 8 + 4);
    put_u64(&b, s0);
    put_u64(&b, s_end);
    const uint32_t crc = b.oom ? 0 : crc32_update(0, b.p, b.n);
    put_u32(&b, crc);
    emit_buf(w, &b);
    emit(w, magic, sizeof magic);
    free(b.p);

    int rc = w->error ? -1 : 0;
    if (fclose(w->f) != 0 && rc == 0) {
        w->error = errno;
        rc = -1;
    }
    const int error = w->error;
    for (uint16_t k = 0; k < w->n_ch; ++k) {
        free(w->ch[k].record.p);
        free(w->ch[k].index);
    }
    for (size_t i = 0; i < w->n_chunks; ++i) {
        free(w->chunks[i].ch);
        free(w->chunks[i].ch_off);
    }
    free(w->ch);
    free(w->chunks);
    free(w->schemas.p);
    free(w->metadata_index.p);
    free(w->chunk.p);
    free(w);
    errno = error;
    return rc;
}
