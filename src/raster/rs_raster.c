/* rs_raster: the triangle rasterizer (see rs_raster.h for the pipeline,
 * the precision argument and the depth convention).
 *
 * Who calls what: rs_render (one pass over jobs) = rs__cull_clusters
 * (parallel over clusters; a visible cluster marks the blocks of welded
 * positions it uses) -> rs__vertex_job (parallel over vertex chunks, only
 * the marked blocks) -> rs__setup_bin (parallel over fixed triangle chunks)
 * -> rs__raster_tile (parallel over 64x64 tiles). rs_render_serial runs the
 * same steps on the caller's thread.
 *
 * Fixed point and ranges. Screen positions are snapped to 1/256 pixel.
 * Vertices must lie within the guard band |x|, |y| <= 2^15 pixels of the
 * image centre (triangles reaching beyond are clipped against guard-band
 * planes in homogeneous space first), so snapped coordinates are below 2^24
 * in magnitude, edge-function coefficients below 2^25, and an edge function
 * at any pixel centre below 2^25 * 2^24 * 2 = 2^50: exact in int64. */
#include "rs_raster.h"

#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "rs_raster_kernels.h"
#include "simd.h" /* the baseline vocabulary (SSE2 on x86-64): tile bookkeeping outside the kernels */

#define RS_CLUSTER 256     /* triangles per culling cluster */
#define RS_CHUNK 2048      /* triangles per setup/binning job item */
#define RS_VCHUNK 8192     /* vertices per vertex-stage job item */
#define RS_VBLOCK 256      /* vertices per block the vertex stage transforms or skips */
/* The flags a scratch keeps for n welded positions: one per block (and one spare). */
#define RS_VBLOCKS(n) ((n) / RS_VBLOCK + 1)
#define RS_GUARD 32768.0f  /* guard band, pixels from the image centre */

/* ------------------------------------------------------------------ types */

/* rs__tri, the set-up triangle, is in rs_raster_kernels.h (the kernels read it). */

/* The alpha test's extra planes for a masked triangle: 1/w, b1/w, b2/w
 * (b = barycentrics of the scene triangle), so b1 = (b1/w) / (1/w) is
 * perspective-correct. */
typedef struct rs__tri_masked {
    float iw0, diwdx, diwdy, u0, dudx, dudy, v0, dvdx, dvdy;
} rs__tri_masked;

/* One setup chunk's output: triangles and their bins, sorted by tile.
 * Chunks are written by different threads, so each starts on its own cache
 * line (its counters change for every triangle: false sharing otherwise). */
typedef struct rs__chunk {
    _Alignas(64) rs__tri *tris; /* 64-byte aligned */
    uint32_t tri_count, tri_cap;
    rs__tri_masked *masked;
    uint32_t masked_count, masked_cap;
    uint64_t *entries; /* unsorted bin entries: tile << 32 | triangle index in this chunk */
    uint32_t entry_count, entry_cap;
    uint32_t *sorted;     /* tri indices grouped by tile, triangle order kept */
    uint32_t *tile_start; /* tile_count + 1 */
    uint32_t sorted_cap, tile_cap;
    uint32_t failed; /* an allocation failed in this pass: the chunk is skipped */
    rs_stats stats;
} rs__chunk;

/* A vertex after the vertex stage: clip-space position, and for a vertex
 * inside the frustum (rs__inside) its snapped screen position, which every
 * triangle using it would otherwise recompute (a division and two
 * conversions; the conference room's triangles share each vertex ~6 times).
 * X = RS__NO_SNAP outside the frustum. */
typedef struct rs__vtx {
    float x, y, z, w;
    int32_t X, Y;
    float zs, iw; /* z / w and 1 / w, inside the frustum */
    float rx, ry; /* the unsnapped screen position minus the snapped one, pixels (rs__snap_rest) */
} rs__vtx;
#define RS__NO_SNAP INT32_MIN
/* a bin entry's flag (rs__chunk.sorted): the triangle is alpha-masked */
#define RS__ENTRY_MASKED 0x80000000u
_Static_assert((uint64_t)RS_CHUNK * 10 < RS__ENTRY_MASKED, "a chunk's records (clipping makes at most 10 of a triangle) "
                                                          "are indexed below the flag");

typedef struct rs__cluster {
    pf_vec3 lo, hi;
} rs__cluster;

/* A tile's triangles in drawing order, handed to the kernel in one call. */
typedef struct rs__list {
    const rs__tri **tris;
    const void **masked;
    uint32_t cap;
} rs__list;

struct rs_scratch {
    uint32_t chunk_count;
    rs__vtx *vtx; /* vtx_cap + 1: clip position and, inside the frustum, the snapped screen position */
    uint32_t vtx_cap;
    uint8_t *cluster_visible;
    /* per block of RS_VBLOCK welded positions: 1 when a visible cluster uses
     * one of them (only those blocks are transformed); vblock_cap blocks */
    uint8_t *vblock_need;
    uint32_t vblock_cap;
    rs__chunk *chunks; /* chunk_count */
    rs__list *lists; /* per worker: a tile's triangles for the kernel, grown with the largest tile */
    uint32_t list_count;
    uint32_t *tile_list, tile_list_cap; /* rs_render_tiles' tiles */
    /* allocation failures since rs_scratch_status last read them: failed
     * chunks and passes counted after each pass, tiles by the job items
     * (relaxed atomics) */
    uint32_t failed_chunks, failed_tiles, failed_pass;
};

struct rs_context {
    const pf_scene *scene;
    pf_jobs *jobs;
    rs_simd simd;
    /* Positions welded by exact value: scenes with flat normals store three
     * vertices per triangle, but the vertex stage only needs each distinct
     * position once (the conference room: 994K vertices, 194K positions). */
    uint32_t weld_count;
    pf_vec3 *weld_pos;
    uint32_t *weld_idx;  /* 3 per triangle, into weld_pos */
    uint32_t *weld_of;   /* per scene vertex: its welded position (rs_context_update) */
    uint32_t *weld_refs; /* per welded position: how many scene vertices share it */
    uint32_t *weld_seen; /* rs_context_update's scratch, per welded position (zero between calls) */
    uint32_t cluster_count, chunk_count;
    rs__cluster *clusters;
    /* the blocks of RS_VBLOCK welded positions cluster c's triangles use:
     * cluster_blocks[cluster_block_start[c] .. cluster_block_start[c + 1]) */
    uint32_t *cluster_block_start, *cluster_blocks;
    rs_scratch *scratch; /* for rs_render */
    rs_resolve_tri *resolve_table; /* the G-buffer resolve's per-triangle constants */
    uint8_t *tri_masked;           /* per triangle: 1 if its material is alpha-masked (alphaMode MASK) */
};

/* The state of one pass, shared by the job items. */
typedef struct rs__pass_state {
    const rs_context *ctx;
    rs_scratch *s;
    const rs_pass *pass;
    rs_target *t;
    uint32_t tiles_x, tiles_y;
    /* the tiles the pass draws: [rtx0, rtx1) x [rty0, rty1) (all of them but
     * for rs_render_tiles: its tiles' bounds), and their pixels [rpx0, rpx1] x [rpy0, rpy1] */
    uint32_t rtx0, rty0, rtx1, rty1;
    int64_t rpx0, rpy0, rpx1, rpy1;
    /* rs_render_tiles: the tiles drawn (bit ty * tiles_x + tx), NULL for a
     * whole rectangle; and their indices in row order, one per tile job */
    const uint64_t *tile_mask;
    const uint32_t *tile_list;
    uint32_t tile_jobs; /* tiles drawn */
    float gx, gy; /* guard band in NDC units */
    rs_simd simd;
} rs__pass_state;

/* ---------------------------------------------------------------- matrices */

rs_simd rs_simd_for_isa(pf_isa isa)
{
    if (isa == PF_ISA_AVX512) return RS_SIMD_AVX512;
    if (isa == PF_ISA_AVX2) return RS_SIMD_AVX2;
    return RS_SIMD_SCALAR;
}

const char *rs_simd_name(rs_simd simd)
{
    static const char *const names[] = {"scalar", "avx2", "avx512"};
    return (unsigned)simd < 3 ? names[simd] : "?";
}

/* View matrix rows (right, up, -forward) times a projection; written out so
 * the float operations are explicit. */
static rs_mat4 rs__view_proj(pf_vec3 eye, pf_vec3 f, pf_vec3 up_hint, float sx, float sy, float zr_a, float zr_b,
                             int perspective)
{
    f = pf_v3_normalize(f);
    pf_vec3 r = pf_v3_normalize(pf_v3_cross(f, up_hint));
    if (r.x == 0.0f && r.y == 0.0f && r.z == 0.0f) {
        pf_vec3 t, b;
        pf_v3_basis(f, &t, &b);
        r = t;
    }
    pf_vec3 u = pf_v3_cross(r, f);
    /* view space: vx = r.(p-e), vy = u.(p-e), vd = f.(p-e) (depth, > 0 in front) */
    float tr = -pf_v3_dot(r, eye), tu = -pf_v3_dot(u, eye), tf = -pf_v3_dot(f, eye);
    rs_mat4 m;
    memset(&m, 0, sizeof m);
    /* row 0: sx * vx; row 1: sy * vy */
    m.m[0] = sx * r.x, m.m[4] = sx * r.y, m.m[8] = sx * r.z, m.m[12] = sx * tr;
    m.m[1] = sy * u.x, m.m[5] = sy * u.y, m.m[9] = sy * u.z, m.m[13] = sy * tu;
    if (perspective) {
        /* z_clip = znear (constant), w_clip = vd: zs = znear / vd */
        m.m[14] = zr_a;
        m.m[3] = f.x, m.m[7] = f.y, m.m[11] = f.z, m.m[15] = tf;
    } else {
        /* z_clip = 1 - (vd - znear) / (zfar - znear) = zr_a * vd + zr_b, w = 1 */
        m.m[2] = zr_a * f.x, m.m[6] = zr_a * f.y, m.m[10] = zr_a * f.z, m.m[14] = zr_a * tf + zr_b;
        m.m[15] = 1.0f;
    }
    return m;
}

rs_mat4 rs_mat4_perspective(pf_vec3 eye, pf_vec3 forward, pf_vec3 up, float yfov, float aspect, float znear)
{
    float sy = 1.0f / tanf(0.5f * yfov);
    return rs__view_proj(eye, forward, up, sy / aspect, sy, znear, 0.0f, 1);
}

rs_mat4 rs_mat4_ortho(pf_vec3 eye, pf_vec3 forward, pf_vec3 up, float half_w, float half_h, float znear, float zfar)
{
    float inv = 1.0f / (zfar - znear);
    return rs__view_proj(eye, forward, up, 1.0f / half_w, 1.0f / half_h, -inv, 1.0f + znear * inv, 0);
}

rs_mat4 rs_mat4_camera(const pf_camera *cam, uint32_t width, uint32_t height)
{
    return rs_mat4_perspective(cam->eye, cam->forward, cam->up, cam->yfov, (float)width / (float)height,
                               cam->znear > 0.0f ? cam->znear : 0.01f);
}

void rs_mat4_transform(const rs_mat4 *m, pf_vec3 p, float c[4])
{
    for (int r = 0; r < 4; r++) c[r] = m->m[r] * p.x + m->m[4 + r] * p.y + m->m[8 + r] * p.z + m->m[12 + r];
}

/* ---------------------------------------------------------------- context */

static void rs__chunk_free(rs__chunk *c)
{
    free(c->tris);
    free(c->masked);
    free(c->entries);
    free(c->sorted);
    free(c->tile_start);
}

rs_scratch *rs_scratch_create(const rs_context *ctx)
{
    rs_scratch *s = calloc(1, sizeof *s);
    if (!s) return NULL;
    s->vtx = malloc(sizeof(rs__vtx) * ((size_t)ctx->weld_count + 1));
    s->vtx_cap = ctx->weld_count;
    s->cluster_visible = calloc(ctx->cluster_count ? ctx->cluster_count : 1, 1);
    s->vblock_cap = RS_VBLOCKS(ctx->weld_count);
    s->vblock_need = calloc(s->vblock_cap, 1);
    s->chunk_count = ctx->chunk_count;
    size_t chunk_bytes = sizeof(rs__chunk) * (ctx->chunk_count ? ctx->chunk_count : 1);
    s->chunks = aligned_alloc(64, (chunk_bytes + 63) / 64 * 64);
    if (s->chunks) memset(s->chunks, 0, chunk_bytes);
    if (!s->vtx || !s->cluster_visible || !s->vblock_need || !s->chunks) {
        rs_scratch_destroy(s);
        return NULL;
    }
    return s;
}

void rs_scratch_destroy(rs_scratch *s)
{
    if (!s) return;
    free(s->vtx);
    free(s->cluster_visible);
    free(s->vblock_need);
    for (uint32_t w = 0; w < s->list_count; w++) free(s->lists[w].tris), free(s->lists[w].masked);
    free(s->lists);
    free(s->tile_list);
    if (s->chunks)
        for (uint32_t c = 0; c < s->chunk_count; c++) rs__chunk_free(&s->chunks[c]);
    free(s->chunks);
    free(s);
}

/* Welds the scene's positions by exact bit pattern with an open-addressing
 * hash; ids are assigned in order of first use, so the result is fixed. */
static int rs__weld(rs_context *ctx)
{
    const pf_scene *sc = ctx->scene;
    uint32_t n = sc->vertex_count, cap = 16;
    while (cap < 2 * n) cap *= 2;
    uint32_t *table = malloc(sizeof(uint32_t) * cap), *remap = ctx->weld_of;
    if (!remap) remap = ctx->weld_of = malloc(sizeof(uint32_t) * (n ? n : 1));
    if (!ctx->weld_pos) ctx->weld_pos = malloc(sizeof(pf_vec3) * ((size_t)n + 1));
    if (!ctx->weld_idx) ctx->weld_idx = malloc(sizeof(uint32_t) * 3 * ((size_t)sc->tri_count + 1));
    if (!ctx->weld_refs) ctx->weld_refs = calloc((size_t)n + 1, sizeof(uint32_t));
    if (!ctx->weld_seen) ctx->weld_seen = calloc((size_t)n + 1, sizeof(uint32_t));
    if (!table || !remap || !ctx->weld_pos || !ctx->weld_idx || !ctx->weld_refs || !ctx->weld_seen) {
        free(table);
        return 0;
    }
    memset(table, 0xff, sizeof(uint32_t) * cap);
    uint32_t count = 0;
    for (uint32_t v = 0; v < n; v++) {
        uint32_t b[3];
        memcpy(b, &sc->positions[v], sizeof b);
        uint32_t h = (b[0] * 0x9e3779b1u) ^ (b[1] * 0x85ebca77u) ^ (b[2] * 0xc2b2ae3du);
        h ^= h >> 15;
        for (uint32_t slot = h & (cap - 1);; slot = (slot + 1) & (cap - 1)) {
            uint32_t id = table[slot];
            if (id == 0xffffffffu) {
                table[slot] = count;
                ctx->weld_pos[count] = sc->positions[v];
                remap[v] = count++;
                break;
            }
            if (memcmp(&ctx->weld_pos[id], &sc->positions[v], sizeof(pf_vec3)) == 0) {
                remap[v] = id;
                break;
            }
        }
    }
    for (size_t i = 0; i < 3 * (size_t)sc->tri_count; i++) ctx->weld_idx[i] = remap[sc->indices[i]];
    ctx->weld_count = count;
    memset(ctx->weld_refs, 0, sizeof(uint32_t) * ((size_t)n + 1));
    for (uint32_t v = 0; v < n; v++) ctx->weld_refs[remap[v]]++;
    free(table);
    return 1;
}

/* The box of culling cluster c from the scene's positions. */
static void rs__cluster_box(rs_context *ctx, uint32_t c)
{
    const pf_scene *scene = ctx->scene;
    pf_vec3 lo = pf_v3(INFINITY, INFINITY, INFINITY), hi = pf_v3(-INFINITY, -INFINITY, -INFINITY);
    uint32_t t1 = (c + 1) * RS_CLUSTER < scene->tri_count ? (c + 1) * RS_CLUSTER : scene->tri_count;
    for (uint32_t t = c * RS_CLUSTER; t < t1; t++)
        for (int k = 0; k < 3; k++) {
            pf_vec3 p = scene->positions[scene->indices[3 * t + k]];
            lo = pf_v3_min(lo, p);
            hi = pf_v3_max(hi, p);
        }
    ctx->clusters[c].lo = lo;
    ctx->clusters[c].hi = hi;
}

/* Every cluster's list of vertex blocks, each once, in the order its
 * triangles first use them (made after each weld: the ids change only
 * then). 0 when out of memory. */
static int rs__cluster_blocks(rs_context *ctx)
{
    const uint32_t n = ctx->scene->tri_count, nb = RS_VBLOCKS(ctx->weld_count);
    uint32_t *start = realloc(ctx->cluster_block_start, sizeof(uint32_t) * ((size_t)ctx->cluster_count + 1));
    uint8_t *seen = calloc(nb, 1);
    if (start) ctx->cluster_block_start = start;
    if (!start || !seen) {
        free(seen);
        return 0;
    }
    uint32_t *list = NULL, count = 0, cap = 0;
    start[0] = 0;
    for (uint32_t c = 0; c < ctx->cluster_count; c++) {
        uint32_t t1 = (c + 1) * RS_CLUSTER < n ? (c + 1) * RS_CLUSTER : n, first = count;
        for (size_t i = (size_t)c * RS_CLUSTER * 3; i < (size_t)t1 * 3; i++) {
            uint32_t b = ctx->weld_idx[i] / RS_VBLOCK;
            if (seen[b]) continue;
            seen[b] = 1;
            if (count == cap) {
                uint32_t nc = cap ? 2 * cap : 1024;
                uint32_t *l = realloc(list, sizeof(uint32_t) * nc);
                if (!l) {
                    free(list), free(seen);
                    return 0;
                }
                list = l, cap = nc;
            }
            list[count++] = b;
        }
        for (uint32_t k = first; k < count; k++) seen[list[k]] = 0;
        start[c + 1] = count;
    }
    free(seen);
    free(ctx->cluster_blocks);
    ctx->cluster_blocks = list ? list : malloc(sizeof(uint32_t));
    return ctx->cluster_blocks != NULL;
}

pf_result rs_context_create(rs_context **out, const pf_scene *scene, pf_jobs *jobs, rs_simd simd, pf_error *err)
{
    *out = NULL;
    rs_context *ctx = calloc(1, sizeof *ctx);
    if (!ctx) return pf_error_set(err, PF_ERR_OUT_OF_MEMORY, "out of memory for the rasterizer");
    ctx->scene = scene;
    ctx->jobs = jobs;
    ctx->simd = simd;
    ctx->cluster_count = (scene->tri_count + RS_CLUSTER - 1) / RS_CLUSTER;
    ctx->chunk_count = (scene->tri_count + RS_CHUNK - 1) / RS_CHUNK;
    ctx->clusters = calloc(ctx->cluster_count ? ctx->cluster_count : 1, sizeof *ctx->clusters);
    if (!ctx->clusters || !rs__weld(ctx)) goto oom;
    for (uint32_t c = 0; c < ctx->cluster_count; c++) rs__cluster_box(ctx, c);
    if (!rs__cluster_blocks(ctx)) goto oom;
    ctx->scratch = rs_scratch_create(ctx);
    ctx->resolve_table = rs_resolve_table_create(scene);
    ctx->tri_masked = malloc(scene->tri_count ? scene->tri_count : 1);
    if (!ctx->scratch || !ctx->resolve_table || !ctx->tri_masked) goto oom;
    for (uint32_t t = 0; t < scene->tri_count; t++)
        ctx->tri_masked[t] = scene->materials[scene->tri_material[t]].alpha_mode == PF_ALPHA_MASK;
    *out = ctx;
    return PF_OK;
oom:
    rs_context_destroy(ctx);
    return pf_error_set(err, PF_ERR_OUT_OF_MEMORY, "out of memory for the rasterizer");
}

void rs_context_destroy(rs_context *ctx)
{
    if (!ctx) return;
    rs_scratch_destroy(ctx->scratch);
    free(ctx->clusters);
    free(ctx->cluster_block_start);
    free(ctx->cluster_blocks);
    free(ctx->weld_pos);
    free(ctx->weld_idx);
    free(ctx->weld_of);
    free(ctx->weld_refs);
    free(ctx->weld_seen);
    rs_resolve_table_destroy(ctx->resolve_table);
    free(ctx->tri_masked);
    free(ctx);
}

pf_result rs_context_update(rs_context *ctx, const pf_anim_moved *moved, uint32_t count, pf_error *err)
{
    const pf_scene *sc = ctx->scene;
    for (uint32_t m = 0; m < count; m++) {
        const pf_anim_moved *r = &moved[m];
        if ((uint64_t)r->vertex_first + r->vertex_count > sc->vertex_count ||
            (uint64_t)r->tri_first + r->tri_count > sc->tri_count)
            return pf_error_set(err, PF_ERR_ARGUMENT, "rasterizer update: range %u (vertices %u+%u, triangles %u+%u) "
                                "is outside the scene", m, r->vertex_first, r->vertex_count, r->tri_first, r->tri_count);
    }
    /* 1. welded positions: a moved vertex's welded position takes its new
     * place unless that position is shared with a vertex that stayed or
     * moved elsewhere; then the scene is welded again */
    int reweld = 0;
    for (uint32_t m = 0; m < count && !reweld; m++) {
        if (!moved[m].moved) continue;
        for (uint32_t v = moved[m].vertex_first; v < moved[m].vertex_first + moved[m].vertex_count; v++) {
            uint32_t id = ctx->weld_of[v];
            if (ctx->weld_seen[id]++ == 0) ctx->weld_pos[id] = sc->positions[v];
            else if (memcmp(&ctx->weld_pos[id], &sc->positions[v], sizeof(pf_vec3)) != 0) reweld = 1;
        }
    }
    for (uint32_t m = 0; m < count; m++) {
        if (!moved[m].moved) continue;
        for (uint32_t v = moved[m].vertex_first; v < moved[m].vertex_first + moved[m].vertex_count; v++) {
            uint32_t id = ctx->weld_of[v];
            if (ctx->weld_seen[id] && ctx->weld_seen[id] != ctx->weld_refs[id]) reweld = 1;
            ctx->weld_seen[id] = 0;
        }
    }
    if (reweld) {
        uint32_t before = ctx->weld_count;
        if (!rs__weld(ctx)) return pf_error_set(err, PF_ERR_OUT_OF_MEMORY, "out of memory welding moved vertices");
        if (!rs__cluster_blocks(ctx))
            return pf_error_set(err, PF_ERR_OUT_OF_MEMORY, "out of memory for the rasterizer's cluster lists");
        if (ctx->weld_count > before) { /* a vertex split off: the scratch's vertex records grow */
            rs__vtx *v = realloc(ctx->scratch->vtx, sizeof(rs__vtx) * ((size_t)ctx->weld_count + 1));
            if (!v) return pf_error_set(err, PF_ERR_OUT_OF_MEMORY, "out of memory for the rasterizer's vertices");
            ctx->scratch->vtx = v;
            uint32_t blocks = RS_VBLOCKS(ctx->weld_count);
            if (blocks > ctx->scratch->vblock_cap) {
                uint8_t *b = realloc(ctx->scratch->vblock_need, blocks);
                if (!b) return pf_error_set(err, PF_ERR_OUT_OF_MEMORY, "out of memory for the rasterizer's vertices");
                ctx->scratch->vblock_need = b;
                ctx->scratch->vblock_cap = blocks;
            }
        }
        ctx->scratch->vtx_cap = ctx->weld_count;
    }
    /* 2. the culling clusters' boxes and 3. the resolve's table entries of
     * the moved triangles */
    for (uint32_t m = 0; m < count; m++) {
        const pf_anim_moved *r = &moved[m];
        if (!r->moved || r->tri_count == 0) continue;
        for (uint32_t c = r->tri_first / RS_CLUSTER; c <= (r->tri_first + r->tri_count - 1) / RS_CLUSTER; c++)
            rs__cluster_box(ctx, c);
        rs_resolve_table_update(ctx->resolve_table, sc, r->tri_first, r->tri_count);
    }
    return PF_OK;
}

rs_simd rs_context_simd(const rs_context *ctx) { return ctx->simd; }
const rs_resolve_tri *rs_context_resolve_table(const rs_context *ctx) { return ctx->resolve_table; }
void rs_context_set_simd(rs_context *ctx, rs_simd simd) { ctx->simd = simd; }

/* ------------------------------------------------------- 1. vertex stage */

/* floorf without the libm call: exact for |x| < 2^62 (the guard band keeps
 * snapped coordinates below 2^24). */
static int64_t rs__floor64(float x)
{
    int64_t i = (int64_t)x;
    return i - ((float)i > x);
}

/* -w <= x, y <= w and 0 <= z <= w with w finite: then w >= 0, so
 * gx w - x >= w - x >= 0 and the like hold in floating point too (gx, gy >= 1
 * as RS_MAX_SIZE <= 2 RS_GUARD; rounding is monotonic): rs__clip_mask is 0.
 * False for NaN. */
static int rs__inside(float x, float y, float z, float w)
{
    /* w >= FLT_MIN (not just >= 0): a vertex at the eye (x = y = z = w = 0)
     * or with a denormal w (0 under DAZ) would pass the tests above, and 1/w
     * = inf would make its snapped position NaN, whose conversion to an
     * integer is undefined. Such vertices take the clipper's path. */
    return x >= -w && x <= w && y >= -w && y <= w && z >= 0.0f && z <= w && w >= FLT_MIN && w < INFINITY;
}

/* The snapped screen position (1/RS_SUB pixel, y down) of a clip-space
 * vertex on a W x H target. */
static void rs__snap(float x, float y, float w, float W, float H, int64_t *X, int64_t *Y)
{
    float iw = 1.0f / w;
    float sx = (x * iw * 0.5f + 0.5f) * W, sy = (0.5f - y * iw * 0.5f) * H;
    *X = rs__floor64(sx * (float)RS_SUB + 0.5f);
    *Y = rs__floor64(sy * (float)RS_SUB + 0.5f);
}

/* What snapping took off a vertex: its exact screen position (in double,
 * pixels) minus the snapped one, as floats (below 1/512 pixel, so float
 * keeps it to 2^-33 pixel). The depth plane goes through the unsnapped
 * positions: a triangle seen at a grazing angle whose clipped vertices lie
 * far out in the guard band would otherwise tilt by the snapping error. */
static void rs__snap_rest(float x, float y, float w, float W, float H, int64_t X, int64_t Y, float *rx, float *ry)
{
    double dx = ((double)x / w * 0.5 + 0.5) * W, dy = (0.5 - (double)y / w * 0.5) * H;
    *rx = (float)(dx - (double)X * (1.0 / RS_SUB));
    *ry = (float)(dy - (double)Y * (1.0 / RS_SUB));
}

/* Transforms vertices [v0, v1) to clip space (-ffp-contract=off: each
 * product and sum rounded on its own) and snaps those inside the frustum
 * with the very operations rs__setup_tri would use, so the bits are the
 * same whichever of the two snaps a vertex. */
static void rs__transform(const rs__pass_state *st, const pf_vec3 *pos, rs__vtx *vtx, uint32_t v0, uint32_t v1)
{
    const float *M = st->pass->view_proj.m;
    float W = (float)st->t->width, H = (float)st->t->height;
    for (uint32_t v = v0; v < v1; v++) {
        float x = pos[v].x, y = pos[v].y, z = pos[v].z;
        rs__vtx *c = &vtx[v];
        c->x = M[0] * x + M[4] * y + M[8] * z + M[12];
        c->y = M[1] * x + M[5] * y + M[9] * z + M[13];
        c->z = M[2] * x + M[6] * y + M[10] * z + M[14];
        c->w = M[3] * x + M[7] * y + M[11] * z + M[15];
        c->X = c->Y = RS__NO_SNAP;
        c->zs = c->iw = c->rx = c->ry = 0.0f;
        if (rs__inside(c->x, c->y, c->z, c->w)) {
            int64_t X, Y;
            rs__snap(c->x, c->y, c->w, W, H, &X, &Y); /* |X|, |Y| < 2^23 inside the frustum */
            c->X = (int32_t)X, c->Y = (int32_t)Y;
            c->iw = 1.0f / c->w;
            c->zs = c->z * c->iw;
            rs__snap_rest(c->x, c->y, c->w, W, H, X, Y, &c->rx, &c->ry);
        }
    }
}

/* rs__transform of the positions in [v0, v1) that lie in blocks a visible
 * cluster uses (marked by the cluster stage; the setup reads no other
 * vertex record), runs of needed blocks at a time. */
static void rs__transform_needed(const rs__pass_state *st, uint32_t v0, uint32_t v1)
{
    const uint8_t *need = st->s->vblock_need;
    for (uint32_t v = v0; v < v1;) {
        uint32_t b = v / RS_VBLOCK;
        if (!__atomic_load_n(&need[b], __ATOMIC_RELAXED)) {
            v = (b + 1) * RS_VBLOCK;
            continue;
        }
        uint32_t e = v;
        while (e < v1 && __atomic_load_n(&need[e / RS_VBLOCK], __ATOMIC_RELAXED)) e = (e / RS_VBLOCK + 1) * RS_VBLOCK;
        e = e < v1 ? e : v1;
        rs__transform(st, st->ctx->weld_pos, st->s->vtx, v, e);
        v = e;
    }
}

static void rs__vertex_job(void *p, uint32_t item, uint32_t worker)
{
    (void)worker;
    rs__pass_state *st = p;
    uint32_t n = st->ctx->weld_count;
    uint32_t v0 = item * RS_VCHUNK, v1 = v0 + RS_VCHUNK < n ? v0 + RS_VCHUNK : n;
    rs__transform_needed(st, v0, v1);
}

int rs_box_rect(const rs_mat4 *vp, uint32_t width, uint32_t height, pf_vec3 lo, pf_vec3 hi, uint32_t r[4])
{
    unsigned all = 63;
    int behind = 0;
    float x0 = INFINITY, y0 = INFINITY, x1 = -INFINITY, y1 = -INFINITY, W = (float)width, H = (float)height;
    for (int k = 0; k < 8; k++) {
        pf_vec3 p = pf_v3(k & 1 ? hi.x : lo.x, k & 2 ? hi.y : lo.y, k & 4 ? hi.z : lo.z);
        float q[4];
        rs_mat4_transform(vp, p, q);
        all &= (unsigned)(q[0] < -q[3]) | (unsigned)(q[0] > q[3]) << 1 | (unsigned)(q[1] < -q[3]) << 2 |
               (unsigned)(q[1] > q[3]) << 3 | (unsigned)(q[2] < 0.0f) << 4 | (unsigned)(q[2] > q[3]) << 5;
        if (!(q[3] > 0.0f)) {
            behind = 1;
            continue;
        }
        float sx = (q[0] / q[3] * 0.5f + 0.5f) * W, sy = (0.5f - q[1] / q[3] * 0.5f) * H;
        x0 = fminf(x0, sx), x1 = fmaxf(x1, sx), y0 = fminf(y0, sy), y1 = fmaxf(y1, sy);
    }
    if (all) return 0;
    if (behind || !(x1 - x0 < 4.0f * W) || !(y1 - y0 < 4.0f * H)) { /* unbounded, huge or NaN */
        r[0] = r[1] = 0, r[2] = width, r[3] = height;
        return 1;
    }
    x0 = fmaxf(x0 - 1.0f, 0.0f), y0 = fmaxf(y0 - 1.0f, 0.0f);
    x1 = fminf(x1 + 2.0f, W), y1 = fminf(y1 + 2.0f, H);
    if (!(x0 < x1 && y0 < y1)) return 0;
    r[0] = (uint32_t)x0, r[1] = (uint32_t)y0, r[2] = (uint32_t)x1, r[3] = (uint32_t)y1;
    return 1;
}

/* Whether the pixel box [px0, px1] x [py0, py1] (inside the pass's tile
 * rectangle's bounds, clamped to the target) meets a tile of the pass's
 * mask (rs_render_tiles). */
static int rs__mask_meets(const rs__pass_state *st, int64_t px0, int64_t py0, int64_t px1, int64_t py1)
{
    int64_t tx0 = px0 / RS_TILE, tx1 = px1 / RS_TILE, ty0 = py0 / RS_TILE, ty1 = py1 / RS_TILE;
    tx0 = tx0 > st->rtx0 ? tx0 : st->rtx0, tx1 = tx1 < st->rtx1 - 1 ? tx1 : st->rtx1 - 1;
    ty0 = ty0 > st->rty0 ? ty0 : st->rty0, ty1 = ty1 < st->rty1 - 1 ? ty1 : st->rty1 - 1;
    for (int64_t ty = ty0; ty <= ty1; ty++)
        for (int64_t tx = tx0; tx <= tx1; tx++) {
            uint64_t tile = (uint64_t)ty * st->tiles_x + (uint64_t)tx;
            if (rs_tile_bit(st->tile_mask, tile)) return 1;
        }
    return 0;
}

/* ------------------------------------------------------- 2. cluster culling */

/* A cluster is culled when all 8 corners of its box lie outside one clip
 * plane (x < -w, x > w, y < -w, y > w, z < 0, z > w), or its projected box
 * (rs_box_rect) misses the target or rs_render_tiles' tiles: conservative. */
static void rs__cull_clusters(rs__pass_state *st, uint32_t c0, uint32_t c1)
{
    const rs_context *ctx = st->ctx;
    for (uint32_t c = c0; c < c1; c++) {
        const rs__cluster *cl = &ctx->clusters[c];
        /* in front of no clip plane's far side, and for rs_render_tiles
         * meeting one of the pass's tiles */
        uint32_t r[4];
        int visible = rs_box_rect(&st->pass->view_proj, st->t->width, st->t->height, cl->lo, cl->hi, r) &&
                      (!st->tile_mask || rs__mask_meets(st, r[0], r[1], (int64_t)r[2] - 1, (int64_t)r[3] - 1));
        st->s->cluster_visible[c] = (uint8_t)visible;
        if (!visible) continue;
        /* its positions' blocks are needed (relaxed atomics: clusters on
         * other threads may mark the same block; the set marked is fixed) */
        for (uint32_t k = ctx->cluster_block_start[c]; k < ctx->cluster_block_start[c + 1]; k++) {
            uint8_t *b = &st->s->vblock_need[ctx->cluster_blocks[k]];
            if (!__atomic_load_n(b, __ATOMIC_RELAXED)) __atomic_store_n(b, 1, __ATOMIC_RELAXED);
        }
    }
}

/* ------------------------------------------------------- 3. setup + binning */

typedef struct rs__cv {
    float x, y, z, w;
    float u, v; /* barycentrics of the scene triangle, carried through clipping */
} rs__cv;

/* Signed distance to clip plane k (inside >= 0): 0 near (w - z), 1 far (z),
 * 2..5 guard band (gx w - x, gx w + x, gy w - y, gy w + y). */
static float rs__plane(const rs__pass_state *st, int k, rs__cv v)
{
    switch (k) {
    case 0: return v.w - v.z;
    case 1: return v.z;
    case 2: return st->gx * v.w - v.x;
    case 3: return st->gx * v.w + v.x;
    case 4: return st->gy * v.w - v.y;
    default: return st->gy * v.w + v.y;
    }
}

/* Sutherland-Hodgman against the planes in `mask`; returns the vertex count
 * (0..9) of the clipped convex polygon. Intersections are computed from the
 * inside vertex towards the outside one, so a shared edge is cut at the same
 * point from both of its triangles (no cracks). */
static int rs__clip_polygon(const rs__pass_state *st, unsigned mask, rs__cv *poly, int n)
{
    rs__cv tmp[12];
    for (int k = 0; k < 6 && n > 0; k++) {
        if (!(mask & (1u << k))) continue;
        int m = 0;
        for (int i = 0; i < n; i++) {
            rs__cv a = poly[i], b = poly[(i + 1) % n];
            float da = rs__plane(st, k, a), db = rs__plane(st, k, b);
            if (da >= 0.0f) tmp[m++] = a;
            if ((da >= 0.0f) != (db >= 0.0f)) {
                /* from the inside vertex to the outside one */
                rs__cv in = da >= 0.0f ? a : b, outv = da >= 0.0f ? b : a;
                float di = da >= 0.0f ? da : db, dout = da >= 0.0f ? db : da;
                float t = di / (di - dout);
                rs__cv r = {in.x + (outv.x - in.x) * t, in.y + (outv.y - in.y) * t, in.z + (outv.z - in.z) * t,
                            in.w + (outv.w - in.w) * t, in.u + (outv.u - in.u) * t, in.v + (outv.v - in.v) * t};
                tmp[m++] = r;
            }
        }
        n = m;
        memcpy(poly, tmp, sizeof(rs__cv) * (size_t)n);
    }
    return n;
}

static int rs__grow(void **p, uint32_t *cap, uint32_t need, size_t elem)
{
    if (need <= *cap) return 1;
    uint32_t nc = *cap ? *cap : 256;
    while (nc < need) nc *= 2;
    void *q = realloc(*p, (size_t)nc * elem);
    if (!q) return 0;
    *p = q;
    *cap = nc;
    return 1;
}

/* rs__grow for an array of 64-byte-aligned records (realloc keeps 16). */
static int rs__grow_aligned(void **p, uint32_t *cap, uint32_t need, size_t elem, uint32_t count)
{
    if (need <= *cap) return 1;
    uint32_t nc = *cap ? *cap : 256;
    while (nc < need) nc *= 2;
    void *q = aligned_alloc(64, ((size_t)nc * elem + 63) / 64 * 64);
    if (!q) return 0;
    if (count) memcpy(q, *p, (size_t)count * elem);
    free(*p);
    *p = q;
    *cap = nc;
    return 1;
}

/* A vertex ready for setup: its snapped screen position (1/RS_SUB pixel, y
 * down), zs = z / w, 1/w, and the barycentrics (u, v) of the scene
 * triangle it lies at (vertices 1 and 2 of an unclipped triangle: (1, 0),
 * (0, 1); the alpha test's planes interpolate them). */
typedef struct rs__sv {
    int64_t X, Y;
    float z, iw, u, v;
    float rx, ry; /* rs__snap_rest */
} rs__sv;

/* The snapped vertex of a clip-space vertex (clipped ones; the vertex stage
 * does the same for vertices inside the frustum). 0 for a vertex at the eye
 * (w = 0 passes the z >= 0 plane): every point of its triangle then lies on
 * a line through the eye with one of the other two, so the triangle projects
 * to a segment and covers nothing; 1/w = inf would snap to NaN (undefined
 * as an integer). */
static int rs__snap_cv(const rs__pass_state *st, const rs__cv *c, rs__sv *out)
{
    if (!(c->w >= FLT_MIN)) return 0;
    float W = (float)st->t->width, H = (float)st->t->height;
    rs__snap(c->x, c->y, c->w, W, H, &out->X, &out->Y);
    rs__snap_rest(c->x, c->y, c->w, W, H, out->X, out->Y, &out->rx, &out->ry);
    out->iw = 1.0f / c->w;
    out->z = c->z * out->iw;
    out->u = c->u, out->v = c->v;
    return 1;
}

/* The pixel box of a triangle whose snapped coordinates span [minx, maxx]
 * x [miny, maxy]: the pixels whose centre 256 x + 128 lies inside, clamped
 * to the target, in b = {px0, px1, py0, py1}. 0 when it holds no pixel
 * centre or lies outside rs_render_tiles' bounds (the triangle is culled). */
static inline int rs__pixel_box(const rs__pass_state *st, int64_t minx, int64_t maxx, int64_t miny, int64_t maxy,
                                int64_t b[4])
{
    const rs_target *t = st->t;
    int64_t px0 = (minx - RS_SUB / 2 + RS_SUB - 1) >> RS_SUBPIXEL_BITS, px1 = (maxx - RS_SUB / 2) >> RS_SUBPIXEL_BITS;
    int64_t py0 = (miny - RS_SUB / 2 + RS_SUB - 1) >> RS_SUBPIXEL_BITS, py1 = (maxy - RS_SUB / 2) >> RS_SUBPIXEL_BITS;
    if (px0 < 0) px0 = 0;
    if (py0 < 0) py0 = 0;
    if (px1 > (int64_t)t->width - 1) px1 = (int64_t)t->width - 1;
    if (py1 > (int64_t)t->height - 1) py1 = (int64_t)t->height - 1;
    b[0] = px0, b[1] = px1, b[2] = py0, b[3] = py1;
    return !(px0 > px1 || py0 > py1 || px1 < st->rpx0 || px0 > st->rpx1 || py1 < st->rpy0 || py0 > st->rpy1);
}

/* Sets up one screen triangle (snapped vertices) whose pixel box
 * (rs__pixel_box) holds a pixel centre, and bins it. */
static void rs__setup_boxed(rs__pass_state *st, rs__chunk *ch, const rs__sv sv[3], uint32_t prim, const int64_t b[4])
{
    const int64_t px0 = b[0], px1 = b[1], py0 = b[2], py1 = b[3];
    if (st->tile_mask && !rs__mask_meets(st, px0, py0, px1, py1)) {
        ch->stats.triangles_culled++; /* meets none of rs_render_tiles' tiles */
        return;
    }
    int64_t X[3] = {sv[0].X, sv[1].X, sv[2].X}, Y[3] = {sv[0].Y, sv[1].Y, sv[2].Y};
    int64_t area = (X[1] - X[0]) * (Y[2] - Y[0]) - (X[2] - X[0]) * (Y[1] - Y[0]);
    /* y points down on screen: counter-clockwise (front) triangles have area < 0 */
    if (area == 0 || (st->pass->cull == RS_CULL_BACK && area > 0) || (st->pass->cull == RS_CULL_FRONT && area < 0)) {
        ch->stats.triangles_culled++;
        return;
    }
    int o[3] = {0, 1, 2}; /* vertex order: the interior on the positive side of every edge */
    if (area < 0) {
        o[1] = 2, o[2] = 1;
        X[1] = sv[2].X, Y[1] = sv[2].Y, X[2] = sv[1].X, Y[2] = sv[1].Y;
    }
    if (!rs__grow_aligned((void **)&ch->tris, &ch->tri_cap, ch->tri_count + 1, sizeof(rs__tri), ch->tri_count)) {
        ch->failed = 1; /* out of memory: the chunk is dropped (rs_scratch_status) */
        return;
    }
    rs__tri *r = &ch->tris[ch->tri_count];
    for (int k = 0; k < 3; k++) {
        int a = k, b = (k + 1) % 3;
        /* E(p) = (Xb - Xa)(py - Ya) - (Yb - Ya)(px - Xa) = A px + B py + C */
        int64_t A = Y[a] - Y[b], B = X[b] - X[a];
        int64_t C = -A * X[a] - B * Y[a];
        /* top-left rule (y down, interior positive): a top edge is horizontal
         * going +x (A == 0, B > 0), a left edge goes up (A > 0). Pixels exactly
         * on other edges are excluded: test E - 1 >= 0 there. */
        int top_left = (A == 0 && B > 0) || A > 0;
        r->a[k] = (int32_t)A;
        r->b[k] = (int32_t)B;
        r->c[k] = C - (top_left ? 0 : 1);
    }
    r->x0 = (int32_t)px0, r->x1 = (int32_t)px1, r->y0 = (int32_t)py0, r->y1 = (int32_t)py1;
    r->flags = 0;
    rs__tri_classify(r);
    /* the depth plane through the unsnapped vertices (rs__snap_rest), in
     * pixel units, in double relative to vertex 0: the snapped differences
     * are exact, so clipped vertices far out in the guard band cost no
     * precision through cancellation */
    float Z[3] = {sv[o[0]].z, sv[o[1]].z, sv[o[2]].z};
    {
        double rx0 = sv[o[0]].rx, ry0 = sv[o[0]].ry;
        double dx1 = (double)(X[1] - X[0]) * (1.0 / RS_SUB) + ((double)sv[o[1]].rx - rx0);
        double dy1 = (double)(Y[1] - Y[0]) * (1.0 / RS_SUB) + ((double)sv[o[1]].ry - ry0);
        double dx2 = (double)(X[2] - X[0]) * (1.0 / RS_SUB) + ((double)sv[o[2]].rx - rx0);
        double dy2 = (double)(Y[2] - Y[0]) * (1.0 / RS_SUB) + ((double)sv[o[2]].ry - ry0);
        double d1 = (double)Z[1] - Z[0], d2 = (double)Z[2] - Z[0];
        double den = dx1 * dy2 - dx2 * dy1;
        double inv = den != 0.0 ? 1.0 / den : 0.0; /* the snapped area is nonzero; the exact one can vanish */
        r->dzdx_d = (d1 * dy2 - d2 * dy1) * inv;
        r->dzdy_d = (d2 * dx1 - d1 * dx2) * inv;
        r->zv = Z[0];
        r->xv = (double)X[0] * (1.0 / RS_SUB) + rx0;
        r->yv = (double)Y[0] * (1.0 / RS_SUB) + ry0;
    }
    r->masked = RS__NOT_MASKED;
    if (st->ctx->tri_masked[prim]) {
        if (!rs__grow((void **)&ch->masked, &ch->masked_cap, ch->masked_count + 1, sizeof(rs__tri_masked))) {
            ch->failed = 1;
            return;
        }
        rs__tri_masked *m = &ch->masked[ch->masked_count];
        r->masked = ch->masked_count++;
        /* a screen-linear quantity q: plane through the vertices, evaluated
         * as q0 + dqdx x + dqdy y at pixel centre (x + .5, y + .5) */
        float fx[3], fy[3], IW[3], U[3], V[3];
        for (int k = 0; k < 3; k++) {
            fx[k] = (float)X[k] * (1.0f / RS_SUB), fy[k] = (float)Y[k] * (1.0f / RS_SUB);
            IW[k] = sv[o[k]].iw, U[k] = sv[o[k]].u * IW[k], V[k] = sv[o[k]].v * IW[k];
        }
        float e1x = fx[1] - fx[0], e1y = fy[1] - fy[0], e2x = fx[2] - fx[0], e2y = fy[2] - fy[0];
        float inv_area = 1.0f / (e1x * e2y - e2x * e1y);
#define RS__PLANE(Q, q0, dqdx, dqdy)                                                                                   \
    do {                                                                                                           \
        float d1 = Q[1] - Q[0], d2 = Q[2] - Q[0];                                                                  \
        dqdx = (d1 * e2y - d2 * e1y) * inv_area;                                                                   \
        dqdy = (d2 * e1x - d1 * e2x) * inv_area;                                                                   \
        q0 = Q[0] + dqdx * (0.5f - fx[0]) + dqdy * (0.5f - fy[0]);                                                 \
    } while (0)
        RS__PLANE(IW, m->iw0, m->diwdx, m->diwdy);
        RS__PLANE(U, m->u0, m->dudx, m->dudy);
        RS__PLANE(V, m->v0, m->dvdx, m->dvdy);
#undef RS__PLANE
    }
    r->zmin = fminf(Z[0], fminf(Z[1], Z[2]));
    r->zmax = fmaxf(Z[0], fmaxf(Z[1], Z[2]));
    r->prim = prim;
    uint32_t ti = ch->tri_count++;
    ch->stats.triangles_binned++;
    /* binned into the tiles it meets that the pass draws (the box is kept
     * whole: the kernels' classification reads it) */
    uint32_t tx0 = (uint32_t)px0 / RS_TILE, tx1 = (uint32_t)px1 / RS_TILE;
    uint32_t ty0 = (uint32_t)py0 / RS_TILE, ty1 = (uint32_t)py1 / RS_TILE;
    tx0 = tx0 > st->rtx0 ? tx0 : st->rtx0, tx1 = tx1 < st->rtx1 - 1 ? tx1 : st->rtx1 - 1;
    ty0 = ty0 > st->rty0 ? ty0 : st->rty0, ty1 = ty1 < st->rty1 - 1 ? ty1 : st->rty1 - 1;
    uint32_t need = ch->entry_count + (tx1 - tx0 + 1) * (ty1 - ty0 + 1);
    if (!rs__grow((void **)&ch->entries, &ch->entry_cap, need, sizeof(uint64_t))) {
        ch->failed = 1;
        return;
    }
    /* the entry: the tile, the record's index and, in RS__ENTRY_MASKED,
     * whether it is alpha-masked (so gathering a tile's list reads no
     * record: the kernel's prefetch fetches it) */
    const uint32_t entry = ti | (r->masked == RS__NOT_MASKED ? 0u : RS__ENTRY_MASKED);
    for (uint32_t ty = ty0; ty <= ty1; ty++)
        for (uint32_t tx = tx0; tx <= tx1; tx++) {
            uint32_t tile = ty * st->tiles_x + tx;
            if (st->tile_mask && !rs_tile_bit(st->tile_mask, tile)) continue;
            ch->entries[ch->entry_count++] = (uint64_t)tile << 32 | entry;
        }
}

/* Sets up one screen triangle (snapped vertices) and bins it: the pixel
 * box first, since most triangles of a detailed scene cover no pixel
 * centre and are rejected there before anything else is computed. */
static void rs__setup_tri(rs__pass_state *st, rs__chunk *ch, const rs__sv sv[3], uint32_t prim)
{
    int64_t minx = sv[0].X, maxx = sv[0].X, miny = sv[0].Y, maxy = sv[0].Y, b[4];
    for (int k = 1; k < 3; k++) {
        minx = sv[k].X < minx ? sv[k].X : minx, maxx = sv[k].X > maxx ? sv[k].X : maxx;
        miny = sv[k].Y < miny ? sv[k].Y : miny, maxy = sv[k].Y > maxy ? sv[k].Y : maxy;
    }
    if (!rs__pixel_box(st, minx, maxx, miny, maxy, b)) {
        ch->stats.triangles_culled++; /* falls between pixel centres, off screen or outside rs_render_tiles' bounds */
        return;
    }
    rs__setup_boxed(st, ch, sv, prim, b);
}

/* A clip-space triangle inside the guard band (clipped or not): snapped
 * here, then set up. */
static void rs__setup_cv(rs__pass_state *st, rs__chunk *ch, const rs__cv v[3], uint32_t prim)
{
    rs__sv sv[3];
    for (int k = 0; k < 3; k++)
        if (!rs__snap_cv(st, &v[k], &sv[k])) {
            ch->stats.triangles_culled++;
            return;
        }
    rs__setup_tri(st, ch, sv, prim);
}

/* Frustum outcode (for trivial reject) and the planes a vertex violates
 * (near, far, guard band: what clipping must handle). */
static unsigned rs__outcode(rs__cv v) /* x<-w, x>w, y<-w, y>w, z<0, z>w */
{
    return (unsigned)(v.x < -v.w) | (unsigned)(v.x > v.w) << 1 | (unsigned)(v.y < -v.w) << 2 |
           (unsigned)(v.y > v.w) << 3 | (unsigned)(v.z < 0.0f) << 4 | (unsigned)(v.z > v.w) << 5;
}

static unsigned rs__clip_mask(const rs__pass_state *st, rs__cv v)
{
    unsigned m = 0;
    for (int k = 0; k < 6; k++)
        if (!(rs__plane(st, k, v) >= 0.0f)) m |= 1u << k;
    return m;
}

/* Setup and binning of one fixed chunk of triangles (scene order). */
static void rs__setup_bin(rs__pass_state *st, uint32_t chunk)
{
    const pf_scene *sc = st->ctx->scene;
    rs__chunk *ch = &st->s->chunks[chunk];
    ch->tri_count = 0;
    ch->masked_count = 0;
    ch->entry_count = 0;
    ch->failed = 0;
    memset(&ch->stats, 0, sizeof ch->stats);
    uint32_t t0 = chunk * RS_CHUNK, t1 = t0 + RS_CHUNK < sc->tri_count ? t0 + RS_CHUNK : sc->tri_count;
    const rs__vtx *vtx = st->s->vtx;
    _Static_assert(RS_CHUNK % RS_CLUSTER == 0, "a chunk is whole clusters");
    for (uint32_t t = t0; t < t1 && !ch->failed; t++) {
        if (t % RS_CLUSTER == 0 && !st->s->cluster_visible[t / RS_CLUSTER]) { /* a culled cluster: skipped whole */
            t += RS_CLUSTER - 1;
            continue;
        }
        ch->stats.triangles_in++;
        const uint32_t *idx = &st->ctx->weld_idx[3 * t];
        const rs__vtx *c0 = &vtx[idx[0]], *c1 = &vtx[idx[1]], *c2 = &vtx[idx[2]];
        /* vertices inside the frustum are inside every clip plane (the guard
         * band is wider than the frustum): no clipping, snapped already */
        if (c0->X != RS__NO_SNAP && c1->X != RS__NO_SNAP && c2->X != RS__NO_SNAP) {
            /* rs__setup_tri's pixel box straight from the vertex records,
             * before any copy: most triangles end here */
            int32_t x0 = c0->X, x1 = c1->X, x2 = c2->X, y0 = c0->Y, y1 = c1->Y, y2 = c2->Y;
            int32_t minx = x0 < x1 ? x0 : x1, maxx = x0 > x1 ? x0 : x1, miny = y0 < y1 ? y0 : y1,
                    maxy = y0 > y1 ? y0 : y1;
            minx = x2 < minx ? x2 : minx, maxx = x2 > maxx ? x2 : maxx;
            miny = y2 < miny ? y2 : miny, maxy = y2 > maxy ? y2 : maxy;
            int64_t b[4];
            if (!rs__pixel_box(st, minx, maxx, miny, maxy, b)) {
                ch->stats.triangles_culled++; /* as rs__setup_tri */
                continue;
            }
            rs__sv sv[3] = {{c0->X, c0->Y, c0->zs, c0->iw, 0.0f, 0.0f, c0->rx, c0->ry},
                            {c1->X, c1->Y, c1->zs, c1->iw, 1.0f, 0.0f, c1->rx, c1->ry},
                            {c2->X, c2->Y, c2->zs, c2->iw, 0.0f, 1.0f, c2->rx, c2->ry}};
            rs__setup_boxed(st, ch, sv, t, b);
            continue;
        }
        rs__cv v[3];
        const rs__vtx *cs[3] = {c0, c1, c2};
        for (int k = 0; k < 3; k++) {
            v[k].x = cs[k]->x, v[k].y = cs[k]->y, v[k].z = cs[k]->z, v[k].w = cs[k]->w;
            v[k].u = k == 1 ? 1.0f : 0.0f;
            v[k].v = k == 2 ? 1.0f : 0.0f;
        }
        if (rs__outcode(v[0]) & rs__outcode(v[1]) & rs__outcode(v[2])) {
            ch->stats.triangles_culled++;
            continue;
        }
        unsigned need = rs__clip_mask(st, v[0]) | rs__clip_mask(st, v[1]) | rs__clip_mask(st, v[2]);
        if (!need) {
            rs__setup_cv(st, ch, v, t);
            continue;
        }
        ch->stats.triangles_clipped++;
        rs__cv poly[12] = {v[0], v[1], v[2]};
        int n = rs__clip_polygon(st, need, poly, 3);
        for (int i = 1; i + 1 < n; i++) {
            rs__cv tri[3] = {poly[0], poly[i], poly[i + 1]};
            rs__setup_cv(st, ch, tri, t);
        }
    }
    /* counting sort of the bin entries by tile; stable, so triangle order is
     * kept within every tile */
    uint32_t tiles = st->tiles_x * st->tiles_y;
    if (ch->failed || !rs__grow((void **)&ch->tile_start, &ch->tile_cap, tiles + 1, sizeof(uint32_t)) ||
        !rs__grow((void **)&ch->sorted, &ch->sorted_cap, ch->entry_count ? ch->entry_count : 1, sizeof(uint32_t))) {
        ch->failed = 1; /* the tile raster skips the chunk */
        return;
    }
    memset(ch->tile_start, 0, sizeof(uint32_t) * (tiles + 1));
    for (uint32_t e = 0; e < ch->entry_count; e++) ch->tile_start[(ch->entries[e] >> 32) + 1]++;
    for (uint32_t k = 0; k < tiles; k++) ch->tile_start[k + 1] += ch->tile_start[k];
    /* place entries: use tile_start as running cursors, then shift back */
    for (uint32_t e = 0; e < ch->entry_count; e++) {
        uint32_t tile = (uint32_t)(ch->entries[e] >> 32);
        ch->sorted[ch->tile_start[tile]++] = (uint32_t)ch->entries[e];
    }
    for (uint32_t k = tiles; k > 0; k--) ch->tile_start[k] = ch->tile_start[k - 1];
    ch->tile_start[0] = 0;
}

/* ------------------------------------------------------- 4. tile raster */

/* The triangle kernels (rs_raster_kernels.c, one table per instruction set)
 * compute, for pixel (x, y) of a triangle,
 *   covered = E0(x, y) >= 0 && E1 >= 0 && E2 >= 0 (exact integers)
 *   z = zrow(8-pixel block of x, y) + dzdx * (float)(x & 7), clamped to the
 *       vertices' range
 * so all paths give identical bits. Masked triangles take the scalar alpha
 * test below on every path. */

/* Alpha-masked triangles (alphaMode MASK): the perspective-correct
 * barycentrics of pixel (x, y) give the texture coordinate and the texel
 * alpha at mip level 0 decides (alpha < cutoff is a hole): the same test
 * Embree's filter function makes, so raster and ray agree. The kernels call
 * it for covered pixels that pass the depth test. */
static int rs__alpha(const void *ctx, const void *masked, const rs__tri *t, int32_t x, int32_t y)
{
    const pf_scene *sc = ctx;
    const rs__tri_masked *m = masked;
    const uint32_t *tri = &sc->indices[3 * t->prim];
    uint32_t mat = sc->tri_material[t->prim];
    float xf = (float)x, yf = (float)y;
    float iw = m->iw0 + m->diwdx * xf + m->diwdy * yf;
    float b1 = (m->u0 + m->dudx * xf + m->dudy * yf) / iw, b2 = (m->v0 + m->dvdx * xf + m->dvdy * yf) / iw;
    float b0 = 1.0f - b1 - b2;
    pf_vec2 pa = sc->uvs[tri[0]], pb = sc->uvs[tri[1]], pc = sc->uvs[tri[2]];
    pf_vec2 uv = {b0 * pa.x + b1 * pb.x + b2 * pc.x, b0 * pa.y + b1 * pb.y + b2 * pc.y};
    float rgba[4];
    pf_material_sample(sc, mat, uv, 0.0f, rgba);
    return !(rgba[3] < sc->materials[mat].alpha_cutoff);
}

const rs_raster_kernels *rs_raster_kernels_for(rs_simd simd)
{
#if SIMD_X86
    if (simd == RS_SIMD_AVX512) return &rs_raster_kernels_avx512;
    if (simd == RS_SIMD_AVX2) return &rs_raster_kernels_avx2;
#endif
    (void)simd;
    return &rs_raster_kernels_scalar;
}

/* Copies n 32-bit values of a finished tile row to the target. Rows that
 * are aligned to a vector with n a multiple of SIMD_W (16 bytes and 4 with
 * SSE2: every full tile of a target whose width is a multiple of 4) go with
 * non-temporal stores: the target's
 * lines are not read for ownership first and the tile does not evict the
 * cache. Measured with the scratch A/B harness (docs/perf.md): the cube
 * shadow maps 5-9% faster with 1 and 2 threads, the G-buffer's visibility
 * followed by its resolve 0-3% faster. */
static void rs__copy_out(void *dst, const void *src, size_t n)
{
    if (n % SIMD_W == 0 && ((uintptr_t)dst & (SIMD_W * 4 - 1)) == 0) {
        int32_t *d = dst;
        const int32_t *s = src; /* tile rows: 64-byte aligned */
        for (size_t i = 0; i < n; i += SIMD_W) simd_stream_i(d + i, simd_load_i(s + i));
        return;
    }
    memcpy(dst, src, n * 4);
}

/* Tile row y (tile-relative) of a plane in the kernels' stamp order
 * (rs_raster_kernels.h), as plain pixels. */
static void rs__unstamp_row(uint32_t *row, const uint32_t *plane, int32_t y, uint32_t stamp_h)
{
    const uint32_t *src = plane + (size_t)(y / (int32_t)stamp_h) * RS_STAMPS_X * RS_STAMP_W * stamp_h +
                          (size_t)(y % (int32_t)stamp_h) * RS_STAMP_W;
    for (int s = 0; s < RS_STAMPS_X; s++) memcpy(row + s * RS_STAMP_W, src + (size_t)s * RS_STAMP_W * stamp_h, 16);
}

/* Tile row y of a plane to the target's n pixels at dst: a whole row of a
 * vector-aligned target straight from the stamps with non-temporal stores
 * when this file's vector is one stamp row (4 lanes: the baseline build),
 * else through rs__unstamp_row and rs__copy_out. The same values. */
static void rs__row_out(uint32_t *dst, const uint32_t *plane, int32_t y, uint32_t stamp_h, size_t n)
{
    if (SIMD_W == RS_STAMP_W && n == RS_TILE && ((uintptr_t)dst & (SIMD_W * 4 - 1)) == 0) {
        const int32_t *src = (const int32_t *)plane +
                             (size_t)(y / (int32_t)stamp_h) * RS_STAMPS_X * RS_STAMP_W * stamp_h +
                             (size_t)(y % (int32_t)stamp_h) * RS_STAMP_W;
        for (int s = 0; s < RS_STAMPS_X; s++)
            simd_stream_i((int32_t *)dst + s * RS_STAMP_W, simd_load_i(src + (size_t)s * RS_STAMP_W * stamp_h));
        return;
    }
    _Alignas(64) uint32_t row[RS_TILE];
    rs__unstamp_row(row, plane, y, stamp_h);
    rs__copy_out(dst, row, n);
}

/* Rasterizes one tile: its triangles, gathered from the chunks' bins in
 * drawing order, go to the kernel in one call, into a tile buffer on this
 * thread's stack (L1/L2-resident; cleared there and copied to the target
 * once, instead of clearing and writing the target's rows, which costs a
 * read for ownership of every line and, with 2 threads, contention for the
 * shared cache). `list`: room for the tile's triangles (the caller grows it). */
static void rs__raster_tile(rs__pass_state *st, uint32_t tile, rs__list *list)
{
    const rs_target *tg = st->t;
    int32_t tx0 = (int32_t)(tile % st->tiles_x) * RS_TILE, ty0 = (int32_t)(tile / st->tiles_x) * RS_TILE;
    const rs_raster_kernels *kern = rs_raster_kernels_for(st->simd);
    uint32_t n = 0;
    for (uint32_t c = 0; c < st->s->chunk_count; c++) {
        const rs__chunk *ch = &st->s->chunks[c];
        if (ch->tri_count && !ch->failed) n += ch->tile_start[tile + 1] - ch->tile_start[tile];
    }
    if (n > list->cap) {
        uint32_t cap = list->cap ? list->cap : 256;
        while (cap < n) cap *= 2;
        const rs__tri **tris = realloc(list->tris, sizeof(*tris) * cap);
        if (tris) list->tris = tris;
        const void **masked = realloc(list->masked, sizeof(*masked) * cap);
        if (masked) list->masked = masked;
        if (!tris || !masked) {
            __atomic_fetch_add(&st->s->failed_tiles, 1u, __ATOMIC_RELAXED); /* the tile stays as it was */
            return;
        }
        list->cap = cap;
    }
    const rs__tri **tris = list->tris;
    const void **masked = list->masked;
    _Alignas(64) float depth[RS_TILE * RS_TILE];
    _Alignas(64) uint32_t prim[RS_TILE * RS_TILE];
    uint32_t *coverage = NULL;
    if (tg->coverage && !(coverage = calloc(RS_TILE * RS_TILE, sizeof(uint32_t)))) /* tests only */
        __atomic_fetch_add(&st->s->failed_tiles, 1u, __ATOMIC_RELAXED);        /* that tile's counts are missing */
    memset(depth, 0, sizeof depth);
    if (tg->prim)
        for (int i = 0; i < RS_TILE * RS_TILE; i++) prim[i] = RS_NO_PRIM;
    n = 0;
    for (uint32_t c = 0; c < st->s->chunk_count; c++) {
        const rs__chunk *ch = &st->s->chunks[c];
        if (ch->tri_count == 0 || ch->failed) continue;
        for (uint32_t e = ch->tile_start[tile]; e < ch->tile_start[tile + 1]; e++, n++) {
            const uint32_t entry = ch->sorted[e];
            const rs__tri *t = &ch->tris[entry & ~RS__ENTRY_MASKED];
            tris[n] = t;
            masked[n] = entry & RS__ENTRY_MASKED ? &ch->masked[t->masked] : NULL;
        }
    }
    rs__tile_in in = {tris, masked, n, tx0, ty0, 0, 0, rs__alpha, st->ctx->scene, depth, tg->prim ? prim : NULL,
                      coverage};
    in.xlim = (int32_t)tg->width - tx0 < RS_TILE ? (int32_t)tg->width - tx0 : RS_TILE;
    in.ylim = (int32_t)tg->height - ty0 < RS_TILE ? (int32_t)tg->height - ty0 : RS_TILE;
    kern->tile(&in);
    _Alignas(64) uint32_t row[RS_TILE];
    size_t w = (size_t)in.xlim;
    for (int32_t y = 0; y < in.ylim; y++) {
        size_t o = (size_t)(ty0 + y) * tg->width + (size_t)tx0;
        rs__row_out((uint32_t *)tg->depth + o, (const uint32_t *)depth, y, kern->stamp_h, w);
        if (tg->prim) rs__row_out(tg->prim + o, prim, y, kern->stamp_h, w);
        if (coverage) {
            rs__unstamp_row(row, coverage, y, kern->stamp_h);
            memcpy(tg->coverage + o, row, sizeof(uint32_t) * w);
        }
    }
    simd_stream_fence(); /* the streamed rows are visible before the job reports the tile done */
    free(coverage);
}

/* ------------------------------------------------------- the pass */

static void rs__cull_job(void *p, uint32_t item, uint32_t worker)
{
    (void)worker;
    rs__pass_state *st = p;
    uint32_t c0 = item * 64, c1 = c0 + 64 < st->ctx->cluster_count ? c0 + 64 : st->ctx->cluster_count;
    rs__cull_clusters(st, c0, c1);
}

static void rs__setup_job(void *p, uint32_t item, uint32_t worker)
{
    (void)worker;
    rs__setup_bin(p, item);
}

/* The item-th tile the pass draws (row by row over its tile rectangle). */
static uint32_t rs__pass_tile(const rs__pass_state *st, uint32_t item)
{
    if (st->tile_list) return st->tile_list[item];
    uint32_t w = st->rtx1 - st->rtx0;
    return (st->rty0 + item / w) * st->tiles_x + st->rtx0 + item % w;
}

static void rs__tile_job(void *p, uint32_t item, uint32_t worker)
{
    rs__pass_state *st = p;
    rs__raster_tile(st, rs__pass_tile(st, item), &st->s->lists[worker]);
}

/* One tile list per thread that may run tile jobs (grown once: a scratch
 * keeps its lists). 0 when out of memory. */
static int rs__lists(rs_scratch *s, uint32_t count)
{
    if (count <= s->list_count) return 1;
    rs__list *l = realloc(s->lists, sizeof *l * count);
    if (!l) return 0;
    memset(l + s->list_count, 0, sizeof *l * (count - s->list_count));
    s->lists = l;
    s->list_count = count;
    return 1;
}

/* Limits a pass to the tiles [tx0, tx1) x [ty0, ty1) (non-empty, inside). */
static void rs__pass_rect(rs__pass_state *st, uint32_t tx0, uint32_t ty0, uint32_t tx1, uint32_t ty1)
{
    st->rtx0 = tx0, st->rty0 = ty0, st->rtx1 = tx1, st->rty1 = ty1;
    st->rpx0 = (int64_t)tx0 * RS_TILE, st->rpy0 = (int64_t)ty0 * RS_TILE;
    st->rpx1 = (int64_t)tx1 * RS_TILE - 1, st->rpy1 = (int64_t)ty1 * RS_TILE - 1;
    st->tile_jobs = (tx1 - tx0) * (ty1 - ty0);
}

static int rs__begin(rs__pass_state *st, const rs_context *ctx, rs_scratch *s, const rs_pass *pass, rs_target *t,
                     rs_simd simd)
{
    memset(st, 0, sizeof *st);
    if (t->width == 0 || t->height == 0 || t->width > RS_MAX_SIZE || t->height > RS_MAX_SIZE) return 0;
    st->ctx = ctx;
    st->s = s;
    st->pass = pass;
    st->t = t;
    st->tiles_x = (t->width + RS_TILE - 1) / RS_TILE;
    st->tiles_y = (t->height + RS_TILE - 1) / RS_TILE;
    rs__pass_rect(st, 0, 0, st->tiles_x, st->tiles_y);
    st->gx = 2.0f * RS_GUARD / (float)t->width;
    st->gy = 2.0f * RS_GUARD / (float)t->height;
    st->simd = simd;
    return 1;
}

/* After a pass: the chunks whose allocations failed (the only failures a
 * pass can have besides the tile buffers' coverage counts), added to what
 * the scratch holds until rs_scratch_status reads it. */
static void rs__finish_status(const rs__pass_state *st)
{
    for (uint32_t c = 0; c < st->s->chunk_count; c++) st->s->failed_chunks += st->s->chunks[c].failed != 0;
}

pf_result rs_scratch_status(rs_scratch *s, pf_error *err)
{
    pf_result r = PF_OK;
    if (s->failed_pass)
        r = pf_error_set(err, PF_ERR_OUT_OF_MEMORY,
                         "rasterizer: out of memory for the tile lists of %u passes; they drew nothing",
                         s->failed_pass);
    else if (s->failed_chunks)
        r = pf_error_set(err, PF_ERR_OUT_OF_MEMORY,
                         "rasterizer: out of memory growing the triangle records or bins of %u setup chunks (of %u per "
                         "pass); those passes lack the chunks' triangles",
                         s->failed_chunks, s->chunk_count);
    else if (s->failed_tiles)
        r = pf_error_set(err, PF_ERR_OUT_OF_MEMORY,
                         "rasterizer: out of memory for the triangle lists or coverage counts of %u tiles; they were not drawn or not counted",
                         s->failed_tiles);
    s->failed_chunks = s->failed_tiles = s->failed_pass = 0;
    return r;
}

pf_result rs_context_status(rs_context *ctx, pf_error *err) { return rs_scratch_status(ctx->scratch, err); }

static void rs__finish_stats(const rs__pass_state *st, rs_stats *out)
{
    if (!out) return;
    memset(out, 0, sizeof *out);
    for (uint32_t c = 0; c < st->ctx->cluster_count; c++) out->clusters_culled += !st->s->cluster_visible[c];
    for (uint32_t c = 0; c < st->s->chunk_count; c++) {
        const rs_stats *cs = &st->s->chunks[c].stats;
        out->triangles_in += cs->triangles_in;
        out->triangles_clipped += cs->triangles_clipped;
        out->triangles_culled += cs->triangles_culled;
        out->triangles_binned += cs->triangles_binned;
    }
}

/* rs_render and rs_render_tiles: the pass over the tiles st was limited to. */
static void rs__render(rs_context *ctx, rs__pass_state *st, rs_stats *stats)
{
    uint32_t tiles = st->tile_jobs;
    pf_jobs *jobs = ctx->jobs;
    if (!rs__lists(ctx->scratch, pf_jobs_thread_count(jobs))) {
        ctx->scratch->failed_pass++; /* nothing drawn (rs_context_status) */
        return;
    }
    uint32_t nv = (ctx->weld_count + RS_VCHUNK - 1) / RS_VCHUNK;
    /* clusters first: they say which vertex blocks the setup will read */
    memset(ctx->scratch->vblock_need, 0, RS_VBLOCKS(ctx->weld_count));
    pf_job_id cj = pf_jobs_add(jobs, rs__cull_job, st, (ctx->cluster_count + 63) / 64, 1, NULL, 0);
    pf_job_id vj = pf_jobs_add(jobs, rs__vertex_job, st, nv, 1, &cj, 1);
    pf_job_id sj = pf_jobs_add(jobs, rs__setup_job, st, ctx->chunk_count, 1, &vj, 1);
    pf_job_id tj = pf_jobs_add(jobs, rs__tile_job, st, tiles, 1, &sj, 1);
    pf_jobs_wait(jobs, tj);
    rs__finish_status(st);
    rs__finish_stats(st, stats);
}

void rs_render(rs_context *ctx, const rs_pass *pass, rs_target *t, rs_stats *stats)
{
    rs__pass_state st;
    if (rs__begin(&st, ctx, ctx->scratch, pass, t, ctx->simd)) rs__render(ctx, &st, stats);
}

uint32_t rs_render_tiles(rs_context *ctx, const rs_pass *pass, rs_target *t, const uint64_t *tiles, rs_stats *stats)
{
    rs__pass_state st;
    if (stats) memset(stats, 0, sizeof *stats);
    if (!rs__begin(&st, ctx, ctx->scratch, pass, t, ctx->simd)) return 0;
    rs_scratch *s = ctx->scratch;
    uint32_t n = st.tiles_x * st.tiles_y, count = 0;
    if (!rs__grow((void **)&s->tile_list, &s->tile_list_cap, n, sizeof(uint32_t))) {
        s->failed_pass++; /* nothing drawn (rs_context_status) */
        return 0;
    }
    /* the tiles in row order, and their bounding rectangle */
    uint32_t tx0 = st.tiles_x, ty0 = st.tiles_y, tx1 = 0, ty1 = 0;
    for (uint32_t k = 0; k < n; k++) {
        if (!rs_tile_bit(tiles, k)) continue;
        uint32_t tx = k % st.tiles_x, ty = k / st.tiles_x;
        tx0 = tx < tx0 ? tx : tx0, tx1 = tx + 1 > tx1 ? tx + 1 : tx1;
        ty0 = ty < ty0 ? ty : ty0, ty1 = ty + 1 > ty1 ? ty + 1 : ty1;
        s->tile_list[count++] = k;
    }
    if (!count) return 0;
    rs__pass_rect(&st, tx0, ty0, tx1, ty1);
    st.tile_mask = tiles;
    st.tile_list = s->tile_list;
    st.tile_jobs = count;
    rs__render(ctx, &st, stats);
    return count;
}

void rs_render_serial(const rs_context *ctx, rs_scratch *s, const rs_pass *pass, rs_target *t, rs_stats *stats)
{
    rs__pass_state st;
    if (s->vtx_cap < ctx->weld_count) { /* made before an update split vertices: rs_scratch_create again */
        s->failed_pass++;
        return;
    }
    if (!rs__begin(&st, ctx, s, pass, t, ctx->simd)) return;
    if (!rs__lists(s, 1)) {
        s->failed_pass++;
        return;
    }
    if (s->vblock_cap < RS_VBLOCKS(ctx->weld_count)) {
        s->failed_pass++;
        return;
    }
    memset(s->vblock_need, 0, RS_VBLOCKS(ctx->weld_count));
    rs__cull_clusters(&st, 0, ctx->cluster_count);
    rs__transform_needed(&st, 0, ctx->weld_count);
    for (uint32_t c = 0; c < ctx->chunk_count; c++) rs__setup_bin(&st, c);
    for (uint32_t k = 0; k < st.tile_jobs; k++) rs__raster_tile(&st, rs__pass_tile(&st, k), &s->lists[0]);
    rs__finish_status(&st);
    rs__finish_stats(&st, stats);
}
