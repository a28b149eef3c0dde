/* simd: the SIMD vocabulary, one small header per instruction set with the
 * same names (after Masked Occlusion Culling's width-generic `_mmw_`
 * vocabulary; docs/raster.md "The SIMD vocabulary").
 *
 * A kernel is written once over these names and compiled once per
 * instruction set: CMake compiles each kernel file three times (scalar,
 * -mavx2, -mavx512f/dq/bw/vl), and this header picks the vocabulary from
 * what the compiler was told:
 *
 *   SIMD_FORCE_SCALAR defined      simd_scalar.h   8 lanes, plain C (the reference)
 *   AVX-512 F, DQ, BW and VL       simd_avx512.h   16 lanes
 *   AVX2                           simd_avx2.h     8 lanes
 *   SSE2 (every x86-64)            simd_sse.h      4 lanes (code outside the kernels)
 *   anything else                  simd_scalar.h
 *
 * Every vocabulary gives every operation the same IEEE result lane by lane:
 * no approximate reciprocals, no fused multiply-adds (-ffp-contract=off),
 * min(a, b) = a < b ? a : b and max(a, b) = a > b ? a : b as the x86
 * instructions define them. simd_scalar.h spells out each operation in plain
 * C and is the definition the others are tested against: a kernel compiled
 * with it is the scalar path, and every SIMD path must give its bits.
 *
 * Names: simd_f (SIMD_W floats), simd_i (SIMD_W int32), simd_l (SIMD_WL
 * int64), simd_mask (a lane mask in the instruction set's own form: plain
 * bits on the scalar path, vector lanes on SSE2 and AVX2, a mask register
 * on AVX-512), so kernels combine masks only with simd_mask_and / _or /
 * _andnot / _not and turn them into plain bits (lane l in bit l) with
 * simd_mask_bits where they loop over or count lanes; simd_mask_from_bits
 * goes the other way. Operations end in _f, _i or _l by the lanes they
 * work on. Raw intrinsics belong in these headers only. */
#ifndef SIMD_H
#define SIMD_H

#include "simd_arch.h" /* SIMD_X86: the one "is this x86?" test of the project */

#if defined(SIMD_FORCE_SCALAR)
#include "simd_scalar.h"
#elif defined(__AVX512F__) && defined(__AVX512DQ__) && defined(__AVX512BW__) && defined(__AVX512VL__)
#include "simd_avx512.h"
#elif defined(__AVX2__)
#include "simd_avx2.h"
#elif defined(__SSE2__)
#include "simd_sse.h"
#else
#include "simd_scalar.h"
#endif

#endif
