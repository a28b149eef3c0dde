/* rs_shadow: direct-light shadow maps and their 16-tap PCF lookup (Laine et
 * al. 2007, Sec. 6; percentage-closer filtering after Reeves, Salesin and
 * Cook 1987). Conventions are in rs_shadow.h; this file derives the
 * projections and the bias. */
#include "rs_shadow.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "rs_shadow_kernels.h"
#include "rs_shadow_lookup.h" /* rs_shadow_lookup_eligible */
#include "simd.h"

/* ------------------------------------------------------------- projections */

/* Cube faces in the standard order with the standard ups (rs_shadow.h). */
static const float rs__cube_axes[6][2][3] = {
    {{1, 0, 0}, {0, -1, 0}},  {{-1, 0, 0}, {0, -1, 0}}, {{0, 1, 0}, {0, 0, 1}},
    {{0, -1, 0}, {0, 0, -1}}, {{0, 0, 1}, {0, -1, 0}},  {{0, 0, -1}, {0, -1, 0}},
};

static pf_vec3 rs__v3(const float a[3]) { return pf_v3(a[0], a[1], a[2]); }

/* tan of half the fov of a map that must cover the tangent-plane square
 * [-t, t]^2 plus RS_SHADOW_MARGIN_TEXELS on every side. A map of n texels
 * spanning [-T, T] has texels 2T/n wide, so we need
 *   T - margin * 2T / n >= t   <=>   T = t / (1 - 2 margin / n). */
static float rs__widen(float t, uint32_t size) { return t / (1.0f - 2.0f * RS_SHADOW_MARGIN_TEXELS / (float)size); }

/* The image axes of face f as rs_mat4_perspective/ortho build them from the
 * forward axis and the up hint: right = f x up, up = right x f. */
static void rs__axes(rs_shadow_map *m, uint32_t face, pf_vec3 up_hint)
{
    m->right[face] = pf_v3_normalize(pf_v3_cross(m->forward[face], up_hint));
    m->up[face] = pf_v3_cross(m->right[face], m->forward[face]);
}

static void rs__setup_perspective(rs_shadow_map *m, const pf_scene *s, const pf_light *L)
{
    pf_vec3 ext = pf_v3_sub(s->bounds_max, s->bounds_min);
    /* Perspective maps store zs = znear / depth: float keeps the same relative
     * precision at every depth (2^-24 of the depth), so znear costs nothing
     * in precision and can be tiny; geometry nearer than it is clipped. */
    m->znear = fmaxf(1.0e-4f * pf_v3_length(ext), 1.0e-6f);
    m->zfar = 0.0f;
    m->eye = L->position;
    if (m->kind == RS_SHADOW_SPOT) {
        pf_vec3 f = pf_v3_normalize(L->direction), t, b;
        pf_v3_basis(f, &t, &b);
        /* The cone of half-angle `outer` fits in the square of half-side
         * tan(outer); a zero cone still gets a (tiny) map. */
        float outer = pf_clampf(L->outer_cone, 1.0e-3f, RS_SHADOW_SPOT_MAX_CONE);
        m->tan_half = rs__widen(tanf(outer), m->size);
        m->forward[0] = f;
        rs__axes(m, 0, b);
        m->view_proj[0] = rs_mat4_perspective(m->eye, f, b, 2.0f * atanf(m->tan_half), 1.0f, m->znear);
        return;
    }
    /* Cube: each face covers its 90-degree square (tan = 1) plus the margin,
     * so the PCF taps of a point that projects to a face (by its major axis)
     * never leave that face. */
    m->tan_half = rs__widen(1.0f, m->size);
    for (uint32_t f = 0; f < 6; f++) {
        m->forward[f] = rs__v3(rs__cube_axes[f][0]);
        rs__axes(m, f, rs__v3(rs__cube_axes[f][1]));
        m->view_proj[f] = rs_mat4_perspective(m->eye, m->forward[f], rs__v3(rs__cube_axes[f][1]),
                                              2.0f * atanf(m->tan_half), 1.0f, m->znear);
    }
}

static void rs__setup_ortho(rs_shadow_map *m, const pf_scene *s, const pf_light *L)
{
    pf_vec3 f = pf_v3_normalize(L->direction), t, b;
    pf_v3_basis(f, &t, &b);
    /* Half extents of the scene's bounding box projected on each axis a:
     * sum_i |a_i| e_i for the box's half sizes e. */
    pf_vec3 c = pf_v3_scale(pf_v3_add(s->bounds_min, s->bounds_max), 0.5f);
    pf_vec3 e = pf_v3_scale(pf_v3_sub(s->bounds_max, s->bounds_min), 0.5f);
    float et = fabsf(t.x) * e.x + fabsf(t.y) * e.y + fabsf(t.z) * e.z;
    float eb = fabsf(b.x) * e.x + fabsf(b.y) * e.y + fabsf(b.z) * e.z;
    float ef = fabsf(f.x) * e.x + fabsf(f.y) * e.y + fabsf(f.z) * e.z;
    /* A flat scene seen edge-on has a zero extent; keep the box non-empty. */
    float floor_ext = 1.0e-4f * pf_v3_max_comp(e) + 1.0e-6f;
    et = fmaxf(et, floor_ext);
    eb = fmaxf(eb, floor_ext);
    ef = fmaxf(ef, floor_ext);
    /* Depth: the scene spans [c - ef, c + ef] along f. The eye sits 2 pads
     * before it and the box [pad, 2 ef + 3 pad] leaves a pad on both sides,
     * so no triangle touches the near or far clip plane. */
    float pad = 0.05f * ef;
    m->eye = pf_v3_sub(c, pf_v3_scale(f, ef + 2.0f * pad));
    m->znear = pad;
    m->zfar = 2.0f * ef + 3.0f * pad;
    /* rs_mat4_ortho's right axis is f x b = -t or t: same extent either way. */
    m->half_w = rs__widen(et, m->size);
    m->half_h = rs__widen(eb, m->size);
    m->tan_half = 0.0f;
    m->forward[0] = f;
    rs__axes(m, 0, b);
    m->view_proj[0] = rs_mat4_ortho(m->eye, f, b, m->half_w, m->half_h, m->znear, m->zfar);
}

/* The map's kind, size and matrices for the light (everything but the planes). */
static pf_result rs__shadow_map_setup(rs_shadow_map *m, const pf_scene *scene, uint32_t light,
                                     const rs_shadow_desc *desc, pf_error *err)
{
    memset(m, 0, sizeof *m);
    if (desc) m->desc = *desc;
    if (light >= scene->light_count)
        return pf_error_set(err, PF_ERR_ARGUMENT, "shadow map for light %u, but the scene has %u lights", light,
                            scene->light_count);
    const pf_light *L = &scene->lights[light];
    uint32_t size = m->desc.size ? m->desc.size : RS_SHADOW_DEFAULT_SIZE;
    if (size < RS_SHADOW_MIN_SIZE || size > RS_MAX_SIZE)
        return pf_error_set(err, PF_ERR_ARGUMENT, "shadow map size %u is outside [%u, %u]", size, RS_SHADOW_MIN_SIZE,
                            RS_MAX_SIZE);
    if (!pf_v3_is_finite(L->position) || !pf_v3_is_finite(L->direction))
        return pf_error_set(err, PF_ERR_NONFINITE, "light %u (%s) is not finite", light, L->name);
    if (L->type != PF_LIGHT_POINT && pf_v3_length(L->direction) == 0.0f)
        return pf_error_set(err, PF_ERR_ARGUMENT, "light %u (%s) has no direction", light, L->name);
    m->light = light;
    m->size = size;
    m->fresh = 1;
    switch (L->type) {
    case PF_LIGHT_SPOT:
        m->kind = L->outer_cone > RS_SHADOW_SPOT_MAX_CONE ? RS_SHADOW_CUBE : RS_SHADOW_SPOT;
        break;
    case PF_LIGHT_DIRECTIONAL: m->kind = RS_SHADOW_ORTHO; break;
    default: m->kind = RS_SHADOW_CUBE; break;
    }
    m->face_count = m->kind == RS_SHADOW_CUBE ? 6 : 1;
    if (m->kind == RS_SHADOW_ORTHO)
        rs__setup_ortho(m, scene, L);
    else
        rs__setup_perspective(m, scene, L);
    return PF_OK;
}

/* The tile masks' layout for the map's size (rs_shadow.h). */
static void rs__tiles_layout(rs_shadow_map *m)
{
    m->tiles_side = (m->size + RS_TILE - 1) / RS_TILE;
    m->tile_words = (m->tiles_side * m->tiles_side + 63) / 64;
}

static pf_result rs__shadow_map_alloc(rs_shadow_map *m, pf_error *err)
{
    rs__tiles_layout(m);
    size_t words = (size_t)m->face_count * m->tile_words;
    m->depth = rs_plane_alloc((size_t)m->face_count * m->size * m->size * sizeof(float));
    m->valid = calloc(words, sizeof(uint64_t));
    m->need = calloc(words, sizeof(uint64_t));
    if (!m->depth || !m->valid || !m->need) {
        rs_shadow_map_free(m);
        return pf_error_set(err, PF_ERR_OUT_OF_MEMORY, "out of memory for a %ux%ux%u shadow map", m->size, m->size,
                            m->face_count);
    }
    return PF_OK;
}

pf_result rs_shadow_map_init(rs_shadow_map *m, const pf_scene *scene, uint32_t light, const rs_shadow_desc *desc,
                             pf_error *err)
{
    pf_result r = rs__shadow_map_setup(m, scene, light, desc, err);
    return r == PF_OK ? rs__shadow_map_alloc(m, err) : r;
}

pf_result rs_shadow_map_update(rs_shadow_map *m, const pf_scene *scene, uint32_t light, const rs_shadow_desc *desc,
                               pf_error *err)
{
    float *depth = m->depth;
    uint64_t *valid = m->valid, *need = m->need;
    uint32_t faces = m->face_count, size = m->size;
    pf_result r = rs__shadow_map_setup(m, scene, light, desc, err);
    if (r == PF_OK && depth && valid && need && faces == m->face_count && size == m->size) {
        /* the same planes, none of their tiles valid for the new light */
        m->depth = depth, m->valid = valid, m->need = need;
        rs__tiles_layout(m);
        memset(valid, 0, (size_t)faces * m->tile_words * sizeof(uint64_t));
        memset(need, 0, (size_t)faces * m->tile_words * sizeof(uint64_t));
        return PF_OK;
    }
    free(depth), free(valid), free(need);
    return r == PF_OK ? rs__shadow_map_alloc(m, err) : r;
}

void rs_shadow_map_free(rs_shadow_map *m)
{
    free(m->depth), free(m->valid), free(m->need);
    m->depth = NULL;
    m->valid = m->need = NULL;
}

float *rs_shadow_map_face(const rs_shadow_map *m, uint32_t face)
{
    return m->depth + (size_t)face * m->size * m->size;
}

pf_result rs_shadow_set_init(rs_shadow_set *set, const pf_scene *scene, const rs_shadow_desc *desc, pf_error *err)
{
    set->count = 0;
    set->maps = calloc(scene->light_count ? scene->light_count : 1, sizeof *set->maps);
    if (!set->maps) return pf_error_set(err, PF_ERR_OUT_OF_MEMORY, "out of memory for shadow maps");
    for (uint32_t l = 0; l < scene->light_count; l++) {
        pf_result r = rs_shadow_map_init(&set->maps[l], scene, l, desc, err);
        if (r != PF_OK) {
            rs_shadow_map_free(&set->maps[l]);
            rs_shadow_set_free(set);
            return r;
        }
        set->count++;
    }
    return PF_OK;
}

void rs_shadow_set_free(rs_shadow_set *set)
{
    for (uint32_t l = 0; l < set->count; l++) rs_shadow_map_free(&set->maps[l]);
    free(set->maps);
    set->maps = NULL;
    set->count = 0;
}

/* --------------------------------------------------------------- rendering */

/* Every tile of every face set in the map's mask `bits`. */
static void rs__mask_all(const rs_shadow_map *m, uint64_t *bits)
{
    uint32_t tiles = m->tiles_side * m->tiles_side;
    for (uint32_t f = 0; f < m->face_count; f++)
        for (uint32_t w = 0; w < m->tile_words; w++) {
            uint32_t left = tiles - w * 64;
            bits[(size_t)f * m->tile_words + w] = left >= 64 ? ~(uint64_t)0 : ((uint64_t)1 << left) - 1;
        }
}

static void rs__stats_add(rs_stats *sum, const rs_stats *s)
{
    sum->clusters_culled += s->clusters_culled;
    sum->triangles_in += s->triangles_in;
    sum->triangles_clipped += s->triangles_clipped;
    sum->triangles_culled += s->triangles_culled;
    sum->triangles_binned += s->triangles_binned;
}

/* One rs_render pass per face, in map and face order. A 1024 face has 256
 * tiles, plenty to keep every worker busy, so the faces are not spread over
 * jobs with rs_render_serial: measured on Sibenik (75k triangles, 2
 * threads), the six cube faces take 46 ms either way, and the serial form
 * would need a scratch per worker. */
void rs_shadow_render(rs_context *ctx, rs_shadow_map *maps, uint32_t count, rs_stats *stats)
{
    if (stats) memset(stats, 0, sizeof *stats);
    for (uint32_t i = 0; i < count; i++) {
        rs_shadow_map *m = &maps[i];
        for (uint32_t f = 0; f < m->face_count; f++) {
            /* Cull nothing: open meshes and single-sided walls must still
             * cast shadows from both sides. */
            rs_pass pass = {.view_proj = m->view_proj[f], .cull = RS_CULL_NONE};
            rs_target target = {.width = m->size, .height = m->size, .depth = rs_shadow_map_face(m, f)};
            rs_stats s;
            memset(&s, 0, sizeof s);
            rs_render(ctx, &pass, &target, &s);
            if (stats) rs__stats_add(stats, &s);
        }
        if (m->valid) rs__mask_all(m, m->valid);
    }
}

/* rs_render_tiles on face f of m (its tiles `draw`), added to *stats (may
 * be NULL); the tiles drawn. */
static uint32_t rs__face_tiles(rs_context *ctx, rs_shadow_map *m, uint32_t f, const uint64_t *draw, rs_stats *stats)
{
    rs_pass pass = {.view_proj = m->view_proj[f], .cull = RS_CULL_NONE};
    rs_target target = {.width = m->size, .height = m->size, .depth = rs_shadow_map_face(m, f)};
    rs_stats s;
    uint32_t n = rs_render_tiles(ctx, &pass, &target, draw, &s);
    if (stats) rs__stats_add(stats, &s);
    return n;
}

void rs_shadow_need_clear(rs_shadow_map *maps, uint32_t count)
{
    for (uint32_t i = 0; i < count; i++)
        if (maps[i].need) memset(maps[i].need, 0, (size_t)maps[i].face_count * maps[i].tile_words * sizeof(uint64_t));
}

void rs_shadow_need_all(rs_shadow_map *m)
{
    if (m->need) rs__mask_all(m, m->need);
}

uint32_t rs_shadow_render_needed(rs_context *ctx, rs_shadow_map *maps, uint32_t count, rs_stats *stats)
{
    if (stats) memset(stats, 0, sizeof *stats);
    uint32_t drawn = 0;
    for (uint32_t i = 0; i < count; i++) {
        rs_shadow_map *m = &maps[i];
        if (!m->depth || !m->valid || !m->need) continue;
        for (uint32_t f = 0; f < m->face_count; f++) {
            uint64_t *valid = m->valid + (size_t)f * m->tile_words;
            const uint64_t *need = m->need + (size_t)f * m->tile_words;
            uint64_t draw[RS_SHADOW_MASK_WORDS], any = 0;
            for (uint32_t w = 0; w < m->tile_words; w++) any |= draw[w] = need[w] & ~valid[w];
            if (!any) continue;
            drawn += rs__face_tiles(ctx, m, f, draw, stats);
            for (uint32_t w = 0; w < m->tile_words; w++) valid[w] |= draw[w];
        }
    }
    return drawn;
}

uint32_t rs_shadow_render_box(rs_context *ctx, rs_shadow_map *maps, uint32_t count, pf_vec3 lo, pf_vec3 hi,
                              uint64_t *texels, rs_stats *stats)
{
    if (stats) memset(stats, 0, sizeof *stats);
    uint32_t faces = 0;
    for (uint32_t i = 0; i < count; i++) {
        rs_shadow_map *m = &maps[i];
        if (!m->depth || !m->valid) continue;
        for (uint32_t f = 0; f < m->face_count; f++) {
            uint32_t r[4];
            if (!rs_box_rect(&m->view_proj[f], m->size, m->size, lo, hi, r)) continue;
            /* the valid tiles that meet the rectangle */
            uint64_t draw[RS_SHADOW_MASK_WORDS];
            memset(draw, 0, sizeof(uint64_t) * m->tile_words);
            const uint64_t *valid = m->valid + (size_t)f * m->tile_words;
            uint64_t tex = 0;
            for (uint32_t ty = r[1] / RS_TILE; ty < (r[3] + RS_TILE - 1) / RS_TILE; ty++)
                for (uint32_t tx = r[0] / RS_TILE; tx < (r[2] + RS_TILE - 1) / RS_TILE; tx++) {
                    uint32_t t = ty * m->tiles_side + tx;
                    if (!rs_tile_bit(valid, t)) continue;
                    draw[t / 64] |= (uint64_t)1 << (t % 64);
                    uint32_t w = m->size - tx * RS_TILE, h = m->size - ty * RS_TILE; /* what it drew: whole tiles */
                    tex += (uint64_t)(w < RS_TILE ? w : RS_TILE) * (h < RS_TILE ? h : RS_TILE);
                }
            if (!tex) continue;
            rs__face_tiles(ctx, m, f, draw, stats);
            if (texels) *texels += tex;
            faces++;
        }
    }
    return faces;
}

/* ------------------------------------------------------------------ lookup */

uint32_t rs_shadow_cube_face(pf_vec3 eye, pf_vec3 p)
{
    pf_vec3 v = pf_v3_sub(p, eye);
    float ax = fabsf(v.x), ay = fabsf(v.y), az = fabsf(v.z);
    if (ax >= ay && ax >= az) return v.x >= 0.0f ? 0u : 1u;
    if (ay >= az) return v.y >= 0.0f ? 2u : 3u;
    return v.z >= 0.0f ? 4u : 5u;
}

/* Which face a point uses and its depth along that face's axis. */
static uint32_t rs__face(const rs_shadow_map *m, pf_vec3 p, float *depth)
{
    uint32_t f = m->kind == RS_SHADOW_CUBE ? rs_shadow_cube_face(m->eye, p) : 0u;
    *depth = pf_v3_dot(pf_v3_sub(p, m->eye), m->forward[f]);
    return f;
}

/* Percentage-closer filtering over the n x n texels starting at (x0, y0)
 * (clamped to the map): the fraction whose stored zs is no nearer the light
 * than the receiver's plane at that texel's centre (tx, ty) plus the bias,
 *   zs_p + gx (tx - fx) + gy (ty - fy) + zs_bias
 * (reversed depth: nearer = greater; empty texels, 0, are always lit). The
 * sum counts whole taps, so the result is exact. */
static float rs__pcf(const float *plane, uint32_t size, int x0, int y0, int n, float fx, float fy, float zs_p,
                     float gx, float gy, float zs_bias)
{
    int lit = 0, last = (int)size - 1;
    for (int j = 0; j < n; j++) {
        int y = y0 + j < 0 ? 0 : (y0 + j > last ? last : y0 + j);
        const float *row = plane + (size_t)y * size;
        float zy = zs_p + gy * ((float)(y0 + j) + 0.5f - fy) + zs_bias;
        for (int i = 0; i < n; i++) {
            int x = x0 + i < 0 ? 0 : (x0 + i > last ? last : x0 + i);
            lit += row[x] <= zy + gx * ((float)(x0 + i) + 0.5f - fx);
        }
    }
    return (float)lit / (float)(n * n);
}

/* The bias, step by step (w = world size of a texel at p, across the light's
 * rays; theta = angle between the geometric normal and the direction l to
 * the light).
 *
 * 1. Slope, per tap. A tap reads the map at its texel's centre, up to 2
 *    texels per axis from p (4x4 kernel) or 0.7 texel (one tap). For a flat
 *    receiver the rasterizer stored there the receiver's own depth at that
 *    centre, which differs from p's by (offset . gradient): up to
 *    offset * w * tan(theta) along l. Classic slope-scaled bias adds the
 *    worst case, reach * w * tan(theta), to every tap; at 16 taps that is
 *    2.8 w tan(theta) and it hides real shadows (contact shadows, concave
 *    surfaces such as Sibenik's arches lit at grazing angles: measured, it
 *    cost 1.3% agreement there). Instead each tap is compared against the
 *    receiver plane's own zs at the tap's centre: zs is linear in screen
 *    space on a plane (that is why the rasterizer interpolates it
 *    linearly), so it is zs_p plus a constant gradient (gx, gy) per texel,
 *    derived below from the normal. This is the slope-scaled bias taken
 *    along the plane's gradient tap by tap ("receiver plane depth bias",
 *    Isidoro, GDC 2006); it is exact for planes at any angle.
 *    Perspective face (right r, up u, forward f, eye e; p on the plane
 *    n.(x - p) = 0): the ray through NDC (x, y) is e + d (x t r + y t u + f)
 *    with t = tan_half, so on the plane 1/d = (x t n.r + y t n.u + n.f) / D,
 *    D = n.(p - e), and zs = znear / d gives
 *      dzs/dx_ndc = znear t n.r / D,  dzs/dy_ndc = znear t n.u / D;
 *    texels: dx_ndc = 2 / size per texel right, dy_ndc = -2 / size per
 *    texel down. Ortho (half sizes hw, hh, depth range R): on the plane
 *    d = (n.(p - e) - x hw n.r - y hh n.u) / n.f and zs = 1 - (d - znear) / R
 *    gives dzs/dx_ndc = hw n.r / (R n.f), dzs/dy_ndc = hh n.u / (R n.f).
 *    Both blow up as the plane turns edge-on (D, n.f -> 0); the gradient is
 *    capped where tan(theta) exceeds RS_SHADOW_TAN_MAX (100: 89.4 degrees,
 *    1% of the light).
 * 2. Constant plus slope, for what is not exactly planar: p is compared as
 *    if it were  w (bias_const + bias_slope min(tan(theta), tan_max))
 *    nearer the light. Defaults 1 and 0.5 texel: the constant covers
 *    tessellated curves and the vertex snapping to 1/256 pixel (which
 *    tilts the rasterized plane by up to ~tan(theta)/256 texel of depth);
 *    the small slope term covers the same errors growing with the slope, and
 *    at grazing angles the extrapolation's rounding. Measured on the Cornell
 *    box, maze and Sibenik (tests/test_shadow.c), slope 0 leaves acne on the
 *    Cornell ceiling lit at 88 degrees by the light 1 cm below it; more than
 *    0.5, or a larger constant, only adds light leaks at contacts.
 * 3. Normal offset (off by default): p moved towards the light side along
 *    the normal by normal_offset * w * sin(theta) before projecting. With
 *    the per-tap plane it is not needed; it is kept for scenes whose
 *    geometric normals are unreliable. */
float rs_shadow_visibility(const rs_shadow_map *m, pf_vec3 p, pf_vec3 ng)
{
    const int pcf = m->desc.filter != RS_SHADOW_PCF1;
    const int ortho = m->kind == RS_SHADOW_ORTHO;
    /* Unit direction l from p towards the light, and the world size w of one
     * texel at p: perspective maps span 2 tan_half depth over `size` texels
     * at a given depth (along the face axis; across an off-axis ray a texel
     * is smaller, so this errs on the safe side), ortho maps 2 half_w. */
    float depth;
    uint32_t face = rs__face(m, p, &depth);
    pf_vec3 l;
    float texel;
    if (ortho) {
        l = pf_v3_scale(m->forward[0], -1.0f);
        texel = 2.0f * fmaxf(m->half_w, m->half_h) / (float)m->size;
    } else {
        if (!(depth > 0.0f)) return m->kind == RS_SHADOW_SPOT ? 0.0f : 1.0f; /* behind a spot / at the light */
        l = pf_v3_normalize(pf_v3_sub(m->eye, p));
        texel = 2.0f * m->tan_half * depth / (float)m->size;
    }
    float nlen = pf_v3_length(ng);
    pf_vec3 n = nlen > 0.0f ? pf_v3_scale(ng, 1.0f / nlen) : l; /* no normal: treat as facing the light */
    float cos_t = fabsf(pf_v3_dot(n, l));
    float sin_t = sqrtf(fmaxf(0.0f, 1.0f - cos_t * cos_t));
    float tan_max = m->desc.tan_max > 0.0f ? m->desc.tan_max : RS_SHADOW_TAN_MAX;
    int capped = !(sin_t < tan_max * cos_t);
    float tan_t = capped ? tan_max : sin_t / cos_t;
    float b_const = m->desc.bias_const > 0.0f ? m->desc.bias_const : RS_SHADOW_BIAS_CONST;
    float b_slope = m->desc.bias_slope > 0.0f ? m->desc.bias_slope : RS_SHADOW_BIAS_SLOPE;
    float bias = texel * (b_const + b_slope * tan_t); /* step 2, world units along the axis */

    if (m->desc.normal_offset > 0.0f) { /* step 3 */
        float k = m->desc.normal_offset * texel * sin_t;
        p = pf_v3_add(p, pf_v3_scale(n, pf_v3_dot(n, l) < 0.0f ? -k : k));
        face = rs__face(m, p, &depth);
        if (!ortho && !(depth > 0.0f)) return m->kind == RS_SHADOW_SPOT ? 0.0f : 1.0f;
    }

    /* Project with the very matrix the face was rendered with, so the
     * receiver's zs is computed the way the rasterizer computed its
     * vertices'. */
    float c[4];
    rs_mat4_transform(&m->view_proj[face], p, c);
    const float s = (float)m->size;
    float nr = pf_v3_dot(n, m->right[face]), nu = pf_v3_dot(n, m->up[face]);
    float cap = capped && sin_t > 0.0f ? tan_max * cos_t / sin_t : 1.0f; /* step 1's gradient cap */
    float x, y, zs_p, zs_bias, k;
    if (ortho) {
        /* w = 1; zs falls by 1 / (zfar - znear) per unit of depth. Outside
         * the box (laterally or in depth) nothing was rendered: lit. */
        x = c[0];
        y = c[1];
        zs_p = c[2];
        if (!(fabsf(x) <= 1.0f && fabsf(y) <= 1.0f && zs_p >= 0.0f && zs_p <= 1.0f)) return 1.0f;
        float inv_range = 1.0f / (m->zfar - m->znear);
        zs_bias = bias * inv_range;
        float nf = pf_v3_dot(n, m->forward[face]);
        k = nf != 0.0f ? 2.0f * inv_range / (s * nf) * cap : 0.0f;
        nr *= m->half_w;
        nu *= m->half_h;
    } else {
        /* z_clip = znear, w = depth: the point moved `bias` towards the
         * light has zs = znear / (w - bias). Nearer than znear nothing can
         * be recorded in front of it: lit. A spot lights nothing outside its
         * frustum (its cone factor is 0 there anyway). */
        x = c[0] / c[3];
        y = c[1] / c[3];
        zs_p = c[2] / c[3];
        if (m->kind == RS_SHADOW_SPOT && !(fabsf(x) <= 1.0f && fabsf(y) <= 1.0f)) return 0.0f;
        float wb = c[3] - bias;
        if (!(wb > c[2])) return 1.0f;
        zs_bias = c[2] / wb - zs_p;
        float d = pf_v3_dot(n, pf_v3_sub(p, m->eye));
        k = d != 0.0f ? 2.0f * m->znear * m->tan_half / (s * d) * cap : 0.0f;
    }
    float gx = k * nr, gy = -k * nu; /* zs per texel right / down */

    /* NDC to texels: x in [-1, 1] left to right, y in [1, -1] top to bottom;
     * clamped first (fmaxf drops a NaN) so the float-to-int conversion is
     * defined for any input. */
    float fx = fminf(fmaxf((0.5f * x + 0.5f) * s, -8.0f), s + 8.0f);
    float fy = fminf(fmaxf((0.5f - 0.5f * y) * s, -8.0f), s + 8.0f);
    const float *plane = rs_shadow_map_face(m, face);
    if (!pcf) return rs__pcf(plane, m->size, (int)floorf(fx), (int)floorf(fy), 1, fx, fy, zs_p, gx, gy, zs_bias);
    /* Taps at offsets -1.5, -0.5, 0.5, 1.5 texels read texels floor(fx - 1.5)
     * .. floor(fx - 1.5) + 3: the 4x4 texels whose centres surround p. */
    return rs__pcf(plane, m->size, (int)floorf(fx - 1.5f), (int)floorf(fy - 1.5f), 4, fx, fy, zs_p, gx, gy, zs_bias);
}

/* ------------------------------------------------------------ SIMD lookup */

/* rs_shadow_visibility_lanes (rs_shadow_lookup.h) is the lookup above
 * written once over the SIMD vocabulary; rs_shadow_kernels.c compiles it
 * per instruction set. */
const rs_shadow_kernels *rs_shadow_kernels_for(rs_simd simd)
{
#if SIMD_X86
    if (simd == RS_SIMD_AVX512) return &rs_shadow_kernels_avx512;
    if (simd == RS_SIMD_AVX2) return &rs_shadow_kernels_avx2;
#endif
    (void)simd;
    return &rs_shadow_kernels_scalar;
}

void rs_shadow_visibility8(const rs_shadow_map *m, rs_simd simd, const float *px, const float *py, const float *pz,
                           const float *ngx, const float *ngy, const float *ngz, unsigned active, float *out)
{
    const rs_shadow_kernels *k = rs_shadow_kernels_for(simd);
    if (!rs_shadow_lookup_eligible(m)) {
        for (int i = 0; i < 8; i++)
            out[i] = (active >> i) & 1u
                         ? rs_shadow_visibility(m, pf_v3(px[i], py[i], pz[i]), pf_v3(ngx[i], ngy[i], ngz[i]))
                         : 0.0f;
        return;
    }
    if (k->lanes == 8) {
        k->visibility(m, px, py, pz, ngx, ngy, ngz, active & 0xffu, out);
        return;
    }
    /* a wider kernel: the 8 points in its first lanes, zeros after */
    float in[6][RS_SHADOW_MAX_LANES], o[RS_SHADOW_MAX_LANES];
    const float *src[6] = {px, py, pz, ngx, ngy, ngz};
    for (int c = 0; c < 6; c++)
        for (uint32_t i = 0; i < k->lanes; i++) in[c][i] = i < 8 ? src[c][i] : 0.0f;
    k->visibility(m, in[0], in[1], in[2], in[3], in[4], in[5], active & 0xffu, o);
    memcpy(out, o, 8 * sizeof(float));
}
