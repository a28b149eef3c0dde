/* simd_avx2.h: the SIMD vocabulary on AVX2, 8 lanes (see simd.h; the
 * meaning of every operation is the plain C of simd_scalar.h). Compiled
 * with -mavx2 only: no FMA. A mask is a vector whose lane l is set iff its
 * sign bit is (the other bits may be anything): every instruction that
 * takes a mask here reads only sign bits (blendvps, vmaskmov, vgatherdps,
 * movmskps), so compares, sign tests and bits all serve without
 * conversion; simd_mask_from_bits is the one place the bits-to-lanes idiom
 * is written. */
#ifndef SIMD_AVX2_H
#define SIMD_AVX2_H

#include <immintrin.h>
#include <stddef.h>
#include <stdint.h>

#define SIMD_NAME "avx2"
#define SIMD_W 8  /* 32-bit lanes */
#define SIMD_WL 4 /* 64-bit lanes */
#define SIMD_FULL 0xffu

typedef __m256 simd_f;
typedef __m256i simd_i;
typedef __m256i simd_l;
typedef __m256 simd_mask; /* lane l set iff its sign bit is */

/* bit l of b -> the sign bit of lane l */
static inline simd_mask simd_mask_from_bits(uint32_t b)
{
    return _mm256_castsi256_ps(
        _mm256_sllv_epi32(_mm256_set1_epi32((int)b), _mm256_setr_epi32(31, 30, 29, 28, 27, 26, 25, 24)));
}

/* ---- float lanes */
static inline simd_f simd_set1_f(float x) { return _mm256_set1_ps(x); }
static inline simd_f simd_zero_f(void) { return _mm256_setzero_ps(); }
static inline simd_f simd_add_f(simd_f a, simd_f b) { return _mm256_add_ps(a, b); }
static inline simd_f simd_sub_f(simd_f a, simd_f b) { return _mm256_sub_ps(a, b); }
static inline simd_f simd_mul_f(simd_f a, simd_f b) { return _mm256_mul_ps(a, b); }
static inline simd_f simd_div_f(simd_f a, simd_f b) { return _mm256_div_ps(a, b); }
static inline simd_f simd_min_f(simd_f a, simd_f b) { return _mm256_min_ps(a, b); }
static inline simd_f simd_max_f(simd_f a, simd_f b) { return _mm256_max_ps(a, b); }
static inline simd_f simd_sqrt_f(simd_f a) { return _mm256_sqrt_ps(a); }
static inline simd_f simd_floor_f(simd_f a) { return _mm256_round_ps(a, _MM_FROUND_TO_NEG_INF | _MM_FROUND_NO_EXC); }
static inline simd_f simd_ceil_f(simd_f a) { return _mm256_round_ps(a, _MM_FROUND_TO_POS_INF | _MM_FROUND_NO_EXC); }
static inline simd_mask simd_gt_f(simd_f a, simd_f b) { return _mm256_cmp_ps(a, b, _CMP_GT_OQ); }
static inline simd_mask simd_ge_f(simd_f a, simd_f b) { return _mm256_cmp_ps(a, b, _CMP_GE_OQ); }
static inline simd_mask simd_lt_f(simd_f a, simd_f b) { return _mm256_cmp_ps(a, b, _CMP_LT_OQ); }
static inline simd_mask simd_le_f(simd_f a, simd_f b) { return _mm256_cmp_ps(a, b, _CMP_LE_OQ); }
static inline simd_f simd_select_f(simd_mask m, simd_f a, simd_f b)
{
    return _mm256_blendv_ps(b, a, m);
}
static inline float simd_hmin_f(simd_f a)
{
    __m128 m = _mm_min_ps(_mm256_castps256_ps128(a), _mm256_extractf128_ps(a, 1));
    m = _mm_min_ps(m, _mm_movehl_ps(m, m));
    m = _mm_min_ss(m, _mm_shuffle_ps(m, m, 1));
    return _mm_cvtss_f32(m);
}

static inline simd_f simd_abs_f(simd_f a) { return _mm256_andnot_ps(_mm256_set1_ps(-0.0f), a); }
static inline simd_f simd_neg_f(simd_f a) { return _mm256_xor_ps(a, _mm256_set1_ps(-0.0f)); }
static inline simd_mask simd_eq_f(simd_f a, simd_f b) { return _mm256_cmp_ps(a, b, _CMP_EQ_OQ); }

/* ---- float memory */
static inline simd_f simd_load_f(const float *p) { return _mm256_load_ps(p); }
static inline simd_f simd_loadu_f(const float *p) { return _mm256_loadu_ps(p); }
/* p aligned to the vector (SIMD_W * 4 bytes) */
static inline void simd_store_f(float *p, simd_f a) { _mm256_store_ps(p, a); }
static inline void simd_storeu_f(float *p, simd_f a) { _mm256_storeu_ps(p, a); }
static inline simd_f simd_maskz_loadu_f(const float *p, simd_mask m) { return _mm256_maskload_ps(p, _mm256_castps_si256(m)); }
static inline void simd_mask_storeu_f(float *p, simd_mask m, simd_f a) { _mm256_maskstore_ps(p, _mm256_castps_si256(m), a); }
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
static inline simd_f simd_set_rows8_f(const float *r) { return _mm256_set1_ps(r[0]); }
static inline simd_f simd_spread4_f(const float *r)
{
    return _mm256_insertf128_ps(_mm256_castps128_ps256(_mm_set1_ps(r[0])), _mm_set1_ps(r[1]), 1);
}

/* ---- int32 lanes */
static inline simd_i simd_set1_i(int32_t x) { return _mm256_set1_epi32(x); }
static inline simd_i simd_iota_i(void) { return _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7); }
static inline simd_i simd_add_i(simd_i a, simd_i b) { return _mm256_add_epi32(a, b); }
static inline simd_i simd_sub_i(simd_i a, simd_i b) { return _mm256_sub_epi32(a, b); }
static inline simd_i simd_mullo_i(simd_i a, simd_i b) { return _mm256_mullo_epi32(a, b); }
static inline simd_i simd_and_i(simd_i a, simd_i b) { return _mm256_and_si256(a, b); }
static inline simd_i simd_or_i(simd_i a, simd_i b) { return _mm256_or_si256(a, b); }
static inline simd_i simd_srli_i(simd_i a, int n) { return _mm256_srli_epi32(a, n); }
static inline simd_mask simd_eq_i(simd_i a, simd_i b) { return _mm256_castsi256_ps(_mm256_cmpeq_epi32(a, b)); }
static inline simd_mask simd_gt_i(simd_i a, simd_i b) { return _mm256_castsi256_ps(_mm256_cmpgt_epi32(a, b)); }
static inline simd_mask simd_negative_i(simd_i a) { return _mm256_castsi256_ps(a); } /* the sign bits themselves */
static inline simd_f simd_i2f(simd_i a) { return _mm256_cvtepi32_ps(a); }
static inline simd_f simd_asfloat_i(simd_i a) { return _mm256_castsi256_ps(a); }
static inline simd_i simd_f2i_trunc(simd_f a) { return _mm256_cvttps_epi32(a); }
static inline simd_i simd_load_i(const int32_t *p) { return _mm256_load_si256((const __m256i *)p); }
static inline simd_i simd_maskz_loadu_i(const int32_t *p, simd_mask m)
{
    return _mm256_maskload_epi32((const int *)p, _mm256_castps_si256(m));
}
static inline simd_i simd_loadu_i(const int32_t *p) { return _mm256_loadu_si256((const __m256i *)p); }
/* p aligned to the vector (SIMD_W * 4 bytes) */
static inline void simd_store_i(int32_t *p, simd_i a) { _mm256_store_si256((__m256i *)p, a); }
static inline void simd_storeu_i(int32_t *p, simd_i a) { _mm256_storeu_si256((__m256i *)p, a); }
static inline void simd_mask_storeu_i(int32_t *p, simd_mask m, simd_i a) { _mm256_maskstore_epi32(p, _mm256_castps_si256(m), a); }
static inline void simd_mask_storeu_rows8_i(int32_t *p, size_t stride, simd_mask m, simd_i a)
{
    (void)stride;
    simd_mask_storeu_i(p, m, a);
}
static inline void simd_stream_i(int32_t *p, simd_i a) { _mm256_stream_si256((__m256i *)p, a); }
static inline void simd_stream_fence(void) { _mm_sfence(); }

static inline simd_i simd_select_i(simd_mask m, simd_i a, simd_i b)
{
    return _mm256_castps_si256(_mm256_blendv_ps(_mm256_castsi256_ps(b), _mm256_castsi256_ps(a), m));
}
/* no compress instruction on AVX2: through memory, lane by lane */
static inline int simd_compress_storeu_f(float *p, simd_mask m, simd_f a)
{
    float v[8];
    _mm256_storeu_ps(v, a);
    int n = 0;
    for (unsigned b = (unsigned)_mm256_movemask_ps(m); b; b &= b - 1) p[n++] = v[__builtin_ctz(b)];
    return n;
}
static inline int simd_compress_storeu_i(int32_t *p, simd_mask m, simd_i a)
{
    int32_t v[8];
    _mm256_storeu_si256((__m256i *)v, a);
    int n = 0;
    for (unsigned b = (unsigned)_mm256_movemask_ps(m); b; b &= b - 1) p[n++] = v[__builtin_ctz(b)];
    return n;
}
/* simd_pack_make (see simd_scalar.h): the permutation that moves the lanes
 * of m to the front in lane order, from a table of 256 entries (entry b:
 * the set lanes of b, one per 4-bit nibble from the lowest); each store is
 * then vpermps and one whole-vector store. On AMD Zen 3 the store-per-lane
 * loop above was a quarter of the paraboloid front end (docs/perf.md,
 * 2026-12-02 evening). */
typedef __m256i simd_pack;
static inline simd_pack simd_pack_make(simd_mask m)
{
    static const uint32_t lanes[256] = {
    0x00000000, 0x00000000, 0x00000001, 0x00000010, 0x00000002, 0x00000020, 0x00000021, 0x00000210,
    0x00000003, 0x00000030, 0x00000031, 0x00000310, 0x00000032, 0x00000320, 0x00000321, 0x00003210,
    0x00000004, 0x00000040, 0x00000041, 0x00000410, 0x00000042, 0x00000420, 0x00000421, 0x00004210,
    0x00000043, 0x00000430, 0x00000431, 0x00004310, 0x00000432, 0x00004320, 0x00004321, 0x00043210,
    0x00000005, 0x00000050, 0x00000051, 0x00000510, 0x00000052, 0x00000520, 0x00000521, 0x00005210,
    0x00000053, 0x00000530, 0x00000531, 0x00005310, 0x00000532, 0x00005320, 0x00005321, 0x00053210,
    0x00000054, 0x00000540, 0x00000541, 0x00005410, 0x00000542, 0x00005420, 0x00005421, 0x00054210,
    0x00000543, 0x00005430, 0x00005431, 0x00054310, 0x00005432, 0x00054320, 0x00054321, 0x00543210,
    0x00000006, 0x00000060, 0x00000061, 0x00000610, 0x00000062, 0x00000620, 0x00000621, 0x00006210,
    0x00000063, 0x00000630, 0x00000631, 0x00006310, 0x00000632, 0x00006320, 0x00006321, 0x00063210,
    0x00000064, 0x00000640, 0x00000641, 0x00006410, 0x00000642, 0x00006420, 0x00006421, 0x00064210,
    0x00000643, 0x00006430, 0x00006431, 0x00064310, 0x00006432, 0x00064320, 0x00064321, 0x00643210,
    0x00000065, 0x00000650, 0x00000651, 0x00006510, 0x00000652, 0x00006520, 0x00006521, 0x00065210,
    0x00000653, 0x00006530, 0x00006531, 0x00065310, 0x00006532, 0x00065320, 0x00065321, 0x00653210,
    0x00000654, 0x00006540, 0x00006541, 0x00065410, 0x00006542, 0x00065420, 0x00065421, 0x00654210,
    0x00006543, 0x00065430, 0x00065431, 0x00654310, 0x00065432, 0x00654320, 0x00654321, 0x06543210,
    0x00000007, 0x00000070, 0x00000071, 0x00000710, 0x00000072, 0x00000720, 0x00000721, 0x00007210,
    0x00000073, 0x00000730, 0x00000731, 0x00007310, 0x00000732, 0x00007320, 0x00007321, 0x00073210,
    0x00000074, 0x00000740, 0x00000741, 0x00007410, 0x00000742, 0x00007420, 0x00007421, 0x00074210,
    0x00000743, 0x00007430, 0x00007431, 0x00074310, 0x00007432, 0x00074320, 0x00074321, 0x00743210,
    0x00000075, 0x00000750, 0x00000751, 0x00007510, 0x00000752, 0x00007520, 0x00007521, 0x00075210,
    0x00000753, 0x00007530, 0x00007531, 0x00075310, 0x00007532, 0x00075320, 0x00075321, 0x00753210,
    0x00000754, 0x00007540, 0x00007541, 0x00075410, 0x00007542, 0x00075420, 0x00075421, 0x00754210,
    0x00007543, 0x00075430, 0x00075431, 0x00754310, 0x00075432, 0x00754320, 0x00754321, 0x07543210,
    0x00000076, 0x00000760, 0x00000761, 0x00007610, 0x00000762, 0x00007620, 0x00007621, 0x00076210,
    0x00000763, 0x00007630, 0x00007631, 0x00076310, 0x00007632, 0x00076320, 0x00076321, 0x00763210,
    0x00000764, 0x00007640, 0x00007641, 0x00076410, 0x00007642, 0x00076420, 0x00076421, 0x00764210,
    0x00007643, 0x00076430, 0x00076431, 0x00764310, 0x00076432, 0x00764320, 0x00764321, 0x07643210,
    0x00000765, 0x00007650, 0x00007651, 0x00076510, 0x00007652, 0x00076520, 0x00076521, 0x00765210,
    0x00007653, 0x00076530, 0x00076531, 0x00765310, 0x00076532, 0x00765320, 0x00765321, 0x07653210,
    0x00007654, 0x00076540, 0x00076541, 0x00765410, 0x00076542, 0x00765420, 0x00765421, 0x07654210,
    0x00076543, 0x00765430, 0x00765431, 0x07654310, 0x00765432, 0x07654320, 0x07654321, 0x76543210,
    };
    const __m256i nib = _mm256_srlv_epi32(_mm256_set1_epi32((int)lanes[_mm256_movemask_ps(m)]),
                                          _mm256_setr_epi32(0, 4, 8, 12, 16, 20, 24, 28));
    return _mm256_and_si256(nib, _mm256_set1_epi32(7));
}
static inline void simd_pack_storeu_f(float *p, simd_pack k, simd_f a)
{
    _mm256_storeu_ps(p, _mm256_permutevar8x32_ps(a, k));
}
static inline void simd_pack_storeu_i(int32_t *p, simd_pack k, simd_i a)
{
    _mm256_storeu_si256((__m256i *)p, _mm256_permutevar8x32_epi32(a, k));
}
/* eight plain loads, not vpgatherdd: on AMD Zen 2 the microcoded gather cost
 * the many-light accumulation (one paraboloid code per pixel-VPL pair)
 * 1-2 ms more at 1024x768 (`bench frame --method iir`, docs/perf.md) */
static inline simd_i simd_gather_u16(const uint16_t *base, simd_i idx)
{
    int32_t i[8];
    _mm256_storeu_si256((__m256i *)i, idx);
    return _mm256_setr_epi32(base[i[0]], base[i[1]], base[i[2]], base[i[3]], base[i[4]], base[i[5]], base[i[6]], base[i[7]]);
}

static inline simd_i simd_min_i(simd_i a, simd_i b) { return _mm256_min_epi32(a, b); }
static inline simd_i simd_max_i(simd_i a, simd_i b) { return _mm256_max_epi32(a, b); }
static inline simd_i simd_slli_i(simd_i a, int n) { return _mm256_slli_epi32(a, n); }
static inline int32_t simd_lane0_i(simd_i a) { return _mm256_cvtsi256_si32(a); }
static inline simd_f simd_gather_f(const float *base, simd_i idx) { return _mm256_i32gather_ps(base, idx, 4); }
static inline simd_f simd_maskz_gather_f(const float *base, simd_i idx, simd_mask m)
{
    return _mm256_mask_i32gather_ps(_mm256_setzero_ps(), base, idx, m, 4);
}
/* lane l's four floats: row l & 3 of the 4x4 transposed in 128-bit half
 * l >> 2 (rows q and q + 4 share a register) */
static inline void simd_gather4_f(const float *base, simd_i idx, simd_f out[4])
{
    int32_t i[8];
    _mm256_storeu_si256((__m256i *)i, idx);
    __m256 r[4];
    for (int q = 0; q < 4; q++)
        r[q] = _mm256_insertf128_ps(_mm256_castps128_ps256(_mm_loadu_ps(base + i[q])), _mm_loadu_ps(base + i[q + 4]), 1);
    __m256 t0 = _mm256_unpacklo_ps(r[0], r[1]), t1 = _mm256_unpackhi_ps(r[0], r[1]);
    __m256 t2 = _mm256_unpacklo_ps(r[2], r[3]), t3 = _mm256_unpackhi_ps(r[2], r[3]);
    out[0] = _mm256_shuffle_ps(t0, t2, 0x44), out[1] = _mm256_shuffle_ps(t0, t2, 0xee);
    out[2] = _mm256_shuffle_ps(t1, t3, 0x44), out[3] = _mm256_shuffle_ps(t1, t3, 0xee);
}
/* The SIMD_W triples at p (3 SIMD_W floats: x0 y0 z0 x1 y1 z1 ...) as three
 * vectors of their first, second and third members (data movement only). */
static inline void simd_load3_f(const float *p, simd_f *a, simd_f *b, simd_f *c)
{
    /* lane k of member m is float 3 k + m of the 24: permutes and blends */
    const __m256 e0 = _mm256_loadu_ps(p), e1 = _mm256_loadu_ps(p + 8), e2 = _mm256_loadu_ps(p + 16);
    *a = _mm256_blend_ps(_mm256_blend_ps(_mm256_permutevar8x32_ps(e0, _mm256_setr_epi32(0, 3, 6, 0, 0, 0, 0, 0)),
                                         _mm256_permutevar8x32_ps(e1, _mm256_setr_epi32(0, 0, 0, 1, 4, 7, 0, 0)), 0x38),
                         _mm256_permutevar8x32_ps(e2, _mm256_setr_epi32(0, 0, 0, 0, 0, 0, 2, 5)), 0xc0);
    *b = _mm256_blend_ps(_mm256_blend_ps(_mm256_permutevar8x32_ps(e0, _mm256_setr_epi32(1, 4, 7, 0, 0, 0, 0, 0)),
                                         _mm256_permutevar8x32_ps(e1, _mm256_setr_epi32(0, 0, 0, 2, 5, 0, 0, 0)), 0x18),
                         _mm256_permutevar8x32_ps(e2, _mm256_setr_epi32(0, 0, 0, 0, 0, 0, 3, 6)), 0xe0);
    *c = _mm256_blend_ps(_mm256_blend_ps(_mm256_permutevar8x32_ps(e0, _mm256_setr_epi32(2, 5, 0, 0, 0, 0, 0, 0)),
                                         _mm256_permutevar8x32_ps(e1, _mm256_setr_epi32(0, 0, 0, 3, 6, 0, 0, 0)), 0x1c),
                         _mm256_permutevar8x32_ps(e2, _mm256_setr_epi32(0, 0, 0, 0, 0, 1, 4, 7)), 0xe0);
}

static inline simd_i simd_load_rows4_i(const int32_t *p, size_t stride)
{
    return _mm256_inserti128_si256(_mm256_castsi128_si256(_mm_loadu_si128((const __m128i *)p)),
                                   _mm_loadu_si128((const __m128i *)(p + stride)), 1);
}
static inline void simd_store_rows4_f(float *p, size_t stride, simd_f a)
{
    _mm_storeu_ps(p, _mm256_castps256_ps128(a));
    _mm_storeu_ps(p + stride, _mm256_extractf128_ps(a, 1));
}
static inline simd_f simd_tile4_f(const float *p) { return _mm256_broadcast_ps((const __m128 *)p); }

static inline simd_f simd_permute_f(simd_f a, simd_i idx) { return _mm256_permutevar8x32_ps(a, idx); }
static inline simd_i simd_permute_i(simd_i a, simd_i idx) { return _mm256_permutevar8x32_epi32(a, idx); }

/* ---- int64 lanes */
static inline simd_l simd_set1_l(int64_t x) { return _mm256_set1_epi64x(x); }
static inline simd_l simd_ramp_l(int64_t base, int64_t step)
{
    return _mm256_add_epi64(_mm256_set1_epi64x(base), _mm256_set_epi64x(3 * step, 2 * step, step, 0));
}
static inline simd_l simd_or_l(simd_l a, simd_l b) { return _mm256_or_si256(a, b); }
static inline uint32_t simd_negative_l(simd_l a) { return (uint32_t)_mm256_movemask_pd(_mm256_castsi256_pd(a)); }

static inline void simd_zeroupper(void) { _mm256_zeroupper(); }

/* ---- masks */
static inline simd_mask simd_mask_and(simd_mask a, simd_mask b) { return _mm256_and_ps(a, b); }
static inline simd_mask simd_mask_or(simd_mask a, simd_mask b) { return _mm256_or_ps(a, b); }
static inline simd_mask simd_mask_andnot(simd_mask a, simd_mask b) { return _mm256_andnot_ps(b, a); }
static inline simd_mask simd_mask_not(simd_mask a) { return _mm256_xor_ps(a, _mm256_castsi256_ps(_mm256_set1_epi32(-1))); }
static inline uint32_t simd_mask_bits(simd_mask m) { return (uint32_t)_mm256_movemask_ps(m); }
static inline int simd_mask_any(simd_mask m) { return _mm256_movemask_ps(m) != 0; }
static inline int simd_mask_count(simd_mask m) { return __builtin_popcount((unsigned)_mm256_movemask_ps(m)); }

#endif
