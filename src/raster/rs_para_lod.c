/* rs_para_lod: the paraboloid maps' levels of detail (see rs_para_lod.h).
 *
 * This work is based on meshoptimizer 0.18 (Kapoulkine: meshopt_simplify,
 * an edge-collapse simplifier with quadric error metrics after Garland &
 * Heckbert, SIGGRAPH 1997, with meshopt_SimplifyLockBorder) and on the
 * separate shadow-geometry copy of Laine et al. 2007, Sec. 6. */
#include "rs_para_lod.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include <meshoptimizer.h>

/* Spreads the low 10 bits of x to every third bit. */
static uint32_t rs__part1by2(uint32_t x)
{
    x &= 0x3ff;
    x = (x | (x << 16)) & 0x030000ff;
    x = (x | (x << 8)) & 0x0300f00f;
    x = (x | (x << 4)) & 0x030c30c3;
    x = (x | (x << 2)) & 0x09249249;
    return x;
}

static uint32_t rs__cell(float v, float lo, float hi)
{
    float s = hi > lo ? (v - lo) / (hi - lo) * 1024.0f : 0.0f;
    return !(s > 0.0f) ? 0u : s >= 1023.0f ? 1023u : (uint32_t)s;
}

static int rs__cmp_u64(const void *a, const void *b)
{
    uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
    return x < y ? -1 : x > y;
}

/* Room for `more` triangles in lod->tri (capacity *cap triangles). */
static int rs__reserve(rs__lod *lod, size_t *cap, size_t more)
{
    size_t need = (size_t)lod->tri_count + more;
    if (need <= *cap) return 1;
    size_t c = *cap * 2 > need ? *cap * 2 : need;
    pf_vec3 *grown = realloc(lod->tri, c * 3 * sizeof(pf_vec3));
    if (!grown) return 0;
    lod->tri = grown;
    *cap = c;
    return 1;
}

/* Appends the triangles idx[0..n3) (local vertex indices into v) that are
 * not degenerate to lod->tri (room reserved); returns how many. */
static uint32_t rs__append(rs__lod *lod, const unsigned int *idx, size_t n3, const pf_vec3 *v)
{
    uint32_t kept = 0;
    for (size_t t = 0; t + 2 < n3; t += 3) {
        unsigned a = idx[t], b = idx[t + 1], c = idx[t + 2];
        if (a == b || b == c || c == a) continue;
        pf_vec3 n = pf_v3_cross(pf_v3_sub(v[b], v[a]), pf_v3_sub(v[c], v[a]));
        if (!(pf_v3_dot(n, n) > 0.0f)) continue;
        pf_vec3 *o = &lod->tri[3 * (size_t)lod->tri_count];
        o[0] = v[a], o[1] = v[b], o[2] = v[c];
        lod->tri_count++;
        kept++;
    }
    return kept;
}

pf_result rs__lod_build(rs__lod *lod, const pf_scene *scene, pf_error *err)
{
    memset(lod, 0, sizeof *lod);
    const uint32_t N = scene->tri_count;
    const uint32_t G = (N + RS__LOD_GROUP - 1) / RS__LOD_GROUP;
    uint64_t *key = malloc((size_t)N * sizeof(uint64_t));
    size_t cap = (size_t)N * 2; /* triangles; grown when the levels need more */
    lod->tri = malloc(cap * 3 * sizeof(pf_vec3));
    lod->groups = calloc(G, sizeof(rs__lod_group));
    pf_vec3 *corner = malloc((size_t)RS__LOD_GROUP * 3 * sizeof(pf_vec3));
    pf_vec3 *vert = malloc((size_t)RS__LOD_GROUP * 3 * sizeof(pf_vec3));
    unsigned int *remap = malloc((size_t)RS__LOD_GROUP * 3 * sizeof(unsigned int));
    unsigned int *idx0 = malloc((size_t)RS__LOD_GROUP * 3 * sizeof(unsigned int));
    unsigned int *idx = malloc((size_t)RS__LOD_GROUP * 3 * sizeof(unsigned int));
    if (!key || !lod->tri || !lod->groups || !corner || !vert || !remap || !idx0 || !idx) {
        free(key), free(corner), free(vert), free(remap), free(idx0), free(idx);
        rs__lod_free(lod);
        return pf_error_set(err, PF_ERR_OUT_OF_MEMORY, "paraboloid maps: out of memory for the levels of detail");
    }

    /* 1. Morton order of the centroids */
    pf_vec3 lo = scene->bounds_min, hi = scene->bounds_max;
    for (uint32_t t = 0; t < N; t++) {
        const uint32_t *i = &scene->indices[3 * t];
        pf_vec3 a = scene->positions[i[0]], b = scene->positions[i[1]], c = scene->positions[i[2]];
        float cx = (a.x + b.x + c.x) * (1.0f / 3.0f), cy = (a.y + b.y + c.y) * (1.0f / 3.0f),
              cz = (a.z + b.z + c.z) * (1.0f / 3.0f);
        uint32_t m = rs__part1by2(rs__cell(cx, lo.x, hi.x)) | rs__part1by2(rs__cell(cy, lo.y, hi.y)) << 1 |
                     rs__part1by2(rs__cell(cz, lo.z, hi.z)) << 2;
        key[t] = (uint64_t)m << 32 | t;
    }
    qsort(key, N, sizeof(uint64_t), rs__cmp_u64);

    for (uint32_t g = 0; g < G; g++) {
        rs__lod_group *gr = &lod->groups[g];
        uint32_t t0 = g * RS__LOD_GROUP, n = N - t0 < RS__LOD_GROUP ? N - t0 : RS__LOD_GROUP;
        /* 2. weld the group's corners */
        for (uint32_t k = 0; k < n; k++) {
            const uint32_t *i = &scene->indices[3 * (uint32_t)key[t0 + k]];
            for (int v = 0; v < 3; v++) corner[3 * k + v] = scene->positions[i[v]];
        }
        size_t n3 = (size_t)n * 3;
        size_t nv = meshopt_generateVertexRemap(remap, NULL, n3, corner, n3, sizeof(pf_vec3));
        meshopt_remapVertexBuffer(vert, corner, n3, sizeof(pf_vec3), remap);
        for (size_t k = 0; k < n3; k++) idx0[k] = remap[k];
        float scale = meshopt_simplifyScale(&vert[0].x, nv, sizeof(pf_vec3));

        /* level 0: the triangles themselves, in Morton order */
        if (!rs__reserve(lod, &cap, n)) goto oom;
        gr->first[0] = lod->tri_count;
        for (uint32_t k = 0; k < n; k++) {
            pf_vec3 *o = &lod->tri[3 * (size_t)lod->tri_count++];
            for (int v = 0; v < 3; v++) o[v] = corner[3 * k + v];
        }
        gr->count[0] = n;
        gr->err[0] = 0.0f;
        gr->levels = 1;
        /* coarser levels, each from level 0 */
        for (uint32_t L = 1; L < RS__LOD_LEVELS; L++) {
            size_t target = (n3 / 3 >> L) * 3;
            if (target < 3) break;
            float rel = 0.0f;
            size_t got = meshopt_simplify(idx, idx0, n3, &vert[0].x, nv, sizeof(pf_vec3), target, 1.0f,
                                          meshopt_SimplifyLockBorder, &rel);
            if (got == 0 || (double)got > 0.85 * 3.0 * gr->count[L - 1]) break;
            if (!rs__reserve(lod, &cap, got / 3)) goto oom;
            uint32_t first = lod->tri_count, kept = rs__append(lod, idx, got, vert);
            if (kept == 0) break;
            gr->first[L] = first;
            gr->count[L] = kept;
            float e = rel * scale;
            gr->err[L] = e > gr->err[L - 1] ? e : gr->err[L - 1];
            gr->levels = L + 1;
        }

        /* 3. bounding sphere of level 0, radius in double rounded up */
        float blo[3] = {INFINITY, INFINITY, INFINITY}, bhi[3] = {-INFINITY, -INFINITY, -INFINITY};
        for (size_t k = 0; k < nv; k++) {
            const float p[3] = {vert[k].x, vert[k].y, vert[k].z};
            for (int a = 0; a < 3; a++) {
                blo[a] = p[a] < blo[a] ? p[a] : blo[a];
                bhi[a] = p[a] > bhi[a] ? p[a] : bhi[a];
            }
        }
        gr->cx = 0.5f * (blo[0] + bhi[0]);
        gr->cy = 0.5f * (blo[1] + bhi[1]);
        gr->cz = 0.5f * (blo[2] + bhi[2]);
        double r2 = 0.0;
        for (size_t k = 0; k < nv; k++) {
            double dx = (double)vert[k].x - gr->cx, dy = (double)vert[k].y - gr->cy, dz = (double)vert[k].z - gr->cz;
            double d2 = dx * dx + dy * dy + dz * dz;
            r2 = d2 > r2 ? d2 : r2;
        }
        gr->r = nextafterf((float)(sqrt(r2) * (1.0 + 1e-6)), INFINITY);
    }
    lod->group_count = G;
    free(key), free(corner), free(vert), free(remap), free(idx0), free(idx);
    return PF_OK;
oom:
    free(key), free(corner), free(vert), free(remap), free(idx0), free(idx);
    rs__lod_free(lod);
    return pf_error_set(err, PF_ERR_OUT_OF_MEMORY, "paraboloid maps: out of memory for the levels of detail");
}

void rs__lod_free(rs__lod *lod)
{
    free(lod->groups);
    free(lod->tri);
    memset(lod, 0, sizeof *lod);
}
