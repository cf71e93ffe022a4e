/* SPDX-License-Identifier: MIT */
/* mca_ring: order, drop-oldest, counters, argument checks, and a two-thread stress test where the
 * consumer checks every record against its sequence number (no torn record, strictly increasing). */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include <pthread.h>
#include <sched.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "mca/err.h"
#include "mca/ring.h"

typedef struct rec16 {
    uint64_t seq;
    uint64_t val;
} rec16_t;

static void test_init_rejects_bad_arguments(void **state) {
    (void)state;
    mca_ring_t r;
    _Alignas(8) unsigned char buf[MCA_RING_STORAGE_SIZE(16, 8)];
    assert_int_equal(mca_ring_init(NULL, buf, sizeof buf, 16, 8), MCA_EINVAL);
    assert_int_equal(mca_ring_init(&r, NULL, sizeof buf, 16, 8), MCA_EINVAL);
    assert_int_equal(mca_ring_init(&r, buf, sizeof buf, 0, 8), MCA_EINVAL);
    assert_int_equal(mca_ring_init(&r, buf, sizeof buf, 16, 6), MCA_EINVAL);  /* not a power of two */
    assert_int_equal(mca_ring_init(&r, buf, sizeof buf, 16, 1), MCA_EINVAL);  /* too small */
    assert_int_equal(mca_ring_init(&r, buf, sizeof buf, 16, 16), MCA_EINVAL); /* storage too small */
    assert_int_equal(mca_ring_init(&r, buf, sizeof buf - 1, 16, 8), MCA_EINVAL);
    assert_int_equal(mca_ring_init(&r, buf + 1, sizeof buf - 1, 8, 2), MCA_EINVAL); /* misaligned */
    assert_int_equal(mca_ring_init(&r, buf, sizeof buf, 16, 8), MCA_OK);
    assert_int_equal(mca_ring_capacity(&r), 8);
    /* Slot = 8-byte sequence word + payload rounded up to 8 bytes. */
    assert_int_equal(MCA_RING_SLOT_SIZE(1), 16);
    assert_int_equal(MCA_RING_SLOT_SIZE(8), 16);
    assert_int_equal(MCA_RING_SLOT_SIZE(9), 24);
}

static void test_fifo_order_and_empty(void **state) {
    (void)state;
    mca_ring_t r;
    _Alignas(8) unsigned char buf[MCA_RING_STORAGE_SIZE(sizeof(rec16_t), 8)];
    assert_int_equal(mca_ring_init(&r, buf, sizeof buf, sizeof(rec16_t), 8), MCA_OK);

    rec16_t out = {.seq = 777, .val = 888};
    assert_int_equal(mca_ring_pop(&r, &out), MCA_EAGAIN);
    assert_int_equal(out.seq, 777); /* unchanged on EAGAIN */
    assert_int_equal(out.val, 888);

    /* Interleave pushes and pops across the wrap point several times. */
    uint64_t next_push = 0, next_pop = 0;
    for (int round = 0; round < 50; ++round) {
        const int n = 1 + round % 8;
        for (int i = 0; i < n; ++i, ++next_push) {
            const rec16_t in = {.seq = next_push, .val = next_push * 31u + 7u};
            mca_ring_push(&r, &in);
        }
        for (int i = 0; i < n; ++i, ++next_pop) {
            assert_int_equal(mca_ring_pop(&r, &out), MCA_OK);
            assert_int_equal(out.seq, next_pop);
            assert_int_equal(out.val, next_pop * 31u + 7u);
        }
        assert_int_equal(mca_ring_pop(&r, &out), MCA_EAGAIN);
    }
    mca_ring_stats_t st;
    mca_ring_stats(&r, &st);
    assert_int_equal(st.pushed, next_push);
    assert_int_equal(st.popped, next_push);
    assert_int_equal(st.dropped, 0);
    assert_int_equal(st.pending, 0);
}

static void test_full_ring_drops_oldest(void **state) {
    (void)state;
    mca_ring_t r;
    _Alignas(8) unsigned char buf[MCA_RING_STORAGE_SIZE(sizeof(rec16_t), 8)];
    assert_int_equal(mca_ring_init(&r, buf, sizeof buf, sizeof(rec16_t), 8), MCA_OK);
    mca_ring_stats_t st;

    /* Exactly full: nothing lost. */
    for (uint64_t i = 0; i < 8; ++i) {
        const rec16_t in = {.seq = i, .val = ~i};
        mca_ring_push(&r, &in);
    }
    mca_ring_stats(&r, &st);
    assert_int_equal(st.pushed, 8);
    assert_int_equal(st.dropped, 0);
    assert_int_equal(st.pending, 8);

    /* 12 more: records 0..11 are overwritten, 12..19 remain. */
    for (uint64_t i = 8; i < 20; ++i) {
        const rec16_t in = {.seq = i, .val = ~i};
        mca_ring_push(&r, &in);
    }
    mca_ring_stats(&r, &st);
    assert_int_equal(st.pushed, 20);
    assert_int_equal(st.popped, 0);
    assert_int_equal(st.dropped, 12); /* counted before the consumer even looks */
    assert_int_equal(st.pending, 8);

    rec16_t out;
    for (uint64_t i = 12; i < 20; ++i) {
        assert_int_equal(mca_ring_pop(&r, &out), MCA_OK);
        assert_int_equal(out.seq, i);
        assert_int_equal(out.val, ~i);
    }
    assert_int_equal(mca_ring_pop(&r, &out), MCA_EAGAIN);
    mca_ring_stats(&r, &st);
    assert_int_equal(st.pushed, 20);
    assert_int_equal(st.popped, 8);
    assert_int_equal(st.dropped, 12);
    assert_int_equal(st.pending, 0);

    /* Partly read, then overrun by exactly one record: only the oldest unread one goes. */
    for (uint64_t i = 20; i < 28; ++i) {
        const rec16_t in = {.seq = i, .val = ~i};
        mca_ring_push(&r, &in);
    }
    assert_int_equal(mca_ring_pop(&r, &out), MCA_OK);
    assert_int_equal(out.seq, 20);
    for (uint64_t i = 28; i < 30; ++i) { /* 21..29 = 9 records for 8 slots: 21 is lost */
        const rec16_t in = {.seq = i, .val = ~i};
        mca_ring_push(&r, &in);
    }
    assert_int_equal(mca_ring_pop(&r, &out), MCA_OK);
    assert_int_equal(out.seq, 22);
    mca_ring_stats(&r, &st);
    assert_int_equal(st.dropped, 13);
    assert_int_equal(st.popped, 10);
    assert_int_equal(st.pending, 7);
    assert_int_equal(st.pushed, st.popped + st.dropped + st.pending);
}

static void test_odd_element_size(void **state) {
    (void)state;
    enum { ELEM = 13, CAP = 4 };
    mca_ring_t r;
    _Alignas(8) unsigned char buf[MCA_RING_STORAGE_SIZE(ELEM, CAP)];
    assert_int_equal(mca_ring_init(&r, buf, sizeof buf, ELEM, CAP), MCA_OK);
    for (int k = 0; k < 10; ++k) {
        unsigned char in[ELEM], out[ELEM + 3];
        for (int i = 0; i < ELEM; ++i) {
            in[i] = (unsigned char)(k * 17 + i);
        }
        memset(out, 0xAB, sizeof out);
        mca_ring_push(&r, in);
        assert_int_equal(mca_ring_pop(&r, out), MCA_OK);
        assert_memory_equal(in, out, ELEM);
        /* pop writes exactly elem_size bytes */
        assert_int_equal(out[ELEM], 0xAB);
        assert_int_equal(out[ELEM + 2], 0xAB);
    }
}

/* ---- two-thread stress ---- */

enum { STRESS_WORDS = 30 };
typedef struct stress_rec {
    uint64_t seq;
    uint64_t w[STRESS_WORDS];
    uint64_t sum;
} stress_rec_t;

static uint64_t mix(uint64_t x) {
    x ^= x >> 33;
    x *= 0xff51afd7ed558ccdULL;
    x ^= x >> 33;
    x *= 0xc4ceb9fe1a85ec53ULL;
    x ^= x >> 33;
    return x;
}

static void make_rec(stress_rec_t *r, uint64_t seq) {
    r->seq = seq;
    uint64_t sum = seq;
    for (int i = 0; i < STRESS_WORDS; ++i) {
        r->w[i] = mix(seq * STRESS_WORDS + (uint64_t)i);
        sum += r->w[i] * (uint64_t)(i + 1);
    }
    r->sum = sum;
}

static int rec_ok(const stress_rec_t *r) {
    stress_rec_t ref;
    make_rec(&ref, r->seq);
    return memcmp(&ref, r, sizeof ref) == 0;
}

typedef struct stress_ctx {
    mca_ring_t ring;
    uint64_t n;
    _Atomic int started;
    _Atomic int done;
} stress_ctx_t;

static void *producer(void *arg) {
    stress_ctx_t *c = arg;
    atomic_fetch_add(&c->started, 1);
    while (atomic_load(&c->started) < 2) {
    }
    stress_rec_t r;
    for (uint64_t i = 0; i < c->n; ++i) {
        make_rec(&r, i);
        mca_ring_push(&c->ring, &r);
    }
    atomic_store_explicit(&c->done, 1, memory_order_release);
    return NULL;
}

typedef struct stress_result {
    uint64_t popped, bad, non_increasing, last;
} stress_result_t;

static void consume(stress_ctx_t *c, stress_result_t *res) {
    atomic_fetch_add(&c->started, 1);
    while (atomic_load(&c->started) < 2) {
    }
    stress_rec_t r;
    int64_t last = -1;
    uint64_t iter = 0;
    for (;;) {
        const int done = atomic_load_explicit(&c->done, memory_order_acquire);
        const int rc = mca_ring_pop(&c->ring, &r);
        if (rc == MCA_EAGAIN) {
            if (done) {
                break; /* producer finished before our last look and the ring is empty */
            }
            sched_yield(); /* be kind to a loaded CI machine */
            continue;
        }
        assert_int_equal(rc, MCA_OK);
        res->popped++;
        if (!rec_ok(&r)) {
            res->bad++;
        }
        if ((int64_t)r.seq <= last) {
            res->non_increasing++;
        }
        last = (int64_t)r.seq;
        /* Now and then fall behind so the producer laps us. */
        if (++iter % 20000 == 0) {
            const struct timespec ts = {0, 200000};
            nanosleep(&ts, NULL);
        }
    }
    res->last = (uint64_t)last;
}

static void run_stress(size_t capacity, uint64_t n) {
    stress_ctx_t *c = calloc(1, sizeof *c);
    const size_t bytes = MCA_RING_STORAGE_SIZE(sizeof(stress_rec_t), capacity);
    void *storage = aligned_alloc(64, (bytes + 63) & ~(size_t)63);
    assert_non_null(c);
    assert_non_null(storage);
    assert_int_equal(mca_ring_init(&c->ring, storage, bytes, sizeof(stress_rec_t), capacity), MCA_OK);
    c->n = n;
    pthread_t th;
    assert_int_equal(pthread_create(&th, NULL, producer, c), 0);
    stress_result_t res = {0};
    consume(c, &res);
    assert_int_equal(pthread_join(th, NULL), 0);

    mca_ring_stats_t st;
    mca_ring_stats(&c->ring, &st);
    print_message("  capacity %zu: pushed %llu popped %llu dropped %llu\n", capacity,
                  (unsigned long long)st.pushed, (unsigned long long)st.popped,
                  (unsigned long long)st.dropped);
    assert_int_equal(res.bad, 0);
    assert_int_equal(res.non_increasing, 0);
    assert_int_equal(st.pushed, n);
    assert_int_equal(st.popped, res.popped);
    assert_int_equal(st.pending, 0);
    assert_int_equal(st.popped + st.dropped, st.pushed);
    assert_true(res.popped > 0);
    assert_int_equal(res.last, n - 1); /* the newest record is never dropped once pushing stops */
    free(storage);
    free(c);
}

/* A ring and its storage in one block moved elsewhere (as two processes map one memfd at different
 * addresses): the copy works; a producer with its own geometry (mca_ring_producer_t) never writes outside the
 * storage even when the ring's fields are scribbled over (the consumer may be another process). */
/* push_parts writes only the given words of a record (a range past the end cut there, on a record whose size
 * is not a multiple of 8); the slot's other words keep the earlier record's. */
static void test_push_parts(void **state) {
    (void)state;
    enum { CAP = 2, SIZE = 60 }; /* 7 whole words and 4 bytes */
    static mca_ring_t ring;
    static _Alignas(64) unsigned char storage[MCA_RING_STORAGE_SIZE(SIZE, CAP)];
    assert_int_equal(mca_ring_init(&ring, storage, sizeof storage, SIZE, CAP), MCA_OK);
    mca_ring_producer_t p;
    mca_ring_producer_init(&p, &ring);
    unsigned char a[SIZE], b[SIZE], out[SIZE], want[SIZE];
    for (int i = 0; i < SIZE; ++i) {
        a[i] = (unsigned char)(1 + i);
        b[i] = (unsigned char)(101 + i);
    }
    const mca_ring_part_t parts[] = {{0, 16}, {40, 8}, {56, 64}}; /* words 0-1, 5, and the last 4 bytes */
    mca_ring_producer_push_parts(&p, a, parts, 3);                /* slot 0, never written before */
    assert_int_equal(mca_ring_pop(&ring, out), MCA_OK);
    memset(want, 0, sizeof want);
    memcpy(want, a, 16);
    memcpy(want + 40, a + 40, 8);
    memcpy(want + 56, a + 56, 4);
    assert_memory_equal(out, want, SIZE);

    mca_ring_producer_push(&p, b);                 /* slot 1 */
    mca_ring_producer_push(&p, b);                 /* slot 0: whole b */
    mca_ring_producer_push_parts(&p, a, parts, 3); /* slot 1 again (over b): drops the oldest b */
    assert_int_equal(mca_ring_pop(&ring, out), MCA_OK);
    assert_memory_equal(out, b, SIZE);
    assert_int_equal(mca_ring_pop(&ring, out), MCA_OK);
    memcpy(want, b, SIZE);
    memcpy(want, a, 16);
    memcpy(want + 40, a + 40, 8);
    memcpy(want + 56, a + 56, 4);
    assert_memory_equal(out, want, SIZE);
    assert_int_equal(mca_ring_pop(&ring, out), MCA_EAGAIN);
    mca_ring_stats_t st;
    mca_ring_stats(&ring, &st);
    assert_int_equal(st.pushed, 4);
    assert_int_equal(st.dropped, 1);
}

static void test_position_independent_and_producer_copy(void **state) {
    (void)state;
    enum { CAP = 8 };
    typedef struct block {
        mca_ring_t ring;
        _Alignas(64) unsigned char storage[MCA_RING_STORAGE_SIZE(sizeof(rec16_t), CAP)];
        unsigned char guard[64];
    } block_t;
    static block_t a, b;
    memset(&a, 0, sizeof a);
    memset(a.guard, 0x5a, sizeof a.guard);
    assert_int_equal(mca_ring_init(&a.ring, a.storage, sizeof a.storage, sizeof(rec16_t), CAP), MCA_OK);
    for (uint64_t k = 0; k < 3; ++k) {
        const rec16_t in = {.seq = k, .val = 100 + k};
        mca_ring_push(&a.ring, &in);
    }
    memcpy(&b, &a, sizeof b); /* the same bytes at another address */
    rec16_t out;
    for (uint64_t k = 0; k < 3; ++k) {
        assert_int_equal(mca_ring_pop(&b.ring, &out), MCA_OK);
        assert_int_equal(out.seq, k);
        assert_int_equal(out.val, 100 + k);
    }
    assert_int_equal(mca_ring_pop(&b.ring, &out), MCA_EAGAIN);

    mca_ring_producer_t p;
    mca_ring_producer_init(&p, &a.ring);
    for (uint64_t k = 3; k < 6; ++k) {
        const rec16_t in = {.seq = k, .val = 100 + k};
        mca_ring_producer_push(&p, &in);
    }
    for (uint64_t k = 0; k < 6; ++k) {
        assert_int_equal(mca_ring_pop(&a.ring, &out), MCA_OK);
        assert_int_equal(out.seq, k);
    }
    /* a consumer scribbles over the ring's geometry and head: the producer's pushes stay in the storage */
    a.ring.mask = ~(uint64_t)0;
    a.ring.slot_size = 1u << 20;
    a.ring.elem_size = 1u << 20;
    a.ring.slots_off = 1 << 30;
    atomic_store(&a.ring.head, 0x123456789abcdefULL);
    for (uint64_t k = 0; k < 2 * CAP; ++k) {
        const rec16_t in = {.seq = k, .val = k};
        mca_ring_producer_push(&p, &in);
    }
    for (size_t i = 0; i < sizeof a.guard; ++i) {
        assert_int_equal(a.guard[i], 0x5a);
    }
}

static void test_stress_two_threads_small_ring(void **state) {
    (void)state;
    run_stress(4, 500000); /* constant lapping and torn reads */
}

static void test_stress_two_threads_large_ring(void **state) {
    (void)state;
    run_stress(1024, 500000);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_init_rejects_bad_arguments),
        cmocka_unit_test(test_fifo_order_and_empty),
        cmocka_unit_test(test_full_ring_drops_oldest),
        cmocka_unit_test(test_odd_element_size),
        cmocka_unit_test(test_position_independent_and_producer_copy),
        cmocka_unit_test(test_push_parts),
        cmocka_unit_test(test_stress_two_threads_small_ring),
        cmocka_unit_test(test_stress_two_threads_large_ring),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
