/* gi_iir: Incremental Instant Radiosity (Laine, Saransaari, Kontkanen,
 * Lehtinen, Aila 2007, Sec. 3 steps 1-4 and Sec. 4 "VPL Management").
 *
 * VPLs sit on the first hits of rays from the primary lights (single
 * bounce, as in the paper: --bounces does not apply). Each frame, per
 * primary light, in the paper's order:
 *   1. gi__iir_validity        Sec. 4.4: a shadow ray from the light to each
 *                              VPL (Embree), plus the outside-the-cone test
 *                              for spots (outside-the-beam for directional);
 *   2. gi__iir_delete_invalid  Sec. 4.5: remove them, rebuild the Delaunay
 *      gi__iir_delete_for_room triangulation, then delete valid ones by the
 *                              shortest-edge / second-closest-neighbour rule
 *                              until recalcMin slots are free;
 *   3. gi__iir_create_new      Sec. 4.6: new sampling points at the centre of
 *                              the largest empty circle until recalcMax
 *                              insertions or maxLights; one ray each;
 *   4. gi__iir_intensities     Sec. 4.7: intensities from the Voronoi areas,
 *                              scaled so they sum to the light's power.
 *
 * Domains (Sec. 4.1; gi_delaunay.h does the geometry):
 *   point light: the unit sphere; the sampling point of a VPL is the unit
 *     direction from the light to it. Uniform on the sphere = the light's
 *     (uniform) emission.
 *   spot light: the unit disc (Nusselt analog). A disc point at radius r
 *     and angle phi maps to the direction at polar angle theta around the
 *     spot axis with sin(theta) = r sin(outer), i.e. the paper's "radial
 *     stretch" so the disc covers exactly the outer cone (outer = 90 deg is
 *     the paper's 180-degree spot). Uniform on the disc is then the cosine
 *     lobe squeezed into the cone, with solid angle per disc area
 *     d(omega)/dA = sin^2(outer) / cos(theta). softgi's spots are
 *     KHR_lights_punctual spots (a smooth cone factor f(theta), not the
 *     paper's cosine), so a VPL's weight is its Voronoi area times the
 *     emission per disc area, f(theta) sin^2(outer) / cos(theta), evaluated
 *     at its sampling point (for the paper's spot this is constant and the
 *     weight is the area, as in the paper).
 *   directional light (EXTENSION, not in the paper): the unit disc scaled to
 *     a disc of the scene's bounding radius R across the beam, 2R before the
 *     scene centre (exactly gi_ir.c's emission disc); power E pi R^2.
 *   area lights (emissive triangles, gi_area.h; EXTENSION, not in the
 *     paper, whose Sec. 7 says a true area light would need a 4D domain):
 *     all emitters share one more domain, the unit disc as the cosine lobe
 *     around the emitter normal (sin(theta) = r, Nusselt); each sample also
 *     has a point on the emitters, drawn by power (gi_area_sample_point)
 *     from stable per-sample values (a hash of its VPL id), fixed for its
 *     life. So the distribution is managed over directions only; the
 *     points are plain Monte Carlo. Its flux is its Voronoi-area fraction of
 *     pi Le / pdf_area (an unbiased share of the emitters' power). While
 *     the emitters stay, these VPLs stay valid (the shadow ray from the
 *     emission point is still cast) and only recalcMin churns; when an
 *     animated emitter moves, every one of them is invalid (gi__iir_validity).
 *
 * Units match gi_ir.c: a light's power is 4 pi I (point), I integral of
 * the cone factor over the cone (spot), E pi R^2 (directional), in RGB; a
 * VPL's flux is that power times its weight over the sum of the weights of
 * all the light's sampling points (including those whose ray left the
 * scene, whose power is lost as in IR); its intensity Phi albedo / pi.
 * Several lights: one domain each, the VPL budget split by the lights'
 * luminance power (gi_ir.c's measure) with largest remainders.
 *
 * Deviations (also in the README section):
 *   - A sampling point whose ray left the scene stays in the distribution
 *     as an empty sample (it takes a slot, emits nothing) while its ray
 *     still misses, re-tested each frame like a VPL; the paper drops it, so
 *     the same empty region would be re-sampled every frame.
 *   - The paper does not say how the set starts: the first frame (and any
 *     frame after the lights or the budget change) fills each domain to its
 *     quota by repeated largest-empty-circle insertion (a farthest-point
 *     sequence); recalcMax applies from the next frame on.
 *   - Two VPLs whose sampling points coincide on the 2^-24 grid (or that
 *     the sphere's hull leaves inside) are deleted with the invalid ones
 *     (the shortest-edge rule would pick them first anyway).
 *   - Surface colour: the albedo at texture mip level albedoLod (default 4,
 *     a 16x16-texel box average) for the paper's "heavily blurred" texture.
 *   - Moved flags: only a new VPL is `moved`: its slot's paraboloid map must
 *     be rendered. Re-weighting (Sec. 4.7 changes every intensity every
 *     frame) needs no new map, so those VPLs are not flagged. A VPL keeps its
 *     slot (index in the output) while it lives; new VPLs fill the lowest
 *     free slots; free slots are emitted as zero-intensity entries so every
 *     slot index stays stable for the frame's per-slot map cache.
 *   - Steady state: with a static light every VPL stays valid, yet
 *     recalcMin > 0 still replaces recalcMin VPLs per frame (Sec. 4.2: "the
 *     quality of the VPL distribution is improved even when all VPLs are
 *     valid"); recalcMin=0 freezes a converged set.
 *
 * Parameters (--param KEY=VALUE): recalcMin (4), recalcMax (8), albedoLod
 * (4). maxLights is the VPL budget (--vpls, 256 by default). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gi_delaunay.h"
#include "gi_light.h"
#include "gi_vpl.h"

enum { GI__EMPTY = 0, GI__VPL = 1, GI__MISS = 2 };

typedef struct gi__slot {
    uint8_t kind, born; /* born: created this frame (moved) */
    uint16_t light;
    uint32_t id;
    uint32_t prim; /* VPLs: the triangle it sits on (moved geometry invalidates it) */
    pf_vec3 pos, nrm, albedo;
    pf_vec3 intensity;
    double dp[3]; /* sampling point (misses keep theirs; VPLs recompute it each frame) */
    /* area lights: the emission point (pushed off the emitter), its face
     * normal and Le / pdf_area (W/(sr m^2) over 1/m^2) */
    pf_vec3 em_p, em_n, em_w;
} gi__slot;

/* A light's frame: where its domain sits this frame. */
typedef struct gi__lframe {
    int area;               /* the area-light domain (extension) */
    pf_light_type type;
    pf_vec3 pos, dir, t, b; /* dir: spot axis / beam direction; t, b complete the basis */
    float sin_o, cos_o;     /* spot: outer cone */
    pf_vec3 centre;         /* directional: scene centre, radius */
    float radius;
} gi__lframe;

typedef struct gi__domain {
    gi_dt dt;
    int area;
    pf_light_type type;
    uint32_t quota;
    uint32_t filled; /* the initial fill is done */
} gi__domain;

typedef struct gi__iir_state {
    uint32_t recalc_min, recalc_max, albedo_lod;
    uint32_t budget, nlights, ndom; /* ndom = nlights + 1 when the scene has area lights */
    gi__domain *dom;
    gi__slot *slot;
    uint32_t next_id;
    /* scratch, budget-sized */
    pf_ray *rays;
    pf_hit *hits;
    uint8_t *occ;
    uint32_t *ray_slot;
    double *area;
} gi__iir_state;

static pf_result gi__iir_create(void **state, const gi_params *params, pf_error *err)
{
    static const char *const known[] = {"recalcMin", "recalcMax", "albedoLod", NULL};
    pf_result r = gi_params_check(params, "iir", known, err);
    if (r != PF_OK) return r;
    uint32_t rmin = 4, rmax = 8, lod = (uint32_t)GI_VPL_ALBEDO_LOD;
    if ((r = gi_param_u32(params, "recalcMin", 0, 65536, &rmin, err)) != PF_OK) return r;
    if ((r = gi_param_u32(params, "recalcMax", 1, 65536, &rmax, err)) != PF_OK) return r;
    if ((r = gi_param_u32(params, "albedoLod", 0, 16, &lod, err)) != PF_OK) return r;
    if (rmin > rmax)
        return pf_error_set(err, PF_ERR_ARGUMENT, "--method iir: recalcMin (%u) must not exceed recalcMax (%u)", rmin,
                            rmax);
    gi__iir_state *s = calloc(1, sizeof *s);
    if (!s) return pf_error_set(err, PF_ERR_OUT_OF_MEMORY, "out of memory");
    s->recalc_min = rmin, s->recalc_max = rmax, s->albedo_lod = lod;
    *state = s;
    return PF_OK;
}

static void gi__iir_reset(gi__iir_state *s)
{
    for (uint32_t l = 0; l < s->ndom; l++) gi_dt_free(&s->dom[l].dt);
    free(s->dom), free(s->slot), free(s->rays), free(s->hits), free(s->occ), free(s->ray_slot), free(s->area);
    s->dom = NULL, s->slot = NULL, s->rays = NULL, s->hits = NULL, s->occ = NULL, s->ray_slot = NULL, s->area = NULL;
    s->nlights = 0, s->ndom = 0, s->budget = 0;
}

static void gi__iir_destroy(void *state)
{
    gi__iir_state *s = state;
    if (!s) return;
    gi__iir_reset(s);
    free(s);
}


/* Integral of the spot's cone factor over its cone, per unit intensity
 * (sr): the midpoint rule of gi_ir.c's gi__light_power. */
static double gi__spot_solid(const pf_light *l)
{
    double co = cos((double)l->outer_cone), sum = 0.0;
    for (int k = 0; k < 256; k++) {
        double ct = co + (1.0 - co) * (k + 0.5) / 256.0;
        sum += gi_light_spot_factor(l, (float)ct);
    }
    return 2.0 * PF_PI * sum * (1.0 - co) / 256.0;
}

/* Emitted power per unit colour (W per unit of `color`), as gi_ir.c. */
static double gi__light_power1(const pf_light *l, double radius)
{
    switch (l->type) {
    case PF_LIGHT_POINT: return 4.0 * PF_PI * l->intensity;
    case PF_LIGHT_SPOT: return l->intensity * gi__spot_solid(l);
    default: return l->intensity * PF_PI * radius * radius;
    }
}

static gi__lframe gi__light_frame(const pf_light *L, const pf_scene *s)
{
    gi__lframe f;
    memset(&f, 0, sizeof f);
    f.type = L->type;
    f.pos = L->position;
    f.dir = L->direction;
    pf_v3_basis(f.dir, &f.t, &f.b);
    float outer = fminf(fmaxf(L->outer_cone, 1e-4f), 0.5f * PF_PI);
    f.sin_o = sinf(outer);
    f.cos_o = cosf(L->outer_cone);
    f.centre = pf_v3_scale(pf_v3_add(s->bounds_min, s->bounds_max), 0.5f);
    f.radius = 0.5f * pf_v3_length(pf_v3_sub(s->bounds_max, s->bounds_min)) * 1.001f; /* as gi_ir.c */
    return f;
}

/* A VPL position -> its sampling point; 0 if outside the light's domain
 * (behind a spot's outer cone, outside the directional beam's disc). */
static int gi__to_domain(const gi__lframe *f, pf_vec3 p, double dp[3])
{
    if (f->type == PF_LIGHT_DIRECTIONAL) {
        pf_vec3 q = pf_v3_sub(p, f->centre);
        double x = pf_v3_dot(q, f->t) / f->radius, y = pf_v3_dot(q, f->b) / f->radius;
        dp[0] = x, dp[1] = y, dp[2] = 0.0;
        return x * x + y * y <= 1.0;
    }
    pf_vec3 w = pf_v3_normalize(pf_v3_sub(p, f->pos));
    if (f->type == PF_LIGHT_POINT) {
        dp[0] = w.x, dp[1] = w.y, dp[2] = w.z;
        return 1;
    }
    float z = pf_v3_dot(w, f->dir);
    dp[0] = pf_v3_dot(w, f->t) / f->sin_o, dp[1] = pf_v3_dot(w, f->b) / f->sin_o, dp[2] = 0.0;
    return z > 0.0f && z >= f->cos_o; /* outside the cone: invalid (Sec. 4.4, condition 2) */
}

/* A sampling point -> the ray that creates its VPL. */
static pf_ray gi__from_domain(const gi__lframe *f, const double dp[3])
{
    pf_ray r;
    r.tnear = 0.0f;
    r.tfar = INFINITY;
    if (f->type == PF_LIGHT_DIRECTIONAL) {
        r.org = pf_v3_add(pf_v3_sub(f->centre, pf_v3_scale(f->dir, 2.0f * f->radius)),
                          pf_v3_add(pf_v3_scale(f->t, (float)dp[0] * f->radius), pf_v3_scale(f->b, (float)dp[1] * f->radius)));
        r.dir = f->dir;
        return r;
    }
    r.org = f->pos;
    if (f->type == PF_LIGHT_POINT) {
        r.dir = pf_v3_normalize(pf_v3((float)dp[0], (float)dp[1], (float)dp[2]));
        return r;
    }
    double x = dp[0] * f->sin_o, y = dp[1] * f->sin_o, st2 = fmin(1.0, x * x + y * y);
    float z = (float)sqrt(1.0 - st2);
    r.dir = pf_v3_normalize(pf_v3_add(pf_v3_add(pf_v3_scale(f->t, (float)x), pf_v3_scale(f->b, (float)y)), pf_v3_scale(f->dir, z)));
    return r;
}

/* Area lights: the disc point as the cosine lobe around the emitter's
 * normal (Nusselt analog, sin(theta) = r), from the sample's emission point. */
static pf_ray gi__from_domain_area(const gi__slot *q)
{
    pf_vec3 t, b;
    pf_v3_basis(q->em_n, &t, &b);
    double x = q->dp[0], y = q->dp[1];
    float z = (float)sqrt(fmax(0.0, 1.0 - (x * x + y * y)));
    pf_ray r = {q->em_p, 0.0f, pf_v3_normalize(pf_v3_add(pf_v3_add(pf_v3_scale(t, (float)x), pf_v3_scale(b, (float)y)), pf_v3_scale(q->em_n, z))), INFINITY};
    return r;
}

/* The emission per unit domain area at sampling point dp, relative to the
 * light's intensity (Sec. 4.7 weights; see the header). */
static double gi__density(const gi__lframe *f, const pf_light *L, const double dp[3])
{
    if (f->area || f->type != PF_LIGHT_SPOT) return 1.0;
    double x = dp[0] * f->sin_o, y = dp[1] * f->sin_o;
    double ct = sqrt(fmax(0.0, 1.0 - (x * x + y * y)));
    return gi_light_spot_factor(L, (float)ct) * (double)f->sin_o * f->sin_o / fmax(ct, 1e-6);
}

static uint32_t gi__domain_count(const gi__iir_state *s, uint32_t l)
{
    uint32_t n = 0;
    for (uint32_t i = 0; i < s->budget; i++) n += s->slot[i].kind != GI__EMPTY && s->slot[i].light == l;
    return n;
}

/* ------------------------------------------------------------ step 1: validity (Sec. 4.4) */

/* Marks invalid samples EMPTY and gives every valid one its sampling point.
 * VPLs: the facing test, the domain test (spot cone, beam disc) and an
 * Embree shadow ray from the light; misses: their ray must still miss.
 * Moved geometry (EXTENSION: the paper's scenes are static): a VPL whose
 * triangle moved since the last frame is invalid, wherever it now is (its
 * stored position is where the surface was), and so is every area-light VPL
 * once an emitter moved (its emission point is stale); a VPL a moved object
 * now hides from the light fails its shadow ray (Embree is up to date), and
 * a miss the moved object now blocks fails its ray. All are re-sampled by
 * Sec. 4.6 like any invalid VPL. */
static void gi__iir_validity(gi__iir_state *s, const gi_vpl_inputs *in, uint32_t l, const gi__lframe *f)
{
    uint32_t nr = 0, nm = 0;
    for (uint32_t i = 0; i < s->budget; i++) {
        gi__slot *q = &s->slot[i];
        if (q->kind != GI__VPL || q->light != l) continue;
        if (gi_motion_tri(in->motion, q->prim) || (f->area && in->motion && in->motion->emitters)) {
            q->kind = GI__EMPTY;
            continue;
        }
        if (f->area) { /* emitters as sampled: the stored sampling point; facing and a shadow ray */
            pf_vec3 d = pf_v3_sub(q->pos, q->em_p);
            if (!(pf_v3_dot(q->nrm, d) < 0.0f)) q->kind = GI__EMPTY;
            else s->rays[nr] = (pf_ray){q->em_p, 0.0f, d, 0.9999f}, s->ray_slot[nr++] = i;
            continue;
        }
        pf_vec3 to_light = f->type == PF_LIGHT_DIRECTIONAL ? pf_v3_scale(f->dir, -1.0f) : pf_v3_sub(f->pos, q->pos);
        if (!(pf_v3_dot(q->nrm, to_light) > 0.0f) || !gi__to_domain(f, q->pos, q->dp)) {
            q->kind = GI__EMPTY;
            continue;
        }
        pf_ray r;
        if (f->type == PF_LIGHT_DIRECTIONAL) r = (pf_ray){q->pos, 0.0f, pf_v3_scale(f->dir, -1.0f), INFINITY};
        else r = (pf_ray){f->pos, 0.0f, pf_v3_sub(q->pos, f->pos), 0.9999f};
        s->rays[nr] = r;
        s->ray_slot[nr++] = i;
    }
    pf_rt_occluded(in->rt, s->rays, s->occ, nr);
    for (uint32_t k = 0; k < nr; k++)
        if (s->occ[k]) s->slot[s->ray_slot[k]].kind = GI__EMPTY;
    for (uint32_t i = 0; i < s->budget; i++) {
        gi__slot *q = &s->slot[i];
        if (q->kind != GI__MISS || q->light != l) continue;
        s->rays[nm] = f->area ? gi__from_domain_area(q) : gi__from_domain(f, q->dp);
        s->ray_slot[nm++] = i;
    }
    pf_rt_intersect(in->rt, s->rays, s->hits, nm);
    for (uint32_t k = 0; k < nm; k++)
        if (s->hits[k].prim != PF_RT_MISS) s->slot[s->ray_slot[k]].kind = GI__EMPTY; /* it would hit now */
}

/* ------------------------------------------------------------ step 2: deletion (Sec. 4.5) */

/* Rebuilds the triangulation of the valid samples; samples it rejects
 * (coincident on the grid) are deleted too. */
static pf_result gi__iir_delete_invalid(gi__iir_state *s, uint32_t l, pf_error *err)
{
    gi_dt *dt = &s->dom[l].dt;
    memset(dt->present, 0, dt->cap);
    for (uint32_t i = 0; i < s->budget; i++)
        if (s->slot[i].kind != GI__EMPTY && s->slot[i].light == l) gi_dt_set_point(dt, i, s->slot[i].dp);
    pf_result r = gi_dt_rebuild(dt, err);
    if (r != PF_OK) return r;
    for (uint32_t i = 0; i < s->budget; i++)
        if (s->slot[i].kind != GI__EMPTY && s->slot[i].light == l && !dt->present[i]) s->slot[i].kind = GI__EMPTY;
    return PF_OK;
}

/* Deletes valid samples by the shortest-Delaunay-edge rule until recalcMin
 * of the light's slots are free (and the light is within its quota). */
static pf_result gi__iir_delete_for_room(gi__iir_state *s, uint32_t l, pf_error *err)
{
    gi__domain *d = &s->dom[l];
    uint32_t count = gi__domain_count(s, l), room = s->recalc_min < d->quota ? s->recalc_min : d->quota;
    while (count > 0 && count + room > d->quota) {
        uint32_t v = gi_dt_deletion_candidate(&d->dt);
        if (v == GI_DT_INF) v = 0; /* a single sample left: take it */
        while (v < s->budget && !(s->slot[v].kind != GI__EMPTY && s->slot[v].light == l)) v++;
        if (v >= s->budget) break;
        s->slot[v].kind = GI__EMPTY;
        pf_result r = gi_dt_remove(&d->dt, v, err);
        if (r != PF_OK) return r;
        count--;
    }
    return PF_OK;
}

/* ------------------------------------------------------------ step 3: creation (Sec. 4.6) */

static uint32_t gi__free_slot(const gi__iir_state *s)
{
    for (uint32_t i = 0; i < s->budget; i++)
        if (s->slot[i].kind == GI__EMPTY) return i;
    return UINT32_MAX;
}

/* New sampling points at the centre of the largest empty circle, each added
 * to the triangulation before the next is chosen; then one ray each: a hit
 * makes a VPL there (surface colour at mip level albedoLod), a miss an
 * empty sample. */
static pf_result gi__iir_create_new(gi__iir_state *s, const gi_vpl_inputs *in, uint32_t l, const gi__lframe *f,
                                    pf_error *err)
{
    gi__domain *d = &s->dom[l];
    uint32_t count = gi__domain_count(s, l), limit = d->filled ? s->recalc_max : d->quota, made = 0;
    while (made < limit && count < d->quota) {
        uint32_t v = gi__free_slot(s);
        if (v == UINT32_MAX) break;
        double c[3];
        gi_dt_largest_empty(&d->dt, c, NULL);
        int ok = gi_dt_insert(&d->dt, v, c, err);
        if (ok < 0) return PF_ERR_OUT_OF_MEMORY;
        if (ok == 0) break; /* the centre coincides with a sample: nothing left to improve */
        gi__slot *q = &s->slot[v];
        q->kind = GI__MISS;
        q->born = 1;
        q->light = (uint16_t)l;
        q->id = s->next_id++;
        memcpy(q->dp, d->dt.p[v], sizeof q->dp);
        if (f->area) {
            /* the point on the emitters from stable per-sample values (a hash
             * of the VPL id), by power as gi_area_sample_point does */
            uint32_t h[3];
            for (uint32_t k = 0; k < 3; k++) h[k] = pf_hash32(q->id * 3u + k + 0x9e3779b9u);
            gi_area_sample as;
            gi_area_sample_point(in->area, (h[0] >> 8) * (1.0 / 16777216.0), (float)((h[1] >> 8) * (1.0 / 16777216.0)),
                                 (float)((h[2] >> 8) * (1.0 / 16777216.0)), &as);
            q->em_n = as.n;
            q->em_p = pf_rt_offset_origin(as.p, as.n, as.n);
            q->em_w = pf_v3_scale(as.radiance, 1.0f / as.pdf_area);
            s->rays[made] = gi__from_domain_area(q);
        } else
            s->rays[made] = gi__from_domain(f, q->dp);
        s->ray_slot[made++] = v;
        count++;
    }
    d->filled = 1;
    pf_rt_intersect(in->rt, s->rays, s->hits, made);
    for (uint32_t k = 0; k < made; k++) {
        gi__slot *q = &s->slot[s->ray_slot[k]];
        if (s->hits[k].prim == PF_RT_MISS) {
            q->pos = f->pos, q->nrm = pf_v3(0, 1, 0); /* a placeholder; never lit */
            continue;
        }
        pf_surface sf;
        pf_rt_surface(in->rt, &s->hits[k], (float)s->albedo_lod, &sf);
        pf_vec3 n = sf.ns, ng = sf.ng, dir = s->rays[k].dir;
        if (pf_v3_dot(ng, dir) > 0.0f) ng = pf_v3_scale(ng, -1.0f); /* two-sided: face the light */
        if (pf_v3_dot(n, ng) < 0.0f) n = pf_v3_scale(n, -1.0f);
        q->kind = GI__VPL;
        q->prim = s->hits[k].prim;
        q->pos = pf_rt_offset_origin(sf.p, ng, ng);
        q->nrm = n;
        q->albedo = pf_v3(sf.albedo[0], sf.albedo[1], sf.albedo[2]);
    }
    return PF_OK;
}

/* ------------------------------------------------------------ step 4: intensities (Sec. 4.7) */

static void gi__iir_intensities(gi__iir_state *s, const pf_light *L, uint32_t l, const gi__lframe *f)
{
    gi_dt_voronoi_areas(&s->dom[l].dt, s->area);
    double wsum = 0.0;
    for (uint32_t i = 0; i < s->budget; i++) {
        gi__slot *q = &s->slot[i];
        if (q->kind == GI__EMPTY || q->light != l) continue;
        s->area[i] *= gi__density(f, L, q->dp);
        wsum += s->area[i];
    }
    double power = f->area ? 0.0 : gi__light_power1(L, f->radius);
    for (uint32_t i = 0; i < s->budget; i++) {
        gi__slot *q = &s->slot[i];
        if (q->kind != GI__VPL || q->light != l) continue;
        float frac = wsum > 0.0 ? (float)(s->area[i] / wsum) : 0.0f;
        /* area: Phi = frac * pi Le / pdf_area (an unbiased share of the
         * emitters' power pi sum A Le), so I = Phi albedo / pi = frac Le / pdf albedo */
        if (f->area) q->intensity = pf_v3_scale(pf_v3_mul(q->em_w, q->albedo), frac);
        else q->intensity = pf_v3_scale(pf_v3_mul(pf_v3_scale(L->color, (float)power * frac), q->albedo), PF_INV_PI);
    }
}

/* ------------------------------------------------------------ the frame */

/* Splits the budget by luminance power (largest remainders, ties to the
 * lower light index). */
static void gi__iir_quotas(gi__iir_state *s, const pf_scene *sc, const gi_area_lights *area, float radius)
{
    double p[257], total = 0.0;
    for (uint32_t l = 0; l < s->ndom; l++) {
        p[l] = l < s->nlights ? fmax(0.0, pf_luminance(sc->lights[l].color) * gi__light_power1(&sc->lights[l], radius))
                              : area->total_power;
        total += p[l];
    }
    uint32_t given = 0;
    double frac[257];
    for (uint32_t l = 0; l < s->ndom; l++) {
        double q = total > 0.0 ? s->budget * p[l] / total : 0.0;
        s->dom[l].quota = (uint32_t)floor(q);
        frac[l] = q - floor(q);
        given += s->dom[l].quota;
    }
    while (total > 0.0 && given < s->budget) {
        uint32_t best = 0;
        for (uint32_t l = 1; l < s->ndom; l++)
            if (frac[l] > frac[best]) best = l;
        s->dom[best].quota++;
        frac[best] = -1.0;
        given++;
    }
}

static pf_result gi__iir_setup(gi__iir_state *s, const gi_vpl_inputs *in, pf_error *err)
{
    const pf_scene *sc = in->scene;
    uint32_t ndom = sc->light_count + (in->area && in->area->count > 0);
    int same = s->budget == in->budget && s->nlights == sc->light_count && s->ndom == ndom;
    for (uint32_t l = 0; same && l < s->nlights; l++) same = s->dom[l].type == sc->lights[l].type;
    if (same) return PF_OK;
    gi__iir_reset(s);
    if (sc->light_count > 256) return pf_error_set(err, PF_ERR_ARGUMENT, "--method iir: at most 256 lights (%u)", sc->light_count);
    uint32_t B = in->budget;
    s->budget = B;
    s->nlights = sc->light_count;
    s->dom = calloc(ndom ? ndom : 1, sizeof *s->dom);
    s->slot = calloc(B + 1, sizeof *s->slot);
    s->rays = calloc(B + 1, sizeof *s->rays);
    s->hits = calloc(B + 1, sizeof *s->hits);
    s->occ = calloc(B + 1, 1);
    s->ray_slot = calloc(B + 1, sizeof *s->ray_slot);
    s->area = calloc(B + 1, sizeof *s->area);
    if (!s->dom || !s->slot || !s->rays || !s->hits || !s->occ || !s->ray_slot || !s->area) {
        gi__iir_reset(s);
        return pf_error_set(err, PF_ERR_OUT_OF_MEMORY, "out of memory");
    }
    for (uint32_t l = 0; l < ndom; l++) {
        s->dom[l].area = l >= s->nlights;
        s->dom[l].type = l < s->nlights ? sc->lights[l].type : PF_LIGHT_POINT;
        gi_dt_domain dom = l < s->nlights && sc->lights[l].type == PF_LIGHT_POINT ? GI_DT_SPHERE : GI_DT_DISC;
        pf_result r = gi_dt_init(&s->dom[l].dt, dom, B, err);
        if (r != PF_OK) {
            s->ndom = l;
            gi__iir_reset(s);
            return r;
        }
        s->ndom = l + 1;
    }
    return PF_OK;
}

/* Writes the slots: VPLs with their intensity, free slots and misses as
 * zero-intensity entries (so slot indices stay stable), up to the highest
 * slot in use. */
static pf_result gi__iir_emit(gi__iir_state *s, gi_vpl_set *out, pf_error *err)
{
    uint32_t count = 0;
    for (uint32_t i = 0; i < s->budget; i++)
        if (s->slot[i].kind != GI__EMPTY) count = i + 1;
    pf_result r = gi_vpl_set_reserve(out, count ? count : 1, err);
    if (r != PF_OK) return r;
    for (uint32_t i = 0; i < count; i++) {
        const gi__slot *q = &s->slot[i];
        gi_vpl *v = &out->v[i];
        v->pos = q->pos;
        v->nrm = q->nrm;
        if (q->kind == GI__VPL) {
            v->intensity = q->intensity;
            v->id = q->id;
            v->moved = q->born;
        } else {
            v->intensity = pf_v3(0, 0, 0);
            v->id = UINT32_MAX;
            v->moved = 0;
        }
    }
    out->count = count;
    return PF_OK;
}

static pf_result gi__iir_update(void *state, const gi_vpl_inputs *in, gi_vpl_set *out, pf_error *err)
{
    gi__iir_state *s = state;
    out->count = 0;
    if (in->budget == 0) return PF_OK;
    pf_result r = gi__iir_setup(s, in, err);
    if (r != PF_OK) return r;
    const pf_scene *sc = in->scene;
    float radius = 0.5f * pf_v3_length(pf_v3_sub(sc->bounds_max, sc->bounds_min)) * 1.001f; /* as gi_ir.c */
    for (uint32_t i = 0; i < s->budget; i++) s->slot[i].born = 0;
    gi__iir_quotas(s, sc, in->area, radius);
    for (uint32_t l = 0; l < s->ndom; l++) {
        const pf_light *L = l < s->nlights ? &sc->lights[l] : NULL;
        gi__lframe f;
        if (L) f = gi__light_frame(L, sc);
        else memset(&f, 0, sizeof f), f.area = 1, f.radius = radius;
        gi__iir_validity(s, in, l, &f);                                 /* step 1 */
        if ((r = gi__iir_delete_invalid(s, l, err)) != PF_OK) return r; /* step 2 */
        if ((r = gi__iir_delete_for_room(s, l, err)) != PF_OK) return r;
        if ((r = gi__iir_create_new(s, in, l, &f, err)) != PF_OK) return r; /* step 3 */
        gi__iir_intensities(s, L, l, &f);                                   /* step 4 */
    }
    return gi__iir_emit(s, out, err);
}

/* ------------------------------------------------------------ the view */

/* Where sampling point dp of a domain is drawn: the disc as itself; the
 * sphere as two discs side by side, the upper hemisphere (z >= 0) left and
 * the lower right, each by Lambert's azimuthal equal-area projection (equal
 * areas stay equal, so Voronoi areas, which set the intensities, read true). */
typedef struct gi__iir_canvas {
    int sphere;
    float cx[2], cy, r;
} gi__iir_canvas;

static int gi__iir_to_canvas(const gi__iir_canvas *c, const double dp[3], float *x, float *y)
{
    if (!c->sphere) {
        *x = c->cx[0] + c->r * (float)dp[0], *y = c->cy - c->r * (float)dp[1];
        return 0;
    }
    int lower = dp[2] < 0.0;
    double z = fabs(dp[2]), k = 1.0 / sqrt(1.0 + z); /* |(x, y)| sqrt(2 / (1 + z)) / sqrt(2) */
    *x = c->cx[lower] + c->r * (float)(dp[0] * k), *y = c->cy - c->r * (float)(dp[1] * k);
    return lower;
}

/* The inverse for the pixel (x, y): 0 outside the discs. */
static int gi__iir_from_canvas(const gi__iir_canvas *c, float x, float y, double dp[3])
{
    for (int h = 0; h < (c->sphere ? 2 : 1); h++) {
        double u = (x - c->cx[h]) / c->r, v = (c->cy - y) / c->r, q = u * u + v * v;
        if (q > 1.0) continue;
        if (!c->sphere) {
            dp[0] = u, dp[1] = v, dp[2] = 0.0;
            return 1;
        }
        double z = 1.0 - q, k = sqrt(1.0 + z); /* inverse of the projection above */
        dp[0] = u * k, dp[1] = v * k, dp[2] = h ? -z : z;
        return 1;
    }
    return 0;
}

static double gi__iir_dist2(int sphere, const double a[3], const double b[3])
{
    double d0 = a[0] - b[0], d1 = a[1] - b[1], d2 = sphere ? a[2] - b[2] : 0.0;
    return d0 * d0 + d1 * d1 + d2 * d2;
}

/* Light l's sampling domain: every pixel coloured by its nearest sample
 * (the Voronoi regions whose areas give the intensities, Sec. 4.7) in the
 * heat colour of that VPL's intensity (an empty sample, whose ray left the
 * scene, dark grey), the Delaunay edges whose shortest one picks the next
 * deletion (Sec. 4.5), the samples (white; new this frame green; empty
 * red) and the centre of the largest empty circle, where the next VPL goes
 * (Sec. 4.6, yellow). The light is the chosen VPL's, else light 0. */
static int gi__iir_view(const void *state, const gi_vpl_view_ctx *c, uint8_t *rgb)
{
    const gi__iir_state *s = state;
    if (!s || !s->ndom || !s->slot) return 0;
    uint32_t l = 0;
    if (c->vpls->count && c->vpl < s->budget && s->slot[c->vpl].kind != GI__EMPTY) l = s->slot[c->vpl].light;
    const gi__domain *d = &s->dom[l];
    const gi_dt *dt = &d->dt;
    const int sphere = dt->domain == GI_DT_SPHERE;
    gi__iir_canvas cv;
    cv.sphere = sphere;
    float side = sphere ? fminf(0.5f * (float)c->width, (float)c->height) : fminf((float)c->width, (float)c->height);
    cv.r = 0.45f * side;
    cv.cy = 0.5f * (float)c->height;
    cv.cx[0] = sphere ? 0.25f * (float)c->width : 0.5f * (float)c->width;
    cv.cx[1] = 0.75f * (float)c->width;
    /* the samples of this domain and their luminance range */
    uint32_t n = 0, fresh = 0, empty = 0;
    float lo = INFINITY, hi = -INFINITY;
    for (uint32_t i = 0; i < s->budget; i++) {
        const gi__slot *q = &s->slot[i];
        if (q->kind == GI__EMPTY || q->light != l || !dt->present[i]) continue;
        n++, fresh += q->born, empty += q->kind == GI__MISS;
        if (q->kind != GI__VPL) continue;
        float y = pf_luminance(q->intensity);
        lo = fminf(lo, y), hi = fmaxf(hi, y);
    }
    if (!(lo <= hi)) lo = hi = 0.0f;
    if (!n) return 0;
    /* Voronoi regions: the nearest present sample per pixel (ties: the
     * lower slot), by brute force */
    for (uint32_t y = 0; y < c->height; y++)
        for (uint32_t x = 0; x < c->width; x++) {
            double dp[3];
            uint8_t *o = rgb + 3 * ((size_t)y * c->width + x);
            if (!gi__iir_from_canvas(&cv, (float)x + 0.5f, (float)y + 0.5f, dp)) {
                o[0] = o[1] = o[2] = 0;
                continue;
            }
            uint32_t best = UINT32_MAX;
            double bd = INFINITY;
            for (uint32_t i = 0; i < s->budget; i++) {
                if (s->slot[i].kind == GI__EMPTY || s->slot[i].light != l || !dt->present[i]) continue;
                double e = gi__iir_dist2(sphere, dp, dt->p[i]);
                if (e < bd) bd = e, best = i;
            }
            const gi__slot *q = &s->slot[best];
            if (q->kind != GI__VPL) {
                o[0] = o[1] = o[2] = 45;
                continue;
            }
            float t = hi > lo ? (pf_luminance(q->intensity) - lo) / (hi - lo) : 1.0f;
            c->heat(sqrtf(t), o);
            o[0] = (uint8_t)(o[0] * 3 / 4), o[1] = (uint8_t)(o[1] * 3 / 4), o[2] = (uint8_t)(o[2] * 3 / 4);
        }
    /* Delaunay edges (each drawn from both sides: the same pixels) */
    static const uint8_t edge[3] = {200, 200, 210};
    for (uint32_t t = 0; t < dt->tri_count; t++) {
        const gi_dt_tri *T = &dt->tri[t];
        if (!T->alive) continue;
        for (int e = 0; e < 3; e++) {
            uint32_t a = T->v[e], b = T->v[(e + 1) % 3];
            if (a == GI_DT_INF || b == GI_DT_INF) continue;
            /* the arc in 8 pieces (a straight line on the disc) */
            for (int k = 0; k < (sphere ? 8 : 1); k++) {
                double p0[3], p1[3];
                for (int j = 0; j < 3; j++) {
                    p0[j] = dt->p[a][j] + (dt->p[b][j] - dt->p[a][j]) * k / (sphere ? 8.0 : 1.0);
                    p1[j] = dt->p[a][j] + (dt->p[b][j] - dt->p[a][j]) * (k + 1) / (sphere ? 8.0 : 1.0);
                }
                if (sphere) {
                    double n0 = sqrt(p0[0] * p0[0] + p0[1] * p0[1] + p0[2] * p0[2]);
                    double n1 = sqrt(p1[0] * p1[0] + p1[1] * p1[1] + p1[2] * p1[2]);
                    if (!(n0 > 0.0 && n1 > 0.0)) continue;
                    for (int j = 0; j < 3; j++) p0[j] /= n0, p1[j] /= n1;
                }
                float x0, y0, x1, y1;
                if (gi__iir_to_canvas(&cv, p0, &x0, &y0) != gi__iir_to_canvas(&cv, p1, &x1, &y1)) continue;
                c->line(c, rgb, (int)floorf(x0), (int)floorf(y0), (int)floorf(x1), (int)floorf(y1), edge);
            }
        }
    }
    /* the samples */
    static const uint8_t white[3] = {255, 255, 255}, green[3] = {60, 240, 60}, red[3] = {240, 60, 60},
                         yellow[3] = {255, 230, 0};
    for (uint32_t i = 0; i < s->budget; i++) {
        const gi__slot *q = &s->slot[i];
        if (q->kind == GI__EMPTY || q->light != l || !dt->present[i]) continue;
        float x, y;
        gi__iir_to_canvas(&cv, dt->p[i], &x, &y);
        const uint8_t *col = q->kind == GI__MISS ? red : q->born ? green : white;
        c->fill(c, rgb, (int)floorf(x) - 1, (int)floorf(y) - 1, 3, 3, col);
    }
    /* the largest empty circle: where Sec. 4.6 puts the next VPL */
    double centre[3];
    gi_dt_largest_empty(dt, centre, NULL);
    float ex, ey;
    gi__iir_to_canvas(&cv, centre, &ex, &ey);
    c->line(c, rgb, (int)ex - 5, (int)ey, (int)ex + 5, (int)ey, yellow);
    c->line(c, rgb, (int)ex, (int)ey - 5, (int)ex, (int)ey + 5, yellow);
    char text[160];
    snprintf(text, sizeof text, "light %u, %s: %u samples, %u new (green), %u empty (red)", l,
             d->area ? "area lights, disc" : sphere ? "point light, sphere (upper | lower)" : "disc", n, fresh, empty);
    c->text(c, rgb, 4, 2, text, white);
    c->text(c, rgb, 4, 12, "Voronoi regions by intensity, Delaunay edges, next insertion (yellow)", yellow);
    c->legend(c, rgb, "VPL luminance", lo, hi, 1);
    return 1;
}

static uint32_t gi__iir_bounce(const void *state, const gi_vpl *v, uint32_t bounces)
{
    (void)state, (void)v, (void)bounces;
    return 1; /* single bounce: first hits of rays from the lights */
}

const gi_vpl_method gi_method_iir = {
    .name = "iir",
    .paper = "Incremental Instant Radiosity (Laine 2007 Sec. 4)",
    .create = gi__iir_create,
    .update = gi__iir_update,
    .destroy = gi__iir_destroy,
    .parts = NULL,
    .gbuffer_free = 1,
    .why = "re-rendering a paraboloid map per VPL is the cost, so IIR keeps every VPL that is still valid and "
           "replaces only a few a frame, where the Voronoi regions of its light's domain are sparsest (Laine 2007 "
           "Sec. 4.2-4.6)",
    .view_caption = "the light's sampling domain: Voronoi regions coloured by VPL intensity (their areas are the "
                    "weights, Sec. 4.7), Delaunay edges (the shortest picks the next deletion, Sec. 4.5), the largest "
                    "empty circle (the next VPL, Sec. 4.6)",
    .view = gi__iir_view,
    .bounce = gi__iir_bounce,
};
