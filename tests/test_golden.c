/* test_golden: the golden-picture helper itself (tu_golden.h), so that a
 * broken golden is known to leave something to look at.
 * - tu_golden_diff counts the differing pixels, finds the largest
 *   difference and its bounding box, and draws changed pixels red to yellow
 *   over the dimmed reference;
 * - a mismatched hash writes NAME-actual.png, NAME-expected.png and
 *   NAME-diff.png (read back here) and says how many pixels differ; a
 *   missing or stale reference fails even when the hash matches; passing
 *   again removes the failure pictures;
 * - update mode (SOFTGI_GOLDEN_UPDATE=1) writes the reference only when the
 *   hash is the expected one. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include "test_util.h"
#include "tu_golden.h"

static char g_tmp[256];

static int setup(void **state)
{
    (void)state;
    return tu_tmpdir_create(g_tmp, sizeof g_tmp, "softgi-golden");
}

static int teardown(void **state)
{
    (void)state;
    return tu_tmpdir_remove(g_tmp);
}

/* A 16 x 8 gradient. */
static void gradient(tu_golden_picture *p)
{
    tu_golden_picture_init(p, 16, 8);
    for (uint32_t y = 0; y < 8; y++)
        for (uint32_t x = 0; x < 16; x++) {
            uint8_t *o = p->rgb + 3 * (y * 16 + x);
            o[0] = (uint8_t)(16 * x);
            o[1] = (uint8_t)(32 * y);
            o[2] = 100;
        }
}

static void test_diff(void **state)
{
    (void)state;
    tu_golden_picture a, b;
    gradient(&a);
    gradient(&b);
    uint8_t diff[16 * 8 * 3];
    tu_golden_diff_stats st;
    assert_int_equal(tu_golden_diff(a.rgb, b.rgb, 16, 8, diff, &st), 0);
    assert_int_equal(st.max, 0);
    /* unchanged: the reference's grey, dimmed to a quarter */
    assert_int_equal(diff[0], (29u * 100 >> 8) / 4);
    assert_int_equal(diff[0], diff[1]);
    a.rgb[3 * (2 * 16 + 3) + 1] += 1;  /* (3, 2): 1/255 */
    a.rgb[3 * (5 * 16 + 12) + 2] -= 40; /* (12, 5): 40/255 */
    assert_int_equal(tu_golden_diff(a.rgb, b.rgb, 16, 8, diff, &st), 2);
    assert_int_equal(st.pixels, 2);
    assert_int_equal(st.max, 40);
    assert_int_equal(st.max_x, 12);
    assert_int_equal(st.max_y, 5);
    assert_int_equal(st.x0, 3);
    assert_int_equal(st.x1, 12);
    assert_int_equal(st.y0, 2);
    assert_int_equal(st.y1, 5);
    const uint8_t *small = diff + 3 * (2 * 16 + 3), *large = diff + 3 * (5 * 16 + 12);
    assert_int_equal(small[0], 255); /* red */
    assert_true(small[1] < 16);
    assert_int_equal(large[0], 255); /* yellow */
    assert_int_equal(large[1], 255);
    assert_int_equal(large[2], 0);
    tu_golden_picture_free(&a);
    tu_golden_picture_free(&b);
}

static void test_failure_pictures(void **state)
{
    (void)state;
    char ref[300], fail[300], path[400], msg[8192];
    snprintf(ref, sizeof ref, "%s/ref", g_tmp);
    snprintf(fail, sizeof fail, "%s/fail", g_tmp);
    tu_golden_picture p;
    gradient(&p);
    unsetenv("SOFTGI_GOLDEN_UPDATE");
    /* no reference yet: the matching hash fails, naming the update mode */
    assert_int_equal(tu_golden_verify(ref, fail, "g", 7, 7, &p, msg, sizeof msg), 1);
    assert_non_null(strstr(msg, "SOFTGI_GOLDEN_UPDATE=1"));
    /* update mode with a wrong hash writes nothing */
    setenv("SOFTGI_GOLDEN_UPDATE", "1", 1);
    assert_int_equal(tu_golden_verify(ref, fail, "g", 8, 7, &p, msg, sizeof msg), 1);
    snprintf(path, sizeof path, "%s/g.png", ref);
    assert_false(tu_file_exists(path));
    /* update mode with the expected hash writes the reference */
    assert_int_equal(tu_golden_verify(ref, fail, "g", 7, 7, &p, msg, sizeof msg), 0);
    assert_true(tu_file_exists(path));
    unsetenv("SOFTGI_GOLDEN_UPDATE");
    assert_int_equal(tu_golden_verify(ref, fail, "g", 7, 7, &p, msg, sizeof msg), 0);
    /* a stale reference fails although the hash matches */
    p.rgb[0] ^= 1;
    assert_int_equal(tu_golden_verify(ref, fail, "g", 7, 7, &p, msg, sizeof msg), 1);
    assert_non_null(strstr(msg, "stale"));
    /* a wrong hash: the three pictures, the count and the largest difference */
    p.rgb[3 * (4 * 16 + 9)] ^= 0x80;
    assert_int_equal(tu_golden_verify(ref, fail, "g", 9, 7, &p, msg, sizeof msg), 1);
    print_message("%s\n", msg);
    assert_non_null(strstr(msg, "hash 0000000000000009, expected 0000000000000007"));
    assert_non_null(strstr(msg, "2 of 128 pixels differ"));
    assert_non_null(strstr(msg, "largest difference 128/255 at (9, 4)"));
    const char *kinds[3] = {"actual", "expected", "diff"};
    for (int k = 0; k < 3; k++) {
        snprintf(path, sizeof path, "%s/g-%s.png", fail, kinds[k]);
        assert_non_null(strstr(msg, path));
        tu_golden_picture r;
        tu_golden_picture_load(&r, path);
        assert_int_equal(r.w, 16);
        assert_int_equal(r.h, 8);
        if (k == 0) assert_memory_equal(r.rgb, p.rgb, sizeof(uint8_t) * 16 * 8 * 3);
        if (k == 2) {
            assert_int_equal(r.rgb[3 * (4 * 16 + 9)], 255); /* the changed pixel is red-yellow */
            assert_int_equal(r.rgb[3 * (4 * 16 + 9) + 1], 255);
        }
        tu_golden_picture_free(&r);
    }
    /* passing again removes the failure's pictures */
    p.rgb[0] ^= 1;
    p.rgb[3 * (4 * 16 + 9)] ^= 0x80;
    assert_int_equal(tu_golden_verify(ref, fail, "g", 7, 7, &p, msg, sizeof msg), 0);
    for (int k = 0; k < 3; k++) {
        snprintf(path, sizeof path, "%s/g-%s.png", fail, kinds[k]);
        assert_false(tu_file_exists(path));
    }
    tu_golden_picture_free(&p);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_diff),
        cmocka_unit_test(test_failure_pictures),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
