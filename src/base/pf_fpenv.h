/* pf_fpenv: the floating-point environment every softgi thread runs with.
 * Flush-to-zero and denormals-are-zero are set on the main thread and on every
 * worker before it runs a job, because Embree asks for them (speed) and
 * because results must not depend on which thread computed them. The same
 * MXCSR on every thread is part of softgi's determinism contract. */
#ifndef PF_FPENV_H
#define PF_FPENV_H

#include "simd_arch.h"

/* A thread's environment as pf_fpenv_save found it (the library restores
 * its caller's on the way out). */
typedef struct pf_fpenv_state {
    unsigned csr;
} pf_fpenv_state;

#if SIMD_X86
static inline void pf_fpenv_set(void) { simd_csr_set(simd_csr_softgi(simd_csr_get())); }
static inline pf_fpenv_state pf_fpenv_save(void) { return (pf_fpenv_state){simd_csr_get()}; }
static inline void pf_fpenv_restore(pf_fpenv_state s) { simd_csr_set(s.csr); }
#else
static inline void pf_fpenv_set(void) {}
static inline pf_fpenv_state pf_fpenv_save(void) { return (pf_fpenv_state){0}; }
static inline void pf_fpenv_restore(pf_fpenv_state s) { (void)s; }
#endif

#endif
