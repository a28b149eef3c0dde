/* test_frames: frame ranges for batch schedulers (issue 13 item 4).
 * - `--frames A:B` parses as frames A..B-1 (zero-based, B excluded; "A:"
 *   to the end, ":B" from 0), and every bad range (B <= A, past the
 *   sequence, not a number, a sign, a space, an exponent, a huge number)
 *   gives one line and exit 2, in process and through the program;
 * - `softgi sequence --frames`: the folders of two ranges merged by file
 *   name equal a full run's folder byte for byte, for a VPL method whose
 *   state runs from frame to frame (IIR, the frames before A rendered and
 *   not written), for the path-traced references (frames skipped), and
 *   with other thread counts than the full run;
 * - `softgi evaluate --frames`: likewise for the per-frame references, and
 *   a later evaluate without --frames reuses the merged references;
 * - bench and view keep --frames N as a count;
 * - the job profile behind `bench`'s Amdahl tables (pf_jobs.h) adds up:
 *   work is the items' time, span the longest item, the predictions fall
 *   from 1 core to many but never below the span, nested waits are not
 *   counted twice, and the results are those of an unprofiled run. (It
 *   belongs in test_jobs.c, which is not this change's file.) */
#include <dirent.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include <math.h>
#include <time.h>

#include "pf_cli.h"
#include "pf_jobs.h"
#include "test_frame_fixture.h"
#include "test_util.h"

static char g_tmp[256];

/* A six-frame sequence of the embedded Cornell box whose light moves every
 * frame, at 32x24. */
static void write_sequence(const char *path)
{
    FILE *f = fopen(path, "w");
    assert_non_null(f);
    fputs("{\"name\": \"frames-test\", \"scene\": \"embedded:cornell-box\", \"frames\": 6, \"size\": [32, 24],\n"
          " \"lights\": [{\"light\": 0, \"keys\": [{\"frame\": 0, \"position\": [0.278, 0.5388, 0.2795]},\n"
          "  {\"frame\": 5, \"position\": [0.10, 0.45, 0.2795]}]}]}\n",
          f);
    fclose(f);
}

/* ---------------------------------------------------------------- parsing */

static void test_parse(void **state)
{
    (void)state;
    pf_error err;
    uint32_t a = 7, b = 7;
    assert_int_equal(pf_cli_parse_frame_range("--frames", "0:10", &a, &b, &err), PF_OK);
    assert_int_equal(a, 0);
    assert_int_equal(b, 10);
    assert_int_equal(pf_cli_parse_frame_range("--frames", "10:", &a, &b, &err), PF_OK);
    assert_int_equal(a, 10);
    assert_int_equal(b, PF_CLI_FRAMES_END);
    assert_int_equal(pf_cli_parse_frame_range("--frames", ":4", &a, &b, &err), PF_OK);
    assert_int_equal(a, 0);
    assert_int_equal(b, 4);
    assert_int_equal(pf_cli_parse_frame_range("--frames", "7", &a, &b, &err), PF_OK); /* frame 7 alone */
    assert_int_equal(a, 7);
    assert_int_equal(b, 8);
    static const char *const bad[] = {"5:3", "3:3", "x:3", "3:y", "1:2:3", "99999999999999:1", "1:99999999999999",
                                      "-1:3", "+1:3", " 1:3", "1 :3", "1e3:", "0x3:4", ":", "", "4x", "1.5:3", "-2"};
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        if (pf_cli_parse_frame_range("--frames", bad[i], &a, &b, &err) != PF_ERR_ARGUMENT)
            fail_msg("--frames '%s' was accepted", bad[i]);
        assert_non_null(strstr(err.message, "--frames"));
    }
    /* against a sequence of 6 frames: an open end becomes 6; beyond it is refused */
    b = PF_CLI_FRAMES_END;
    assert_int_equal(pf_cli_check_frame_range("--frames", 6, 2, &b, &err), PF_OK);
    assert_int_equal(b, 6);
    b = 6;
    assert_int_equal(pf_cli_check_frame_range("--frames", 6, 5, &b, &err), PF_OK);
    b = 7;
    assert_int_equal(pf_cli_check_frame_range("--frames", 6, 0, &b, &err), PF_ERR_ARGUMENT);
    assert_non_null(strstr(err.message, "has 6 frames"));
    b = PF_CLI_FRAMES_END;
    assert_int_equal(pf_cli_check_frame_range("--frames", 6, 6, &b, &err), PF_ERR_ARGUMENT);

    /* the command decides: a range for sequence, a count for bench and view */
    pf_options o;
    char *seq[] = {"softgi", "sequence", "x.seq.json", "--frames", "2:5"};
    assert_int_equal(pf_cli_parse(&o, 5, seq, &err), PF_OK);
    assert_true(o.frame_range);
    assert_int_equal(o.frame_first, 2);
    assert_int_equal(o.frame_end, 5);
    char *first[] = {"softgi", "--frames", "3:", "sequence", "x.seq.json"}; /* before the command */
    assert_int_equal(pf_cli_parse(&o, 5, first, &err), PF_OK);
    assert_int_equal(o.frame_first, 3);
    assert_int_equal(o.frame_end, PF_CLI_FRAMES_END);
    char *bench[] = {"softgi", "bench", "frame", "--frames", "3"};
    assert_int_equal(pf_cli_parse(&o, 5, bench, &err), PF_OK);
    assert_int_equal(o.frames, 3);
    assert_false(o.frame_range);
    char *bench_range[] = {"softgi", "bench", "raster", "--frames", "0:3"};
    assert_int_equal(pf_cli_parse(&o, 5, bench_range, &err), PF_ERR_ARGUMENT);
    char *render[] = {"softgi", "render", "--frames", "0:3"}; /* render takes a count (frames of a still view) */
    assert_int_equal(pf_cli_parse(&o, 4, render, &err), PF_ERR_ARGUMENT);
    assert_non_null(strstr(err.message, "render takes a frame count N (1..1000); ranges A:B are for sequence"));
    char *render_n[] = {"softgi", "render", "--frames", "3"};
    assert_int_equal(pf_cli_parse(&o, 4, render_n, &err), PF_OK);
    assert_int_equal(o.frames, 3);
}

/* One line of output, and the exit status. */
static void expect_one_line(const char *args, int status, const char *needle)
{
    char out[16384];
    int st = tu_softgi_run(args, out, sizeof out);
    size_t lines = 0;
    for (const char *p = out; *p; p++) lines += *p == '\n';
    if (st != status || lines != 1 || !strstr(out, needle))
        fail_msg("softgi %s\n  exit %d (want %d), %zu lines (want 1), output:\n%s\n  (want '%s')", args, st, status,
                 lines, out, needle);
}

static void test_bad_ranges(void **state)
{
    (void)state;
    char seq[300], args[1024];
    snprintf(seq, sizeof seq, "%s/bad.seq.json", g_tmp);
    write_sequence(seq);
    static const struct {
        const char *range, *needle;
    } bad[] = {
        {"5:3", "B must be greater than A"},
        {"3:3", "B must be greater than A"},
        {"0:7", "the sequence has 6 frames"},
        {"6:", "the sequence has 6 frames"},
        {"99:100", "the sequence has 6 frames"},
        {"x:3", "digits only"},
        {"1:2:3", "expected A:B"},
        {"99999999999999999999:1", "digits only"},
        {"1:4294967297", "digits only"},
        {"-1:3", "digits only"},
        {"' 1:3'", "digits only"},
        {"1e3:", "digits only"},
        {"''", "expected A:B"},
        {":", "expected A:B"},
    };
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        snprintf(args, sizeof args, "sequence %s --frames %s -q -o %s/bad", seq, bad[i].range, g_tmp);
        expect_one_line(args, 2, bad[i].needle);
    }
    snprintf(args, sizeof args, "sequence %s --frames", seq);
    expect_one_line(args, 2, "--frames needs a value");
    expect_one_line("render --frames 0:3", 2, "ranges A:B are for sequence");
    /* evaluate: a range no sequence reaches, and a malformed one */
    snprintf(args, sizeof args, "evaluate --sequences %s --methods ir --out %s/ev-bad --frames 6:", seq, g_tmp);
    expect_one_line(args, 2, "no sequence has these frames");
    snprintf(args, sizeof args, "evaluate --sequences %s --methods ir --out %s/ev-bad --frames 2:1", seq, g_tmp);
    expect_one_line(args, 2, "B must be greater than A");
    /* nothing was written for the refused runs */
    snprintf(args, sizeof args, "%s/bad", g_tmp);
    assert_false(tu_file_exists(args));
}

/* ---------------------------------------------------------------- merging */

static int read_file(const char *path, unsigned char **data, size_t *size)
{
    FILE *f = fopen(path, "rb");
    if (!f) return 0;
    fseek(f, 0, SEEK_END);
    long n = ftell(f);
    fseek(f, 0, SEEK_SET);
    *data = malloc(n > 0 ? (size_t)n : 1);
    *size = n > 0 ? fread(*data, 1, (size_t)n, f) : 0;
    fclose(f);
    return 1;
}

/* Every file of `a` is in `b` with the same bytes and vice versa (one
 * level: a frames folder); returns the number of files. */
static size_t assert_same_folder(const char *a, const char *b)
{
    size_t files = 0;
    for (int pass = 0; pass < 2; pass++) {
        const char *from = pass ? b : a, *to = pass ? a : b;
        DIR *d = opendir(from);
        if (!d) fail_msg("%s: cannot open", from);
        struct dirent *e;
        while ((e = readdir(d))) {
            if (e->d_name[0] == '.') continue;
            char pa[1024], pb[1024];
            snprintf(pa, sizeof pa, "%s/%s", from, e->d_name);
            snprintf(pb, sizeof pb, "%s/%s", to, e->d_name);
            unsigned char *da = NULL, *db = NULL;
            size_t na = 0, nb = 0;
            if (!read_file(pa, &da, &na)) fail_msg("%s: cannot read", pa);
            if (!read_file(pb, &db, &nb)) fail_msg("%s is in %s but not in %s", e->d_name, from, to);
            if (na != nb || memcmp(da, db, na)) fail_msg("%s and %s differ", pa, pb);
            free(da), free(db);
            files += !pass;
        }
        closedir(d);
    }
    return files;
}

/* softgi ARGS must succeed. */
static void run_ok(const char *args)
{
    char out[16384];
    int st = tu_softgi_run(args, out, sizeof out);
    if (st != 0) fail_msg("softgi %s: exit %d\n%s", args, st, out);
}

/* A full run of `opts` into DIR/full and two ranges merged into DIR/merged
 * (each range written to its own folder, then copied by file name). */
static void sequence_merge(const char *seq, const char *tag, const char *opts, const char *r1, const char *r2)
{
    char args[2048], full[512], merged[512], part[2][512];
    snprintf(full, sizeof full, "%s/%s-full", g_tmp, tag);
    snprintf(merged, sizeof merged, "%s/%s-merged", g_tmp, tag);
    snprintf(args, sizeof args, "sequence %s %s -q --threads 2 -o %s", seq, opts, full);
    run_ok(args);
    const char *ranges[2] = {r1, r2};
    for (int i = 0; i < 2; i++) {
        snprintf(part[i], sizeof part[i], "%s/%s-part%d", g_tmp, tag, i);
        snprintf(args, sizeof args, "sequence %s %s -q --threads 1 --frames %s -o %s", seq, opts, ranges[i], part[i]);
        run_ok(args);
    }
    char cmd[4096], out[4096];
    snprintf(cmd, sizeof cmd, "mkdir -p '%s' && cp '%s'/* '%s'/ && cp -f '%s'/* '%s'/", merged, part[0], merged,
             part[1], merged);
    assert_int_equal(tu_run(cmd, out, sizeof out), 0);
    /* 6 frames x (pfm, png, view, depth.pfm) + frames.txt + track.txt */
    assert_int_equal(assert_same_folder(full, merged), 6 * 4 + 2);
    /* a range alone holds only its frames, under the full run's names */
    snprintf(cmd, sizeof cmd, "%s/frame_0000.pfm", part[1]);
    assert_false(tu_file_exists(cmd));
}

static void test_sequence_merge(void **state)
{
    (void)state;
    char seq[300];
    snprintf(seq, sizeof seq, "%s/merge.seq.json", g_tmp);
    write_sequence(seq);
    /* IIR keeps its VPLs from frame to frame: the second range must carry it */
    sequence_merge(seq, "iir", "--method iir --vpls 32", "0:2", "2:");
    /* with --exposure auto the PNGs of every range use frame 0's exposure */
    sequence_merge(seq, "auto", "--vpls 16 --exposure auto", ":3", "3:6");
    /* references: every frame on its own */
    sequence_merge(seq, "ref", "--reference --spp 2 --track-spp 4", "0:4", "4:");
    /* direct light only: the area lights' emitter points carry state too; the second range is frame N alone */
    sequence_merge(seq, "direct", "--direct-only", "0:5", "5");
}

static void test_evaluate_merge(void **state)
{
    (void)state;
    char seq[300], args[2048], cmd[4096], out[8192];
    snprintf(seq, sizeof seq, "%s/eval.seq.json", g_tmp);
    write_sequence(seq);
    const char *common = "--methods ir --size 32x24 --spp 2 --track-spp 4 --vpls 16 -q";
    snprintf(args, sizeof args, "evaluate --sequences %s %s --out %s/ev-full", seq, common, g_tmp);
    run_ok(args);
    snprintf(args, sizeof args, "evaluate --sequences %s %s --out %s/ev-a --frames 0:4", seq, common, g_tmp);
    run_ok(args);
    snprintf(args, sizeof args, "evaluate --sequences %s %s --out %s/ev-b --frames 4:", seq, common, g_tmp);
    run_ok(args);
    /* a range renders only references: no method folder, no table */
    snprintf(cmd, sizeof cmd, "%s/ev-a/eval/ir", g_tmp);
    assert_false(tu_file_exists(cmd));
    snprintf(cmd, sizeof cmd, "mkdir -p %s/ev-m && cp -r %s/ev-a/. %s/ev-m/ && cp -r %s/ev-b/. %s/ev-m/", g_tmp, g_tmp,
             g_tmp, g_tmp, g_tmp);
    assert_int_equal(tu_run(cmd, out, sizeof out), 0);
    char full[512], merged[512];
    snprintf(full, sizeof full, "%s/ev-full/eval/reference", g_tmp);
    snprintf(merged, sizeof merged, "%s/ev-m/eval/reference", g_tmp);
    assert_int_equal(assert_same_folder(full, merged), 6 * 4 + 3); /* + frames.txt, track.txt, stamp */
    /* the merged references are reused, and the methods run */
    snprintf(args, sizeof args, "evaluate --sequences %s %s --out %s/ev-m", seq, common, g_tmp);
    char log[16384];
    assert_int_equal(tu_softgi_run(args, log, sizeof log), 0);
    snprintf(full, sizeof full, "%s/ev-full/eval/ir", g_tmp);
    snprintf(merged, sizeof merged, "%s/ev-m/eval/ir", g_tmp);
    assert_same_folder(full, merged);
    /* a merged folder that lacks a range says which one to render */
    snprintf(cmd, sizeof cmd, "%s/ev-m/eval/reference/frame_0004.pfm", g_tmp);
    assert_int_equal(remove(cmd), 0);
    snprintf(args, sizeof args, "evaluate --sequences %s %s --out %s/ev-m", seq, common, g_tmp);
    expect_one_line(args, 1, "--frames 4:5");
}

/* ---------------------------------------------------------------- job profile */

/* Item i busy-waits (i + 1) x 100 us of CPU time and writes its square. */
static void busy_item(void *ctx, uint32_t item, uint32_t worker)
{
    (void)worker;
    struct timespec a, b;
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &a);
    double want = (item + 1) * 100e-6;
    do clock_gettime(CLOCK_THREAD_CPUTIME_ID, &b);
    while ((double)(b.tv_sec - a.tv_sec) + (double)(b.tv_nsec - a.tv_nsec) * 1e-9 < want);
    ((uint64_t *)ctx)[item] = (uint64_t)item * item;
}

typedef struct nested_ctx {
    pf_jobs *jobs;
    uint64_t *out;
} nested_ctx;

/* One item that runs a parallel-for of 8 busy items inside (as the
 * pipelined VPL update does). */
static void nested_item(void *ctx, uint32_t item, uint32_t worker)
{
    (void)item, (void)worker;
    nested_ctx *c = ctx;
    pf_jobs_parallel_for(c->jobs, busy_item, c->out, 8, 1);
}

static void test_jobs_profile(void **state)
{
    (void)state;
    for (uint32_t threads = 1; threads <= 2; threads++) {
        pf_jobs *jobs = pf_jobs_create(threads);
        assert_non_null(jobs);
        uint64_t out[8] = {0};
        pf_jobs_profile p;
        pf_jobs_profile_read(jobs, &p); /* off: zeros */
        assert_true(p.work_ms == 0.0 && p.jobs == 0);
        pf_jobs_profile_enable(jobs, 1);
        pf_jobs_parallel_for(jobs, busy_item, out, 8, 1); /* 0.1 + 0.2 + ... + 0.8 ms = 3.6 ms */
        pf_jobs_profile_read(jobs, &p);
        for (uint32_t i = 0; i < 8; i++) assert_int_equal(out[i], (uint64_t)i * i);
        assert_int_equal(p.jobs, 1);
        assert_int_equal(p.items, 8);
        assert_true(p.work_ms >= 3.5 && p.work_ms < 3.6 * 3.0);
        assert_true(p.span_ms >= 0.79 && p.span_ms <= p.work_ms);
        assert_true(p.wait_ms >= p.work_ms / threads * 0.9); /* the parallel region holds the work */
        /* pf_jobs_profile_cores: 1, 2, 4, ...: the 1-core prediction is the work; more cores, less, never
         * below the span (grain 1: 8 chunks, ceil(8 / N) of the mean each) */
        assert_true(fabs(p.predicted_ms[0] - p.work_ms) < 1e-9);
        for (int k = 1; k < PF_JOBS_PROFILE_CORES; k++) {
            assert_true(p.predicted_ms[k] <= p.predicted_ms[k - 1] + 1e-9);
            assert_true(p.predicted_ms[k] >= p.span_ms - 1e-9);
        }
        /* nested: the outer item's own time excludes the inner job's, so the work is counted once */
        pf_jobs_profile q;
        nested_ctx c = {jobs, out};
        pf_jobs_parallel_for(jobs, nested_item, &c, 1, 1);
        pf_jobs_profile_read(jobs, &q);
        pf_jobs_profile d = pf_jobs_profile_delta(&p, &q);
        assert_int_equal(d.jobs, 2);
        assert_int_equal(d.items, 9);
        assert_true(d.work_ms >= 3.5 && d.work_ms < 3.6 * 3.0);
        pf_jobs_profile_enable(jobs, 0);
        pf_jobs_destroy(jobs);
    }
}

static int setup(void **state)
{
    (void)state;
    return tu_tmpdir_create(g_tmp, sizeof g_tmp, "softgi-frames");
}

static int teardown(void **state)
{
    (void)state;
    return tu_tmpdir_remove(g_tmp);
}

/* A long stage's progress (gi_frame.progress): the VPL maps of a first frame
 * are reported in pieces, done rising to the total, and listening changes
 * no bit of the image. */
typedef struct maps_log {
    uint32_t calls, last_done, total;
    int rising;
} maps_log;

static void on_progress(void *user, const char *what, uint32_t done, uint32_t total)
{
    maps_log *l = user;
    assert_non_null(strstr(what, "paraboloid"));
    l->rising &= done > l->last_done && done <= total;
    l->calls++, l->last_done = done, l->total = total;
}

static void test_maps_progress(void **state)
{
    (void)state;
    tu_fx a, b;
    gi_indirect_options io;
    memset(&io, 0, sizeof io);
    io.vpls = 300;
    tu_load(&a.scene, SOFTGI_SOURCE_DIR "/scenes/cornell-box/cornell-box.gltf");
    tu_load(&b.scene, SOFTGI_SOURCE_DIR "/scenes/cornell-box/cornell-box.gltf");
    tu_fx_begin(&a, 2, RS_SIMD_SCALAR, 48, 36, &a.scene.cameras[0], &io, 1);
    tu_fx_begin(&b, 2, RS_SIMD_SCALAR, 48, 36, &b.scene.cameras[0], &io, 1);
    maps_log l = {0, 0, 0, 1};
    b.f.progress = on_progress, b.f.progress_user = &l;
    gi_frame_render_raster(&a.f);
    gi_frame_render_raster(&b.f);
    print_message("%u progress reports, the last %u of %u maps\n", l.calls, l.last_done, l.total);
    assert_true(l.calls >= 2);
    assert_true(l.rising);
    assert_int_equal(l.last_done, l.total);
    assert_int_equal(l.total, b.f.ind.maps_rendered);
    assert_memory_equal(a.f.final, b.f.final, 48 * 36 * 3 * sizeof(float));
    tu_fx_end(&a);
    tu_fx_end(&b);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_parse),
        cmocka_unit_test(test_jobs_profile),
        cmocka_unit_test(test_maps_progress),
        cmocka_unit_test(test_bad_ranges),
        cmocka_unit_test(test_sequence_merge),
        cmocka_unit_test(test_evaluate_merge),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
