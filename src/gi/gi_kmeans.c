/* gi_kmeans: k-means VPL clustering with Aranha's Eq. 2 metric (Sec. III-B);
 * see gi_kmeans.h for the metric, its deviations and the outline. */
#include "gi_kmeans.h"

#include <math.h>
#include <string.h>

gi_kmeans_options gi_kmeans_defaults(void)
{
    gi_kmeans_options o = {GI_KMEANS_W1, GI_KMEANS_W2, 1.0f, GI_KMEANS_MAX_ITER};
    return o;
}

float gi_kmeans_distance(const gi_kmeans_options *o, pf_vec3 p, pf_vec3 n, pf_vec3 c, pf_vec3 cn)
{
    float cosp = pf_v3_dot(n, cn);
    if (!(cosp > 0.0f)) cosp = 0.0f;
    return o->w1 * pf_v3_length(pf_v3_sub(p, c)) / o->scale + o->w2 * (1.0f - cosp);
}

static uint64_t gi__splitmix(uint64_t *s)
{
    uint64_t z = (*s += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
}

/* "At the beginning of the first iteration, a random VPL is chosen as the
 * centroid seed for each cluster": the first k steps of a Fisher-Yates
 * shuffle of the VPL indices driven by a fixed splitmix64 stream, so the
 * seeds are distinct VPLs and the same for every run. With more clusters
 * than VPLs, cluster j >= count reuses VPL j mod count. */
void gi_kmeans_seed(const pf_vec3 *pos, const pf_vec3 *nrm, uint32_t count, pf_vec3 *cpos, pf_vec3 *cnrm,
                    uint32_t k)
{
    if (!count) return;
    uint64_t rng = 0x55535650u; /* "SSVP" */
    /* the shuffle touches only the first min(k, count) slots: a sparse swap
     * list keeps it O(k) without a count-sized permutation array */
    uint32_t m = k < count ? k : count;
    uint32_t from[64], to[64], nswap = 0;
    for (uint32_t j = 0; j < k; j++) {
        uint32_t pick;
        if (j < m && m <= 64) {
            uint32_t r = j + (uint32_t)(gi__splitmix(&rng) % (uint64_t)(count - j));
            /* value at r and at j after earlier swaps */
            uint32_t vr = r, vj = j;
            for (uint32_t s = 0; s < nswap; s++) {
                if (from[s] == r) vr = to[s];
                if (from[s] == j) vj = to[s];
            }
            pick = vr;
            /* slot r now holds vj */
            int found = 0;
            for (uint32_t s = 0; s < nswap; s++)
                if (from[s] == r) to[s] = vj, found = 1;
            if (!found) from[nswap] = r, to[nswap] = vj, nswap++;
        } else if (j < m) {
            /* more than 64 clusters: a stride through the VPLs (distinct) */
            pick = (uint32_t)(((uint64_t)j * count) / m);
        } else {
            pick = j % count;
        }
        cpos[j] = pos[pick];
        cnrm[j] = nrm[pick];
    }
}

uint32_t gi_kmeans_assign(const gi_kmeans_options *o, const pf_vec3 *pos, const pf_vec3 *nrm, uint32_t count,
                          const pf_vec3 *cpos, const pf_vec3 *cnrm, uint32_t k, uint32_t *assign)
{
    uint32_t changed = 0;
    for (uint32_t i = 0; i < count; i++) {
        uint32_t best = 0;
        float bd = gi_kmeans_distance(o, pos[i], nrm[i], cpos[0], cnrm[0]);
        for (uint32_t j = 1; j < k; j++) {
            float d = gi_kmeans_distance(o, pos[i], nrm[i], cpos[j], cnrm[j]);
            if (d < bd) bd = d, best = j; /* ties keep the lower index */
        }
        changed += assign[i] != best;
        assign[i] = best;
    }
    return changed;
}

uint32_t gi_kmeans_update(const pf_vec3 *pos, const pf_vec3 *nrm, uint32_t count, const uint32_t *assign,
                          pf_vec3 *cpos, pf_vec3 *cnrm, uint32_t k, uint32_t *members)
{
    uint32_t changed = 0;
    for (uint32_t j = 0; j < k; j++) {
        /* sums in double, in VPL order: the same bits for any caller */
        double sp[3] = {0, 0, 0}, sn[3] = {0, 0, 0};
        uint32_t c = 0;
        for (uint32_t i = 0; i < count; i++) {
            if (assign[i] != j) continue;
            sp[0] += pos[i].x, sp[1] += pos[i].y, sp[2] += pos[i].z;
            sn[0] += nrm[i].x, sn[1] += nrm[i].y, sn[2] += nrm[i].z;
            c++;
        }
        members[j] = c;
        if (!c) continue; /* empty: keep the centroid */
        pf_vec3 p = pf_v3((float)(sp[0] / c), (float)(sp[1] / c), (float)(sp[2] / c));
        double len = sqrt(sn[0] * sn[0] + sn[1] * sn[1] + sn[2] * sn[2]);
        pf_vec3 n = cnrm[j]; /* normals that cancel keep the old direction */
        if (len > 1e-12) n = pf_v3((float)(sn[0] / len), (float)(sn[1] / len), (float)(sn[2] / len));
        if (memcmp(&p, &cpos[j], sizeof p) || memcmp(&n, &cnrm[j], sizeof n)) changed++;
        cpos[j] = p;
        cnrm[j] = n;
    }
    return changed;
}

uint32_t gi_kmeans_run(const gi_kmeans_options *o, const pf_vec3 *pos, const pf_vec3 *nrm, uint32_t count,
                       pf_vec3 *cpos, pf_vec3 *cnrm, uint32_t k, int reuse, uint32_t *assign, uint32_t *members)
{
    if (!count || !k) {
        for (uint32_t j = 0; j < k; j++) members[j] = 0;
        return 0;
    }
    if (!reuse) gi_kmeans_seed(pos, nrm, count, cpos, cnrm, k);
    uint32_t it = 0;
    for (uint32_t i = 0; i < count; i++) assign[i] = 0;
    while (it < o->max_iter) {
        it++;
        gi_kmeans_assign(o, pos, nrm, count, cpos, cnrm, k, assign);
        /* converged: "the average position and normal of a centroid does
         * not change between iterations" */
        if (!gi_kmeans_update(pos, nrm, count, assign, cpos, cnrm, k, members)) break;
    }
    /* the assignment handed out matches the final centroids' membership
     * counts (members was computed from this assignment) */
    return it;
}
