/* pf_budget: how much memory softgi may use, checked before allocating.
 *
 * A scene, a texture or a sequence file from a stranger can ask for absurd
 * amounts of memory in a few bytes: sixteen 8192^2 textures in a 25 KB .glb,
 * 2,000 point lights each with a cube shadow map, a 16384^2 frame, 33 M
 * instanced triangles. Every such request is estimated from the file's
 * headers and counts (before anything is decoded or allocated) and taken from
 * one budget; a request that does not fit is refused with one line saying
 * what needed how much. The budget is `--max-memory` (e.g. 8G, 512M), by
 * default half of this machine's memory (the smaller of physical memory and
 * the cgroup limit, so a container's limit counts).
 *
 * The estimates are upper-bound sketches of the big arrays (texels and their
 * mips, per-triangle arrays of the scene, Embree and the rasterizer, frame
 * planes, shadow and paraboloid maps), not an accounting of every malloc; the
 * constants say what they include. */
#ifndef PF_BUDGET_H
#define PF_BUDGET_H

#include <stdint.h>

#include "pf_result.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct pf_budget {
    uint64_t limit; /* bytes */
    uint64_t used;  /* bytes taken so far */
} pf_budget;

/* Bytes one scene triangle costs through the whole pipeline: the scene's
 * arrays (3 positions, normals and uvs, indices, material: 112 B), Embree's
 * BVH (about 100 B at medium quality) and the rasterizer's per-triangle
 * tables and per-frame set-up records (about 300 B). */
#define PF_BUDGET_BYTES_PER_TRIANGLE 512u

/* The machine's memory: min(physical memory, cgroup v2 memory.max, cgroup v1
 * limit_in_bytes). Never 0 (falls back to 1 GiB if nothing can be read). */
uint64_t pf_memory_machine(void);
/* The default budget: half of pf_memory_machine(). */
uint64_t pf_budget_default(void);
/* "8G", "512M", "1.5G", "1048576" (bytes), K/M/G/T binary units; at least 64 MiB. */
pf_result pf_budget_parse(const char *text, uint64_t *bytes, pf_error *err);

/* limit 0 means pf_budget_default(). */
void pf_budget_init(pf_budget *b, uint64_t limit);
/* Takes `bytes` for `what` (e.g. "texture 3 (8192x8192)"), or fails with
 * PF_ERR_OUT_OF_MEMORY and a message naming both sizes and the budget. */
pf_result pf_budget_take(pf_budget *b, uint64_t bytes, const char *what, pf_error *err);
/* Before a large allocation that fits the budget but takes a big share of
 * the machine (at least PF_BUDGET_WARN_SHARE of pf_memory_machine(), e.g.
 * --vpls 100000: 3.3 GB of paraboloid maps), one line on stderr:
 *   softgi: warning: this run will take about 3.4 GiB, 42% of this
 *   machine's 7.8 GiB; use fewer VPLs or --visibility raytrace (--vpls N)
 * `hint` names the option that reduces it. Returns 1 if it warned. */
#define PF_BUDGET_WARN_SHARE 0.25
int pf_budget_warn(const pf_budget *b, const char *hint);
/* a * b, saturating at UINT64_MAX. */
uint64_t pf_budget_mul(uint64_t a, uint64_t b);

#ifdef __cplusplus
}
#endif

#endif
