/* SPDX-License-Identifier: MIT */
/** @file mca/ring.h
 * Lock-free single-producer single-consumer ring of fixed-size records, caller-provided storage.
 *
 * The producer is the 1 kHz loop and NEVER waits: mca_ring_push() always succeeds in bounded time
 * (wait-free); when the consumer is behind, the OLDEST unread record is overwritten. The consumer
 * (a normal-priority thread) notices that it has been lapped and skips ahead, counting the records it
 * lost as dropped. No allocation, no locks, no system calls on either side.
 *
 * Design (per-slot sequence numbers, seqlock style)
 * -------------------------------------------------
 * Records are numbered n = 0, 1, 2, ... in push order; record n lives in slot n & (capacity - 1).
 * `head` (producer-owned) = number of records pushed; `tail` (consumer-owned) = next record to read.
 * Each slot has a 64-bit sequence word `seq`: 2n+1 while record n is being written, 2n+2 once it is
 * complete (0 = never written). Record payload words are accessed with relaxed atomics only, so a torn
 * read is a detected, well-defined event rather than a data race.
 *
 * Producer, record n:                     Consumer, record t = tail:
 *   W1 seq   = 2n+1          (relaxed)        R1 h = head             (acquire)  -> if h == t: EAGAIN
 *   W2 fence(release)                         R2 if h - t > capacity: t = h - capacity (drops counted)
 *   W3 payload words         (relaxed)        R3 s1 = seq             (acquire)
 *   W4 seq   = 2n+2          (release)        R4 payload words        (relaxed)
 *   W5 head  = n+1           (release)        R5 fence(acquire)
 *                                             R6 s2 = seq             (relaxed)
 *                                             valid iff s1 == s2 == 2t+2
 *   (R3 is an early exit that saves a useless copy; R1 and R6 alone make the read safe.)
 *
 * Memory-ordering argument:
 * - Publication: W4 (release) is read by R3 (acquire) with s1 == 2t+2, so every payload store W3 of
 *   record t happens-before the payload loads R4: a valid read sees all of record t. R1 (acquire of W5)
 *   guarantees that seq of every record < h is already >= its "complete" value, so R3 never sees an
 *   older record's value for t < h, only t's own (2t+2) or a later one (lapped).
 * - Torn-read detection: suppose the producer starts record m = t + k*capacity (k >= 1) in the same slot
 *   while R4 runs and R4 reads at least one payload word written by W3 of record m. W2 (release fence)
 *   is sequenced before that W3 and R5 (acquire fence) after that R4, so W2 synchronizes-with R5 and
 *   W1 (seq = 2m+1) happens-before R6: R6 returns >= 2m+1 != s1, and the record is rejected. If R4
 *   read no word of record m, the copy is record t intact whatever R6 returns.
 * - Lapping: if s1 (or s2) != 2t+2 the slot holds (or is receiving) record m = (s-1)/2 >= t+capacity;
 *   every record below m - capacity + 1 has been overwritten, so the consumer sets tail to that value
 *   (at least t+1) and counts the skipped records as dropped. The consumer therefore never spins on an
 *   unfinished producer write, and a returned record is never torn and never older than one already
 *   returned: sequence numbers seen by the consumer are strictly increasing.
 * - Counters: `head` doubles as the pushed count (written by the producer only); `popped` and
 *   `dropped` are written by the consumer only. All are atomics so any thread may read them.
 *   Records the producer overwrote but the consumer has not yet skipped are added to `dropped` by
 *   mca_ring_stats(), so at any time pushed == popped + dropped + pending.
 *
 * Threading: exactly one producer thread and one consumer thread (they may be the same). Counters may
 * be read from any thread. 64-bit counters do not wrap in practice (5.8e8 years at 1 kHz).
 *
 * Between processes: the ring holds no pointer (its storage is an offset from the ring itself) and no
 * lock, so a ring and its storage in one MAP_SHARED mapping (memfd) work in two processes mapping it at
 * different addresses, as long as storage and ring lie in the same mapping. The lock-free 64-bit
 * atomics used here are address-free on the platforms mca supports (x86-64, aarch64). The DDS bridge's
 * publisher process (mca/dds_bridge.h) uses it so.
 */
#ifndef MCA_RING_H
#define MCA_RING_H

#include <stdatomic.h>
#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/** Bytes of one slot for records of elem_size bytes: sequence word + payload rounded up to 8. */
#define MCA_RING_SLOT_SIZE(elem_size) (sizeof(uint64_t) + ((((size_t)(elem_size)) + 7u) & ~(size_t)7u))
/** Bytes of storage mca_ring_init() needs (storage must also be 8-byte aligned). */
#define MCA_RING_STORAGE_SIZE(elem_size, capacity) (MCA_RING_SLOT_SIZE(elem_size) * (size_t)(capacity))
/** Largest capacity accepted (records). */
#define MCA_RING_MAX_CAPACITY (1u << 24)

/** Counters; pushed == popped + dropped + pending at every instant. */
typedef struct mca_ring_stats {
    uint64_t pushed;  /**< records pushed by the producer */
    uint64_t popped;  /**< records returned by mca_ring_pop() */
    uint64_t dropped; /**< records overwritten before the consumer read them */
    uint64_t pending; /**< records still readable now */
} mca_ring_stats_t;

/** Ring state; treat as opaque. Producer and consumer fields on separate cache lines. */
typedef struct mca_ring {
    _Alignas(64) _Atomic uint64_t head; /**< producer: records pushed */
    _Alignas(64) _Atomic uint64_t tail; /**< consumer: next record to read */
    _Atomic uint64_t popped;
    _Atomic uint64_t dropped;
    /** Caller storage as an offset from this struct's own address (read-only after init): a ring and its
     *  storage placed in one shared mapping work at whatever address each process maps it (no pointer
     *  inside). */
    _Alignas(64) int64_t slots_off;
    size_t elem_size;
    size_t slot_size;
    uint64_t mask;
} mca_ring_t;

/**
 * Prepare a ring over caller-provided storage. Context: init (not concurrently with push/pop).
 * @param[out] ring         ring to initialise
 * @param[in]  storage      at least MCA_RING_STORAGE_SIZE(elem_size, capacity) bytes, 8-byte aligned;
 *                          owned by the caller and must outlive the ring
 * @param[in]  storage_size bytes available at storage
 * @param[in]  elem_size    bytes per record (> 0)
 * @param[in]  capacity     records, a power of two in [2, MCA_RING_MAX_CAPACITY]
 * @retval MCA_OK
 * @retval MCA_EINVAL NULL pointer, misaligned storage, elem_size 0, capacity not a power of two or
 *                    out of range, storage_size too small
 */
int mca_ring_init(mca_ring_t *ring, void *storage, size_t storage_size, size_t elem_size, size_t capacity);

/**
 * Append one record (elem_size bytes copied from rec). Never fails and never waits; overwrites the
 * oldest unread record when the ring is full. Context: rt (the single producer). No argument checks.
 */
void mca_ring_push(mca_ring_t *ring, const void *rec);

/**
 * Take the oldest intact record into out (elem_size bytes). Context: non-rt (the single consumer).
 * Skips (and counts as dropped) records that the producer overwrote.
 * @retval MCA_OK     out holds a complete record
 * @retval MCA_EAGAIN the ring is empty; out is unchanged
 */
int mca_ring_pop(mca_ring_t *ring, void *out);

/** Snapshot of the counters. Context: any thread. The fields are read one after the other, so they
 *  are exactly consistent only when producer and consumer are quiet. */
void mca_ring_stats(const mca_ring_t *ring, mca_ring_stats_t *out);

/** The producer's own copy of a ring's geometry (storage address, record and slot size, mask), for a ring in
 *  memory its consumer can write (another process, mca/dds_bridge.h): a push through it reads nothing from
 *  the ring but `head`, which it alone writes and only uses masked, so a consumer that scribbles over the
 *  ring's fields cannot make the producer write outside the storage. */
typedef struct mca_ring_producer {
    mca_ring_t *ring;
    unsigned char *slots;
    size_t elem_size;
    size_t slot_size;
    uint64_t mask;
} mca_ring_producer_t;

/** Take the geometry of a ring this process initialised (mca_ring_init). Context: init. */
void mca_ring_producer_init(mca_ring_producer_t *p, mca_ring_t *ring);

/** mca_ring_push() through the producer's copy of the geometry. Context: rt (the single producer). */
void mca_ring_producer_push(const mca_ring_producer_t *p, const void *rec);

/** A byte range of a record: offset and length, both multiples of 8. */
typedef struct mca_ring_part {
    size_t offset, len;
} mca_ring_part_t;

/** mca_ring_producer_push() of only @p parts of the record (n_parts ranges inside the record; a range past
 *  its end is cut there): the slot's other words keep what an earlier record in that slot left (zero at
 *  first), and a pop copies them as they are. For records of which a varying part is in use (the DDS
 *  snapshot: the arms and pairs there are), so that the unused rest is not copied on the rt path. The
 *  sequence words and the ordering are those of a whole push. Context: rt (the single producer). */
void mca_ring_producer_push_parts(const mca_ring_producer_t *p, const void *rec, const mca_ring_part_t *parts,
                                  int n_parts);

/** Capacity in records. */
static inline size_t mca_ring_capacity(const mca_ring_t *ring) {
    return (size_t)ring->mask + 1u;
}

#ifdef __cplusplus
}
#endif
#endif
