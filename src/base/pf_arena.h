/* pf_arena: a bump allocator for memory with one lifetime.
 *
 * A frame's buffers live exactly as long as the frame (gi_frame_create to
 * gi_frame_free), and a frame's scratch exactly as long as one frame. An
 * arena gives each lifetime one owner: allocations are carved from a few
 * large blocks, zeroed, 64-byte aligned (a cache line, and the widest SIMD
 * load), and released all at once by pf_arena_release (or made reusable by
 * pf_arena_reset, which keeps the blocks: a steady frame loop then stops
 * calling malloc). llvmpipe's lp_scene keeps its bins the same way.
 *
 * Failure is a NULL return, never an abort: the caller turns it into
 * PF_ERR_OUT_OF_MEMORY with a message, as everywhere at the edges. Sizes that
 * overflow are failures too. Under AddressSanitizer the bytes between and
 * after allocations are poisoned, so an overrun of one buffer into the next
 * is still reported, as it would be with separate mallocs.
 *
 * Not thread-safe: one arena has one owner (the frame's thread). */
#ifndef PF_ARENA_H
#define PF_ARENA_H

#include <stddef.h>
#include <stdint.h>

#define PF_ARENA_ALIGN 64u
#define PF_ARENA_BLOCK (1u << 20) /* the smallest block: 1 MiB */

typedef struct pf_arena_block pf_arena_block;

typedef struct pf_arena {
    pf_arena_block *blocks; /* newest first */
    size_t used;            /* bytes handed out since the last reset (aligned sizes) */
    size_t reserved;        /* bytes of all blocks */
} pf_arena;

/* n bytes, zeroed and 64-byte aligned; NULL if n is 0 or memory is short. */
void *pf_arena_alloc(pf_arena *a, size_t n);
/* count * size bytes (NULL on overflow), as calloc. */
void *pf_arena_calloc(pf_arena *a, size_t count, size_t size);
/* Every allocation made so far becomes invalid; the blocks are kept and
 * merged into one the next time they do not suffice. */
void pf_arena_reset(pf_arena *a);
/* Frees every block; the arena is empty (zeroed) again. */
void pf_arena_release(pf_arena *a);

#endif
