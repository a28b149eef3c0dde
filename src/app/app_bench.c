/* app_bench: `softgi bench raster` — the rasterizer's passes against Embree.
 *
 * For Sibenik and the conference room (from --scenes, default
 * ../shared/scenes) at 1024x768, with 1 and 2 threads (or --threads N):
 * - the G-buffer pass: rasterized visibility + attribute resolve, against the
 *   same G-buffer made by Embree primary rays (8-wide packets);
 * - one 128x128 paraboloid map: the mean over 64 maps rendered in one call
 *   from VPLs sampled on the scene's surfaces (fixed seed), against the same
 *   64 maps made with one Embree ray per texel;
 * - one 1024^2 cube shadow map (6 faces) for a point light at the scene's
 *   centre.
 * Each figure is the median over --frames repetitions (default 15) after one
 * warm-up, in milliseconds; the thread counts take turns frame by frame.
 * Triangles/s counts the triangles entering the G-buffer pass (after cluster
 * culling); pixels/s the image's pixels. The target check uses paired
 * ratios: per frame, Embree's time over the rasterizer's (timed back to
 * back) and the 1-thread time over the 2-thread time (adjacent turns), and
 * their median over the frames.
 * Output: a table on stdout and one JSON line (prefix "json: "). */
#include <stdlib.h>
#include <string.h>

#include "app.h"
#include "gi_frame.h"
#include "pf_gltf.h"
#include "pf_rt.h"
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

typedef struct bench_result {
    const char *scene;
    uint32_t threads, tris;
    double vis_ms, resolve_ms, gbuf_ms, embree_rays_ms, embree_gbuf_ms;
    double para_ms, para_embree_ms; /* per map */
    double cube_ms;
    double tris_per_s, pixels_per_s;
    /* paired: the median over frames of one frame's ratio (the two timings
     * of a ratio taken back to back in the same frame) */
    double x_vis, x_gbuf, x_para;          /* Embree time / raster time */
    double up_vis, up_gbuf, up_para, up_cube; /* 1-thread time / this time (2-thread rows) */
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

/* Embree primary rays alone (no attributes): one row per job item, hits to
 * a scratch array; the counterpart of the rasterizer's visibility pass. */
typedef struct bench__rays_ctx {
    const pf_rt *rt;
    const pf_camera *cam;
    pf_hit *hits;
} bench__rays_ctx;

static void bench__rays_row(void *p, uint32_t y, uint32_t worker)
{
    (void)worker;
    bench__rays_ctx *c = p;
    for (uint32_t x0 = 0; x0 < BENCH_W; x0 += PF_RT_WIDTH) {
        pf_ray rays[PF_RT_WIDTH];
        for (uint32_t i = 0; i < PF_RT_WIDTH; i++) rays[i] = gi_camera_ray(c->cam, BENCH_W, BENCH_H, x0 + i, y);
        /* Embree's own hits: the exact recomputation the renderer's images
         * need (pf_rt.h) is not part of the job being compared */
        pf_rt_intersect_embree(c->rt, rays, c->hits + (size_t)y * BENCH_W + x0, PF_RT_WIDTH);
    }
}

/* One thread count's state on one scene (contexts, buffers, samples), so
 * the thread counts can take turns frame by frame: a burst of load on this
 * shared machine then slows both alike instead of one of them, which keeps
 * the 2-thread speed-up honest. */
typedef struct bench_run {
    uint32_t threads, frames;
    pf_jobs *jobs;
    pf_rt *rt;
    rs_context *rs;
    rs_para_context *para;
    pf_camera cam;
    gi_frame f;
    int have_frame;
    pf_hit *hits;
    rs_stats st;
    const pf_vec3 *vp, *vn; /* BENCH_VPLS paraboloid-map origins and normals, the scene's */
    uint16_t *atlas;
    float range;
    pf_scene lit; /* the scene with one point light at its centre (shallow copy) */
    pf_light light;
    rs_shadow_map map;
    int have_map;
    /* samples, frames each */
    double *vis, *res, *tot, *emb, *rays, *pm, *pe, *cube;
} bench_run;

static void bench__close(bench_run *r)
{
    if (r->have_map) rs_shadow_map_free(&r->map);
    if (r->have_frame) gi_frame_free(&r->f);
    free(r->vis), free(r->res), free(r->tot), free(r->emb), free(r->pm), free(r->pe), free(r->cube), free(r->rays);
    free(r->hits);
    free(r->atlas);
    rs_para_context_destroy(r->para);
    rs_context_destroy(r->rs);
    pf_rt_destroy(r->rt);
    if (r->jobs) pf_jobs_destroy(r->jobs);
    memset(r, 0, sizeof *r);
}

static int bench__open(bench_run *r, const pf_scene *scene, const bench_scene *bs, const pf_vec3 *vp,
                       const pf_vec3 *vn, uint32_t threads, pf_isa isa, uint32_t frames)
{
    pf_error err;
    memset(r, 0, sizeof *r);
    r->threads = threads;
    r->frames = frames;
    r->vp = vp;
    r->vn = vn;
    if (!(r->jobs = pf_jobs_create(threads))) {
        pf_error_set(&err, PF_ERR_OUT_OF_MEMORY, "cannot start %u threads", threads);
        goto fail;
    }
    if (pf_rt_create(&r->rt, scene, isa, threads, &err) != PF_OK ||
        rs_context_create(&r->rs, scene, r->jobs, rs_simd_for_isa(isa), &err) != PF_OK ||
        rs_para_context_create(&r->para, scene, NULL, &err) != PF_OK ||
        pf_camera_look_at(&r->cam, bs->eye, bs->target, pf_radians(bs->fovy_deg), &err) != PF_OK ||
        gi_frame_init(&r->f, scene, r->rt, r->rs, r->jobs, &r->cam, BENCH_W, BENCH_H, 0, &err) != PF_OK)
        goto fail;
    r->have_frame = 1;
    double **samples[] = {&r->vis, &r->res, &r->tot, &r->emb, &r->rays, &r->pm, &r->pe, &r->cube};
    for (size_t k = 0; k < sizeof samples / sizeof samples[0]; k++)
        if (!(*samples[k] = calloc(frames, sizeof(double)))) goto oom;
    r->range = rs_para_default_range(scene);
    if (!(r->hits = malloc(sizeof(pf_hit) * BENCH_W * BENCH_H)) ||
        !(r->atlas = malloc(rs_para_atlas_bytes(rs_para_resolution(r->para), BENCH_VPLS))))
        goto oom;
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
    return 1;
oom:
    pf_error_set(&err, PF_ERR_OUT_OF_MEMORY, "out of memory for the benchmark");
fail:
    fprintf(stderr, "softgi bench: %s\n", err.message);
    bench__close(r);
    return 0;
}

/* One frame of every measurement; frame 0 is the warm-up (not recorded). */
static void bench__frame(bench_run *r, uint32_t i)
{
    /* G-buffer: raster (visibility + resolve) vs Embree */
    double t0 = pf_time_now();
    rs_target tg = {BENCH_W, BENCH_H, r->f.gbuf.depth, r->f.gbuf.prim, NULL};
    rs_pass pass = {rs_mat4_camera(&r->cam, BENCH_W, BENCH_H), RS_CULL_NONE};
    rs_render(r->rs, &pass, &tg, &r->st);
    double t1 = pf_time_now();
    gi_stage_gbuffer_resolve(&r->f);
    double t2 = pf_time_now();
    gi_stage_gbuffer_raytrace(&r->f);
    double t3 = pf_time_now();
    bench__rays_ctx rc = {r->rt, &r->cam, r->hits};
    pf_jobs_parallel_for(r->jobs, bench__rays_row, &rc, BENCH_H, 1);
    double t4 = pf_time_now();
    pf_jobs_wait_all(r->jobs);
    /* paraboloid maps: 64 in one call, per-map mean */
    uint32_t res_para = rs_para_resolution(r->para);
    double t5 = pf_time_now();
    rs_para_render(r->atlas, r->para, r->jobs, r->vp, r->vn, BENCH_VPLS, r->range, NULL);
    double t6 = pf_time_now();
    rs_para_render_traced(r->atlas, res_para, r->rt, r->jobs, r->vp, r->vn, BENCH_VPLS, r->range);
    double t7 = pf_time_now();
    pf_jobs_wait_all(r->jobs);
    /* cube shadow map */
    double t8 = pf_time_now();
    rs_shadow_render(r->rs, &r->map, 1, NULL);
    double t9 = pf_time_now();
    pf_jobs_wait_all(r->jobs);
    if (i == 0) return;
    r->vis[i - 1] = (t1 - t0) * 1e3;
    r->res[i - 1] = (t2 - t1) * 1e3;
    r->tot[i - 1] = (t2 - t0) * 1e3;
    r->emb[i - 1] = (t3 - t2) * 1e3;
    r->rays[i - 1] = (t4 - t3) * 1e3;
    r->pm[i - 1] = (t6 - t5) * 1e3 / BENCH_VPLS;
    r->pe[i - 1] = (t7 - t6) * 1e3 / BENCH_VPLS;
    r->cube[i - 1] = (t9 - t8) * 1e3;
}

/* `base`: the 1-thread run of the same scene for a 2-thread row's
 * speed-ups, or NULL. Call for the 2-thread run first: medians sort the
 * sample arrays, and pairs need them in frame order. */
static void bench__result(bench_run *r, const bench_run *base, const char *scene, bench_result *out, double *tmp)
{
    memset(out, 0, sizeof *out);
    out->scene = scene;
    out->threads = r->threads;
    uint32_t n = r->frames;
    out->x_vis = bench__paired(r->rays, r->vis, n, tmp);
    out->x_gbuf = bench__paired(r->emb, r->tot, n, tmp);
    out->x_para = bench__paired(r->pe, r->pm, n, tmp);
    if (base) {
        out->up_vis = bench__paired(base->vis, r->vis, n, tmp);
        out->up_gbuf = bench__paired(base->tot, r->tot, n, tmp);
        out->up_para = bench__paired(base->pm, r->pm, n, tmp);
        out->up_cube = bench__paired(base->cube, r->cube, n, tmp);
    }
    out->tris = (uint32_t)r->st.triangles_in;
    out->vis_ms = bench__median(r->vis, r->frames);
    out->resolve_ms = bench__median(r->res, r->frames);
    out->gbuf_ms = bench__median(r->tot, r->frames);
    out->embree_gbuf_ms = bench__median(r->emb, r->frames);
    out->embree_rays_ms = bench__median(r->rays, r->frames);
    out->para_ms = bench__median(r->pm, r->frames);
    out->para_embree_ms = bench__median(r->pe, r->frames);
    out->cube_ms = bench__median(r->cube, r->frames);
    out->tris_per_s = out->tris / (out->vis_ms * 1e-3);
    out->pixels_per_s = (double)BENCH_W * BENCH_H / (out->gbuf_ms * 1e-3);
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
    bench_result results[8];
    uint32_t nres = 0;
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
        pf_vec3 vp[BENCH_VPLS], vn[BENCH_VPLS];
        bench__sample_vpls(&scene, vp, vn, BENCH_VPLS);
        bench_run runs[2];
        uint32_t opened = 0;
        for (; opened < nthreads; opened++)
            if (!bench__open(&runs[opened], &scene, &k_scenes[k], vp, vn, thread_list[opened], isa, frames)) break;
        if (opened < nthreads) {
            for (uint32_t t = 0; t < opened; t++) bench__close(&runs[t]);
            pf_scene_free(&scene);
            return 1;
        }
        pf_cpu_ticks c0 = pf_cpu_ticks_now();
        for (uint32_t i = 0; i <= frames; i++) /* thread counts take turns */
            for (uint32_t t = 0; t < nthreads; t++) bench__frame(&runs[t], i);
        pf_cpu_ticks c1 = pf_cpu_ticks_now();
        if (pf_cpu_steal_share(c0, c1) >= 0.0) {
            steal.valid = 1;
            steal.total += c1.total - c0.total;
            steal.steal += c1.steal - c0.steal;
        }
        double *tmp = malloc(sizeof(double) * frames);
        if (!tmp) {
            fprintf(stderr, "softgi bench: out of memory for the benchmark\n");
            for (uint32_t t = 0; t < nthreads; t++) bench__close(&runs[t]);
            pf_scene_free(&scene);
            return 1;
        }
        /* the 2-thread row first: its pairs need the 1-thread samples unsorted */
        for (uint32_t t = nthreads; t-- > 0;)
            bench__result(&runs[t], t == 1 ? &runs[0] : NULL, k_scenes[k].name, &results[nres + t], tmp);
        nres += nthreads;
        free(tmp);
        for (uint32_t t = 0; t < nthreads; t++) bench__close(&runs[t]);
        pf_scene_free(&scene);
    }
    printf("\nG-buffer: raster visibility vs Embree primary rays (visibility only), then the whole G-buffer\n"
           "(visibility + attributes) both ways; paraboloid: ms per 128x128 map; cube: 6 faces of 1024^2\n");
    printf("%-11s %3s | %7s %7s %6s | %7s %7s %7s %6s | %8s %8s %6s | %8s | %7s %8s\n", "scene", "thr", "vis ms",
           "rays ms", "x", "resolve", "gbuf ms", "embree", "x", "para ms", "embree", "x", "cube ms", "Mtri/s", "Mpix/s");
    for (uint32_t i = 0; i < nres; i++) {
        const bench_result *r = &results[i];
        printf("%-11s %3u | %7.2f %7.2f %6.2f | %7.2f %7.2f %7.2f %6.2f | %8.3f %8.3f %6.2f | %8.2f | %7.1f %8.1f\n",
               r->scene, r->threads, r->vis_ms, r->embree_rays_ms, r->embree_rays_ms / r->vis_ms, r->resolve_ms,
               r->gbuf_ms, r->embree_gbuf_ms, r->embree_gbuf_ms / r->gbuf_ms, r->para_ms, r->para_embree_ms,
               r->para_embree_ms / r->para_ms, r->cube_ms, r->tris_per_s * 1e-6, r->pixels_per_s * 1e-6);
    }
    /* targets (issue 3), on the paired medians: each frame times the raster
     * pass and its Embree equivalent back to back, and the 1- and 2-thread
     * runs take turns frame by frame, so a frame's ratio compares timings
     * taken under the same load; the median over frames of those ratios is
     * steadier on a shared machine than the ratio of the medians above */
    printf("\ntargets: G-buffer >= 5x Embree; paraboloid map >= 1x Embree; 2 threads >= 1.8x 1 thread\n"
           "(paired: the median over frames of each frame's ratio)\n");
    for (uint32_t i = 0; i < nres; i++) {
        const bench_result *r = &results[i];
        printf("  %-11s %u thr: visibility %.2fx %s, whole G-buffer %.2fx %s, paraboloid %.2fx %s", r->scene, r->threads,
               r->x_vis, r->x_vis >= 5.0 ? "met" : "NOT met", r->x_gbuf, r->x_gbuf >= 5.0 ? "met" : "NOT met", r->x_para,
               r->x_para >= 1.0 ? "met" : "NOT met");
        if (r->up_gbuf > 0.0)
            printf(", 2-thread speed-up visibility %.2fx, gbuffer %.2fx %s, paraboloid %.2fx %s, cube %.2fx %s", r->up_vis,
                   r->up_gbuf, r->up_gbuf >= 1.8 ? "met" : "NOT met", r->up_para, r->up_para >= 1.8 ? "met" : "NOT met",
                   r->up_cube, r->up_cube >= 1.8 ? "met" : "NOT met");
        printf("\n");
    }
    printf("  2048 paraboloid maps of 128x128: %.1f MB\n", rs_para_atlas_bytes(128, 2048) / (1024.0 * 1024.0));
    pf_cpu_ticks zero = {1, 0, 0};
    double steal_share = pf_cpu_steal_share(zero, steal);
    if (steal_share >= 0.0)
        printf("cpu steal during the timed frames: %.1f%% of all CPU time (a virtual machine's host running other\n"
               "guests; the 2-thread rows, which need both CPUs at once, suffer most)\n",
               100.0 * steal_share);
    printf("json: {\"bench\":\"raster\",\"width\":%d,\"height\":%d,\"isa\":\"%s\",\"frames\":%u,\"cpu_steal\":%.4f,"
           "\"results\":[",
           BENCH_W, BENCH_H, pf_isa_name(isa), frames, steal_share);
    for (uint32_t i = 0; i < nres; i++) {
        const bench_result *r = &results[i];
        printf("%s{\"scene\":\"%s\",\"threads\":%u,\"gbuffer_visibility_ms\":%.3f,\"gbuffer_resolve_ms\":%.3f,"
               "\"gbuffer_ms\":%.3f,\"embree_rays_ms\":%.3f,\"gbuffer_embree_ms\":%.3f,\"paraboloid_ms\":%.4f,\"paraboloid_embree_ms\":%.4f,"
               "\"cube_ms\":%.3f,\"triangles_per_s\":%.0f,\"pixels_per_s\":%.0f,\"paired_x_visibility\":%.3f,"
               "\"paired_x_gbuffer\":%.3f,\"paired_x_paraboloid\":%.3f,\"paired_speedup_visibility\":%.3f,"
               "\"paired_speedup_gbuffer\":%.3f,\"paired_speedup_paraboloid\":%.3f,\"paired_speedup_cube\":%.3f}",
               i ? "," : "", r->scene, r->threads, r->vis_ms, r->resolve_ms, r->gbuf_ms, r->embree_rays_ms, r->embree_gbuf_ms, r->para_ms,
               r->para_embree_ms, r->cube_ms, r->tris_per_s, r->pixels_per_s, r->x_vis, r->x_gbuf, r->x_para, r->up_vis,
               r->up_gbuf, r->up_para, r->up_cube);
    }
    printf("]}\n");
    return 0;
}
