/* app_bench_embree: Embree baselines for `softgi bench raster` (see
 * app_bench_embree.h). Called only by app_bench.c. */
#include "app_bench_embree.h"

#include <embree3/rtcore.h>
#include <math.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "pf_fpenv.h"
#include "simd.h" /* the baseline vocabulary (SSE2 on x86-64): streaming stores */
#include "pf_timer.h"
#include "rs_paraboloid.h"

/* Embree's standard build (binned SAH). The build is outside the timing,
 * so the quality to take is the one that traces fastest, and no quality
 * does on every job: HIGH (spatial splits) measured within +-5% of MEDIUM
 * (paraboloid maps 2-4% faster, the visibility buffer 1-4% slower, the cube
 * map faster on one scene and slower on the other), LOW 10-20% slower on
 * all (docs/perf.md "Benchmarks"). */
#define APP_EMBREE_BUILD_QUALITY RTC_BUILD_QUALITY_MEDIUM
#define APP_EMBREE_TILE 16u /* pixels per side of one job item */
#define APP_EMBREE_MAX_LANES 16u

struct app_embree {
    RTCDevice device;
    RTCScene scene;
    const pf_scene *src;
    uint32_t lanes; /* rays per packet: 16, 8 or 4, over blocks of 4x4, 4x2 or 2x2 pixels (APP__BLOCK_W) */
    double build_ms;
    pf_error *build_err; /* where the error callback writes during creation */
};

/* ------------------------------------------------------------ ray packets */

/* A ray-hit packet of N lanes in Embree's structure-of-arrays layout
 * (rtcore_ray.h, RTCRayHitN): each field below is N consecutive 4-byte
 * entries. One buffer of the widest size serves every width; the asserts
 * check the layout against Embree's own structures. */
enum {
    APP__ORG_X, APP__ORG_Y, APP__ORG_Z, APP__TNEAR, APP__DIR_X, APP__DIR_Y, APP__DIR_Z, APP__TIME, APP__TFAR,
    APP__MASK, APP__ID, APP__FLAGS, APP__NG_X, APP__NG_Y, APP__NG_Z, APP__U, APP__V, APP__PRIM, APP__GEOM,
    APP__INST, APP__FIELDS
};
_Static_assert(RTC_MAX_INSTANCE_LEVEL_COUNT == 1, "one instID field");
_Static_assert(sizeof(struct RTCRayHit16) == APP__FIELDS * 16 * 4 &&
                   offsetof(struct RTCRayHit16, ray.tfar) == APP__TFAR * 16 * 4 &&
                   offsetof(struct RTCRayHit16, hit.Ng_x) == APP__NG_X * 16 * 4 &&
                   offsetof(struct RTCRayHit16, hit.primID) == APP__PRIM * 16 * 4 &&
                   offsetof(struct RTCRayHit16, hit.instID) == APP__INST * 16 * 4,
               "RTCRayHit16 layout");
_Static_assert(sizeof(struct RTCRayHit8) == APP__FIELDS * 8 * 4 &&
                   offsetof(struct RTCRayHit8, hit.primID) == APP__PRIM * 8 * 4,
               "RTCRayHit8 layout");
_Static_assert(sizeof(struct RTCRayHit4) == APP__FIELDS * 4 * 4 &&
                   offsetof(struct RTCRayHit4, hit.primID) == APP__PRIM * 4 * 4,
               "RTCRayHit4 layout");

typedef union app__lane {
    float f;
    uint32_t u;
} app__lane;

typedef struct app__packet {
    _Alignas(64) app__lane a[APP__FIELDS * APP_EMBREE_MAX_LANES];
    _Alignas(64) int valid[APP_EMBREE_MAX_LANES];
} app__packet;

/* Field `field`, lane `l` of packet p of L lanes. The kernels below take L
 * as a parameter and are inlined into one call per width with L a constant
 * (app__views_tile, app__para_map), so the compiler unrolls and vectorises
 * the per-lane loops: the rays' set-up and the outputs' stores cost half
 * of what scalar per-lane code with a run-time width did (measured: from a
 * quarter of the time spent inside Embree to an eighth). */
#define APP__F(p, L, field, l) ((p)->a[(field) * (L) + (l)].f)
#define APP__U(p, L, field, l) ((p)->a[(field) * (L) + (l)].u)
#define APP__INLINE static inline __attribute__((always_inline))
/* The block of pixels or texels a packet of L lanes covers: BW x L/BW, lane
 * l at (l % BW, l / BW). */
#define APP__BLOCK_W(L) ((L) == 4 ? 2u : 4u)

/* The fields a packet's rays share for a whole job item: origin, tnear,
 * time, mask, flags. Embree leaves them as they are, so each packet then
 * sets only its directions, tfar and geomID. */
APP__INLINE void app__packet_init(app__packet *p, const uint32_t L, pf_vec3 org, float tnear)
{
    memset(p, 0, sizeof *p);
    for (uint32_t l = 0; l < L; l++) {
        APP__F(p, L, APP__ORG_X, l) = org.x;
        APP__F(p, L, APP__ORG_Y, l) = org.y;
        APP__F(p, L, APP__ORG_Z, l) = org.z;
        APP__F(p, L, APP__TNEAR, l) = tnear;
        APP__U(p, L, APP__MASK, l) = 0xffffffffu;
        APP__U(p, L, APP__ID, l) = l;
        APP__U(p, L, APP__INST, l) = RTC_INVALID_GEOMETRY_ID;
    }
}

/* Traces the packet's valid lanes; a lane hit something iff its geomID is
 * no longer invalid. */
APP__INLINE void app__trace(const app_embree *e, app__packet *p, const uint32_t L)
{
    struct RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    ctx.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
    if (L == 16) rtcIntersect16(p->valid, e->scene, &ctx, (struct RTCRayHit16 *)(void *)p->a);
    else if (L == 8) rtcIntersect8(p->valid, e->scene, &ctx, (struct RTCRayHit8 *)(void *)p->a);
    else rtcIntersect4(p->valid, e->scene, &ctx, (struct RTCRayHit4 *)(void *)p->a);
}

/* ---------------------------------------------------------------- device */

static void app__embree_error(void *user, enum RTCError code, const char *str)
{
    app_embree *e = user;
    if (e && e->build_err)
        pf_error_set(e->build_err, PF_ERR_EMBREE, "Embree: %s (error %d)", str ? str : "", (int)code);
    else
        fprintf(stderr, "softgi bench: Embree error: %s (error %d)\n", str ? str : "", (int)code);
}

pf_result app_embree_create(app_embree **out, const pf_scene *scene, pf_isa isa, uint32_t build_threads,
                            pf_error *err)
{
    *out = NULL;
    pf_fpenv_set(); /* FTZ/DAZ on the calling thread too, as Embree asks */
    app_embree *e = calloc(1, sizeof *e);
    if (!e) return pf_error_set(err, PF_ERR_OUT_OF_MEMORY, "out of memory creating the Embree baseline");
    pf_error local;
    local.code = PF_OK;
    e->build_err = &local;
    e->src = scene;
    char config[128];
    snprintf(config, sizeof config, "ignore_config_files=1,threads=%u,set_affinity=0,isa=%s",
             build_threads ? build_threads : 1u, pf_isa_name(isa));
    e->device = rtcNewDevice(config);
    if (!e->device) {
        free(e);
        return pf_error_set(err, PF_ERR_EMBREE, "Embree: cannot create a device with '%s' (error %d)", config,
                            (int)rtcGetDeviceError(NULL));
    }
    rtcSetDeviceErrorFunction(e->device, app__embree_error, e);

    /* The widest packet the ISA traces natively. */
    e->lanes = isa == PF_ISA_AVX512 ? 16u : isa == PF_ISA_AVX2 ? 8u : 4u;
    if (e->lanes == 16 && !rtcGetDeviceProperty(e->device, RTC_DEVICE_PROPERTY_NATIVE_RAY16_SUPPORTED)) e->lanes = 8;
    if (e->lanes == 8 && !rtcGetDeviceProperty(e->device, RTC_DEVICE_PROPERTY_NATIVE_RAY8_SUPPORTED)) e->lanes = 4;

    double t0 = pf_time_now();
    e->scene = rtcNewScene(e->device);
    rtcSetSceneFlags(e->scene, RTC_SCENE_FLAG_NONE);
    rtcSetSceneBuildQuality(e->scene, APP_EMBREE_BUILD_QUALITY);
    RTCGeometry geom = rtcNewGeometry(e->device, RTC_GEOMETRY_TYPE_TRIANGLE);
    rtcSetGeometryBuildQuality(geom, APP_EMBREE_BUILD_QUALITY);
    /* the scene's arrays, shared (positions carry Embree's padding vertex) */
    rtcSetSharedGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, scene->positions, 0,
                               sizeof(pf_vec3), scene->vertex_count);
    rtcSetSharedGeometryBuffer(geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, scene->indices, 0,
                               3 * sizeof(uint32_t), scene->tri_count);
    rtcCommitGeometry(geom);
    rtcAttachGeometry(e->scene, geom);
    rtcReleaseGeometry(geom);
    rtcCommitScene(e->scene);
    e->build_ms = (pf_time_now() - t0) * 1e3;
    e->build_err = NULL;
    if (local.code != PF_OK || rtcGetDeviceError(e->device) != RTC_ERROR_NONE) {
        if (local.code == PF_OK) pf_error_set(&local, PF_ERR_EMBREE, "Embree: building the baseline scene failed");
        app_embree_destroy(e);
        if (err) *err = local;
        return local.code;
    }
    *out = e;
    return PF_OK;
}

void app_embree_destroy(app_embree *e)
{
    if (!e) return;
    if (e->scene) rtcReleaseScene(e->scene);
    if (e->device) rtcReleaseDevice(e->device);
    free(e);
}

uint32_t app_embree_packet_width(const app_embree *e) { return e->lanes; }
double app_embree_build_ms(const app_embree *e) { return e->build_ms; }

/* ------------------------------------------------------ perspective views */

/* A perspective view traced one 16x16 tile per job item: the camera's
 * image (visibility buffer or whole G-buffer) or the faces of a shadow
 * map. Pixel (x, y) of a view traces eye + t (f + sx(x) r + sy(y) u) with
 * sx(x) = (2 (x + 0.5) / width - 1) kx, sy(y) = (1 - 2 (y + 0.5) / height) ky
 * (pf_camera_ray_dir's expression), so t is the view depth. */
typedef struct app__view {
    pf_vec3 eye, f, r, u;
    float kx, ky, znear;
    float *depth; /* reversed depth planes (visibility, shadow faces) */
    uint32_t *prim;
} app__view;

typedef struct app__views_job {
    const app_embree *e;
    const app__view *views;
    uint32_t width, height, tiles_x, tiles_per_view;
    rs_gbuffer *g; /* whole G-buffer of views[0], or NULL: reversed depth (+ prim) */
} app__views_job;

/* One 16x16 tile of the G-buffer, filled packet by packet and copied out
 * once (app__tile_store), as rs_raster does with its tiles: the planes'
 * lines are then written whole, with non-temporal stores, instead of 16
 * bytes at a time from each packet (10% faster on the G-buffer job).
 * Planes: view depth, position, normal, albedo; then the triangle ids. */
enum { APP__T_DEPTH, APP__T_POS, APP__T_NRM = APP__T_POS + 3, APP__T_ALB = APP__T_NRM + 3, APP__T_PLANES = APP__T_ALB + 3 };
#define APP__TILE_PIXELS (APP_EMBREE_TILE * APP_EMBREE_TILE)
typedef struct app__tile {
    _Alignas(64) float f[APP__T_PLANES][APP__TILE_PIXELS];
    _Alignas(64) uint32_t prim[APP__TILE_PIXELS];
} app__tile;

/* n 32-bit values of a tile row to the image (rs_raster's rs__copy_out). */
static void app__copy_out(void *dst, const void *src, size_t n)
{
    if (n % SIMD_W == 0 && ((uintptr_t)dst & (SIMD_W * 4 - 1)) == 0) {
        int32_t *d = dst;
        const int32_t *s = src; /* tile rows: 64-byte aligned */
        for (size_t i = 0; i < n; i += SIMD_W) simd_stream_i(d + i, simd_load_i(s + i));
        return;
    }
    memcpy(dst, src, n * 4);
}

/* The tile's planes `planes` (float planes dst[k] from tile plane k) and,
 * where prim is not NULL, its triangle ids, for the w x h pixels at
 * (x0, y0) of an image `width` wide. */
static void app__tile_store(const app__tile *t, float *const *dst, uint32_t planes, uint32_t *prim, uint32_t width,
                            uint32_t x0, uint32_t y0, uint32_t w, uint32_t h)
{
    for (uint32_t y = 0; y < h; y++) {
        size_t row = (size_t)(y0 + y) * width + x0;
        for (uint32_t k = 0; k < planes; k++) app__copy_out(dst[k] + row, &t->f[k][y * APP_EMBREE_TILE], w);
        if (prim) app__copy_out(prim + row, &t->prim[y * APP_EMBREE_TILE], w);
    }
    simd_stream_fence(); /* the streamed rows are visible before the job reports the tile done */
}

/* The G-buffer values of one traced packet into the tile at (tx, ty), as
 * rs_gbuffer_resolve computes them: the lane-parallel parts (position,
 * facing, normalisation) as loops over lanes the compiler vectorises, the
 * per-triangle fetches (indices, vertex normals, material) lane by lane. */
APP__INLINE void app__gbuffer_block(app__tile *tb, const pf_scene *s, const app__packet *p, const uint32_t L,
                                    uint32_t tx, uint32_t ty)
{
    const uint32_t BW = APP__BLOCK_W(L);
    float depth[APP_EMBREE_MAX_LANES], px[APP_EMBREE_MAX_LANES], py[APP_EMBREE_MAX_LANES], pz[APP_EMBREE_MAX_LANES];
    float nx[APP_EMBREE_MAX_LANES], ny[APP_EMBREE_MAX_LANES], nz[APP_EMBREE_MAX_LANES];
    float ar[APP_EMBREE_MAX_LANES], ag[APP_EMBREE_MAX_LANES], ab[APP_EMBREE_MAX_LANES];
    uint32_t prim[APP_EMBREE_MAX_LANES];
    for (uint32_t l = 0; l < L; l++) {
        int hit = APP__U(p, L, APP__GEOM, l) != RTC_INVALID_GEOMETRY_ID;
        float t = APP__F(p, L, APP__TFAR, l);
        depth[l] = hit ? t : INFINITY;
        prim[l] = hit ? APP__U(p, L, APP__PRIM, l) : RS_GBUFFER_EMPTY;
        px[l] = hit ? APP__F(p, L, APP__ORG_X, l) + APP__F(p, L, APP__DIR_X, l) * t : 0.0f;
        py[l] = hit ? APP__F(p, L, APP__ORG_Y, l) + APP__F(p, L, APP__DIR_Y, l) * t : 0.0f;
        pz[l] = hit ? APP__F(p, L, APP__ORG_Z, l) + APP__F(p, L, APP__DIR_Z, l) * t : 0.0f;
    }
    for (uint32_t l = 0; l < L; l++) {
        nx[l] = ny[l] = nz[l] = ar[l] = ag[l] = ab[l] = 0.0f;
        if (prim[l] == RS_GBUFFER_EMPTY) continue;
        const uint32_t *tri = &s->indices[3 * (size_t)prim[l]];
        float u = APP__F(p, L, APP__U, l), v = APP__F(p, L, APP__V, l), w = 1.0f - u - v;
        pf_vec3 n0 = s->normals[tri[0]], n1 = s->normals[tri[1]], n2 = s->normals[tri[2]];
        nx[l] = n0.x * w + n1.x * u + n2.x * v;
        ny[l] = n0.y * w + n1.y * u + n2.y * v;
        nz[l] = n0.z * w + n1.z * u + n2.z * v;
        uint32_t m = s->tri_material[prim[l]];
        const float *albedo = s->materials[m].base_color;
        float rgba[4];
        if (s->materials[m].base_color_texture >= 0) {
            const pf_vec2 *uv = s->uvs;
            pf_vec2 tc = {w * uv[tri[0]].x + u * uv[tri[1]].x + v * uv[tri[2]].x,
                          w * uv[tri[0]].y + u * uv[tri[1]].y + v * uv[tri[2]].y};
            pf_material_sample(s, m, tc, 0.0f, rgba);
            albedo = rgba;
        }
        ar[l] = albedo[0], ag[l] = albedo[1], ab[l] = albedo[2];
    }
    int vanished = 0;
    for (uint32_t l = 0; l < L; l++) {
        /* Embree's Ng is (v1 - v0) x (v2 - v0), unnormalised: only its side
         * counts, turning the normal to face the camera (two-sided shading) */
        float facing = APP__F(p, L, APP__NG_X, l) * APP__F(p, L, APP__DIR_X, l) +
                       APP__F(p, L, APP__NG_Y, l) * APP__F(p, L, APP__DIR_Y, l) +
                       APP__F(p, L, APP__NG_Z, l) * APP__F(p, L, APP__DIR_Z, l);
        float len2 = nx[l] * nx[l] + ny[l] * ny[l] + nz[l] * nz[l];
        float k = len2 > 0.0f ? (facing > 0.0f ? -1.0f : 1.0f) / sqrtf(len2) : 0.0f;
        nx[l] *= k, ny[l] *= k, nz[l] *= k;
        vanished |= len2 == 0.0f && prim[l] != RS_GBUFFER_EMPTY;
    }
    if (vanished) /* the interpolated normal vanished: the facing geometric normal, as pf_scene_surface does */
        for (uint32_t l = 0; l < L; l++) {
            if (prim[l] == RS_GBUFFER_EMPTY || nx[l] != 0.0f || ny[l] != 0.0f || nz[l] != 0.0f) continue;
            pf_vec3 ng = pf_v3_normalize(
                pf_v3(APP__F(p, L, APP__NG_X, l), APP__F(p, L, APP__NG_Y, l), APP__F(p, L, APP__NG_Z, l)));
            pf_vec3 d = pf_v3(APP__F(p, L, APP__DIR_X, l), APP__F(p, L, APP__DIR_Y, l), APP__F(p, L, APP__DIR_Z, l));
            if (pf_v3_dot(ng, d) > 0.0f) ng = pf_v3_scale(ng, -1.0f);
            nx[l] = ng.x, ny[l] = ng.y, nz[l] = ng.z;
        }
    for (uint32_t l = 0; l < L; l++) {
        uint32_t i = (ty + l / BW) * APP_EMBREE_TILE + tx + l % BW;
        tb->f[APP__T_DEPTH][i] = depth[l], tb->prim[i] = prim[l];
        tb->f[APP__T_POS][i] = px[l], tb->f[APP__T_POS + 1][i] = py[l], tb->f[APP__T_POS + 2][i] = pz[l];
        tb->f[APP__T_NRM][i] = nx[l], tb->f[APP__T_NRM + 1][i] = ny[l], tb->f[APP__T_NRM + 2][i] = nz[l];
        tb->f[APP__T_ALB][i] = ar[l], tb->f[APP__T_ALB + 1][i] = ag[l], tb->f[APP__T_ALB + 2][i] = ab[l];
    }
}

APP__INLINE void app__views_tile_n(const app__views_job *job, uint32_t item, const uint32_t L)
{
    const uint32_t BW = APP__BLOCK_W(L), BH = L / BW;
    const app__view *vw = &job->views[item / job->tiles_per_view];
    uint32_t tile = item % job->tiles_per_view;
    uint32_t x0 = (tile % job->tiles_x) * APP_EMBREE_TILE, y0 = (tile / job->tiles_x) * APP_EMBREE_TILE;
    const uint32_t W = job->width, H = job->height;
    uint32_t tw = W - x0 < APP_EMBREE_TILE ? W - x0 : APP_EMBREE_TILE;
    uint32_t th = H - y0 < APP_EMBREE_TILE ? H - y0 : APP_EMBREE_TILE;
    const float inv_w = 2.0f / (float)W, inv_h = 2.0f / (float)H;
    const pf_vec3 f = vw->f, r = vw->r, u = vw->u;
    app__packet p;
    app__packet_init(&p, L, vw->eye, vw->znear);
    app__tile tb;
    for (uint32_t ty = 0; ty < th; ty += BH)
        for (uint32_t tx = 0; tx < tw; tx += BW) {
            for (uint32_t l = 0; l < L; l++) {
                uint32_t x = x0 + tx + l % BW, y = y0 + ty + l / BW;
                p.valid[l] = x < W && y < H ? -1 : 0;
                float sx = (((float)x + 0.5f) * inv_w - 1.0f) * vw->kx;
                float sy = (1.0f - ((float)y + 0.5f) * inv_h) * vw->ky;
                APP__F(&p, L, APP__DIR_X, l) = f.x + (r.x * sx + u.x * sy);
                APP__F(&p, L, APP__DIR_Y, l) = f.y + (r.y * sx + u.y * sy);
                APP__F(&p, L, APP__DIR_Z, l) = f.z + (r.z * sx + u.z * sy);
                APP__F(&p, L, APP__TFAR, l) = INFINITY;
                APP__U(&p, L, APP__GEOM, l) = RTC_INVALID_GEOMETRY_ID;
            }
            app__trace(job->e, &p, L);
            if (job->g) {
                app__gbuffer_block(&tb, job->e->src, &p, L, tx, ty);
                continue;
            }
            /* depth-only passes store straight from the packet: through
             * the tile they measured 3-5% slower (cube maps) or the same
             * (visibility), while the G-buffer's 11 planes gain 10% */
            for (uint32_t l = 0; l < L; l++) {
                uint32_t x = x0 + tx + l % BW, y = y0 + ty + l / BW;
                if (x >= W || y >= H) continue;
                size_t i = (size_t)y * W + x;
                int hit = APP__U(&p, L, APP__GEOM, l) != RTC_INVALID_GEOMETRY_ID;
                vw->depth[i] = hit ? vw->znear / APP__F(&p, L, APP__TFAR, l) : 0.0f;
                if (vw->prim) vw->prim[i] = hit ? APP__U(&p, L, APP__PRIM, l) : RS_GBUFFER_EMPTY;
            }
        }
    if (job->g) {
        rs_gbuffer *g = job->g;
        float *const planes[APP__T_PLANES] = {g->depth, g->pos_x, g->pos_y, g->pos_z, g->nrm_x,
                                              g->nrm_y, g->nrm_z, g->alb_r, g->alb_g, g->alb_b};
        app__tile_store(&tb, planes, APP__T_PLANES, g->prim, W, x0, y0, tw, th);
    }
}

static void app__views_tile(void *ctx, uint32_t item, uint32_t worker)
{
    (void)worker;
    const app__views_job *job = ctx;
    switch (job->e->lanes) {
    case 16: app__views_tile_n(job, item, 16); break;
    case 8: app__views_tile_n(job, item, 8); break;
    default: app__views_tile_n(job, item, 4); break;
    }
}

static void app__trace_views(const app_embree *e, pf_jobs *jobs, const app__view *views, uint32_t count,
                             uint32_t width, uint32_t height, rs_gbuffer *g)
{
    uint32_t tiles_x = (width + APP_EMBREE_TILE - 1) / APP_EMBREE_TILE;
    uint32_t tiles_y = (height + APP_EMBREE_TILE - 1) / APP_EMBREE_TILE;
    app__views_job job = {e, views, width, height, tiles_x, tiles_x * tiles_y, g};
    pf_jobs_parallel_for(jobs, app__views_tile, &job, count * job.tiles_per_view, 1);
}

/* The camera as a view: rs_mat4_camera's near plane, pf_camera_ray_dir's
 * directions. */
static app__view app__camera_view(const pf_camera *cam, uint32_t width, uint32_t height)
{
    float th = tanf(0.5f * cam->yfov);
    app__view v = {cam->eye, cam->forward, cam->right, cam->up, th * ((float)width / (float)height), th,
                   cam->znear > 0.0f ? cam->znear : 0.01f, NULL, NULL};
    return v;
}

void app_embree_visibility(float *depth, uint32_t *prim, const app_embree *e, pf_jobs *jobs, const pf_camera *cam,
                           uint32_t width, uint32_t height)
{
    app__view v = app__camera_view(cam, width, height);
    v.depth = depth;
    v.prim = prim;
    app__trace_views(e, jobs, &v, 1, width, height, NULL);
}

void app_embree_gbuffer(rs_gbuffer *g, const app_embree *e, pf_jobs *jobs, const pf_camera *cam)
{
    app__view v = app__camera_view(cam, g->width, g->height);
    app__trace_views(e, jobs, &v, 1, g->width, g->height, g);
}

void app_embree_shadow(rs_shadow_map *map, const app_embree *e, pf_jobs *jobs)
{
    /* rs_shadow's perspective faces: rs_mat4_perspective with aspect 1 and
     * tan(fov / 2) = tan_half, so both axes span [-tan_half, tan_half] */
    app__view views[RS_SHADOW_MAX_FACES];
    for (uint32_t f = 0; f < map->face_count; f++) {
        app__view v = {map->eye, map->forward[f], map->right[f], map->up[f], map->tan_half, map->tan_half,
                       map->znear, rs_shadow_map_face(map, f), NULL};
        views[f] = v;
    }
    app__trace_views(e, jobs, views, map->face_count, map->size, map->size, NULL);
}

/* ------------------------------------------------------- paraboloid maps */

typedef struct app__para_job {
    const app_embree *e;
    uint16_t *atlas;
    uint32_t res;
    const pf_vec3 *positions, *normals;
    float scale; /* codes per unit distance */
} app__para_job;

APP__INLINE void app__para_map_n(const app__para_job *job, uint32_t item, const uint32_t L)
{
    const uint32_t BW = APP__BLOCK_W(L), BH = L / BW;
    const int32_t R = (int32_t)job->res; /* <= RS_PARA_MAX_RES: the disc test below fits 32 bits */
    uint16_t *out = job->atlas + (size_t)R * R * item;
    rs_para_frame f = rs_para_frame_make(job->positions[item], job->normals[item]);
    app__packet p;
    app__packet_init(&p, L, f.o, 0.0f);
    for (int32_t bj = 0; bj < R; bj += (int32_t)BH)
        for (int32_t bi = 0; bi < R; bi += (int32_t)BW) {
            int any = 0;
            for (uint32_t l = 0; l < L; l++) {
                int32_t i = bi + (int32_t)(l % BW), j = bj + (int32_t)(l / BW);
                int32_t a = 2 * i + 1 - R, b = 2 * j + 1 - R;
                int inside = i < R && j < R && a * a + b * b <= R * R; /* rs_para_texel_inside */
                p.valid[l] = inside ? -1 : 0;
                any |= inside;
                /* the texel centre's direction, as rs_para_render_traced
                 * computes it: (2u, 2v, 1 - s) / (1 + s) in the VPL frame */
                float u = (float)a / (float)R, v = (float)b / (float)R, s = u * u + v * v;
                float dx = 2.0f * u, dy = 2.0f * v, dz = 1.0f - s, k = 1.0f / (1.0f + s);
                APP__F(&p, L, APP__DIR_X, l) = ((f.t.x * dx + f.b.x * dy) + f.n.x * dz) * k;
                APP__F(&p, L, APP__DIR_Y, l) = ((f.t.y * dx + f.b.y * dy) + f.n.y * dz) * k;
                APP__F(&p, L, APP__DIR_Z, l) = ((f.t.z * dx + f.b.z * dy) + f.n.z * dz) * k;
                APP__F(&p, L, APP__TFAR, l) = INFINITY;
                APP__U(&p, L, APP__GEOM, l) = RTC_INVALID_GEOMETRY_ID;
            }
            if (any) app__trace(job->e, &p, L);
            for (uint32_t ly = 0; ly < BH; ly++) {
                if (bj + (int32_t)ly >= R) break;
                for (uint32_t lx = 0; lx < BW; lx++) {
                    if (bi + (int32_t)lx >= R) continue;
                    uint32_t l = ly * BW + lx;
                    /* rs_paraboloid's quantisation: floor(t S), clamped */
                    float q = APP__F(&p, L, APP__TFAR, l) * job->scale;
                    uint16_t code = q < (float)RS_PARA_MAX_CODE ? (uint16_t)q : RS_PARA_MAX_CODE;
                    if (APP__U(&p, L, APP__GEOM, l) == RTC_INVALID_GEOMETRY_ID) code = RS_PARA_EMPTY;
                    if (!p.valid[l]) code = RS_PARA_OUTSIDE;
                    out[(size_t)(bj + (int32_t)ly) * R + bi + (int32_t)lx] = code;
                }
            }
        }
}

static void app__para_map(void *ctx, uint32_t item, uint32_t worker)
{
    (void)worker;
    const app__para_job *job = ctx;
    switch (job->e->lanes) {
    case 16: app__para_map_n(job, item, 16); break;
    case 8: app__para_map_n(job, item, 8); break;
    default: app__para_map_n(job, item, 4); break;
    }
}

void app_embree_paraboloid(uint16_t *atlas, const app_embree *e, pf_jobs *jobs, uint32_t resolution,
                           const pf_vec3 *positions, const pf_vec3 *normals, uint32_t count, float range)
{
    app__para_job job = {e, atlas, resolution, positions, normals, RS_PARA_CODES / range};
    pf_jobs_parallel_for(jobs, app__para_map, &job, count, 1);
}
