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

typedef struct gi_vpl {
    pf_vec3 pos, nrm;
    pf_vec3 intensity; /* Phi * albedo / pi, RGB (W/sr at normal exitance) */
    uint32_t id;       /* stable while the VPL lives */
    uint32_t moved;    /* new, moved or re-weighted this frame */
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
} gi_vpl_inputs;

typedef struct gi_vpl_method {
    const char *name;
    const char *paper; /* what it implements, for captions */
    pf_result (*create)(void **state, pf_error *err);
    /* Fills `out` (cleared first) with the frame's VPL set. */
    pf_result (*update)(void *state, const gi_vpl_inputs *in, gi_vpl_set *out, pf_error *err);
    void (*destroy)(void *state);
} gi_vpl_method;

/* The methods softgi has, by name ("ir"). NULL if unknown. */
const gi_vpl_method *gi_vpl_method_find(const char *name);
/* Comma-separated names, for messages. */
const char *gi_vpl_method_names(void);

pf_result gi_vpl_set_reserve(gi_vpl_set *set, uint32_t count, pf_error *err);
void gi_vpl_set_free(gi_vpl_set *set);

/* The Instant Radiosity baseline (gi_ir.c). */
extern const gi_vpl_method gi_method_ir;

/* Radical inverse in base `base` of index i (Halton), exact in double. */
double gi_halton(uint32_t i, uint32_t base);

#endif
