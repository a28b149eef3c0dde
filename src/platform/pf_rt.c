/* pf_rt: Embree 3 device, scene and queries (see pf_rt.h). */
#include "pf_rt.h"

#include <embree3/rtcore.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "pf_fpenv.h"

struct pf_rt {
    RTCDevice device;
    RTCScene scene;
    const pf_scene *src;
    pf_error *build_err; /* where the error callback writes during creation */
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
    const pf_rt *rt = args->geometryUserPtr;
    const pf_scene *s = rt->src;
    for (unsigned i = 0; i < args->N; i++) {
        if (args->valid[i] != -1) continue;
        uint32_t prim = pf__hitn_prim(args->hit, args->N, i);
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

pf_result pf_rt_create(pf_rt **out, const pf_scene *scene, pf_isa isa, uint32_t build_threads, pf_error *err)
{
    *out = NULL;
    pf_fpenv_set();
    pf_rt *rt = calloc(1, sizeof *rt);
    if (!rt) return pf_error_set(err, PF_ERR_OUT_OF_MEMORY, "out of memory creating the Embree device");
    pf_error local;
    local.code = PF_OK;
    rt->build_err = &local;
    rt->src = scene;

    char config[128];
    snprintf(config, sizeof config, "ignore_config_files=1,threads=%u,set_affinity=0%s%s",
             build_threads ? build_threads : 1u, isa == PF_ISA_AUTO ? "" : ",isa=",
             isa == PF_ISA_AUTO ? "" : pf_isa_name(isa));
    rt->device = rtcNewDevice(config);
    if (!rt->device) {
        enum RTCError e = rtcGetDeviceError(NULL);
        free(rt);
        return pf_error_set(err, PF_ERR_EMBREE, "Embree: cannot create a device with '%s' (error %d)", config,
                            (int)e);
    }
    rtcSetDeviceErrorFunction(rt->device, pf__embree_error, rt);

    rt->scene = rtcNewScene(rt->device);
    rtcSetSceneFlags(rt->scene, RTC_SCENE_FLAG_ROBUST);
    rtcSetSceneBuildQuality(rt->scene, RTC_BUILD_QUALITY_MEDIUM);
    RTCGeometry geom = rtcNewGeometry(rt->device, RTC_GEOMETRY_TYPE_TRIANGLE);
    rtcSetGeometryBuildQuality(geom, RTC_BUILD_QUALITY_MEDIUM);
    /* The scene owns the arrays; positions carry a padding vertex so Embree's
     * 16-byte loads at the last vertex stay inside the allocation. */
    rtcSetSharedGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, scene->positions, 0,
                               sizeof(pf_vec3), scene->vertex_count);
    rtcSetSharedGeometryBuffer(geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, scene->indices, 0,
                               3 * sizeof(uint32_t), scene->tri_count);
    int any_mask = 0;
    for (uint32_t m = 0; m < scene->material_count; m++) any_mask |= scene->materials[m].alpha_mode == PF_ALPHA_MASK;
    if (any_mask) {
        rtcSetGeometryUserData(geom, rt);
        rtcSetGeometryIntersectFilterFunction(geom, pf__alpha_filter);
        rtcSetGeometryOccludedFilterFunction(geom, pf__alpha_filter);
    }
    rtcCommitGeometry(geom);
    rtcAttachGeometry(rt->scene, geom);
    rtcReleaseGeometry(geom);
    rtcCommitScene(rt->scene);
    rt->build_err = NULL;
    if (local.code != PF_OK || rtcGetDeviceError(rt->device) != RTC_ERROR_NONE) {
        if (local.code == PF_OK) pf_error_set(&local, PF_ERR_EMBREE, "Embree: building the scene failed");
        pf_rt_destroy(rt);
        if (err) *err = local;
        return local.code;
    }
    *out = rt;
    return PF_OK;
}

void pf_rt_destroy(pf_rt *rt)
{
    if (!rt) return;
    if (rt->scene) rtcReleaseScene(rt->scene);
    if (rt->device) rtcReleaseDevice(rt->device);
    free(rt);
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
                h->prim = rh.hit.primID[i];
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
