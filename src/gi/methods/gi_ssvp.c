/* gi_ssvp: Screen-Space VPL Propagation, two diffuse bounces (Aranha,
 * Macedo, Apolinario: "Screen-space VPL propagation for real-time indirect
 * lighting", Sec. III), as a softgi VPL method. Each frame runs the paper's
 * pipeline (Fig. 1), one named function per step:
 *
 *   gi_ssvp_first_bounce    (III-A) the light's reflective shadow map (RSM,
 *                           Dachsbacher 2005: position, normal, flux per
 *                           texel; rasterized by gi_rsm.c, 256^2 per map or
 *                           cube face by default) sampled at the 2D
 *                           Hammersley set of Eq. 1,
 *                           (k / n, radical inverse of k), n = 256: one
 *                           first-bounce VPL per sample that lands on a lit
 *                           texel;
 *   gi_ssvp_cluster         (III-B) k-means over the first-bounce VPLs with
 *                           the Eq. 2 metric (w1 = 0.6, w2 = 0.4; gi_kmeans.h),
 *                           at most 5 iterations, centroids reused from the
 *                           previous frame (seeded only on the first frame,
 *                           k-means++ style: see gi_kmeans.c);
 *   gi_ssvp_cluster_maps    (III-C) one 256 x 256 paraboloid RSM per cluster
 *                           centroid (hemisphere around the centroid's
 *                           normal, rs_paraboloid.h's mapping), rendered with
 *                           Embree: one ray per inside texel centre (8-wide
 *                           packets, one job item per map row) whose closest
 *                           hit the texel keeps, a visibility buffer whose
 *                           position, normal and albedo are resolved for the
 *                           texels the samples read (as rs_gbuffer resolves
 *                           the camera's). A map is kept while its centroid
 *                           does not move (bitwise), so a static scene
 *                           renders its maps once;
 *   gi_ssvp_second_bounce   (III-C) "uniform sampling on the unit circle":
 *                           the Hammersley set, shifted per cluster, mapped
 *                           to the unit disc (r = sqrt(u), phi = 2 pi v),
 *                           each point read at its paraboloid texel; a
 *                           second-bounce VPL on every texel that hit a
 *                           surface;
 *   (III-D, shading, is the frame's: gi_indirect.c, with the paper's
 *   edge-aware Gaussian denoise as --filter gaussian.)
 *
 * Units (gi_vpl.h; the same as gi_ir.c): a VPL's intensity is
 * I = Phi * albedo / pi. How each VPL's Phi follows from Eq. 6's Monte
 * Carlo normalisation "divide each VPL's contribution by the probability of
 * it being selected":
 *
 * - First bounce. RSM texel t receives the flux the light sends through it,
 *   Phi_t = I_light * cone(w_t) * dOmega_t (spot; point: I dOmega_t;
 *   directional: E * texel area; gi_rsm.h stores albedo * Phi_t). A
 *   Hammersley point picks texel t with probability 1 / T (uniform over the
 *   map's T texels), so with n samples the VPL's flux is Phi = Phi_t T / n
 *   and its intensity Phi albedo / pi: the n VPLs together are an unbiased
 *   estimate of the light's flux landing on the scene.
 * - Second bounce. A cluster radiates from its centroid what its members
 *   reflect: radiant intensity J(w) = sum_i I_i (n_i . w)^+ (each member
 *   with its own normal, all moved to the centroid). Texel t of the
 *   cluster's map receives flux Phi_t = J(w_t) dOmega_t; a sample picks it
 *   with probability pdf(w_t) dOmega_t, so with m samples for the cluster
 *   the VPL's flux is Phi = J(w_t) / (pdf(w_t) m): J(w_t) pi / (cos_c m)
 *   for the default cosine-distributed disc, J(w_t) 4 pi / ((1 + r_t^2)^2
 *   m) for points uniform on the paraboloid map's disc (the paper's
 *   reading, --param disc=paraboloid; dOmega_t = 4 / (1 + r_t^2)^2 (2 /
 *   R)^2, r_t = |uv| of the texel centre). The sample points are shifted
 *   per cluster so that this is unbiased for any m (gi_ssvp_second_bounce;
 *   docs/ssvp.md).
 *
 * Deviations from the paper (README "ssvp"):
 * - Eq. 6 prints the geometry term as (cos theta + cos sigma) / d^2 and
 *   normalises by 1 / N with N the number of first AND second bounce VPLs.
 *   The frame shades with the product cos theta cos sigma / d^2 (survey
 *   Eq. 8), and each bounce's estimator is normalised by its own sample count
 *   (n for the first bounce, m per cluster for the second): with one 1 / N
 *   over both lists and n = 256 first- plus 256 second-bounce VPLs every
 *   contribution would be halved, i.e. the two bounces averaged instead of
 *   added.
 * - Only the RSM of the first punctual light in the scene is sampled ("the
 *   main light source"); further punctual lights get no VPLs. Point lights
 *   (the paper's main light is a spot or the sun) get gi_rsm's cube map,
 *   its six faces sampled as one tall image.
 * - Beyond the paper: emissive triangles (gi_area.h) get the area lights'
 *   RSM (gi_rsm_area.h: K hemispherical faces from power-weighted emitter
 *   points, every texel the same projected solid angle). It is the main
 *   light of a scene without punctual lights; in a scene with both it is
 *   stacked below the main light's map and sampled as part of one image
 *   (--param area_points=K, default GI_RSM_DEFAULT_AREA_POINTS). A scene
 *   without emitters gives the VPLs it gave before.
 * - The cluster maps hold each texel's hit (a visibility buffer); the
 *   surface (position, normal, albedo) and the flux of a texel
 *   (J(w_t) dOmega_t above) are evaluated when a sample reads it: the flux
 *   changes whenever the light moves while the geometry seen from an
 *   unmoved centroid does not, and a frame reads only about 32 of a map's
 *   51,000 inside texels.
 * - Option (--param lazy_maps=1, off by default): no cluster map is
 *   rendered; each second-bounce sample traces just its texel's ray, the
 *   same ray the full map traces for that texel, so the VPLs are the same
 *   bits (tested) for a fraction of the rays (32 instead of 51,000 per
 *   cluster). On a GPU the paper renders whole maps because rasterizing is
 *   cheap; on a CPU the unread texels are pure cost.
 * - Second-bounce samples are split evenly over the non-empty clusters (the
 *   paper does not say how they are distributed).
 * - The second bounce's disc points are cosine-distributed about the
 *   centroid's normal by default and shifted per cluster
 *   (gi_ssvp_second_bounce). --param disc=paraboloid takes them uniform on
 *   the paraboloid map's disc, as the paper does. --param origin=members
 *   (beyond the paper) traces each sample from a member VPL instead of
 *   the centroid, the unbiased second bounce the cluster model
 *   approximates. Left unset, the origin is the paper's centroid in a
 *   frame that shades its whole set, and members under VPL cycling
 *   (gi_vpl_inputs.cycle > 1): averaged over a cycle, the unbiased model's
 *   noise goes and the cluster model's bias stays (docs/ssvp.md).
 * - The frame's VPL budget (--vpls) caps first + second. Left at their
 *   defaults, the two counts follow the budget: half each (--vpls 512 gives
 *   the paper's 256 + 256, the default --vpls 256 128 + 128, and a VPL
 *   cycle's C x 256 budget C x 128 each, so its C slices are C different
 *   sets), the whole budget for the first bounce with --bounces 1. A count
 *   given with --param keeps its value and the other its paper default
 *   (256); counts that then exceed the budget are an error.
 *
 * VPL ids: first bounce k (the Hammersley index), second bounce
 * 0x80000000 | cluster << 16 | sample. Moved flags compare with the previous
 * frame's VPL in the same slot (as gi_ir.c). */
#include <assert.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gi_kmeans.h"
#include "gi_rsm.h"
#include "gi_vpl.h"
#include "pf_random.h"
#include "rs_paraboloid.h"

#define GI__SSVP_MAX_CLUSTERS 64u
#define GI__SSVP_MAX_SAMPLES 65535u
#define GI__SSVP_STREAM 0x55u /* pf_random stream of the clusters' sample shifts */

/* --param disc and origin: how a second-bounce sample's unit-disc point
 * becomes a direction, and where its ray starts (gi_ssvp_second_bounce). */
enum { GI__SSVP_DISC_COSINE, GI__SSVP_DISC_PARABOLOID };
enum { GI__SSVP_ORIGIN_CENTROID, GI__SSVP_ORIGIN_MEMBERS };

typedef struct gi__ssvp_map {
    pf_vec3 cpos, cnrm;        /* the centroid the map was rendered from */
    int valid;
    /* per texel (R*R, row j = v, column i = u): the closest hit of the ray
     * through the texel centre (prim PF_RT_MISS: outside the disc or nothing
     * hit). Position, normal and albedo are this hit's surface
     * (pf_rt_surface), resolved for the texels a sample reads. */
    pf_hit *hit;
} gi__ssvp_map;

typedef struct gi__ssvp_state {
    /* options */
    uint32_t clusters, first, second, map_res, rsm_res, iters, lazy_maps, area_points;
    uint32_t disc; /* GI__SSVP_DISC_*: how a unit-disc sample picks a cluster map texel */
    uint32_t origin; /* GI__SSVP_ORIGIN_*: where the second-bounce rays start (this update's) */
    int first_set, second_set, origin_set;
    /* k-means state kept between frames */
    pf_vec3 cpos[GI__SSVP_MAX_CLUSTERS], cnrm[GI__SSVP_MAX_CLUSTERS];
    uint32_t members[GI__SSVP_MAX_CLUSTERS];
    int have_centroids;
    uint32_t last_iterations; /* k-means iterations of the last frame */
    uint32_t maps_rendered;   /* cluster maps rendered in the last frame */
    gi__ssvp_map map[GI__SSVP_MAX_CLUSTERS];
    /* first-bounce VPLs of this frame (room for fcap) */
    uint32_t fcap;
    pf_vec3 *fpos, *fnrm;
    uint32_t *assign;
    float *kscratch;       /* k-means seeding */
    gi_rsm_set rsm;        /* the light's reflective shadow map */
    /* per-worker rays of the map rows (allocated on the first frame) */
    pf_ray *wrays;         /* per worker: map_res rays */
    uint32_t workers;
    gi_vpl_set prev;
} gi__ssvp_state;

/* --------------------------------------------------------------- options */

/* Room for n first-bounce VPLs in fpos, fnrm, assign and kscratch (grown,
 * never shrunk; a default count follows the frame's budget). 0: out of
 * memory, the old arrays kept. */
static int gi__ssvp_first_room(gi__ssvp_state *s, uint32_t n)
{
    if (n <= s->fcap) return 1;
    pf_vec3 *p = realloc(s->fpos, sizeof(pf_vec3) * n);
    if (p) s->fpos = p;
    pf_vec3 *q = realloc(s->fnrm, sizeof(pf_vec3) * n);
    if (q) s->fnrm = q;
    uint32_t *a = realloc(s->assign, sizeof(uint32_t) * n);
    if (a) s->assign = a;
    float *k = realloc(s->kscratch, sizeof(float) * n);
    if (k) s->kscratch = k;
    if (!p || !q || !a || !k) return 0;
    memset(s->fpos + s->fcap, 0, sizeof(pf_vec3) * (n - s->fcap));
    memset(s->fnrm + s->fcap, 0, sizeof(pf_vec3) * (n - s->fcap));
    memset(s->assign + s->fcap, 0, sizeof(uint32_t) * (n - s->fcap));
    memset(s->kscratch + s->fcap, 0, sizeof(float) * (n - s->fcap));
    s->fcap = n;
    return 1;
}

static void gi__ssvp_destroy(void *state)
{
    gi__ssvp_state *s = state;
    if (!s) return;
    for (uint32_t j = 0; j < GI__SSVP_MAX_CLUSTERS; j++)
        free(s->map[j].hit);
    free(s->fpos), free(s->fnrm), free(s->assign), free(s->kscratch);
    free(s->wrays);
    gi_vpl_set_free(&s->prev);
    gi_rsm_set_free(&s->rsm);
    free(s);
}

static int gi__has(const gi_params *p, const char *key)
{
    size_t n = strlen(key); /* gi_params keeps "KEY=VALUE" as the key */
    for (uint32_t i = 0; p && i < p->count; i++)
        if (!strncmp(p->key[i], key, n) && (p->key[i][n] == '=' || p->key[i][n] == '\0')) return 1;
    return 0;
}

static pf_result gi__ssvp_create(void **state, const gi_params *params, pf_error *err)
{
    static const char *const known[] = {"clusters", "first",     "second",      "map_res", "rsm_res",
                                        "iters",    "lazy_maps", "area_points", "disc",    "origin",
                                        NULL};
    static const char *const discs[] = {"cosine", "paraboloid", NULL};
    static const char *const origins[] = {"centroid", "members", NULL};
    *state = NULL;
    pf_result r = gi_params_check(params, "ssvp", known, err);
    if (r != PF_OK) return r;
    gi__ssvp_state *s = calloc(1, sizeof *s);
    if (!s) return pf_error_set(err, PF_ERR_OUT_OF_MEMORY, "out of memory");
    s->clusters = 8;       /* Sec. IV: 8 clusters keep the paper's frame under 16 ms */
    s->first = 256;        /* Sec. III-A: 256 Hammersley samples */
    s->second = 256;       /* Sec. IV-A: 256 second-bounce VPLs */
    s->map_res = 256;      /* Sec. III-C: "a resolution of 256^2 pixels is sufficient" */
    s->rsm_res = 256;      /* not given by the paper */
    s->iters = GI_KMEANS_MAX_ITER;
    s->area_points = GI_RSM_DEFAULT_AREA_POINTS;
    s->disc = GI__SSVP_DISC_COSINE;       /* see gi_ssvp_second_bounce */
    s->origin = GI__SSVP_ORIGIN_CENTROID; /* Sec. III-C */
    if ((r = gi_param_u32(params, "clusters", 1, GI__SSVP_MAX_CLUSTERS, &s->clusters, err)) != PF_OK ||
        (r = gi_param_u32(params, "first", 1, GI__SSVP_MAX_SAMPLES, &s->first, err)) != PF_OK ||
        (r = gi_param_u32(params, "second", 0, GI__SSVP_MAX_SAMPLES, &s->second, err)) != PF_OK ||
        (r = gi_param_u32(params, "map_res", 8, 2048, &s->map_res, err)) != PF_OK ||
        (r = gi_param_u32(params, "rsm_res", GI_RSM_MIN_SIZE, GI_RSM_MAX_SIZE, &s->rsm_res, err)) != PF_OK ||
        (r = gi_param_u32(params, "iters", 1, 100, &s->iters, err)) != PF_OK ||
        (r = gi_param_u32(params, "lazy_maps", 0, 1, &s->lazy_maps, err)) != PF_OK ||
        (r = gi_param_u32(params, "area_points", 1, GI_RSM_MAX_AREA_POINTS, &s->area_points, err)) != PF_OK ||
        (r = gi_param_choice(params, "disc", discs, &s->disc, err)) != PF_OK ||
        (r = gi_param_choice(params, "origin", origins, &s->origin, err)) != PF_OK) {
        gi__ssvp_destroy(s);
        return r;
    }
    s->first_set = gi__has(params, "first");
    s->second_set = gi__has(params, "second");
    s->origin_set = gi__has(params, "origin");
    gi_rsm_set_init(&s->rsm, s->rsm_res);
    s->rsm.area_points = s->area_points;
    if (!gi__ssvp_first_room(s, s->first)) {
        gi__ssvp_destroy(s);
        return pf_error_set(err, PF_ERR_OUT_OF_MEMORY, "out of memory");
    }
    *state = s;
    return PF_OK;
}

/* ------------------------------------------------------------ helpers */

/* Van der Corput radical inverse in base 2 (gamma of Eq. 1), exact. */
static float gi__vdc(uint32_t k)
{
    k = (k << 16) | (k >> 16);
    k = ((k & 0x00ff00ffu) << 8) | ((k & 0xff00ff00u) >> 8);
    k = ((k & 0x0f0f0f0fu) << 4) | ((k & 0xf0f0f0f0u) >> 4);
    k = ((k & 0x33333333u) << 2) | ((k & 0xccccccccu) >> 2);
    k = ((k & 0x55555555u) << 1) | ((k & 0xaaaaaaaau) >> 1);
    return (float)((double)k * (1.0 / 4294967296.0));
}

/* Eq. 1: point k of the n-point 2D Hammersley set. */
static void gi__hammersley(uint32_t k, uint32_t n, float *u, float *v)
{
    *u = (float)((double)k / (double)n);
    *v = gi__vdc(k);
}

/* ------------------------------------------------- III-A first bounce */

/* A surface hit as a VPL site: position pushed off the surface towards the
 * ray's origin side, shading normal turned to that side. */
static void gi__site(const pf_rt *rt, const pf_hit *h, pf_vec3 dir, pf_vec3 *pos, pf_vec3 *nrm, pf_vec3 *alb)
{
    pf_surface sf;
    pf_rt_surface(rt, h, GI_VPL_ALBEDO_LOD, &sf); /* gi_vpl.h's albedo rule */
    pf_vec3 n = sf.ns, ng = sf.ng;
    if (pf_v3_dot(ng, dir) > 0.0f) ng = pf_v3_scale(ng, -1.0f);
    if (pf_v3_dot(n, ng) < 0.0f) n = pf_v3_scale(n, -1.0f);
    *pos = pf_rt_offset_origin(sf.p, ng, ng);
    *nrm = n;
    *alb = pf_v3(sf.albedo[0], sf.albedo[1], sf.albedo[2]);
}

/* Returns the number of first-bounce VPLs appended to out (their sites are
 * also kept in s->fpos/fnrm for clustering). The light's RSM (gi_rsm.h) is
 * re-rendered by gi_rsm_set_update only when a light changed. The sampled
 * image: the main light's map (maps[0]: the first punctual light, or the
 * area lights' map when the scene has no punctual light) with, in a scene
 * that has both, the area lights' map stacked below it (gi_rsm_area.h).
 * Texel t of that image, picked with probability 1 / T (T texels: the
 * Hammersley point (u, v) addresses column floor(u size), row floor(v rows),
 * the faces of a cube or area map stacked as rows), gives a VPL of intensity
 * flux_t T / (pi n) (flux_t is the flux the texel's surface reflects,
 * albedo included). */
static uint32_t gi_ssvp_first_bounce(gi__ssvp_state *s, uint32_t n, gi_vpl_set *out)
{
    const gi_rsm_set *R = &s->rsm;
    const gi_rsm_map *mp = &R->maps[0]; /* "the main light source" */
    const gi_rsm_map *am = R->punctual > 0 && R->count > R->punctual ? &R->maps[R->punctual] : NULL;
    const uint32_t cols = mp->size, rows0 = mp->size * mp->face_count;
    const uint32_t rows = rows0 + (am ? am->size * am->face_count : 0);
    const uint32_t T = mp->texel_count + (am ? am->texel_count : 0);
    const float scale = (float)T / (float)n * PF_INV_PI;
    uint32_t c = 0;
    for (uint32_t k = 0; k < n; k++) {
        float u, v;
        gi__hammersley(k, n, &u, &v);
        uint32_t x = (uint32_t)(u * (float)cols), y = (uint32_t)(v * (float)rows);
        if (x >= cols) x = cols - 1;
        if (y >= rows) y = rows - 1;
        uint32_t t = y < rows0 ? mp->first + y * cols + x : am->first + (y - rows0) * cols + x;
        if (!R->valid[t]) continue; /* nothing seen, or outside a spot's cone */
        pf_vec3 p = pf_v3(R->pos_x[t], R->pos_y[t], R->pos_z[t]);
        pf_vec3 ng = pf_v3(R->ng_x[t], R->ng_y[t], R->ng_z[t]);
        gi_vpl *vp = &out->v[out->count++];
        vp->pos = pf_rt_offset_origin(p, ng, ng); /* off the surface, on the lit side */
        vp->nrm = pf_v3(R->nrm_x[t], R->nrm_y[t], R->nrm_z[t]);
        vp->intensity = pf_v3_scale(pf_v3(R->flux_r[t], R->flux_g[t], R->flux_b[t]), scale);
        vp->id = k;
        vp->moved = 1;
        s->fpos[c] = vp->pos;
        s->fnrm[c] = vp->nrm;
        c++;
    }
    return c;
}

/* ------------------------------------------------------ III-B cluster */

static void gi_ssvp_cluster(gi__ssvp_state *s, const pf_scene *sc, uint32_t count)
{
    gi_kmeans_options o = gi_kmeans_defaults();
    o.scale = pf_v3_length(pf_v3_sub(sc->bounds_max, sc->bounds_min));
    if (!(o.scale > 0.0f)) o.scale = 1.0f;
    o.max_iter = s->iters;
    int reuse = s->have_centroids && count > 0;
    s->last_iterations =
        gi_kmeans_run(&o, s->fpos, s->fnrm, count, s->cpos, s->cnrm, s->clusters, reuse, s->assign, s->members,
                      s->kscratch);
    if (count) s->have_centroids = 1;
}

/* ------------------------------------------ III-C paraboloid RSM per cluster */

typedef struct gi__map_job {
    gi__ssvp_state *s;
    const pf_rt *rt;
    const uint32_t *todo; /* clusters whose map is rendered */
} gi__map_job;

/* One row j of one map: the ray through every inside texel centre. Writes
 * only that row of that map. */
static void gi__map_row(void *p, uint32_t item, uint32_t worker)
{
    gi__map_job *J = p;
    gi__ssvp_state *s = J->s;
    const uint32_t R = s->map_res, c = J->todo[item / R], j = item % R;
    gi__ssvp_map *m = &s->map[c];
    rs_para_frame fr = rs_para_frame_make(s->cpos[c], s->cnrm[c]);
    pf_vec3 org = pf_rt_offset_origin(s->cpos[c], fr.n, fr.n);
    pf_ray *rays = s->wrays + (size_t)worker * R; /* per-worker scratch */
    for (uint32_t i = 0; i < R; i++) {
        pf_vec3 d = rs_para_uv_to_dir(rs_para_texel_uv(R, i, j));
        rays[i].org = org;
        rays[i].dir = pf_v3_add(pf_v3_add(pf_v3_scale(fr.t, d.x), pf_v3_scale(fr.b, d.y)), pf_v3_scale(fr.n, d.z));
        rays[i].tnear = 0.0f;
        rays[i].tfar = rs_para_texel_inside(R, i, j) ? INFINITY : -1.0f;
    }
    pf_rt_intersect(J->rt, rays, m->hit + (size_t)j * R, R);
}

/* Moved geometry (EXTENSION, the paper's scenes are static): a
 * cluster's map (the closest hits of rays into the hemisphere in front of
 * its centroid) is traced again unless the moved bounds, before and after,
 * lie wholly behind the centroid's tangent plane, where no such ray can
 * reach. The RSM is drawn again (gi_rsm_set_geometry_moved), so the
 * first-bounce VPLs and hence the clusters (k-means from the last
 * centroids, every frame) follow the moved surfaces. */
static void gi_ssvp_motion(gi__ssvp_state *s, const gi_motion *mo)
{
    if (!gi_motion_any(mo)) return;
    for (uint32_t c = 0; c < s->clusters; c++) {
        gi__ssvp_map *m = &s->map[c];
        if (!m->valid) continue;
        int behind = !mo->emitters;
        for (int k = 0; k < 8 && behind; k++) {
            pf_vec3 p = pf_v3(k & 1 ? mo->hi.x : mo->lo.x, k & 2 ? mo->hi.y : mo->lo.y, k & 4 ? mo->hi.z : mo->lo.z);
            behind = pf_v3_dot(pf_v3_sub(p, m->cpos), m->cnrm) < 0.0f;
        }
        if (!behind) m->valid = 0;
    }
}

/* Renders the maps of the non-empty clusters whose centroid moved. Returns
 * 0 when out of memory. */
static int gi_ssvp_cluster_maps(gi__ssvp_state *s, const gi_vpl_inputs *in)
{
    const uint32_t R = s->map_res;
    const size_t texels = (size_t)R * R;
    uint32_t todo[GI__SSVP_MAX_CLUSTERS], nt = 0;
    for (uint32_t c = 0; c < s->clusters; c++) {
        gi__ssvp_map *m = &s->map[c];
        if (!s->members[c]) continue;
        if (m->valid && !memcmp(&m->cpos, &s->cpos[c], sizeof m->cpos) && !memcmp(&m->cnrm, &s->cnrm[c], sizeof m->cnrm))
            continue;
        if (!m->hit && !(m->hit = malloc(texels * sizeof(pf_hit)))) return 0;
        m->cpos = s->cpos[c];
        m->cnrm = s->cnrm[c];
        m->valid = 1;
        todo[nt++] = c;
    }
    s->maps_rendered = nt;
    if (!nt) return 1;
    uint32_t workers = in->jobs ? pf_jobs_thread_count(in->jobs) : 1;
    if (workers > s->workers) { /* first frame (or more threads): grow once */
        free(s->wrays);
        s->wrays = malloc(sizeof(pf_ray) * R * workers);
        s->workers = s->wrays ? workers : 0;
        if (!s->workers) {
            for (uint32_t k = 0; k < nt; k++) s->map[todo[k]].valid = 0;
            return 0;
        }
    }
    gi__map_job J = {s, in->rt, todo};
    if (in->jobs) pf_jobs_parallel_for(in->jobs, gi__map_row, &J, nt * R, 4);
    else
        for (uint32_t it = 0; it < nt * R; it++) gi__map_row(&J, it, 0);
    return 1;
}

/* ------------------------------------------------ III-C second bounce */

/* The cluster's radiant intensity towards unit world direction w: what its
 * first-bounce members reflect, J(w) = sum I_i (n_i . w)^+ (in VPL order). */
static pf_vec3 gi__cluster_intensity(const gi_vpl *first, uint32_t nfirst, const uint32_t *assign, uint32_t c,
                                     pf_vec3 w)
{
    pf_vec3 J = pf_v3(0, 0, 0);
    for (uint32_t i = 0; i < nfirst; i++) {
        if (assign[i] != c) continue;
        float ct = pf_v3_dot(first[i].nrm, w);
        if (ct > 0.0f) J = pf_v3_add(J, pf_v3_scale(first[i].intensity, ct));
    }
    return J;
}

/* Aranha Sec. III-C: m "uniform samples on the unit circle" per cluster, each
 * read at its texel of the cluster's paraboloid map, one second-bounce VPL
 * per texel that hit a surface. The paper gives no flux for these VPLs;
 * softgi's follows Eq. 6's normalisation ("divide the contribution of each
 * VPL by the probability of it being selected"): the flux sent towards the
 * sample's direction divided by the sample's probability density and by m,
 * Phi = J(w) / (pdf(w) m), the intensity then Phi albedo / pi.
 *
 * The sample points. The 2D Hammersley set of Eq. 1, shifted by a
 * per-cluster random offset (xi, zeta) (Cranley-Patterson rotation; the
 * same every frame, so a static cluster keeps its VPLs):
 * u = (k + xi) / m, v = radical_inverse_2(k) + zeta (mod 1), then r =
 * sqrt(u), phi = 2 pi v. Each point is uniform over its own ring of equal
 * area, so the estimate is unbiased for any m. Without the
 * shift (u = k / m), point k = 0 sat at r = 0, on the centroid's normal, in
 * every cluster, and every point at the inner edge of its ring. For a
 * cluster facing its normal the paraboloid weight J / pdf = 4 pi sum I_i
 * (1 - u) / (1 + u)^3 (u = r^2: cos = (1 - u) / (1 + u), pdf = (1 + u)^2 /
 * (4 pi)) falls from 4 pi sum I_i at the centre to 0 at the rim (mean pi
 * sum I_i), so those points were a left Riemann sum of a falling
 * function: the cluster's flux came out 1 + 2 / m times
 * too large for large m (+4.8% at m = 42, +6% at m = 32), 1.58x at m = 4 and
 * 2.3x at m = 2. With the budget split over more clusters, m shrinks, so the
 * second bounce got brighter with the cluster count (docs/ssvp.md has the
 * before/after measurements).
 *
 * disc (--param disc=), what the disc point means:
 * - cosine (the default): the point is lifted to the hemisphere about the
 *   centroid's normal (Malley's method, z = sqrt(1 - r^2)): pdf = cos_c / pi.
 *   It is looked up in the same paraboloid map, and the weight uses the
 *   texel's direction. A cluster whose members face the centroid's normal
 *   has J(w) = cos_c sum I_i, so every VPL carries exactly pi sum I_i / m.
 *   That has no sampling error, even at m = 2.
 * - paraboloid (the paper's reading): the point is the map's own (u, v),
 *   uniform over its disc, so texel t is picked with probability
 *   (2 / R)^2 / pi, i.e. pdf = (1 + r_t^2)^2 / (4 pi) per steradian
 *   (dOmega = 4 / (1 + r^2)^2 du dv). The weights vary 4:1 over the disc,
 *   so with few samples per cluster the second bounce is noisier.
 *
 * origin (--param origin=), where the second-bounce rays start:
 * - centroid (the paper): the cluster is one point light at its centroid.
 *   It radiates J(w), what its members reflect, and its map gives the
 *   visibility. The estimate conserves the members' flux but moves it to the
 *   centroid, and a k-means centroid can float in the air or sit inside a
 *   solid (the paper's own caveat in III-B). The flux then lands where the
 *   centroid would send it, not where the members would: a bias that depends
 *   on the clusters' shapes (+16% flux at 8 clusters on the Cornell box:
 *   docs/ssvp.md).
 * - members (beyond the paper; unbiased): each sample picks a member i
 *   with probability P_i = lum(I_i) / sum lum(I), stratified (u selects the
 *   member, and its remainder within the member's interval is the sample's
 *   u). It traces one ray from the member itself: J = I_i (n_i . w)^+ / P_i,
 *   with the disc point about n_i. This is the "visibility map for each VPL"
 *   the paper wishes for (IV-B) at one ray per sample. It needs no cluster
 *   map; the clusters only split the budget. */
static void gi_ssvp_second_bounce(gi__ssvp_state *s, const pf_rt *rt, uint32_t nfirst, uint32_t m_total,
                                  gi_vpl_set *out)
{
    const uint32_t R = s->map_res;
    const gi_vpl *first = out->v; /* the first nfirst VPLs of out, in assign's order */
    const int members = s->origin == GI__SSVP_ORIGIN_MEMBERS, cosine = s->disc == GI__SSVP_DISC_COSINE;
    uint32_t nonempty = 0;
    for (uint32_t c = 0; c < s->clusters; c++) nonempty += s->members[c] > 0;
    if (!nonempty || !m_total) return;
    uint32_t rank = 0;
    for (uint32_t c = 0; c < s->clusters; c++) {
        if (!s->members[c]) continue;
        /* even split; the first (m_total mod nonempty) clusters get one more */
        uint32_t m = m_total / nonempty + (rank < m_total % nonempty);
        rank++;
        if (!m) continue;
        double total = 0.0; /* origin=members: the members' summed luminance */
        for (uint32_t i = 0; members && i < nfirst; i++)
            if (s->assign[i] == c) total += (double)pf_luminance(first[i].intensity);
        if (members && !(total > 0.0)) continue;
        const gi__ssvp_map *map = &s->map[c];
        rs_para_frame fr = rs_para_frame_make(s->cpos[c], s->cnrm[c]);
        pf_vec3 org = pf_rt_offset_origin(s->cpos[c], fr.n, fr.n);
        /* the cluster's own shift of the point set, the same every frame */
        const double xi = pf_random(GI__SSVP_STREAM, c, 0, 0), zeta = pf_random(GI__SSVP_STREAM, c, 0, 1);
        uint32_t src = 0;   /* origin=members: the member u falls in (scanned forward: u grows with k) */
        double below = 0.0; /* the summed luminance of the members before src */
        for (uint32_t k = 0; k < m; k++) {
            double u = ((double)k + xi) / (double)m, v = (double)gi__vdc(k) + zeta, p_src = 1.0;
            if (v >= 1.0) v -= 1.0;
            if (members) {
                double x = u * total, l;
                for (;;) {
                    while (src < nfirst && s->assign[src] != c) src++;
                    assert(src < nfirst);
                    l = (double)pf_luminance(first[src].intensity);
                    if (x < below + l) break;
                    below += l, src++;
                }
                p_src = l / total;
                u = (x - below) / l; /* uniform in [0, 1) again */
                fr = rs_para_frame_make(first[src].pos, first[src].nrm);
            }
            float uf = fminf((float)u, 0x1.fffffep-1f), r = sqrtf(uf), ph = 2.0f * PF_PI * (float)v;
            pf_vec2 uv = {r * cosf(ph), r * sinf(ph)};
            pf_vec3 dl = cosine ? pf_v3(uv.x, uv.y, sqrtf(fmaxf(0.0f, 1.0f - uf))) : rs_para_uv_to_dir(uv);
            uint32_t t = 0;
            if (!members) { /* the map's texel, and its direction from here on */
                t = rs_para_texel_of(R, dl);
                uv = rs_para_texel_uv(R, t % R, t / R);
                dl = rs_para_uv_to_dir(uv);
            }
            /* the sample's probability density per steradian */
            float q = 1.0f + uv.x * uv.x + uv.y * uv.y;
            float pdf = cosine ? dl.z * PF_INV_PI : q * q / (4.0f * PF_PI);
            if (!(pdf > 0.0f)) continue; /* on the horizon: never picked by the cosine density */
            /* the texel's ray, the same expression as gi__map_row's */
            pf_vec3 w = pf_v3_add(pf_v3_add(pf_v3_scale(fr.t, dl.x), pf_v3_scale(fr.b, dl.y)), pf_v3_scale(fr.n, dl.z));
            pf_hit hit;
            if (members) {
                pf_ray ray = {first[src].pos, 0.0f, w, INFINITY}; /* already off its surface */
                hit = pf_rt_intersect1(rt, ray);
            } else if (s->lazy_maps) {
                pf_ray ray = {org, 0.0f, w, INFINITY};
                hit = pf_rt_intersect1(rt, ray); /* the same bits as in a packet (pf_rt.h) */
            } else {
                hit = map->hit[t];
            }
            if (hit.prim == PF_RT_MISS) continue;
            pf_vec3 J = members ? pf_v3_scale(first[src].intensity, fmaxf(0.0f, pf_v3_dot(first[src].nrm, w)))
                                : gi__cluster_intensity(first, nfirst, s->assign, c, w);
            float f = (float)(1.0 / ((double)pdf * (double)m * p_src)) * PF_INV_PI; /* Phi / J, then albedo / pi */
            pf_vec3 alb;
            gi_vpl *vp = &out->v[out->count++];
            gi__site(rt, &hit, w, &vp->pos, &vp->nrm, &alb);
            vp->intensity = pf_v3_scale(pf_v3_mul(J, alb), f);
            vp->id = 0x80000000u | (c << 16) | k;
            vp->moved = 1;
        }
    }
}

/* ------------------------------------------------------------- update */

static pf_result gi__ssvp_update(void *state, const gi_vpl_inputs *in, gi_vpl_set *out, pf_error *err)
{
    gi__ssvp_state *s = state;
    out->count = 0;
    uint32_t n1 = s->first, n2 = in->bounces == 1 ? 0 : s->second;
    if (!s->first_set && !s->second_set) { /* defaults: the budget, half each (256 + 256 at --vpls 512) */
        uint32_t b = in->budget < 2u * GI__SSVP_MAX_SAMPLES ? in->budget : 2u * GI__SSVP_MAX_SAMPLES;
        n1 = n2 ? b / 2 : b;
        if (n1 > GI__SSVP_MAX_SAMPLES) n1 = GI__SSVP_MAX_SAMPLES;
        if (!n1) n1 = 1;
        if (n2) n2 = b > n1 ? b - n1 : 0;
    }
    if (n1 + n2 > in->budget) {
        if (s->first_set || (s->second_set && n2))
            return pf_error_set(err, PF_ERR_ARGUMENT,
                                "--method ssvp: first=%u + second=%u VPLs exceed the VPL budget --vpls %u", n1, n2,
                                in->budget);
        /* left: no second bounce (second=0 or --bounces 1) and the default
         * first bounce, which fits itself to the budget */
        n1 = in->budget;
    }
    if (!s->origin_set) /* the default origin: the paper's in one frame, the unbiased one under cycling */
        s->origin = in->cycle > 1 ? GI__SSVP_ORIGIN_MEMBERS : GI__SSVP_ORIGIN_CENTROID;
    if (!gi__ssvp_first_room(s, n1)) return pf_error_set(err, PF_ERR_OUT_OF_MEMORY, "out of memory");
    pf_result r = gi_vpl_set_reserve(out, n1 + n2 ? n1 + n2 : 1, err);
    if (r != PF_OK) return r;
    s->maps_rendered = 0;
    if (!in->jobs) return pf_error_set(err, PF_ERR_ARGUMENT, "--method ssvp: needs the job system (inputs.jobs)");
    if ((r = gi_rsm_set_geometry_moved(&s->rsm, in->motion, err)) != PF_OK) return r;
    if ((r = gi_rsm_set_update(&s->rsm, in->scene, in->area, in->rt, in->jobs, err)) != PF_OK) return r;
    gi_ssvp_motion(s, in->motion);
    if (s->rsm.count > 0 && n1) {
        uint32_t nf = gi_ssvp_first_bounce(s, n1, out);
        gi_ssvp_cluster(s, in->scene, nf);
        if (n2 && nf) {
            if (!s->lazy_maps && s->origin == GI__SSVP_ORIGIN_CENTROID && !gi_ssvp_cluster_maps(s, in))
                return pf_error_set(err, PF_ERR_OUT_OF_MEMORY, "out of memory");
            gi_ssvp_second_bounce(s, in->rt, nf, n2, out);
        }
    }
    /* moved flags against the previous frame (same id at the same slot) */
    for (uint32_t i = 0; i < out->count; i++) {
        gi_vpl *v = &out->v[i];
        if (i < s->prev.count && s->prev.v[i].id == v->id && !memcmp(&s->prev.v[i].pos, &v->pos, sizeof v->pos) &&
            !memcmp(&s->prev.v[i].nrm, &v->nrm, sizeof v->nrm) &&
            !memcmp(&s->prev.v[i].intensity, &v->intensity, sizeof v->intensity))
            v->moved = 0;
    }
    r = gi_vpl_set_reserve(&s->prev, out->count ? out->count : 1, err);
    if (r != PF_OK) return r;
    memcpy(s->prev.v, out->v, sizeof(gi_vpl) * out->count);
    s->prev.count = out->count;
    return PF_OK;
}

/* ------------------------------------------------------------- the view */

/* The clusters of III-B over the image: each first-bounce VPL the camera
 * sees in its cluster's colour (3x3), each centroid as a cross with its
 * normal (the point its paraboloid RSM of III-C is rendered from), and the
 * second-bounce VPLs made from that cluster's map as single dots of the
 * same colour. */
static int gi__ssvp_view(const void *state, const gi_vpl_view_ctx *c, uint8_t *rgb)
{
    const gi__ssvp_state *s = state;
    if (!s || !s->have_centroids || !s->fpos) return 0;
    static const uint8_t white[3] = {255, 255, 255};
    c->background(c, rgb);
    uint32_t nf = 0, nonempty = 0;
    for (uint32_t k = 0; k < s->clusters; k++) nf += s->members[k], nonempty += s->members[k] > 0;
    float x, y;
    uint8_t col[3];
    for (uint32_t i = 0; i < nf && i < s->fcap; i++) {
        if (!c->project(c, s->fpos[i], &x, &y) || !c->visible(c, s->fpos[i])) continue;
        c->palette(s->assign[i], col);
        c->fill(c, rgb, (int)floorf(x) - 1, (int)floorf(y) - 1, 3, 3, col);
    }
    uint32_t second = 0;
    for (uint32_t i = 0; i < c->vpls->count; i++) {
        const gi_vpl *v = &c->vpls->v[i];
        if (!(v->id & 0x80000000u)) continue;
        second++;
        if (!c->project(c, v->pos, &x, &y) || !c->visible(c, v->pos)) continue;
        c->palette((v->id >> 16) & 0x7fffu, col);
        c->fill(c, rgb, (int)floorf(x), (int)floorf(y), 1, 1, col);
    }
    float diag = pf_v3_length(pf_v3_sub(c->scene->bounds_max, c->scene->bounds_min));
    for (uint32_t k = 0; k < s->clusters; k++) {
        if (!s->members[k] || !c->project(c, s->cpos[k], &x, &y)) continue;
        float nx, ny;
        c->palette(k, col);
        c->line(c, rgb, (int)floorf(x) - 6, (int)floorf(y), (int)floorf(x) + 6, (int)floorf(y), white);
        c->line(c, rgb, (int)floorf(x), (int)floorf(y) - 6, (int)floorf(x), (int)floorf(y) + 6, white);
        c->fill(c, rgb, (int)floorf(x) - 2, (int)floorf(y) - 2, 5, 5, col);
        if (c->project(c, pf_v3_add(s->cpos[k], pf_v3_scale(s->cnrm[k], 0.05f * diag)), &nx, &ny))
            c->line(c, rgb, (int)floorf(x), (int)floorf(y), (int)floorf(nx), (int)floorf(ny), col);
    }
    char text[160];
    snprintf(text, sizeof text, "%u first-bounce VPLs in %u clusters (k-means, %u iterations), %u second-bounce VPLs",
             nf, nonempty, s->last_iterations, second);
    c->text(c, rgb, 4, 2, text, white);
    c->text(c, rgb, 4, 12, "crosses: centroids and normals (one paraboloid RSM each, III-C)", white);
    /* the key: the clusters' colours and sizes (the first 8) */
    char names[8][48]; /* "cluster %u: %u VPLs" with two 10-digit numbers fits */
    const char *np[8];
    uint8_t cols[8][3];
    uint32_t nk = 0;
    for (uint32_t k = 0; k < s->clusters && nk < 8; k++) {
        if (!s->members[k]) continue;
        snprintf(names[nk], sizeof names[nk], "cluster %u: %u VPLs", k, s->members[k]);
        np[nk] = names[nk];
        c->palette(k, cols[nk++]);
    }
    c->key(c, rgb, "k-means clusters (Eq. 2)", np, (const uint8_t(*)[3])cols, nk);
    return 1;
}

static uint32_t gi__ssvp_bounce(const void *state, const gi_vpl *v, uint32_t bounces)
{
    (void)state, (void)bounces;
    return v->id & 0x80000000u ? 2u : 1u; /* second-bounce ids carry the high bit */
}

const gi_vpl_method gi_method_ssvp = {
    .name = "ssvp",
    .paper = "Screen-space VPL propagation, two bounces (Aranha, Sec. III)",
    .create = gi__ssvp_create,
    .update = gi__ssvp_update,
    .destroy = gi__ssvp_destroy,
    .parts = NULL,
    .why = "a second bounce costs one map per VPL, so SSVP clusters the first-bounce VPLs (k-means, Eq. 2) and "
           "renders one paraboloid RSM per cluster to place the second-bounce VPLs (Aranha Sec. III-B, III-C)",
    .view_caption = "the first-bounce VPLs by cluster colour, the centroids with their normals (one RSM each) and "
                    "the second-bounce VPLs each cluster's map gave (dots)",
    .view = gi__ssvp_view,
    .bounce = gi__ssvp_bounce,
};
