/* pf_math: the small vector vocabulary every module shares.
 *
 * Conventions: right-handed world space, +Y up (as glTF). Column vectors;
 * pf_mat4 is column-major (m[col*4+row]) like glTF node matrices. All maths is
 * IEEE single precision with -ffp-contract=off, so no compiler-fused
 * multiply-adds change bits between paths or compilers. */
#ifndef PF_MATH_H
#define PF_MATH_H

#include <math.h>
#include <stdint.h>

#define PF_PI 3.14159265358979323846f
#define PF_INV_PI 0.31830988618379067154f

typedef struct pf_vec3 { float x, y, z; } pf_vec3;
typedef struct pf_vec2 { float x, y; } pf_vec2;
typedef struct pf_mat4 { double m[16]; } pf_mat4; /* double: node chains stay exact */

static inline pf_vec3 pf_v3(float x, float y, float z) { pf_vec3 r = {x, y, z}; return r; }
static inline pf_vec3 pf_v3_add(pf_vec3 a, pf_vec3 b) { return pf_v3(a.x + b.x, a.y + b.y, a.z + b.z); }
static inline pf_vec3 pf_v3_sub(pf_vec3 a, pf_vec3 b) { return pf_v3(a.x - b.x, a.y - b.y, a.z - b.z); }
static inline pf_vec3 pf_v3_mul(pf_vec3 a, pf_vec3 b) { return pf_v3(a.x * b.x, a.y * b.y, a.z * b.z); }
static inline pf_vec3 pf_v3_scale(pf_vec3 a, float s) { return pf_v3(a.x * s, a.y * s, a.z * s); }
static inline float pf_v3_dot(pf_vec3 a, pf_vec3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
static inline pf_vec3 pf_v3_cross(pf_vec3 a, pf_vec3 b)
{
    return pf_v3(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x);
}
static inline float pf_v3_length(pf_vec3 a) { return sqrtf(pf_v3_dot(a, a)); }
/* Returns the zero vector for a zero-length input (callers check). */
static inline pf_vec3 pf_v3_normalize(pf_vec3 a)
{
    float l = pf_v3_length(a);
    return l > 0.0f ? pf_v3_scale(a, 1.0f / l) : pf_v3(0.0f, 0.0f, 0.0f);
}
/* Normalises vectors of any finite magnitude (1e-30 or 1e30 alike) by
 * dividing by the largest component first, so the squared length neither
 * underflows into denormals (flushed to zero under FTZ) nor overflows.
 * Used on file data; hot paths use pf_v3_normalize. */
static inline pf_vec3 pf_v3_normalize_safe(pf_vec3 a)
{
    float m = fmaxf(fabsf(a.x), fmaxf(fabsf(a.y), fabsf(a.z)));
    if (!(m > 0.0f) || !isfinite(m)) return pf_v3(0.0f, 0.0f, 0.0f);
    return pf_v3_normalize(pf_v3_scale(a, 1.0f / m));
}
/* Componentwise min / max (box bounds). */
static inline pf_vec3 pf_v3_min(pf_vec3 a, pf_vec3 b) { return pf_v3(fminf(a.x, b.x), fminf(a.y, b.y), fminf(a.z, b.z)); }
static inline pf_vec3 pf_v3_max(pf_vec3 a, pf_vec3 b) { return pf_v3(fmaxf(a.x, b.x), fmaxf(a.y, b.y), fmaxf(a.z, b.z)); }
static inline float pf_v3_max_comp(pf_vec3 a) { return fmaxf(a.x, fmaxf(a.y, a.z)); }
static inline int pf_v3_is_finite(pf_vec3 a) { return isfinite(a.x) && isfinite(a.y) && isfinite(a.z); }
static inline float pf_clampf(float x, float lo, float hi) { return x < lo ? lo : (x > hi ? hi : x); }
static inline float pf_radians(float deg) { return deg * (PF_PI / 180.0f); }
/* Luminance of linear RGB: ITU-R BT.709 (= sRGB) weights, the Y row of the
 * RGB -> XYZ matrix. */
static inline float pf_luminance(pf_vec3 c) { return 0.2126f * c.x + 0.7152f * c.y + 0.0722f * c.z; }

/* Stable hashes, for random numbers seeded from ids (frame, VPL, pixel):
 * SplitMix64's finaliser (Steele et al. 2014; constants by D. Stafford,
 * "Mix13"), a bijection on 64-bit words with full avalanche, and lowbias32
 * (C. Wellons) on 32-bit words. */
static inline uint64_t pf_mix64(uint64_t z)
{
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
}
static inline uint32_t pf_hash32(uint32_t x)
{
    x ^= x >> 16;
    x *= 0x7feb352du;
    x ^= x >> 15;
    x *= 0x846ca68bu;
    x ^= x >> 16;
    return x;
}

/* Orthonormal basis around unit n (Duff et al. 2017, branchless). */
static inline void pf_v3_basis(pf_vec3 n, pf_vec3 *t, pf_vec3 *b)
{
    float sign = copysignf(1.0f, n.z);
    float a = -1.0f / (sign + n.z);
    float bb = n.x * n.y * a;
    *t = pf_v3(1.0f + sign * n.x * n.x * a, sign * bb, -sign * n.x);
    *b = pf_v3(bb, sign + n.y * n.y * a, -n.y);
}

static inline pf_mat4 pf_mat4_identity(void)
{
    pf_mat4 r = {{1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1}};
    return r;
}
static inline pf_mat4 pf_mat4_mul(const pf_mat4 *a, const pf_mat4 *b)
{
    pf_mat4 r;
    for (int c = 0; c < 4; c++)
        for (int rr = 0; rr < 4; rr++) {
            double s = 0.0;
            for (int k = 0; k < 4; k++) s += a->m[k * 4 + rr] * b->m[c * 4 + k];
            r.m[c * 4 + rr] = s;
        }
    return r;
}
static inline pf_vec3 pf_mat4_point(const pf_mat4 *a, pf_vec3 p)
{
    const double *m = a->m;
    return pf_v3((float)(m[0] * p.x + m[4] * p.y + m[8] * p.z + m[12]),
                 (float)(m[1] * p.x + m[5] * p.y + m[9] * p.z + m[13]),
                 (float)(m[2] * p.x + m[6] * p.y + m[10] * p.z + m[14]));
}
static inline pf_vec3 pf_mat4_dir(const pf_mat4 *a, pf_vec3 d)
{
    const double *m = a->m;
    return pf_v3((float)(m[0] * d.x + m[4] * d.y + m[8] * d.z), (float)(m[1] * d.x + m[5] * d.y + m[9] * d.z),
                 (float)(m[2] * d.x + m[6] * d.y + m[10] * d.z));
}
/* Determinant of the upper 3x3 (its sign says whether the winding flips). */
static inline double pf_mat4_det3(const pf_mat4 *a)
{
    const double *m = a->m;
    return m[0] * (m[5] * m[10] - m[9] * m[6]) - m[4] * (m[1] * m[10] - m[9] * m[2]) +
           m[8] * (m[1] * m[6] - m[5] * m[2]);
}
/* Normal matrix: cofactor matrix of the upper 3x3 (inverse-transpose up to a
 * positive-or-negative scale; callers renormalise and fix the sign with det). */
static inline pf_vec3 pf_mat4_normal(const pf_mat4 *a, pf_vec3 n)
{
    const double *m = a->m;
    double c00 = m[5] * m[10] - m[6] * m[9], c01 = m[6] * m[8] - m[4] * m[10], c02 = m[4] * m[9] - m[5] * m[8];
    double c10 = m[9] * m[2] - m[10] * m[1], c11 = m[10] * m[0] - m[8] * m[2], c12 = m[8] * m[1] - m[9] * m[0];
    double c20 = m[1] * m[6] - m[2] * m[5], c21 = m[2] * m[4] - m[0] * m[6], c22 = m[0] * m[5] - m[1] * m[4];
    /* row i of the cofactor matrix of M^T: n' = cof(M) n */
    return pf_v3((float)(c00 * n.x + c10 * n.y + c20 * n.z), (float)(c01 * n.x + c11 * n.y + c21 * n.z),
                 (float)(c02 * n.x + c12 * n.y + c22 * n.z));
}

#endif
