/* SPDX-License-Identifier: MIT */
/* mca_ring torn-read and lapping detection, deterministic: ring.c is compiled here with
 * MCA_RING_TEST_HOOK, which calls back halfway through the consumer's payload copy; the callback plays
 * the producer at that worst moment. Every record's words derive from its sequence number, so a torn
 * copy (half one record, half another) cannot pass the content check. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include <string.h>

#include "mca/err.h"
#include "mca/ring.h"

extern void (*mca_ring_test_hook)(mca_ring_t *ring);

enum { WORDS = 8, CAP = 4 };
typedef struct rec {
    uint64_t w[WORDS]; /* w[i] = seq * 1000 + i */
} rec_t;

static rec_t make(uint64_t seq) {
    rec_t r;
    for (int i = 0; i < WORDS; ++i) {
        r.w[i] = seq * 1000u + (uint64_t)i;
    }
    return r;
}

/* The record's sequence number if all its words agree, else UINT64_MAX (torn). */
static uint64_t seq_of(const rec_t *r) {
    const uint64_t s = r->w[0] / 1000u;
    for (int i = 0; i < WORDS; ++i) {
        if (r->w[i] != s * 1000u + (uint64_t)i) {
            return UINT64_MAX;
        }
    }
    return s;
}

static mca_ring_t g_ring;
static _Alignas(8) unsigned char g_storage[MCA_RING_STORAGE_SIZE(sizeof(rec_t), CAP)];
static uint64_t g_next;   /* next sequence number the "producer" pushes */
static int g_hook_pushes; /* how many the hook pushes */
static int g_hook_calls;

static void push_n(int n) {
    for (int i = 0; i < n; ++i) {
        const rec_t r = make(g_next++);
        mca_ring_push(&g_ring, &r);
    }
}

static void hook(mca_ring_t *ring) {
    assert_ptr_equal(ring, &g_ring);
    g_hook_calls++;
    mca_ring_test_hook = NULL; /* once */
    push_n(g_hook_pushes);
}

static int setup(void **state) {
    (void)state;
    assert_int_equal(mca_ring_init(&g_ring, g_storage, sizeof g_storage, sizeof(rec_t), CAP), MCA_OK);
    g_next = 0;
    g_hook_calls = 0;
    mca_ring_test_hook = NULL;
    return 0;
}

static void expect_pop(uint64_t seq) {
    rec_t out;
    assert_int_equal(mca_ring_pop(&g_ring, &out), MCA_OK);
    assert_int_equal(seq_of(&out), seq);
}

static void expect_stats(uint64_t pushed, uint64_t popped, uint64_t dropped, uint64_t pending) {
    mca_ring_stats_t st;
    mca_ring_stats(&g_ring, &st);
    assert_int_equal(st.pushed, pushed);
    assert_int_equal(st.popped, popped);
    assert_int_equal(st.dropped, dropped);
    assert_int_equal(st.pending, pending);
}

/* Full ring; while record 0 is being copied the producer writes 4 more: the whole ring is replaced,
 * the half-copied record is torn. The consumer must return record 4 intact and count 0..3 dropped. */
static void test_lapped_during_copy(void **state) {
    (void)state;
    push_n(4);
    g_hook_pushes = 4;
    mca_ring_test_hook = hook;
    expect_pop(4);
    assert_int_equal(g_hook_calls, 1);
    expect_stats(8, 1, 4, 3);
    expect_pop(5);
    expect_pop(6);
    expect_pop(7);
    rec_t out;
    assert_int_equal(mca_ring_pop(&g_ring, &out), MCA_EAGAIN);
    expect_stats(8, 4, 4, 0);
}

/* Full ring; one push during the copy of record 0 overwrites exactly that slot: record 0 is lost,
 * record 1 is the next intact one. */
static void test_one_overwrite_during_copy(void **state) {
    (void)state;
    push_n(4);
    g_hook_pushes = 1;
    mca_ring_test_hook = hook;
    expect_pop(1);
    expect_stats(5, 1, 1, 3);
    expect_pop(2);
    expect_pop(3);
    expect_pop(4);
}

/* A push into ANOTHER slot during the copy must not be mistaken for a tear. */
static void test_push_elsewhere_is_not_a_tear(void **state) {
    (void)state;
    push_n(1);
    g_hook_pushes = 2;
    mca_ring_test_hook = hook;
    expect_pop(0);
    expect_stats(3, 1, 0, 2);
    expect_pop(1);
    expect_pop(2);
}

/* The producer is half-way through record 4 (slot 0 sequence word odd, head not yet advanced): the
 * consumer must skip record 0 without waiting and without returning the half-written slot. */
static void test_producer_mid_write(void **state) {
    (void)state;
    push_n(4);
    _Atomic uint64_t *seq0 = (_Atomic uint64_t *)(void *)g_storage; /* slot 0's sequence word */
    assert_int_equal(atomic_load(seq0), 2u * 0u + 2u);
    atomic_store(seq0, 2u * 4u + 1u);
    expect_pop(1);
    mca_ring_stats_t st;
    mca_ring_stats(&g_ring, &st);
    assert_int_equal(st.dropped, 1);
    assert_int_equal(st.popped, 1);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_setup(test_lapped_during_copy, setup),
        cmocka_unit_test_setup(test_one_overwrite_during_copy, setup),
        cmocka_unit_test_setup(test_push_elsewhere_is_not_a_tear, setup),
        cmocka_unit_test_setup(test_producer_mid_write, setup),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
