/* gi_rsm: reflective shadow maps (Dachsbacher and Stamminger 2005; Barak
 * 2013 Sec. 3: "we create reflective shadow map (RSM) for each primary light
 * source ... stored as g-buffers"). Conventions and units are in gi_rsm.h.
 *
 * Per update, for every light whose map is stale:
 *   1. gi__rsm_layout     map kind, axes and matrices, texel solid angles;
 *   2. gi__rsm_rasterize  rs_render of each face: a visibility buffer
 *                         (triangle per texel) from the light;
 *   3. gi__rsm_resolve    per texel: the ray through the texel centre meets
 *                         the triangle's plane (barycentrics, clamped to the
 *                         triangle as rs_gbuffer_resolve does), the surface
 *                         (pf_scene_surface, texture LOD from the neighbour
 *                         texels' footprint) and the reflected flux.
 * Once per scene (emitters do not move): the area lights' map (gi_rsm_area.h;
 * laid out by gi_rsm_area_layout, traced and resolved by
 * gi_rsm_area_render). */
#include "gi_rsm.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "gi_light.h"
#include "gi_rsm_area.h"
#include "gi_vpl.h"
#include "pf_isa.h"
#include "rs_shadow.h"

/* Cube faces, as rs_shadow.c: forward axis and up hint. */
static const float gi__cube_axes[6][2][3] = {
    {{1, 0, 0}, {0, -1, 0}},  {{-1, 0, 0}, {0, -1, 0}}, {{0, 1, 0}, {0, 0, 1}},
    {{0, -1, 0}, {0, 0, -1}}, {{0, 0, 1}, {0, -1, 0}},  {{0, 0, -1}, {0, -1, 0}},
};

static pf_vec3 gi__v3(const float a[3]) { return pf_v3(a[0], a[1], a[2]); }

void gi_rsm_set_init(gi_rsm_set *set, uint32_t size)
{
    memset(set, 0, sizeof *set);
    set->size = size ? size : GI_RSM_DEFAULT_SIZE;
}

static void gi__rsm_free_planes(gi_rsm_set *s)
{
    float **planes[] = {&s->pos_x, &s->pos_y, &s->pos_z, &s->nrm_x, &s->nrm_y, &s->nrm_z, &s->ng_x,
                        &s->ng_y,  &s->ng_z,  &s->flux_r, &s->flux_g, &s->flux_b, &s->depth_};
    for (size_t k = 0; k < sizeof planes / sizeof planes[0]; k++) {
        free(*planes[k]);
        *planes[k] = NULL;
    }
    free(s->valid);
    free(s->prim);
    s->valid = NULL;
    s->prim = NULL;
    for (uint32_t m = 0; m < s->count; m++) {
        free(s->maps[m].solid_angle);
        free(s->maps[m].faces);
    }
    free(s->maps);
    s->maps = NULL;
    s->count = 0;
    s->punctual = 0;
    s->texel_count = 0;
    s->area_ = NULL;
    s->area_rendered_ = 0;
}

void gi_rsm_set_free(gi_rsm_set *set)
{
    gi__rsm_free_planes(set);
    free(set->lights_);
    set->lights_ = NULL;
    if (set->raster_) rs_context_destroy(set->raster_);
    set->raster_ = NULL;
}

uint32_t gi_rsm_map_of(const gi_rsm_set *set, uint32_t t)
{
    uint32_t lo = 0, hi = set->count;
    while (hi - lo > 1) {
        uint32_t mid = (lo + hi) / 2;
        if (set->maps[mid].first <= t)
            lo = mid;
        else
            hi = mid;
    }
    return lo;
}

/* ------------------------------------------------------------- 1. layout */

/* Solid angle of the rectangle [0, x] x [0, y] on the plane at distance 1
 * seen from the origin: atan(x y / sqrt(1 + x^2 + y^2)) (signed). A texel
 * [x0, x1] x [y0, y1] then has the exact solid angle
 *   A(x1, y1) - A(x0, y1) - A(x1, y0) + A(x0, y0). */
static double gi__rect_sa(double x, double y) { return atan(x * y / sqrt(1.0 + x * x + y * y)); }

static pf_result gi__rsm_solid_angles(gi_rsm_map *m, pf_error *err)
{
    if (!m->solid_angle) m->solid_angle = malloc((size_t)m->size * m->size * sizeof(float));
    if (!m->solid_angle) return pf_error_set(err, PF_ERR_OUT_OF_MEMORY, "out of memory for an RSM");
    double t = m->tan_half, n = m->size;
    for (uint32_t y = 0; y < m->size; y++) {
        double y0 = t * (1.0 - 2.0 * (y + 1) / n), y1 = t * (1.0 - 2.0 * y / n);
        for (uint32_t x = 0; x < m->size; x++) {
            double x0 = t * (2.0 * x / n - 1.0), x1 = t * (2.0 * (x + 1) / n - 1.0);
            double sa = gi__rect_sa(x1, y1) - gi__rect_sa(x0, y1) - gi__rect_sa(x1, y0) + gi__rect_sa(x0, y0);
            m->solid_angle[(size_t)y * m->size + x] = (float)sa;
        }
    }
    return PF_OK;
}

static void gi__rsm_axes(gi_rsm_map *m, uint32_t f, pf_vec3 up_hint)
{
    m->right[f] = pf_v3_normalize(pf_v3_cross(m->forward[f], up_hint));
    m->up[f] = pf_v3_cross(m->right[f], m->forward[f]);
}

/* Kind, axes and matrices of light L's map (rs_shadow.c's set-up without
 * the PCF margin). */
static void gi__rsm_layout(gi_rsm_map *m, const pf_scene *s, const pf_light *L)
{
    pf_vec3 ext = pf_v3_sub(s->bounds_max, s->bounds_min);
    if (L->type == PF_LIGHT_DIRECTIONAL) {
        m->kind = GI_RSM_ORTHO;
        m->face_count = 1;
        pf_vec3 f = pf_v3_normalize(L->direction), t, b;
        pf_v3_basis(f, &t, &b);
        pf_vec3 c = pf_v3_scale(pf_v3_add(s->bounds_min, s->bounds_max), 0.5f);
        pf_vec3 e = pf_v3_scale(ext, 0.5f);
        float et = fabsf(t.x) * e.x + fabsf(t.y) * e.y + fabsf(t.z) * e.z;
        float eb = fabsf(b.x) * e.x + fabsf(b.y) * e.y + fabsf(b.z) * e.z;
        float ef = fabsf(f.x) * e.x + fabsf(f.y) * e.y + fabsf(f.z) * e.z;
        float floor_ext = 1.0e-4f * pf_v3_max_comp(e) + 1.0e-6f;
        et = fmaxf(et, floor_ext), eb = fmaxf(eb, floor_ext), ef = fmaxf(ef, floor_ext);
        float pad = 0.05f * ef;
        m->eye = pf_v3_sub(c, pf_v3_scale(f, ef + 2.0f * pad));
        m->znear = pad;
        m->zfar = 2.0f * ef + 3.0f * pad;
        m->half_w = et * 1.001f; /* a hair wider so the bounds' edges are inside */
        m->half_h = eb * 1.001f;
        m->forward[0] = f;
        gi__rsm_axes(m, 0, b);
        m->view_proj[0] = rs_mat4_ortho(m->eye, f, b, m->half_w, m->half_h, m->znear, m->zfar);
        return;
    }
    m->eye = L->position;
    m->znear = fmaxf(1.0e-4f * pf_v3_length(ext), 1.0e-6f);
    m->zfar = 0.0f;
    if (L->type == PF_LIGHT_SPOT && L->outer_cone <= RS_SHADOW_SPOT_MAX_CONE) {
        m->kind = GI_RSM_SPOT;
        m->face_count = 1;
        pf_vec3 f = pf_v3_normalize(L->direction), t, b;
        pf_v3_basis(f, &t, &b);
        m->tan_half = tanf(pf_clampf(L->outer_cone, 1.0e-3f, RS_SHADOW_SPOT_MAX_CONE));
        m->forward[0] = f;
        gi__rsm_axes(m, 0, b);
        m->view_proj[0] = rs_mat4_perspective(m->eye, f, b, 2.0f * atanf(m->tan_half), 1.0f, m->znear);
        return;
    }
    m->kind = GI_RSM_CUBE;
    m->face_count = 6;
    m->tan_half = 1.0f;
    for (uint32_t f = 0; f < 6; f++) {
        m->forward[f] = gi__v3(gi__cube_axes[f][0]);
        gi__rsm_axes(m, f, gi__v3(gi__cube_axes[f][1]));
        m->view_proj[f] = rs_mat4_perspective(m->eye, m->forward[f], gi__v3(gi__cube_axes[f][1]),
                                              2.0f * atanf(1.0f), 1.0f, m->znear);
    }
}

pf_vec3 gi_rsm_light_power(const gi_rsm_map *m, const pf_light *L)
{
    if (m->kind == GI_RSM_AREA) return m->power;
    pf_vec3 c = pf_v3_scale(L->color, L->intensity);
    if (m->kind == GI_RSM_ORTHO) return pf_v3_scale(c, 4.0f * m->half_w * m->half_h);
    if (L->type == PF_LIGHT_POINT) return pf_v3_scale(c, 4.0f * PF_PI);
    /* spot: 2 pi int_{cos outer}^{1} t(c)^2 dc with t linear in c between
     * cos outer and cos inner: (ci - co) / 3 + (1 - ci), the cone factor's
     * denominator max(0.001, ci - co) taken into account. */
    double co = cos((double)L->outer_cone), ci = cos((double)L->inner_cone), d = fmax(0.001, ci - co);
    double integral;
    if (ci - co >= 0.001)
        integral = (ci - co) / 3.0 + (1.0 - ci);
    else /* t reaches 1 at co + d */
        integral = d / 3.0 + (1.0 - fmin(1.0, co + d));
    return pf_v3_scale(c, (float)(2.0 * PF_PI * integral));
}

/* Allocates the planes for the scene's lights and, when `area` has
 * emitters, the area lights' map after them (called when the layout
 * changes: the light count, a light's kind or the emitters). */
static pf_result gi__rsm_allocate(gi_rsm_set *s, const pf_scene *scene, const gi_area_lights *area, pf_error *err)
{
    gi__rsm_free_planes(s);
    uint32_t n = scene->light_count, with_area = area && area->count > 0;
    s->maps = calloc((n + with_area) ? (n + with_area) : 1, sizeof *s->maps);
    if (!s->maps) return pf_error_set(err, PF_ERR_OUT_OF_MEMORY, "out of memory for RSMs");
    s->count = n + with_area;
    s->punctual = n;
    uint64_t total = 0;
    for (uint32_t l = 0; l < n; l++) {
        gi_rsm_map *m = &s->maps[l];
        m->light = l;
        m->size = s->size;
        gi__rsm_layout(m, scene, &scene->lights[l]);
        m->first = (uint32_t)total;
        m->texel_count = m->face_count * s->size * s->size;
        total += m->texel_count;
    }
    if (with_area) {
        gi_rsm_map *m = &s->maps[n];
        pf_result r = gi_rsm_area_layout(m, area, s->area_points, s->size, err);
        if (r != PF_OK) return r;
        m->first = (uint32_t)total;
        total += m->texel_count;
        s->area_ = area;
    }
    if (total > 0x7fffffffu) return pf_error_set(err, PF_ERR_ARGUMENT, "RSMs of %llu texels are too large",
                                                 (unsigned long long)total);
    s->texel_count = (uint32_t)total;
    size_t T = total ? (size_t)total : 1;
    float **planes[] = {&s->pos_x, &s->pos_y, &s->pos_z, &s->nrm_x, &s->nrm_y, &s->nrm_z, &s->ng_x,
                        &s->ng_y,  &s->ng_z,  &s->flux_r, &s->flux_g, &s->flux_b, &s->depth_};
    for (size_t k = 0; k < sizeof planes / sizeof planes[0]; k++)
        if (!(*planes[k] = calloc(T, sizeof(float))))
            return pf_error_set(err, PF_ERR_OUT_OF_MEMORY, "out of memory for RSMs");
    s->valid = calloc(T, 1);
    s->prim = calloc(T, sizeof(uint32_t));
    if (!s->valid || !s->prim) return pf_error_set(err, PF_ERR_OUT_OF_MEMORY, "out of memory for RSMs");
    return PF_OK;
}

/* ---------------------------------------------------------- 2. rasterize */

static void gi__rsm_rasterize(gi_rsm_set *s, const gi_rsm_map *m)
{
    size_t face = (size_t)m->size * m->size;
    for (uint32_t f = 0; f < m->face_count; f++) {
        /* cull nothing: single-sided walls and open meshes reflect from both sides */
        rs_pass pass = {.view_proj = m->view_proj[f], .cull = RS_CULL_NONE};
        size_t o = m->first + f * face;
        rs_target target = {.width = m->size, .height = m->size, .depth = s->depth_ + o, .prim = s->prim + o};
        rs_render(s->raster_, &pass, &target, NULL);
    }
}

/* ------------------------------------------------------------ 3. resolve */

typedef struct gi__rsm_resolve_ctx {
    gi_rsm_set *set;
    const pf_scene *scene;
    uint32_t map; /* rows of this map are the job's items (face_count * size) */
} gi__rsm_resolve_ctx;

/* The ray through NDC (x, y) of face f. */
static void gi__rsm_ray(const gi_rsm_map *m, uint32_t f, float x, float y, pf_vec3 *o, pf_vec3 *d)
{
    if (m->kind == GI_RSM_ORTHO) {
        *o = pf_v3_add(m->eye, pf_v3_add(pf_v3_scale(m->right[f], x * m->half_w), pf_v3_scale(m->up[f], y * m->half_h)));
        *d = m->forward[f];
    } else {
        *o = m->eye;
        *d = pf_v3_add(m->forward[f],
                       pf_v3_add(pf_v3_scale(m->right[f], x * m->tan_half), pf_v3_scale(m->up[f], y * m->tan_half)));
    }
}

/* Unclamped barycentrics (weights of vertices 1 and 2) where the ray o + t d
 * meets the plane of the triangle p0, p0 + e1, p0 + e2 (Moeller-Trumbore). */
static int gi__rsm_bary(pf_vec3 p0, pf_vec3 e1, pf_vec3 e2, pf_vec3 o, pf_vec3 d, float *u, float *v)
{
    pf_vec3 pv = pf_v3_cross(d, e2);
    float det = pf_v3_dot(e1, pv);
    if (det == 0.0f) return 0;
    float inv = 1.0f / det;
    pf_vec3 tv = pf_v3_sub(o, p0);
    *u = pf_v3_dot(tv, pv) * inv;
    pf_vec3 qv = pf_v3_cross(tv, e1);
    *v = pf_v3_dot(d, qv) * inv;
    return 1;
}

static void gi__rsm_resolve_row(void *p, uint32_t row, uint32_t worker)
{
    (void)worker;
    const gi__rsm_resolve_ctx *rc = p;
    gi_rsm_set *s = rc->set;
    const pf_scene *sc = rc->scene;
    const gi_rsm_map *m = &s->maps[rc->map];
    const pf_light *L = &sc->lights[m->light];
    uint32_t n = m->size, f = row / n, y = row % n;
    float texel = 2.0f / (float)n;
    float cos_outer = cosf(L->outer_cone);
    for (uint32_t x = 0; x < n; x++) {
        size_t i = m->first + (size_t)row * n + x;
        uint32_t prim = s->prim[i];
        s->valid[i] = 0;
        s->pos_x[i] = s->pos_y[i] = s->pos_z[i] = 0.0f;
        s->nrm_x[i] = s->nrm_y[i] = s->nrm_z[i] = 0.0f;
        s->ng_x[i] = s->ng_y[i] = s->ng_z[i] = 0.0f;
        s->flux_r[i] = s->flux_g[i] = s->flux_b[i] = 0.0f;
        if (prim == RS_NO_PRIM) continue;
        float nx = ((float)x + 0.5f) * texel - 1.0f, ny = 1.0f - ((float)y + 0.5f) * texel;
        pf_vec3 o, d;
        gi__rsm_ray(m, f, nx, ny, &o, &d);
        /* the light's flux into the texel (before the surface's albedo) */
        float recv;
        if (m->kind == GI_RSM_ORTHO) {
            recv = L->intensity * (texel * m->half_w) * (texel * m->half_h);
        } else {
            float cone = 1.0f;
            if (L->type == PF_LIGHT_SPOT) {
                float ct = pf_v3_dot(pf_v3_normalize(d), pf_v3_normalize(L->direction));
                cone = ct > cos_outer ? gi_light_spot_factor(L, ct) : 0.0f;
            }
            recv = L->intensity * cone * m->solid_angle[(size_t)y * n + x];
        }
        if (!(recv > 0.0f)) continue;
        const uint32_t *tri = &sc->indices[3 * prim];
        pf_vec3 p0 = sc->positions[tri[0]];
        pf_vec3 e1 = pf_v3_sub(sc->positions[tri[1]], p0), e2 = pf_v3_sub(sc->positions[tri[2]], p0);
        float u = 0.0f, v = 0.0f;
        if (!gi__rsm_bary(p0, e1, e2, o, d, &u, &v)) continue; /* edge-on: the texel sees no area */
        /* texture LOD from the neighbouring texel centres' rays (rs_gbuffer_resolve's footprint) */
        float lod = 0.0f;
        uint32_t mat = sc->tri_material[prim];
        if (sc->materials[mat].base_color_texture >= 0) {
            pf_vec3 ox, dx, oy, dy;
            float ux, vx, uy, vy;
            gi__rsm_ray(m, f, nx + texel, ny, &ox, &dx);
            gi__rsm_ray(m, f, nx, ny - texel, &oy, &dy);
            if (gi__rsm_bary(p0, e1, e2, ox, dx, &ux, &vx) && gi__rsm_bary(p0, e1, e2, oy, dy, &uy, &vy)) {
                pf_vec2 uv0 = sc->uvs[tri[0]], uv1 = sc->uvs[tri[1]], uv2 = sc->uvs[tri[2]];
                float du1 = uv1.x - uv0.x, du2 = uv2.x - uv0.x, dv1 = uv1.y - uv0.y, dv2 = uv2.y - uv0.y;
                lod = pf_material_lod(sc, mat, du1 * (ux - u) + du2 * (vx - v), dv1 * (ux - u) + dv2 * (vx - v),
                                      du1 * (uy - u) + du2 * (vy - v), dv1 * (uy - u) + dv2 * (vy - v));
            }
        }
        u = pf_clampf(u, 0.0f, 1.0f);
        v = pf_clampf(v, 0.0f, 1.0f);
        if (u + v > 1.0f) {
            float sum = u + v;
            u /= sum;
            v /= sum;
        }
        pf_surface sf;
        /* a texel is a VPL site: at least gi_vpl.h's blurred level */
        pf_scene_surface(sc, prim, u, v, lod > GI_VPL_ALBEDO_LOD ? lod : GI_VPL_ALBEDO_LOD, &sf);
        /* two-sided: both normals face the light */
        pf_vec3 ng = sf.ng, ns = sf.ns;
        if (pf_v3_dot(ng, d) > 0.0f) ng = pf_v3_scale(ng, -1.0f);
        if (pf_v3_dot(ns, ng) < 0.0f) ns = pf_v3_scale(ns, -1.0f);
        s->valid[i] = 1;
        s->pos_x[i] = sf.p.x, s->pos_y[i] = sf.p.y, s->pos_z[i] = sf.p.z;
        s->nrm_x[i] = ns.x, s->nrm_y[i] = ns.y, s->nrm_z[i] = ns.z;
        s->ng_x[i] = ng.x, s->ng_y[i] = ng.y, s->ng_z[i] = ng.z;
        s->flux_r[i] = recv * L->color.x * sf.albedo[0];
        s->flux_g[i] = recv * L->color.y * sf.albedo[1];
        s->flux_b[i] = recv * L->color.z * sf.albedo[2];
    }
}

static void gi__rsm_resolve(gi_rsm_set *s, const pf_scene *scene, pf_jobs *jobs, uint32_t map)
{
    gi__rsm_resolve_ctx rc = {s, scene, map};
    const gi_rsm_map *m = &s->maps[map];
    pf_jobs_parallel_for(jobs, gi__rsm_resolve_row, &rc, m->face_count * m->size, 0);
}

/* ------------------------------------------------------------------ update */

static int gi__light_same(const pf_light *a, const pf_light *b)
{
    return a->type == b->type && !memcmp(&a->position, &b->position, sizeof a->position) &&
           !memcmp(&a->direction, &b->direction, sizeof a->direction) &&
           !memcmp(&a->color, &b->color, sizeof a->color) && a->intensity == b->intensity &&
           a->inner_cone == b->inner_cone && a->outer_cone == b->outer_cone;
}

/* Fails on an RSM size or area point count out of range, a non-finite
 * light, or a spot/directional light without a direction. */
static pf_result gi__rsm_check(const gi_rsm_set *s, const pf_scene *scene, pf_error *err)
{
    if (s->size < GI_RSM_MIN_SIZE || s->size > GI_RSM_MAX_SIZE)
        return pf_error_set(err, PF_ERR_ARGUMENT, "RSM size %u is outside [%u, %u]", s->size, GI_RSM_MIN_SIZE,
                            GI_RSM_MAX_SIZE);
    if (s->area_points < 1 || s->area_points > GI_RSM_MAX_AREA_POINTS)
        return pf_error_set(err, PF_ERR_ARGUMENT, "RSM area points %u are outside [1, %u]", s->area_points,
                            GI_RSM_MAX_AREA_POINTS);
    for (uint32_t l = 0; l < scene->light_count; l++) {
        const pf_light *L = &scene->lights[l];
        if (!pf_v3_is_finite(L->position) || !pf_v3_is_finite(L->direction) || !isfinite(L->intensity) ||
            !pf_v3_is_finite(L->color) || !isfinite(L->outer_cone) || !isfinite(L->inner_cone))
            return pf_error_set(err, PF_ERR_NONFINITE, "light %u (%s) is not finite", l, L->name);
        if (L->type != PF_LIGHT_POINT && pf_v3_length(L->direction) == 0.0f)
            return pf_error_set(err, PF_ERR_ARGUMENT, "light %u (%s) has no direction", l, L->name);
    }
    return PF_OK;
}

/* 1 when the set's area map is the one `area` asks for (none, or laid out
 * for these emitters with the set's point count). */
static int gi__rsm_area_same(const gi_rsm_set *s, const gi_area_lights *area)
{
    int want = area && area->count > 0, have = s->maps && s->count > s->punctual;
    if (!want || !have) return want == have;
    return s->area_ == area && s->maps[s->punctual].face_count == s->area_points;
}

/* Renders the punctual lights' maps for scene->lights (their layout is
 * current). */
static pf_result gi__rsm_render_punctual(gi_rsm_set *s, const pf_scene *scene, pf_jobs *jobs, pf_error *err)
{
    pf_result r;
    for (uint32_t m = 0; m < s->punctual; m++) {
        gi_rsm_map *mp = &s->maps[m];
        float old_tan = mp->tan_half;
        gi__rsm_layout(mp, scene, &scene->lights[m]);
        if (mp->kind != GI_RSM_ORTHO && (!mp->solid_angle || old_tan != mp->tan_half) &&
            (r = gi__rsm_solid_angles(mp, err)) != PF_OK)
            return r;
    }
    for (uint32_t m = 0; m < s->punctual; m++) {
        gi__rsm_rasterize(s, &s->maps[m]);
        gi__rsm_resolve(s, scene, jobs, m);
    }
    return PF_OK;
}

pf_result gi_rsm_set_geometry_moved(gi_rsm_set *s, const gi_motion *motion, pf_error *err)
{
    if (!gi_motion_any(motion)) return PF_OK;
    if (s->raster_ && motion->range_count) {
        pf_result r = rs_context_update(s->raster_, motion->ranges, motion->range_count, err);
        if (r != PF_OK) { /* made again at the next update */
            rs_context_destroy(s->raster_);
            s->raster_ = NULL;
        }
    }
    if (s->lights_) /* no light matches: every punctual map is drawn again */
        memset(s->lights_, 0xff, (s->punctual ? s->punctual : 1) * sizeof(pf_light));
    s->area_rendered_ = 0;
    return PF_OK;
}

pf_result gi_rsm_set_update(gi_rsm_set *s, const pf_scene *scene, const gi_area_lights *area, const pf_rt *rt,
                            pf_jobs *jobs, pf_error *err)
{
    s->changed = 0;
    if (!s->area_points) s->area_points = GI_RSM_DEFAULT_AREA_POINTS;
    pf_result r = gi__rsm_check(s, scene, err);
    if (r != PF_OK) return r;
    int with_area = area && area->count > 0;
    if (with_area && !rt) return pf_error_set(err, PF_ERR_ARGUMENT, "the area lights' RSM needs the ray tracer");
    if (!s->raster_ || s->raster_scene_ != scene || s->raster_jobs_ != jobs) {
        if (s->raster_) rs_context_destroy(s->raster_);
        s->raster_ = NULL;
        r = rs_context_create(&s->raster_, scene, jobs, rs_simd_for_isa(pf_isa_detect()), err);
        if (r != PF_OK) return r;
        s->raster_scene_ = scene;
        s->raster_jobs_ = jobs;
        free(s->lights_);
        s->lights_ = NULL;
        gi__rsm_free_planes(s);
    }
    int same = s->lights_ && s->punctual == scene->light_count;
    for (uint32_t l = 0; same && l < scene->light_count; l++) same = gi__light_same(&s->lights_[l], &scene->lights[l]);
    int area_same = gi__rsm_area_same(s, area);
    if (same && area_same && (!with_area || s->area_rendered_)) return PF_OK;
    /* The planes are reallocated only when the layout changes (light
     * count, a map's kind or the emitters); otherwise a moved light
     * re-lays out its matrices in place, so moving lights do not allocate
     * per frame. */
    int relayout = !s->maps || !s->lights_ || s->punctual != scene->light_count || !area_same;
    for (uint32_t l = 0; !relayout && l < scene->light_count; l++) {
        gi_rsm_map probe;
        memset(&probe, 0, sizeof probe);
        gi__rsm_layout(&probe, scene, &scene->lights[l]);
        relayout = probe.kind != s->maps[l].kind;
    }
    if (relayout) {
        r = gi__rsm_allocate(s, scene, with_area ? area : NULL, err);
        if (r != PF_OK) return r;
        free(s->lights_);
        s->lights_ = malloc((scene->light_count ? scene->light_count : 1) * sizeof(pf_light));
        if (!s->lights_) return pf_error_set(err, PF_ERR_OUT_OF_MEMORY, "out of memory for RSMs");
        same = 0;
    }
    if (!same) {
        /* until the maps are complete, remember no light (a failure below
         * must not leave maps that look current) */
        memset(s->lights_, 0xff, (scene->light_count ? scene->light_count : 1) * sizeof(pf_light));
        if ((r = gi__rsm_render_punctual(s, scene, jobs, err)) != PF_OK) return r;
        if (scene->light_count) /* lights may be NULL when there are none: memcpy's source must not be */
            memcpy(s->lights_, scene->lights, scene->light_count * sizeof(pf_light));
    }
    if (with_area && !s->area_rendered_) { /* emitters do not move: traced once */
        gi_rsm_area_render(s, s->punctual, rt, jobs);
        s->area_rendered_ = 1;
    }
    s->changed = 1;
    s->updates++;
    return PF_OK;
}
