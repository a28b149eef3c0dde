/* simd_scalar.h: the SIMD vocabulary in plain C, 8 lanes (see simd.h).
 *
 * This is the reference: each operation is written as the C expression
 * whose IEEE result every instruction set must reproduce lane by lane. A
 * kernel compiled with it (-DSIMD_FORCE_SCALAR) is softgi's scalar path,
 * the one `--isa sse2` and `sse4.2` run and the golden hashes pin. Eight
 * lanes, as AVX2, so a kernel has the same structure on every path; the
 * compiler is free to turn the loops into SSE2, which changes no bit.
 * Integer arithmetic wraps (through uint32_t / uint64_t) as the
 * instructions do. */
#ifndef SIMD_SCALAR_H
#define SIMD_SCALAR_H

#include <math.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#define SIMD_NAME "scalar"
#define SIMD_W 8  /* 32-bit lanes */
#define SIMD_WL 8 /* 64-bit lanes */
#define SIMD_FULL 0xffu

typedef struct simd_f { float v[SIMD_W]; } simd_f;
typedef struct simd_i { int32_t v[SIMD_W]; } simd_i;
typedef struct simd_l { int64_t v[SIMD_WL]; } simd_l;
typedef uint32_t simd_mask;

/* ---- float lanes */
static inline simd_f simd_set1_f(float x)
{
    simd_f r;
    for (int l = 0; l < SIMD_W; l++) r.v[l] = x;
    return r;
}
static inline simd_f simd_zero_f(void) { return simd_set1_f(0.0f); }
static inline simd_f simd_add_f(simd_f a, simd_f b)
{
    simd_f r;
    for (int l = 0; l < SIMD_W; l++) r.v[l] = a.v[l] + b.v[l];
    return r;
}
static inline simd_f simd_sub_f(simd_f a, simd_f b)
{
    simd_f r;
    for (int l = 0; l < SIMD_W; l++) r.v[l] = a.v[l] - b.v[l];
    return r;
}
static inline simd_f simd_mul_f(simd_f a, simd_f b)
{
    simd_f r;
    for (int l = 0; l < SIMD_W; l++) r.v[l] = a.v[l] * b.v[l];
    return r;
}
static inline simd_f simd_div_f(simd_f a, simd_f b)
{
    simd_f r;
    for (int l = 0; l < SIMD_W; l++) r.v[l] = a.v[l] / b.v[l];
    return r;
}
/* minps: b unless a < b */
static inline simd_f simd_min_f(simd_f a, simd_f b)
{
    simd_f r;
    for (int l = 0; l < SIMD_W; l++) r.v[l] = a.v[l] < b.v[l] ? a.v[l] : b.v[l];
    return r;
}
/* maxps: b unless a > b */
static inline simd_f simd_max_f(simd_f a, simd_f b)
{
    simd_f r;
    for (int l = 0; l < SIMD_W; l++) r.v[l] = a.v[l] > b.v[l] ? a.v[l] : b.v[l];
    return r;
}
static inline simd_f simd_sqrt_f(simd_f a)
{
    simd_f r;
    for (int l = 0; l < SIMD_W; l++) r.v[l] = sqrtf(a.v[l]);
    return r;
}
static inline simd_f simd_floor_f(simd_f a)
{
    simd_f r;
    for (int l = 0; l < SIMD_W; l++) r.v[l] = floorf(a.v[l]);
    return r;
}
static inline simd_f simd_ceil_f(simd_f a)
{
    simd_f r;
    for (int l = 0; l < SIMD_W; l++) r.v[l] = ceilf(a.v[l]);
    return r;
}
/* ordered, quiet comparisons: false where either lane is NaN */
static inline simd_mask simd_gt_f(simd_f a, simd_f b)
{
    simd_mask m = 0;
    for (int l = 0; l < SIMD_W; l++) m |= (simd_mask)(a.v[l] > b.v[l]) << l;
    return m;
}
static inline simd_mask simd_ge_f(simd_f a, simd_f b)
{
    simd_mask m = 0;
    for (int l = 0; l < SIMD_W; l++) m |= (simd_mask)(a.v[l] >= b.v[l]) << l;
    return m;
}
static inline simd_mask simd_lt_f(simd_f a, simd_f b)
{
    simd_mask m = 0;
    for (int l = 0; l < SIMD_W; l++) m |= (simd_mask)(a.v[l] < b.v[l]) << l;
    return m;
}
static inline simd_mask simd_le_f(simd_f a, simd_f b)
{
    simd_mask m = 0;
    for (int l = 0; l < SIMD_W; l++) m |= (simd_mask)(a.v[l] <= b.v[l]) << l;
    return m;
}
/* lanes of m from a, the others from b */
static inline simd_f simd_select_f(simd_mask m, simd_f a, simd_f b)
{
    simd_f r;
    for (int l = 0; l < SIMD_W; l++) r.v[l] = m >> l & 1 ? a.v[l] : b.v[l];
    return r;
}
/* the smallest lane (callers pass no NaN: then the order does not matter) */
static inline float simd_hmin_f(simd_f a)
{
    float m = a.v[0];
    for (int l = 1; l < SIMD_W; l++) m = a.v[l] < m ? a.v[l] : m;
    return m;
}

static inline simd_f simd_abs_f(simd_f a) /* sign bit cleared */
{
    simd_f r;
    for (int l = 0; l < SIMD_W; l++) r.v[l] = fabsf(a.v[l]);
    return r;
}
static inline simd_f simd_neg_f(simd_f a) /* sign bit flipped (0 - a differs at 0) */
{
    simd_f r;
    for (int l = 0; l < SIMD_W; l++) r.v[l] = -a.v[l];
    return r;
}
static inline simd_mask simd_eq_f(simd_f a, simd_f b)
{
    simd_mask m = 0;
    for (int l = 0; l < SIMD_W; l++) m |= (simd_mask)(a.v[l] == b.v[l]) << l;
    return m;
}

/* ---- float memory. load: aligned to SIMD_W floats; loadu: any. Masked
 * forms touch no memory of the lanes outside m (which read as 0). */
static inline simd_f simd_loadu_f(const float *p)
{
    simd_f r;
    for (int l = 0; l < SIMD_W; l++) r.v[l] = p[l];
    return r;
}
static inline simd_f simd_load_f(const float *p) { return simd_loadu_f(p); }
/* p aligned to the vector (SIMD_W * 4 bytes) */
static inline void simd_store_f(float *p, simd_f a)
{
    for (int l = 0; l < SIMD_W; l++) p[l] = a.v[l];
}
static inline void simd_storeu_f(float *p, simd_f a)
{
    for (int l = 0; l < SIMD_W; l++) p[l] = a.v[l];
}
static inline simd_f simd_maskz_loadu_f(const float *p, simd_mask m)
{
    simd_f r;
    for (int l = 0; l < SIMD_W; l++) r.v[l] = m >> l & 1 ? p[l] : 0.0f;
    return r;
}
static inline void simd_mask_storeu_f(float *p, simd_mask m, simd_f a)
{
    for (int l = 0; l < SIMD_W; l++)
        if (m >> l & 1) p[l] = a.v[l];
}
/* Rows of 8: lane l is element (l & 7) of row l >> 3, rows `stride`
 * elements apart (one row when SIMD_W <= 8). */
static inline simd_f simd_maskz_loadu_rows8_f(const float *p, size_t stride, simd_mask m)
{
    (void)stride;
    return simd_maskz_loadu_f(p, m);
}
static inline void simd_mask_storeu_rows8_f(float *p, size_t stride, simd_mask m, simd_f a)
{
    (void)stride;
    simd_mask_storeu_f(p, m, a);
}
/* lane l = r[l >> 3] */
static inline simd_f simd_set_rows8_f(const float *r) { return simd_set1_f(r[0]); }
/* lane l = r[l >> 2]: a stamp's row values spread over its rows of 4 lanes */
static inline simd_f simd_spread4_f(const float *r)
{
    simd_f v;
    for (int l = 0; l < SIMD_W; l++) v.v[l] = r[l >> 2];
    return v;
}

/* ---- int32 lanes (wrapping) */
static inline simd_i simd_set1_i(int32_t x)
{
    simd_i r;
    for (int l = 0; l < SIMD_W; l++) r.v[l] = x;
    return r;
}
static inline simd_i simd_iota_i(void) /* 0, 1, ..., SIMD_W - 1 */
{
    simd_i r;
    for (int l = 0; l < SIMD_W; l++) r.v[l] = l;
    return r;
}
static inline simd_i simd_add_i(simd_i a, simd_i b)
{
    simd_i r;
    for (int l = 0; l < SIMD_W; l++) r.v[l] = (int32_t)((uint32_t)a.v[l] + (uint32_t)b.v[l]);
    return r;
}
static inline simd_i simd_sub_i(simd_i a, simd_i b)
{
    simd_i r;
    for (int l = 0; l < SIMD_W; l++) r.v[l] = (int32_t)((uint32_t)a.v[l] - (uint32_t)b.v[l]);
    return r;
}
static inline simd_i simd_mullo_i(simd_i a, simd_i b)
{
    simd_i r;
    for (int l = 0; l < SIMD_W; l++) r.v[l] = (int32_t)((uint32_t)a.v[l] * (uint32_t)b.v[l]);
    return r;
}
static inline simd_i simd_and_i(simd_i a, simd_i b)
{
    simd_i r;
    for (int l = 0; l < SIMD_W; l++) r.v[l] = a.v[l] & b.v[l];
    return r;
}
static inline simd_i simd_or_i(simd_i a, simd_i b)
{
    simd_i r;
    for (int l = 0; l < SIMD_W; l++) r.v[l] = a.v[l] | b.v[l];
    return r;
}
static inline simd_i simd_srli_i(simd_i a, int n) /* logical shift right by a constant */
{
    simd_i r;
    for (int l = 0; l < SIMD_W; l++) r.v[l] = (int32_t)((uint32_t)a.v[l] >> n);
    return r;
}
static inline simd_mask simd_eq_i(simd_i a, simd_i b)
{
    simd_mask m = 0;
    for (int l = 0; l < SIMD_W; l++) m |= (simd_mask)(a.v[l] == b.v[l]) << l;
    return m;
}
static inline simd_mask simd_gt_i(simd_i a, simd_i b)
{
    simd_mask m = 0;
    for (int l = 0; l < SIMD_W; l++) m |= (simd_mask)(a.v[l] > b.v[l]) << l;
    return m;
}
/* lanes whose sign bit is set */
static inline simd_mask simd_negative_i(simd_i a)
{
    simd_mask m = 0;
    for (int l = 0; l < SIMD_W; l++) m |= (simd_mask)(a.v[l] < 0) << l;
    return m;
}
/* the int32 lanes' bits as floats (data movement only) */
static inline simd_f simd_asfloat_i(simd_i a)
{
    simd_f r;
    memcpy(r.v, a.v, sizeof r.v);
    return r;
}
static inline simd_f simd_i2f(simd_i a) /* int32 -> float, rounded to nearest */
{
    simd_f r;
    for (int l = 0; l < SIMD_W; l++) r.v[l] = (float)a.v[l];
    return r;
}
/* float -> int32 towards zero; NaN and out-of-range lanes give INT32_MIN as
 * cvttps does (callers mask them) */
static inline simd_i simd_f2i_trunc(simd_f a)
{
    simd_i r;
    for (int l = 0; l < SIMD_W; l++)
        r.v[l] = a.v[l] > -2147483904.0f && a.v[l] < 2147483648.0f ? (int32_t)a.v[l] : INT32_MIN;
    return r;
}
/* p[l] for the lanes of m, 0 elsewhere (reads nothing for the others) */
static inline simd_i simd_maskz_loadu_i(const int32_t *p, simd_mask m)
{
    simd_i r;
    for (int l = 0; l < SIMD_W; l++) r.v[l] = m >> l & 1 ? p[l] : 0;
    return r;
}
static inline simd_i simd_loadu_i(const int32_t *p)
{
    simd_i r;
    for (int l = 0; l < SIMD_W; l++) r.v[l] = p[l];
    return r;
}
static inline simd_i simd_load_i(const int32_t *p) { return simd_loadu_i(p); }
/* p aligned to the vector (SIMD_W * 4 bytes) */
static inline void simd_store_i(int32_t *p, simd_i a)
{
    for (int l = 0; l < SIMD_W; l++) p[l] = a.v[l];
}
static inline void simd_storeu_i(int32_t *p, simd_i a)
{
    for (int l = 0; l < SIMD_W; l++) p[l] = a.v[l];
}
static inline void simd_mask_storeu_i(int32_t *p, simd_mask m, simd_i a)
{
    for (int l = 0; l < SIMD_W; l++)
        if (m >> l & 1) p[l] = a.v[l];
}
static inline void simd_mask_storeu_rows8_i(int32_t *p, size_t stride, simd_mask m, simd_i a)
{
    (void)stride;
    simd_mask_storeu_i(p, m, a);
}
/* A store that bypasses the cache (p aligned to SIMD_W elements); call
 * simd_stream_fence before another thread may read what was streamed. */
static inline void simd_stream_i(int32_t *p, simd_i a) { simd_storeu_i(p, a); }
static inline void simd_stream_fence(void) {}

static inline simd_i simd_select_i(simd_mask m, simd_i a, simd_i b)
{
    simd_i r;
    for (int l = 0; l < SIMD_W; l++) r.v[l] = m >> l & 1 ? a.v[l] : b.v[l];
    return r;
}
/* The lanes of m stored contiguously at p, in lane order; returns how many.
 * Writes only those elements. */
static inline int simd_compress_storeu_f(float *p, simd_mask m, simd_f a)
{
    int n = 0;
    for (int l = 0; l < SIMD_W; l++)
        if (m >> l & 1) p[n++] = a.v[l];
    return n;
}
static inline int simd_compress_storeu_i(int32_t *p, simd_mask m, simd_i a)
{
    int n = 0;
    for (int l = 0; l < SIMD_W; l++)
        if (m >> l & 1) p[n++] = a.v[l];
    return n;
}
/* Left-packing of several vectors under one mask: k = simd_pack_make(m)
 * once, then simd_pack_storeu_f/_i(p, k, a) stores a's lanes of m at p in
 * lane order, as simd_compress_storeu does, but may also write anything to
 * the elements after them up to p[SIMD_W - 1]: the destination needs room
 * for SIMD_W elements. (AVX2 has no compress instruction: one permutation
 * and one whole-vector store there, instead of a store per lane.) */
typedef simd_mask simd_pack;
static inline simd_pack simd_pack_make(simd_mask m) { return m; }
static inline void simd_pack_storeu_f(float *p, simd_pack k, simd_f a) { (void)simd_compress_storeu_f(p, k, a); }
static inline void simd_pack_storeu_i(int32_t *p, simd_pack k, simd_i a) { (void)simd_compress_storeu_i(p, k, a); }
/* base[idx] of a table of 16-bit values, every lane (indices must be in
 * the table whether or not the lane is used later); the SIMD headers read
 * 32 bits at 2 idx and keep the low half, so the table needs two bytes of
 * slack after its last element. */
static inline simd_i simd_gather_u16(const uint16_t *base, simd_i idx)
{
    simd_i r;
    for (int l = 0; l < SIMD_W; l++) r.v[l] = base[idx.v[l]];
    return r;
}

static inline simd_i simd_min_i(simd_i a, simd_i b)
{
    simd_i r;
    for (int l = 0; l < SIMD_W; l++) r.v[l] = a.v[l] < b.v[l] ? a.v[l] : b.v[l];
    return r;
}
static inline simd_i simd_max_i(simd_i a, simd_i b)
{
    simd_i r;
    for (int l = 0; l < SIMD_W; l++) r.v[l] = a.v[l] > b.v[l] ? a.v[l] : b.v[l];
    return r;
}
static inline simd_i simd_slli_i(simd_i a, int n)
{
    simd_i r;
    for (int l = 0; l < SIMD_W; l++) r.v[l] = (int32_t)((uint32_t)a.v[l] << n);
    return r;
}
static inline int32_t simd_lane0_i(simd_i a) { return a.v[0]; }
/* base[idx] for every lane (every index must be inside the array) */
static inline simd_f simd_gather_f(const float *base, simd_i idx)
{
    simd_f r;
    for (int l = 0; l < SIMD_W; l++) r.v[l] = base[idx.v[l]];
    return r;
}
/* The SIMD_W triples at p (3 SIMD_W floats: x0 y0 z0 x1 y1 z1 ...) as three
 * vectors of their first, second and third members (data movement only). */
static inline void simd_load3_f(const float *p, simd_f *a, simd_f *b, simd_f *c)
{
    for (int l = 0; l < SIMD_W; l++) a->v[l] = p[3 * l], b->v[l] = p[3 * l + 1], c->v[l] = p[3 * l + 2];
}
/* base[idx] for the lanes of m, 0 elsewhere (reads nothing for the others) */
static inline simd_f simd_maskz_gather_f(const float *base, simd_i idx, simd_mask m)
{
    simd_f r;
    for (int l = 0; l < SIMD_W; l++) r.v[l] = m >> l & 1 ? base[idx.v[l]] : 0.0f;
    return r;
}
/* Four consecutive floats per lane, transposed: lane l of out[k] is
 * base[idx_l + k] (data movement only; every lane's four floats must lie
 * inside the array). One 4-float load per lane instead of four gathers. */
static inline void simd_gather4_f(const float *base, simd_i idx, simd_f out[4])
{
    for (int k = 0; k < 4; k++)
        for (int l = 0; l < SIMD_W; l++) out[k].v[l] = base[idx.v[l] + k];
}

/* Stamps of 4-pixel rows (SIMD_W / 4 rows): lane l is column l & 3 of row
 * l >> 2 of a row-major plane with row stride `stride`. */
static inline simd_i simd_load_rows4_i(const int32_t *p, size_t stride)
{
    simd_i r;
    for (int l = 0; l < SIMD_W; l++) r.v[l] = p[(size_t)(l >> 2) * stride + (size_t)(l & 3)];
    return r;
}
static inline void simd_store_rows4_f(float *p, size_t stride, simd_f a)
{
    for (int l = 0; l < SIMD_W; l++) p[(size_t)(l >> 2) * stride + (size_t)(l & 3)] = a.v[l];
}
/* lane l = p[l & 3]: a stamp's column values repeated over its rows */
static inline simd_f simd_tile4_f(const float *p)
{
    simd_f r;
    for (int l = 0; l < SIMD_W; l++) r.v[l] = p[l & 3];
    return r;
}

/* lane l = a[idx[l] mod SIMD_W]: a permutation within one vector */
static inline simd_f simd_permute_f(simd_f a, simd_i idx)
{
    simd_f r;
    for (int l = 0; l < SIMD_W; l++) r.v[l] = a.v[idx.v[l] & (SIMD_W - 1)];
    return r;
}
static inline simd_i simd_permute_i(simd_i a, simd_i idx)
{
    simd_i r;
    for (int l = 0; l < SIMD_W; l++) r.v[l] = a.v[idx.v[l] & (SIMD_W - 1)];
    return r;
}

/* ---- int64 lanes (wrapping) */
static inline simd_l simd_set1_l(int64_t x)
{
    simd_l r;
    for (int l = 0; l < SIMD_WL; l++) r.v[l] = x;
    return r;
}
/* base + lane * step, exact (the callers' values do not overflow) */
static inline simd_l simd_ramp_l(int64_t base, int64_t step)
{
    simd_l r;
    for (int l = 0; l < SIMD_WL; l++) r.v[l] = base + step * l;
    return r;
}
static inline simd_l simd_or_l(simd_l a, simd_l b)
{
    simd_l r;
    for (int l = 0; l < SIMD_WL; l++) r.v[l] = a.v[l] | b.v[l];
    return r;
}
/* the lanes whose sign bit is set, as plain bits (64-bit lanes do not
 * match simd_mask's 32-bit ones) */
static inline uint32_t simd_negative_l(simd_l a)
{
    uint32_t m = 0;
    for (int l = 0; l < SIMD_WL; l++) m |= (uint32_t)(a.v[l] < 0) << l;
    return m;
}

/* Before calling code compiled for another vector width (SSE-encoded
 * functions of the baseline build): no cost on the scalar and SSE paths,
 * vzeroupper on AVX2 and AVX-512 (mixing VEX and legacy SSE encodings
 * otherwise stalls: the resolve ran 60% slower without it). */
static inline void simd_zeroupper(void) {}

/* ---- masks */
/* Masks: a bit per lane here. The instruction sets keep them in whatever
 * form their instructions take (vector lanes on SSE2 and AVX2, mask
 * registers on AVX-512), so kernels combine and test masks only through
 * these functions, and turn them into plain bits (lane l in bit l) with
 * simd_mask_bits where they loop over lanes or count them. */
static inline simd_mask simd_mask_and(simd_mask a, simd_mask b) { return a & b; }
static inline simd_mask simd_mask_or(simd_mask a, simd_mask b) { return a | b; }
static inline simd_mask simd_mask_andnot(simd_mask a, simd_mask b) { return a & ~b; } /* a and not b */
static inline simd_mask simd_mask_not(simd_mask a) { return ~a & SIMD_FULL; }
static inline uint32_t simd_mask_bits(simd_mask m) { return m; }
static inline simd_mask simd_mask_from_bits(uint32_t b) { return b & SIMD_FULL; }
static inline int simd_mask_any(simd_mask m) { return m != 0; }
static inline int simd_mask_count(simd_mask m) { return __builtin_popcount(m); }

#endif
