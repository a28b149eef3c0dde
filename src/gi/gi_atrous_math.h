/* gi_atrous_math: the a-trous filter's scalar arithmetic (gi_atrous.h), the
 * definition the SIMD kernels (gi_indirect_kernels.c) repeat operation for
 * operation so every path gives the same bits. */
#ifndef GI_ATROUS_MATH_H
#define GI_ATROUS_MATH_H

#include <math.h>
#include <stdint.h>
#include <string.h>

/* Rec. 709 luminance, summed in this order */
#define GI_ATROUS_LR 0.2126f
#define GI_ATROUS_LG 0.7152f
#define GI_ATROUS_LB 0.0722f
#define GI_ATROUS_EPS 1e-10f
#define GI_ATROUS_LOG2E 1.44269504088896f
/* 2^-f on [0, 1) = 1 + f (C1 + f (C2 + ...)): a least-squares fit at
 * Chebyshev nodes, relative error 1.2e-7 */
#define GI_ATROUS_C1 (-0.6931443f)
#define GI_ATROUS_C2 0.24018562f
#define GI_ATROUS_C3 (-0.05531363f)
#define GI_ATROUS_C4 0.00922489f
#define GI_ATROUS_C5 (-0.00095265f)

static inline float gi_atrous_lum(float r, float g, float b)
{
    return GI_ATROUS_LR * r + GI_ATROUS_LG * g + GI_ATROUS_LB * b;
}

/* exp(-t) for t >= 0 without libm (whose last bit the SIMD paths could not
 * repeat): 2^-(n + f) = 2^-n 2^-f, n = floor(t log2 e) up to 125. */
static inline float gi_atrous_expneg(float t)
{
    float y = t * GI_ATROUS_LOG2E;
    y = y < 125.0f ? y : 125.0f;
    float n = floorf(y), f = y - n;
    float p = ((((GI_ATROUS_C5 * f + GI_ATROUS_C4) * f + GI_ATROUS_C3) * f + GI_ATROUS_C2) * f + GI_ATROUS_C1) * f + 1.0f;
    int32_t bits = (127 - (int32_t)n) * (1 << 23);
    float scale;
    memcpy(&scale, &bits, sizeof scale);
    return p * scale;
}

/* max(0, c)^128 by seven squarings (SVGF's sigma_n = 128). */
static inline float gi_atrous_pow128(float c)
{
    c = c > 0.0f ? c : 0.0f;
    for (int k = 0; k < 7; k++) c = c * c;
    return c;
}

/* The B3-spline's 3-tap sibling (1, 2, 1) / 4 in each direction. */
static const float gi_atrous_h[3] = {0.25f, 0.5f, 0.25f};

#endif
