/* gi_probe: one pixel of a frame, buffer by buffer, and its tile's VPLs
 * re-evaluated with the accumulation's formula (see gi_probe.h). */
#include "gi_probe.h"

#include <assert.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>

#include "gi_ism.h"

static pf_vec3 gi__rgb(const float *buf, size_t i) { return pf_v3(buf[3 * i], buf[3 * i + 1], buf[3 * i + 2]); }

/* ------------------------------------------------------------ step 1, 5, 10 */

static void gi__probe_gbuffer(gi_probe *p, const gi_frame *f, size_t i)
{
    const rs_gbuffer *g = &f->gbuf;
    p->prim = g->prim[i];
    p->surface = p->prim != RS_GBUFFER_EMPTY;
    p->depth = g->depth[i];
    if (!p->surface) return; /* the dump writes 0 there (gi_dump.h: A = 0) */
    p->position = pf_v3(g->pos_x[i], g->pos_y[i], g->pos_z[i]);
    p->normal = pf_v3(g->nrm_x[i], g->nrm_y[i], g->nrm_z[i]);
    p->albedo = pf_v3(g->alb_r[i], g->alb_g[i], g->alb_b[i]);
    p->material = f->scene->tri_material[p->prim];
    if (f->show_direct) {
        const float *e = f->scene->materials[p->material].emission;
        p->emission = pf_v3(e[0], e[1], e[2]);
    }
}

/* ------------------------------------------------------------ step 7, VPL by VPL */

/* The visibility test gi_stage_accumulate made for VPL vi at (pos, nrm). */
static int gi__vpl_visible(const gi_frame *f, uint32_t vi, pf_vec3 pos, pf_vec3 nrm, pf_vec3 w, float r)
{
    const gi_indirect *ind = &f->ind;
    const uint32_t R = ind->opt.para_res;
    const uint16_t *map = ind->atlas ? ind->atlas + (size_t)vi * R * R : NULL;
    if (map) /* exact maps (the receiver-plane test or bias_scale 1) or ISMs: the one lookup */
        return rs_para_visible_scaled(map, R, ind->range, &ind->frames[vi], pos, ind->plane ? &nrm : NULL,
                                      pf_v3_dot(nrm, w), ind->bias_scale);
    pf_ray ray = {pf_rt_offset_origin(pos, nrm, w), 0.0f, w, r * (1.0f - 1.0e-4f)};
    return !pf_rt_occluded1(f->rt, ray);
}

/* Inserts c into the top list (largest luminance first; ties in the
 * tile's order). */
static void gi__top_insert(gi_probe *p, const gi_probe_vpl *c)
{
    float lum = pf_luminance(c->e);
    uint32_t k = p->top_count < GI_PROBE_TOP ? p->top_count : GI_PROBE_TOP;
    while (k > 0 && pf_luminance(p->top[k - 1].e) < lum) k--;
    if (k >= GI_PROBE_TOP) return;
    uint32_t last = p->top_count < GI_PROBE_TOP ? p->top_count : GI_PROBE_TOP - 1;
    memmove(&p->top[k + 1], &p->top[k], (last - k) * sizeof p->top[0]);
    p->top[k] = *c;
    if (p->top_count < GI_PROBE_TOP) p->top_count++;
}

/* The tile's VPLs at the pixel, in the tile's order: E = T * sum I G_b V. */
static void gi__probe_tile_vpls(gi_probe *p, const gi_frame *f)
{
    const gi_indirect *ind = &f->ind;
    const uint32_t k = p->split;
    if (!ind->split_valid[k]) return;
    pf_vec3 pos = pf_v3(ind->split_px[k], ind->split_py[k], ind->split_pz[k]);
    pf_vec3 nrm = pf_v3(ind->split_nx[k], ind->split_ny[k], ind->split_nz[k]);
    pf_vec3 sum = pf_v3(0, 0, 0);
    const uint32_t grp = gi_indirect_tile_group(ind, p->tile);
    for (uint32_t q = ind->assign_start[grp]; q < ind->assign_start[grp + 1]; q++) {
        uint32_t vi = ind->assign[q];
        const gi_vpl *v = &ind->vpls.v[vi];
        gi_probe_vpl c;
        memset(&c, 0, sizeof c);
        pf_vec3 w = pf_v3(0, 0, 0);
        c.clamped = 0;
        pf_vec3 e = gi_vpl_irradiance(v, pos, nrm, ind->b, &w, &c.distance, &c.g, &c.clamped);
        if (e.x == 0.0f && e.y == 0.0f && e.z == 0.0f) continue;
        if (!gi__vpl_visible(f, vi, pos, nrm, w, c.distance)) {
            p->occluded++;
            continue;
        }
        sum = pf_v3_add(sum, e);
        p->lit++;
        p->clamped += c.clamped != 0;
        c.index = vi, c.id = v->id, c.pos = v->pos, c.nrm = v->nrm, c.intensity = v->intensity;
        c.e = pf_v3_scale(e, p->weight);
        gi__top_insert(p, &c);
    }
    p->tile_sum = pf_v3_scale(sum, p->weight); /* gi__accumulate_row: e = sum x weight */
}

static void gi__probe_indirect(gi_probe *p, const gi_frame *f, size_t i)
{
    const gi_indirect *ind = &f->ind;
    p->indirect = 1;
    p->tiles_n = ind->n, p->tiles_m = ind->m;
    /* the indirect image's pixel (the frame's unless --indirect-scale > 1) */
    const uint32_t xi = p->x / ind->scale, yi = p->y / ind->scale;
    p->tile_i = xi % ind->n, p->tile_j = yi % ind->m;
    p->tile = p->tile_j * ind->n + p->tile_i;
    p->split = gi_split_index(ind, ind->w, xi, yi);
    p->mosaic_x = p->tile_i * ind->tile_w[0] + xi / ind->n; /* gi_view.c's mosaic */
    p->mosaic_y = p->tile_j * ind->tile_h[0] + yi / ind->m;
    p->weight = gi_indirect_tile_weight(ind);
    const uint32_t grp = gi_indirect_tile_group(ind, p->tile);
    p->tile_vpls = ind->assign_start[grp + 1] - ind->assign_start[grp];
    p->tile_e = gi__rgb(ind->split_e, p->split);
    p->combined = gi__rgb(ind->combined, gi_indirect_pixel(ind, p->x, p->y));
    p->filtered = gi__rgb(ind->filtered, i);
    gi__probe_tile_vpls(p, f);
}

void gi_probe_pixel(gi_probe *out, const gi_frame *f, uint32_t x, uint32_t y)
{
    assert(x < f->width && y < f->height);
    memset(out, 0, sizeof *out);
    out->x = x, out->y = y;
    const size_t i = (size_t)y * f->width + x;
    gi__probe_gbuffer(out, f, i);
    out->has_direct = f->show_direct;
    if (f->show_direct) out->direct = gi__rgb(f->direct, i);
    if (f->indirect) gi__probe_indirect(out, f, i);
    out->final = gi__rgb(f->final, i);
}

/* ------------------------------------------------------------ text */

typedef struct gi__out {
    char *buf;
    size_t size, len;
    int total;
} gi__out;

__attribute__((format(printf, 2, 3))) static void gi__put(gi__out *o, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    int n = vsnprintf(o->len < o->size ? o->buf + o->len : NULL, o->len < o->size ? o->size - o->len : 0, fmt, ap);
    va_end(ap);
    if (n < 0) return;
    o->total += n;
    o->len += (size_t)n;
}

static void gi__put_v3(gi__out *o, const char *name, pf_vec3 v, int d)
{
    gi__put(o, "%s %.*g %.*g %.*g\n", name, d, (double)v.x, d, (double)v.y, d, (double)v.z);
}

int gi_probe_text(char *buf, size_t size, const gi_probe *p, int digits, uint32_t top)
{
    gi__out o = {buf, size, 0, 0};
    if (size) buf[0] = 0;
    const int d = digits;
    gi__put(&o, "pixel %u %u\n", p->x, p->y);
    if (!p->surface) {
        gi__put(&o, "no surface (background)\n");
    } else {
        gi__put(&o, "depth %.*g\n", d, (double)p->depth);
        gi__put(&o, "triangle %u material %u\n", p->prim, p->material);
        gi__put_v3(&o, "position", p->position, d);
        gi__put_v3(&o, "normal", p->normal, d);
        gi__put_v3(&o, "albedo", p->albedo, d);
        if (p->emission.x != 0.0f || p->emission.y != 0.0f || p->emission.z != 0.0f)
            gi__put_v3(&o, "emission", p->emission, d);
    }
    if (p->has_direct) gi__put_v3(&o, "direct", p->direct, d);
    if (p->indirect) {
        gi__put(&o, "tile %u %u of %ux%u, T %g: %u VPLs, %u lit, %u occluded, %u clamped\n", p->tile_i, p->tile_j,
                p->tiles_n, p->tiles_m, (double)p->weight, p->tile_vpls, p->lit, p->occluded, p->clamped);
        gi__put_v3(&o, "tile-irradiance", p->tile_e, d);
        gi__put_v3(&o, "combined", p->combined, d);
        gi__put_v3(&o, "filtered", p->filtered, d);
    }
    gi__put_v3(&o, "final", p->final, d);
    float total = pf_luminance(p->tile_sum);
    for (uint32_t k = 0; k < p->top_count && k < top; k++) {
        const gi_probe_vpl *v = &p->top[k];
        gi__put(&o, "vpl %u (id %u) %.0f%%: E %.*g %.*g %.*g, G %.*g%s, r %.*g\n", v->index, v->id,
                total > 0.0f ? 100.0 * pf_luminance(v->e) / total : 0.0, d, (double)v->e.x, d, (double)v->e.y, d,
                (double)v->e.z, d, (double)v->g, v->clamped ? " (clamped)" : "", d, (double)v->distance);
    }
    return o.total;
}
