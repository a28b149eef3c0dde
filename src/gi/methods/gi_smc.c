/* gi_smc: Sequential Monte Carlo Instant Radiosity (Hedman, Karras and
 * Lehtinen 2017, Sec. 3 and Algorithm 1; parameters of Sec. 3.2 and 5).
 *
 * A set Y of I VPLs lives from frame to frame. Each frame (one iteration of
 * Algorithm 1's loop; 100 iterations before the first frame, Sec. 3.2):
 *
 *   line 3     gi__smc_raycast_from_camera       X: directly visible points,
 *                                                one jittered pixel per cell of
 *                                                a fixed stratified grid on the
 *                                                frame's G-buffer
 *   line 4     gi__smc_indirectly_visible_vpls   mail-boxing + V rays from X
 *                                                towards invalid VPLs, two
 *                                                iterations (Sec. 3.2.2)
 *   line 5     gi__smc_raycast_from_points       ratio * I cosine-weighted rays
 *                                                from random points of X
 *   line 6     gi__smc_resample_candidates       ratio:1 weighted resampling
 *                                                without replacement towards a
 *                                                uniform area density (3.2.1)
 *   line 7     gi__smc_estimate_radiosities_candidates
 *   line 18    gi__smc_estimate_radiosities_vpls path tracer, gi_radiosity.h
 *                                                (3.2.3)
 *   line 8     gi__smc_estimate_densities_candidates  kNN, Eq. 7, k = 1
 *   line 19    gi__smc_estimate_densities_vpls   kNN, Eq. 7, k of Eq. 8
 *   (beyond)   gi__smc_estimate_areas_vpls       rendering areas: Voronoi
 *                                                cells measured with line 5's
 *                                                points (see "Units")
 *   (beyond)   gi__smc_photons                   rendered flux: light paths'
 *                                                hits binned into the cells
 *   line 9     gi__smc_count_undersampled        M_min, Eq. 9 (the 95% rule)
 *   line 10-13 gi__smc_invalidate_and_clamp      FINDSMALLESTINTENSITY until
 *                                                |INVALID| >= M_min, then
 *                                                CLAMPSIZE: remove <= M_max
 *   line 14-17 gi__smc_take_strongest            FINDLARGESTINTENSITY, repeated
 *   line 20    gi__smc_output                    the frame's VPL set
 *   line 1     gi__smc_initialize_vpls, then gi__smc_iterate (lines 3-19)
 *              `warmup` times, on the first update
 *
 * Units (what the frame receives). The paper's estimator (Eq. 5, 6) sums
 * over the I VPLs  (1/I) W G L(y_i) / p(y_i): a VPL y with reflected
 * radiance L(y) = albedo(y) E(y) / pi (E its irradiance, gi_radiosity.h) and
 * area density p(y) stands for a patch of area A_y = 1 / (I p(y)) radiating
 * L(y). A Lambertian patch of area A and radiance L has radiant intensity
 * L A cos; gi_vpl.h's intensity is exactly that at normal exitance:
 *     intensity = L(y) A_y = albedo E(y) / pi * 1 / (I p(y))
 * which is Instant Radiosity's "flux * albedo / pi" (gi_ir.c) with the flux
 * Phi = E(y) A_y arriving on the patch. With Eq. 7, A_y = pi r_k^2 / k
 * (--param area=knn, the paper). By default (area=voronoi, beyond the
 * paper) A_y is the area of y's Voronoi cell among the live VPLs, measured
 * with each iteration's intersection points and averaged over the VPL's
 * life (gi__smc_estimate_areas_vpls): the paper's discs add up to about
 * 1.3x the surface they cover on the repulsive set lines 10-17 keep, the
 * cells to the surface itself. Lines 8-17 rank with Eq. 7 as the paper
 * does either way; only what is rendered changes.
 * The paper's scalar intensity I(y) = L(y) / p(y) (Eq. 6) is used, as
 * luminance, only to rank VPLs and candidates (lines 9-17).
 *
 * Slots. A VPL keeps its index in the output array for its whole life; a
 * new VPL takes the lowest free slot. `moved` marks the slots whose VPL is
 * new since the previous frame (its paraboloid map must be rendered);
 * intensities change every frame (densities and lights) without a new map.
 *
 * Determinism. Every random number is a hash of (iteration, item, dim)
 * (gi_radiosity_random), every parallel job item writes only its own
 * outputs, and every choice (sorting, resampling, validation) is made
 * serially in a fixed order with index tie-breaks; so the VPL set is the
 * same bits for any thread count.
 *
 * Deviations from the paper (also in the README section):
 * - Resampling without replacement (Sec. 3.2.1) is done exactly with
 *   Efraimidis-Spirakis keys u^(1/w) (top I keys), instead of parallel
 *   random draws with atomics and at most 8 retries: same distribution
 *   without the retry cap, and deterministic.
 * - The intersection points' own density (for the resampling weights) is
 *   a kNN estimate among themselves with Eq. 8's k for their count.
 * - Two radiosity estimates per VPL (--param independent=1, the default):
 *   lines 9-12 rank VPLs by one (the winning candidate's own estimate,
 *   free), the frame renders with another from the VPL's own seed. With a
 *   single estimate (independent=0, the paper) the VPLs whose 16-sample
 *   estimate came out high survive and the low ones are removed, so over
 *   the iterations the rendered radiosities drift upwards (measured on the
 *   Cornell box, 2048 VPLs, k = 8, 100 warm-up iterations: 1.24x the
 *   reference with one estimate, 1.00x with two).
 * - Eq. 8 gives k = 1 up to I = 4095. On the evenly spread (blue noise) sets
 *   SMC produces, Eq. 7 then over-estimates each VPL's area: the disc to the
 *   k-th neighbour holds about k + 1 VPLs, not k (measured in the furnace:
 *   +29% at k = 1, +8.6% at k = 8). The default stays Eq. 8; --param k=8
 *   is the closer choice at I = 2048 (README).
 * - Line 18 re-estimates only the VPLs that are new or whose estimate
 *   predates a light change: the estimate is a pure function of the VPL's
 *   seed (from its id) and the lights, so for the others it would return
 *   the same bits. Candidates use seeds of their own (iteration, ray), so a
 *   new VPL's value is independent of the noisy estimate it won with.
 * - CLAMPSIZE removes the VPLs that failed the visibility test first (the
 *   weakest of them first), then the weakest valid ones.
 * - I is the frame's VPL budget (--vpls, default 256), not a --param: the
 *   frame sizes its buffers by it. The paper's setting is --vpls 2048.
 * - Empty slots (fewer candidates than free slots, e.g. the camera sees
 *   sky) are output as zero-intensity VPLs so the other slots keep their
 *   indices.
 *
 * Parameters (--param KEY=VALUE; paper values as defaults):
 *   Mmax=16        VPLs replaced per frame at most (Sec. 3.2)
 *   V=16           validation rays per visible point and pass (Sec. 3.2.2)
 *   vis_iters=2    validation passes (Sec. 3.2.2)
 *   points=1024    directly visible points X per frame (the paper does not
 *                  give |X|)
 *   ratio=16       intersection points per candidate (16:1, Sec. 3.2.1)
 *   spp=16         radiosity samples (Sec. 3.2.3)
 *   bounces=0      radiosity bounces, 0: the frame's --bounces (default 3, Sec. 5)
 *   warmup=100     iterations before the first frame (Sec. 3.2)
 *   k=0            kNN k of line 19 (ranking, and rendering with area=knn), 0: Eq. 8
 *   independent=1  separate ranking and rendering estimates (above)
 *   area=voronoi   rendering areas: voronoi (beyond the paper, above) or knn
 *                  (the paper's 1 / (I p), Eq. 7)
 *   area_window=32 with area=voronoi: the running mean of a VPL's cell
 *                  measures averages all of them up to this many, then
 *                  forgets at rate 1 / area_window (follows moving cells)
 *   flux=photons   with area=voronoi, what a VPL emits: the flux of light
 *                  paths binned into its cell (photons, beyond the paper,
 *                  "photons" below) or its radiosity estimate times its
 *                  cell's area (point)
 *   photons=16     light paths per VPL for flux=photons
 *   cycle=chains   with VPL cycling (--vpl-cycle C): chains (beyond the
 *                  paper, below) or whole (one chain over the whole set)
 *   chain_warmup=8 with cycle=chains: each chain's iterations before its
 *                  first frame (below; at most 1000)
 *
 * VPL cycling (gi_vpl_inputs.cycle = C >= 2, beyond the paper). The frame
 * keeps C x --vpls VPLs and shades one slice of --vpls a frame, slot i in
 * slice i mod C (gi_indirect.h). With cycle=whole, Algorithm 1 runs over
 * the whole set every frame, so an update costs C times a plain frame's
 * (ratio x C x --vpls rays, C x photons paths, kNN over all of them) and
 * still replaces only Mmax VPLs. With cycle=chains (the default) the set is
 * C independent chains of I_c = --vpls VPLs, chain c in slice c (its slot
 * j at c + j C), each the paper's algorithm with a budget of I_c and
 * random streams of its own: iteration keys from a seed of its own, VPL
 * ids c + C n (so the radiosity seeds differ), and photons from the c-th
 * run of photons x I_c indices of the Halton sequence. An update iterates
 * only the chain of the slice the frame shades (gi_vpl_inputs.slice), so a
 * frame costs a plain frame's update; the chains not shaded keep their
 * VPLs and intensities, except that VPLs on moved triangles go at once; a
 * light change reaches a chain at its next iteration, before it is shaded.
 * A chain's set is an estimate of the whole light on its own, so its
 * intensities are divided by C: the history's average over the C slices is
 * the mean of C independent SMC estimates. A chain is made (line 1 and
 * chain_warmup iterations, not warmup's 100: on the scenes measured
 * the warm-up changes the error by under 1% of it, docs/smc.md) when the
 * frame may first shade it or draw its maps (gi_vpl_inputs.live: all at
 * the first frame, or one after the other in the progressive warm-up);
 * until then its slots are empty (dark, id GI__SMC_NONE). */
#include <assert.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gi_knn.h"
#include "gi_lightpath.h"
#include "gi_radiosity.h"
#include "gi_vpl.h"

#define GI__SMC_NONE 0xffffffffu
/* chain_warmup's default: each chain's iterations before its first frame
 * (see "VPL cycling"; measured in docs/smc.md) */
#define GI__SMC_CHAIN_WARMUP 8u
/* its largest value: up to 64 chains are made in one frame (1..1000) */
#define GI__SMC_MAX_CHAIN_WARMUP 1000u

/* A live VPL of Y. */
typedef struct gi__smc_vpl {
    pf_vec3 pos;        /* on the surface, pushed off along ng */
    pf_vec3 ng, ns;     /* turned to the side it was found from */
    pf_vec3 albedo;
    pf_vec3 E;          /* irradiance estimate for rendering (gi_radiosity) */
    pf_vec3 phot;       /* flux=photons: the intensity of the photon hits in its cell */
    pf_vec3 E_rank;     /* the estimate lines 9-12 rank by (see "independent") */
    pf_vec3 mail_p, mail_n; /* the visible point that validated it (Sec. 3.2.2) */
    uint64_t seed;      /* radiosity seed, fixed for its life */
    uint32_t light_epoch; /* lights E was estimated with */
    uint32_t rank_epoch;  /* lights E_rank was estimated with */
    float density;      /* p(y), Eq. 7 */
    float intensity;    /* lum(L) / p, Eq. 6 */
    float area;         /* rendering area (area=voronoi): running mean of its cell's estimates */
    float cell;         /* this iteration's estimate of its cell's area */
    uint32_t area_n;    /* estimates in the mean (capped at area_window) */
    uint32_t id, alive, valid, born;
    uint32_t prim;        /* the triangle it sits on (moved geometry removes it) */
    uint32_t paths;       /* GI__SMC_PATHS_E / _RANK: the estimate's paths are in the cache */
    uint32_t paths_epoch; /* the cache's epoch they were traced in */
} gi__smc_vpl;

/* A point of X. */
typedef struct gi__smc_point {
    pf_vec3 p, ng, ns; /* normals facing the camera */
} gi__smc_point;

/* An intersection point of line 5, candidate after line 6. */
typedef struct gi__smc_cand {
    pf_vec3 surf;      /* surface point */
    pf_vec3 pos;       /* pushed off along ng */
    pf_vec3 ng, ns;    /* facing the ray's origin */
    pf_vec3 albedo;
    pf_vec3 E;
    uint64_t seed;
    uint32_t x;        /* index into X of the point it was traced from */
    uint32_t hit;
    uint32_t prim;     /* the triangle hit */
    float key;         /* resampling key, then density */
    float area;        /* the area it stands for among the intersection points: pi r_k^2 / k */
    float intensity;
} gi__smc_cand;

/* A sort record: a key, a class (sorted first), the item index (ties).
 * Records sort ascending by (cls, key, i), a total order (gi__smc_sort). */
typedef struct gi__smc_sortkey {
    float key;
    uint32_t cls, i;
} gi__smc_sortkey;

/* Sorts o[0, n), given in ascending i, ascending by (cls, key, i): the
 * order qsort with that comparison gave (-0 equal to +0; a -0 key comes
 * back +0), by a stable radix sort on (cls, key): the input's i order
 * breaks the ties. tmp: scratch of n records. */
static void gi__smc_sort(gi__smc_sortkey *o, gi__smc_sortkey *tmp, uint32_t n)
{
    uint32_t cnt[2048];
    uint32_t cls_any = 0;
    for (uint32_t i = 0; i < n; i++) {
        assert(i == 0 || o[i - 1].i < o[i].i);
        cls_any |= o[i].cls;
    }
    /* the key's bits in an unsigned order: x + 0 makes -0 into +0 */
    for (uint32_t i = 0; i < n; i++) {
        float f = o[i].key + 0.0f;
        uint32_t u;
        memcpy(&u, &f, sizeof u);
        u = (u & 0x80000000u) ? ~u : (u | 0x80000000u);
        memcpy(&o[i].key, &u, sizeof u); /* restored below */
    }
    gi__smc_sortkey *a = o, *b = tmp;
    for (uint32_t pass = 0; pass < 4; pass++) { /* 11, 11, 10 bits of the key, then the class */
        if (pass == 3 && !cls_any) break;
        uint32_t shift = pass * 11, bins = pass == 2 ? 1024u : (pass == 3 ? 2u : 2048u);
        memset(cnt, 0, sizeof(uint32_t) * bins);
        for (uint32_t i = 0; i < n; i++) {
            uint32_t u;
            memcpy(&u, &a[i].key, sizeof u);
            cnt[pass == 3 ? a[i].cls : (u >> shift) & (bins - 1)]++;
        }
        for (uint32_t k = 0, sum = 0; k < bins; k++) {
            uint32_t c = cnt[k];
            cnt[k] = sum, sum += c;
        }
        for (uint32_t i = 0; i < n; i++) {
            uint32_t u;
            memcpy(&u, &a[i].key, sizeof u);
            b[cnt[pass == 3 ? a[i].cls : (u >> shift) & (bins - 1)]++] = a[i];
        }
        gi__smc_sortkey *t = a;
        a = b, b = t;
    }
    if (a != o) memcpy(o, a, sizeof *o * n);
    for (uint32_t i = 0; i < n; i++) {
        uint32_t u;
        memcpy(&u, &o[i].key, sizeof u);
        u = (u & 0x80000000u) ? (u & 0x7fffffffu) : ~u;
        memcpy(&o[i].key, &u, sizeof u);
    }
}

/* Rendering areas: the paper's 1 / (I p(y)) from Eq. 7, or (the default)
 * each VPL's Voronoi cell measured with the intersection points. */
typedef enum gi__smc_area { GI__SMC_AREA_VORONOI = 0, GI__SMC_AREA_KNN } gi__smc_area;
/* What a VPL emits (area=voronoi): the photons' flux into its cell, or its
 * radiosity estimate at the VPL times its area. */
typedef enum gi__smc_flux { GI__SMC_FLUX_PHOTONS = 0, GI__SMC_FLUX_POINT } gi__smc_flux;

/* A photon's hit (flux=photons). */
typedef struct gi__smc_photon {
    pf_vec3 pos, nrm;
    pf_vec3 intensity; /* Phi albedo / pi / photons, W/sr (gi_lightpath_hit) */
    uint32_t valid;    /* a hit (paths end early) */
    uint32_t morton;   /* of its position (gi__smc_order_photons) */
    uint32_t bin;      /* the slot of the VPL it is binned to; GI__SMC_NONE when it lands where no
                          intersection point reaches (see gi__smc_photons) */
} gi__smc_photon;

typedef struct gi__smc_params {
    uint32_t m_max, v, vis_iters, points, ratio, spp, bounces, warmup, k, independent, area, area_window, flux,
        photons, cycle, chain_warmup;
} gi__smc_params;

/* cycle=: what VPL cycling (gi_vpl_inputs.cycle) gets (see "VPL cycling") */
typedef enum gi__smc_cycle { GI__SMC_CYCLE_CHAINS = 0, GI__SMC_CYCLE_WHOLE } gi__smc_cycle;

typedef struct gi__smc_state {
    gi__smc_params prm;
    /* the chain's random streams (see "VPL cycling"): iteration keys from
     * seed, VPL ids id_base + id_stride n (n = 0, 1, ...: next_id), photon
     * paths from Halton index halton0 + 1; 0x5eed, 0, 1, 0 for one chain */
    uint64_t seed;
    uint32_t id_base, id_stride, halton0;
    uint32_t I;               /* the budget the state was built for (0: not yet) */
    uint32_t next_id, iter, updates, light_epoch;
    int warmed;
    gi__smc_vpl *y;           /* I slots */
    uint32_t *prev_id;        /* per slot: the id output last frame */
    gi__smc_point *x;         /* X */
    uint32_t x_count, x_cap;
    gi__smc_cand *raw;        /* ratio * I intersection points */
    uint32_t raw_count, raw_cap;
    uint32_t *cand;           /* indices into raw: the candidates */
    uint32_t cand_count;
    uint8_t *vis_hit;         /* points * V validation results */
    uint32_t *list, *list2;   /* scratch index lists (I) */
    pf_vec3 *knn_pts;         /* scratch for tree builds (max(raw, I)) */
    pf_vec3 *knn_pts2, *knn_nrm; /* the same, for a second tree built at once (raw) */
    uint32_t *knn_slot;
    uint32_t *nearest;        /* per intersection point: tree index of its nearest VPL */
    gi__smc_photon *phot;     /* flux=photons: the hits of photons * I light paths, bounces slots each */
    uint32_t *phot_order;     /* the valid photons (phot_valid of them) in Morton order of their positions */
    uint32_t *phot_sort;      /* scratch of the sort: 3 x phot_cap */
    uint32_t phot_valid;
    pf_vec3 morton_lo, morton_scale; /* the scene's bounds -> [0, 1024)^3 */
    size_t phot_cap;
    uint32_t phot_count, phot_paths, phot_traced, phot_epoch, phot_bounces, raw_k;
    gi_knn raw_tree;          /* the last iteration's intersection points (the photons' region test) */
    int raw_tree_wanted;      /* this iteration builds raw_tree (the update's last, flux=photons) */
    gi__smc_sortkey *sortkeys, *sortkeys2; /* scratch (max(raw, I)) */
    gi_knn tree;
    pf_light *lights;         /* the lights E was estimated with */
    uint32_t light_count, light_cap, lights_tracked;
    const gi_vpl_inputs *in;  /* this update's inputs (for the jobs) */
    gi_radiosity_ctx rad;
    /* Line 18 under moving lights: each VPL's two estimates keep their
     * light-independent paths (gi_radiosity_trace), so a light change
     * re-gathers them with shadow rays only (gi__smc_estimate_radiosities_vpls) */
    gi_radiosity_vertex *paths; /* 2 estimates per slot, path_nv records each (NULL: no cache) */
    size_t paths_cap;           /* records allocated */
    uint32_t path_nv;           /* records per estimate (gi_radiosity_vertex_count) */
    uint32_t paths_epoch;       /* bumps when what the paths depend on changes */
    gi_radiosity_ctx paths_rad; /* the ctx they were traced with */
    gi_radiosity_vertex *rad_scratch; /* per worker: GI__SMC_RAD_GROUP estimates' records */
    size_t rad_scratch_cap;
    uint32_t *est;            /* line 18's estimates: slot * 2 + (0: E, 1: E_rank) */
    uint32_t est_count;
    pf_stage_times parts;     /* the last update's time by Hedman 2017 Table 2's columns */
    double t_mark;            /* gi__smc_part: when the running part began */
} gi__smc_state;

/* The method's state: one chain, or with VPL cycling and cycle=chains one
 * per slice (see "VPL cycling"). */
typedef struct gi__smc {
    gi__smc_params prm;
    gi__smc_state *chain;     /* `chains` of them */
    uint32_t chains;          /* 1, or the cycle C */
    uint32_t I;               /* chains: the whole set's budget the slots were laid out for (0: not yet) */
    uint32_t last;            /* the chain the last update iterated (the view's) */
    gi_vpl_set all;           /* chains: the whole set as output last */
    gi_vpl_set one;           /* chains: one chain's output (scratch) */
    pf_stage_times parts;     /* the last update's, all chains it ran together */
} gi__smc;

/* Chain c of n: its parameters and random streams (see "VPL cycling"). */
static void gi__smc_chain_init(gi__smc_state *s, const gi__smc_params *p, uint32_t c, uint32_t n)
{
    s->prm = *p;
    s->seed = c ? gi_radiosity_hash(0x5eed, ((uint64_t)1 << 32) | c) : 0x5eed;
    s->id_base = c, s->id_stride = n;
    s->halton0 = 0; /* set with the budget (gi__smc_update_chain) */
}

static float gi__rand(uint64_t key, uint32_t a, uint32_t b, uint32_t c) { return gi_radiosity_random(key, a, b, c); }

/* Hedman 2017 Table 2's columns of VPL sampling, which the update's time
 * is split into (timing only: nothing reads it back). */
#define GI__SMC_T_CAND "candidate sampling"       /* lines 3, 5, 9-17 */
#define GI__SMC_T_RESAMPLE "candidate resampling" /* line 6 */
#define GI__SMC_T_VIS "indirect visibility"       /* line 4 */
#define GI__SMC_T_RAD "radiosity"                 /* lines 7, 18 */
#define GI__SMC_T_KNN "kNN"                       /* lines 8, 19 (and the rendering areas) */
#define GI__SMC_T_PHOTONS "photons (beyond the paper)" /* flux=photons */

/* Charges the time since the last mark to `part` and sets a new mark. */
static void gi__smc_part(gi__smc_state *s, const char *part)
{
    double t = pf_time_now();
    pf_stage_add(&s->parts, part, (t - s->t_mark) * 1e3);
    s->t_mark = t;
}

/* ---------------------------------------------------------------- create / destroy */

static pf_result gi__smc_create(void **state, const gi_params *params, pf_error *err)
{
    static const char *const known[] = {"Mmax",    "V",      "vis_iters", "points", "ratio", "spp",
                                        "bounces", "warmup", "k",         "independent", "area", "area_window",
                                        "flux",    "photons", "cycle", "chain_warmup", NULL};
    static const char *const areas[] = {"voronoi", "knn", NULL};
    static const char *const fluxes[] = {"photons", "point", NULL};
    static const char *const cycles[] = {"chains", "whole", NULL};
    *state = NULL;
    gi__smc_params p = {16, 16, 2, 1024, 16, 16, 0, 100, 0, 1, GI__SMC_AREA_VORONOI, 32,
                        GI__SMC_FLUX_PHOTONS, 16, GI__SMC_CYCLE_CHAINS, GI__SMC_CHAIN_WARMUP};
    pf_result r = gi_params_check(params, "smc", known, err);
    if (r == PF_OK) r = gi_param_u32(params, "Mmax", 1, 1u << 20, &p.m_max, err);
    if (r == PF_OK) r = gi_param_u32(params, "V", 0, 1024, &p.v, err);
    if (r == PF_OK) r = gi_param_u32(params, "vis_iters", 0, 16, &p.vis_iters, err);
    if (r == PF_OK) r = gi_param_u32(params, "points", 1, 1u << 16, &p.points, err);
    if (r == PF_OK) r = gi_param_u32(params, "ratio", 1, 256, &p.ratio, err);
    if (r == PF_OK) r = gi_param_u32(params, "spp", 1, GI_RADIOSITY_MAX_SPP, &p.spp, err);
    if (r == PF_OK) r = gi_param_u32(params, "bounces", 0, GI_RADIOSITY_MAX_BOUNCES, &p.bounces, err);
    if (r == PF_OK) r = gi_param_u32(params, "warmup", 1, 100000, &p.warmup, err);
    if (r == PF_OK) r = gi_param_u32(params, "k", 0, GI_KNN_MAX_K, &p.k, err);
    if (r == PF_OK) r = gi_param_u32(params, "independent", 0, 1, &p.independent, err);
    if (r == PF_OK) r = gi_param_choice(params, "area", areas, &p.area, err);
    if (r == PF_OK) r = gi_param_u32(params, "area_window", 1, 1u << 20, &p.area_window, err);
    if (r == PF_OK) r = gi_param_choice(params, "flux", fluxes, &p.flux, err);
    if (r == PF_OK) r = gi_param_u32(params, "photons", 1, 256, &p.photons, err);
    if (r == PF_OK) r = gi_param_choice(params, "cycle", cycles, &p.cycle, err);
    if (r == PF_OK) r = gi_param_u32(params, "chain_warmup", 1, GI__SMC_MAX_CHAIN_WARMUP, &p.chain_warmup, err);
    if (r == PF_OK && p.area == GI__SMC_AREA_KNN) p.flux = GI__SMC_FLUX_POINT; /* the paper, all of it */
    if (r != PF_OK) return r;
    gi__smc *w = calloc(1, sizeof *w);
    gi__smc_state *s = calloc(1, sizeof *s);
    if (!w || !s) {
        free(w), free(s);
        return pf_error_set(err, PF_ERR_OUT_OF_MEMORY, "out of memory");
    }
    gi__smc_chain_init(s, &p, 0, 1);
    w->prm = p;
    w->chain = s;
    w->chains = 1;
    *state = w;
    return PF_OK;
}

static void gi__smc_free_buffers(gi__smc_state *s)
{
    free(s->y), free(s->prev_id), free(s->x), free(s->raw), free(s->cand), free(s->vis_hit);
    free(s->list), free(s->list2), free(s->knn_pts), free(s->knn_slot), free(s->nearest), free(s->lights);
    free(s->phot), free(s->phot_order), free(s->phot_sort);
    s->phot = NULL, s->phot_order = NULL, s->phot_sort = NULL;
    free(s->paths), free(s->rad_scratch), free(s->est);
    s->paths = NULL, s->rad_scratch = NULL, s->est = NULL;
    s->paths_cap = s->rad_scratch_cap = 0;
    gi_knn_free(&s->raw_tree);
    free(s->sortkeys), free(s->sortkeys2), free(s->knn_pts2), free(s->knn_nrm);
    s->sortkeys = s->sortkeys2 = NULL;
    s->knn_pts2 = s->knn_nrm = NULL;
    s->light_count = s->light_cap = s->lights_tracked = 0;
    gi_knn_free(&s->tree);
    s->y = NULL, s->prev_id = NULL, s->x = NULL, s->raw = NULL, s->cand = NULL, s->vis_hit = NULL;
    s->list = s->list2 = NULL, s->knn_pts = NULL, s->knn_slot = NULL, s->nearest = NULL, s->lights = NULL;
}

static void gi__smc_free_chains(gi__smc *w)
{
    for (uint32_t c = 0; c < w->chains; c++) gi__smc_free_buffers(&w->chain[c]);
    free(w->chain);
    w->chain = NULL;
    w->chains = 0;
}

static void gi__smc_destroy(void *state)
{
    gi__smc *w = state;
    if (!w) return;
    gi__smc_free_chains(w);
    gi_vpl_set_free(&w->all);
    gi_vpl_set_free(&w->one);
    free(w);
}

/* All buffers for a budget of I VPLs, once (or again when I changes). */
static pf_result gi__smc_alloc(gi__smc_state *s, uint32_t I, pf_error *err)
{
    gi__smc_free_buffers(s);
    uint64_t raw = (uint64_t)s->prm.ratio * I;
    if (raw > (1u << 26))
        return pf_error_set(err, PF_ERR_ARGUMENT, "smc: ratio %u x %u VPLs is too many rays", s->prm.ratio, I);
    s->I = I;
    s->raw_cap = (uint32_t)raw;
    s->x_cap = s->prm.points;
    uint32_t big = s->raw_cap > I ? s->raw_cap : I;
    s->y = calloc(I, sizeof *s->y);
    s->prev_id = malloc(sizeof(uint32_t) * I);
    s->x = calloc(s->x_cap, sizeof *s->x);
    s->raw = calloc(s->raw_cap, sizeof *s->raw);
    s->cand = calloc(I, sizeof(uint32_t));
    s->vis_hit = calloc((size_t)s->x_cap * (s->prm.v ? s->prm.v : 1), 1);
    s->list = calloc(I, sizeof(uint32_t));
    s->list2 = calloc(I, sizeof(uint32_t));
    s->knn_pts = calloc(big, sizeof(pf_vec3));
    s->knn_pts2 = calloc(big, sizeof(pf_vec3));
    s->knn_nrm = calloc(big, sizeof(pf_vec3));
    s->sortkeys2 = calloc(big, sizeof *s->sortkeys2);
    s->knn_slot = calloc(big, sizeof(uint32_t));
    s->nearest = calloc(s->raw_cap ? s->raw_cap : 1, sizeof(uint32_t));
    s->phot_count = 0, s->phot_cap = 0, s->phot_traced = 0, s->phot_valid = 0;
    s->sortkeys = calloc(big, sizeof *s->sortkeys);
    s->est = calloc(2 * (size_t)I, sizeof(uint32_t));
    if (!s->est || !s->sortkeys || !s->sortkeys2 || !s->knn_pts2 || !s->knn_nrm || !s->y || !s->prev_id || !s->x || !s->raw || !s->cand || !s->vis_hit || !s->list || !s->list2 ||
        !s->knn_pts || !s->knn_slot || !s->nearest) {
        gi__smc_free_buffers(s);
        s->I = 0;
        return pf_error_set(err, PF_ERR_OUT_OF_MEMORY, "smc: out of memory for %u VPLs", I);
    }
    for (uint32_t i = 0; i < I; i++) s->prev_id[i] = GI__SMC_NONE - 1u; /* nothing output yet */
    s->warmed = 0;
    pf_result r = gi_knn_build_facing(&s->tree, s->knn_pts, s->knn_nrm, big, err); /* size the trees once */
    if (r == PF_OK && s->prm.flux == GI__SMC_FLUX_PHOTONS)
        r = gi_knn_build_facing(&s->raw_tree, s->knn_pts2, s->knn_nrm, s->raw_cap ? s->raw_cap : 1, err);
    return r;
}

/* ---------------------------------------------------------------- lights */

/* Bumps light_epoch when the scene's punctual lights differ from the ones
 * the radiosities were estimated with (area lights are static). The copy
 * grows only when the scene has more lights than ever before. */
static pf_result gi__smc_track_lights(gi__smc_state *s, const pf_scene *scene, pf_error *err)
{
    uint32_t n = scene->light_count;
    if (s->lights_tracked && s->light_count == n && (!n || !memcmp(s->lights, scene->lights, sizeof(pf_light) * n)))
        return PF_OK;
    if (n > s->light_cap) {
        pf_light *l = realloc(s->lights, sizeof(pf_light) * n);
        if (!l) return pf_error_set(err, PF_ERR_OUT_OF_MEMORY, "out of memory");
        s->lights = l;
        s->light_cap = n;
    }
    if (n) memcpy(s->lights, scene->lights, sizeof(pf_light) * n);
    s->light_count = n;
    s->lights_tracked = 1;
    s->light_epoch++;
    return PF_OK;
}

/* Moved geometry (gi_motion.h). Hedman 2017 Sec. 1 and 6: SMC
 * "is able to illuminate moving objects": its VPLs are validated every
 * frame by the mail-boxed visibility rays of line 4, which, cast against
 * the updated Embree scene, catch the VPLs a moved object now hides from
 * the camera's points, and lines 5-17 sample the posed surfaces. Beyond the
 * paper (its moving objects carry no VPLs of their own): a VPL that sits on
 * a moved triangle is removed at once (its position is where the surface
 * was; lines 14-17 refill the slot this frame), and, since moved geometry
 * can shadow or light any VPL's surroundings, every radiosity estimate is
 * stale, as under a moving light: the light epoch is bumped (line 18
 * re-estimates, the photons are traced again) and the cache of the
 * estimates' light-independent paths is emptied. */
static void gi__smc_motion(gi__smc_state *s, const gi_motion *m)
{
    if (!gi_motion_any(m)) return;
    for (uint32_t i = 0; i < s->I; i++) {
        gi__smc_vpl *v = &s->y[i];
        if (v->alive && gi_motion_tri(m, v->prim)) v->alive = 0, v->valid = 0;
    }
    s->light_epoch++;
    s->paths_epoch++;
}

/* ---------------------------------------------------------------- line 3 */

/* X: one pixel per cell of a gx x gy grid over the image (gx gy >= points),
 * jittered inside its cell by the iteration's hash; pixels that see nothing
 * are skipped. Normals are turned to face the camera (the G-buffer's
 * shading normal already does; the geometric one is the triangle's). */
static void gi__smc_raycast_from_camera(gi__smc_state *s, const gi_vpl_inputs *in, uint64_t key)
{
    const rs_gbuffer *g = in->gbuf;
    uint32_t W = g->width, H = g->height;
    double want = (double)s->prm.points;
    uint32_t gx = (uint32_t)ceil(sqrt(want * W / H));
    if (gx < 1) gx = 1;
    if (gx > W) gx = W;
    uint32_t gy = (uint32_t)((s->prm.points + gx - 1) / gx);
    if (gy > H) gy = H;
    s->x_count = 0;
    for (uint32_t cy = 0; cy < gy; cy++)
        for (uint32_t cx = 0; cx < gx && s->x_count < s->x_cap; cx++) {
            uint32_t cell = cy * gx + cx;
            uint32_t x0 = (uint32_t)((uint64_t)cx * W / gx), x1 = (uint32_t)((uint64_t)(cx + 1) * W / gx);
            uint32_t y0 = (uint32_t)((uint64_t)cy * H / gy), y1 = (uint32_t)((uint64_t)(cy + 1) * H / gy);
            if (x1 <= x0 || y1 <= y0) continue;
            uint32_t px = x0 + (uint32_t)(gi__rand(key, 1, cell, 0) * (float)(x1 - x0));
            uint32_t py = y0 + (uint32_t)(gi__rand(key, 1, cell, 1) * (float)(y1 - y0));
            if (px >= x1) px = x1 - 1;
            if (py >= y1) py = y1 - 1;
            size_t i = (size_t)py * W + px;
            if (g->prim[i] == RS_GBUFFER_EMPTY) continue;
            gi__smc_point *X = &s->x[s->x_count++];
            X->p = pf_v3(g->pos_x[i], g->pos_y[i], g->pos_z[i]);
            X->ns = pf_v3(g->nrm_x[i], g->nrm_y[i], g->nrm_z[i]);
            X->ng = pf_scene_face_normal(in->scene, g->prim[i]);
            if (pf_v3_dot(X->ng, pf_v3_sub(in->camera->eye, X->p)) < 0.0f) X->ng = pf_v3_scale(X->ng, -1.0f);
            if (pf_v3_dot(X->ns, X->ng) <= 0.0f) X->ns = X->ng;
        }
}

/* ---------------------------------------------------------------- line 4 */

/* The ray from the camera to point p (on a surface facing n), or 0 when p
 * is behind its surface as seen from the camera or outside the frustum. */
static int gi__smc_camera_ray(const gi_vpl_inputs *in, pf_vec3 p, pf_vec3 n, pf_ray *r)
{
    const pf_camera *c = in->camera;
    pf_vec3 d = pf_v3_sub(p, c->eye);
    if (!(pf_v3_dot(n, d) < 0.0f)) return 0;
    float z = pf_v3_dot(d, c->forward);
    if (!(z > c->znear) || (c->zfar > 0.0f && z > c->zfar)) return 0;
    float th = tanf(0.5f * c->yfov), aspect = (float)in->width / (float)in->height;
    float sx = pf_v3_dot(d, c->right) / (z * th * aspect), sy = pf_v3_dot(d, c->up) / (z * th);
    if (!(fabsf(sx) <= 1.0f) || !(fabsf(sy) <= 1.0f)) return 0;
    r->org = c->eye;
    r->dir = pf_v3_sub(pf_rt_offset_origin(p, n, n), c->eye);
    r->tnear = 0.0f;
    r->tfar = 1.0f - 1.0e-4f;
    return 1;
}

/* The shadow ray from a visible point to a VPL, or 0 when they do not face
 * each other (the VPL lights only its front hemisphere). */
static int gi__smc_point_to_vpl_ray(const gi__smc_point *X, const gi__smc_vpl *v, pf_ray *r)
{
    pf_vec3 d = pf_v3_sub(v->pos, X->p);
    if (!(pf_v3_dot(X->ng, d) > 0.0f) || !(pf_v3_dot(v->ng, d) < 0.0f)) return 0;
    r->org = pf_rt_offset_origin(X->p, X->ng, X->ng);
    r->dir = pf_v3_sub(v->pos, r->org);
    r->tnear = 0.0f;
    r->tfar = 1.0f - 1.0e-4f;
    return 1;
}

/* VPLs [64 chunk, 64 chunk + 64): valid if the camera still sees their
 * mail-box point (in front, in the frustum, one unoccluded ray). */
static void gi__smc_mailbox_job(void *ctx, uint32_t chunk, uint32_t worker)
{
    (void)worker;
    gi__smc_state *s = ctx;
    pf_ray rays[64];
    uint32_t who[64], q = 0;
    uint8_t occ[64];
    for (uint32_t i = chunk * 64; i < s->I && i < chunk * 64 + 64; i++) {
        gi__smc_vpl *v = &s->y[i];
        if (!v->alive) continue;
        v->valid = 0;
        if (gi__smc_camera_ray(s->in, v->mail_p, v->mail_n, &rays[q])) who[q++] = i;
    }
    if (!q) return;
    pf_rt_occluded(s->in->rt, rays, occ, q);
    for (uint32_t k = 0; k < q; k++) s->y[who[k]].valid = !occ[k];
}

typedef struct gi__smc_vis_ctx {
    gi__smc_state *s;
    uint64_t key;
    uint32_t pass, n_invalid;
} gi__smc_vis_ctx;

/* Point j casts V rays towards randomly chosen invalid VPLs (s->list). */
static void gi__smc_validate_job(void *ctx, uint32_t j, uint32_t worker)
{
    (void)worker;
    gi__smc_vis_ctx *c = ctx;
    gi__smc_state *s = c->s;
    uint32_t V = s->prm.v;
    pf_ray rays[1024];
    uint32_t who[1024], q = 0;
    uint8_t occ[1024];
    memset(s->vis_hit + (size_t)j * V, 0, V);
    for (uint32_t v = 0; v < V; v++) {
        uint32_t pick = (uint32_t)(gi__rand(c->key, 2 + c->pass, j, v) * (float)c->n_invalid);
        if (pick >= c->n_invalid) pick = c->n_invalid - 1;
        if (gi__smc_point_to_vpl_ray(&s->x[j], &s->y[s->list[pick]], &rays[q])) who[q++] = v;
    }
    if (!q) return;
    pf_rt_occluded(s->in->rt, rays, occ, q);
    for (uint32_t k = 0; k < q; k++) s->vis_hit[(size_t)j * V + who[k]] = occ[k] ? 0 : 1;
}

/* INVALID <- Y \ INDIRECTLYVISIBLEVPLS(X, Y), Sec. 3.2.2: a VPL is valid if
 * the camera still sees its mail-box point; then `vis_iters` passes in
 * which every point of X casts V rays towards randomly chosen VPLs that
 * are still invalid; a VPL a ray reaches is valid and takes that point as
 * its mail box (the first such ray in (point, ray) order). */
static void gi__smc_indirectly_visible_vpls(gi__smc_state *s, const gi_vpl_inputs *in, uint64_t key)
{
    pf_jobs_parallel_for(in->jobs, gi__smc_mailbox_job, s, (s->I + 63) / 64, 1);
    for (uint32_t pass = 0; pass < s->prm.vis_iters && s->prm.v > 0 && s->x_count > 0; pass++) {
        uint32_t n = 0;
        for (uint32_t i = 0; i < s->I; i++)
            if (s->y[i].alive && !s->y[i].valid) s->list[n++] = i;
        if (!n) break;
        gi__smc_vis_ctx c = {s, key, pass, n};
        pf_jobs_parallel_for(in->jobs, gi__smc_validate_job, &c, s->x_count, 4);
        for (uint32_t j = 0; j < s->x_count; j++)
            for (uint32_t v = 0; v < s->prm.v; v++) {
                if (!s->vis_hit[(size_t)j * s->prm.v + v]) continue;
                uint32_t pick = (uint32_t)(gi__rand(key, 2 + pass, j, v) * (float)n);
                if (pick >= n) pick = n - 1;
                gi__smc_vpl *y = &s->y[s->list[pick]];
                if (y->valid) continue;
                y->valid = 1;
                y->mail_p = s->x[j].p;
                y->mail_n = s->x[j].ng;
            }
    }
}

/* ---------------------------------------------------------------- line 5 */

#define GI__SMC_RAY_CHUNK 64

typedef struct gi__smc_ray_ctx {
    gi__smc_state *s;
    uint64_t key;
} gi__smc_ray_ctx;

static void gi__smc_trace_job(void *ctx, uint32_t chunk, uint32_t worker)
{
    (void)worker;
    gi__smc_ray_ctx *c = ctx;
    gi__smc_state *s = c->s;
    uint32_t r0 = chunk * GI__SMC_RAY_CHUNK;
    uint32_t n = s->raw_cap - r0 < GI__SMC_RAY_CHUNK ? s->raw_cap - r0 : GI__SMC_RAY_CHUNK;
    pf_ray rays[GI__SMC_RAY_CHUNK];
    pf_hit hits[GI__SMC_RAY_CHUNK];
    uint32_t from[GI__SMC_RAY_CHUNK];
    memset(rays, 0, sizeof rays);
    for (uint32_t i = 0; i < n; i++) {
        uint32_t r = r0 + i;
        uint32_t j = (uint32_t)(gi__rand(c->key, 10, r, 0) * (float)s->x_count);
        if (j >= s->x_count) j = s->x_count - 1;
        const gi__smc_point *X = &s->x[j];
        float u0 = gi__rand(c->key, 10, r, 1), u1 = gi__rand(c->key, 10, r, 2);
        rays[i] = gi_radiosity_bounce_ray(X->p, X->ns, X->ng, u0, u1);
        from[i] = j;
    }
    pf_rt_intersect(s->in->rt, rays, hits, n);
    for (uint32_t i = 0; i < n; i++) {
        gi__smc_cand *C = &s->raw[r0 + i];
        memset(C, 0, sizeof *C);
        C->seed = gi_radiosity_hash(c->key, r0 + i);
        C->x = from[i];
        if (hits[i].prim == PF_RT_MISS) continue;
        pf_surface sf;
        pf_rt_surface(s->in->rt, &hits[i], GI_VPL_ALBEDO_LOD, &sf); /* the VPL's albedo: gi_vpl.h's rule */
        int back = pf_v3_dot(sf.ng, rays[i].dir) > 0.0f;
        C->surf = sf.p;
        C->ng = back ? pf_v3_scale(sf.ng, -1.0f) : sf.ng;
        C->ns = back ? pf_v3_scale(sf.ns, -1.0f) : sf.ns;
        if (pf_v3_dot(C->ns, C->ng) <= 0.0f) C->ns = C->ng;
        C->pos = pf_rt_offset_origin(sf.p, C->ng, C->ng);
        C->albedo = pf_v3(sf.albedo[0], sf.albedo[1], sf.albedo[2]);
        C->hit = 1;
        C->prim = hits[i].prim;
    }
}

/* Y^ <- RAYCASTFROMPOINTS(X): ratio * I rays, each from a random point of X
 * in a cosine-weighted direction; misses are dropped (raw_count hits,
 * compacted in ray order). */
static void gi__smc_raycast_from_points(gi__smc_state *s, const gi_vpl_inputs *in, uint64_t key)
{
    s->raw_count = 0;
    if (!s->x_count) return;
    gi__smc_ray_ctx c = {s, key};
    pf_jobs_parallel_for(in->jobs, gi__smc_trace_job, &c, (s->raw_cap + GI__SMC_RAY_CHUNK - 1) / GI__SMC_RAY_CHUNK, 1);
    for (uint32_t r = 0; r < s->raw_cap; r++)
        if (s->raw[r].hit) s->raw[s->raw_count++] = s->raw[r];
}

/* ---------------------------------------------------------------- line 6 */

typedef struct gi__smc_key_ctx {
    gi__smc_state *s;
    uint64_t key;
    uint32_t k;
} gi__smc_key_ctx;

static void gi__smc_key_job(void *ctx, uint32_t chunk, uint32_t worker)
{
    (void)worker;
    gi__smc_key_ctx *c = ctx;
    gi__smc_state *s = c->s;
    /* in the tree's order (s->tree.idx: a permutation of the points), so
     * that consecutive queries are neighbours and walk the same branches */
    for (uint32_t j = chunk * 256; j < s->raw_count && j < chunk * 256 + 256; j++) {
        const uint32_t i = s->tree.idx[j];
        /* weight w = 1 / p(point) ~ r_k^2 (the constant k / (N pi) cancels) */
        float r2 = gi_knn_kth_dist2(&s->tree, s->raw[i].surf, c->k, i);
        float u = 1.0f - gi__rand(c->key, 20, i, 0); /* (0, 1] */
        /* Efraimidis-Spirakis: the I largest u^(1/w), i.e. log(u) / w */
        float key = !(r2 > 0.0f) ? -INFINITY : (isinf(r2) ? 0.0f : logf(u) / r2);
        s->raw[i].key = key;
        /* 1 / (raw_count p) by Eq. 7: the area this point stands for */
        s->raw[i].area = r2 > 0.0f && isfinite(r2) ? (float)(PF_PI * (double)r2 / (double)c->k) : 0.0f;
    }
}

/* Y^ <- RESAMPLECANDIDATES(Y^): draws min(I, hits) of the intersection
 * points without replacement with probability ~ 1 / (their density), so the
 * candidates are about uniform in area (Sec. 3.2.1, rate ratio:1). */
typedef struct gi__smc_build_ctx {
    gi__smc_state *s;
    pf_result r[2];
    pf_error err[2];
} gi__smc_build_ctx;

/* Item 0: the intersection points' tree of line 6 (their surface points);
 * item 1: the photons' region tree (the pushed-off points and normals). */
static void gi__smc_build_job(void *ctx, uint32_t item, uint32_t worker)
{
    (void)worker;
    gi__smc_build_ctx *c = ctx;
    gi__smc_state *s = c->s;
    c->r[item] = item == 0 ? gi_knn_build(&s->tree, s->knn_pts, s->raw_count, &c->err[item])
                           : gi_knn_build_facing(&s->raw_tree, s->knn_pts2, s->knn_nrm, s->raw_count, &c->err[item]);
}

static pf_result gi__smc_resample_candidates(gi__smc_state *s, const gi_vpl_inputs *in, uint64_t key, pf_error *err)
{
    s->cand_count = 0;
    if (!s->raw_count) return PF_OK;
    for (uint32_t i = 0; i < s->raw_count; i++) s->knn_pts[i] = s->raw[i].surf;
    if (s->raw_tree_wanted)
        for (uint32_t i = 0; i < s->raw_count; i++) s->knn_pts2[i] = s->raw[i].pos, s->knn_nrm[i] = s->raw[i].ns;
    gi__smc_build_ctx b = {s, {PF_OK, PF_OK}, {{0}}};
    pf_jobs_parallel_for(in->jobs, gi__smc_build_job, &b, s->raw_tree_wanted ? 2 : 1, 1);
    for (int i = 0; i < 2; i++)
        if (b.r[i] != PF_OK) {
            *err = b.err[i];
            return b.r[i];
        }
    uint32_t k = (uint32_t)floor(sqrt((double)s->raw_count) / 32.0);
    gi__smc_key_ctx c = {s, key, k < 1 ? 1 : (k > GI_KNN_MAX_K ? GI_KNN_MAX_K : k)};
    s->raw_k = c.k;
    pf_jobs_parallel_for(in->jobs, gi__smc_key_job, &c, (s->raw_count + 255) / 256, 1);
    /* the top keys: sorted descending (ascending on -key), ties by index */
    gi__smc_sortkey *o = s->sortkeys;
    for (uint32_t i = 0; i < s->raw_count; i++) o[i] = (gi__smc_sortkey){-s->raw[i].key, 0, i};
    gi__smc_sort(o, s->sortkeys2, s->raw_count);
    s->cand_count = s->raw_count < s->I ? s->raw_count : s->I;
    for (uint32_t i = 0; i < s->cand_count; i++) s->cand[i] = o[i].i;
    return PF_OK;
}

/* ---------------------------------------------------------------- lines 7 and 18 */

/* Estimates per job item: their shadow and bounce rays share packets. */
#define GI__SMC_RAD_GROUP 4
/* The path cache's size limit (records of all VPLs' two estimates, 64 bytes
 * each): beyond it line 18 traces every estimate again, which gives the
 * same bits, only slower. 2048 VPLs at spp 16 and 3 bounces take 12 MiB. */
#define GI__SMC_PATHS_MAX ((size_t)256 << 20)
#define GI__SMC_PATHS_E 1u
#define GI__SMC_PATHS_RANK 2u
#define GI__SMC_RANK_SEED 0x52414e4bull

/* The light-independent part of every estimate depends on the scene, the
 * area lights, spp and bounces: a change of any of them empties the cache.
 * Sizes the cache and the per-worker scratch (once, or when they grow). */
static pf_result gi__smc_paths_prepare(gi__smc_state *s, const gi_vpl_inputs *in, pf_error *err)
{
    const gi_radiosity_ctx *r = &s->rad;
    uint32_t nv = gi_radiosity_vertex_count(r);
    if (r->scene != s->paths_rad.scene || r->rt != s->paths_rad.rt || r->area != s->paths_rad.area ||
        r->spp != s->paths_rad.spp || r->bounces != s->paths_rad.bounces || nv != s->path_nv) {
        s->paths_epoch++;
        s->paths_rad = *r;
        s->path_nv = nv;
    }
    uint32_t workers = in->jobs ? pf_jobs_thread_count(in->jobs) : 1;
    size_t scratch = (size_t)workers * GI__SMC_RAD_GROUP * nv;
    if (scratch > s->rad_scratch_cap) {
        gi_radiosity_vertex *p = realloc(s->rad_scratch, scratch * sizeof *p);
        if (!p) return pf_error_set(err, PF_ERR_OUT_OF_MEMORY, "smc: out of memory for the radiosity paths");
        s->rad_scratch = p, s->rad_scratch_cap = scratch;
    }
    size_t cache = (size_t)s->I * 2 * nv;
    if (cache * sizeof(gi_radiosity_vertex) > GI__SMC_PATHS_MAX / s->id_stride)
        cache = 0; /* too large (chains share the cap, id_stride of them): no cache */
    if (cache > s->paths_cap) {
        free(s->paths);
        s->paths = malloc(cache * sizeof *s->paths);
        s->paths_cap = s->paths ? cache : 0;
        s->paths_epoch++; /* what was cached is gone (a failed allocation only slows line 18) */
    } else if (!cache && s->paths_cap) {
        free(s->paths);
        s->paths = NULL, s->paths_cap = 0;
        s->paths_epoch++;
    }
    return PF_OK;
}

/* Line 7 for candidates [GROUP i, GROUP i + GROUP): traced and gathered at
 * once in the worker's scratch (a candidate is estimated only once). */
static void gi__smc_rad_cand_job(void *ctx, uint32_t item, uint32_t worker)
{
    gi__smc_state *s = ctx;
    gi_radiosity_site y[GI__SMC_RAD_GROUP] = {0};
    uint64_t seed[GI__SMC_RAD_GROUP] = {0};
    gi_radiosity_vertex *v[GI__SMC_RAD_GROUP] = {0};
    pf_vec3 E[GI__SMC_RAD_GROUP];
    uint32_t n = 0;
    for (uint32_t i = item * GI__SMC_RAD_GROUP; i < s->cand_count && n < GI__SMC_RAD_GROUP; i++, n++) {
        const gi__smc_cand *C = &s->raw[s->cand[i]];
        y[n] = (gi_radiosity_site){C->surf, C->ng, C->ns};
        seed[n] = C->seed;
        v[n] = s->rad_scratch + ((size_t)worker * GI__SMC_RAD_GROUP + n) * s->path_nv;
    }
    gi_radiosity_trace(&s->rad, y, seed, n, v);
    gi_radiosity_gather(&s->rad, y, (const gi_radiosity_vertex *const *)v, n, E);
    for (uint32_t k = 0; k < n; k++) s->raw[s->cand[item * GI__SMC_RAD_GROUP + k]].E = E[k];
}

/* Line 18 for the estimates est[GROUP i, GROUP i + GROUP): the paths come
 * from the cache when they were traced for this VPL and estimate in the
 * cache's epoch, else they are traced (into the cache when there is one);
 * then all are gathered with the lights of now. */
static void gi__smc_rad_vpl_job(void *ctx, uint32_t item, uint32_t worker)
{
    gi__smc_state *s = ctx;
    const uint32_t *est = s->est + (size_t)item * GI__SMC_RAD_GROUP;
    const uint32_t left = s->est_count - item * GI__SMC_RAD_GROUP;
    const uint32_t n = left < GI__SMC_RAD_GROUP ? left : GI__SMC_RAD_GROUP;
    gi_radiosity_site y[GI__SMC_RAD_GROUP] = {0}, ty[GI__SMC_RAD_GROUP] = {0};
    uint64_t tseed[GI__SMC_RAD_GROUP] = {0};
    gi_radiosity_vertex *v[GI__SMC_RAD_GROUP] = {0}, *tv[GI__SMC_RAD_GROUP] = {0};
    pf_vec3 E[GI__SMC_RAD_GROUP];
    uint32_t t = 0;
    for (uint32_t k = 0; k < n; k++) {
        gi__smc_vpl *V = &s->y[est[k] >> 1];
        uint32_t which = est[k] & 1u, bit = which ? GI__SMC_PATHS_RANK : GI__SMC_PATHS_E;
        /* v->pos is the pushed-off point; the estimator pushes again by the
         * same rule, a few ulps further: immaterial */
        y[k] = (gi_radiosity_site){V->pos, V->ng, V->ns};
        v[k] = s->paths ? s->paths + (size_t)est[k] * s->path_nv
                        : s->rad_scratch + ((size_t)worker * GI__SMC_RAD_GROUP + k) * s->path_nv;
        if (s->paths && V->paths_epoch == s->paths_epoch && (V->paths & bit)) continue;
        ty[t] = y[k];
        tseed[t] = which ? V->seed ^ GI__SMC_RANK_SEED : V->seed;
        tv[t++] = v[k];
    }
    if (t) gi_radiosity_trace(&s->rad, ty, tseed, t, tv);
    gi_radiosity_gather(&s->rad, y, (const gi_radiosity_vertex *const *)v, n, E);
    for (uint32_t k = 0; k < n; k++) {
        gi__smc_vpl *V = &s->y[est[k] >> 1];
        if (est[k] & 1u) V->E_rank = E[k];
        else V->E = E[k];
    }
}

/* ESTIMATERADIOSITIES for the candidates (line 7): every candidate. */
static void gi__smc_estimate_radiosities_candidates(gi__smc_state *s, const gi_vpl_inputs *in)
{
    pf_jobs_parallel_for(in->jobs, gi__smc_rad_cand_job, s, (s->cand_count + GI__SMC_RAD_GROUP - 1) / GI__SMC_RAD_GROUP,
                         1);
}

/* ESTIMATERADIOSITIES for Y (line 18): a VPL's estimate is a pure function
 * of its seed and the lights, so only VPLs whose estimate predates a light
 * change are recomputed (new VPLs carry their candidate's value for
 * ranking). With independent=0 the ranking estimate is the rendering one. */
static void gi__smc_estimate_radiosities_vpls(gi__smc_state *s, const gi_vpl_inputs *in)
{
    uint32_t n = 0;
    for (uint32_t i = 0; i < s->I; i++) {
        const gi__smc_vpl *v = &s->y[i];
        if (!v->alive) continue;
        if (v->light_epoch != s->light_epoch) s->est[n++] = 2 * i;
        if (v->rank_epoch != s->light_epoch && s->prm.independent) s->est[n++] = 2 * i + 1;
    }
    s->est_count = n;
    pf_jobs_parallel_for(in->jobs, gi__smc_rad_vpl_job, s, (n + GI__SMC_RAD_GROUP - 1) / GI__SMC_RAD_GROUP, 1);
    for (uint32_t k = 0; k < n; k++) { /* the cache now holds these estimates' paths */
        gi__smc_vpl *v = &s->y[s->est[k] >> 1];
        if (!s->paths) continue;
        if (v->paths_epoch != s->paths_epoch) v->paths = 0, v->paths_epoch = s->paths_epoch;
        v->paths |= (s->est[k] & 1u) ? GI__SMC_PATHS_RANK : GI__SMC_PATHS_E;
    }
    for (uint32_t i = 0; i < s->I; i++) {
        gi__smc_vpl *v = &s->y[i];
        if (!v->alive) continue;
        v->light_epoch = s->light_epoch;
        if (v->rank_epoch != s->light_epoch) v->E_rank = s->prm.independent ? v->E_rank : v->E;
        v->rank_epoch = s->light_epoch;
    }
}

/* ---------------------------------------------------------------- lines 8 and 19 */

/* Builds the tree over the live VPLs (knn_slot maps tree index -> slot,
 * list2 slot -> tree index); returns their count. */
static pf_result gi__smc_build_vpl_tree(gi__smc_state *s, uint32_t *count, pf_error *err)
{
    uint32_t n = 0;
    for (uint32_t i = 0; i < s->I; i++) {
        s->list2[i] = GI_KNN_NONE;
        if (!s->y[i].alive) continue;
        s->knn_pts[n] = s->y[i].pos;
        s->knn_nrm[n] = s->y[i].ns;
        s->knn_slot[n] = i;
        s->list2[i] = n++;
    }
    *count = n;
    return gi_knn_build_facing(&s->tree, s->knn_pts, s->knn_nrm, n, err);
}

static void gi__smc_density_cand_job(void *ctx, uint32_t i, uint32_t worker)
{
    (void)worker;
    gi__smc_state *s = ctx;
    gi__smc_cand *C = &s->raw[s->cand[i]];
    float L = pf_luminance(C->albedo) > 0.0f ? pf_luminance(pf_v3_scale(pf_v3_mul(C->albedo, C->E), PF_INV_PI)) : 0.0f;
    float p = gi_knn_density(1, s->I, gi_knn_kth_dist2(&s->tree, C->pos, 1, GI_KNN_NONE));
    C->key = p;
    /* Eq. 6 (luminance); no VPL yet (p = 0): the candidate is infinitely
     * strong, ranked by its radiosity among equals via the tie-break */
    C->intensity = p > 0.0f ? L / p : (L > 0.0f ? INFINITY : 0.0f);
}

typedef struct gi__smc_dens_ctx {
    gi__smc_state *s;
    uint32_t k;
} gi__smc_dens_ctx;

static void gi__smc_density_vpl_job(void *ctx, uint32_t t, uint32_t worker)
{
    (void)worker;
    gi__smc_dens_ctx *c = ctx;
    gi__smc_state *s = c->s;
    gi__smc_vpl *v = &s->y[s->knn_slot[t]];
    float L = pf_luminance(pf_v3_scale(pf_v3_mul(v->albedo, v->E_rank), PF_INV_PI));
    v->density = gi_knn_density(c->k, s->I, gi_knn_kth_dist2(&s->tree, v->pos, c->k, t));
    v->intensity = v->density > 0.0f ? L / v->density : 0.0f;
}

/* ESTIMATEPROBABILITYDENSITIES(Y^), line 8: Eq. 7 with k = 1 among the
 * current VPLs, so candidates near a VPL are unlikely to be chosen. */
static pf_result gi__smc_estimate_densities_candidates(gi__smc_state *s, const gi_vpl_inputs *in, pf_error *err)
{
    uint32_t n;
    pf_result r = gi__smc_build_vpl_tree(s, &n, err);
    if (r != PF_OK) return r;
    pf_jobs_parallel_for(in->jobs, gi__smc_density_cand_job, s, s->cand_count, 16);
    return PF_OK;
}

/* Eq. 8: k = max(1, floor(sqrt(I) / 32)). */
static uint32_t gi__smc_render_k(uint32_t I)
{
    uint32_t k = (uint32_t)floor(sqrt((double)I) / 32.0);
    return k < 1 ? 1 : (k > GI_KNN_MAX_K ? GI_KNN_MAX_K : k);
}

/* ESTIMATEPROBABILITYDENSITIES(Y), line 19: Eq. 7 with Eq. 8's k among the
 * other VPLs. */
static pf_result gi__smc_estimate_densities_vpls(gi__smc_state *s, const gi_vpl_inputs *in, pf_error *err)
{
    uint32_t n;
    pf_result r = gi__smc_build_vpl_tree(s, &n, err);
    if (r != PF_OK) return r;
    gi__smc_dens_ctx c = {s, s->prm.k ? s->prm.k : gi__smc_render_k(s->I)};
    pf_jobs_parallel_for(in->jobs, gi__smc_density_vpl_job, &c, n, 16);
    return PF_OK;
}

/* ---------------------------------------------------------------- rendering areas */

/* Beyond the paper (area=voronoi, the default; area=knn is the paper's).
 * The area A_y a VPL stands for when rendered. Eq. 7 among the VPLs
 * themselves over-estimates it on the set SMC converges to: lines 10-17
 * keep the VPLs whose r_k came out large, so the set is repulsive and the
 * discs pi r_k^2 / k add up to 1.3x the surface they cover (docs/smc.md).
 * Here each VPL's Voronoi cell among the live VPLs is measured with this
 * iteration's intersection points (line 5), which do not depend on which
 * VPLs were kept: the cell's area is the sum of the areas pi r_k^2 / k that
 * the points nearest to the VPL stand for (Eq. 7 among the intersection
 * points, the resampling's own estimate; those points are independent
 * draws, for which Eq. 7 is unbiased). One iteration's measure rests on
 * about `ratio` points, so each VPL keeps a running mean of its measures:
 * all of them while it has fewer than area_window, then an exponential
 * mean of rate 1 / area_window, which follows a cell that changes (the
 * camera moves, a neighbour is replaced). Areas do not depend on the
 * lights. Needs the VPL tree of line 19. Measured only when rendering
 * uses them (flux=point): with flux=photons a VPL emits its photons and no
 * area (gi__smc_needs_areas). */
#define GI__SMC_NEAREST_CHUNK 256

static int gi__smc_needs_areas(const gi__smc_state *s)
{
    return s->prm.area == GI__SMC_AREA_VORONOI && s->prm.flux == GI__SMC_FLUX_POINT;
}

static void gi__smc_nearest_job(void *ctx, uint32_t chunk, uint32_t worker)
{
    (void)worker;
    gi__smc_state *s = ctx;
    for (uint32_t i = chunk * GI__SMC_NEAREST_CHUNK; i < s->raw_count && i < (chunk + 1) * GI__SMC_NEAREST_CHUNK; i++)
        s->nearest[i] = gi_knn_nearest(&s->tree, s->raw[i].pos, NULL);
}

static void gi__smc_estimate_areas_vpls(gi__smc_state *s, const gi_vpl_inputs *in)
{
    pf_jobs_parallel_for(in->jobs, gi__smc_nearest_job, s, (s->raw_count + GI__SMC_NEAREST_CHUNK - 1) / GI__SMC_NEAREST_CHUNK,
                         1);
    for (uint32_t i = 0; i < s->I; i++) s->y[i].cell = 0.0f;
    for (uint32_t i = 0; i < s->raw_count; i++) /* in point order: the same sums for any thread count */
        if (s->nearest[i] != GI_KNN_NONE) s->y[s->knn_slot[s->nearest[i]]].cell += s->raw[i].area;
    for (uint32_t i = 0; i < s->I; i++) {
        gi__smc_vpl *v = &s->y[i];
        if (!v->alive) continue;
        if (v->area_n < s->prm.area_window) v->area_n++;
        v->area += (v->cell - v->area) / (float)v->area_n;
    }
}

/* ---------------------------------------------------------------- photons */

/* Beyond the paper (flux=photons, the default with area=voronoi). The
 * rendering area alone still assumes a VPL's radiosity is about constant
 * over its cell. Next to a light (the Cornell box's, 1 cm under the
 * ceiling) the radiosity changes by orders of magnitude within a cell, on
 * the ceiling (direct light) and on the walls beside it (light from that
 * bright ceiling), SMC crowds VPLs there, and a VPL at a peak would carry
 * its peak value over its whole cell (docs/smc.md). So what a VPL emits is
 * the flux that reaches its cell, counted with photons: photons x I light
 * paths with IR's numbers and bounces (gi_lightpath_trace_halton: a fixed
 * Halton sequence, so the same photons every frame while the lights stand
 * still; traced again only when they move), each hit binned to its nearest
 * live VPL with IR's intensity Phi albedo / pi / paths. The flux lands where
 * it lands, so no cell counts more light than it receives. A hit counts
 * only where the intersection points of line 5 reach, within GI__SMC_REACH
 * times its nearest (facing) intersection point's r_k of it: surfaces no directly
 * visible point sees light the image only through other surfaces, whose
 * VPLs carry that light already. The VPLs' radiosity estimates still rank
 * them (lines 9-17); only what is rendered changes. */
#define GI__SMC_PHOTON_CHUNK 64
#define GI__SMC_REACH 8.0f

/* 10 bits of each coordinate, interleaved (x highest): nearby points get
 * nearby codes. */
static uint32_t gi__smc_morton(pf_vec3 p, pf_vec3 lo, pf_vec3 scale)
{
    float f[3] = {(p.x - lo.x) * scale.x, (p.y - lo.y) * scale.y, (p.z - lo.z) * scale.z};
    uint32_t c[3], m = 0;
    for (int a = 0; a < 3; a++) c[a] = f[a] > 0.0f ? (f[a] < 1023.0f ? (uint32_t)f[a] : 1023u) : 0u;
    for (int b = 9; b >= 0; b--)
        for (int a = 0; a < 3; a++) m = (m << 1) | ((c[a] >> b) & 1u);
    return m;
}

static void gi__smc_photon_job(void *ctx, uint32_t chunk, uint32_t worker)
{
    (void)worker;
    const gi_lightpath_lights *lights = ((void **)ctx)[1];
    gi__smc_state *s = ((void **)ctx)[0];
    uint32_t B = s->rad.bounces, paths = s->phot_paths;
    uint32_t i0 = chunk * GI__SMC_PHOTON_CHUNK, m = paths - i0 < GI__SMC_PHOTON_CHUNK ? paths - i0 : GI__SMC_PHOTON_CHUNK;
    gi_vpl hits[GI__SMC_PHOTON_CHUNK * GI_RADIOSITY_MAX_BOUNCES];
    uint32_t got[GI__SMC_PHOTON_CHUNK];
    gi_lightpath_trace_halton_batch(lights, s->in->rt, s->halton0 + i0 + 1, m, B, hits,
                                    got); /* path i is Halton index halton0 + i + 1 */
    for (uint32_t i = 0; i < m; i++)
        for (uint32_t k = 0; k < B; k++) {
            gi__smc_photon *P = &s->phot[(size_t)(i0 + i) * B + k];
            const gi_vpl *h = &hits[(size_t)i * B + k];
            memset(P, 0, sizeof *P);
            if (k >= got[i]) continue;
            P->pos = h->pos;
            P->nrm = h->nrm;
            P->intensity = pf_v3_scale(h->intensity, 1.0f / (float)paths);
            P->valid = 1;
            P->morton = gi__smc_morton(P->pos, s->morton_lo, s->morton_scale);
        }
}

/* phot_order: the valid photons sorted by the Morton code of their
 * positions (ties in photon order), so the binning's queries come in
 * spatial order, neighbours after neighbours: the trees' branches and
 * leaves they walk are the previous query's (about twice as fast as photon
 * order at 2048 VPLs). Only the order of the queries changes, not their
 * answers. */
static void gi__smc_order_photons(gi__smc_state *s)
{
    uint32_t *key = s->phot_sort, *key2 = key + s->phot_cap, *ord2 = key2 + s->phot_cap, *ord = s->phot_order;
    uint32_t n = 0;
    for (uint32_t i = 0; i < s->phot_count; i++) {
        s->phot[i].bin = GI__SMC_NONE;
        if (!s->phot[i].valid) continue;
        key[n] = s->phot[i].morton;
        ord[n++] = i;
    }
    for (uint32_t pass = 0; pass < 3; pass++) { /* stable LSD radix sort, 10 bits a pass */
        uint32_t cnt[1024] = {0}, shift = 10 * pass;
        for (uint32_t i = 0; i < n; i++) cnt[(key[i] >> shift) & 1023u]++;
        for (uint32_t b = 0, sum = 0; b < 1024; b++) {
            uint32_t c = cnt[b];
            cnt[b] = sum, sum += c;
        }
        for (uint32_t i = 0; i < n; i++) {
            uint32_t at = cnt[(key[i] >> shift) & 1023u]++;
            key2[at] = key[i], ord2[at] = ord[i];
        }
        uint32_t *t = key;
        key = key2, key2 = t;
        t = ord, ord = ord2, ord2 = t;
    }
    if (ord != s->phot_order) memcpy(s->phot_order, ord, sizeof(uint32_t) * n);
    s->phot_valid = n;
}

/* Traces the photons when the lights changed since they were traced. */
static pf_result gi__smc_trace_photons(gi__smc_state *s, const gi_vpl_inputs *in, pf_error *err)
{
    uint32_t B = s->rad.bounces, paths = s->prm.photons * s->I;
    if (s->phot_traced && s->phot_epoch == s->light_epoch && s->phot_bounces == B) return PF_OK;
    size_t need = (size_t)paths * B;
    if (need > s->phot_cap) {
        free(s->phot), free(s->phot_order), free(s->phot_sort);
        s->phot = malloc(need * sizeof *s->phot);
        s->phot_order = malloc(need * sizeof(uint32_t));
        s->phot_sort = malloc(3 * need * sizeof(uint32_t));
        s->phot_cap = s->phot && s->phot_order && s->phot_sort ? need : 0;
        if (!s->phot_cap) return pf_error_set(err, PF_ERR_OUT_OF_MEMORY, "smc: out of memory for %u photon paths", paths);
    }
    s->phot_paths = paths;
    s->phot_count = 0;
    gi_lightpath_lights lights;
    gi_lightpath_lights_init(&lights, in->scene, in->area);
    pf_vec3 ext = pf_v3_sub(in->scene->bounds_max, in->scene->bounds_min);
    s->morton_lo = in->scene->bounds_min;
    s->morton_scale = pf_v3(ext.x > 0.0f ? 1024.0f / ext.x : 0.0f, ext.y > 0.0f ? 1024.0f / ext.y : 0.0f,
                            ext.z > 0.0f ? 1024.0f / ext.z : 0.0f);
    if (lights.nl && lights.total > 0.0) {
        void *ctx[2] = {s, &lights};
        s->in = in;
        pf_jobs_parallel_for(in->jobs, gi__smc_photon_job, ctx, (paths + GI__SMC_PHOTON_CHUNK - 1) / GI__SMC_PHOTON_CHUNK,
                             1);
        s->in = NULL;
        s->phot_count = (uint32_t)need;
    }
    gi__smc_order_photons(s);
    s->phot_traced = 1, s->phot_epoch = s->light_epoch, s->phot_bounces = B;
    return PF_OK;
}

/* Photons and surfaces: a photon belongs to a surface that faces its way
 * (normals within 60 degrees). It counts only near an intersection point
 * that faces its way (a photon on the back of a thin wall is near the
 * points on its front but not of them), and goes to the nearest VPL that
 * faces its way: a VPL stands for a patch of its own surface, and the 3D
 * nearest one may lie across a corner, on a wall that would emit the
 * photon's flux in another direction (measured on the Cornell box at 1:1,
 * 256 VPLs: 1.13x the reference with the plain nearest VPL, 1.01x with
 * this); with none, the nearest. */
#define GI__SMC_COMPAT 0.5f


/* Photons [256 chunk, 256 chunk + 256): whether they land where the
 * intersection points reach, then the VPL each is binned to. */
static void gi__smc_bin_job(void *ctx, uint32_t chunk, uint32_t worker)
{
    (void)worker;
    gi__smc_state *s = ctx;
    for (uint32_t o = chunk * 256; o < s->phot_valid && o < (chunk + 1) * 256; o++) {
        gi__smc_photon *P = &s->phot[s->phot_order[o]]; /* in Morton order; the others stay unbinned */
        float d2;
        /* the trees carry the points' normals (raw[i].ns, the VPLs' ns) */
        uint32_t r = gi_knn_nearest_facing(&s->raw_tree, P->pos, P->nrm, GI__SMC_COMPAT, &d2);
        float rk2 = r != GI_KNN_NONE ? s->raw[r].area * (float)s->raw_k * (float)PF_INV_PI : 0.0f;
        P->bin = GI__SMC_NONE;
        if (!(r != GI_KNN_NONE && d2 <= GI__SMC_REACH * GI__SMC_REACH * rk2)) continue;
        uint32_t t = gi_knn_nearest_facing(&s->tree, P->pos, P->nrm, GI__SMC_COMPAT, NULL);
        if (t == GI_KNN_NONE) t = gi_knn_nearest(&s->tree, P->pos, NULL);
        if (t != GI_KNN_NONE) P->bin = s->knn_slot[t];
    }
}

/* The photons binned into the cells of the live VPLs (s->tree must be the
 * VPL tree of line 19). */
static pf_result gi__smc_photons(gi__smc_state *s, const gi_vpl_inputs *in, pf_error *err)
{
    for (uint32_t i = 0; i < s->I; i++) s->y[i].phot = pf_v3(0, 0, 0);
    pf_result r = gi__smc_trace_photons(s, in, err);
    if (r != PF_OK || !s->raw_count || !s->phot_count) return r; /* raw_tree: built with line 6 */
    pf_jobs_parallel_for(in->jobs, gi__smc_bin_job, s, (s->phot_valid + 255) / 256, 1);
    for (uint32_t i = 0; i < s->phot_count; i++) { /* in photon order: the same sums for any thread count */
        if (s->phot[i].bin == GI__SMC_NONE) continue;
        gi__smc_vpl *v = &s->y[s->phot[i].bin];
        v->phot = pf_v3_add(v->phot, s->phot[i].intensity);
    }
    return PF_OK;
}

/* ---------------------------------------------------------------- line 9 */

/* M_min = min(M_max, M_strong), Eq. 9: M_strong counts the candidates
 * stronger than 95% of the current VPLs. */
static uint32_t gi__smc_count_undersampled(gi__smc_state *s)
{
    gi__smc_sortkey *v = s->sortkeys;
    uint32_t n = 0;
    for (uint32_t i = 0; i < s->I; i++)
        if (s->y[i].alive) v[n++] = (gi__smc_sortkey){s->y[i].intensity, 0, i};
    if (!n) return 0;
    gi__smc_sort(v, s->sortkeys2, n);
    uint32_t at = (uint32_t)ceil(0.95 * n); /* the candidate must beat v[0 .. at-1] */
    float t = v[(at ? at : 1) - 1].key;
    uint32_t strong = 0;
    for (uint32_t i = 0; i < s->cand_count; i++) strong += s->raw[s->cand[i]].intensity > t;
    return strong < s->prm.m_max ? strong : s->prm.m_max;
}

/* ---------------------------------------------------------------- lines 10-17 */

/* Lines 10-12 and 13: while |INVALID| < M_min, FINDSMALLESTINTENSITY among
 * the valid VPLs joins INVALID; then Y <- Y \ CLAMPSIZE(INVALID, M_max).
 * Sorting the live VPLs (invalid first, then by intensity) does both: the
 * first max(|INVALID|, M_min) entries are INVALID in that order, and the
 * first min(that, M_max) are removed. Returns how many were removed. */
static uint32_t gi__smc_invalidate_and_clamp(gi__smc_state *s, uint32_t m_min)
{
    gi__smc_sortkey *o = s->sortkeys;
    uint32_t n = 0, invalid = 0;
    for (uint32_t i = 0; i < s->I; i++)
        if (s->y[i].alive) {
            o[n++] = (gi__smc_sortkey){s->y[i].intensity, s->y[i].valid ? 1u : 0u, i};
            invalid += !s->y[i].valid;
        }
    gi__smc_sort(o, s->sortkeys2, n); /* invalid first, then weaker first, then slot */
    uint32_t inv = invalid > m_min ? invalid : (m_min < n ? m_min : n);
    uint32_t removed = inv < s->prm.m_max ? inv : s->prm.m_max;
    for (uint32_t k = 0; k < removed; k++) s->y[o[k].i].alive = 0;
    return removed;
}

/* Lines 14-17: while |Y| < I, FINDLARGESTINTENSITY among the candidates
 * moves into Y (the lowest free slot). */
static void gi__smc_take_strongest(gi__smc_state *s)
{
    gi__smc_sortkey *o = s->sortkeys; /* strongest first: ascending on -intensity, ties by candidate order */
    for (uint32_t i = 0; i < s->cand_count; i++) o[i] = (gi__smc_sortkey){-s->raw[s->cand[i]].intensity, 0, i};
    gi__smc_sort(o, s->sortkeys2, s->cand_count);
    uint32_t next = 0;
    for (uint32_t slot = 0; slot < s->I && next < s->cand_count; slot++) {
        if (s->y[slot].alive) continue;
        const gi__smc_cand *C = &s->raw[s->cand[o[next++].i]];
        gi__smc_vpl *v = &s->y[slot];
        memset(v, 0, sizeof *v);
        v->pos = C->pos, v->ng = C->ng, v->ns = C->ns, v->albedo = C->albedo;
        v->prim = C->prim;
        v->id = s->id_base + s->id_stride * s->next_id++;
        /* its own radiosity seed, independent of the candidate's: the
         * candidate won on its noisy estimate, so reusing that estimate
         * would keep the winners' upward noise (line 18 re-estimates) */
        v->seed = gi_radiosity_hash(0x7b1, v->id);
        v->light_epoch = s->light_epoch - 1u; /* stale: line 18 estimates it */
        /* ranking: the candidate's own estimate (independent mode) costs nothing */
        v->E_rank = C->E;
        v->rank_epoch = s->prm.independent ? s->light_epoch : s->light_epoch - 1u;
        v->mail_p = s->x[C->x].p;
        v->mail_n = s->x[C->x].ng;
        v->alive = 1;
        v->valid = 1;
        v->born = s->updates;
    }
}

/* ---------------------------------------------------------------- the loop */

/* Line 1: Y <- INITIALIZEVPLS(): candidates sampled as in lines 3-7, all
 * taken (Sec. 3.2: "identically to how we generate candidate VPLs"). */
static pf_result gi__smc_initialize_vpls(gi__smc_state *s, const gi_vpl_inputs *in, pf_error *err)
{
    uint64_t key = gi_radiosity_hash(s->seed, s->iter++);
    for (uint32_t i = 0; i < s->I; i++) s->y[i].alive = 0;
    gi__smc_raycast_from_camera(s, in, key);
    gi__smc_raycast_from_points(s, in, key);
    pf_result r = gi__smc_resample_candidates(s, in, key, err);
    if (r != PF_OK) return r;
    for (uint32_t i = 0; i < s->cand_count; i++) s->raw[s->cand[i]].intensity = (float)(s->cand_count - i);
    gi__smc_take_strongest(s); /* all of them, in resampling order */
    for (uint32_t i = 0; i < s->I; i++) s->y[i].rank_epoch = s->light_epoch - 1u; /* no candidate estimates here */
    gi__smc_estimate_radiosities_vpls(s, in);
    r = gi__smc_estimate_densities_vpls(s, in, err);
    if (r == PF_OK && gi__smc_needs_areas(s)) gi__smc_estimate_areas_vpls(s, in);
    return r;
}

/* Lines 3-19: one iteration. */
static pf_result gi__smc_iterate(gi__smc_state *s, const gi_vpl_inputs *in, pf_error *err)
{
    uint64_t key = gi_radiosity_hash(s->seed, s->iter++);
    gi__smc_raycast_from_camera(s, in, key);                      /* 3 */
    gi__smc_part(s, GI__SMC_T_CAND);
    gi__smc_indirectly_visible_vpls(s, in, key);                  /* 4 */
    gi__smc_part(s, GI__SMC_T_VIS);
    gi__smc_raycast_from_points(s, in, key);                      /* 5 */
    gi__smc_part(s, GI__SMC_T_CAND);
    pf_result r = gi__smc_resample_candidates(s, in, key, err);   /* 6 */
    gi__smc_part(s, GI__SMC_T_RESAMPLE);
    if (r != PF_OK) return r;
    gi__smc_estimate_radiosities_candidates(s, in);               /* 7 */
    gi__smc_part(s, GI__SMC_T_RAD);
    r = gi__smc_estimate_densities_candidates(s, in, err);        /* 8 */
    gi__smc_part(s, GI__SMC_T_KNN);
    if (r != PF_OK) return r;
    uint32_t m_min = gi__smc_count_undersampled(s);               /* 9 */
    gi__smc_invalidate_and_clamp(s, m_min);                       /* 10-13 */
    gi__smc_take_strongest(s);                                    /* 14-17 */
    gi__smc_part(s, GI__SMC_T_CAND);
    gi__smc_estimate_radiosities_vpls(s, in);                     /* 18 */
    gi__smc_part(s, GI__SMC_T_RAD);
    r = gi__smc_estimate_densities_vpls(s, in, err);              /* 19 */
    if (r == PF_OK && gi__smc_needs_areas(s)) gi__smc_estimate_areas_vpls(s, in); /* beyond the paper */
    gi__smc_part(s, GI__SMC_T_KNN);
    return r;
}

/* An empty slot: a dark VPL that keeps the others' indices (gi__smc_output,
 * and the chains' slots until their chain is made). */
static gi_vpl gi__smc_dark(void)
{
    gi_vpl o;
    memset(&o, 0, sizeof o);
    o.nrm = pf_v3(0, 1, 0);
    o.id = GI__SMC_NONE;
    return o;
}

/* Line 20's input: every slot as a gi_vpl (see "Units" above), up to the
 * last live one, or with `all` every slot. */
static pf_result gi__smc_output(gi__smc_state *s, int all, gi_vpl_set *out, pf_error *err)
{
    out->count = 0;
    pf_result r = gi_vpl_set_reserve(out, s->I, err);
    if (r != PF_OK) return r;
    uint32_t last = all ? s->I : 0;
    for (uint32_t i = 0; i < s->I && !all; i++)
        if (s->y[i].alive) last = i + 1;
    for (uint32_t i = 0; i < last; i++) {
        const gi__smc_vpl *v = &s->y[i];
        gi_vpl *o = &out->v[i];
        if (v->alive) {
            /* intensity = L A = albedo E / pi / (I p) */
            float A = s->prm.area == GI__SMC_AREA_VORONOI
                          ? v->area
                          : (v->density > 0.0f && isfinite(v->density) ? 1.0f / ((float)s->I * v->density) : 0.0f);
            o->pos = v->pos;
            o->nrm = v->ns;
            o->intensity = s->prm.flux == GI__SMC_FLUX_PHOTONS ? v->phot
                                                               : pf_v3_scale(pf_v3_mul(v->albedo, v->E), PF_INV_PI * A);
            o->id = v->id;
        } else {
            *o = gi__smc_dark();
        }
        o->moved = s->prev_id[i] != o->id;
        s->prev_id[i] = o->id;
    }
    out->count = last;
    return PF_OK;
}

/* One update of one chain with a budget of I: on its first, line 1 and
 * `warmup` iterations, then one; `out` gets its set (every slot with
 * `all`). */
static pf_result gi__smc_update_chain(gi__smc_state *s, const gi_vpl_inputs *in, uint32_t I, uint32_t warmup, int all,
                                      gi_vpl_set *out, pf_error *err)
{
    pf_result r = PF_OK;
    if (s->I != I) r = gi__smc_alloc(s, I, err);
    if (r == PF_OK) r = gi__smc_track_lights(s, in->scene, err);
    if (r != PF_OK) return r;
    if (s->warmed) gi__smc_motion(s, in->motion);
    s->halton0 = s->id_base * s->prm.photons * I; /* chain c's photons: the c-th run of the sequence */
    s->in = in;
    s->rad.scene = in->scene;
    s->rad.rt = in->rt;
    s->rad.area = in->area;
    s->rad.spp = s->prm.spp;
    s->rad.bounces = s->prm.bounces ? s->prm.bounces : (in->bounces ? in->bounces : 3);
    if (s->rad.bounces > GI_RADIOSITY_MAX_BOUNCES) s->rad.bounces = GI_RADIOSITY_MAX_BOUNCES;
    r = gi__smc_paths_prepare(s, in, err);
    if (r != PF_OK) return r;
    uint32_t iters = 1;
    s->parts.count = 0;
    s->t_mark = pf_time_now();
    if (!s->warmed) {
        s->raw_tree_wanted = 0;
        r = gi__smc_initialize_vpls(s, in, err); /* line 1 */
        gi__smc_part(s, GI__SMC_T_CAND);
        iters = warmup;                          /* Sec. 3.2: 100 iterations before the first frame */
        s->warmed = 1;
    }
    for (uint32_t k = 0; k < iters && r == PF_OK; k++) {
        s->raw_tree_wanted = k + 1 == iters && s->prm.flux == GI__SMC_FLUX_PHOTONS;
        r = gi__smc_iterate(s, in, err);
    }
    s->in = NULL;
    if (r == PF_OK && s->prm.flux == GI__SMC_FLUX_PHOTONS) {
        r = gi__smc_photons(s, in, err);
        gi__smc_part(s, GI__SMC_T_PHOTONS);
    }
    if (r == PF_OK) r = gi__smc_output(s, all, out, err);
    gi__smc_part(s, GI__SMC_T_CAND); /* line 20 (replacing into the output set) */
    s->updates++;
    return r;
}

/* w->parts += the parts of the chain's last update */
static void gi__smc_add_parts(gi__smc *w, const gi__smc_state *s)
{
    for (uint32_t i = 0; i < s->parts.count; i++) pf_stage_add(&w->parts, s->parts.name[i], s->parts.ms[i]);
}

/* n chains (chain c: gi__smc_chain_init(c, n)); kept while n stays. */
static pf_result gi__smc_chains(gi__smc *w, uint32_t n, pf_error *err)
{
    if (w->chains == n && w->chain) return PF_OK;
    gi__smc_free_chains(w);
    w->chain = calloc(n, sizeof *w->chain);
    if (!w->chain) return pf_error_set(err, PF_ERR_OUT_OF_MEMORY, "smc: out of memory for %u chains", n);
    for (uint32_t c = 0; c < n; c++) gi__smc_chain_init(&w->chain[c], &w->prm, c, n);
    w->chains = n;
    w->I = 0;
    return PF_OK;
}

/* VPL cycling with cycle=chains: the update of the chains (see "VPL
 * cycling"), `out` the whole set of I = C x I_c slots, chain c's slot j at
 * c + j C. */
static pf_result gi__smc_update_chains(gi__smc *w, const gi_vpl_inputs *in, gi_vpl_set *out, pf_error *err)
{
    const uint32_t C = w->chains, N = in->budget, I = N / C;
    const uint32_t live = in->live && in->live < C ? in->live : C, slice = in->slice < C ? in->slice : 0u;
    pf_result r = gi_vpl_set_reserve(&w->all, N, err);
    if (r != PF_OK) return r;
    if (w->I != N) { /* a new layout: every chain starts again, its slots empty until it is made */
        for (uint32_t i = 0; i < N; i++) w->all.v[i] = gi__smc_dark();
        for (uint32_t c = 0; c < C; c++) w->chain[c].warmed = 0;
        w->all.count = w->I = N;
    }
    for (uint32_t i = 0; i < N; i++) w->all.v[i].moved = 0;
    for (uint32_t c = 0; c < C && r == PF_OK; c++) {
        gi__smc_state *s = &w->chain[c];
        if (c == slice || (c < live && !s->warmed)) { /* the frame's chain, or one first needed now */
            r = gi__smc_update_chain(s, in, I, w->prm.chain_warmup, 1, &w->one, err);
            gi__smc_add_parts(w, s);
        } else if (s->warmed && gi_motion_any(in->motion)) { /* its VPLs on moved triangles go now */
            gi__smc_motion(s, in->motion);
            r = gi__smc_output(s, 1, &w->one, err);
        } else {
            continue; /* its slots as they were */
        }
        for (uint32_t j = 0; j < I && r == PF_OK; j++) {
            gi_vpl v = w->one.v[j];
            v.intensity = pf_v3_scale(v.intensity, 1.0f / (float)C); /* one of C estimates */
            w->all.v[c + j * C] = v;
        }
    }
    w->last = slice;
    if (r == PF_OK) r = gi_vpl_set_reserve(out, N, err);
    if (r != PF_OK) return r;
    memcpy(out->v, w->all.v, sizeof *out->v * N);
    out->count = N;
    return PF_OK;
}

static pf_result gi__smc_update(void *state, const gi_vpl_inputs *in, gi_vpl_set *out, pf_error *err)
{
    gi__smc *w = state;
    out->count = 0;
    if (!in->gbuf || !in->gbuf->prim || in->gbuf->width != in->width || in->gbuf->height != in->height ||
        !in->width || !in->height)
        return pf_error_set(err, PF_ERR_ARGUMENT, "--method smc needs the frame's G-buffer (directly visible points)");
    if (!in->budget) return pf_error_set(err, PF_ERR_ARGUMENT, "--method smc: a VPL budget of 0");
    const uint32_t C = in->cycle > 1 && w->prm.cycle == GI__SMC_CYCLE_CHAINS ? in->cycle : 1u;
    if (in->budget % C)
        return pf_error_set(err, PF_ERR_ARGUMENT, "--method smc: %u VPLs do not split into %u chains", in->budget, C);
    pf_result r = gi__smc_chains(w, C, err);
    if (r != PF_OK) return r;
    w->parts.count = 0;
    if (C > 1) return gi__smc_update_chains(w, in, out, err);
    w->last = 0;
    r = gi__smc_update_chain(&w->chain[0], in, in->budget, w->prm.warmup, 0, out, err);
    gi__smc_add_parts(w, &w->chain[0]);
    return r;
}

static const pf_stage_times *gi__smc_parts(const void *state) { return &((const gi__smc *)state)->parts; }

/* ---------------------------------------------------------------- the view */

/* A circle of radius r around p in the plane of normal n, projected. */
static void gi__smc_view_circle(const gi_vpl_view_ctx *c, uint8_t *rgb, pf_vec3 p, pf_vec3 n, float r,
                                const uint8_t col[3])
{
    pf_vec3 t, b;
    pf_v3_basis(n, &t, &b);
    float px = 0.0f, py = 0.0f;
    int have = 0;
    for (int k = 0; k <= 24; k++) {
        float a = 2.0f * PF_PI * (float)k / 24.0f, x, y;
        pf_vec3 q = pf_v3_add(p, pf_v3_add(pf_v3_scale(t, r * cosf(a)), pf_v3_scale(b, r * sinf(a))));
        int ok = c->project(c, q, &x, &y);
        if (ok && have) c->line(c, rgb, (int)floorf(px), (int)floorf(py), (int)floorf(x), (int)floorf(y), col);
        have = ok, px = x, py = y;
    }
}

/* The last iteration of Algorithm 1 over the image: the directly visible
 * points X of line 3 (grey), the candidates that line 6 resampled (cyan),
 * and the VPLs of Y the camera sees, coloured by the intensity lines 9-17
 * rank them by (Eq. 6, L / p) with the disc of their kNN radius r_k (Eq. 7:
 * p = k / (I pi r_k^2)) in their tangent plane: green when new in the last
 * update, red when the visibility test of line 4 failed, grey otherwise. */
static int gi__smc_view(const void *state, const gi_vpl_view_ctx *c, uint8_t *rgb)
{
    const gi__smc *w = state;
    const gi__smc_state *s = w && w->chain && w->last < w->chains ? &w->chain[w->last] : NULL;
    if (!s || !s->I || !s->y) return 0;
    static const uint8_t grey[3] = {150, 150, 150}, cyan[3] = {40, 220, 230}, green[3] = {60, 240, 60},
                         red[3] = {240, 60, 60}, white[3] = {255, 255, 255};
    c->background(c, rgb);
    float x, y;
    for (uint32_t i = 0; i < s->x_count; i++)
        if (c->project(c, s->x[i].p, &x, &y)) c->fill(c, rgb, (int)floorf(x), (int)floorf(y), 1, 1, grey);
    uint32_t cand_seen = 0;
    for (uint32_t i = 0; i < s->cand_count; i++) {
        const gi__smc_cand *C = &s->raw[s->cand[i]];
        if (!c->project(c, C->pos, &x, &y) || !c->visible(c, C->pos)) continue;
        c->fill(c, rgb, (int)floorf(x), (int)floorf(y), 2, 2, cyan);
        cand_seen++;
    }
    float lo = INFINITY, hi = -INFINITY;
    uint32_t alive = 0, fresh = 0, invalid = 0;
    for (uint32_t i = 0; i < s->I; i++) {
        const gi__smc_vpl *v = &s->y[i];
        if (!v->alive || !isfinite(v->intensity)) continue;
        lo = fminf(lo, v->intensity), hi = fmaxf(hi, v->intensity);
    }
    if (!(lo <= hi)) lo = hi = 0.0f;
    const uint32_t k = s->prm.k ? s->prm.k : gi__smc_render_k(s->I);
    const uint32_t last = s->updates ? s->updates - 1 : 0;
    for (uint32_t i = 0; i < s->I; i++) {
        const gi__smc_vpl *v = &s->y[i];
        if (!v->alive) continue;
        alive++, fresh += v->born == last, invalid += !v->valid;
        if (!c->project(c, v->pos, &x, &y) || !c->visible(c, v->pos)) continue;
        if (v->density > 0.0f && isfinite(v->density)) {
            float r = sqrtf((float)k / ((float)s->I * PF_PI * v->density));
            gi__smc_view_circle(c, rgb, v->pos, v->ng, r, !v->valid ? red : v->born == last ? green : grey);
        }
        uint8_t col[3];
        float t = hi > lo && isfinite(v->intensity) ? (v->intensity - lo) / (hi - lo) : 1.0f;
        c->heat(sqrtf(t), col);
        c->fill(c, rgb, (int)floorf(x) - 1, (int)floorf(y) - 1, 3, 3, col);
    }
    char text[160];
    snprintf(text, sizeof text, "X: %u points (grey), %u candidates (cyan, %u seen), Y: %u VPLs, %u new, %u invalid",
             s->x_count, s->cand_count, cand_seen, alive, fresh, invalid);
    c->text(c, rgb, 4, 2, text, white);
    if (w->chains > 1)
        snprintf(text, sizeof text, "chain %u of %u (VPL cycling); circles: kNN radius r_k, k = %u (Eq. 7)", w->last,
                 w->chains, k);
    else
        snprintf(text, sizeof text, "circles: kNN radius r_k, k = %u (Eq. 7)", k);
    c->text(c, rgb, 4, 12, text, white);
    c->legend(c, rgb, "Eq. 6 intensity L / p", lo, hi, 1);
    return 1;
}

const gi_vpl_method gi_method_smc = {
    .name = "smc",
    .paper = "Sequential Monte Carlo Instant Radiosity (Hedman 2017 Sec. 3, Algorithm 1)",
    .create = gi__smc_create,
    .update = gi__smc_update,
    .destroy = gi__smc_destroy,
    .parts = gi__smc_parts,
    .why = "only VPLs that light what the camera sees matter, so SMC samples candidates from the camera's points, "
           "keeps the strong ones and replaces at most Mmax a frame where VPLs are sparse or invisible (Hedman 2017 "
           "Sec. 3, Algorithm 1)",
    .view_caption = "the last iteration: visible points X (grey), resampled candidates (cyan), the VPLs by Eq. 6 "
                    "intensity with their kNN radius (Eq. 7; green new, red failed visibility)",
    .view = gi__smc_view,
};
