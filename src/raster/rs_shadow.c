/* rs_shadow: direct-light shadow maps and their 16-tap PCF lookup (Laine et
 * al. 2007, Sec. 6; percentage-closer filtering after Reeves, Salesin and
 * Cook 1987). Conventions are in rs_shadow.h; this file derives the
 * projections and the bias. */
#include "rs_shadow.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

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

pf_result rs_shadow_map_init(rs_shadow_map *m, const pf_scene *scene, uint32_t light, const rs_shadow_desc *desc,
                             pf_error *err)
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
    m->depth = rs_plane_alloc((size_t)m->face_count * size * size * sizeof(float));
    if (!m->depth)
        return pf_error_set(err, PF_ERR_OUT_OF_MEMORY, "out of memory for a %ux%ux%u shadow map", size, size,
                            m->face_count);
    return PF_OK;
}

void rs_shadow_map_free(rs_shadow_map *m)
{
    free(m->depth);
    m->depth = NULL;
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

static void rs__stats_add(rs_stats *sum, const rs_stats *s)
{
    sum->clusters_culled += s->clusters_culled;
    sum->triangles_in += s->triangles_in;
    sum->triangles_clipped += s->triangles_clipped;
    sum->triangles_culled += s->triangles_culled;
    sum->triangles_binned += s->triangles_binned;
    sum->blocks_early_z_rejected += s->blocks_early_z_rejected;
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
    }
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

/* ------------------------------------------------------------ 8-wide lookup */

/* rs_shadow_visibility for 8 points at once (AVX2): lane by lane the very
 * IEEE operations of the scalar lookup above, in the same order and
 * association (no FMA, no approximate reciprocals), so the bits agree. Each
 * early return of the scalar code becomes a lane mask applied at the end,
 * latest check first so that the earliest one wins as it does there; a cube
 * map's per-face constants are gathered by each lane's face; the PCF taps
 * are gathers from the face planes at the same clamped texel indices. The
 * normal offset (step 3, off by default) is not vectorised:
 * rs_shadow_visibility8 sends such maps to the scalar lookup. */
#if defined(__x86_64__) || defined(__i386__)
#include <immintrin.h>

__attribute__((target("avx2"))) static inline __m256 rs__dot8(__m256 ax, __m256 ay, __m256 az, __m256 bx, __m256 by,
                                                             __m256 bz)
{
    return _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(ax, bx), _mm256_mul_ps(ay, by)), _mm256_mul_ps(az, bz));
}

/* Element k of a per-face array (stride floats per face) for each lane's
 * face: gathered (base: face 0) or, when every lane has the same face,
 * broadcast (base: that face). */
__attribute__((target("avx2"))) static inline __m256 rs__face_val8(const float *base, int gather, __m256i face_off,
                                                                  int k)
{
    if (!gather) return _mm256_set1_ps(base[k]);
    return _mm256_i32gather_ps(base, _mm256_add_epi32(face_off, _mm256_set1_epi32(k)), 4);
}

__attribute__((target("avx2"))) static void rs__visibility8_avx2(const rs_shadow_map *m, const float *px,
                                                                 const float *py, const float *pz, const float *ngx,
                                                                 const float *ngy, const float *ngz, unsigned active,
                                                                 float *out)
{
    const int pcf = m->desc.filter != RS_SHADOW_PCF1;
    const int ortho = m->kind == RS_SHADOW_ORTHO, cube = m->kind == RS_SHADOW_CUBE, spot = m->kind == RS_SHADOW_SPOT;
    const __m256 zero = _mm256_setzero_ps(), one = _mm256_set1_ps(1.0f), sign = _mm256_set1_ps(-0.0f);
    const __m256 p_x = _mm256_loadu_ps(px), p_y = _mm256_loadu_ps(py), p_z = _mm256_loadu_ps(pz);
    const __m256i bits = _mm256_setr_epi32(1, 2, 4, 8, 16, 32, 64, 128);
    const __m256 lane_on =
        _mm256_castsi256_ps(_mm256_cmpeq_epi32(_mm256_and_si256(bits, _mm256_set1_epi32((int)active)), bits));

    /* rs__face: v = p - eye; the cube face of the major axis of v (ties to
     * x, then y, then z; a NaN falls through to z like the scalar code),
     * and the depth along the face's axis. */
    __m256 v_x = _mm256_sub_ps(p_x, _mm256_set1_ps(m->eye.x));
    __m256 v_y = _mm256_sub_ps(p_y, _mm256_set1_ps(m->eye.y));
    __m256 v_z = _mm256_sub_ps(p_z, _mm256_set1_ps(m->eye.z));
    __m256i face = _mm256_setzero_si256();
    if (cube) {
        __m256 ax = _mm256_andnot_ps(sign, v_x), ay = _mm256_andnot_ps(sign, v_y), az = _mm256_andnot_ps(sign, v_z);
        __m256 is_x = _mm256_and_ps(_mm256_cmp_ps(ax, ay, _CMP_GE_OQ), _mm256_cmp_ps(ax, az, _CMP_GE_OQ));
        __m256 is_y = _mm256_cmp_ps(ay, az, _CMP_GE_OQ);
        /* v >= 0 ? 2a : 2a + 1 (a compare's true is -1) */
        __m256i f_x = _mm256_add_epi32(_mm256_set1_epi32(1), _mm256_castps_si256(_mm256_cmp_ps(v_x, zero, _CMP_GE_OQ)));
        __m256i f_y = _mm256_add_epi32(_mm256_set1_epi32(3), _mm256_castps_si256(_mm256_cmp_ps(v_y, zero, _CMP_GE_OQ)));
        __m256i f_z = _mm256_add_epi32(_mm256_set1_epi32(5), _mm256_castps_si256(_mm256_cmp_ps(v_z, zero, _CMP_GE_OQ)));
        __m256 fyz = _mm256_blendv_ps(_mm256_castsi256_ps(f_z), _mm256_castsi256_ps(f_y), is_y);
        face = _mm256_castps_si256(_mm256_blendv_ps(fyz, _mm256_castsi256_ps(f_x), is_x));
    }
    /* the face's constants: broadcast when the 8 points share a face (the
     * usual case), gathered per lane otherwise */
    const int f0 = _mm256_cvtsi256_si32(face);
    const int one_face = _mm256_movemask_epi8(_mm256_cmpeq_epi32(face, _mm256_set1_epi32(f0))) == -1;
    const int gather = cube && !one_face;
    const int fb = gather ? 0 : f0;
    const __m256i off3 = _mm256_mullo_epi32(face, _mm256_set1_epi32(3));
    const __m256i off16 = _mm256_slli_epi32(face, 4);
    const float *fwd = &m->forward[fb].x, *rgt = &m->right[fb].x, *upv = &m->up[fb].x, *vp = m->view_proj[fb].m;
    __m256 f_x = rs__face_val8(fwd, gather, off3, 0), f_y = rs__face_val8(fwd, gather, off3, 1);
    __m256 f_z = rs__face_val8(fwd, gather, off3, 2);
    __m256 depth = rs__dot8(v_x, v_y, v_z, f_x, f_y, f_z);

    /* l (unit, towards the light) and texel (world size of a texel at p) */
    __m256 l_x, l_y, l_z, texel, behind = zero;
    if (ortho) {
        pf_vec3 l = pf_v3_scale(m->forward[0], -1.0f);
        l_x = _mm256_set1_ps(l.x);
        l_y = _mm256_set1_ps(l.y);
        l_z = _mm256_set1_ps(l.z);
        texel = _mm256_set1_ps(2.0f * fmaxf(m->half_w, m->half_h) / (float)m->size);
    } else {
        behind = _mm256_cmp_ps(depth, zero, _CMP_NGT_UQ); /* !(depth > 0) */
        __m256 d_x = _mm256_sub_ps(_mm256_set1_ps(m->eye.x), p_x);
        __m256 d_y = _mm256_sub_ps(_mm256_set1_ps(m->eye.y), p_y);
        __m256 d_z = _mm256_sub_ps(_mm256_set1_ps(m->eye.z), p_z);
        __m256 len = _mm256_sqrt_ps(rs__dot8(d_x, d_y, d_z, d_x, d_y, d_z));
        __m256 inv = _mm256_div_ps(one, len), ok = _mm256_cmp_ps(len, zero, _CMP_GT_OQ);
        l_x = _mm256_and_ps(ok, _mm256_mul_ps(d_x, inv));
        l_y = _mm256_and_ps(ok, _mm256_mul_ps(d_y, inv));
        l_z = _mm256_and_ps(ok, _mm256_mul_ps(d_z, inv));
        /* a power-of-two size divides exactly as a multiplication by its
         * reciprocal (also exact), which is cheaper */
        __m256 t2d = _mm256_mul_ps(_mm256_set1_ps(2.0f * m->tan_half), depth);
        texel = (m->size & (m->size - 1)) == 0 ? _mm256_mul_ps(t2d, _mm256_set1_ps(1.0f / (float)m->size))
                                               : _mm256_div_ps(t2d, _mm256_set1_ps((float)m->size));
    }

    /* n: unit geometric normal (l where it has none); the slope and bias */
    const __m256 g_x = _mm256_loadu_ps(ngx), g_y = _mm256_loadu_ps(ngy), g_z = _mm256_loadu_ps(ngz);
    __m256 nlen = _mm256_sqrt_ps(rs__dot8(g_x, g_y, g_z, g_x, g_y, g_z));
    __m256 ninv = _mm256_div_ps(one, nlen), has_n = _mm256_cmp_ps(nlen, zero, _CMP_GT_OQ);
    __m256 n_x = _mm256_blendv_ps(l_x, _mm256_mul_ps(g_x, ninv), has_n);
    __m256 n_y = _mm256_blendv_ps(l_y, _mm256_mul_ps(g_y, ninv), has_n);
    __m256 n_z = _mm256_blendv_ps(l_z, _mm256_mul_ps(g_z, ninv), has_n);
    __m256 cos_t = _mm256_andnot_ps(sign, rs__dot8(n_x, n_y, n_z, l_x, l_y, l_z));
    /* fmaxf(0, v): max_ps returns its second operand for a NaN, like fmaxf */
    __m256 sin_t = _mm256_sqrt_ps(_mm256_max_ps(_mm256_sub_ps(one, _mm256_mul_ps(cos_t, cos_t)), zero));
    const float tan_max_s = m->desc.tan_max > 0.0f ? m->desc.tan_max : RS_SHADOW_TAN_MAX;
    const __m256 tan_max = _mm256_set1_ps(tan_max_s);
    __m256 tmax_cos = _mm256_mul_ps(tan_max, cos_t);
    __m256 capped = _mm256_cmp_ps(sin_t, tmax_cos, _CMP_NLT_UQ); /* !(sin_t < tan_max cos_t) */
    __m256 tan_t = _mm256_blendv_ps(_mm256_div_ps(sin_t, cos_t), tan_max, capped);
    float b_const = m->desc.bias_const > 0.0f ? m->desc.bias_const : RS_SHADOW_BIAS_CONST;
    float b_slope = m->desc.bias_slope > 0.0f ? m->desc.bias_slope : RS_SHADOW_BIAS_SLOPE;
    __m256 bias =
        _mm256_mul_ps(texel, _mm256_add_ps(_mm256_set1_ps(b_const), _mm256_mul_ps(_mm256_set1_ps(b_slope), tan_t)));

    /* project with the face's matrix: c[r] = m[r] x + m[4+r] y + m[8+r] z + m[12+r] */
    __m256 c[4];
    for (int r = 0; r < 4; r++) {
        __m256 acc = _mm256_mul_ps(rs__face_val8(vp, gather, off16, r), p_x);
        acc = _mm256_add_ps(acc, _mm256_mul_ps(rs__face_val8(vp, gather, off16, 4 + r), p_y));
        acc = _mm256_add_ps(acc, _mm256_mul_ps(rs__face_val8(vp, gather, off16, 8 + r), p_z));
        c[r] = _mm256_add_ps(acc, rs__face_val8(vp, gather, off16, 12 + r));
    }
    const float s_s = (float)m->size;
    const __m256 s = _mm256_set1_ps(s_s);
    __m256 nr = rs__dot8(n_x, n_y, n_z, rs__face_val8(rgt, gather, off3, 0), rs__face_val8(rgt, gather, off3, 1),
                         rs__face_val8(rgt, gather, off3, 2));
    __m256 nu = rs__dot8(n_x, n_y, n_z, rs__face_val8(upv, gather, off3, 0), rs__face_val8(upv, gather, off3, 1),
                         rs__face_val8(upv, gather, off3, 2));
    __m256 cap = _mm256_blendv_ps(one, _mm256_div_ps(tmax_cos, sin_t),
                                  _mm256_and_ps(capped, _mm256_cmp_ps(sin_t, zero, _CMP_GT_OQ)));
    __m256 x, y, zs_p, zs_bias, k, lit_early = zero, unlit_early = zero;
    if (ortho) {
        x = c[0];
        y = c[1];
        zs_p = c[2];
        __m256 inside = _mm256_and_ps(_mm256_cmp_ps(_mm256_andnot_ps(sign, x), one, _CMP_LE_OQ),
                                      _mm256_cmp_ps(_mm256_andnot_ps(sign, y), one, _CMP_LE_OQ));
        inside = _mm256_and_ps(inside, _mm256_and_ps(_mm256_cmp_ps(zs_p, zero, _CMP_GE_OQ),
                                                     _mm256_cmp_ps(zs_p, one, _CMP_LE_OQ)));
        lit_early = _mm256_andnot_ps(inside, _mm256_castsi256_ps(_mm256_set1_epi32(-1)));
        float inv_range = 1.0f / (m->zfar - m->znear);
        zs_bias = _mm256_mul_ps(bias, _mm256_set1_ps(inv_range));
        __m256 nf = rs__dot8(n_x, n_y, n_z, f_x, f_y, f_z);
        k = _mm256_mul_ps(_mm256_div_ps(_mm256_set1_ps(2.0f * inv_range), _mm256_mul_ps(s, nf)), cap);
        k = _mm256_and_ps(_mm256_cmp_ps(nf, zero, _CMP_NEQ_UQ), k);
        nr = _mm256_mul_ps(nr, _mm256_set1_ps(m->half_w));
        nu = _mm256_mul_ps(nu, _mm256_set1_ps(m->half_h));
    } else {
        x = _mm256_div_ps(c[0], c[3]);
        y = _mm256_div_ps(c[1], c[3]);
        zs_p = _mm256_div_ps(c[2], c[3]);
        __m256 wb = _mm256_sub_ps(c[3], bias);
        lit_early = _mm256_cmp_ps(wb, c[2], _CMP_NGT_UQ); /* !(wb > c2): nearer than znear */
        if (spot) {
            __m256 inside = _mm256_and_ps(_mm256_cmp_ps(_mm256_andnot_ps(sign, x), one, _CMP_LE_OQ),
                                          _mm256_cmp_ps(_mm256_andnot_ps(sign, y), one, _CMP_LE_OQ));
            unlit_early = _mm256_andnot_ps(inside, _mm256_castsi256_ps(_mm256_set1_epi32(-1)));
        }
        zs_bias = _mm256_sub_ps(_mm256_div_ps(c[2], wb), zs_p);
        __m256 d = rs__dot8(n_x, n_y, n_z, v_x, v_y, v_z);
        k = _mm256_mul_ps(_mm256_div_ps(_mm256_set1_ps(2.0f * m->znear * m->tan_half), _mm256_mul_ps(s, d)), cap);
        k = _mm256_and_ps(_mm256_cmp_ps(d, zero, _CMP_NEQ_UQ), k);
    }
    __m256 gx = _mm256_mul_ps(k, nr), gy = _mm256_mul_ps(_mm256_xor_ps(k, sign), nu);

    /* NDC to texels, clamped (max_ps drops a NaN as fmaxf does) */
    const __m256 half = _mm256_set1_ps(0.5f), lo = _mm256_set1_ps(-8.0f), hi = _mm256_set1_ps(s_s + 8.0f);
    __m256 fx = _mm256_min_ps(_mm256_max_ps(_mm256_mul_ps(_mm256_add_ps(_mm256_mul_ps(half, x), half), s), lo), hi);
    __m256 fy = _mm256_min_ps(_mm256_max_ps(_mm256_mul_ps(_mm256_sub_ps(half, _mm256_mul_ps(half, y)), s), lo), hi);
    const int n = pcf ? 4 : 1;
    const __m256 start = _mm256_set1_ps(pcf ? 1.5f : 0.0f);
    __m256i x0 = _mm256_cvttps_epi32(_mm256_floor_ps(pcf ? _mm256_sub_ps(fx, start) : fx));
    __m256i y0 = _mm256_cvttps_epi32(_mm256_floor_ps(pcf ? _mm256_sub_ps(fy, start) : fy));

    /* rs__pcf: count the taps whose stored zs is no nearer than the
     * receiver's plane at the tap's texel centre plus the bias */
    const __m256i last = _mm256_set1_epi32((int)m->size - 1), izero = _mm256_setzero_si256();
    const __m256i size_i = _mm256_set1_epi32((int)m->size);
    const __m256i plane_off = _mm256_mullo_epi32(face, _mm256_set1_epi32((int)(m->size * m->size)));
    __m256i lit = _mm256_setzero_si256();
    for (int j = 0; j < n; j++) {
        __m256i yy = _mm256_add_epi32(y0, _mm256_set1_epi32(j));
        __m256i yc = _mm256_min_epi32(_mm256_max_epi32(yy, izero), last);
        __m256i row = _mm256_add_epi32(plane_off, _mm256_mullo_epi32(yc, size_i));
        __m256 ty = _mm256_sub_ps(_mm256_add_ps(_mm256_cvtepi32_ps(yy), half), fy);
        __m256 zy = _mm256_add_ps(_mm256_add_ps(zs_p, _mm256_mul_ps(gy, ty)), zs_bias);
        for (int i = 0; i < n; i++) {
            __m256i xx = _mm256_add_epi32(x0, _mm256_set1_epi32(i));
            __m256i xc = _mm256_min_epi32(_mm256_max_epi32(xx, izero), last);
            __m256 tap = _mm256_mask_i32gather_ps(zero, m->depth, _mm256_add_epi32(row, xc), lane_on, 4);
            __m256 tx = _mm256_sub_ps(_mm256_add_ps(_mm256_cvtepi32_ps(xx), half), fx);
            __m256 le = _mm256_cmp_ps(tap, _mm256_add_ps(zy, _mm256_mul_ps(gx, tx)), _CMP_LE_OQ);
            lit = _mm256_sub_epi32(lit, _mm256_castps_si256(le));
        }
    }
    /* lit / (n n): n n is 16 or 1, so the multiplication by 1/16 or 1 is the
     * same exact operation */
    __m256 vis = _mm256_mul_ps(_mm256_cvtepi32_ps(lit), _mm256_set1_ps(pcf ? 0.0625f : 1.0f));

    /* the scalar code's early returns, latest first */
    vis = _mm256_blendv_ps(vis, one, lit_early);
    vis = _mm256_blendv_ps(vis, zero, unlit_early);
    if (!ortho) vis = _mm256_blendv_ps(vis, spot ? zero : one, behind);
    _mm256_storeu_ps(out, _mm256_and_ps(vis, lane_on));
}
#endif

void rs_shadow_visibility8(const rs_shadow_map *m, rs_simd simd, const float *px, const float *py, const float *pz,
                           const float *ngx, const float *ngy, const float *ngz, unsigned active, float *out)
{
#if defined(__x86_64__) || defined(__i386__)
    uint64_t texels = (uint64_t)m->face_count * m->size * m->size;
    if (simd != RS_SIMD_SCALAR && m->depth && m->size > 0 && texels < ((uint64_t)1 << 31) &&
        !(m->desc.normal_offset > 0.0f)) {
        rs__visibility8_avx2(m, px, py, pz, ngx, ngy, ngz, active, out);
        return;
    }
#else
    (void)simd;
#endif
    for (int i = 0; i < 8; i++)
        out[i] = (active >> i) & 1u ? rs_shadow_visibility(m, pf_v3(px[i], py[i], pz[i]), pf_v3(ngx[i], ngy[i], ngz[i]))
                                    : 0.0f;
}
