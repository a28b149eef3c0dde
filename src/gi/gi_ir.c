/* gi_ir: Instant Radiosity (Keller 1997), the baseline VPL method, as the
 * survey's Sec. 4.1 describes it: random walks from the lights with a VPL
 * at every diffuse bounce, "flux" by Eq. 6, Russian roulette by albedo.
 *
 * Sampling: the Halton sequence with a fixed start, one index per light
 * path, so a static scene keeps a static VPL set; when anything changes (a
 * light moves), the whole set is regenerated from the same indices, which is
 * the flickering baseline the later methods beat. Dimensions of path i:
 * 2 light choice, 3/5 emission (area lights: also 7/11), then per bounce k (0-based) a pair of
 * primes for the cosine-weighted direction and one for Russian roulette.
 *
 * Path construction (per path, light l chosen with probability p_l
 * proportional to its power):
 *   point:       direction uniform on the sphere, Phi = 4 pi I / p_l
 *   spot:        direction uniform on the outer cone's cap,
 *                Phi = I * cone(w) * 2 pi (1 - cos outer) / p_l
 *   directional: origin uniform on a disc of the scene's bounding radius R
 *                across the beam, Phi = E pi R^2 / p_l
 *   area lights: the scene's emissive triangles (gi_area.h) are one more
 *                entry of the light CDF, with their total power
 *                sum pi A lum(Le); a path that picks them reuses the light
 *                choice's number, rescaled to [0, 1) inside the entry, to pick
 *                an emitter by power (gi_area_sample_point), a point uniform on
 *                it (dims 3/5), a cosine-weighted direction around its
 *                emitting normal (dims 7/11; the bounce dimensions below then
 *                shift by 2), Phi = pi Le / (pdf_area p_l) (cosine emission:
 *                Le cos / (pdf_area (cos / pi)) per unit p_l)
 * At each surface hit x_j: a VPL with intensity Phi * albedo / pi; survive
 * with q = min(1, max albedo), then Phi *= albedo / q and continue with a
 * cosine-weighted direction (pdf cos / pi cancels the BRDF's cos / pi), up
 * to `bounces` VPLs per path. Paths are started until the VPL budget is
 * filled, and every intensity is divided by the number of paths started
 * (survey Sec. 4.1, last step). VPL ids are path * bounces + k. */
#include <stdlib.h>
#include <string.h>

#include "gi_area.h"
#include "gi_light.h"
#include "gi_vpl.h"

static const uint32_t gi__primes[] = {2,  3,  5,  7,  11, 13, 17, 19, 23, 29, 31, 37, 41, 43, 47, 53, 59,
                                      61, 67, 71, 73, 79, 83, 89, 97, 101, 103, 107, 109, 113, 127, 131,
                                      137, 139, 149, 151, 157, 163, 167, 173, 179, 181, 191, 193, 197, 199};
#define GI__DIMS (sizeof gi__primes / sizeof gi__primes[0])

typedef struct gi__ir_state {
    gi_vpl_set prev; /* last frame's set, for the moved flags */
} gi__ir_state;

static pf_result gi__ir_create(void **state, const gi_params *params, pf_error *err)
{
    static const char *const known[] = {NULL};
    pf_result r = gi_params_check(params, "ir", known, err);
    if (r != PF_OK) return r;
    *state = calloc(1, sizeof(gi__ir_state));
    return *state ? PF_OK : pf_error_set(err, PF_ERR_OUT_OF_MEMORY, "out of memory");
}

static void gi__ir_destroy(void *state)
{
    gi__ir_state *s = state;
    if (!s) return;
    gi_vpl_set_free(&s->prev);
    free(s);
}

static float gi__lum(pf_vec3 c) { return 0.2126f * c.x + 0.7152f * c.y + 0.0722f * c.z; }

/* Emitted power of a light (luminance-weighted, for choosing lights). */
static double gi__light_power(const pf_light *l, double radius)
{
    double c = gi__lum(l->color) * (double)l->intensity;
    switch (l->type) {
    case PF_LIGHT_POINT: return 4.0 * PF_PI * c;
    case PF_LIGHT_SPOT: {
        /* 2 pi integral of the cone factor over cos(angle), midpoint rule */
        double co = cos((double)l->outer_cone), sum = 0.0;
        for (int k = 0; k < 256; k++) {
            double ct = co + (1.0 - co) * (k + 0.5) / 256.0;
            sum += gi_light_spot_factor(l, (float)ct);
        }
        return 2.0 * PF_PI * c * sum * (1.0 - co) / 256.0;
    }
    default: return c * PF_PI * radius * radius;
    }
}

/* Unit vector in the frame around axis n from cos(theta) and phi. */
static pf_vec3 gi__around(pf_vec3 n, float cos_t, float phi)
{
    pf_vec3 t, b;
    pf_v3_basis(n, &t, &b);
    float sin_t = sqrtf(fmaxf(0.0f, 1.0f - cos_t * cos_t));
    return pf_v3_add(pf_v3_add(pf_v3_scale(t, sin_t * cosf(phi)), pf_v3_scale(b, sin_t * sinf(phi))),
                     pf_v3_scale(n, cos_t));
}

static pf_result gi__ir_update(void *state, const gi_vpl_inputs *in, gi_vpl_set *out, pf_error *err)
{
    gi__ir_state *st = state;
    const pf_scene *s = in->scene;
    out->count = 0;
    uint32_t budget = in->budget, B = in->bounces ? in->bounces : 3;
    pf_result r = gi_vpl_set_reserve(out, budget, err);
    if (r != PF_OK) return r;
    pf_vec3 centre = pf_v3_scale(pf_v3_add(s->bounds_min, s->bounds_max), 0.5f);
    float radius = 0.5f * pf_v3_length(pf_v3_sub(s->bounds_max, s->bounds_min)) * 1.001f;
    /* light selection CDF by power; entry np (after the punctual lights) is
     * the set of area lights, when the scene has emitters */
    double total = 0.0, cdf[65];
    uint32_t np = s->light_count < 64 ? s->light_count : 64, nl = np;
    for (uint32_t l = 0; l < np; l++) {
        total += gi__light_power(&s->lights[l], radius);
        cdf[l] = total;
    }
    if (in->area->count > 0 && in->area->total_power > 0.0) {
        total += in->area->total_power;
        cdf[nl++] = total;
    }
    if (nl == 0 || !(total > 0.0)) return PF_OK; /* nothing emits: no VPLs */
    uint32_t paths = 0;
    for (uint32_t path = 0; out->count < budget && path < budget * 64u; path++) {
        paths++;
        uint32_t hi = path + 1; /* Halton index (0 maps every dimension to 0) */
        double ul = gi_halton(hi, 2) * total;
        uint32_t l = 0;
        while (l + 1 < nl && cdf[l] <= ul) l++;
        const pf_light *L = l < np ? &s->lights[l] : NULL;
        double lo = l ? cdf[l - 1] : 0.0, pl = (cdf[l] - lo) / total;
        float u1 = (float)gi_halton(hi, 3), u2 = (float)gi_halton(hi, 5);
        pf_ray ray;
        pf_vec3 phi;
        ray.tnear = 0.0f;
        ray.tfar = INFINITY;
        uint32_t dim0 = 3; /* first bounce dimension */
        if (!L) {
            double ua = (ul - lo) / (cdf[l] - lo);
            if (!(ua < 1.0)) ua = 0x1.fffffffffffffp-1;
            if (!(ua >= 0.0)) ua = 0.0;
            gi_area_sample as;
            gi_area_sample_point(in->area, ua, u1, u2, &as);
            float a1 = (float)gi_halton(hi, gi__primes[3]), a2 = (float)gi_halton(hi, gi__primes[4]);
            ray.org = pf_rt_offset_origin(as.p, as.n, as.n);
            ray.dir = gi__around(as.n, sqrtf(1.0f - a1), 2.0f * PF_PI * a2);
            phi = pf_v3_scale(as.radiance, (float)(PF_PI / ((double)as.pdf_area * pl)));
            dim0 = 5;
        } else if (L->type == PF_LIGHT_POINT) {
            ray.org = L->position;
            ray.dir = gi__around(pf_v3(0, 0, 1), 1.0f - 2.0f * u1, 2.0f * PF_PI * u2);
            phi = pf_v3_scale(L->color, (float)(L->intensity * 4.0 * PF_PI / pl));
        } else if (L->type == PF_LIGHT_SPOT) {
            float co = cosf(L->outer_cone), ct = 1.0f - u1 * (1.0f - co);
            ray.org = L->position;
            ray.dir = gi__around(L->direction, ct, 2.0f * PF_PI * u2);
            float w = gi_light_spot_factor(L, ct) * 2.0f * PF_PI * (1.0f - co);
            phi = pf_v3_scale(L->color, (float)(L->intensity * w / pl));
        } else {
            pf_vec3 t, b;
            pf_v3_basis(L->direction, &t, &b);
            float rr = radius * sqrtf(u1), a = 2.0f * PF_PI * u2;
            ray.org = pf_v3_add(pf_v3_sub(centre, pf_v3_scale(L->direction, 2.0f * radius)),
                                pf_v3_add(pf_v3_scale(t, rr * cosf(a)), pf_v3_scale(b, rr * sinf(a))));
            ray.dir = L->direction;
            phi = pf_v3_scale(L->color, (float)(L->intensity * PF_PI * radius * radius / pl));
        }
        for (uint32_t k = 0; k < B && out->count < budget; k++) {
            pf_hit h = pf_rt_intersect1(in->rt, ray);
            if (h.prim == PF_RT_MISS) break;
            pf_surface sf;
            pf_rt_surface(in->rt, &h, 0.0f, &sf);
            pf_vec3 n = sf.ns, ng = sf.ng;
            if (pf_v3_dot(ng, ray.dir) > 0.0f) ng = pf_v3_scale(ng, -1.0f); /* two-sided: face the photon */
            if (pf_v3_dot(n, ng) < 0.0f) n = pf_v3_scale(n, -1.0f);
            pf_vec3 albedo = pf_v3(sf.albedo[0], sf.albedo[1], sf.albedo[2]);
            gi_vpl *v = &out->v[out->count++];
            v->pos = pf_rt_offset_origin(sf.p, ng, ng);
            v->nrm = n;
            v->intensity = pf_v3_scale(pf_v3_mul(phi, albedo), PF_INV_PI);
            v->id = path * B + k;
            v->moved = 1;
            /* Russian roulette by albedo, then a cosine-weighted bounce */
            uint32_t d = dim0 + 3 * k;
            float q = fminf(1.0f, pf_v3_max_comp(albedo));
            if (d + 2 >= GI__DIMS || !((float)gi_halton(hi, gi__primes[d + 2]) < q)) break;
            phi = pf_v3_scale(pf_v3_mul(phi, albedo), 1.0f / q);
            float a1 = (float)gi_halton(hi, gi__primes[d]), a2 = (float)gi_halton(hi, gi__primes[d + 1]);
            ray.org = v->pos;
            ray.dir = gi__around(n, sqrtf(1.0f - a1), 2.0f * PF_PI * a2);
            ray.tnear = 0.0f;
            ray.tfar = INFINITY;
        }
    }
    float inv = 1.0f / (float)paths;
    for (uint32_t i = 0; i < out->count; i++) out->v[i].intensity = pf_v3_scale(out->v[i].intensity, inv);
    /* moved flags against the previous frame (same id at the same slot) */
    for (uint32_t i = 0; i < out->count; i++) {
        gi_vpl *v = &out->v[i];
        if (i < st->prev.count && st->prev.v[i].id == v->id && !memcmp(&st->prev.v[i].pos, &v->pos, sizeof v->pos) &&
            !memcmp(&st->prev.v[i].nrm, &v->nrm, sizeof v->nrm) &&
            !memcmp(&st->prev.v[i].intensity, &v->intensity, sizeof v->intensity))
            v->moved = 0;
    }
    r = gi_vpl_set_reserve(&st->prev, out->count ? out->count : 1, err);
    if (r != PF_OK) return r;
    memcpy(st->prev.v, out->v, sizeof(gi_vpl) * out->count);
    st->prev.count = out->count;
    (void)in->frame;
    return PF_OK;
}

const gi_vpl_method gi_method_ir = {
    "ir", "Instant Radiosity (Keller 1997; survey Sec. 4.1)", gi__ir_create, gi__ir_update, gi__ir_destroy,
};
