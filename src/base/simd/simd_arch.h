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

#endif
