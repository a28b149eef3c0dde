/* alloc_count: counts malloc, calloc and realloc calls per calling function,
 * an LD_PRELOAD library for checking that softgi's frame loop does not
 * allocate once it is warm (docs/architecture.md, "Memory lifetimes").
 *
 *   cc -shared -fPIC -O2 tools/alloc_count.c -o /tmp/alloc_count.so -ldl -lpthread
 *   LD_PRELOAD=/tmp/alloc_count.so ./build/softgi sequence \
 *       scenes/sequences/cornell-light.seq.json --method smc --size 160x120 \
 *       --frames 0:10 -o /tmp/seq -q 2>&1 | grep '^alloc'
 *
 * prints, at exit, the callers with the most calls as "alloc COUNT OBJECT+OFFSET";
 * `addr2line -f -e ./build/softgi OFFSET` names a caller inside the program.
 * Run with --frames 0:2 and 0:10: a caller whose count grows with the frames
 * allocates in every frame. A diagnostic, not part of the build. */
#define _GNU_SOURCE
#include <dlfcn.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>

enum { SLOTS = 4096, SHOWN = 60 };
static void *(*real_malloc)(size_t), *(*real_calloc)(size_t, size_t), *(*real_realloc)(void *, size_t);
static char boot[65536]; /* dlsym itself calls calloc before real_calloc is known */
static size_t boot_used;
static void *caller[SLOTS];
static unsigned long count[SLOTS];
static pthread_mutex_t lock = PTHREAD_MUTEX_INITIALIZER;
static __thread int busy;

static void note(void *who)
{
    if (busy) return;
    busy = 1;
    pthread_mutex_lock(&lock);
    size_t h = ((size_t)who >> 4) % SLOTS;
    for (int k = 0; k < SLOTS; k++, h = (h + 1) % SLOTS)
        if (caller[h] == who || !caller[h]) {
            caller[h] = who;
            count[h]++;
            break;
        }
    pthread_mutex_unlock(&lock);
    busy = 0;
}

void *malloc(size_t n)
{
    if (!real_malloc) real_malloc = (void *(*)(size_t))dlsym(RTLD_NEXT, "malloc");
    note(__builtin_return_address(0));
    return real_malloc(n);
}

void *calloc(size_t a, size_t b)
{
    if (!real_calloc) {
        void *p = boot + boot_used;
        boot_used += (a * b + 15) & ~(size_t)15;
        return p;
    }
    note(__builtin_return_address(0));
    return real_calloc(a, b);
}

void *realloc(void *p, size_t n)
{
    if (!real_realloc) real_realloc = (void *(*)(void *, size_t))dlsym(RTLD_NEXT, "realloc");
    note(__builtin_return_address(0));
    return real_realloc(p, n);
}

__attribute__((constructor)) static void alloc_count_init(void)
{
    real_calloc = (void *(*)(size_t, size_t))dlsym(RTLD_NEXT, "calloc");
}

__attribute__((destructor)) static void alloc_count_report(void)
{
    busy = 1;
    for (int r = 0; r < SHOWN; r++) {
        int best = -1;
        for (int k = 0; k < SLOTS; k++)
            if (caller[k] && count[k] && (best < 0 || count[k] > count[best])) best = k;
        if (best < 0) break;
        Dl_info d;
        if (dladdr(caller[best], &d) && d.dli_fname)
            fprintf(stderr, "alloc %8lu %s+%#lx\n", count[best], d.dli_fname,
                    (unsigned long)((char *)caller[best] - (char *)d.dli_fbase));
        else
            fprintf(stderr, "alloc %8lu %p\n", count[best], caller[best]);
        count[best] = 0;
    }
}
