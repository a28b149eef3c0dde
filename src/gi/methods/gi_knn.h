/* gi_knn: k-nearest-neighbour queries over a fixed set of 3D points with a
 * k-d tree, for the kNN density estimates of Sequential Monte Carlo Instant
 * Radiosity (Hedman 2017 Sec. 3.2.4, Eq. 7; the paper builds a BVH on the
 * GPU, Sec. 4: any exact kNN structure gives the same answers).
 *
 * Tree: the points are permuted into a tree of buckets. A node holds the
 * points [lo, hi); with more than GI_KNN_LEAF points it splits on the axis
 * where its points spread most, at the median of a sample of their
 * coordinates (one branch-free partition pass; an exact median when the
 * sample's splits the node worse than 1:7): the points of [lo, mid) lie at
 * or below the split, those of [mid, hi) at or above it. Nodes are stored
 * in preorder (the left child follows its parent). A leaf's points are
 * scanned together from structure-of-arrays coordinates (the loop
 * vectorises). Build O(n log n), query about O(log n + k) for well-spread
 * points.
 *
 * Queries are exact: the k-th smallest distance and the nearest point
 * (lowest index among equally near ones) are properties of the point set,
 * each distance computed as dot(p - q, p - q) = (dx dx + dy dy) + dz dz, and
 * a subtree is skipped only when its splitting plane is farther than the
 * current answer: rounding is monotonic, so no point behind the plane can
 * come out nearer than the plane. Any tree over the same points, and any
 * traversal order, gives the same answers, bit for bit. Queries only read
 * the tree and may run on many threads at once.
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

#define GI_KNN_LEAF 16 /* points per leaf at most */

typedef struct gi_knn_rec gi_knn_rec;   /* the build's scratch (gi_knn.c) */
typedef struct gi_knn_node gi_knn_node; /* gi_knn.c */

typedef struct gi_knn {
    uint32_t count, cap, node_count, node_cap;
    float *x, *y, *z;    /* the points in tree order */
    float *nx, *ny, *nz; /* their normals (gi_knn_build_facing), in tree order */
    uint32_t *idx;       /* their indices in the array given to gi_knn_build */
    gi_knn_node *node;   /* preorder */
    gi_knn_rec *rec;     /* build scratch */
    int facing;          /* built with normals */
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

/* The tree with a unit normal per point, for gi_knn_nearest_facing. */
pf_result gi_knn_build_facing(gi_knn *t, const pf_vec3 *pts, const pf_vec3 *nrms, uint32_t count, pf_error *err);
/* gi_knn_nearest among the points whose normal m faces n's way:
 * pf_v3_dot(m, n) >= cos_min (a tree built by gi_knn_build_facing). */
uint32_t gi_knn_nearest_facing(const gi_knn *t, pf_vec3 q, pf_vec3 n, float cos_min, float *dist2);

/* Eq. 7: density w.r.t. area of N points, given the squared k-NN radius
 * (0 for r2 = INFINITY; INFINITY for r2 = 0). */
float gi_knn_density(uint32_t k, uint32_t n, float r2);

#endif
