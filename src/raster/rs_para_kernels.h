/* rs_para_kernels: the paraboloid renderer's front end and texel scan,
 * written once over the SIMD vocabulary (src/base/simd/simd.h) in
 * rs_para_kernels.c and compiled once per instruction set; rs_paraboloid.c
 * picks a table at run time (rs_para_kernels_for). Private to src/raster:
 * the types the renderer and its kernels share (the algorithm is described
 * at the top of rs_paraboloid.c).
 *
 * Every path computes, lane by lane, the same IEEE operations in the same
 * order as the scalar compile (no FMA: -ffp-contract=off and no -mfma), and
 * the lanes the float filter leaves undecided go through the one scalar
 * rs__para_resolve, so every path gives the same bits and the same
 * statistics (test_paraboloid). */
#ifndef RS_PARA_KERNELS_H
#define RS_PARA_KERNELS_H

#include <stdint.h>

#include "rs_paraboloid.h"

#define RS__UV_EPS 4e-6f      /* uv margin of every bound (float error of projections is ~5e-7) */
#define RS__TILE 8            /* tile side (texels) of the occlusion-culling depth maxima */
#define RS__LANES 16          /* triangles per front-end batch; cluster sizes are multiples of it */
#define RS__SUPER 16          /* clusters per super-cluster (partial renders' first cull) */
#define RS__FILTER 0x1p-17f   /* float filter: |g| > RS__FILTER |A||B| fixes the sign */

/* ------------------------------------------------------------------ types */

typedef struct rs__cluster {
    float cx, cy, cz, r; /* bounding sphere */
    uint32_t first, count;
} rs__cluster;

/* A level-of-detail group as a map selects it (rs_para_lod.h): its sphere,
 * and per level the error and the run of clusters. */
typedef struct rs__lod_sel {
    float cx, cy, cz, r;
    uint32_t levels;
    float err[8];
    uint32_t cl_first[8], cl_count[8];
} rs__lod_sel;

typedef struct rs__rect {
    int32_t i0, i1, j0, j1; /* inclusive texel range; empty when i0 > i1 or j0 > j1 */
} rs__rect;

/* The front end's survivors in one cluster, structure of arrays (the SIMD
 * front end compress-stores into it). */
typedef struct rs__batch {
    uint32_t n;
    uint32_t *tri;
    float *l[9];          /* local coordinates x0 y0 z0 x1 y1 z1 x2 y2 z2 */
    float *len[3];        /* |A|, |B|, |C| */
    float *pu[3], *pv[3]; /* projected vertices (when not crossing) */
    float *c2max;         /* largest squared chord (when not crossing) */
    int32_t *rect[4];     /* i0 i1 j0 j1 (when not crossing) */
    int32_t *crossing;    /* 1: crosses the tangent plane (bound made by rs__setup_triangle) */
} rs__batch;

/* A triangle after setup: what the texel loop needs. */
typedef struct rs__setup {
    float e[3][3];  /* oriented edge normals e'_k, float */
    float bound[3]; /* float filter bounds */
    float nf[3];    /* oriented plane normal N', float */
    float det;      /* det' (float) */
    float sgn;      /* s */
    /* the double path, made on first use */
    int have_d;
    double ed[3][3];
    const struct rs_para_context *ctx;
    const rs_para_frame *f;
    uint32_t tri;
} rs__setup;

/* One worker's scratch, in its own cache lines (the statistics are written
 * per triangle: two workers sharing a line would slow each other down). */
typedef struct rs__scratch {
    _Alignas(64) float *depth; /* R*R: nearest distance so far (INFINITY: nothing) */
    float *tile_max;     /* tiles*tiles: maximum depth over a tile's inside texels */
    uint8_t *tile_dirty; /* tiles*tiles: tile_max is stale (too large) */
    uint8_t *tile_skip;  /* tiles*tiles: the pass does not draw the tile (rs_para_render_box's classes) */
    uint8_t *tile_class; /* tiles*tiles: rs_para_render_box's class of each tile */
    rs__rect *crect;     /* per cluster: texel rectangle of its image */
    float *cnear;        /* per cluster: nearest possible hit distance */
    uint16_t *key;       /* sort keys */
    uint32_t *order, *order_tmp;
    void *batch_block;
    rs__batch batch;
    rs_para_stats stats;
    rs__rect limit;      /* the texels the map being drawn renders (all, or rs_para_render_box's) */
    int partial;         /* limit is not the whole map */
} rs__scratch;

struct rs_para_context {
    uint32_t res, tiles;
    uint32_t tri_count, tri_padded;
    uint32_t cluster_size, cluster_count;
    float *soa[13]; /* x0 y0 z0 x1 y1 z1 x2 y2 z2 nx ny nz emax, tri_padded each (zero padding) */
    float *soa_block;
    rs__cluster *clusters;
    /* every RS__LANES-triangle batch of the clusters (lane k: triangles
     * [k RS__LANES, ...), count 0 for padding) with its own sphere: partial
     * renders (rs_para_render_box) cull batches by it, since a cluster that
     * meets a small texel rectangle mostly holds triangles that do not */
    rs__cluster *lanes;
    uint32_t lane_count;
    /* every RS__SUPER consecutive clusters as one sphere (exact maps only,
     * NULL with levels of detail): a partial render skips the clusters of
     * a super-cluster whose image misses its texels without testing each */
    rs__cluster *supers;
    uint32_t super_count;
    uint8_t *cluster_moved; /* rs_para_render_box's scratch: the clusters holding moved triangles */
    /* rs_para_set_dynamic: the clusters holding a triangle that may move
     * (cluster_dynamic) and the others (cluster_static, its complement);
     * a static map (rs_para_render_split) draws the cluster_static ones */
    uint8_t *cluster_dynamic, *cluster_static;
    /* levels of detail (rs_para_lod.h; lod 0: none, every cluster is drawn) */
    float lod;
    uint32_t lod_count;
    struct rs__lod_sel *lod_groups;
    /* texel tables */
    float *u;                 /* R: u_i = (2i+1-R)/R (also v_j) */
    float *d2;                /* R: 2 u_i (D.x of column i, D.y of row j) */
    float *dz, *w;            /* R*R: 1 - (u^2 + v^2), 1 + (u^2 + v^2) */
    int32_t *row_lo, *row_hi; /* inside columns of row j */
    rs_simd simd;
    uint32_t scratch_count;
    rs__scratch **scratch; /* per worker, each 64-byte aligned */
};

/* Texel with direction (dx, dy, dz) given its three float edge values: 1 if
 * covered. Shared by every path (the scan calls it for the lanes the filter
 * left undecided); in rs_paraboloid.c. */
int rs__para_resolve(rs__setup *s, const float g[3], float dx, float dy, float dz, uint64_t *fallbacks);

/* One compiled kernel file: a table per instruction set.
 * front: the front end of one cluster, survivors appended to sc->batch
 *        (rs__draw_cluster step 3);
 * scan:  the exact test and nearest distance of one set-up triangle over the
 *        texels of rect; returns the texels tested;
 * visible: the lookup, for tests and batch callers. */
typedef struct rs_para_kernels {
    const char *isa; /* SIMD_NAME of the vocabulary it was compiled with */
    uint32_t lanes;  /* SIMD_W */
    void (*front)(const rs_para_context *ctx, rs__scratch *sc, const rs_para_frame *f, const rs__cluster *cl);
    uint64_t (*scan)(const rs_para_context *ctx, rs__scratch *sc, rs__setup *s, rs__rect r);
    /* rs_para_visible_lanes (rs_para_lookup.h) of `lanes` points (arrays of
     * `lanes`): bit i set iff point i is visible (rs_para_visible_scaled);
     * normals nx, ny, nz (all or none NULL) select the receiver-plane test */
    uint32_t (*visible)(const uint16_t *map, uint32_t resolution, float range, float bias_scale,
                        const rs_para_frame *f, const float *px, const float *py, const float *pz,
                        const float *cos_receiver, const float *nx, const float *ny, const float *nz);
} rs_para_kernels;

extern const rs_para_kernels rs_para_kernels_scalar;
extern const rs_para_kernels rs_para_kernels_avx2;   /* x86 only */
extern const rs_para_kernels rs_para_kernels_avx512; /* x86 only */

/* The table for a SIMD path (rs_paraboloid.c). */
const rs_para_kernels *rs_para_kernels_for(rs_simd simd);

#endif
