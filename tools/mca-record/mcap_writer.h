/* SPDX-License-Identifier: MIT */
/* A small MCAP writer (https://mcap.dev/spec, version 0) for mca-record: header, schemas and channels in the
 * data section, messages in uncompressed chunks each followed by its message indexes, then the summary
 * (schemas, channels, statistics, chunk indexes), summary offsets and the footer. Chunk and summary CRCs
 * are written, so any MCAP reader can check them. Messages are written as given (for ROS 2: the CDR bytes
 * with their 4-byte encapsulation header, unchanged). Context: non-rt, one thread. */
#ifndef MCA_RECORD_MCAP_WRITER_H
#define MCA_RECORD_MCAP_WRITER_H

#include <stddef.h>
#include <stdint.h>

typedef struct mcap_writer mcap_writer_t;

/** Opens path for writing and writes the magic and the header record (profile, library).
 *  chunk_bytes: a chunk is closed once its records reach this size. NULL on error (errno set). */
mcap_writer_t *mcap_writer_open(const char *path, const char *profile, const char *library,
                                size_t chunk_bytes);

/** A schema record (name e.g. "sensor_msgs/msg/JointState", encoding "ros2msg", data its text); its id
 *  (1..) or 0 on error. */
uint16_t mcap_writer_schema(mcap_writer_t *w, const char *name, const char *encoding, const void *data,
                            size_t len);

/** A channel record; metadata: n_meta key/value pairs (keys[i], values[i]); its id (1..) or 0 on error. */
uint16_t mcap_writer_channel(mcap_writer_t *w, uint16_t schema_id, const char *topic, const char *encoding,
                             size_t n_meta, const char *const *keys, const char *const *values);

/** One message of channel ch (times in ns since the epoch). 0 or -1 (write error, errno set). */
int mcap_writer_message(mcap_writer_t *w, uint16_t ch, uint32_t sequence, uint64_t log_time,
                        uint64_t publish_time, const void *data, size_t len);

/** A metadata record (name, n key/value pairs) between chunks, indexed in the summary: what the recorder
 *  knows of the recording itself (its gaps). 0 or -1 (write error, errno set). */
int mcap_writer_metadata(mcap_writer_t *w, const char *name, size_t n, const char *const *keys,
                         const char *const *values);

/** Writes the open chunk (if it holds messages) and flushes the file: what was recorded so far survives a
 *  crash of the recorder (the file then lacks its summary and footer, `mcap recover` mends it). */
int mcap_writer_flush(mcap_writer_t *w);

/** Messages written so far, in all and on channel ch; bytes written to the file so far. */
uint64_t mcap_writer_messages(const mcap_writer_t *w);
uint64_t mcap_writer_channel_messages(const mcap_writer_t *w, uint16_t ch);
uint64_t mcap_writer_bytes(const mcap_writer_t *w);

/** Last chunk, data end, summary, footer, magic; closes the file and frees w. 0 or -1 (write error). */
int mcap_writer_close(mcap_writer_t *w);

#endif
