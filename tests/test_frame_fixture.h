/* test_frame_fixture: what most GI tests set up around a scene: its Embree
 * scene (pinned to sse2, so hashes do not depend on the CPU), a job system,
 * the rasterizer and a frame, built and freed together.
 *
 *   tu_fx x;
 *   tu_load(&x.scene, PATH);          (or tu_make_scene, or any pf_scene)
 *   tu_fx_begin(&x, 2, RS_SIMD_SCALAR, 64, 48, &x.scene.cameras[0], &io, 0);
 *   gi_frame_render_raster(&x.f);     (or the stages one by one)
 *   ... x.f.final, x.f.gbuf, x.f.ind ...
 *   tu_fx_end(&x);
 *
 * tu_fx_begin_with takes a description for the other cases: Embree at
 * another ISA or built by several threads, a ray-traced frame without the
 * rasterizer, a shadow-map size other than 64. */
#ifndef TEST_FRAME_FIXTURE_H
#define TEST_FRAME_FIXTURE_H

#include <math.h>

#include "gi_frame.h"
#include "pf_gltf.h"

typedef struct tu_fx {
    pf_scene scene; /* loaded or built by the test before tu_fx_begin */
    pf_rt *rt;
    pf_jobs *jobs;
    rs_context *rs; /* NULL for a ray-traced frame (tu_fx_desc.no_raster) */
    gi_frame f;
} tu_fx;

/* What tu_fx_begin_with builds; zero fields are tu_fx_begin's defaults. */
typedef struct tu_fx_desc {
    uint32_t threads;       /* job system threads, the caller's included (0: 2) */
    rs_simd simd;           /* the rasterizer's path (0: scalar) */
    int no_raster;          /* 1: no rasterizer (x->rs NULL): gi_frame_render_raytraced only */
    pf_isa isa;             /* Embree's ISA (0: sse2, the tests' pin; pf_isa_detect() for the best) */
    uint32_t build_threads; /* threads building Embree's BVH (0: 1) */
    uint32_t w, h;          /* frame size */
    const pf_camera *cam;   /* NULL: the scene's first camera */
    uint32_t shadow_size;   /* direct-light shadow maps' side (0: 64) */
    const gi_indirect_options *io; /* non-NULL: the indirect stages on */
    int indirect_only;      /* with io: no emission and direct light in the final image */
} tu_fx_desc;

/* Loads a glTF file into s; fails the test with the loader's message. */
static inline void tu_load(pf_scene *s, const char *path)
{
    pf_error err;
    if (pf_gltf_load(s, path, NULL, &err) != PF_OK) fail_msg("%s: %s", path, err.message);
}

/* Validates x->scene, then builds what d describes. */
static inline void tu_fx_begin_with(tu_fx *x, const tu_fx_desc *d)
{
    pf_error err;
    assert_int_equal(pf_scene_validate(&x->scene, &err), PF_OK);
    pf_isa isa = d->isa ? d->isa : PF_ISA_SSE2;
    if (pf_rt_create(&x->rt, &x->scene, isa, d->build_threads ? d->build_threads : 1, &err) != PF_OK)
        fail_msg("%s", err.message);
    x->jobs = pf_jobs_create(d->threads ? d->threads : 2);
    assert_non_null(x->jobs);
    x->rs = NULL;
    if (!d->no_raster) assert_int_equal(rs_context_create(&x->rs, &x->scene, x->jobs, d->simd, &err), PF_OK);
    const pf_camera *cam = d->cam;
    if (!cam) {
        assert_true(x->scene.camera_count > 0);
        cam = &x->scene.cameras[0];
    }
    gi_frame_desc fd = {.scene = &x->scene, .rt = x->rt, .jobs = x->jobs, .raster = x->rs, .camera = cam, .width = d->w,
                        .height = d->h, .shadow_size = d->shadow_size ? d->shadow_size : 64, .indirect = d->io,
                        .indirect_only = d->indirect_only};
    if (gi_frame_create(&x->f, &fd, &err) != PF_OK) fail_msg("%s", err.message);
}

/* Validates x->scene, then builds Embree, `threads` workers, the rasterizer
 * with `simd` and a w x h frame (64^2 direct-light shadow maps); with io,
 * turns the indirect stages on (indirect_only: no direct light). */
static inline void tu_fx_begin(tu_fx *x, uint32_t threads, rs_simd simd, uint32_t w, uint32_t h,
                               const pf_camera *cam, const gi_indirect_options *io, int indirect_only)
{
    tu_fx_desc d = {0};
    d.threads = threads;
    d.simd = simd;
    d.w = w;
    d.h = h;
    d.cam = cam;
    d.io = io;
    d.indirect_only = indirect_only;
    tu_fx_begin_with(x, &d);
}

/* Frees the frame, the rasterizer, the jobs and Embree; the scene stays
 * (a test that lends the fixture its scene frees it itself). */
static inline void tu_fx_end_frame(tu_fx *x)
{
    gi_frame_free(&x->f);
    if (x->rs) rs_context_destroy(x->rs);
    pf_jobs_destroy(x->jobs);
    pf_rt_destroy(x->rt);
    x->rs = NULL;
    x->jobs = NULL;
    x->rt = NULL;
}

static inline void tu_fx_end(tu_fx *x)
{
    tu_fx_end_frame(x);
    pf_scene_free(&x->scene);
}

/* Mean relative difference of b's green channel to a's over the n RGB
 * pixels where a's exceeds 1e-6 (1 when there is none). */
static inline double tu_mean_rel_green(const float *a, const float *b, size_t n)
{
    double rel = 0.0;
    uint32_t count = 0;
    for (size_t i = 0; i < n; i++) {
        double x = a[3 * i + 1], y = b[3 * i + 1];
        if (x > 1e-6) rel += fabs(y - x) / x, count++;
    }
    return count ? rel / count : 1.0;
}

#endif
