/* rs_para_kernels: the paraboloid renderer's front end and texel scan,
 * written once over the SIMD vocabulary and compiled once per instruction
 * set (see rs_para_kernels.h and docs/raster.md "The SIMD vocabulary").
 * CMake compiles this file three times, each time naming the table it
 * exports with -DRS_PARA_KERNELS=rs_para_kernels_<isa>: scalar (8 plain-C
 * lanes, the reference), avx2 (8 lanes), avx512 (16 lanes). Lane l of a
 * front-end vector is triangle base + l; of a scan vector, texel i + l of
 * row j. */
#include "rs_para_kernels.h"

#include "rs_para_lookup.h"
#include "simd.h"

#ifndef RS_PARA_KERNELS
#error "compile with -DRS_PARA_KERNELS=<table name> (CMakeLists.txt)"
#endif

_Static_assert(RS__LANES % SIMD_W == 0, "cluster sizes are multiples of RS__LANES, hence of SIMD_W");

/* (u, v) intervals -> inclusive texel ranges, as rs__uv_to_texels
 * (rs_paraboloid.c): centre u_i = (2i+1-R)/R >= lo <=> i >= (lo + 1) R/2 -
 * 1/2, clamped to [first, last]: the map's (0, R - 1), or the texels a
 * partial render draws (rs_para_render_box: triangles outside them are
 * dropped here, before any setup). max(fa, first) = fa > first ? fa : first
 * and min(fb, last) = fb < last ? fb : last are the scalar expressions; NaN
 * lanes fail fa <= fb either way. Returns the mask of non-empty ranges. */
static inline simd_mask rs__uv_to_texels_w(simd_f lo, simd_f hi, uint32_t res, int32_t first, int32_t last,
                                           simd_i *a, simd_i *b)
{
    const simd_f h = simd_set1_f(0.5f * (float)res), top = simd_set1_f((float)last);
    const simd_f one = simd_set1_f(1.0f), half = simd_set1_f(0.5f);
    simd_f fa = simd_ceil_f(simd_sub_f(simd_mul_f(simd_add_f(lo, one), h), half));
    simd_f fb = simd_floor_f(simd_sub_f(simd_mul_f(simd_add_f(hi, one), h), half));
    fa = simd_max_f(fa, simd_set1_f((float)first));
    fb = simd_min_f(fb, top);
    simd_mask ok = simd_le_f(fa, fb);
    *a = simd_f2i_trunc(fa);
    *b = simd_f2i_trunc(fb);
    return ok;
}

/* (p . a) in the order (px ax + py ay) + pz az */
static inline simd_f rs__dot3(simd_f px, simd_f py, simd_f pz, simd_f ax, simd_f ay, simd_f az)
{
    return simd_add_f(simd_add_f(simd_mul_f(px, ax), simd_mul_f(py, ay)), simd_mul_f(pz, az));
}

/* The front end, SIMD_W triangles at a time: local coordinates (z first:
 * triangles wholly behind the tangent plane need nothing else), the
 * hemisphere cull, the projected vertices (one division per vertex), the
 * conservative (u, v) bound grown by the c^2/4 sagitta margin, its texel
 * rectangle; survivors are compress-stored into the batch in triangle
 * order. Triangles crossing the tangent plane get their bound in
 * rs__setup_triangle (double precision). */
static void rs__front(const rs_para_context *ctx, rs__scratch *sc, const rs_para_frame *f, const rs__cluster *cl)
{
    const simd_f ox = simd_set1_f(f->o.x), oy = simd_set1_f(f->o.y), oz = simd_set1_f(f->o.z);
    const simd_f tx = simd_set1_f(f->t.x), ty = simd_set1_f(f->t.y), tz = simd_set1_f(f->t.z);
    const simd_f bx = simd_set1_f(f->b.x), by = simd_set1_f(f->b.y), bz = simd_set1_f(f->b.z);
    const simd_f nx = simd_set1_f(f->n.x), ny = simd_set1_f(f->n.y), nz = simd_set1_f(f->n.z);
    const simd_f zero = simd_zero_f(), one = simd_set1_f(1.0f), quarter = simd_set1_f(0.25f);
    const simd_f eps = simd_set1_f(RS__UV_EPS);
    const simd_i lane = simd_iota_i();
    rs__batch *b = &sc->batch;
    for (uint32_t base = cl->first; base < cl->first + cl->count; base += SIMD_W) {
        uint32_t left = cl->first + cl->count - base;
        simd_mask valid = simd_mask_from_bits(left >= SIMD_W ? SIMD_FULL : (1u << left) - 1u);
        simd_f l[3][3], len[3], pu[3], pv[3];
        simd_mask above[3];
        for (int v = 0; v < 3; v++) {
            simd_f px = simd_sub_f(simd_load_f(ctx->soa[3 * v] + base), ox);
            simd_f py = simd_sub_f(simd_load_f(ctx->soa[3 * v + 1] + base), oy);
            simd_f pz = simd_sub_f(simd_load_f(ctx->soa[3 * v + 2] + base), oz);
            l[v][0] = rs__dot3(px, py, pz, tx, ty, tz);
            l[v][1] = rs__dot3(px, py, pz, bx, by, bz);
            l[v][2] = rs__dot3(px, py, pz, nx, ny, nz);
            above[v] = simd_gt_f(l[v][2], zero);
        }
        simd_mask any = simd_mask_and(valid, simd_mask_or(simd_mask_or(above[0], above[1]), above[2]));
        simd_mask all = simd_mask_and(valid, simd_mask_and(simd_mask_and(above[0], above[1]), above[2]));
        sc->stats.triangles_behind += (uint64_t)simd_mask_count(simd_mask_andnot(valid, any));
        if (!simd_mask_any(any)) continue;
        for (int v = 0; v < 3; v++) {
            len[v] = simd_sqrt_f(rs__dot3(l[v][0], l[v][1], l[v][2], l[v][0], l[v][1], l[v][2]));
            simd_f inv = simd_div_f(one, simd_add_f(len[v], l[v][2]));
            pu[v] = simd_mul_f(l[v][0], inv);
            pv[v] = simd_mul_f(l[v][1], inv);
        }
        /* c2max = max over the edges of the squared chord, max(c2max, c2) =
         * c2max > c2 ? c2max : c2 */
        simd_f c2max = zero;
        for (int k = 0; k < 3; k++) {
            int m = k == 2 ? 0 : k + 1;
            simd_f du = simd_sub_f(pu[m], pu[k]), dv = simd_sub_f(pv[m], pv[k]);
            c2max = simd_max_f(c2max, simd_add_f(simd_mul_f(du, du), simd_mul_f(dv, dv)));
        }
        simd_f mg = simd_add_f(simd_mul_f(c2max, quarter), eps);
        simd_f umin = simd_sub_f(simd_min_f(simd_min_f(pu[0], pu[1]), pu[2]), mg);
        simd_f umax = simd_add_f(simd_max_f(simd_max_f(pu[0], pu[1]), pu[2]), mg);
        simd_f vmin = simd_sub_f(simd_min_f(simd_min_f(pv[0], pv[1]), pv[2]), mg);
        simd_f vmax = simd_add_f(simd_max_f(simd_max_f(pv[0], pv[1]), pv[2]), mg);
        simd_i i0, i1, j0, j1;
        simd_mask okx = rs__uv_to_texels_w(umin, umax, ctx->res, sc->limit.i0, sc->limit.i1, &i0, &i1);
        simd_mask oky = rs__uv_to_texels_w(vmin, vmax, ctx->res, sc->limit.j0, sc->limit.j1, &j0, &j1);
        simd_mask drawn = simd_mask_and(all, simd_mask_and(okx, oky));
        simd_mask crossing = simd_mask_andnot(any, all);
        sc->stats.triangles_between_texels += (uint64_t)simd_mask_count(simd_mask_andnot(all, drawn));
        simd_mask keep = simd_mask_or(drawn, crossing);
        if (!simd_mask_any(keep)) continue;
        /* left-packed into the batch (each array has room for SIMD_W
         * elements past the cluster's triangles: rs__scratch_init) */
        uint32_t n = b->n;
        const simd_pack pk = simd_pack_make(keep);
        simd_pack_storeu_i((int32_t *)b->tri + n, pk, simd_add_i(simd_set1_i((int32_t)base), lane));
        for (int v = 0; v < 3; v++) {
            for (int c = 0; c < 3; c++) simd_pack_storeu_f(b->l[3 * v + c] + n, pk, l[v][c]);
            simd_pack_storeu_f(b->len[v] + n, pk, len[v]);
            simd_pack_storeu_f(b->pu[v] + n, pk, pu[v]);
            simd_pack_storeu_f(b->pv[v] + n, pk, pv[v]);
        }
        simd_pack_storeu_f(b->c2max + n, pk, c2max);
        simd_pack_storeu_i(b->rect[0] + n, pk, i0);
        simd_pack_storeu_i(b->rect[1] + n, pk, i1);
        simd_pack_storeu_i(b->rect[2] + n, pk, j0);
        simd_pack_storeu_i(b->rect[3] + n, pk, j1);
        simd_pack_storeu_i(b->crossing + n, pk, simd_select_i(crossing, simd_set1_i(1), simd_set1_i(0)));
        b->n = n + (uint32_t)simd_mask_count(keep);
    }
}

/* The texel loop, SIMD_W texels of a row at a time: edge values g_k = D .
 * e'_k with D = (d2[i], d2[j], dz[j][i]) in the order (dx ex + dy ey) + dz
 * ez; a lane is in when every g_k exceeds its filter bound, out when one is
 * below minus its bound, and rs__para_resolve decides the rest; covered
 * texels keep the nearest t = det' w / (D . N'). */
static uint64_t rs__scan(const rs_para_context *ctx, rs__scratch *sc, rs__setup *s, rs__rect r)
{
    const uint32_t R = ctx->res;
    uint64_t tested = 0;
    simd_f ex[3], ez[3], bp[3], bn[3];
    for (int k = 0; k < 3; k++) {
        ex[k] = simd_set1_f(s->e[k][0]);
        ez[k] = simd_set1_f(s->e[k][2]);
        bp[k] = simd_set1_f(s->bound[k]);
        bn[k] = simd_set1_f(-s->bound[k]);
    }
    const simd_f nx = simd_set1_f(s->nf[0]), nz = simd_set1_f(s->nf[2]), det = simd_set1_f(s->det);
    const simd_f zero = simd_zero_f();
    for (int32_t j = r.j0; j <= r.j1; j++) {
        int32_t lo = r.i0 > ctx->row_lo[j] ? r.i0 : ctx->row_lo[j];
        int32_t hi = r.i1 < ctx->row_hi[j] ? r.i1 : ctx->row_hi[j];
        if (lo > hi) continue;
        float dy = ctx->d2[j];
        simd_f ry[3];
        for (int k = 0; k < 3; k++) ry[k] = simd_set1_f(dy * s->e[k][1]);
        const simd_f ny = simd_set1_f(dy * s->nf[1]);
        const float *dzr = ctx->dz + (size_t)j * R, *wr = ctx->w + (size_t)j * R;
        float *depth = sc->depth + (size_t)j * R;
        for (int32_t i = lo; i <= hi; i += SIMD_W) {
            int32_t cnt = hi - i + 1;
            simd_mask valid = simd_mask_from_bits(cnt >= SIMD_W ? SIMD_FULL : (1u << cnt) - 1u);
            tested += (uint64_t)simd_mask_count(valid);
            /* whole vectors: the tables are padded, the lanes past hi are
             * never in nor unsure (valid masks them) */
            simd_f dx = simd_loadu_f(ctx->d2 + i), dz = simd_loadu_f(dzr + i);
            simd_f g[3];
            simd_mask in = valid, out = simd_mask_from_bits(0);
            for (int k = 0; k < 3; k++) {
                g[k] = simd_add_f(simd_add_f(simd_mul_f(dx, ex[k]), ry[k]), simd_mul_f(dz, ez[k]));
                in = simd_mask_and(in, simd_gt_f(g[k], bp[k]));
                out = simd_mask_or(out, simd_lt_f(g[k], bn[k]));
            }
            uint32_t unsure = simd_mask_bits(simd_mask_andnot(simd_mask_andnot(valid, in), out));
            if (unsure) {
                float gl[3][SIMD_W], dxl[SIMD_W], dzl[SIMD_W];
                for (int k = 0; k < 3; k++) simd_storeu_f(gl[k], g[k]);
                simd_storeu_f(dxl, dx);
                simd_storeu_f(dzl, dz);
                uint32_t resolved = 0;
                for (uint32_t m = unsure; m; m &= m - 1) {
                    int q = __builtin_ctz(m);
                    float gq[3] = {gl[0][q], gl[1][q], gl[2][q]};
                    if (rs__para_resolve(s, gq, dxl[q], dy, dzl[q], &sc->stats.texels_exact_fallback))
                        resolved |= 1u << q;
                }
                in = simd_mask_or(in, simd_mask_from_bits(resolved));
            }
            if (!simd_mask_any(in)) continue;
            /* whole-vector loads and a whole-vector store of the kept or
             * new depths (the tables and the depth plane are padded; the
             * lanes outside `in` write back what they read): AMD Zen 3 runs
             * masked loads and stores far slower (docs/perf.md, 2026-12-02
             * evening); the same values */
            simd_f w = simd_loadu_f(wr + i);
            simd_f dn = simd_add_f(simd_add_f(simd_mul_f(dx, nx), ny), simd_mul_f(dz, nz));
            simd_f t = simd_div_f(simd_mul_f(det, w), dn);
            simd_f old = simd_loadu_f(depth + i);
            simd_mask upd = simd_mask_and(in, simd_mask_and(simd_gt_f(t, zero), simd_lt_f(t, old)));
            simd_storeu_f(depth + i, simd_select_f(upd, t, old));
        }
    }
    return tested;
}

static uint32_t rs__visible(const uint16_t *map, uint32_t resolution, float range, float bias_scale,
                            const rs_para_frame *f, const float *px, const float *py, const float *pz,
                            const float *cos_receiver, const float *nx, const float *ny, const float *nz)
{
    const simd_f zero = simd_zero_f();
    return simd_mask_bits(rs_para_visible_lanes(map, resolution, range, bias_scale, f, simd_loadu_f(px),
                                                simd_loadu_f(py), simd_loadu_f(pz), simd_loadu_f(cos_receiver),
                                                nx != NULL, nx ? simd_loadu_f(nx) : zero, ny ? simd_loadu_f(ny) : zero,
                                                nz ? simd_loadu_f(nz) : zero));
}

const rs_para_kernels RS_PARA_KERNELS = {SIMD_NAME, SIMD_W, rs__front, rs__scan, rs__visible};
