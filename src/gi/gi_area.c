/* gi_area: the scene's emissive triangles as area lights (see gi_area.h). */
#include "gi_area.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>


pf_result gi_area_lights_build(gi_area_lights *a, const pf_scene *s, pf_error *err)
{
    memset(a, 0, sizeof *a);
    uint32_t n = 0;
    for (uint32_t t = 0; t < s->tri_count; t++) {
        const float *e = s->materials[s->tri_material[t]].emission;
        if (e[0] > 0.0f || e[1] > 0.0f || e[2] > 0.0f) n++;
    }
    if (!n) return PF_OK;
    a->tri = calloc(n, sizeof *a->tri);
    a->cdf = calloc(n, sizeof *a->cdf);
    if (!a->tri || !a->cdf) {
        gi_area_lights_free(a);
        return pf_error_set(err, PF_ERR_OUT_OF_MEMORY, "out of memory for %u area-light triangles", n);
    }
    double total = 0.0, cx = 0.0, cy = 0.0, cz = 0.0;
    pf_vec3 rgb = pf_v3(0, 0, 0);
    for (uint32_t t = 0; t < s->tri_count; t++) {
        const pf_material *m = &s->materials[s->tri_material[t]];
        if (!(m->emission[0] > 0.0f || m->emission[1] > 0.0f || m->emission[2] > 0.0f)) continue;
        const uint32_t *ix = &s->indices[3 * t];
        gi_area_light *L = &a->tri[a->count];
        L->prim = t;
        L->v0 = s->positions[ix[0]];
        L->e1 = pf_v3_sub(s->positions[ix[1]], L->v0);
        L->e2 = pf_v3_sub(s->positions[ix[2]], L->v0);
        L->normal = pf_scene_face_normal(s, t);
        L->radiance = pf_v3(m->emission[0], m->emission[1], m->emission[2]);
        L->area = 0.5f * pf_v3_length(pf_v3_cross(L->e1, L->e2));
        L->two_sided = m->double_sided ? 1u : 0u;
        double faces = L->two_sided ? 2.0 : 1.0;
        double pw = faces * PF_PI * (double)L->area * (double)pf_luminance(L->radiance);
        total += pw;
        a->cdf[a->count] = total;
        rgb = pf_v3_add(rgb, pf_v3_scale(L->radiance, (float)(faces * PF_PI * L->area)));
        pf_vec3 c = pf_v3_add(L->v0, pf_v3_scale(pf_v3_add(L->e1, L->e2), 1.0f / 3.0f));
        cx += pw * c.x, cy += pw * c.y, cz += pw * c.z;
        a->count++;
    }
    a->total_power = total;
    a->power_rgb = rgb;
    a->centroid = total > 0.0 ? pf_v3((float)(cx / total), (float)(cy / total), (float)(cz / total)) : pf_v3(0, 0, 0);
    return PF_OK;
}

void gi_area_lights_free(gi_area_lights *a)
{
    free(a->tri);
    free(a->cdf);
    memset(a, 0, sizeof *a);
}

void gi_area_sample_point(const gi_area_lights *a, double u0, float u1, float u2, gi_area_sample *out)
{
    double x = u0 * a->total_power;
    uint32_t lo = 0, hi = a->count - 1; /* first index with cdf > x */
    while (lo < hi) {
        uint32_t mid = lo + (hi - lo) / 2;
        if (a->cdf[mid] > x) hi = mid;
        else lo = mid + 1;
    }
    const gi_area_light *L = &a->tri[lo];
    float su = sqrtf(u1);
    float s = 1.0f - su, t = u2 * su; /* uniform on the triangle */
    out->index = lo;
    out->p = pf_v3_add(L->v0, pf_v3_add(pf_v3_scale(L->e1, s), pf_v3_scale(L->e2, t)));
    out->n = L->normal;
    if (L->two_sided) {
        /* reuse u0's position inside the chosen CDF bin to pick a face */
        double b0 = lo ? a->cdf[lo - 1] : 0.0, w = a->cdf[lo] - b0;
        if (w > 0.0 && (x - b0) / w >= 0.5) out->n = pf_v3_scale(L->normal, -1.0f);
    }
    out->radiance = L->radiance;
    out->pdf_area = gi_area_pdf(a, lo);
}

float gi_area_pdf(const gi_area_lights *a, uint32_t index)
{
    const gi_area_light *L = &a->tri[index];
    double w = a->cdf[index] - (index ? a->cdf[index - 1] : 0.0);
    double faces = L->two_sided ? 2.0 : 1.0;
    if (!(a->total_power > 0.0) || !(L->area > 0.0f)) return 0.0f;
    return (float)(w / a->total_power / ((double)L->area * faces));
}

uint32_t gi_area_find(const gi_area_lights *a, uint32_t prim)
{
    uint32_t lo = 0, hi = a->count; /* tri[] is sorted by prim */
    while (lo < hi) {
        uint32_t mid = lo + (hi - lo) / 2;
        if (a->tri[mid].prim < prim) lo = mid + 1;
        else hi = mid;
    }
    return lo < a->count && a->tri[lo].prim == prim ? lo : UINT32_MAX;
}

int gi_area_sample_irradiance(const gi_area_sample *s, pf_vec3 p, pf_vec3 n, pf_vec3 *irradiance, pf_vec3 *wi,
                              float *distance)
{
    pf_vec3 d = pf_v3_sub(s->p, p);
    float r2 = pf_v3_dot(d, d);
    *irradiance = pf_v3(0.0f, 0.0f, 0.0f);
    *wi = pf_v3(0.0f, 0.0f, 1.0f);
    *distance = 0.0f;
    if (!(r2 > 0.0f) || !(s->pdf_area > 0.0f)) return 0;
    float r = sqrtf(r2);
    pf_vec3 w = pf_v3_scale(d, 1.0f / r);
    float cr = pf_v3_dot(n, w), ce = -pf_v3_dot(s->n, w);
    if (!(cr > 0.0f) || !(ce > 0.0f)) return 0;
    *irradiance = pf_v3_scale(s->radiance, cr * ce / (r2 * s->pdf_area));
    *wi = w;
    *distance = r;
    return 1;
}
