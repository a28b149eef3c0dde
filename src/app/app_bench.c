/* app_bench: `softgi bench raster` — the rasterizer's passes against Embree.
 *
 * For Sibenik and the conference room (from --scenes, default
 * ../shared/scenes) at 1024x768, with 1 and 2 threads (or --threads N),
 * four jobs, each done by softgi's rasterizer and by Embree used as well as
 * it can be for that job (app_bench_embree.h: its own scene with robust
 * mode off, coherent packets as wide as the ISA's registers over 4x4-pixel
 * blocks, one job item per 16x16 tile, the same outputs written):
 * - the visibility buffer (reversed depth + triangle id): rs_render against
 *   Embree primary rays;
 * - the whole G-buffer (visibility + every attribute plane): rs_render +
 *   the attribute resolve against Embree primary rays writing the same
 *   planes from their hits;
 * - one 128x128 paraboloid map: the mean over 64 maps rendered in one call
 *   from VPLs sampled on the scene's surfaces (fixed seed), against one
 *   Embree ray per texel centre in 4x4-texel packets;
 * - one 1024^2 cube shadow map (6 faces) for a point light at the scene's
 *   centre, against Embree rays through the faces' texel centres.
 * Before the timing, once per scene, each baseline's output is compared
 * with softgi's (triangle ids, attributes, paraboloid codes, cube depths)
 * and the agreement printed, so a baseline that does less work than the
 * rasterizer would show.
 * Each figure is the median over --frames repetitions (default 15) after one
 * warm-up, in milliseconds; the thread counts take turns frame by frame, and
 * within a frame the two sides of each job run back to back, softgi first
 * in even frames and Embree first in odd ones. The ratios are paired: per
 * frame, Embree's time over softgi's (and the 1-thread time over the
 * 2-thread time, adjacent turns), and their median over the frames.
 * Output: a table on stdout and one JSON line (prefix "json: ").
 *
 * Scaling past two cores: the job profile (pf_jobs.h) is
 * on for every timed call, and per scene and thread count a table gives
 * each pass's serial part (outside parallel-fors) beside its parallel work
 * and span, and its predicted time and speed-up on 8, 16 and 64 cores
 * (app_amdahl_print, app_bench_frame.c). --threads N may not exceed the
 * cores: more threads than cores measure the scheduler, not softgi. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "app.h"
#include "app_bench_embree.h"
#include "gi_frame.h"
#include "pf_gltf.h"
#include "pf_timer.h"
#include "rs_paraboloid.h"
#include "rs_raster.h"
#include "rs_shadow.h"

#define BENCH_W 1024
#define BENCH_H 768
#define BENCH_VPLS 64

typedef struct bench_scene {
    const char *name, *file;
    pf_vec3 eye, target;
    float fovy_deg;
} bench_scene;

/* The cameras: Sibenik's nave towards the altar; the conference room across
 * the table (see README "Benchmarks"). */
static const bench_scene k_scenes[] = {
    {"sibenik", "sibenik/sibenik.gltf", {-18.0f, -11.0f, 0.0f}, {10.0f, -8.0f, 0.0f}, 70.0f},
    {"conference", "conference/conference.gltf", {1400.0f, 420.0f, 500.0f}, {-600.0f, 150.0f, -700.0f}, 65.0f},
};

/* The jobs, each timed on both sides. */
enum { BENCH_VIS, BENCH_GBUF, BENCH_PARA, BENCH_CUBE, BENCH_JOBS };
static const char *const k_job_names[BENCH_JOBS] = {"visibility", "gbuffer", "paraboloid", "cube"};
/* the targets: softgi over Embree per job (0: none) */
static const double k_job_target[BENCH_JOBS] = {5.0, 4.0, 2.0, 0.0};
#define BENCH_SPEEDUP_TARGET 1.8 /* 2 threads over 1 */
#define BENCH_AGREE_TARGET 0.99  /* the baselines' agreement with softgi */

/* How a scene's baselines agree with softgi's outputs (shares in [0, 1]). */
typedef struct bench_check {
    double vis_ids;      /* pixels with the same triangle (or both empty) */
    double gbuf_attr;    /* of the pixels with the same triangle: depth within 1e-3, normal within 1 degree,
                          * albedo equal */
    double para_codes;   /* inside texels: same EMPTY, or distance codes within 1 step */
    double para_error;   /* inside texels: one EMPTY and the other not, or distances more than a texel's
                          * footprint apart (the measure --para-lod is held to: at most 1%) */
    double cube_depth;   /* texels: both empty, or depth within 1e-3 relative */
} bench_check;

typedef struct bench_result {
    const char *scene;
    uint32_t threads, tris;
    double resolve_ms;
    double ms[BENCH_JOBS], embree_ms[BENCH_JOBS]; /* medians (paraboloid: per map) */
    double x[BENCH_JOBS];                         /* paired: Embree time / softgi time */
    double up[BENCH_JOBS];                        /* paired: 1-thread time / this time (2-thread rows) */
    double tris_per_s, pixels_per_s;
    bench_check check;
    app_amdahl amdahl; /* the job profile, medians */
} bench_result;

static int bench__cmp(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

static double bench__median(double *v, uint32_t n)
{
    qsort(v, n, sizeof *v, bench__cmp);
    return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

/* The median of num[i] / den[i] (frame by frame); the inputs are not
 * reordered. `tmp`: n doubles. */
static double bench__paired(const double *num, const double *den, uint32_t n, double *tmp)
{
    for (uint32_t i = 0; i < n; i++) tmp[i] = num[i] / den[i];
    return bench__median(tmp, n);
}

/* VPL-like sample points: random triangles (by area), random barycentrics,
 * lifted off the surface along the geometric normal; fixed seed. */
static void bench__sample_vpls(const pf_scene *s, pf_vec3 *pos, pf_vec3 *nrm, uint32_t n)
{
    uint64_t state = 0x9e3779b97f4a7c15ull;
    double *cdf = malloc(sizeof(double) * s->tri_count);
    double total = 0.0;
    for (uint32_t t = 0; t < s->tri_count; t++) {
        const uint32_t *i = &s->indices[3 * t];
        pf_vec3 c = pf_v3_cross(pf_v3_sub(s->positions[i[1]], s->positions[i[0]]),
                                pf_v3_sub(s->positions[i[2]], s->positions[i[0]]));
        total += 0.5 * pf_v3_length(c);
        cdf[t] = total;
    }
    pf_vec3 ext = pf_v3_sub(s->bounds_max, s->bounds_min);
    float lift = 1e-4f * pf_v3_length(ext);
    for (uint32_t k = 0; k < n; k++) {
        double r[3];
        for (int j = 0; j < 3; j++) {
            state = state * 6364136223846793005ull + 1442695040888963407ull;
            r[j] = (double)(state >> 11) * (1.0 / 9007199254740992.0);
        }
        double target = r[0] * total;
        uint32_t lo = 0, hi = s->tri_count - 1;
        while (lo < hi) {
            uint32_t mid = (lo + hi) / 2;
            if (cdf[mid] < target) lo = mid + 1;
            else hi = mid;
        }
        float su = (float)sqrt(r[1]), b1 = 1.0f - su, b2 = (float)r[2] * su;
        pf_surface sf;
        pf_scene_surface(s, lo, b1, b2, 0.0f, &sf);
        pos[k] = pf_v3_add(sf.p, pf_v3_scale(sf.ng, lift));
        nrm[k] = sf.ng;
    }
    free(cdf);
}

/* One thread count's state on one scene (contexts, buffers, samples), so
 * the thread counts can take turns frame by frame: a burst of load on this
 * shared machine then slows both alike instead of one of them, which keeps
 * the 2-thread speed-up honest. The Embree scene is the scene's, shared by
 * the thread counts (built once). */
typedef struct bench_run {
    uint32_t threads, frames;
    pf_jobs *jobs;
    const app_embree *emb;
    rs_context *rs;
    rs_para_context *para;
    pf_camera cam;
    gi_frame f; /* softgi's G-buffer */
    int have_frame;
    rs_gbuffer eg; /* Embree's */
    int have_eg;
    rs_stats st;
    const pf_vec3 *vp, *vn; /* BENCH_VPLS paraboloid-map origins and normals, the scene's */
    uint16_t *atlas, *eatlas;
    float range;
    pf_scene lit; /* the scene with one point light at its centre (shallow copy) */
    pf_light light;
    rs_shadow_map map, emap;
    int have_map, have_emap;
    /* samples, frames each: softgi's visibility, resolve and both; the jobs' */
    double *vis, *res, *sample[BENCH_JOBS], *esample[BENCH_JOBS];
    /* the job profile of each timed frame (app.h), and the probe while one runs */
    app_amdahl *am;
    app_amdahl_probe *probe;
} bench_run;

static void bench__close(bench_run *r)
{
    if (r->have_emap) rs_shadow_map_free(&r->emap);
    if (r->have_map) rs_shadow_map_free(&r->map);
    if (r->have_eg) rs_gbuffer_free(&r->eg);
    if (r->have_frame) gi_frame_free(&r->f);
    free(r->vis), free(r->res);
    for (int j = 0; j < BENCH_JOBS; j++) free(r->sample[j]), free(r->esample[j]);
    free(r->atlas), free(r->eatlas);
    free(r->am);
    rs_para_context_destroy(r->para);
    rs_context_destroy(r->rs);
    if (r->jobs) pf_jobs_destroy(r->jobs);
    memset(r, 0, sizeof *r);
}

static int bench__open(bench_run *r, const pf_scene *scene, const bench_scene *bs, const app_embree *emb,
                       const pf_vec3 *vp, const pf_vec3 *vn, uint32_t threads, pf_isa isa, uint32_t frames,
                       float para_lod)
{
    pf_error err;
    memset(r, 0, sizeof *r);
    r->threads = threads;
    r->frames = frames;
    r->emb = emb;
    r->vp = vp;
    r->vn = vn;
    if (!(r->jobs = pf_jobs_create(threads))) {
        pf_error_set(&err, PF_ERR_OUT_OF_MEMORY, "cannot start %u threads", threads);
        goto fail;
    }
    if (rs_context_create(&r->rs, scene, r->jobs, rs_simd_for_isa(isa), &err) != PF_OK ||
        rs_para_context_create(&r->para, scene, &(rs_para_options){.lod = para_lod}, &err) != PF_OK ||
        pf_camera_look_at(&r->cam, bs->eye, bs->target, pf_radians(bs->fovy_deg), &err) != PF_OK ||
        gi_frame_create(&r->f,
                        &(gi_frame_desc){.scene = scene, .jobs = r->jobs, .raster = r->rs, .camera = &r->cam,
                                         .width = BENCH_W, .height = BENCH_H},
                        &err) != PF_OK)
        goto fail;
    r->have_frame = 1;
    if (rs_gbuffer_init(&r->eg, BENCH_W, BENCH_H, &err) != PF_OK) goto fail;
    r->have_eg = 1;
    pf_jobs_profile_enable(r->jobs, 1);
    if (!(r->vis = calloc(frames, sizeof(double))) || !(r->res = calloc(frames, sizeof(double))) ||
        !(r->am = calloc(frames, sizeof(app_amdahl))))
        goto oom;
    for (int j = 0; j < BENCH_JOBS; j++)
        if (!(r->sample[j] = calloc(frames, sizeof(double))) || !(r->esample[j] = calloc(frames, sizeof(double))))
            goto oom;
    r->range = rs_para_default_range(scene);
    size_t atlas_bytes = rs_para_atlas_bytes(rs_para_resolution(r->para), BENCH_VPLS);
    if (!(r->atlas = malloc(atlas_bytes)) || !(r->eatlas = malloc(atlas_bytes))) goto oom;
    /* cube shadow map, 1024^2 per face, point light at the scene centre */
    r->lit = *scene;
    r->light.type = PF_LIGHT_POINT;
    r->light.position = pf_v3_scale(pf_v3_add(scene->bounds_min, scene->bounds_max), 0.5f);
    r->light.color = pf_v3(1, 1, 1);
    r->light.intensity = 1.0f;
    r->lit.lights = &r->light;
    r->lit.light_count = 1;
    rs_shadow_desc desc;
    memset(&desc, 0, sizeof desc);
    if (rs_shadow_map_init(&r->map, &r->lit, 0, &desc, &err) != PF_OK) goto fail;
    r->have_map = 1;
    if (rs_shadow_map_init(&r->emap, &r->lit, 0, &desc, &err) != PF_OK) goto fail;
    r->have_emap = 1;
    return 1;
oom:
    pf_error_set(&err, PF_ERR_OUT_OF_MEMORY, "out of memory for the benchmark");
fail:
    fprintf(stderr, "softgi bench: %s\n", err.message);
    bench__close(r);
    return 0;
}

/* The job profile around a timed call (outside its timing): a new
 * interval starts, and the one that ends is recorded under `name`. No-ops
 * outside the timed frames. */
static void bench__skip(bench_run *r)
{
    if (r->probe) app_amdahl_skip(r->probe);
}

static void bench__mark(bench_run *r, const char *name)
{
    if (r->probe) app_amdahl_mark(r->probe, name);
}

/* The two sides of each job; each returns its milliseconds. */
static void bench__softgi_gbuffer(bench_run *r, double *vis_ms, double *res_ms)
{
    bench__skip(r);
    double t0 = pf_time_now();
    rs_target tg = {BENCH_W, BENCH_H, r->f.gbuf.depth, r->f.gbuf.prim, NULL};
    rs_pass pass = {rs_mat4_camera(&r->cam, BENCH_W, BENCH_H), RS_CULL_NONE};
    rs_render(r->rs, &pass, &tg, &r->st);
    double t1 = pf_time_now();
    bench__mark(r, "softgi visibility");
    double t1b = pf_time_now();
    gi_stage_gbuffer_resolve(&r->f);
    double t2 = pf_time_now();
    bench__mark(r, "softgi resolve (attributes)");
    *vis_ms = (t1 - t0) * 1e3;
    *res_ms = (t2 - t1b) * 1e3;
}

static void bench__embree_gbuffer(bench_run *r, double *vis_ms, double *gbuf_ms)
{
    bench__skip(r);
    double t0 = pf_time_now();
    app_embree_visibility(r->eg.depth, r->eg.prim, r->emb, r->jobs, &r->cam, BENCH_W, BENCH_H);
    double t1 = pf_time_now();
    bench__mark(r, "Embree visibility");
    double t1b = pf_time_now();
    app_embree_gbuffer(&r->eg, r->emb, r->jobs, &r->cam);
    double t2 = pf_time_now();
    bench__mark(r, "Embree G-buffer");
    *vis_ms = (t1 - t0) * 1e3;
    *gbuf_ms = (t2 - t1b) * 1e3;
}

static double bench__softgi_para(bench_run *r)
{
    bench__skip(r);
    double t0 = pf_time_now();
    rs_para_render(r->atlas, r->para, r->jobs, r->vp, r->vn, BENCH_VPLS, r->range, NULL);
    double ms = (pf_time_now() - t0) * 1e3 / BENCH_VPLS;
    bench__mark(r, "softgi 64 paraboloid maps");
    return ms;
}

static double bench__embree_para(bench_run *r)
{
    bench__skip(r);
    double t0 = pf_time_now();
    app_embree_paraboloid(r->eatlas, r->emb, r->jobs, rs_para_resolution(r->para), r->vp, r->vn, BENCH_VPLS,
                          r->range);
    double ms = (pf_time_now() - t0) * 1e3 / BENCH_VPLS;
    bench__mark(r, "Embree 64 paraboloid maps");
    return ms;
}

static double bench__softgi_cube(bench_run *r)
{
    bench__skip(r);
    double t0 = pf_time_now();
    rs_shadow_render(r->rs, &r->map, 1, NULL);
    double ms = (pf_time_now() - t0) * 1e3;
    bench__mark(r, "softgi cube map (6 x 1024^2)");
    return ms;
}

static double bench__embree_cube(bench_run *r)
{
    bench__skip(r);
    double t0 = pf_time_now();
    app_embree_shadow(&r->emap, r->emb, r->jobs);
    double ms = (pf_time_now() - t0) * 1e3;
    bench__mark(r, "Embree cube map");
    return ms;
}

/* One frame of every measurement; frame 0 is the warm-up (not recorded).
 * Odd frames run Embree's side of each job first, so neither side always
 * finds the caches as the other left them. */
static void bench__frame(bench_run *r, uint32_t i)
{
    double vis = 0, res = 0, evis = 0, egbuf = 0, para = 0, epara = 0, cube = 0, ecube = 0;
    int embree_first = i & 1;
    app_amdahl_probe probe;
    if (i > 0) {
        app_amdahl_begin(&probe, r->jobs, &r->am[i - 1]);
        r->probe = &probe;
    }
    if (embree_first) bench__embree_gbuffer(r, &evis, &egbuf);
    bench__softgi_gbuffer(r, &vis, &res);
    if (!embree_first) bench__embree_gbuffer(r, &evis, &egbuf);
    if (embree_first) epara = bench__embree_para(r);
    para = bench__softgi_para(r);
    if (!embree_first) epara = bench__embree_para(r);
    if (embree_first) ecube = bench__embree_cube(r);
    cube = bench__softgi_cube(r);
    if (!embree_first) ecube = bench__embree_cube(r);
    pf_jobs_wait_all(r->jobs);
    if (i == 0) return;
    app_amdahl_end(&probe, NULL);
    r->probe = NULL;
    uint32_t k = i - 1;
    r->vis[k] = vis;
    r->res[k] = res;
    r->sample[BENCH_VIS][k] = vis;
    r->sample[BENCH_GBUF][k] = vis + res;
    r->sample[BENCH_PARA][k] = para;
    r->sample[BENCH_CUBE][k] = cube;
    r->esample[BENCH_VIS][k] = evis;
    r->esample[BENCH_GBUF][k] = egbuf;
    r->esample[BENCH_PARA][k] = epara;
    r->esample[BENCH_CUBE][k] = ecube;
}

/* Each baseline's output against softgi's, once, untimed: the evidence
 * that the two sides do the same job. Edges differ (the rasterizer's
 * coverage is exact on snapped vertices, Embree's non-robust test may slip
 * through an edge), so agreement is a share, not equality. */
static void bench__check(bench_run *r, bench_check *c)
{
    double ms[2];
    bench__softgi_gbuffer(r, &ms[0], &ms[1]);
    const rs_gbuffer *g = &r->f.gbuf;
    rs_gbuffer *eg = &r->eg;
    /* visibility: the Embree pass alone, triangle ids per pixel */
    app_embree_visibility(eg->depth, eg->prim, r->emb, r->jobs, &r->cam, BENCH_W, BENCH_H);
    size_t n = (size_t)BENCH_W * BENCH_H, same = 0, attr_ok = 0, hits = 0;
    for (size_t i = 0; i < n; i++) same += g->prim[i] == eg->prim[i];
    c->vis_ids = (double)same / (double)n;
    /* whole G-buffer: the attributes of the pixels that show the same triangle */
    app_embree_gbuffer(eg, r->emb, r->jobs, &r->cam);
    const float cos_1deg = 0.99984769f;
    for (size_t i = 0; i < n; i++) {
        if (g->prim[i] != eg->prim[i] || g->prim[i] == RS_GBUFFER_EMPTY) continue;
        hits++;
        float dot = g->nrm_x[i] * eg->nrm_x[i] + g->nrm_y[i] * eg->nrm_y[i] + g->nrm_z[i] * eg->nrm_z[i];
        int depth_ok = fabsf(g->depth[i] - eg->depth[i]) <= 1e-3f * g->depth[i];
        int albedo_ok = g->alb_r[i] == eg->alb_r[i] && g->alb_g[i] == eg->alb_g[i] && g->alb_b[i] == eg->alb_b[i];
        attr_ok += depth_ok && albedo_ok && dot >= cos_1deg;
    }
    c->gbuf_attr = hits ? (double)attr_ok / (double)hits : 1.0;
    /* paraboloid maps: codes texel by texel (same directions) */
    bench__softgi_para(r);
    bench__embree_para(r);
    uint32_t res = rs_para_resolution(r->para);
    size_t texels = (size_t)res * res * BENCH_VPLS, inside = 0, close = 0, off = 0;
    for (size_t i = 0; i < texels; i++) {
        uint16_t a = r->atlas[i], b = r->eatlas[i];
        if (a == RS_PARA_OUTSIDE && b == RS_PARA_OUTSIDE) continue;
        inside++;
        int a_code = a <= RS_PARA_MAX_CODE, b_code = b <= RS_PARA_MAX_CODE;
        close += a_code && b_code ? abs((int)a - (int)b) <= 1 : a == b;
        if (a_code != b_code) {
            off++;
        } else if (a_code) {
            uint32_t t = (uint32_t)(i % ((size_t)res * res));
            pf_vec3 d = rs_para_uv_to_dir(rs_para_texel_uv(res, t % res, t / res));
            float da = rs_para_decode(a, r->range), db = rs_para_decode(b, r->range);
            off += fabsf(da - db) > rs_para_texel_world_size(res, db, d);
        }
    }
    c->para_codes = inside ? (double)close / (double)inside : 1.0;
    c->para_error = inside ? (double)off / (double)inside : 0.0;
    /* cube map: reversed depth per texel */
    bench__softgi_cube(r);
    bench__embree_cube(r);
    size_t cn = (size_t)r->map.size * r->map.size * r->map.face_count, cube_ok = 0;
    for (size_t i = 0; i < cn; i++) {
        float a = r->map.depth[i], b = r->emap.depth[i];
        cube_ok += fabsf(a - b) <= 1e-3f * fmaxf(a, b);
    }
    c->cube_depth = (double)cube_ok / (double)cn;
    pf_jobs_wait_all(r->jobs);
}

/* `base`: the 1-thread run of the same scene for a 2-thread row's
 * speed-ups, or NULL. Call for the 2-thread run first: medians sort the
 * sample arrays, and pairs need them in frame order. */
static void bench__result(bench_run *r, const bench_run *base, const char *scene, bench_result *out, double *tmp)
{
    bench_check check = out->check;
    memset(out, 0, sizeof *out);
    out->check = check;
    out->scene = scene;
    out->threads = r->threads;
    uint32_t n = r->frames;
    for (int j = 0; j < BENCH_JOBS; j++) {
        out->x[j] = bench__paired(r->esample[j], r->sample[j], n, tmp);
        if (base) out->up[j] = bench__paired(base->sample[j], r->sample[j], n, tmp);
    }
    for (int j = 0; j < BENCH_JOBS; j++) {
        out->ms[j] = bench__median(r->sample[j], n);
        out->embree_ms[j] = bench__median(r->esample[j], n);
    }
    out->resolve_ms = bench__median(r->res, n);
    app_amdahl_median(&out->amdahl, r->am, n);
    out->tris = (uint32_t)r->st.triangles_in;
    out->tris_per_s = out->tris / (out->ms[BENCH_VIS] * 1e-3);
    out->pixels_per_s = (double)BENCH_W * BENCH_H / (out->ms[BENCH_GBUF] * 1e-3);
}

/* With levels of detail the paraboloid codes cannot agree within a step;
 * their error must stay within 1% of texels instead (the target's bound). */
static int bench__check_ok(const bench_check *c, float para_lod)
{
    return c->vis_ids >= BENCH_AGREE_TARGET &&
           (para_lod > 0.0f ? c->para_error <= 1.0 - BENCH_AGREE_TARGET : c->para_codes >= BENCH_AGREE_TARGET);
}

int app_bench_raster(const pf_options *o)
{
    pf_error err;
    pf_isa isa;
    if (pf_isa_resolve(o->isa, &isa, &err) != PF_OK) {
        fprintf(stderr, "softgi: %s\n", err.message);
        return 2;
    }
    const char *dir = o->scenes_dir ? o->scenes_dir : "../shared/scenes";
    uint32_t frames = o->frames ? o->frames : 15;
    uint32_t thread_list[2] = {1, 2}, nthreads = 2;
    if (o->threads) thread_list[0] = o->threads, nthreads = 1;
    if (o->threads > pf_jobs_core_count()) {
        fprintf(stderr, "softgi: bench raster: --threads %u: this machine has %u cores (the Amdahl table predicts "
                        "more)\n",
                o->threads, pf_jobs_core_count());
        return 2;
    }
    uint32_t build_threads = thread_list[nthreads - 1];
    bench_result results[8];
    uint32_t nres = 0, lanes = 0;
    int checks_ok = 1;
    pf_cpu_ticks steal = {0, 0, 0}; /* summed over the scenes' timed frames */
    printf("softgi bench raster: %dx%d, isa %s, raster path %s, median of %u\n", BENCH_W, BENCH_H, pf_isa_name(isa),
           rs_simd_name(rs_simd_for_isa(isa)), frames);
    for (size_t k = 0; k < sizeof k_scenes / sizeof k_scenes[0]; k++) {
        char path[4096];
        snprintf(path, sizeof path, "%s/%s", dir, k_scenes[k].file);
        pf_scene scene;
        pf_gltf_options go = {.ignore_textures = 1};
        if (pf_gltf_load(&scene, path, &go, &err) != PF_OK) {
            fprintf(stderr, "softgi bench: %s (give the folder with --scenes)\n", err.message);
            return 1;
        }
        app_embree *emb;
        if (app_embree_create(&emb, &scene, isa, build_threads, &err) != PF_OK) {
            fprintf(stderr, "softgi bench: %s\n", err.message);
            pf_scene_free(&scene);
            return 1;
        }
        lanes = app_embree_packet_width(emb);
        pf_vec3 vp[BENCH_VPLS], vn[BENCH_VPLS];
        bench__sample_vpls(&scene, vp, vn, BENCH_VPLS);
        bench_run runs[2];
        uint32_t opened = 0;
        for (; opened < nthreads; opened++)
            if (!bench__open(&runs[opened], &scene, &k_scenes[k], emb, vp, vn, thread_list[opened], isa, frames,
                             o->para_lod))
                break;
        double *tmp = opened == nthreads ? malloc(sizeof(double) * frames) : NULL;
        if (!tmp) {
            if (opened == nthreads) fprintf(stderr, "softgi bench: out of memory for the benchmark\n");
            for (uint32_t t = 0; t < opened; t++) bench__close(&runs[t]);
            app_embree_destroy(emb);
            pf_scene_free(&scene);
            return 1;
        }
        bench_check check;
        bench__check(&runs[0], &check);
        checks_ok &= bench__check_ok(&check, o->para_lod);
        printf("%s: %u triangles, Embree build %.0f ms; baselines vs softgi: triangle ids %.2f%% of pixels, "
               "G-buffer attributes %.2f%% of those, paraboloid codes within 1 step %.2f%% of texels (off by more "
               "than a texel's footprint: %.3f%%%s), cube depth %.2f%%%s\n",
               k_scenes[k].name, scene.tri_count, app_embree_build_ms(emb), 100.0 * check.vis_ids,
               100.0 * check.gbuf_attr, 100.0 * check.para_codes, 100.0 * check.para_error,
               o->para_lod > 0.0f ? ", levels of detail" : "", 100.0 * check.cube_depth,
               bench__check_ok(&check, o->para_lod)
                   ? ""
                   : o->para_lod > 0.0f ? " (PARABOLOID ERROR ABOVE 1%, or ids below 99%)"
                                        : " (BELOW 99%: the baseline is not doing the same job)");
        pf_cpu_ticks c0 = pf_cpu_ticks_now();
        for (uint32_t i = 0; i <= frames; i++) /* thread counts take turns */
            for (uint32_t t = 0; t < nthreads; t++) bench__frame(&runs[t], i);
        pf_cpu_ticks c1 = pf_cpu_ticks_now();
        if (pf_cpu_steal_share(c0, c1) >= 0.0) {
            steal.valid = 1;
            steal.total += c1.total - c0.total;
            steal.steal += c1.steal - c0.steal;
        }
        /* the 2-thread row first: its pairs need the 1-thread samples unsorted */
        for (uint32_t t = nthreads; t-- > 0;) {
            results[nres + t].check = check;
            bench__result(&runs[t], t == 1 ? &runs[0] : NULL, k_scenes[k].name, &results[nres + t], tmp);
        }
        nres += nthreads;
        free(tmp);
        for (uint32_t t = 0; t < nthreads; t++) bench__close(&runs[t]);
        app_embree_destroy(emb);
        pf_scene_free(&scene);
    }
    printf("\nms: medians; x: Embree / softgi, paired (median over frames of each frame's ratio; > 1: softgi is\n"
           "faster). Embree: its own scene (robust off), %u-ray coherent packets over %s blocks, one job per 16x16\n"
           "tile (paraboloid: per map), the same outputs written. vis: visibility buffer; gbuf: whole G-buffer with\n"
           "attributes (softgi: vis + resolve); para: per 128x128 paraboloid map; cube: 6 faces of 1024^2\n",
           lanes, lanes == 16 ? "4x4" : lanes == 8 ? "4x2" : "2x2");
    printf("%-11s %3s | %7s %7s %5s | %7s %7s %7s %5s | %7s %7s %5s | %7s %7s %5s | %7s %8s\n", "scene", "thr",
           "vis", "Embree", "x", "resolve", "gbuf", "Embree", "x", "para", "Embree", "x", "cube", "Embree", "x",
           "Mtri/s", "Mpix/s");
    for (uint32_t i = 0; i < nres; i++) {
        const bench_result *r = &results[i];
        printf("%-11s %3u | %7.2f %7.2f %5.2f | %7.2f %7.2f %7.2f %5.2f | %7.3f %7.3f %5.2f | %7.2f %7.2f %5.2f | "
               "%7.1f %8.1f\n",
               r->scene, r->threads, r->ms[BENCH_VIS], r->embree_ms[BENCH_VIS], r->x[BENCH_VIS], r->resolve_ms,
               r->ms[BENCH_GBUF], r->embree_ms[BENCH_GBUF], r->x[BENCH_GBUF], r->ms[BENCH_PARA],
               r->embree_ms[BENCH_PARA], r->x[BENCH_PARA], r->ms[BENCH_CUBE], r->embree_ms[BENCH_CUBE],
               r->x[BENCH_CUBE], r->tris_per_s * 1e-6, r->pixels_per_s * 1e-6);
    }
    /* the targets, on the paired medians */
    printf("\ntargets: visibility >= %.0fx Embree, whole G-buffer >= %.0fx, paraboloid map >= %.0fx;\n"
           "2 threads >= %.1fx 1 thread\n",
           k_job_target[BENCH_VIS], k_job_target[BENCH_GBUF], k_job_target[BENCH_PARA], BENCH_SPEEDUP_TARGET);
    for (uint32_t i = 0; i < nres; i++) {
        const bench_result *r = &results[i];
        printf("  %-11s %u thr:", r->scene, r->threads);
        for (int j = 0; j < BENCH_JOBS; j++) {
            if (k_job_target[j] <= 0.0) continue;
            printf(" %s %.2fx %s%s", k_job_names[j], r->x[j], r->x[j] >= k_job_target[j] ? "met" : "NOT met",
                   j + 1 < BENCH_JOBS && k_job_target[j + 1] > 0.0 ? "," : "");
        }
        if (r->up[BENCH_GBUF] > 0.0) {
            printf("; 2-thread speed-up");
            for (int j = 0; j < BENCH_JOBS; j++)
                printf(" %s %.2fx %s%s", k_job_names[j], r->up[j], r->up[j] >= BENCH_SPEEDUP_TARGET ? "met" : "NOT met",
                       j + 1 < BENCH_JOBS ? "," : "");
        }
        printf("\n");
    }
    printf("  2048 paraboloid maps of 128x128: %.1f MB\n", rs_para_atlas_bytes(128, 2048) / (1024.0 * 1024.0));
    printf("\nAmdahl's law per pass (job profile, pf_jobs.h): serial = outside parallel-fors; work = item CPU time\n"
           "summed over threads; span = each job's longest item, summed; N cores = serial + the jobs' predicted\n"
           "time on N cores (chunks, longest item); the rows are separate calls, so the sum is not a frame\n");
    for (uint32_t i = 0; i < nres; i++) {
        char title[96];
        snprintf(title, sizeof title, "\n%s", results[i].scene);
        app_amdahl_print(&results[i].amdahl, title, results[i].threads, "all passes (sum)");
    }
    pf_cpu_ticks zero = {1, 0, 0};
    double steal_share = pf_cpu_steal_share(zero, steal);
    if (steal_share >= 0.0)
        printf("cpu steal during the timed frames: %.1f%% of all CPU time (a virtual machine's host running other\n"
               "guests; the 2-thread rows, which need both CPUs at once, suffer most)\n",
               100.0 * steal_share);
    printf("json: {\"bench\":\"raster\",\"width\":%d,\"height\":%d,\"isa\":\"%s\",\"frames\":%u,\"cpu_steal\":%.4f,"
           "\"embree_packet\":%u,\"para_lod\":%g,\"results\":[",
           BENCH_W, BENCH_H, pf_isa_name(isa), frames, steal_share, lanes, (double)o->para_lod);
    for (uint32_t i = 0; i < nres; i++) {
        const bench_result *r = &results[i];
        printf("%s{\"scene\":\"%s\",\"threads\":%u,\"gbuffer_resolve_ms\":%.3f,\"triangles_per_s\":%.0f,"
               "\"pixels_per_s\":%.0f",
               i ? "," : "", r->scene, r->threads, r->resolve_ms, r->tris_per_s, r->pixels_per_s);
        for (int j = 0; j < BENCH_JOBS; j++)
            printf(",\"%s_ms\":%.4f,\"%s_embree_ms\":%.4f,\"paired_x_%s\":%.3f,\"paired_speedup_%s\":%.3f",
                   k_job_names[j], r->ms[j], k_job_names[j], r->embree_ms[j], k_job_names[j], r->x[j],
                   k_job_names[j], r->up[j]);
        printf(",\"check_visibility_ids\":%.5f,\"check_gbuffer_attributes\":%.5f,\"check_paraboloid_codes\":%.5f,"
               "\"check_paraboloid_error\":%.5f,\"check_cube_depth\":%.5f}",
               r->check.vis_ids, r->check.gbuf_attr, r->check.para_codes, r->check.para_error, r->check.cube_depth);
    }
    printf("]}\n");
    return checks_ok ? 0 : 1;
}
