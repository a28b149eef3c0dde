/* gi_light: punctual-light irradiance (see gi_light.h). */
#include "gi_light.h"

#include <stdlib.h>
#include <string.h>

float gi_light_spot_factor(const pf_light *light, float cos_angle)
{
    float cos_outer = cosf(light->outer_cone), cos_inner = cosf(light->inner_cone);
    float scale = 1.0f / fmaxf(0.001f, cos_inner - cos_outer);
    float t = pf_clampf((cos_angle - cos_outer) * scale, 0.0f, 1.0f);
    return t * t;
}

int gi_light_irradiance(const pf_light *light, pf_vec3 p, pf_vec3 n, gi_light_sample *out)
{
    float e0 = light->intensity;
    if (light->type == PF_LIGHT_DIRECTIONAL) {
        out->wi = pf_v3_scale(light->direction, -1.0f);
        out->distance = INFINITY;
    } else {
        pf_vec3 d = pf_v3_sub(light->position, p);
        float r2 = pf_v3_dot(d, d);
        if (!(r2 > 0.0f)) goto none;
        float r = sqrtf(r2);
        out->wi = pf_v3_scale(d, 1.0f / r);
        out->distance = r;
        e0 /= r2;
        if (light->type == PF_LIGHT_SPOT) e0 *= gi_light_spot_factor(light, -pf_v3_dot(out->wi, light->direction));
    }
    float cos_theta = pf_v3_dot(n, out->wi);
    if (!(cos_theta > 0.0f) || !(e0 > 0.0f)) goto none;
    out->irradiance = pf_v3_scale(light->color, e0 * cos_theta);
    return 1;
none:
    out->irradiance = pf_v3(0.0f, 0.0f, 0.0f);
    return 0;
}

pf_ray gi_light_shadow_ray(const gi_light_sample *ls, pf_vec3 p, pf_vec3 ng)
{
    pf_ray r;
    r.org = pf_rt_offset_origin(p, ng, ls->wi);
    r.dir = ls->wi;
    r.tnear = 0.0f;
    r.tfar = isinf(ls->distance) ? INFINITY : ls->distance * (1.0f - 1.0e-4f);
    return r;
}

int gi_light_copy_same(const gi_light_copy *c, const pf_scene *s, uint32_t i)
{
    return i < c->count && i < s->light_count && !memcmp(&c->v[i], &s->lights[i], sizeof(pf_light));
}

int gi_light_copy_all_same(const gi_light_copy *c, const pf_scene *s)
{
    return c->count == s->light_count && (!c->count || !memcmp(c->v, s->lights, sizeof(pf_light) * c->count));
}

int gi_light_copy_take(gi_light_copy *c, const pf_scene *s)
{
    if (!c->v || c->count != s->light_count) { /* only when lights were added or removed */
        pf_light *copy = realloc(c->v, sizeof(pf_light) * (s->light_count ? s->light_count : 1));
        if (!copy) return 0;
        c->v = copy;
    }
    if (s->light_count) memcpy(c->v, s->lights, sizeof(pf_light) * s->light_count);
    c->count = s->light_count;
    return 1;
}

void gi_light_copy_free(gi_light_copy *c)
{
    free(c->v);
    c->v = NULL;
    c->count = 0;
}
