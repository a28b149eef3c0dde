/* gi_importance_kernels: the importance map's sum over the camera points,
 * SIMD_W texels at a time (see gi_importance_kernels.h). Lane l is texel l;
 * each lane adds camera point k into partial sum k mod 8 with
 * gi__importance_term's operations in its order (max, min and the division
 * as the scalar code's ternaries and '/'), so every lane gets the scalar
 * loop's bits (tests/test_rsm_methods.c compares the paths). */
#include "gi_importance_kernels.h"

#include "simd.h"

#ifndef GI_IMPORTANCE_KERNELS
#error "compile with -DGI_IMPORTANCE_KERNELS=<table name> (CMakeLists.txt)"
#endif

static inline simd_f gi__term(const gi_importance_in *in, uint32_t k, simd_f px, simd_f py, simd_f pz, simd_f vx,
                              simd_f vy, simd_f vz, simd_f zero, simd_f tiny, simd_f g_max)
{
    simd_f dx = simd_sub_f(px, simd_set1_f(in->x[k]));
    simd_f dy = simd_sub_f(py, simd_set1_f(in->y[k]));
    simd_f dz = simd_sub_f(pz, simd_set1_f(in->z[k]));
    simd_f d2 = simd_add_f(simd_add_f(simd_mul_f(dx, dx), simd_mul_f(dy, dy)), simd_mul_f(dz, dz));
    simd_f ck = simd_add_f(simd_add_f(simd_mul_f(simd_set1_f(in->nx[k]), dx), simd_mul_f(simd_set1_f(in->ny[k]), dy)),
                           simd_mul_f(simd_set1_f(in->nz[k]), dz));
    simd_f cv = simd_neg_f(simd_add_f(simd_add_f(simd_mul_f(vx, dx), simd_mul_f(vy, dy)), simd_mul_f(vz, dz)));
    ck = simd_max_f(ck, zero);
    cv = simd_max_f(cv, zero);
    simd_f d4 = simd_max_f(simd_mul_f(d2, d2), tiny);
    simd_f G = simd_min_f(simd_div_f(simd_mul_f(ck, cv), d4), g_max);
    return simd_mul_f(simd_set1_f(in->alb[k]), G);
}

static void gi__texels(const gi_importance_in *in, const float *px_, const float *py_, const float *pz_,
                       const float *vx_, const float *vy_, const float *vz_, float *sum)
{
    const simd_f px = simd_loadu_f(px_), py = simd_loadu_f(py_), pz = simd_loadu_f(pz_);
    const simd_f vx = simd_loadu_f(vx_), vy = simd_loadu_f(vy_), vz = simd_loadu_f(vz_);
    const simd_f zero = simd_zero_f(), tiny = simd_set1_f(1e-30f), g_max = simd_set1_f(in->g_max);
    simd_f acc[8];
    for (int l = 0; l < 8; l++) acc[l] = zero;
    const uint32_t K = in->count;
    uint32_t k = 0;
    for (; k + 8 <= K; k += 8)
        for (uint32_t l = 0; l < 8; l++)
            acc[l] = simd_add_f(acc[l], gi__term(in, k + l, px, py, pz, vx, vy, vz, zero, tiny, g_max));
    for (uint32_t l = 0; k < K; k++, l++)
        acc[l] = simd_add_f(acc[l], gi__term(in, k, px, py, pz, vx, vy, vz, zero, tiny, g_max));
    simd_f s = simd_add_f(simd_add_f(simd_add_f(acc[0], acc[1]), simd_add_f(acc[2], acc[3])),
                          simd_add_f(simd_add_f(acc[4], acc[5]), simd_add_f(acc[6], acc[7])));
    simd_storeu_f(sum, s);
}

const gi_importance_kernels GI_IMPORTANCE_KERNELS = {SIMD_NAME, SIMD_W, gi__texels};
