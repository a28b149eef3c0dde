/* gi_delaunay: Delaunay triangulations of sampling points on the unit disc
 * and on the unit sphere, with the Voronoi quantities Incremental Instant
 * Radiosity needs (Laine 2007 Sec. 4.1, 4.3, 4.5-4.7):
 *   - the largest empty circle (dispersion, Eq. 1) and its centre, the
 *     cases of Sec. 4.6 (disc: Voronoi vertex, Voronoi edge meets the
 *     boundary circle, the boundary-only case; sphere: Voronoi vertex);
 *   - the Voronoi region area of every point (Sec. 4.7), clipped to the
 *     disc; on the sphere the spherical area (the regions sum to 4 pi);
 *   - Delaunay neighbours, for the deletion rule of Sec. 4.5.
 *
 * Robustness: every point is snapped to a grid of 2^-24 of the unit
 * (GI_DT_SCALE) and the predicates are exact in integer arithmetic:
 * orient2d in int64, incircle, the sphere's orient3d and its side tests in
 * __int128 (|coordinate| <= 2^24 + 1, so differences < 2^26, products of
 * three differences < 2^78, sums well inside 2^127). The triangulation is
 * therefore unique up to exactly cocircular points, where the insertion
 * order (Morton order of the grid cells, then index) decides: a rebuild
 * is deterministic.
 *
 * Disc: Bowyer-Watson with "ghost" triangles (a, b, INF) on the hull edges
 * (Shewchuk's convention: the ghost's circumcircle is the open half-plane
 * left of a->b plus the open segment ab), so the triangulation is closed
 * like a sphere and insertion never needs a super-triangle.
 * Sphere: the convex hull of the points (the paper uses a 3D Delaunay
 * tetrahedralization with CGAL; the hull of points on a sphere is the
 * spherical Delaunay triangulation, which the paper's Sec. 6 names as the
 * better choice). Incremental hull = Bowyer-Watson with the conflict test
 * "p sees the face". Snapped points are not exactly on the sphere; a point
 * the hull leaves inside (only possible when two directions agree to about
 * 1e-3 rad) is dropped, and in_dt[] says so.
 *
 * Degenerate sets (disc: fewer than 3 non-collinear points; sphere: fewer
 * than 4 non-coplanar) have no triangulation: the functions then answer by
 * brute force over fixed probe points (largest empty circle: 8192 grid
 * and boundary points on the disc, 4096 Fibonacci points on the sphere;
 * areas: nearest-site counts over 32768 / 16384), which is approximate but only
 * happens for a handful of points (a light's first samples, or after a
 * light jump invalidates almost everything).
 *
 * Vertex indices are the caller's (0..cap-1); the caller marks which are
 * present. */
#ifndef GI_DELAUNAY_H
#define GI_DELAUNAY_H

#include <stdint.h>

#include "pf_result.h"

#define GI_DT_SCALE 16777216.0 /* 2^24 grid steps per unit */
#define GI_DT_INF 0xffffffffu  /* the ghost vertex (disc) */

typedef enum gi_dt_domain { GI_DT_DISC = 0, GI_DT_SPHERE = 1 } gi_dt_domain;

typedef struct gi_dt_tri {
    uint32_t v[3]; /* CCW (disc) / CCW seen from outside (sphere); a ghost has one GI_DT_INF */
    uint32_t n[3]; /* n[i]: the triangle across the edge opposite v[i] */
    double c[3];   /* circumcentre (disc: x, y; sphere: unit outward normal) */
    double r2;     /* squared circumradius (sphere: squared chord to the vertices) */
    uint32_t alive;
} gi_dt_tri;

typedef struct gi_dt {
    gi_dt_domain domain;
    uint32_t cap;      /* vertex slots */
    int64_t (*ip)[3];  /* snapped integer coordinates (z = 0 on the disc) */
    double (*p)[3];    /* the same as doubles, in units */
    uint8_t *present;  /* the caller's set */
    uint8_t *in_dt;    /* present and a vertex of the triangulation */
    uint32_t *vt;      /* a triangle incident to each vertex */
    gi_dt_tri *tri;
    uint32_t tri_count, tri_cap, free_head, last;
    uint32_t solid;    /* number of live triangles (0: degenerate set) */
    /* scratch */
    uint32_t *stack, *cavity, *newt;
    double *poly; /* 2 x 2 (cap + 8) doubles: clipping buffers */
    uint64_t *order; /* rebuild: Morton key << 32 | index */
    uint32_t *by_v1; /* insertion: the fan triangle (v, x, .) by x (GI_DT_INF at cap) */
} gi_dt;

pf_result gi_dt_init(gi_dt *dt, gi_dt_domain domain, uint32_t cap, pf_error *err);
void gi_dt_free(gi_dt *dt);

/* Snaps a point to the grid (disc: x, y in [-1, 1]; sphere: a unit vector).
 * out receives the snapped value as doubles. */
void gi_dt_snap(gi_dt_domain domain, const double in[3], double out[3]);

/* Sets vertex v's point (snapped) and marks it present; no triangulation
 * change until gi_dt_rebuild or gi_dt_insert. */
void gi_dt_set_point(gi_dt *dt, uint32_t v, const double p[3]);
/* Rebuilds the triangulation of the present points (inserted in Morton
 * order of their grid cells, ties by index: deterministic). Points that
 * coincide with an earlier one (after snapping) or that the sphere's hull
 * leaves inside are marked absent (present = 0); the caller decides what
 * to do with them. */
pf_result gi_dt_rebuild(gi_dt *dt, pf_error *err);
/* Adds point p as vertex v (v not present) and updates the triangulation
 * incrementally (Bowyer-Watson). Returns 1 if v became a vertex, 0 if it
 * was rejected (coincident, or inside the sphere's hull): then v is not
 * present. */
int gi_dt_insert(gi_dt *dt, uint32_t v, const double p[3], pf_error *err);
/* Removes vertex v: locally (its star re-triangulated by Delaunay ear
 * clipping), or by a rebuild for tiny or degenerate sets. */
pf_result gi_dt_remove(gi_dt *dt, uint32_t v, pf_error *err);

/* The largest empty circle's centre (disc: z = 0; sphere: unit vector) and
 * its radius (Euclidean; on the sphere the chord, Sec. 4.3). With no points
 * the disc answers its centre and the sphere +z with radius 2. `kind`
 * (optional) receives 1 Voronoi vertex, 2 Voronoi edge meets the boundary,
 * 3 boundary-only case, 0 brute force. */
double gi_dt_largest_empty(const gi_dt *dt, double centre[3], int *kind);
/* The dispersion by brute force over `n` probe points (tests). */
double gi_dt_dispersion_brute(const gi_dt *dt, uint32_t n);

/* Area of each present vertex's Voronoi region (disc: clipped to the unit
 * disc), into area[0..cap) (0 for absent vertices). */
void gi_dt_voronoi_areas(gi_dt *dt, double *area);

/* Delaunay neighbours of v into nb (at most max); returns their count
 * (degenerate sets: every other present vertex). */
uint32_t gi_dt_neighbours(const gi_dt *dt, uint32_t v, uint32_t *nb, uint32_t max);

/* The deletion rule of Sec. 4.5: of the shortest Delaunay edge's two ends,
 * the one whose second-closest neighbour is nearer (ties: the higher
 * index). GI_DT_INF if fewer than 2 vertices. */
uint32_t gi_dt_deletion_candidate(const gi_dt *dt);

/* Number of present vertices. */
uint32_t gi_dt_count(const gi_dt *dt);

#endif
