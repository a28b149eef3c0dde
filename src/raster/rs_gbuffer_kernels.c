/* rs_gbuffer_kernels: the G-buffer resolve, one block of 4 x SIMD_W / 4
 * pixels at a time (4x4 on AVX-512, 4x2 on AVX2: a block of an image shows
 * about half as many triangles as a run of SIMD_W pixels of a row, 2.0
 * against 3.7 on Sibenik), written once over the SIMD vocabulary and
 * compiled once per instruction set (-DRS_GBUFFER_KERNELS=
 * rs_gbuffer_kernels_<isa>; see docs/raster.md "The SIMD vocabulary").
 * rs__gbuf_resolve_pixel and rs__gbuf_normalize_pixel (rs_gbuffer.c) are
 * the reference: a block is resolved here only when its pixels show at most
 * SIMD_W / 2 untextured triangles; then each triangle is resolved for all
 * lanes with the reference's operations in its order (ray direction,
 * rs__bary, clamping and renormalising the barycentrics, position, the
 * camera-facing interpolated normal, view depth, the material's base
 * colour), blended into the lanes that show it and the normal normalised,
 * so the bits are the scalar code's. */
#include "rs_gbuffer_kernels.h"

#include <math.h>

#include "simd.h"

#ifndef RS_GBUFFER_KERNELS
#error "compile with -DRS_GBUFFER_KERNELS=<table name> (CMakeLists.txt)"
#endif

enum { RS__T_P0 = 0, RS__T_E1 = 3, RS__T_E2 = 6, RS__T_NDET = 9, RS__T_NG = 12, RS__T_N0 = 15, RS__T_N1 = 18,
       RS__T_N2 = 21, RS__UV_NU = 0, RS__UV_NV = 3 };
/* more triangles in a group: the scalar code (measured as fast with 8 lanes) */
enum { RS__GROUP_MAX_TRIS = SIMD_W / 2 };

/* (d . base[f..f+2]) in pf_v3_dot's order */
static inline simd_f rs__dot_c(simd_f dx, simd_f dy, simd_f dz, const float *base, int f)
{
    return simd_add_f(simd_add_f(simd_mul_f(dx, simd_set1_f(base[f])), simd_mul_f(dy, simd_set1_f(base[f + 1]))),
                      simd_mul_f(dz, simd_set1_f(base[f + 2])));
}

/* rs__gbuf_resolve_pixel's work for the block whose lanes' ray directions
 * are d, on one untextured triangle (constants T, UV, base colour ALB),
 * every lane. o: depth, position, normal, albedo (10 planes). */
static void rs__resolve_lanes(const rs__resolve_ctx *rc, const float *T, const float *UV, const float *ALB,
                              const simd_f d[3], simd_mask mine, simd_f o[10])
{
    const pf_camera *cam = rc->cam;
    const simd_f zero = simd_zero_f(), one = simd_set1_f(1.0f);
    const float *fw = &cam->forward.x;
    /* rs__bary: u = v = 0 where det == 0 */
    simd_f det = rs__dot_c(d[0], d[1], d[2], T, RS__T_NDET);
    simd_f inv = simd_div_f(one, det);
    simd_mask has = simd_mask_not(simd_eq_f(det, zero));
    simd_f u = simd_select_f(has, simd_mul_f(rs__dot_c(d[0], d[1], d[2], UV, RS__UV_NU), inv), zero);
    simd_f v = simd_select_f(has, simd_mul_f(rs__dot_c(d[0], d[1], d[2], UV, RS__UV_NV), inv), zero);
    simd_mask facing = simd_gt_f(rs__dot_c(d[0], d[1], d[2], T, RS__T_NG), zero);
    /* x < 0 ? 0 : (x > 1 ? 1 : x) as max(0, min(1, x)): min(a, b) is
     * a < b ? a : b and max(a, b) is a > b ? a : b, so with the constant
     * first a NaN or -0 passes through exactly as in the ternaries */
    u = simd_max_f(zero, simd_min_f(one, u));
    v = simd_max_f(zero, simd_min_f(one, v));
    simd_f sum = simd_add_f(u, v);
    simd_mask over = simd_gt_f(sum, one);
    /* the lanes past the edge opposite vertex 0 (rare among the lanes that
     * show the triangle, `mine`; the others' values are not kept): two
     * divisions */
    if (simd_mask_any(simd_mask_and(over, mine))) {
        u = simd_select_f(over, simd_div_f(u, sum), u);
        v = simd_select_f(over, simd_div_f(v, sum), v);
    }
    simd_f w = simd_sub_f(simd_sub_f(one, u), v);
    /* position p0 + (e1 u + e2 v) */
    simd_f p[3];
    for (int k = 0; k < 3; k++)
        p[k] = simd_add_f(simd_set1_f(T[RS__T_P0 + k]), simd_add_f(simd_mul_f(simd_set1_f(T[RS__T_E1 + k]), u),
                                                                   simd_mul_f(simd_set1_f(T[RS__T_E2 + k]), v)));
    /* ns, times -1 (a multiplication, as pf_v3_scale does) where the
     * triangle faces away from the camera; elsewhere the product is by 1:
     * exact, the same bits */
    simd_f flip = simd_select_f(facing, simd_set1_f(-1.0f), one);
    for (int k = 0; k < 3; k++)
        o[4 + k] = simd_mul_f(simd_add_f(simd_add_f(simd_mul_f(simd_set1_f(T[RS__T_N0 + k]), w),
                                                    simd_mul_f(simd_set1_f(T[RS__T_N1 + k]), u)),
                                         simd_mul_f(simd_set1_f(T[RS__T_N2 + k]), v)),
                              flip);
    /* view depth: (p - eye) . forward */
    const float *eye = &cam->eye.x;
    o[0] = simd_add_f(simd_add_f(simd_mul_f(simd_sub_f(p[0], simd_set1_f(eye[0])), simd_set1_f(fw[0])),
                                 simd_mul_f(simd_sub_f(p[1], simd_set1_f(eye[1])), simd_set1_f(fw[1]))),
                      simd_mul_f(simd_sub_f(p[2], simd_set1_f(eye[2])), simd_set1_f(fw[2])));
    o[1] = p[0], o[2] = p[1], o[3] = p[2];
    o[7] = simd_set1_f(ALB[0]), o[8] = simd_set1_f(ALB[1]), o[9] = simd_set1_f(ALB[2]);
}

/* The block of pixels x .. x + 3, y .. y + SIMD_W / 4 - 1: each distinct
 * triangle among them is resolved for all lanes and blended into the lanes
 * that show it; empty lanes get rs__gbuf_resolve_pixel's empty values; the
 * normals are normalised as rs__gbuf_normalize_pixel does (a covered lane
 * whose normal vanished takes that function's fallback). Returns 0
 * (nothing written) when a lane shows a textured triangle or the block
 * shows more than RS__GROUP_MAX_TRIS triangles; the caller then takes the
 * scalar path. The distinct triangles and their lanes come from lane
 * compares (one per triangle, not a scalar search per lane); the (scalar,
 * baseline-encoded) triangle setups then all run after simd_zeroupper and
 * before any further wide register is live, so their loads overlap and no
 * encoding mixing occurs. The cache `c` keeps its triangle if the block
 * shows it, else takes the last lane's, which the next block most likely
 * continues. */
static int rs__group(const rs__resolve_ctx *rc, rs__tri_consts *c, uint32_t x, uint32_t y)
{
    rs_gbuffer *g = rc->g;
    size_t i = (size_t)y * g->width + x;
    const uint32_t *prim = g->prim + i;
    simd_i prims = simd_load_rows4_i((const int32_t *)prim, g->width);
    /* the distinct triangles in lane order, each with its lanes */
    uint32_t tris[RS__GROUP_MAX_TRIS];
    simd_mask lanes[RS__GROUP_MAX_TRIS];
    int n = 0;
    const simd_mask covered = simd_mask_not(simd_eq_i(prims, simd_set1_i((int32_t)RS_GBUFFER_EMPTY)));
    uint32_t left = simd_mask_bits(covered);
    while (left) {
        if (n == RS__GROUP_MAX_TRIS) return 0;
        int l = __builtin_ctz(left);
        uint32_t p = prim[(size_t)(l >> 2) * g->width + (size_t)(l & 3)];
        simd_mask m = simd_eq_i(prims, simd_set1_i((int32_t)p));
        tris[n] = p, lanes[n++] = m;
        left &= ~simd_mask_bits(m);
    }
    /* each triangle's constants: the scene's table and, for this camera,
     * n_u = e2 x tv and n_v = tv x e1 with tv = eye - p0 (rs__gbuf_tri_setup's
     * operations, so the same bits), without a setup call per triangle */
    if (!rc->table) return 0;
    const rs_resolve_tri *tt[RS__GROUP_MAX_TRIS];
    pf_vec3 uv[RS__GROUP_MAX_TRIS][2];
    for (int j = 0; j < n; j++) {
        const rs_resolve_tri *t = tt[j] = &rc->table[tris[j]];
        if (t->textured) return 0;
        pf_vec3 tv = pf_v3_sub(rc->cam->eye, t->p0);
        uv[j][0] = pf_v3_cross(t->e2, tv);
        uv[j][1] = pf_v3_cross(tv, t->e1);
    }
    (void)c;
    simd_f acc[10], o[10];
    /* the lanes' rays, pf_camera_ray_dir: forward + (right sx + up sy) */
    const pf_camera *cam = rc->cam;
    simd_f sx = simd_tile4_f(rc->sx + x), sy = simd_spread4_f(rc->sy + y), d[3];
    const float *fw = &cam->forward.x, *rt = &cam->right.x, *up = &cam->up.x;
    for (int k = 0; k < 3; k++)
        d[k] = simd_add_f(simd_set1_f(fw[k]),
                          simd_add_f(simd_mul_f(simd_set1_f(rt[k]), sx), simd_mul_f(simd_set1_f(up[k]), sy)));
    const pf_material *mat = rc->scene->materials;
    /* the first triangle's values where it shows, the empty pixel's
     * elsewhere (depth +inf, the rest 0); then each further triangle's */
    for (int j = 0; j < n; j++) {
        rs__resolve_lanes(rc, &tt[j]->p0.x, &uv[j][0].x, mat[tt[j]->material].base_color, d, lanes[j], o);
        if (j == 0) {
            acc[0] = simd_select_f(lanes[0], o[0], simd_set1_f(INFINITY));
            for (int k = 1; k < 10; k++) acc[k] = simd_select_f(lanes[0], o[k], simd_zero_f());
        } else
            for (int k = 0; k < 10; k++) acc[k] = simd_select_f(lanes[j], o[k], acc[k]);
    }
    if (n == 0) {
        acc[0] = simd_set1_f(INFINITY);
        for (int k = 1; k < 10; k++) acc[k] = simd_zero_f();
    }
    /* the normal: pf_v3_normalize's operations, l = sqrt((x*x + y*y) + z*z),
     * n * (1 / l), 0 for l = 0 */
    const simd_f zero = simd_zero_f();
    simd_f l = simd_sqrt_f(simd_add_f(simd_add_f(simd_mul_f(acc[4], acc[4]), simd_mul_f(acc[5], acc[5])),
                                      simd_mul_f(acc[6], acc[6])));
    simd_f inv = simd_select_f(simd_gt_f(l, zero), simd_div_f(simd_set1_f(1.0f), l), zero);
    for (int k = 4; k < 7; k++) acc[k] = simd_mul_f(acc[k], inv);
    simd_mask vanished = simd_mask_and(simd_mask_and(simd_eq_f(acc[4], zero), simd_eq_f(acc[5], zero)),
                                       simd_mask_and(simd_eq_f(acc[6], zero), covered));
    float *planes[10] = {g->depth, g->pos_x, g->pos_y, g->pos_z, g->nrm_x, g->nrm_y, g->nrm_z, g->alb_r, g->alb_g, g->alb_b};
    for (int k = 0; k < 10; k++) simd_store_rows4_f(planes[k] + i, g->width, acc[k]);
    for (uint32_t m = simd_mask_bits(vanished); m; m &= m - 1) {
        int b = __builtin_ctz(m);
        rs__gbuf_normal_fallback(rc, x + (uint32_t)(b & 3), y + (uint32_t)(b >> 2));
    }
    return 1;
}

const rs_gbuffer_kernels RS_GBUFFER_KERNELS = {SIMD_NAME, SIMD_W / 4, rs__group};
