/* simd_sse.h: the SIMD vocabulary on SSE2, 4 lanes (see simd.h; the
 * meaning of every operation is the plain C of simd_scalar.h). SSE2 is what
 * every x86-64 compiler targets by default, so this is the vocabulary of
 * code outside the per-ISA kernels (the rasterizer's tile bookkeeping:
 * block minima, streaming copies). The few operations SSE2 lacks (floor,
 * ceil, 32-bit multiply, masked memory) go lane by lane with the scalar C.
 * A mask is a vector with all ones in its set lanes. */
#ifndef SIMD_SSE_H
#define SIMD_SSE_H

#include <emmintrin.h>
#include <math.h>
#include <stddef.h>
#include <stdint.h>

#define SIMD_NAME "sse2"
#define SIMD_W 4  /* 32-bit lanes */
#define SIMD_WL 2 /* 64-bit lanes */
#define SIMD_FULL 0xfu

typedef __m128 simd_f;
typedef __m128i simd_i;
typedef __m128i simd_l;
typedef __m128 simd_mask; /* all ones in the set lanes, zeros in the others */

/* bit l of b -> all ones in lane l */
static inline simd_mask simd_mask_from_bits(uint32_t b)
{
    const __m128i bits = _mm_setr_epi32(1, 2, 4, 8);
    return _mm_castsi128_ps(_mm_cmpeq_epi32(_mm_and_si128(_mm_set1_epi32((int)b), bits), bits));
}

/* ---- float lanes */
static inline simd_f simd_set1_f(float x) { return _mm_set1_ps(x); }
static inline simd_f simd_zero_f(void) { return _mm_setzero_ps(); }
static inline simd_f simd_add_f(simd_f a, simd_f b) { return _mm_add_ps(a, b); }
static inline simd_f simd_sub_f(simd_f a, simd_f b) { return _mm_sub_ps(a, b); }
static inline simd_f simd_mul_f(simd_f a, simd_f b) { return _mm_mul_ps(a, b); }
static inline simd_f simd_div_f(simd_f a, simd_f b) { return _mm_div_ps(a, b); }
static inline simd_f simd_min_f(simd_f a, simd_f b) { return _mm_min_ps(a, b); }
static inline simd_f simd_max_f(simd_f a, simd_f b) { return _mm_max_ps(a, b); }
static inline simd_f simd_sqrt_f(simd_f a) { return _mm_sqrt_ps(a); }
static inline simd_f simd_floor_f(simd_f a)
{
    float v[4];
    _mm_storeu_ps(v, a);
    for (int l = 0; l < 4; l++) v[l] = floorf(v[l]);
    return _mm_loadu_ps(v);
}
static inline simd_f simd_ceil_f(simd_f a)
{
    float v[4];
    _mm_storeu_ps(v, a);
    for (int l = 0; l < 4; l++) v[l] = ceilf(v[l]);
    return _mm_loadu_ps(v);
}
static inline simd_mask simd_gt_f(simd_f a, simd_f b) { return _mm_cmpgt_ps(a, b); }
static inline simd_mask simd_ge_f(simd_f a, simd_f b) { return _mm_cmpge_ps(a, b); }
static inline simd_mask simd_lt_f(simd_f a, simd_f b) { return _mm_cmplt_ps(a, b); }
static inline simd_mask simd_le_f(simd_f a, simd_f b) { return _mm_cmple_ps(a, b); }
static inline simd_f simd_select_f(simd_mask m, simd_f a, simd_f b)
{
    return _mm_or_ps(_mm_and_ps(m, a), _mm_andnot_ps(m, b));
}
static inline float simd_hmin_f(simd_f a)
{
    a = _mm_min_ps(a, _mm_movehl_ps(a, a));
    a = _mm_min_ss(a, _mm_shuffle_ps(a, a, 1));
    return _mm_cvtss_f32(a);
}

static inline simd_f simd_abs_f(simd_f a) { return _mm_andnot_ps(_mm_set1_ps(-0.0f), a); }
static inline simd_f simd_neg_f(simd_f a) { return _mm_xor_ps(a, _mm_set1_ps(-0.0f)); }
static inline simd_mask simd_eq_f(simd_f a, simd_f b) { return _mm_cmpeq_ps(a, b); }

/* ---- float memory (SSE2 has no masked loads: lane by lane) */
static inline simd_f simd_load_f(const float *p) { return _mm_load_ps(p); }
static inline simd_f simd_loadu_f(const float *p) { return _mm_loadu_ps(p); }
/* p aligned to the vector (SIMD_W * 4 bytes) */
static inline void simd_store_f(float *p, simd_f a) { _mm_store_ps(p, a); }
static inline void simd_storeu_f(float *p, simd_f a) { _mm_storeu_ps(p, a); }
static inline simd_f simd_maskz_loadu_f(const float *p, simd_mask m)
{
    float v[4];
    unsigned b = (unsigned)_mm_movemask_ps(m);
    for (int l = 0; l < 4; l++) v[l] = b >> l & 1 ? p[l] : 0.0f;
    return _mm_loadu_ps(v);
}
static inline void simd_mask_storeu_f(float *p, simd_mask m, simd_f a)
{
    float v[4];
    _mm_storeu_ps(v, a);
    unsigned b = (unsigned)_mm_movemask_ps(m);
    for (int l = 0; l < 4; l++)
        if (b >> l & 1) p[l] = v[l];
}
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
static inline simd_f simd_set_rows8_f(const float *r) { return _mm_set1_ps(r[0]); }
static inline simd_f simd_spread4_f(const float *r) { return _mm_set1_ps(r[0]); }

/* ---- int32 lanes */
static inline simd_i simd_set1_i(int32_t x) { return _mm_set1_epi32(x); }
static inline simd_i simd_iota_i(void) { return _mm_setr_epi32(0, 1, 2, 3); }
static inline simd_i simd_add_i(simd_i a, simd_i b) { return _mm_add_epi32(a, b); }
static inline simd_i simd_sub_i(simd_i a, simd_i b) { return _mm_sub_epi32(a, b); }
static inline simd_i simd_mullo_i(simd_i a, simd_i b)
{
    uint32_t x[4], y[4];
    _mm_storeu_si128((__m128i *)x, a);
    _mm_storeu_si128((__m128i *)y, b);
    for (int l = 0; l < 4; l++) x[l] *= y[l];
    return _mm_loadu_si128((const __m128i *)x);
}
static inline simd_i simd_and_i(simd_i a, simd_i b) { return _mm_and_si128(a, b); }
static inline simd_i simd_or_i(simd_i a, simd_i b) { return _mm_or_si128(a, b); }
static inline simd_i simd_srli_i(simd_i a, int n) { return _mm_srli_epi32(a, n); }
static inline simd_mask simd_eq_i(simd_i a, simd_i b) { return _mm_castsi128_ps(_mm_cmpeq_epi32(a, b)); }
static inline simd_mask simd_gt_i(simd_i a, simd_i b) { return _mm_castsi128_ps(_mm_cmpgt_epi32(a, b)); }
static inline simd_mask simd_negative_i(simd_i a) { return _mm_castsi128_ps(_mm_srai_epi32(a, 31)); }
static inline simd_f simd_i2f(simd_i a) { return _mm_cvtepi32_ps(a); }
static inline simd_f simd_asfloat_i(simd_i a) { return _mm_castsi128_ps(a); }
static inline simd_i simd_f2i_trunc(simd_f a) { return _mm_cvttps_epi32(a); }
static inline simd_i simd_load_i(const int32_t *p) { return _mm_load_si128((const __m128i *)p); }
static inline simd_i simd_maskz_loadu_i(const int32_t *p, simd_mask m)
{
    unsigned b = (unsigned)_mm_movemask_ps(m);
    int32_t v[4];
    for (int l = 0; l < 4; l++) v[l] = b >> l & 1 ? p[l] : 0;
    return _mm_loadu_si128((const __m128i *)v);
}
static inline simd_i simd_loadu_i(const int32_t *p) { return _mm_loadu_si128((const __m128i *)p); }
/* p aligned to the vector (SIMD_W * 4 bytes) */
static inline void simd_store_i(int32_t *p, simd_i a) { _mm_store_si128((__m128i *)p, a); }
static inline void simd_storeu_i(int32_t *p, simd_i a) { _mm_storeu_si128((__m128i *)p, a); }
static inline void simd_mask_storeu_i(int32_t *p, simd_mask m, simd_i a)
{
    int32_t v[4];
    _mm_storeu_si128((__m128i *)v, a);
    unsigned b = (unsigned)_mm_movemask_ps(m);
    for (int l = 0; l < 4; l++)
        if (b >> l & 1) p[l] = v[l];
}
static inline void simd_mask_storeu_rows8_i(int32_t *p, size_t stride, simd_mask m, simd_i a)
{
    (void)stride;
    simd_mask_storeu_i(p, m, a);
}
static inline void simd_stream_i(int32_t *p, simd_i a) { _mm_stream_si128((__m128i *)p, a); }
static inline void simd_stream_fence(void) { _mm_sfence(); }

static inline simd_i simd_select_i(simd_mask m, simd_i a, simd_i b)
{
    __m128i k = _mm_castps_si128(m);
    return _mm_or_si128(_mm_and_si128(k, a), _mm_andnot_si128(k, b));
}
static inline int simd_compress_storeu_f(float *p, simd_mask m, simd_f a)
{
    float v[4];
    _mm_storeu_ps(v, a);
    int n = 0;
    for (unsigned b = (unsigned)_mm_movemask_ps(m); b; b &= b - 1) p[n++] = v[__builtin_ctz(b)];
    return n;
}
static inline int simd_compress_storeu_i(int32_t *p, simd_mask m, simd_i a)
{
    int32_t v[4];
    _mm_storeu_si128((__m128i *)v, a);
    int n = 0;
    for (unsigned b = (unsigned)_mm_movemask_ps(m); b; b &= b - 1) p[n++] = v[__builtin_ctz(b)];
    return n;
}
typedef simd_mask simd_pack; /* simd_pack_make: see simd_scalar.h */
static inline simd_pack simd_pack_make(simd_mask m) { return m; }
static inline void simd_pack_storeu_f(float *p, simd_pack k, simd_f a) { (void)simd_compress_storeu_f(p, k, a); }
static inline void simd_pack_storeu_i(int32_t *p, simd_pack k, simd_i a) { (void)simd_compress_storeu_i(p, k, a); }
static inline simd_i simd_gather_u16(const uint16_t *base, simd_i idx)
{
    int32_t i[4], r[4];
    _mm_storeu_si128((__m128i *)i, idx);
    for (int l = 0; l < 4; l++) r[l] = base[i[l]];
    return _mm_loadu_si128((const __m128i *)r);
}

static inline simd_i simd_min_i(simd_i a, simd_i b)
{
    __m128i lt = _mm_cmplt_epi32(a, b);
    return _mm_or_si128(_mm_and_si128(lt, a), _mm_andnot_si128(lt, b));
}
static inline simd_i simd_max_i(simd_i a, simd_i b)
{
    __m128i gt = _mm_cmpgt_epi32(a, b);
    return _mm_or_si128(_mm_and_si128(gt, a), _mm_andnot_si128(gt, b));
}
static inline simd_i simd_slli_i(simd_i a, int n) { return _mm_slli_epi32(a, n); }
static inline int32_t simd_lane0_i(simd_i a) { return _mm_cvtsi128_si32(a); }
static inline simd_f simd_gather_f(const float *base, simd_i idx)
{
    int32_t i[4];
    _mm_storeu_si128((__m128i *)i, idx);
    return _mm_setr_ps(base[i[0]], base[i[1]], base[i[2]], base[i[3]]);
}
/* The SIMD_W triples at p (3 SIMD_W floats: x0 y0 z0 x1 y1 z1 ...) as three
 * vectors of their first, second and third members (data movement only). */
static inline void simd_load3_f(const float *p, simd_f *a, simd_f *b, simd_f *c)
{
    *a = _mm_setr_ps(p[0], p[3], p[6], p[9]);
    *b = _mm_setr_ps(p[1], p[4], p[7], p[10]);
    *c = _mm_setr_ps(p[2], p[5], p[8], p[11]);
}
static inline simd_f simd_maskz_gather_f(const float *base, simd_i idx, simd_mask m)
{
    int32_t i[4];
    float v[4];
    _mm_storeu_si128((__m128i *)i, idx);
    unsigned b = (unsigned)_mm_movemask_ps(m);
    for (int l = 0; l < 4; l++) v[l] = b >> l & 1 ? base[i[l]] : 0.0f;
    return _mm_loadu_ps(v);
}
static inline void simd_gather4_f(const float *base, simd_i idx, simd_f out[4])
{
    int32_t i[4];
    _mm_storeu_si128((__m128i *)i, idx);
    __m128 r0 = _mm_loadu_ps(base + i[0]), r1 = _mm_loadu_ps(base + i[1]);
    __m128 r2 = _mm_loadu_ps(base + i[2]), r3 = _mm_loadu_ps(base + i[3]);
    _MM_TRANSPOSE4_PS(r0, r1, r2, r3);
    out[0] = r0, out[1] = r1, out[2] = r2, out[3] = r3;
}

static inline simd_i simd_load_rows4_i(const int32_t *p, size_t stride)
{
    (void)stride;
    return _mm_loadu_si128((const __m128i *)p);
}
static inline void simd_store_rows4_f(float *p, size_t stride, simd_f a)
{
    (void)stride;
    _mm_storeu_ps(p, a);
}
static inline simd_f simd_tile4_f(const float *p) { return _mm_loadu_ps(p); }

static inline simd_f simd_permute_f(simd_f a, simd_i idx)
{
    float v[4], r[4];
    int32_t i[4];
    _mm_storeu_ps(v, a);
    _mm_storeu_si128((__m128i *)i, idx);
    for (int l = 0; l < 4; l++) r[l] = v[i[l] & 3];
    return _mm_loadu_ps(r);
}
static inline simd_i simd_permute_i(simd_i a, simd_i idx)
{
    int32_t v[4], r[4], i[4];
    _mm_storeu_si128((__m128i *)v, a);
    _mm_storeu_si128((__m128i *)i, idx);
    for (int l = 0; l < 4; l++) r[l] = v[i[l] & 3];
    return _mm_loadu_si128((const __m128i *)r);
}

/* ---- int64 lanes */
static inline simd_l simd_set1_l(int64_t x) { return _mm_set1_epi64x(x); }
static inline simd_l simd_ramp_l(int64_t base, int64_t step)
{
    return _mm_add_epi64(_mm_set1_epi64x(base), _mm_set_epi64x(step, 0));
}
static inline simd_l simd_or_l(simd_l a, simd_l b) { return _mm_or_si128(a, b); }
static inline uint32_t simd_negative_l(simd_l a) { return (uint32_t)_mm_movemask_pd(_mm_castsi128_pd(a)); }

static inline void simd_zeroupper(void) {}

/* ---- masks */
static inline simd_mask simd_mask_and(simd_mask a, simd_mask b) { return _mm_and_ps(a, b); }
static inline simd_mask simd_mask_or(simd_mask a, simd_mask b) { return _mm_or_ps(a, b); }
static inline simd_mask simd_mask_andnot(simd_mask a, simd_mask b) { return _mm_andnot_ps(b, a); }
static inline simd_mask simd_mask_not(simd_mask a) { return _mm_xor_ps(a, _mm_castsi128_ps(_mm_set1_epi32(-1))); }
static inline uint32_t simd_mask_bits(simd_mask m) { return (uint32_t)_mm_movemask_ps(m); }
static inline int simd_mask_any(simd_mask m) { return _mm_movemask_ps(m) != 0; }
static inline int simd_mask_count(simd_mask m) { return __builtin_popcount((unsigned)_mm_movemask_ps(m)); }

#endif
