/* pf_random: counter-based random numbers from stable ids.
 *
 * Every random number softgi draws is a pure function of who draws it (a
 * pixel, a sample index, a path vertex, a dimension), never of a generator's
 * state: the same number comes out on any thread count and in any order,
 * which is what makes the reference path tracer, the ray-traced visibility
 * and MIR bit-exact across threads. The scheme is the reference path
 * tracer's (eval/gi_reference.h names what each argument means there). */
#ifndef PF_RANDOM_H
#define PF_RANDOM_H

#include <stdint.h>

#include "pf_math.h"

/* The random number in [0, 1) of (stream, sample, vertex, dimension). Two
 * rounds: the first makes one word per (stream, sample) (a bijection of the
 * 64-bit counter, offset by the golden ratio so that stream 0 does not map
 * to 0), the second mixes in the position within the stream. The top 24 bits
 * give a float in [0, 1) exactly: k * 2^-24 with k < 2^24 is representable
 * and never rounds up to 1. */
static inline float pf_random(uint32_t stream, uint32_t sample, uint32_t vertex, uint32_t dim)
{
    uint64_t s = pf_mix64((((uint64_t)stream << 32) | sample) + 0x9e3779b97f4a7c15ull);
    uint64_t h = pf_mix64(s ^ (((uint64_t)vertex << 32) | dim));
    return (float)(h >> 40) * 0x1p-24f;
}

#endif
