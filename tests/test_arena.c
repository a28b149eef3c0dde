/* test_arena: the bump allocator of frame-lifetime memory (pf_arena.h):
 * alignment, zeroing, growth across blocks, reset reusing the memory,
 * overflowing sizes refused, release emptying the arena. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include <cmocka.h>

#include "pf_arena.h"

static void test_aligned_zeroed_disjoint(void **state)
{
    (void)state;
    pf_arena a;
    memset(&a, 0, sizeof a);
    unsigned char *p[40];
    size_t sizes[40];
    for (int k = 0; k < 40; k++) {
        sizes[k] = (size_t)(k * 37 % 300) + 1;
        p[k] = pf_arena_alloc(&a, sizes[k]);
        assert_non_null(p[k]);
        assert_int_equal((uintptr_t)p[k] % PF_ARENA_ALIGN, 0);
        for (size_t i = 0; i < sizes[k]; i++) assert_int_equal(p[k][i], 0);
        memset(p[k], k + 1, sizes[k]);
    }
    /* no buffer overlaps another: each still holds its own byte */
    for (int k = 0; k < 40; k++)
        for (size_t i = 0; i < sizes[k]; i++) assert_int_equal(p[k][i], k + 1);
    pf_arena_release(&a);
    assert_null(a.blocks);
    assert_int_equal(a.reserved, 0);
}

static void test_large_and_growth(void **state)
{
    (void)state;
    pf_arena a;
    memset(&a, 0, sizeof a);
    /* larger than a block, then many small ones spilling into new blocks */
    float *big = pf_arena_calloc(&a, 3u << 20, sizeof(float));
    assert_non_null(big);
    big[(3u << 20) - 1] = 1.0f;
    for (int k = 0; k < 100; k++) assert_non_null(pf_arena_alloc(&a, 64 << 10));
    assert_true(a.reserved >= a.used);
    assert_true(a.used >= (size_t)(12u << 20) + 100u * (64u << 10));
    /* reset: one block holding everything, reused without growth */
    pf_arena_reset(&a);
    size_t reserved = a.reserved;
    assert_non_null(a.blocks);
    unsigned char *q = pf_arena_calloc(&a, 3u << 20, sizeof(float));
    assert_non_null(q);
    for (size_t i = 0; i < (size_t)(12u << 20); i += 4099) assert_int_equal(q[i], 0); /* zeroed again */
    for (int k = 0; k < 100; k++) assert_non_null(pf_arena_alloc(&a, 64 << 10));
    assert_int_equal(a.reserved, reserved);
    pf_arena_release(&a);
}

static void test_bad_sizes(void **state)
{
    (void)state;
    pf_arena a;
    memset(&a, 0, sizeof a);
    assert_null(pf_arena_alloc(&a, 0));
    assert_null(pf_arena_alloc(&a, SIZE_MAX));
    assert_null(pf_arena_alloc(&a, SIZE_MAX - 10));
    assert_null(pf_arena_calloc(&a, SIZE_MAX / 2, 4)); /* count * size overflows */
    assert_null(pf_arena_calloc(&a, 0, 4));
    assert_int_equal(a.used, 0);
    pf_arena_release(&a);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_aligned_zeroed_disjoint),
        cmocka_unit_test(test_large_and_growth),
        cmocka_unit_test(test_bad_sizes),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
