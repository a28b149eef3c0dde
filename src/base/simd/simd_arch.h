/* simd_arch: the project's one "is this x86?" test, SIMD_X86 (1 on x86-64
 * and x86, else 0), for code that needs only that answer (the CPU
 * detection, the floating-point environment) without the SIMD vocabulary
 * that simd.h brings. */
#ifndef SIMD_ARCH_H
#define SIMD_ARCH_H

#if defined(__x86_64__) || defined(__i386__)
#define SIMD_X86 1
#else
#define SIMD_X86 0
#endif

/* The SSE control register (MXCSR) for pf_fpenv.h, the one place outside
 * the per-ISA headers that touches it: read, write, and the value softgi
 * runs with (flush-to-zero, denormals-are-zero, round to nearest; the
 * exception masks and flags as they were). */
#if SIMD_X86
#include <xmmintrin.h>
static inline unsigned simd_csr_get(void) { return _mm_getcsr(); }
static inline void simd_csr_set(unsigned csr) { _mm_setcsr(csr); }
static inline unsigned simd_csr_softgi(unsigned csr)
{
    csr |= 0x8000u | 0x0040u; /* FTZ (bit 15), DAZ (bit 6) */
    return csr & ~0x6000u;    /* rounding control (bits 13-14): to nearest */
}
#endif

#endif
