/* pf_arena: a bump allocator for memory with one lifetime (see pf_arena.h). */
#include "pf_arena.h"

#include <stdlib.h>
#include <string.h>

#if defined(__SANITIZE_ADDRESS__)
#define PF__ARENA_ASAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define PF__ARENA_ASAN 1
#endif
#endif
#ifdef PF__ARENA_ASAN
#include <sanitizer/asan_interface.h>
#define PF__POISON(p, n) ASAN_POISON_MEMORY_REGION((p), (n))
#define PF__UNPOISON(p, n) ASAN_UNPOISON_MEMORY_REGION((p), (n))
#else
#define PF__POISON(p, n) ((void)(p), (void)(n))
#define PF__UNPOISON(p, n) ((void)(p), (void)(n))
#endif

struct pf_arena_block {
    pf_arena_block *next;
    size_t size, top; /* bytes of data[], bytes handed out */
    unsigned char *data; /* 64-byte aligned */
};

static size_t pf__round_up(size_t n, size_t a) { return (n + a - 1) / a * a; }

static pf_arena_block *pf__block_new(size_t size)
{
    pf_arena_block *b = malloc(sizeof *b);
    if (!b) return NULL;
    b->data = aligned_alloc(PF_ARENA_ALIGN, size);
    if (!b->data) {
        free(b);
        return NULL;
    }
    b->size = size;
    b->top = 0;
    b->next = NULL;
    PF__POISON(b->data, size);
    return b;
}

void *pf_arena_alloc(pf_arena *a, size_t n)
{
    if (n == 0 || n > SIZE_MAX - 2 * PF_ARENA_ALIGN) return NULL;
    /* one alignment unit more than asked: under ASan it stays poisoned, a
     * red zone between this buffer and the next */
#ifdef PF__ARENA_ASAN
    size_t take = pf__round_up(n, PF_ARENA_ALIGN) + PF_ARENA_ALIGN;
#else
    size_t take = pf__round_up(n, PF_ARENA_ALIGN);
#endif
    pf_arena_block *b = a->blocks;
    if (!b || b->size - b->top < take) {
        size_t size = take > PF_ARENA_BLOCK ? take : PF_ARENA_BLOCK;
        /* grow geometrically with what the arena already holds, so a reset
         * arena soon needs one block per lifetime */
        if (a->reserved > size && a->reserved <= SIZE_MAX / 2) size = pf__round_up(a->reserved, PF_ARENA_ALIGN);
        pf_arena_block *nb = pf__block_new(size);
        if (!nb) return NULL;
        nb->next = a->blocks;
        a->blocks = b = nb;
        a->reserved += size;
    }
    unsigned char *p = b->data + b->top;
    b->top += take;
    a->used += take;
    PF__UNPOISON(p, n);
    memset(p, 0, n);
    return p;
}

void *pf_arena_calloc(pf_arena *a, size_t count, size_t size)
{
    if (size != 0 && count > SIZE_MAX / size) return NULL;
    return pf_arena_alloc(a, count * size);
}

void pf_arena_reset(pf_arena *a)
{
    /* one block holding everything, if there were several: the next
     * lifetime then allocates from it without malloc */
    if (a->blocks && a->blocks->next) {
        size_t total = a->reserved;
        pf_arena_release(a);
        pf_arena_block *b = pf__block_new(total);
        if (b) a->blocks = b, a->reserved = total;
        return;
    }
    for (pf_arena_block *b = a->blocks; b; b = b->next) {
        b->top = 0;
        PF__POISON(b->data, b->size);
    }
    a->used = 0;
}

void pf_arena_release(pf_arena *a)
{
    pf_arena_block *b = a->blocks;
    while (b) {
        pf_arena_block *next = b->next;
        PF__UNPOISON(b->data, b->size);
        free(b->data);
        free(b);
        b = next;
    }
    memset(a, 0, sizeof *a);
}
