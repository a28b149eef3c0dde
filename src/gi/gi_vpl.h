/* gi_vpl: virtual point lights and the interface every VPL method
 * implements (Laine 2007 Sec. 3 steps 1-4: "VPL management"; the survey's
 * Sec. 3-4 for what a VPL carries).
 *
 * A VPL sits on a surface point x2 with unit normal n2 and RGB `intensity`
 * I = Phi * rho2 / pi: its "flux" Phi (survey Eq. 6) times the Lambertian
 * BRDF at x2. It lights a receiver x1 with unit normal n1 with irradiance
 *   E = I * G(x1, x2) * V(x1, x2),  G = max(0, n1.w) max(0, -n2.w) / r^2
 * (w the unit direction x1 -> x2, r the distance), so the receiver reflects
 * albedo1 / pi * E (survey Eq. 8). The frame bounds G by b (the bounded
 * geometry term, survey Sec. 5).
 *
 * A method keeps its own state between frames; each update returns the
 * whole VPL set with stable ids and a moved flag per VPL (new or changed
 * since the previous frame), so the frame re-renders paraboloid maps only
 * for those (Laine 2007 Sec. 3, step 4). */
#ifndef GI_VPL_H
#define GI_VPL_H

#include <stdint.h>

#include "pf_jobs.h"
#include "pf_rt.h"
#include "pf_scene.h"
#include "pf_timer.h"
#include "rs_gbuffer.h"
#include "gi_area.h"
#include "gi_motion.h"

/* The albedo a VPL takes from a textured surface (one rule for every
 * method): the base-colour texture blurred to mip level 4 (1/16 of its
 * resolution per side; the base-colour factor applies as everywhere).
 * Laine 2007 Sec. 7 takes the albedo for VPLs from "a heavily blurred"
 * texture, Hedman 2017 Sec. 5 "average material colours": a VPL stands for
 * a patch of surface, not a point, and a full-resolution texel would make
 * the VPL's colour flicker with the texel it happens to land on. Used by
 * IR and MIR (gi_lightpath.c), SMC, IIR (the default of its --param
 * albedoLod), SSVP's second-bounce sites and the reflective shadow maps
 * (gi_rsm.c: the larger of this level and the texel's footprint level;
 * gi_rsm_area.c). Surfaces seen by the camera, the path tracer's vertices
 * and the radiosity estimates keep mip 0. */
#define GI_VPL_ALBEDO_LOD 4.0f

typedef struct gi_vpl {
    pf_vec3 pos, nrm;
    pf_vec3 intensity; /* Phi * albedo / pi, RGB (W/sr at normal exitance) */
    uint32_t id;       /* stable while the VPL lives */
    uint32_t moved;    /* position or normal new/changed this frame: its paraboloid map must be
                          re-rendered (a changed intensity alone needs no new map) */
} gi_vpl;

typedef struct gi_vpl_set {
    uint32_t count, cap;
    gi_vpl *v;
} gi_vpl_set;

/* What a method sees each frame. */
typedef struct gi_vpl_inputs {
    const pf_scene *scene; /* lights may move between frames */
    const pf_rt *rt;
    pf_jobs *jobs;
    const pf_camera *camera;
    uint32_t frame;    /* frame number: seeds derive from it and from VPL ids */
    uint32_t budget;   /* VPL budget (--vpls) */
    uint32_t bounces;  /* light bounces (--bounces) */
    /* This frame's G-buffer (directly visible points; SMC's X, TCAS's
     * camera samples). NULL when a caller has none (unit tests): methods
     * that need one then fail with a clear error. */
    const rs_gbuffer *gbuf;
    uint32_t width, height;
    const gi_area_lights *area; /* the scene's emissive triangles (count may be 0); never NULL */
    /* What geometry moved since this method's last update (gi_motion.h);
     * NULL: nothing did. Each method says in its file how it reacts. */
    const gi_motion *motion;
    /* The SIMD kernels a method may use (the frame's rasterizer's path, an
     * rs_simd: 0 scalar, 1 AVX2, 2 AVX-512); every path gives the same bits. */
    uint32_t simd;
    /* VPL cycling (--vpl-cycle C, gi_indirect.h): the set is shaded one
     * slice of budget / C a frame and averaged over C frames by the
     * temporal history; 0 or 1: every frame shades the whole set. A method
     * may choose its defaults by it (SSVP's second-bounce origin). */
    uint32_t cycle;
    /* With cycling: the slice (0 .. cycle - 1; slot i is in slice i mod
     * cycle) that the first frame to shade this update's set shades, and
     * how many slices, 0 .. live - 1, that frame may shade or draw maps
     * for (the progressive warm-up's rotation and the slice drawn ahead;
     * 0: all). A method may spend its update on that slice (SMC's chains)
     * and leave the slots of slices >= live empty for now. */
    uint32_t slice, live;
} gi_vpl_inputs;

/* Method parameters from `--param KEY=VALUE` (repeatable). A method reads
 * the keys it knows with the gi_param_* helpers and rejects the others with
 * gi_params_check, so a typo is an error, never silently ignored. */
#define GI_MAX_PARAMS 32
typedef struct gi_params {
    uint32_t count;
    const char *key[GI_MAX_PARAMS];
    const char *value[GI_MAX_PARAMS];
} gi_params;

/* Splits "KEY=VALUE" into p (the strings must outlive p). */
pf_result gi_params_add(gi_params *p, const char *key_eq_value, pf_error *err);
/* Fails naming the first key of p that is not in `known` (NULL-terminated). */
pf_result gi_params_check(const gi_params *p, const char *method, const char *const *known, pf_error *err);
/* The value of `key` as an integer in [lo, hi] or a finite float in [lo, hi];
 * *out keeps its default when the key is absent. p may be NULL. */
pf_result gi_param_u32(const gi_params *p, const char *key, uint32_t lo, uint32_t hi, uint32_t *out, pf_error *err);
pf_result gi_param_f32(const gi_params *p, const char *key, float lo, float hi, float *out, pf_error *err);
/* The value of `key` as one of `names` (NULL-terminated): *out gets its
 * index, or keeps its default when the key is absent; another value is an
 * error that lists the names. */
pf_result gi_param_choice(const gi_params *p, const char *key, const char *const *names, uint32_t *out,
                          pf_error *err);

/* What a method's internal view (gi_vpl_method.view) is given: the frame's
 * camera and image, the VPL set the frame shaded with, and drawing helpers
 * that the view layer (src/view/gi_view.c) supplies, so a method draws its
 * own state without including the view's headers. A view only reads the
 * method's state (const); every helper is deterministic. With --pipeline on
 * the state is one update ahead of `vpls` (gi_indirect.h, "Pipelining"). */
typedef struct gi_vpl_view_ctx gi_vpl_view_ctx;
struct gi_vpl_view_ctx {
    const pf_scene *scene;
    const pf_rt *rt;
    const pf_camera *camera;
    uint32_t width, height;  /* of rgb: RGB8, top row first */
    const gi_vpl_set *vpls;  /* the set the frame shaded with */
    uint32_t vpl;            /* the chosen VPL (index into vpls; 0 when empty) */
    uint32_t bounces;        /* the frame's --bounces */
    void *canvas;            /* the view layer's own (legend record) */
    /* rgb <- the frame's final image, dimmed (a background for overlays) */
    void (*background)(const gi_vpl_view_ctx *c, uint8_t *rgb);
    /* world point -> continuous pixel position (x right, y down); 0 behind the camera */
    int (*project)(const gi_vpl_view_ctx *c, pf_vec3 p, float *x, float *y);
    /* 1 if the camera sees world point p (an Embree ray from the eye) */
    int (*visible)(const gi_vpl_view_ctx *c, pf_vec3 p);
    void (*fill)(const gi_vpl_view_ctx *c, uint8_t *rgb, int x, int y, int w, int h, const uint8_t col[3]);
    void (*line)(const gi_vpl_view_ctx *c, uint8_t *rgb, int x0, int y0, int x1, int y1, const uint8_t col[3]);
    /* text in the built-in font (scale 1); returns the width drawn */
    int (*text)(const gi_vpl_view_ctx *c, uint8_t *rgb, int x, int y, const char *s, const uint8_t col[3]);
    /* the heat colour map, t in [0, 1] (dark blue, red, yellow, white) */
    void (*heat)(float t, uint8_t col[3]);
    /* a categorical colour for index k (clusters, bounces) */
    void (*palette)(uint32_t k, uint8_t col[3]);
    /* the view's legend: a heat colour bar from lo to hi labelled `what`
     * (sqrt_scale: colours follow sqrt((v - lo) / (hi - lo))); the view
     * layer records the range (gi_view_legend) */
    void (*legend)(const gi_vpl_view_ctx *c, uint8_t *rgb, const char *what, float lo, float hi, int sqrt_scale);
    /* or a key: n swatches with their names under the title `what` */
    void (*key)(const gi_vpl_view_ctx *c, uint8_t *rgb, const char *what, const char *const *names,
                const uint8_t (*colours)[3], uint32_t n);
};

typedef struct gi_vpl_method {
    const char *name;
    const char *paper; /* what it implements, for captions */
    /* params may be NULL (all defaults). */
    pf_result (*create)(void **state, const gi_params *params, pf_error *err);
    /* Fills `out` (cleared first) with the frame's VPL set. */
    pf_result (*update)(void *state, const gi_vpl_inputs *in, gi_vpl_set *out, pf_error *err);
    void (*destroy)(void *state);
    /* Optional (NULL: none): where the last update's time went, in the
     * method's own parts (SMC: Hedman 2017 Table 2's columns), for `softgi
     * bench frame`. The times never feed back into results. */
    const pf_stage_times *(*parts)(const void *state);
    /* 1 if update never reads the G-buffer: the method starts at the lights
     * only (IR, IIR), so its pipelined update may start before the G-buffer
     * exists (gi_indirect.h, "Pipelining"). 0, the safe default, for the
     * methods with camera-side samples (SMC's X, TCAS's and InvTM's
     * importance, SSVP's screen-space VPLs, MIR's camera paths). */
    int gbuffer_free;
    /* Optional (NULL: none), for learners (gi_view.h's
     * GI_VIEW_METHOD and captions). Kept at the end so positional
     * initialisers stay valid.
     * why: one line, why the method chooses its VPLs this way, with the
     * paper section ("IIR keeps valid VPLs ... (Laine 2007 Sec. 4.2)").
     * view_caption: what `view` draws, one line.
     * view: draws the method's own state into rgb (ctx->width x height);
     * returns 0 when it has nothing to show (rgb then undefined).
     * bounce: the light bounce VPL v stands for (1 = lit directly by a
     * light), 0 when the method does not know; `bounces` is the frame's
     * --bounces. Reads v (and its id) only. */
    const char *why;
    const char *view_caption;
    int (*view)(const void *state, const gi_vpl_view_ctx *ctx, uint8_t *rgb);
    uint32_t (*bounce)(const void *state, const gi_vpl *v, uint32_t bounces);
} gi_vpl_method;

/* The methods softgi has, by name ("ir", "iir", ...). NULL if unknown. */
const gi_vpl_method *gi_vpl_method_find(const char *name);
/* Comma-separated names, for messages. */
const char *gi_vpl_method_names(void);

pf_result gi_vpl_set_reserve(gi_vpl_set *set, uint32_t count, pf_error *err);
void gi_vpl_set_free(gi_vpl_set *set);

/* The methods (one file each). */
extern const gi_vpl_method gi_method_ir;    /* gi_ir.c: Instant Radiosity (Keller 1997) */
extern const gi_vpl_method gi_method_iir;   /* gi_iir.c: Incremental Instant Radiosity (Laine 2007) */
extern const gi_vpl_method gi_method_smc;   /* gi_smc.c: Sequential Monte Carlo IR (Hedman 2017) */
extern const gi_vpl_method gi_method_mir;   /* gi_mir.c: MIR-style resampled light paths (Hedman 2017 Sec. 5.1) */
extern const gi_vpl_method gi_method_invtm; /* gi_invtm.c: inverse transform method on RSMs (Ritschel 2011) */
extern const gi_vpl_method gi_method_tcas;  /* gi_tcas.c: Metropolis-Hastings RSM sampling (Barak 2013) */
extern const gi_vpl_method gi_method_ssvp;  /* gi_ssvp.c: screen-space VPL propagation (Aranha) */

/* Radical inverse in base `base` of index i (Halton), exact in double. */
double gi_halton(uint32_t i, uint32_t base);

#endif
