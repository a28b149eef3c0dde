/* gi_kmeans: k-means clustering of VPLs with the normal-aware metric of
 * Aranha et al., "Screen-space VPL propagation", Sec. III-B, Eq. 2 (after
 * Dong et al. 2009):
 *
 *   D_ij = w1 |V_i - C_j| / scale + w2 (1 - (n_i . n_j)^+)
 *
 * Deviations from Eq. 2 as printed (README "ssvp"):
 * - the paper prints the normal term as w2 (n_i . n_j)^+, which grows as the
 *   normals agree and so would pull VPLs facing away from a centroid into
 *   it, the very artefact the paper says the metric removes; we use the
 *   dissimilarity 1 - (n_i . n_j)^+ (0 for equal normals, 1 for
 *   perpendicular or opposite ones);
 * - |V_i - C_j| is divided by `scale` (SSVP: the scene's bounding-box
 *   diagonal), so that w1 = 0.6 and w2 = 0.4 weigh the two terms the same
 *   way in a 0.5 m Cornell box and a 30 m cathedral.
 *
 * Algorithm (the paper's outline, each step a function):
 *   gi_kmeans_seed    a random VPL as each cluster's first centroid (drawn
 *                     k-means++ style, a deviation: see gi_kmeans.c), used
 *                     only when there are no centroids from the previous
 *                     frame;
 *   gi_kmeans_assign  every VPL to the nearest centroid by D (ties: lowest
 *                     cluster index);
 *   gi_kmeans_update  centroid = mean position, normalised mean normal of
 *                     its VPLs (summed in VPL order: deterministic); an
 *                     empty cluster keeps its centroid;
 *   gi_kmeans_run     seed (or reuse the previous frame's centroids), then
 *                     assign/update until no centroid changes (bitwise) or
 *                     max_iter iterations (the paper: at most 5). */
#ifndef GI_KMEANS_H
#define GI_KMEANS_H

#include <stdint.h>

#include "pf_math.h"

#define GI_KMEANS_W1 0.6f
#define GI_KMEANS_W2 0.4f
#define GI_KMEANS_MAX_ITER 5u

typedef struct gi_kmeans_options {
    float w1, w2;      /* Eq. 2 weights */
    float scale;       /* distance unit (> 0) */
    uint32_t max_iter; /* >= 1 */
} gi_kmeans_options;

/* w1 = 0.6, w2 = 0.4, scale 1, 5 iterations. */
gi_kmeans_options gi_kmeans_defaults(void);

/* Eq. 2 between a VPL (p, n) and a centroid (c, cn); normals unit length. */
float gi_kmeans_distance(const gi_kmeans_options *o, pf_vec3 p, pf_vec3 n, pf_vec3 c, pf_vec3 cn);

/* Seeds centroid j = a VPL drawn by D^2 (k-means++, fixed random stream;
 * distinct VPLs while k <= the number of distinct VPLs). d2: count floats of
 * scratch. */
void gi_kmeans_seed(const gi_kmeans_options *o, const pf_vec3 *pos, const pf_vec3 *nrm, uint32_t count,
                    pf_vec3 *cpos, pf_vec3 *cnrm, uint32_t k, float *d2);
/* assign[i] = nearest centroid of VPL i. Returns how many assignments
 * differ from assign's previous contents. */
uint32_t gi_kmeans_assign(const gi_kmeans_options *o, const pf_vec3 *pos, const pf_vec3 *nrm, uint32_t count,
                          const pf_vec3 *cpos, const pf_vec3 *cnrm, uint32_t k, uint32_t *assign);
/* Centroids from the assignment; returns the number of centroids changed.
 * members[j] receives each cluster's size. */
uint32_t gi_kmeans_update(const pf_vec3 *pos, const pf_vec3 *nrm, uint32_t count, const uint32_t *assign,
                          pf_vec3 *cpos, pf_vec3 *cnrm, uint32_t k, uint32_t *members);

/* Clusters pos/nrm[0..count) into k clusters. `reuse`: cpos/cnrm hold last
 * frame's centroids (else they are seeded). assign (count) and members (k)
 * are outputs; scratch: count floats. Returns the number of assign/update
 * iterations run (0 when count or k is 0). */
uint32_t gi_kmeans_run(const gi_kmeans_options *o, const pf_vec3 *pos, const pf_vec3 *nrm, uint32_t count,
                       pf_vec3 *cpos, pf_vec3 *cnrm, uint32_t k, int reuse, uint32_t *assign, uint32_t *members,
                       float *scratch);

#endif
