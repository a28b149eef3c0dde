/* pf_rt: Embree 3 device, scene and queries (see pf_rt.h). */
#include "pf_rt.h"

#include <assert.h>
#include <embree3/rtcore.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "pf_fpenv.h"

/* One triangle geometry: a run of the scene's triangles [tri_first,
 * tri_first + tri_count) indexing the scene's whole position array (both
 * buffers shared, the index buffer at an offset), so Embree's primID plus
 * tri_first is the scene's triangle. */
typedef struct pf__rt_part {
    const struct pf_rt *rt; /* the alpha filter's user data */
    uint32_t tri_first, tri_count;
    uint32_t vertex_first, vertex_count; /* a dynamic part: the vertices its triangles use */
    uint32_t child;                      /* the scene it is in */
    RTCGeometry geom;                    /* held by that scene */
} pf__rt_part;

/* One scene of the split (pf_rt.h): the static triangles (several parts,
 * one per run between dynamic primitives) or one dynamic primitive (one
 * part); without a split the top scene itself with its one part. */
typedef struct pf__rt_child {
    RTCScene scene;
    RTCGeometry inst; /* its instance in the top scene (NULL: it is the top scene) */
    uint32_t part_first, part_count;
    int refit;   /* in the REFIT configuration (built or refitted by PF_RT_REFIT since its last rebuild) */
    int pending; /* pf_rt_update's scratch */
} pf__rt_child;

struct pf_rt {
    RTCDevice device;
    RTCScene scene; /* what queries trace: the one scene, or the top scene over the split's instances */
    const pf_scene *src;
    pf_error *build_err; /* where the error callback writes during creation and updates */
    int split;           /* instances: hits are mapped through children and parts */
    uint32_t part_count, child_count, dynamic_count;
    pf__rt_part *parts;     /* the static runs first, then the dynamic primitives in scene order */
    pf__rt_child *children; /* the static child (when it has triangles) first, then one per dynamic part */
};

static void pf__embree_error(void *user, enum RTCError code, const char *str)
{
    pf_rt *rt = user;
    static const char *const names[] = {"none", "unknown", "invalid argument", "invalid operation",
                                        "out of memory", "unsupported CPU", "cancelled"};
    const char *name = (unsigned)code < sizeof names / sizeof names[0] ? names[code] : "?";
    if (rt && rt->build_err)
        pf_error_set(rt->build_err, PF_ERR_EMBREE, "Embree: %s (%s)", str ? str : "", name);
    else
        fprintf(stderr, "softgi: Embree error: %s (%s)\n", str ? str : "", name);
}

/* Embree's RTCHitN accessors exist only for C++; this is the documented
 * structure-of-arrays layout they read (rtcore_ray.h): Ng_x, Ng_y, Ng_z, u,
 * v, primID, geomID, instID, each N entries wide. */
static float pf__hitn_u(const struct RTCHitN *h, unsigned n, unsigned i) { return ((const float *)h)[3 * n + i]; }
static float pf__hitn_v(const struct RTCHitN *h, unsigned n, unsigned i) { return ((const float *)h)[4 * n + i]; }
static uint32_t pf__hitn_prim(const struct RTCHitN *h, unsigned n, unsigned i)
{
    return ((const uint32_t *)h)[5 * n + i];
}

/* The hit, recomputed from the triangle Embree found.
 *
 * Embree's triangle intersectors divide through rcp(), which is the
 * processor's reciprocal approximation (rcpps / vrcpps) refined by one Newton
 * step. The approximation is not specified bit for bit: AMD and Intel
 * processors return different last bits, so Embree's t, u and v differ
 * between machines even with its ISA pinned, and every golden image that
 * depends on a ray (VPL positions, the path tracer) would too. softgi takes
 * only the triangle from Embree and recomputes t, u, v here with the
 * Moller-Trumbore formulas in double precision: IEEE operations that every
 * machine rounds alike (-ffp-contract=off keeps them unfused). u and v are
 * clamped onto the triangle (Embree's watertight test can accept a hit a
 * rounding error outside it). Returns 0 where the ray is parallel to the
 * triangle's plane (the caller keeps Embree's values; Embree reports no such
 * hits in practice). */
static int pf__exact_hit(const pf_scene *s, uint32_t prim, const double org[3], const double dir[3], float *t,
                         float *u, float *v)
{
    const uint32_t *tri = &s->indices[3 * (size_t)prim];
    pf_vec3 a = s->positions[tri[0]], b = s->positions[tri[1]], c = s->positions[tri[2]];
    double e1[3] = {(double)b.x - a.x, (double)b.y - a.y, (double)b.z - a.z};
    double e2[3] = {(double)c.x - a.x, (double)c.y - a.y, (double)c.z - a.z};
    double p[3] = {dir[1] * e2[2] - dir[2] * e2[1], dir[2] * e2[0] - dir[0] * e2[2], dir[0] * e2[1] - dir[1] * e2[0]};
    double det = e1[0] * p[0] + e1[1] * p[1] + e1[2] * p[2];
    if (det == 0.0 || !isfinite(det)) return 0;
    double tv[3] = {org[0] - a.x, org[1] - a.y, org[2] - a.z};
    double q[3] = {tv[1] * e1[2] - tv[2] * e1[1], tv[2] * e1[0] - tv[0] * e1[2], tv[0] * e1[1] - tv[1] * e1[0]};
    double uu = (tv[0] * p[0] + tv[1] * p[1] + tv[2] * p[2]) / det;
    double vv = (dir[0] * q[0] + dir[1] * q[1] + dir[2] * q[2]) / det;
    double tt = (e2[0] * q[0] + e2[1] * q[1] + e2[2] * q[2]) / det;
    if (!isfinite(uu) || !isfinite(vv) || !isfinite(tt)) return 0;
    uu = uu < 0.0 ? 0.0 : uu > 1.0 ? 1.0 : uu;
    vv = vv < 0.0 ? 0.0 : vv > 1.0 ? 1.0 : vv;
    if (uu + vv > 1.0) {
        double sum = uu + vv;
        uu /= sum;
        vv /= sum;
    }
    *t = (float)tt;
    *u = (float)uu;
    *v = (float)vv;
    return 1;
}

/* Embree's RTCRayN layout (rtcore_ray.h): org_x, org_y, org_z, tnear, dir_x,
 * dir_y, dir_z, time, tfar, ... each N entries wide. */
static void pf__rayn(const struct RTCRayN *r, unsigned n, unsigned i, double org[3], double dir[3])
{
    const float *f = (const float *)r;
    org[0] = f[0 * n + i];
    org[1] = f[1 * n + i];
    org[2] = f[2 * n + i];
    dir[0] = f[4 * n + i];
    dir[1] = f[5 * n + i];
    dir[2] = f[6 * n + i];
}

/* Alpha-mask filter (Embree calls it for every candidate hit on the
 * geometry): rejects hits where the material's alpha is below its cutoff.
 * The texture is looked up at the recomputed u, v (pf__exact_hit), so the
 * decision does not depend on the processor either. */
static void pf__alpha_filter(const struct RTCFilterFunctionNArguments *args)
{
    const pf__rt_part *part = args->geometryUserPtr;
    const pf_scene *s = part->rt->src;
    for (unsigned i = 0; i < args->N; i++) {
        if (args->valid[i] != -1) continue;
        uint32_t prim = part->tri_first + pf__hitn_prim(args->hit, args->N, i);
        const pf_material *m = &s->materials[s->tri_material[prim]];
        if (m->alpha_mode != PF_ALPHA_MASK) continue;
        float u = pf__hitn_u(args->hit, args->N, i), v = pf__hitn_v(args->hit, args->N, i), t;
        double org[3], dir[3];
        pf__rayn(args->ray, args->N, i, org, dir);
        pf__exact_hit(s, prim, org, dir, &t, &u, &v);
        const uint32_t *tri = &s->indices[3 * prim];
        float w = 1.0f - u - v;
        pf_vec2 a = s->uvs[tri[0]], b = s->uvs[tri[1]], c = s->uvs[tri[2]];
        pf_vec2 uv = {w * a.x + u * b.x + v * c.x, w * a.y + u * b.y + v * c.y};
        float rgba[4];
        pf_material_sample(s, s->tri_material[prim], uv, 0.0f, rgba);
        if (rgba[3] < m->alpha_cutoff) args->valid[i] = 0;
    }
}

/* The device of a pf_rt, pinned as pf_rt.h says. */
static pf_result pf__device(pf_rt *rt, pf_isa isa, uint32_t build_threads, pf_error *err)
{
    char config[128];
    snprintf(config, sizeof config, "ignore_config_files=1,threads=%u,set_affinity=0%s%s",
             build_threads ? build_threads : 1u, isa == PF_ISA_AUTO ? "" : ",isa=",
             isa == PF_ISA_AUTO ? "" : pf_isa_name(isa));
    rt->device = rtcNewDevice(config);
    if (!rt->device) {
        enum RTCError e = rtcGetDeviceError(NULL);
        return pf_error_set(err, PF_ERR_EMBREE, "Embree: cannot create a device with '%s' (error %d)", config,
                            (int)e);
    }
    rtcSetDeviceErrorFunction(rt->device, pf__embree_error, rt);
    return PF_OK;
}

/* A new scene of the split (and the top scene): ROBUST, MEDIUM, the static
 * builder. */
static RTCScene pf__new_scene(RTCDevice device)
{
    RTCScene scene = rtcNewScene(device);
    rtcSetSceneFlags(scene, RTC_SCENE_FLAG_ROBUST);
    rtcSetSceneBuildQuality(scene, RTC_BUILD_QUALITY_MEDIUM);
    return scene;
}

/* Part p's triangle geometry, attached to `scene` as geometry `id`. */
static void pf__attach_part(pf_rt *rt, uint32_t p, RTCScene scene, uint32_t id, int any_mask)
{
    const pf_scene *s = rt->src;
    pf__rt_part *part = &rt->parts[p];
    RTCGeometry geom = rtcNewGeometry(rt->device, RTC_GEOMETRY_TYPE_TRIANGLE);
    rtcSetGeometryBuildQuality(geom, RTC_BUILD_QUALITY_MEDIUM);
    /* The scene owns the arrays; positions carry a padding vertex so Embree's
     * 16-byte loads at the last vertex stay inside the allocation. */
    rtcSetSharedGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, s->positions, 0,
                               sizeof(pf_vec3), s->vertex_count);
    rtcSetSharedGeometryBuffer(geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, s->indices,
                               3 * sizeof(uint32_t) * (size_t)part->tri_first, 3 * sizeof(uint32_t),
                               part->tri_count);
    if (any_mask) {
        rtcSetGeometryUserData(geom, part);
        rtcSetGeometryIntersectFilterFunction(geom, pf__alpha_filter);
        rtcSetGeometryOccludedFilterFunction(geom, pf__alpha_filter);
    }
    rtcCommitGeometry(geom);
    rtcAttachGeometryByID(scene, geom, id);
    rtcReleaseGeometry(geom); /* the scene holds it */
    part->geom = geom;
}

/* The dynamic primitives of `anim` with triangles, checked against the
 * scene (pf_rt_create_dynamic's contract), into dyn[0..*n) (NULL: count). */
static pf_result pf__dynamic_parts(const pf_scene *s, const pf_anim *anim, pf__rt_part *dyn, uint32_t *n,
                                   pf_error *err)
{
    uint32_t k = 0;
    uint64_t tri_end = 0, vertex_end = 0;
    for (uint32_t i = 0; anim && i < anim->prim_count; i++) {
        const pf_anim_prim *p = &anim->prims[i];
        if (!p->dynamic || p->tri_count == 0) continue;
        uint64_t te = (uint64_t)p->tri_first + p->tri_count, ve = (uint64_t)p->vertex_first + p->vertex_count;
        if (te > s->tri_count || ve > s->vertex_count)
            return pf_error_set(err, PF_ERR_INDEX_RANGE,
                                "Embree: animated primitive %u (triangles %u..%llu, vertices %u..%llu) lies outside "
                                "the scene's %u triangles and %u vertices",
                                i, p->tri_first, (unsigned long long)te - 1, p->vertex_first,
                                (unsigned long long)ve - 1, s->tri_count, s->vertex_count);
        if (p->tri_first < tri_end || p->vertex_first < vertex_end)
            return pf_error_set(err, PF_ERR_INDEX_RANGE,
                                "Embree: animated primitive %u (triangles from %u, vertices from %u) overlaps the "
                                "one before it or comes before it",
                                i, p->tri_first, p->vertex_first);
        tri_end = te;
        vertex_end = ve;
        if (dyn) dyn[k] = (pf__rt_part){.tri_first = p->tri_first, .tri_count = p->tri_count,
                                        .vertex_first = p->vertex_first, .vertex_count = p->vertex_count};
        k++;
    }
    *n = k;
    return PF_OK;
}

/* The dynamic part whose vertex range holds vertex v, or UINT32_MAX
 * (binary search: the ranges are ascending and disjoint). */
static uint32_t pf__part_of_vertex(const pf__rt_part *dyn, uint32_t n, uint32_t v)
{
    uint32_t lo = 0, hi = n;
    while (lo < hi) {
        uint32_t mid = lo + (hi - lo) / 2;
        if (v < dyn[mid].vertex_first) hi = mid;
        else if (v - dyn[mid].vertex_first >= dyn[mid].vertex_count) lo = mid + 1;
        else return mid;
    }
    return UINT32_MAX;
}

/* Every triangle uses only vertices of its own part: a dynamic
 * primitive's triangles its own, the static triangles none of a dynamic
 * primitive's (what moves in pf_anim_pose is exactly the moved parts). */
static pf_result pf__check_vertices(const pf_scene *s, const pf__rt_part *dyn, uint32_t n, pf_error *err)
{
    uint32_t d = 0; /* the first dynamic part not wholly before triangle t */
    for (uint32_t t = 0; t < s->tri_count; t++) {
        while (d < n && t >= dyn[d].tri_first + dyn[d].tri_count) d++;
        uint32_t own = d < n && t >= dyn[d].tri_first ? d : UINT32_MAX;
        for (int c = 0; c < 3; c++) {
            uint32_t at = pf__part_of_vertex(dyn, n, s->indices[3 * (size_t)t + c]);
            if (at != own)
                return pf_error_set(err, PF_ERR_INDEX_RANGE,
                                    "Embree: triangle %u (%s) uses vertex %u of %s: it would not move with its "
                                    "primitive",
                                    t, own == UINT32_MAX ? "static" : "of an animated primitive",
                                    s->indices[3 * (size_t)t + c],
                                    at == UINT32_MAX ? "the static geometry" : "another animated primitive");
        }
    }
    return PF_OK;
}

/* The split's parts and children (pf_rt.h): the static runs between the n
 * dynamic parts dyn[], then the dynamic parts. */
static pf_result pf__split_layout(pf_rt *rt, const pf__rt_part *dyn, uint32_t n, pf_error *err)
{
    const pf_scene *s = rt->src;
    uint32_t runs = 0, at = 0;
    for (uint32_t d = 0; d <= n; d++) {
        uint32_t next = d < n ? dyn[d].tri_first : s->tri_count;
        runs += next > at;
        if (d < n) at = dyn[d].tri_first + dyn[d].tri_count;
    }
    rt->part_count = runs + n;
    rt->child_count = (runs > 0) + n;
    rt->dynamic_count = n;
    rt->parts = calloc(rt->part_count, sizeof *rt->parts);
    rt->children = calloc(rt->child_count, sizeof *rt->children);
    if (!rt->parts || !rt->children)
        return pf_error_set(err, PF_ERR_OUT_OF_MEMORY, "out of memory for the Embree scene's %u parts",
                            rt->part_count);
    uint32_t p = 0;
    at = 0;
    for (uint32_t d = 0; d <= n; d++) {
        uint32_t next = d < n ? dyn[d].tri_first : s->tri_count;
        if (next > at) rt->parts[p++] = (pf__rt_part){.tri_first = at, .tri_count = next - at};
        if (d < n) at = dyn[d].tri_first + dyn[d].tri_count;
    }
    uint32_t c = 0;
    if (runs) rt->children[c++] = (pf__rt_child){.part_first = 0, .part_count = runs};
    for (uint32_t d = 0; d < n; d++, p++, c++) {
        rt->parts[p] = dyn[d];
        rt->children[c] = (pf__rt_child){.part_first = p, .part_count = 1};
    }
    for (uint32_t i = 0; i < rt->child_count; i++)
        for (uint32_t k = 0; k < rt->children[i].part_count; k++) rt->parts[rt->children[i].part_first + k].child = i;
    for (uint32_t i = 0; i < rt->part_count; i++) rt->parts[i].rt = rt;
    return PF_OK;
}
/* The Embree error of a creation or update, or PF_OK. */
static pf_result pf__embree_status(pf_rt *rt, pf_error *local, const char *what)
{
    rt->build_err = NULL;
    if (local->code == PF_OK && rtcGetDeviceError(rt->device) == RTC_ERROR_NONE) return PF_OK;
    if (local->code == PF_OK) pf_error_set(local, PF_ERR_EMBREE, "Embree: %s failed", what);
    return local->code;
}

pf_result pf_rt_create(pf_rt **out, const pf_scene *scene, pf_isa isa, uint32_t build_threads, pf_error *err)
{
    return pf_rt_create_dynamic(out, scene, NULL, isa, build_threads, err);
}

pf_result pf_rt_create_dynamic(pf_rt **out, const pf_scene *scene, const pf_anim *anim, pf_isa isa,
                               uint32_t build_threads, pf_error *err)
{
    *out = NULL;
    pf_fpenv_set();
    uint32_t n = 0;
    pf_result r = pf__dynamic_parts(scene, anim, NULL, &n, err);
    if (r != PF_OK) return r;
    pf__rt_part *dyn = NULL;
    if (n) {
        if (!(dyn = calloc(n, sizeof *dyn)))
            return pf_error_set(err, PF_ERR_OUT_OF_MEMORY, "out of memory for %u animated primitives", n);
        pf__dynamic_parts(scene, anim, dyn, &n, err);
        if ((r = pf__check_vertices(scene, dyn, n, err)) != PF_OK) {
            free(dyn);
            return r;
        }
    }
    pf_rt *rt = calloc(1, sizeof *rt);
    if (!rt) {
        free(dyn);
        return pf_error_set(err, PF_ERR_OUT_OF_MEMORY, "out of memory creating the Embree device");
    }
    rt->src = scene;
    if (n) r = pf__split_layout(rt, dyn, n, err);
    else {
        /* one geometry: the scene's triangles as one part, the top scene its scene */
        rt->part_count = rt->child_count = 1;
        rt->parts = calloc(1, sizeof *rt->parts);
        rt->children = calloc(1, sizeof *rt->children);
        if (!rt->parts || !rt->children)
            r = pf_error_set(err, PF_ERR_OUT_OF_MEMORY, "out of memory creating the Embree scene");
        else {
            rt->parts[0] = (pf__rt_part){.rt = rt, .tri_count = scene->tri_count, .vertex_count = scene->vertex_count};
            rt->children[0] = (pf__rt_child){.part_count = 1};
        }
    }
    free(dyn);
    if (r == PF_OK) r = pf__device(rt, isa, build_threads, err);
    if (r != PF_OK) {
        pf_rt_destroy(rt);
        return r;
    }
    pf_error local;
    local.code = PF_OK;
    rt->build_err = &local;

    int any_mask = 0;
    for (uint32_t m = 0; m < scene->material_count; m++) any_mask |= scene->materials[m].alpha_mode == PF_ALPHA_MASK;
    rt->scene = pf__new_scene(rt->device);
    if (!n) {
        rt->children[0].scene = rt->scene;
        pf__attach_part(rt, 0, rt->scene, 0, any_mask);
    } else {
        /* the children, then the top scene over their instances (instance
         * id = child index, geometry id = part index within the child) */
        rt->split = 1;
        static const float identity[12] = {1, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0};
        for (uint32_t c = 0; c < rt->child_count; c++) {
            pf__rt_child *ch = &rt->children[c];
            ch->scene = pf__new_scene(rt->device);
            for (uint32_t k = 0; k < ch->part_count; k++) pf__attach_part(rt, ch->part_first + k, ch->scene, k, any_mask);
            rtcCommitScene(ch->scene);
            RTCGeometry inst = rtcNewGeometry(rt->device, RTC_GEOMETRY_TYPE_INSTANCE);
            rtcSetGeometryInstancedScene(inst, ch->scene);
            rtcSetGeometryTransform(inst, 0, RTC_FORMAT_FLOAT3X4_COLUMN_MAJOR, identity);
            rtcCommitGeometry(inst);
            rtcAttachGeometryByID(rt->scene, inst, c);
            rtcReleaseGeometry(inst); /* the top scene holds it */
            ch->inst = inst;
        }
    }
    rtcCommitScene(rt->scene);
    if ((r = pf__embree_status(rt, &local, "building the scene")) != PF_OK) {
        pf_rt_destroy(rt);
        if (err) *err = local;
        return r;
    }
    *out = rt;
    return PF_OK;
}

void pf_rt_destroy(pf_rt *rt)
{
    if (!rt) return;
    if (rt->scene) rtcReleaseScene(rt->scene);
    for (uint32_t c = 0; rt->split && c < rt->child_count; c++)
        if (rt->children[c].scene) rtcReleaseScene(rt->children[c].scene);
    if (rt->device) rtcReleaseDevice(rt->device);
    free(rt->parts);
    free(rt->children);
    free(rt);
}

uint32_t pf_rt_dynamic_count(const pf_rt *rt) { return rt->dynamic_count; }

/* The part whose triangles start at tri_first (the dynamic parts are
 * ascending), or UINT32_MAX. */
static uint32_t pf__dynamic_part_at(const pf_rt *rt, uint32_t tri_first)
{
    uint32_t lo = rt->part_count - rt->dynamic_count, hi = rt->part_count;
    while (lo < hi) {
        uint32_t mid = lo + (hi - lo) / 2;
        if (rt->parts[mid].tri_first == tri_first) return mid;
        if (rt->parts[mid].tri_first < tri_first) lo = mid + 1;
        else hi = mid;
    }
    return UINT32_MAX;
}

/* A child's scene (and geometries) switched between the two update
 * configurations (pf_rt.h): REBUILD's static builder, REFIT's dynamic
 * scene with refitted geometries. Without a split the child is the top
 * scene itself. */
static void pf__child_configure(pf_rt *rt, pf__rt_child *ch, int refit)
{
    if (ch->refit == refit) return;
    rtcSetSceneFlags(ch->scene, refit ? RTC_SCENE_FLAG_ROBUST | RTC_SCENE_FLAG_DYNAMIC : RTC_SCENE_FLAG_ROBUST);
    rtcSetSceneBuildQuality(ch->scene, refit ? RTC_BUILD_QUALITY_LOW : RTC_BUILD_QUALITY_MEDIUM);
    for (uint32_t k = 0; k < ch->part_count; k++)
        rtcSetGeometryBuildQuality(rt->parts[ch->part_first + k].geom,
                                   refit ? RTC_BUILD_QUALITY_REFIT : RTC_BUILD_QUALITY_MEDIUM);
    ch->refit = refit;
}

pf_result pf_rt_update(pf_rt *rt, const pf_anim_moved *moved, uint32_t count, pf_rt_update_mode mode,
                       pf_error *err)
{
    if (!rt || (count && !moved))
        return pf_error_set(err, PF_ERR_ARGUMENT, "pf_rt_update: %s is NULL", rt ? "the moved report" : "rt");
    if (mode != PF_RT_REBUILD && mode != PF_RT_REFIT)
        return pf_error_set(err, PF_ERR_ARGUMENT, "pf_rt_update: unknown mode %d", (int)mode);
    const pf_scene *s = rt->src;
    /* Check every entry before touching anything. */
    for (uint32_t c = 0; c < rt->child_count; c++) rt->children[c].pending = 0;
    for (uint32_t i = 0; i < count; i++) {
        const pf_anim_moved *m = &moved[i];
        uint64_t te = (uint64_t)m->tri_first + m->tri_count, ve = (uint64_t)m->vertex_first + m->vertex_count;
        if (te > s->tri_count || ve > s->vertex_count)
            return pf_error_set(err, PF_ERR_INDEX_RANGE,
                                "pf_rt_update: entry %u (triangles %u + %u, vertices %u + %u) lies outside the "
                                "scene's %u triangles and %u vertices",
                                i, m->tri_first, m->tri_count, m->vertex_first, m->vertex_count, s->tri_count,
                                s->vertex_count);
        if (!m->moved || m->tri_count == 0) continue;
        uint32_t p = 0; /* without a split: the one part, the whole scene */
        if (rt->split) {
            p = pf__dynamic_part_at(rt, m->tri_first);
            if (p == UINT32_MAX || rt->parts[p].tri_count != m->tri_count ||
                rt->parts[p].vertex_first != m->vertex_first || rt->parts[p].vertex_count != m->vertex_count)
                return pf_error_set(err, PF_ERR_ARGUMENT,
                                    "pf_rt_update: entry %u moved triangles %u + %u (vertices %u + %u), which are "
                                    "not one of the scene's %u animated primitives: they were built static",
                                    i, m->tri_first, m->tri_count, m->vertex_first, m->vertex_count,
                                    rt->dynamic_count);
        }
        rt->children[rt->parts[p].child].pending = 1;
    }
    /* REBUILD: every scene last refitted too, so that a fresh build's BVHs
     * are back everywhere. */
    int refit = mode == PF_RT_REFIT, any = 0;
    for (uint32_t c = 0; c < rt->child_count; c++) {
        pf__rt_child *ch = &rt->children[c];
        if (!refit && ch->refit) ch->pending = 1;
        any |= ch->pending;
    }
    if (!any) return PF_OK;

    pf_fpenv_set();
    pf_error local;
    local.code = PF_OK;
    rt->build_err = &local;
    for (uint32_t c = 0; c < rt->child_count; c++) {
        pf__rt_child *ch = &rt->children[c];
        if (!ch->pending) continue;
        pf__child_configure(rt, ch, refit);
        for (uint32_t k = 0; k < ch->part_count; k++) {
            RTCGeometry geom = rt->parts[ch->part_first + k].geom;
            rtcUpdateGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0);
            rtcCommitGeometry(geom);
        }
        if (ch->inst) {
            rtcCommitScene(ch->scene);
            rtcCommitGeometry(ch->inst); /* the top scene reads the child's new bounds */
        }
        ch->pending = 0;
    }
    rtcCommitScene(rt->scene);
    pf_result r = pf__embree_status(rt, &local, "updating the scene");
    if (r != PF_OK && err) *err = local;
    return r;
}

const pf_scene *pf_rt_scene(const pf_rt *rt) { return rt->src; }

/* Fills an 8-wide ray packet from rays[0..n), n <= 8; unused lanes invalid. */
static void pf__pack(struct RTCRay8 *r, int valid[PF_RT_WIDTH], const pf_ray *rays, uint32_t n)
{
    for (uint32_t i = 0; i < PF_RT_WIDTH; i++) {
        const pf_ray *src = &rays[i < n ? i : 0];
        valid[i] = i < n ? -1 : 0;
        r->org_x[i] = src->org.x;
        r->org_y[i] = src->org.y;
        r->org_z[i] = src->org.z;
        r->tnear[i] = src->tnear;
        r->dir_x[i] = src->dir.x;
        r->dir_y[i] = src->dir.y;
        r->dir_z[i] = src->dir.z;
        r->time[i] = 0.0f;
        r->tfar[i] = src->tfar;
        r->mask[i] = 0xffffffffu;
        r->id[i] = i;
        r->flags[i] = 0;
    }
}

static void pf__intersect(const pf_rt *rt, const pf_ray *rays, pf_hit *hits, uint32_t count, int exact);

/* The scene's triangle of an Embree hit: without a split Embree's primID
 * (one geometry over every triangle); with one, instance = child,
 * geometry = its part, primID counted from the part's first triangle. */
static uint32_t pf__scene_prim(const pf_rt *rt, uint32_t inst, uint32_t geom, uint32_t prim)
{
    if (!rt->split) return prim;
    assert(inst < rt->child_count && geom < rt->children[inst].part_count);
    return rt->parts[rt->children[inst].part_first + geom].tri_first + prim;
}

void pf_rt_intersect(const pf_rt *rt, const pf_ray *rays, pf_hit *hits, uint32_t count)
{
    pf__intersect(rt, rays, hits, count, 1);
}

void pf_rt_intersect_embree(const pf_rt *rt, const pf_ray *rays, pf_hit *hits, uint32_t count)
{
    pf__intersect(rt, rays, hits, count, 0);
}

static void pf__intersect(const pf_rt *rt, const pf_ray *rays, pf_hit *hits, uint32_t count, int exact)
{
    for (uint32_t base = 0; base < count; base += PF_RT_WIDTH) {
        uint32_t n = count - base < PF_RT_WIDTH ? count - base : PF_RT_WIDTH;
        struct RTCRayHit8 rh;
        int valid[PF_RT_WIDTH];
        pf__pack(&rh.ray, valid, rays + base, n);
        for (int i = 0; i < PF_RT_WIDTH; i++) {
            rh.hit.geomID[i] = RTC_INVALID_GEOMETRY_ID;
            rh.hit.primID[i] = RTC_INVALID_GEOMETRY_ID;
            rh.hit.instID[0][i] = RTC_INVALID_GEOMETRY_ID;
            rh.hit.u[i] = rh.hit.v[i] = 0.0f;
            rh.hit.Ng_x[i] = rh.hit.Ng_y[i] = rh.hit.Ng_z[i] = 0.0f;
        }
        struct RTCIntersectContext ctx;
        rtcInitIntersectContext(&ctx);
        rtcIntersect8(valid, rt->scene, &ctx, &rh);
        for (uint32_t i = 0; i < n; i++) {
            pf_hit *h = &hits[base + i];
            if (rh.hit.geomID[i] == RTC_INVALID_GEOMETRY_ID) {
                h->t = INFINITY;
                h->prim = PF_RT_MISS;
                h->u = h->v = 0.0f;
            } else {
                h->t = rh.ray.tfar[i];
                h->prim = pf__scene_prim(rt, rh.hit.instID[0][i], rh.hit.geomID[i], rh.hit.primID[i]);
                h->u = rh.hit.u[i];
                h->v = rh.hit.v[i];
                if (!exact) continue;
                const pf_ray *src = &rays[base + i];
                double org[3] = {src->org.x, src->org.y, src->org.z}, dir[3] = {src->dir.x, src->dir.y, src->dir.z};
                pf__exact_hit(rt->src, h->prim, org, dir, &h->t, &h->u, &h->v);
            }
        }
    }
}

void pf_rt_occluded(const pf_rt *rt, const pf_ray *rays, uint8_t *occluded, uint32_t count)
{
    for (uint32_t base = 0; base < count; base += PF_RT_WIDTH) {
        uint32_t n = count - base < PF_RT_WIDTH ? count - base : PF_RT_WIDTH;
        struct RTCRay8 r;
        int valid[PF_RT_WIDTH];
        pf__pack(&r, valid, rays + base, n);
        struct RTCIntersectContext ctx;
        rtcInitIntersectContext(&ctx);
        rtcOccluded8(valid, rt->scene, &ctx, &r);
        /* Embree sets tfar to -inf for occluded rays. */
        for (uint32_t i = 0; i < n; i++) occluded[base + i] = r.tfar[i] == -INFINITY;
    }
}

pf_hit pf_rt_intersect1(const pf_rt *rt, pf_ray ray)
{
    pf_hit h;
    pf_rt_intersect(rt, &ray, &h, 1);
    return h;
}

int pf_rt_occluded1(const pf_rt *rt, pf_ray ray)
{
    uint8_t o;
    pf_rt_occluded(rt, &ray, &o, 1);
    return o;
}

void pf_rt_surface(const pf_rt *rt, const pf_hit *hit, float lod, pf_surface *out)
{
    pf_scene_surface(rt->src, hit->prim, hit->u, hit->v, lod, out);
}

pf_vec3 pf_rt_offset_origin(pf_vec3 p, pf_vec3 ng, pf_vec3 towards)
{
    /* 2^-17 relative to the largest coordinate plus an absolute floor: a few
     * hundred float ulps at that magnitude, far below any feature size. */
    float mag = fmaxf(fabsf(p.x), fmaxf(fabsf(p.y), fabsf(p.z)));
    float eps = 1.0e-5f + mag * 7.62939453125e-6f;
    if (pf_v3_dot(ng, towards) < 0.0f) eps = -eps;
    return pf_v3_add(p, pf_v3_scale(ng, eps));
}
