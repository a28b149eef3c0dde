/* pf_fpenv: the floating-point environment every softgi thread runs with.
 * Flush-to-zero and denormals-are-zero are set on the main thread and on every
 * worker before it runs a job, because Embree asks for them (speed) and
 * because results must not depend on which thread computed them. The same
 * MXCSR on every thread is part of softgi's determinism contract. */
#ifndef PF_FPENV_H
#define PF_FPENV_H

#if defined(__x86_64__) || defined(__i386__)
#include <pmmintrin.h>
#include <xmmintrin.h>
static inline void pf_fpenv_set(void)
{
    _MM_SET_FLUSH_ZERO_MODE(_MM_FLUSH_ZERO_ON);
    _MM_SET_DENORMALS_ZERO_MODE(_MM_DENORMALS_ZERO_ON);
    _MM_SET_ROUNDING_MODE(_MM_ROUND_NEAREST);
}
#else
static inline void pf_fpenv_set(void) {}
#endif

#endif
