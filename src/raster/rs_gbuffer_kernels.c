/* rs_gbuffer_kernels: the G-buffer resolve, SIMD_W pixels of a row at a
 * time, written once over the SIMD vocabulary and compiled once per
 * instruction set (-DRS_GBUFFER_KERNELS=rs_gbuffer_kernels_<isa>; see
 * docs/raster.md "The SIMD vocabulary"). rs__gbuf_resolve_pixel
 * (rs_gbuffer.c) is the reference: a group is resolved here only when its
 * pixels show at most SIMD_W / 2 untextured triangles; then each triangle
 * is resolved for all lanes with the reference's operations in its order
 * (ray direction, rs__bary, clamping and renormalising the barycentrics,
 * position, the camera-facing interpolated normal, view depth, the
 * material's base colour) and blended into the lanes that show it, so the
 * bits are the scalar code's. */
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

/* rs__gbuf_resolve_pixel's work for pixels x.. of row y on one untextured
 * triangle (constants T, UV, base colour ALB), every lane. o: depth,
 * position, normal, albedo (10 planes). */
static void rs__resolve_lanes(const rs__resolve_ctx *rc, const float *T, const float *UV, const float *ALB, uint32_t x,
                              uint32_t y, simd_f o[10])
{
    const pf_camera *cam = rc->cam;
    const simd_f zero = simd_zero_f(), one = simd_set1_f(1.0f);
    simd_f sx = simd_loadu_f(rc->sx + x), sy = simd_set1_f(rc->sy[y]);
    /* pf_camera_ray_dir: forward + (right sx + up sy) */
    simd_f d[3];
    const float *fw = &cam->forward.x, *rt = &cam->right.x, *up = &cam->up.x;
    for (int k = 0; k < 3; k++)
        d[k] = simd_add_f(simd_set1_f(fw[k]),
                          simd_add_f(simd_mul_f(simd_set1_f(rt[k]), sx), simd_mul_f(simd_set1_f(up[k]), sy)));
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
    u = simd_select_f(over, simd_div_f(u, sum), u);
    v = simd_select_f(over, simd_div_f(v, sum), v);
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

/* The pixels x .. x + SIMD_W - 1 of row y: each distinct triangle among
 * them is resolved for all lanes and blended into the lanes that show it;
 * empty lanes get rs__gbuf_resolve_pixel's empty values. Returns 0
 * (nothing written) when a lane shows a textured triangle or the group
 * shows more than RS__GROUP_MAX_TRIS triangles; the caller then takes the
 * scalar path (per-lane constants transposed from the setups were measured
 * no faster). The distinct triangles and their lanes come from lane
 * compares (one per triangle, not a scalar search per lane); the (scalar,
 * baseline-encoded) triangle setups then all run after simd_zeroupper and
 * before any further wide register is live, so their loads overlap and no
 * encoding mixing occurs. The cache `c` keeps its triangle if the group
 * shows it, else takes the last lane's, which the next group most likely
 * continues. */
static int rs__group(const rs__resolve_ctx *rc, rs__tri_consts *c, uint32_t x, uint32_t y)
{
    rs_gbuffer *g = rc->g;
    size_t i = (size_t)y * g->width + x;
    const uint32_t *prim = g->prim + i;
    simd_i prims = simd_loadu_i((const int32_t *)prim);
    /* the distinct triangles in lane order, each with its lanes */
    uint32_t tris[RS__GROUP_MAX_TRIS];
    simd_mask lanes[RS__GROUP_MAX_TRIS];
    int n = 0;
    uint32_t left = simd_mask_bits(simd_mask_not(simd_eq_i(prims, simd_set1_i((int32_t)RS_GBUFFER_EMPTY))));
    while (left) {
        if (n == RS__GROUP_MAX_TRIS) return 0;
        uint32_t p = prim[__builtin_ctz(left)];
        simd_mask m = simd_eq_i(prims, simd_set1_i((int32_t)p));
        tris[n] = p, lanes[n++] = m;
        left &= ~simd_mask_bits(m);
    }
    simd_zeroupper(); /* the setups below are baseline-encoded */
    rs__tri_consts other[RS__GROUP_MAX_TRIS];
    const rs__tri_consts *consts[RS__GROUP_MAX_TRIS];
    int keep = 0;
    for (int j = 0; j < n; j++) keep |= tris[j] == c->prim;
    for (int j = 0; j < n; j++) {
        if (tris[j] == c->prim || (!keep && tris[j] == prim[SIMD_W - 1])) {
            if (tris[j] != c->prim) rs__gbuf_tri_setup(c, rc, tris[j]);
            consts[j] = c;
        } else {
            rs__gbuf_tri_setup(&other[j], rc, tris[j]);
            consts[j] = &other[j];
        }
        if (consts[j]->t->textured) return 0;
    }
    simd_f acc[10], o[10];
    acc[0] = simd_set1_f(INFINITY);
    for (int k = 1; k < 10; k++) acc[k] = simd_zero_f();
    const pf_material *mat = rc->scene->materials;
    for (int j = 0; j < n; j++) {
        const rs__tri_consts *cj = consts[j];
        rs__resolve_lanes(rc, &cj->t->p0.x, &cj->n_u.x, mat[cj->t->material].base_color, x, y, o);
        for (int k = 0; k < 10; k++) acc[k] = simd_select_f(lanes[j], o[k], acc[k]);
    }
    float *planes[10] = {g->depth, g->pos_x, g->pos_y, g->pos_z, g->nrm_x, g->nrm_y, g->nrm_z, g->alb_r, g->alb_g, g->alb_b};
    for (int k = 0; k < 10; k++) simd_storeu_f(planes[k] + i, acc[k]);
    return 1;
}

const rs_gbuffer_kernels RS_GBUFFER_KERNELS = {SIMD_NAME, SIMD_W, rs__group};
