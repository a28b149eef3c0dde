/* gi_knn: k-nearest-neighbour queries over a fixed set of 3D points with a
 * k-d tree, for the kNN density estimates of Sequential Monte Carlo Instant
 * Radiosity (Hedman 2017 Sec. 3.2.4, Eq. 7; the paper builds a BVH on the
 * GPU, Sec. 4: any exact kNN structure gives the same answers).
 *
 * Tree: the point indices are permuted in place into an implicit balanced
 * tree. Node [lo, hi) splits at mid = (lo + hi) / 2 on the axis where its
 * points spread most; idx[mid] is the node's point, [lo, mid) lie at or
 * below it on that axis and (mid, hi) at or above it. The split is a
 * quickselect on the total order (coordinate, index), so the tree depends
 * only on the points, never on timing. Build O(n log n), query about
 * O(log n + k) for well-spread points.
 *
 * Queries are exact: the k-th smallest distance is a property of the point
 * set, so any traversal order returns the same value, bit for bit. Queries
 * only read the tree and may run on many threads at once.
 *
 * Density (Eq. 7, the photon-mapping assumption that the k neighbours lie
 * on one plane through the query point):
 *     p(y) = k / (N pi r_k(y)^2)
 * w.r.t. surface area, for N points in all; r_k the distance to the k-th
 * nearest other point. */
#ifndef GI_KNN_H
#define GI_KNN_H

#include <stdint.h>

#include "pf_math.h"
#include "pf_result.h"

#define GI_KNN_MAX_K 64
#define GI_KNN_NONE 0xffffffffu

typedef struct gi_knn {
    uint32_t count, cap;
    pf_vec3 *pts;   /* copies of the points, by original index */
    uint32_t *idx;  /* the implicit tree: a permutation of 0..count-1 */
    pf_vec3 *tpts;  /* pts[idx[i]]: the points in tree order, so queries read memory in order */
    uint8_t *axis;  /* split axis of the node whose point is idx[i] */
} gi_knn;

/* Builds the tree over pts[0..count) (copied; count may be 0). Reuses the
 * tree's memory when it is large enough (no allocation in steady state). */
pf_result gi_knn_build(gi_knn *t, const pf_vec3 *pts, uint32_t count, pf_error *err);
void gi_knn_free(gi_knn *t);

/* Squared distance from q to its k-th nearest point of the tree, not
 * counting the point with index `exclude` (GI_KNN_NONE: none excluded).
 * INFINITY when fewer than k points qualify. 1 <= k <= GI_KNN_MAX_K. */
float gi_knn_kth_dist2(const gi_knn *t, pf_vec3 q, uint32_t k, uint32_t exclude);

/* Index (into the points given to gi_knn_build) of the point nearest to q,
 * the lowest index among equally near ones, so the answer is a property of
 * the point set; *dist2 (may be NULL) gets its squared distance.
 * GI_KNN_NONE for an empty tree. */
uint32_t gi_knn_nearest(const gi_knn *t, pf_vec3 q, float *dist2);
/* The same among the points for which ok(ctx, index) is true (GI_KNN_NONE
 * when none is). */
uint32_t gi_knn_nearest_where(const gi_knn *t, pf_vec3 q, int (*ok)(const void *ctx, uint32_t index),
                              const void *ctx, float *dist2);

/* Eq. 7: density w.r.t. area of N points, given the squared k-NN radius
 * (0 for r2 = INFINITY; INFINITY for r2 = 0). */
float gi_knn_density(uint32_t k, uint32_t n, float r2);

#endif
