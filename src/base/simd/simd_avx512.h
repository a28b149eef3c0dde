/* simd_avx512.h: the SIMD vocabulary on AVX-512 (F, DQ, BW, VL), 16 lanes
 * (see simd.h; the meaning of every operation is the plain C of
 * simd_scalar.h). Masks are the mask registers' bits. */
#ifndef SIMD_AVX512_H
#define SIMD_AVX512_H

#include <immintrin.h>
#include <stddef.h>
#include <stdint.h>

#define SIMD_NAME "avx512"
#define SIMD_W 16 /* 32-bit lanes */
#define SIMD_WL 8 /* 64-bit lanes */
#define SIMD_FULL 0xffffu

typedef __m512 simd_f;
typedef __m512i simd_i;
typedef __m512i simd_l;
typedef __mmask16 simd_mask;

/* ---- float lanes */
static inline simd_f simd_set1_f(float x) { return _mm512_set1_ps(x); }
static inline simd_f simd_zero_f(void) { return _mm512_setzero_ps(); }
static inline simd_f simd_add_f(simd_f a, simd_f b) { return _mm512_add_ps(a, b); }
static inline simd_f simd_sub_f(simd_f a, simd_f b) { return _mm512_sub_ps(a, b); }
static inline simd_f simd_mul_f(simd_f a, simd_f b) { return _mm512_mul_ps(a, b); }
static inline simd_f simd_div_f(simd_f a, simd_f b) { return _mm512_div_ps(a, b); }
static inline simd_f simd_min_f(simd_f a, simd_f b) { return _mm512_min_ps(a, b); }
static inline simd_f simd_max_f(simd_f a, simd_f b) { return _mm512_max_ps(a, b); }
static inline simd_f simd_sqrt_f(simd_f a) { return _mm512_sqrt_ps(a); }
static inline simd_f simd_floor_f(simd_f a) { return _mm512_roundscale_ps(a, _MM_FROUND_TO_NEG_INF | _MM_FROUND_NO_EXC); }
static inline simd_f simd_ceil_f(simd_f a) { return _mm512_roundscale_ps(a, _MM_FROUND_TO_POS_INF | _MM_FROUND_NO_EXC); }
static inline simd_mask simd_gt_f(simd_f a, simd_f b) { return _mm512_cmp_ps_mask(a, b, _CMP_GT_OQ); }
static inline simd_mask simd_ge_f(simd_f a, simd_f b) { return _mm512_cmp_ps_mask(a, b, _CMP_GE_OQ); }
static inline simd_mask simd_lt_f(simd_f a, simd_f b) { return _mm512_cmp_ps_mask(a, b, _CMP_LT_OQ); }
static inline simd_mask simd_le_f(simd_f a, simd_f b) { return _mm512_cmp_ps_mask(a, b, _CMP_LE_OQ); }
static inline simd_f simd_select_f(simd_mask m, simd_f a, simd_f b) { return _mm512_mask_blend_ps((__mmask16)m, b, a); }
static inline float simd_hmin_f(simd_f a)
{
    __m256 h = _mm256_min_ps(_mm512_castps512_ps256(a), _mm512_extractf32x8_ps(a, 1));
    __m128 m = _mm_min_ps(_mm256_castps256_ps128(h), _mm256_extractf128_ps(h, 1));
    m = _mm_min_ps(m, _mm_movehl_ps(m, m));
    m = _mm_min_ss(m, _mm_shuffle_ps(m, m, 1));
    return _mm_cvtss_f32(m);
}

static inline simd_f simd_abs_f(simd_f a) { return _mm512_abs_ps(a); }
static inline simd_f simd_neg_f(simd_f a)
{
    return _mm512_castsi512_ps(_mm512_xor_si512(_mm512_castps_si512(a), _mm512_set1_epi32((int)0x80000000u)));
}
static inline simd_mask simd_eq_f(simd_f a, simd_f b) { return _mm512_cmp_ps_mask(a, b, _CMP_EQ_OQ); }

/* ---- float memory */
static inline simd_f simd_load_f(const float *p) { return _mm512_load_ps(p); }
static inline simd_f simd_loadu_f(const float *p) { return _mm512_loadu_ps(p); }
/* p aligned to the vector (SIMD_W * 4 bytes) */
static inline void simd_store_f(float *p, simd_f a) { _mm512_store_ps(p, a); }
static inline void simd_storeu_f(float *p, simd_f a) { _mm512_storeu_ps(p, a); }
static inline simd_f simd_maskz_loadu_f(const float *p, simd_mask m) { return _mm512_maskz_loadu_ps((__mmask16)m, p); }
static inline void simd_mask_storeu_f(float *p, simd_mask m, simd_f a) { _mm512_mask_storeu_ps(p, (__mmask16)m, a); }
/* two rows of 8: lanes 0-7 at p, lanes 8-15 at p + stride */
static inline simd_f simd_maskz_loadu_rows8_f(const float *p, size_t stride, simd_mask m)
{
    __m256 r0 = _mm256_maskz_loadu_ps((__mmask8)m, p);
    __m256 r1 = _mm256_maskz_loadu_ps((__mmask8)(m >> 8), p + stride);
    return _mm512_insertf32x8(_mm512_castps256_ps512(r0), r1, 1);
}
static inline void simd_mask_storeu_rows8_f(float *p, size_t stride, simd_mask m, simd_f a)
{
    _mm256_mask_storeu_ps(p, (__mmask8)m, _mm512_castps512_ps256(a));
    _mm256_mask_storeu_ps(p + stride, (__mmask8)(m >> 8), _mm512_extractf32x8_ps(a, 1));
}
static inline simd_f simd_set_rows8_f(const float *r)
{
    return _mm512_insertf32x8(_mm512_castps256_ps512(_mm256_set1_ps(r[0])), _mm256_set1_ps(r[1]), 1);
}
static inline simd_f simd_spread4_f(const float *r)
{
    return _mm512_permutexvar_ps(_mm512_setr_epi32(0, 0, 0, 0, 1, 1, 1, 1, 2, 2, 2, 2, 3, 3, 3, 3),
                                 _mm512_castps128_ps512(_mm_loadu_ps(r)));
}

/* ---- int32 lanes */
static inline simd_i simd_set1_i(int32_t x) { return _mm512_set1_epi32(x); }
static inline simd_i simd_iota_i(void) { return _mm512_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15); }
static inline simd_i simd_add_i(simd_i a, simd_i b) { return _mm512_add_epi32(a, b); }
static inline simd_i simd_sub_i(simd_i a, simd_i b) { return _mm512_sub_epi32(a, b); }
static inline simd_i simd_mullo_i(simd_i a, simd_i b) { return _mm512_mullo_epi32(a, b); }
static inline simd_i simd_and_i(simd_i a, simd_i b) { return _mm512_and_si512(a, b); }
static inline simd_i simd_or_i(simd_i a, simd_i b) { return _mm512_or_si512(a, b); }
static inline simd_i simd_srli_i(simd_i a, int n) { return _mm512_srli_epi32(a, (unsigned)n); }
static inline simd_mask simd_eq_i(simd_i a, simd_i b) { return _mm512_cmpeq_epi32_mask(a, b); }
static inline simd_mask simd_gt_i(simd_i a, simd_i b) { return _mm512_cmpgt_epi32_mask(a, b); }
static inline simd_mask simd_negative_i(simd_i a) { return _mm512_movepi32_mask(a); }
static inline simd_f simd_i2f(simd_i a) { return _mm512_cvtepi32_ps(a); }
static inline simd_f simd_asfloat_i(simd_i a) { return _mm512_castsi512_ps(a); }
static inline simd_i simd_f2i_trunc(simd_f a) { return _mm512_cvttps_epi32(a); }
static inline simd_i simd_load_i(const int32_t *p) { return _mm512_load_si512(p); }
static inline simd_i simd_maskz_loadu_i(const int32_t *p, simd_mask m)
{
    return _mm512_maskz_loadu_epi32((__mmask16)m, p);
}
static inline simd_i simd_loadu_i(const int32_t *p) { return _mm512_loadu_si512(p); }
/* p aligned to the vector (SIMD_W * 4 bytes) */
static inline void simd_store_i(int32_t *p, simd_i a) { _mm512_store_si512(p, a); }
static inline void simd_storeu_i(int32_t *p, simd_i a) { _mm512_storeu_si512(p, a); }
static inline void simd_mask_storeu_i(int32_t *p, simd_mask m, simd_i a) { _mm512_mask_storeu_epi32(p, (__mmask16)m, a); }
static inline void simd_mask_storeu_rows8_i(int32_t *p, size_t stride, simd_mask m, simd_i a)
{
    _mm256_mask_storeu_epi32(p, (__mmask8)m, _mm512_castsi512_si256(a));
    _mm256_mask_storeu_epi32(p + stride, (__mmask8)(m >> 8), _mm512_extracti32x8_epi32(a, 1));
}
static inline void simd_stream_i(int32_t *p, simd_i a) { _mm512_stream_si512((void *)p, a); }
static inline void simd_stream_fence(void) { _mm_sfence(); }

static inline simd_i simd_select_i(simd_mask m, simd_i a, simd_i b) { return _mm512_mask_blend_epi32((__mmask16)m, b, a); }
/* Compress in a register, then a masked store of the first n lanes: the
 * same bytes as vcompressps/vpcompressd with a memory operand, which AMD's
 * Zen 4 runs microcoded at a fraction of the speed (the paraboloid front
 * end's 25 compress-stores per 16 triangles: a 128x128 map took 1.55 ms on
 * Sibenik with them and 1.01 ms with this, docs/perf.md). */
static inline int simd_compress_storeu_f(float *p, simd_mask m, simd_f a)
{
    int n = __builtin_popcount(m);
    _mm512_mask_storeu_ps(p, (__mmask16)((1u << n) - 1u), _mm512_maskz_compress_ps(m, a));
    return n;
}
static inline int simd_compress_storeu_i(int32_t *p, simd_mask m, simd_i a)
{
    int n = __builtin_popcount(m);
    _mm512_mask_storeu_epi32(p, (__mmask16)((1u << n) - 1u), _mm512_maskz_compress_epi32(m, a));
    return n;
}
typedef simd_mask simd_pack; /* simd_pack_make: see simd_scalar.h; the compress above */
static inline simd_pack simd_pack_make(simd_mask m) { return m; }
static inline void simd_pack_storeu_f(float *p, simd_pack k, simd_f a) { (void)simd_compress_storeu_f(p, k, a); }
static inline void simd_pack_storeu_i(int32_t *p, simd_pack k, simd_i a) { (void)simd_compress_storeu_i(p, k, a); }
static inline simd_i simd_gather_u16(const uint16_t *base, simd_i idx)
{
    return _mm512_and_si512(_mm512_i32gather_epi32(idx, (const void *)base, 2), _mm512_set1_epi32(0xffff));
}

static inline simd_i simd_min_i(simd_i a, simd_i b) { return _mm512_min_epi32(a, b); }
static inline simd_i simd_max_i(simd_i a, simd_i b) { return _mm512_max_epi32(a, b); }
static inline simd_i simd_slli_i(simd_i a, int n) { return _mm512_slli_epi32(a, (unsigned)n); }
static inline int32_t simd_lane0_i(simd_i a) { return _mm_cvtsi128_si32(_mm512_castsi512_si128(a)); }
static inline simd_f simd_gather_f(const float *base, simd_i idx) { return _mm512_i32gather_ps(idx, base, 4); }
static inline simd_f simd_maskz_gather_f(const float *base, simd_i idx, simd_mask m)
{
    return _mm512_mask_i32gather_ps(_mm512_setzero_ps(), (__mmask16)m, idx, base, 4);
}
/* lane l's four floats: row l & 3 of the 4x4 transposed in 128-bit block
 * l >> 2 (rows q, q + 4, q + 8, q + 12 share a register) */
static inline void simd_gather4_f(const float *base, simd_i idx, simd_f out[4])
{
    int32_t i[16];
    _mm512_storeu_si512((void *)i, idx);
    __m512 r[4];
    for (int q = 0; q < 4; q++) {
        __m512 v = _mm512_castps128_ps512(_mm_loadu_ps(base + i[q]));
        v = _mm512_insertf32x4(v, _mm_loadu_ps(base + i[q + 4]), 1);
        v = _mm512_insertf32x4(v, _mm_loadu_ps(base + i[q + 8]), 2);
        r[q] = _mm512_insertf32x4(v, _mm_loadu_ps(base + i[q + 12]), 3);
    }
    __m512 t0 = _mm512_unpacklo_ps(r[0], r[1]), t1 = _mm512_unpackhi_ps(r[0], r[1]);
    __m512 t2 = _mm512_unpacklo_ps(r[2], r[3]), t3 = _mm512_unpackhi_ps(r[2], r[3]);
    out[0] = _mm512_shuffle_ps(t0, t2, 0x44), out[1] = _mm512_shuffle_ps(t0, t2, 0xee);
    out[2] = _mm512_shuffle_ps(t1, t3, 0x44), out[3] = _mm512_shuffle_ps(t1, t3, 0xee);
}
/* The SIMD_W triples at p (3 SIMD_W floats: x0 y0 z0 x1 y1 z1 ...) as three
 * vectors of their first, second and third members (data movement only). */
static inline void simd_load3_f(const float *p, simd_f *a, simd_f *b, simd_f *c)
{
    /* member m of lane k is float 3 k + m of the 48: a two-source permute of
     * the first two vectors gives the lanes whose float lies there, a second
     * one takes the rest from the third (index 16 + j selects its float j) */
    const __m512 e0 = _mm512_loadu_ps(p), e1 = _mm512_loadu_ps(p + 16), e2 = _mm512_loadu_ps(p + 32);
    const __m512i lane = _mm512_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15);
    const __m512i k3 = _mm512_mullo_epi32(lane, _mm512_set1_epi32(3));
    simd_f *out[3] = {a, b, c};
    for (int m = 0; m < 3; m++) {
        __m512i idx = _mm512_add_epi32(k3, _mm512_set1_epi32(m)); /* 3 k + m, 0..47 */
        __mmask16 in01 = _mm512_cmplt_epi32_mask(idx, _mm512_set1_epi32(32));
        __m512 t = _mm512_permutex2var_ps(e0, _mm512_and_si512(idx, _mm512_set1_epi32(31)), e1);
        __m512i sel = _mm512_mask_mov_epi32(_mm512_sub_epi32(idx, _mm512_set1_epi32(16)), in01, lane);
        *out[m] = _mm512_permutex2var_ps(t, sel, e2);
    }
}

static inline simd_i simd_load_rows4_i(const int32_t *p, size_t stride)
{
    __m512i r = _mm512_castsi128_si512(_mm_loadu_si128((const __m128i *)p));
    r = _mm512_inserti32x4(r, _mm_loadu_si128((const __m128i *)(p + stride)), 1);
    r = _mm512_inserti32x4(r, _mm_loadu_si128((const __m128i *)(p + 2 * stride)), 2);
    return _mm512_inserti32x4(r, _mm_loadu_si128((const __m128i *)(p + 3 * stride)), 3);
}
static inline void simd_store_rows4_f(float *p, size_t stride, simd_f a)
{
    _mm_storeu_ps(p, _mm512_castps512_ps128(a));
    _mm_storeu_ps(p + stride, _mm512_extractf32x4_ps(a, 1));
    _mm_storeu_ps(p + 2 * stride, _mm512_extractf32x4_ps(a, 2));
    _mm_storeu_ps(p + 3 * stride, _mm512_extractf32x4_ps(a, 3));
}
static inline simd_f simd_tile4_f(const float *p) { return _mm512_broadcast_f32x4(_mm_loadu_ps(p)); }

static inline simd_f simd_permute_f(simd_f a, simd_i idx) { return _mm512_permutexvar_ps(idx, a); }
static inline simd_i simd_permute_i(simd_i a, simd_i idx) { return _mm512_permutexvar_epi32(idx, a); }

/* ---- int64 lanes */
static inline simd_l simd_set1_l(int64_t x) { return _mm512_set1_epi64(x); }
static inline simd_l simd_ramp_l(int64_t base, int64_t step)
{
    return _mm512_add_epi64(_mm512_set1_epi64(base),
                            _mm512_mullo_epi64(_mm512_setr_epi64(0, 1, 2, 3, 4, 5, 6, 7), _mm512_set1_epi64(step)));
}
static inline simd_l simd_or_l(simd_l a, simd_l b) { return _mm512_or_si512(a, b); }
static inline uint32_t simd_negative_l(simd_l a) { return _mm512_movepi64_mask(a); }

static inline void simd_zeroupper(void) { _mm256_zeroupper(); }

/* ---- masks */
static inline simd_mask simd_mask_and(simd_mask a, simd_mask b) { return (simd_mask)(a & b); }
static inline simd_mask simd_mask_or(simd_mask a, simd_mask b) { return (simd_mask)(a | b); }
static inline simd_mask simd_mask_andnot(simd_mask a, simd_mask b) { return (simd_mask)(a & ~b); }
static inline simd_mask simd_mask_not(simd_mask a) { return (simd_mask)~a; }
static inline uint32_t simd_mask_bits(simd_mask m) { return m; }
static inline simd_mask simd_mask_from_bits(uint32_t b) { return (simd_mask)b; }
static inline int simd_mask_any(simd_mask m) { return m != 0; }
static inline int simd_mask_count(simd_mask m) { return __builtin_popcount(m); }

#endif
