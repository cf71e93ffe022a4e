/* SPDX-License-Identifier: MIT */
/* Lock-free SPSC drop-oldest ring; the memory-ordering argument is in mca/ring.h. */
#include "mca/ring.h"

#include <string.h>

#include "mca/err.h"

#ifdef MCA_RING_TEST_HOOK
/* Test builds only (tests/ring): called by mca_ring_pop() halfway through copying a payload, so a
 * single-threaded test can play the producer at the worst moment and check torn-read detection. */
void (*mca_ring_test_hook)(mca_ring_t *ring);
#define RING_TEST_HOOK(r)                                                                                    \
    do {                                                                                                     \
        if (mca_ring_test_hook != NULL) {                                                                    \
            mca_ring_test_hook(r);                                                                           \
        }                                                                                                    \
    } while (0)
#else
#define RING_TEST_HOOK(r) ((void)0)
#endif

/* Slot layout: [seq word][payload words...]; everything is an _Atomic uint64_t. */
static inline _Atomic uint64_t *slot_at(const mca_ring_t *ring, uint64_t n) {
    unsigned char *slots = (unsigned char *)(uintptr_t)((uintptr_t)ring + (uintptr_t)ring->slots_off);
    return (_Atomic uint64_t *)(void *)(slots + (size_t)(n & ring->mask) * ring->slot_size);
}

int mca_ring_init(mca_ring_t *ring, void *storage, size_t storage_size, size_t elem_size, size_t capacity) {
    if (ring == NULL || storage == NULL || elem_size == 0 || capacity < 2 ||
        capacity > MCA_RING_MAX_CAPACITY || (capacity & (capacity - 1)) != 0 ||
        ((uintptr_t)storage & 7u) != 0) {
        return MCA_EINVAL;
    }
    if (elem_size > (SIZE_MAX / MCA_RING_MAX_CAPACITY) - 64 ||
        storage_size < MCA_RING_STORAGE_SIZE(elem_size, capacity)) {
        return MCA_EINVAL;
    }
    ring->slots_off = (int64_t)((uintptr_t)storage - (uintptr_t)ring); /* position independent */
    ring->elem_size = elem_size;
    ring->slot_size = MCA_RING_SLOT_SIZE(elem_size);
    ring->mask = (uint64_t)capacity - 1u;
    const size_t words = ring->slot_size / sizeof(uint64_t);
    for (size_t i = 0; i < capacity; ++i) {
        _Atomic uint64_t *s = slot_at(ring, i);
        for (size_t w = 0; w < words; ++w) {
            atomic_init(&s[w], 0);
        }
    }
    atomic_init(&ring->head, 0);
    atomic_init(&ring->tail, 0);
    atomic_init(&ring->popped, 0);
    atomic_init(&ring->dropped, 0);
    return MCA_OK;
}

/* W3 for bytes [from, to) of the record (from a multiple of 8; to <= elem_size). */
static inline void copy_words(_Atomic uint64_t *payload, const unsigned char *src, size_t from, size_t to) {
    const size_t full = to / 8u;
    for (size_t w = from / 8u; w < full; ++w) {
        uint64_t v;
        memcpy(&v, src + 8u * w, 8u);
        atomic_store_explicit(&payload[w], v, memory_order_relaxed);
    }
    if (to % 8u != 0 && from < to) {
        uint64_t v = 0;
        memcpy(&v, src + 8u * full, to % 8u);
        atomic_store_explicit(&payload[full], v, memory_order_relaxed);
    }
}

/* The producer's side, from the geometry given (the ring's own, or the producer's copy of it): the whole
 * record (parts NULL) or the given byte ranges of it. */
static inline void push_at(_Atomic uint64_t *head, unsigned char *slots, size_t elem_size, size_t slot_size,
                           uint64_t mask, const void *rec, const mca_ring_part_t *parts, int n_parts) {
    /* Only this thread writes head, so a relaxed load reads our own last store. */
    const uint64_t n = atomic_load_explicit(head, memory_order_relaxed);
    _Atomic uint64_t *s = (_Atomic uint64_t *)(void *)(slots + (size_t)(n & mask) * slot_size);
    _Atomic uint64_t *payload = s + 1;

    atomic_store_explicit(&s[0], 2u * n + 1u, memory_order_relaxed); /* W1: writing */
    atomic_thread_fence(memory_order_release);                       /* W2 */
    if (parts == NULL) {                                             /* W3 */
        copy_words(payload, rec, 0, elem_size);
    } else {
        for (int k = 0; k < n_parts; ++k) {
            const size_t from = parts[k].offset & ~(size_t)7u;
            if (from < elem_size) {
                const size_t len = parts[k].len < elem_size - from ? parts[k].len : elem_size - from;
                copy_words(payload, rec, from, from + len);
            }
        }
    }
    atomic_store_explicit(&s[0], 2u * n + 2u, memory_order_release); /* W4: complete */
    atomic_store_explicit(head, n + 1u, memory_order_release);       /* W5 */
}

void mca_ring_push(mca_ring_t *ring, const void *rec) {
    push_at(&ring->head, (unsigned char *)(void *)slot_at(ring, 0), ring->elem_size, ring->slot_size,
            ring->mask, rec, NULL, 0);
}

void mca_ring_producer_init(mca_ring_producer_t *p, mca_ring_t *ring) {
    p->ring = ring;
    p->slots = (unsigned char *)(void *)slot_at(ring, 0);
    p->elem_size = ring->elem_size;
    p->slot_size = ring->slot_size;
    p->mask = ring->mask;
}

void mca_ring_producer_push(const mca_ring_producer_t *p, const void *rec) {
    push_at(&p->ring->head, p->slots, p->elem_size, p->slot_size, p->mask, rec, NULL, 0);
}

void mca_ring_producer_push_parts(const mca_ring_producer_t *p, const void *rec, const mca_ring_part_t *parts,
                                  int n_parts) {
    push_at(&p->ring->head, p->slots, p->elem_size, p->slot_size, p->mask, rec, parts, n_parts);
}

/* First record that can still be intact when a slot shows sequence word s (record (s-1)/2 is in it). */
static uint64_t first_survivor(const mca_ring_t *ring, uint64_t s) {
    const uint64_t m = (s - 1u) / 2u;
    return m - ring->mask; /* m - capacity + 1 */
}

int mca_ring_pop(mca_ring_t *ring, void *out) {
    uint64_t t = atomic_load_explicit(&ring->tail, memory_order_relaxed);
    const uint64_t cap = ring->mask + 1u;
    const size_t full = ring->elem_size / 8u;
    const size_t rest = ring->elem_size % 8u;
    unsigned char *dst = out;
    uint64_t lost = 0;
    int rc = MCA_EAGAIN;

    for (;;) {
        const uint64_t h = atomic_load_explicit(&ring->head, memory_order_acquire); /* R1 */
        if (h == t) {
            break;
        }
        if (h - t > cap) { /* R2: lapped by more than a whole ring */
            lost += h - cap - t;
            t = h - cap;
        }
        const _Atomic uint64_t *s = slot_at(ring, t);
        const _Atomic uint64_t *payload = s + 1;
        const uint64_t want = 2u * t + 2u;
        const uint64_t s1 = atomic_load_explicit(&s[0], memory_order_acquire); /* R3 */
        if (s1 != want) {
            /* Overwritten (or being overwritten) since we read head; s1 > want by R1. */
            const uint64_t nt = first_survivor(ring, s1);
            lost += nt - t;
            t = nt;
            continue;
        }
        for (size_t w = 0; w < full; ++w) { /* R4 */
            if (w == full / 2) {
                RING_TEST_HOOK(ring);
            }
            const uint64_t v = atomic_load_explicit(&payload[w], memory_order_relaxed);
            memcpy(dst + 8u * w, &v, 8u);
        }
        if (rest != 0) {
            const uint64_t v = atomic_load_explicit(&payload[full], memory_order_relaxed);
            memcpy(dst + 8u * full, &v, rest);
        }
        atomic_thread_fence(memory_order_acquire);                             /* R5 */
        const uint64_t s2 = atomic_load_explicit(&s[0], memory_order_relaxed); /* R6 */
        if (s2 != want) { /* torn: the producer started a later record in this slot */
            const uint64_t nt = first_survivor(ring, s2);
            lost += nt - t;
            t = nt;
            continue;
        }
        t += 1u;
        rc = MCA_OK;
        break;
    }
    /* Counters are consumer-owned: plain read-modify-write through relaxed load/store. */
    if (lost != 0) {
        atomic_store_explicit(&ring->dropped,
                              atomic_load_explicit(&ring->dropped, memory_order_relaxed) + lost,
                              memory_order_relaxed);
    }
    if (rc == MCA_OK) {
        atomic_store_explicit(&ring->popped, atomic_load_explicit(&ring->popped, memory_order_relaxed) + 1u,
                              memory_order_relaxed);
    }
    atomic_store_explicit(&ring->tail, t, memory_order_relaxed);
    return rc;
}

void mca_ring_stats(const mca_ring_t *ring, mca_ring_stats_t *out) {
    /* Consumer fields first: head only grows, so head - tail never underflows. */
    const uint64_t dropped = atomic_load_explicit(&ring->dropped, memory_order_acquire);
    const uint64_t popped = atomic_load_explicit(&ring->popped, memory_order_acquire);
    const uint64_t t = atomic_load_explicit(&ring->tail, memory_order_acquire);
    const uint64_t h = atomic_load_explicit(&ring->head, memory_order_acquire);
    const uint64_t cap = ring->mask + 1u;
    const uint64_t lag = h >= t ? h - t : 0;
    out->pushed = h;
    out->popped = popped;
    out->dropped = dropped + (lag > cap ? lag - cap : 0);
    out->pending = lag > cap ? cap : lag;
}
