/* test_frame_fixture: what most GI tests set up around a scene: its Embree
 * scene (pinned to sse2, so hashes do not depend on the CPU), a job system,
 * the rasterizer and a frame, built and freed together. */
#ifndef TEST_FRAME_FIXTURE_H
#define TEST_FRAME_FIXTURE_H

#include "gi_frame.h"

typedef struct tu_fx {
    pf_scene scene; /* loaded or built by the test before tu_fx_begin */
    pf_rt *rt;
    pf_jobs *jobs;
    rs_context *rs;
    gi_frame f;
} tu_fx;

/* Validates x->scene, then builds Embree, `threads` workers, the rasterizer
 * with `simd` and a w x h frame (64^2 direct-light shadow maps); with io,
 * turns the indirect stages on (indirect_only: no direct light). */
static inline void tu_fx_begin(tu_fx *x, uint32_t threads, rs_simd simd, uint32_t w, uint32_t h,
                               const pf_camera *cam, const gi_indirect_options *io, int indirect_only)
{
    pf_error err;
    assert_int_equal(pf_scene_validate(&x->scene, &err), PF_OK);
    assert_int_equal(pf_rt_create(&x->rt, &x->scene, PF_ISA_SSE2, 1, &err), PF_OK);
    x->jobs = pf_jobs_create(threads);
    assert_non_null(x->jobs);
    assert_int_equal(rs_context_create(&x->rs, &x->scene, x->jobs, simd, &err), PF_OK);
    assert_int_equal(gi_frame_init(&x->f, &x->scene, x->rt, x->rs, x->jobs, cam, w, h, 64, &err), PF_OK);
    if (io && gi_frame_enable_indirect(&x->f, io, indirect_only, &err) != PF_OK) fail_msg("%s", err.message);
}

static inline void tu_fx_end(tu_fx *x)
{
    gi_frame_free(&x->f);
    rs_context_destroy(x->rs);
    pf_jobs_destroy(x->jobs);
    pf_rt_destroy(x->rt);
    pf_scene_free(&x->scene);
}

#endif
