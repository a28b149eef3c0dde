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

static uint64_t gi__splitmix(uint64_t *s) { return pf_mix64(*s += 0x9e3779b97f4a7c15ull); }

/* "At the beginning of the first iteration, a random VPL is chosen as the
 * centroid seed for each cluster." Deviation (README "ssvp"): the random
 * VPLs are drawn as k-means++ does (Arthur and Vassilvitskii 2007): the first
 * uniformly, each further one with probability proportional to D^2, its
 * squared Eq. 2 distance to the nearest seed so far. Uniform picks put two
 * seeds in one group of similar VPLs often (7 times in 9 for three equal
 * groups: only 3!/3^3 of the picks are one per group), and five iterations
 * cannot undo that; D^2 picks rarely do. The random stream is a fixed splitmix64 sequence, so seeds are the
 * same for every run. VPLs already chosen have D = 0 and are not picked
 * again while another VPL has D > 0; with more clusters than distinct VPLs
 * the extra clusters repeat VPL j mod count. */
void gi_kmeans_seed(const gi_kmeans_options *o, const pf_vec3 *pos, const pf_vec3 *nrm, uint32_t count,
                    pf_vec3 *cpos, pf_vec3 *cnrm, uint32_t k, float *d2)
{
    if (!count || !k) return;
    uint64_t rng = 0x55535650u; /* "SSVP" */
    uint32_t pick = (uint32_t)(gi__splitmix(&rng) % count);
    cpos[0] = pos[pick], cnrm[0] = nrm[pick];
    for (uint32_t i = 0; i < count; i++) {
        float d = gi_kmeans_distance(o, pos[i], nrm[i], cpos[0], cnrm[0]);
        d2[i] = d * d;
    }
    for (uint32_t j = 1; j < k; j++) {
        double total = 0.0;
        for (uint32_t i = 0; i < count; i++) total += d2[i];
        if (!(total > 0.0)) {
            pick = j % count;
        } else {
            /* u in [0, total): the first VPL whose running sum exceeds it */
            double u = (double)(gi__splitmix(&rng) >> 11) * (1.0 / 9007199254740992.0) * total, run = 0.0;
            pick = count - 1;
            for (uint32_t i = 0; i < count; i++) {
                run += d2[i];
                if (d2[i] > 0.0f && u < run) {
                    pick = i;
                    break;
                }
            }
            while (!(d2[pick] > 0.0f)) pick--; /* rounding at the end: the last VPL with D > 0 */
        }
        cpos[j] = pos[pick], cnrm[j] = nrm[pick];
        for (uint32_t i = 0; i < count; i++) {
            float d = gi_kmeans_distance(o, pos[i], nrm[i], cpos[j], cnrm[j]);
            if (d * d < d2[i]) d2[i] = d * d;
        }
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
                       pf_vec3 *cpos, pf_vec3 *cnrm, uint32_t k, int reuse, uint32_t *assign, uint32_t *members,
                       float *scratch)
{
    if (!count || !k) {
        for (uint32_t j = 0; j < k; j++) members[j] = 0;
        return 0;
    }
    if (!reuse) gi_kmeans_seed(o, pos, nrm, count, cpos, cnrm, k, scratch);
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
