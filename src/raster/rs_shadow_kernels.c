/* rs_shadow_kernels: the PCF lookup of rs_shadow_lookup.h compiled once per
 * instruction set (-DRS_SHADOW_KERNELS=rs_shadow_kernels_<isa>; see
 * docs/raster.md "The SIMD vocabulary"), for rs_shadow_visibility8. */
#include "rs_shadow_kernels.h"

#include "rs_shadow_lookup.h"
#include "simd.h"

#ifndef RS_SHADOW_KERNELS
#error "compile with -DRS_SHADOW_KERNELS=<table name> (CMakeLists.txt)"
#endif
_Static_assert(SIMD_W <= RS_SHADOW_MAX_LANES, "rs_shadow_kernels: lanes");

static void rs__visibility(const rs_shadow_map *m, const float *px, const float *py, const float *pz,
                           const float *ngx, const float *ngy, const float *ngz, unsigned active, float *out)
{
    simd_f v = rs_shadow_visibility_lanes(m, simd_loadu_f(px), simd_loadu_f(py), simd_loadu_f(pz), simd_loadu_f(ngx),
                                          simd_loadu_f(ngy), simd_loadu_f(ngz), simd_mask_from_bits(active & SIMD_FULL));
    simd_storeu_f(out, v);
}

const rs_shadow_kernels RS_SHADOW_KERNELS = {SIMD_NAME, SIMD_W, rs__visibility};
