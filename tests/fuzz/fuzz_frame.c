/* fuzz_frame: libFuzzer target that renders whole small GI frames.
 *
 * Each input is read as a description (layout below; missing bytes read as
 * zero) of a small scene built in memory and of the frame's settings:
 *
 * - a triangle soup of up to 16 triangles (or quads), each of one kind:
 *   ordinary, zero-area (a repeated position), collinear, tiny (1e-6 of the
 *   scene scale), huge (coordinates near the PF_SCENE_MAX_COORD = 1e7
 *   limit), or an axis-aligned quad (a floor or wall, so inputs see lit
 *   surfaces); scene scales from 1e-3 to 1e6; unit vertex normals (the
 *   face's, or a random unit vector); uvs in [-4, 4];
 * - 1-3 Lambertian materials (colour, alpha mask, emission: area lights),
 *   optionally with a small texture (1x1 .. 8x8, random wrap and filters);
 * - 0-4 point, spot or directional lights with the values the glTF loader
 *   accepts (finite, non-negative colour and intensity, cones in
 *   0 <= inner < outer <= 90 degrees), intensities 1e-3 .. 1e5;
 * - a camera through pf_camera_look_at (inputs it refuses are skipped);
 * - the frame: 8..40 x 6..30 pixels; rasterized or ray-traced G-buffer;
 *   any registered VPL method (gi_vpl_method_names) with cheap parameters,
 *   or VPLs placed by the input ("bytes", below);
 *   1-64 VPLs; paraboloid maps of 16, 32, 64 or 128 texels a side (the
 *   public gi_indirect_options.para_res; mostly small: they dominate);
 *   1-4 bounces; interleaving on (1..4 x 1..4 tiles) or off;
 *   visibility by paraboloid maps, rays or imperfect shadow maps; every
 *   filter; clamp default or 1..1000; pipelining on or off; indirect-only,
 *   direct-only or both; the rasterizer's SIMD path and Embree's ISA among
 *   those this CPU has; 16..128 shadow maps; 1-3 area strata, 1-8 area
 *   points;
 * - one or two frames, the second with a moved light and/or camera.
 *
 * The scene must pass pf_scene_validate (inputs it refuses are skipped), as
 * every scene the renderer gets does; a set-up step may still refuse it
 * with a message (skipped too; without a message it is a finding). Then the
 * target aborts if the final image holds a NaN, an infinity or a negative
 * value, and the sanitizers (ASan, UBSan with float-cast-overflow) catch the
 * rest: an index computed from a NaN, an out-of-bounds gather, a leak.
 * Clamp 0 (off) is not drawn: without the bound an infinity from 1/r^2 at
 * r -> 0 is the expected maths, not a bug.
 *
 * Speed: the job system (2 threads) is made once; Embree, the rasterizer
 * context and the frame are made per input, as the scene changes. Set
 * FUZZ_FRAME_VERBOSE=1 to print what an input decodes to (for triage).
 *
 * Byte layout, in order (u8 unless said; "u16" little-endian):
 *   width, height, flags, flags2, method, vpls, visibility, simd, isa,
 *   tiles, filter, bounces, shadow, area, scale,
 *   camera: eye 3 x u16, target 3 x u16, fovy,
 *   materials: count, then per material: r, g, b, a, flags, emission;
 *   texture (when a material asks): w, h, wrap, filter, then w h x 4 texels,
 *   lights: count, then per light: type, position 3 x u16, direction 3 x u16,
 *           r, g, b, intensity, inner, outer,
 *   triangles: count, then per triangle: kind, material, 9 x u16, normal
 *              mode, [quads: axis u16], per vertex: [normal 3 x u16], uv 2 x u16,
 *   the "bytes" method only: per VPL: mode, [position], [normal], r, g, b, scale,
 *   frame 2 motion: 3 x u16.
 * The layout is a file format: the findings kept in tests/fuzz/regress/frame/
 * and the seeds (written by a generator that follows it) mean what they
 * mean only under it. A change to it must re-capture them. */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gi_frame.h"
#include "gi_indirect.h"
#include "gi_vpl.h"
#include "pf_fpenv.h"
#include "pf_isa.h"
#include "pf_jobs.h"
#include "pf_rt.h"
#include "pf_scene.h"
#include "pf_timer.h"
#include "rs_raster.h"

#define FZ_MAX_TRIS 16
#define FZ_MAX_LIGHTS 4
#define FZ_MAX_METHODS 32

/* ---------------------------------------------------------------- input */

typedef struct fz_in {
    const uint8_t *p;
    size_t n;
} fz_in;

static uint8_t fz_u8(fz_in *in)
{
    if (in->n == 0) return 0;
    in->n--;
    return *in->p++;
}

static uint16_t fz_u16(fz_in *in)
{
    uint16_t lo = fz_u8(in);
    return (uint16_t)(lo | (uint16_t)fz_u8(in) << 8);
}

/* [0, 1] from a u8 / u16 */
static float fz_unit8(fz_in *in) { return (float)fz_u8(in) / 255.0f; }
static float fz_unit16(fz_in *in) { return (float)fz_u16(in) / 65535.0f; }
/* [-s, s] on a grid of 65535 steps that holds -s, 0 and s exactly (exact
 * zeros and shared coordinates are where degenerate cases live) */
static float fz_sym(fz_in *in, float s)
{
    int32_t k = (int32_t)fz_u16(in) - 32768; /* -32768 .. 32767 */
    if (k < -32767) k = -32767;
    return (float)k / 32767.0f * s;
}
static pf_vec3 fz_vec(fz_in *in, float s)
{
    float x = fz_sym(in, s), y = fz_sym(in, s);
    return pf_v3(x, y, fz_sym(in, s));
}

/* a unit vector (a zero draw gives -y) */
static pf_vec3 fz_unit_dir(fz_in *in)
{
    pf_vec3 d = pf_v3_normalize_safe(fz_vec(in, 1.0f));
    return pf_v3_length(d) > 0.5f ? d : pf_v3(0.0f, -1.0f, 0.0f);
}

/* ---------------------------------------------------------------- state */

static pf_jobs *fz_jobs;
static const gi_vpl_method *fz_methods[FZ_MAX_METHODS];
static uint32_t fz_method_count;
static pf_isa fz_best_isa;
static int fz_verbose;

/* Cheap parameters per method, so an input renders in a few milliseconds
 * (the defaults are sized for 2048 VPLs and 640x480: TCAS's 128^2 RSMs took
 * 2.8 s a frame here). A method not listed runs with its defaults. */
typedef struct fz_method_params {
    const char *name;
    const char *params[6];
} fz_method_params;

static const fz_method_params fz_cheap[] = {
    {"smc", {"warmup=3", "points=256", "spp=4", "ratio=4", NULL}},
    {"mir", {"ratio=8", "points=256", NULL}},
    {"invtm", {"rsm=16", "P=16", NULL}},
    {"tcas", {"rsm=16", "P=16", "M=4", NULL}},
    {"ssvp", {"rsm_res=16", "map_res=16", "clusters=4", "first=64", "second=16", "iters=3"}},
};

/* The "bytes" VPL method: VPLs placed by the input, not by light paths,
 * so the stages after the update (maps, split, assign, accumulate, filter)
 * see the sets no sampler makes on purpose but a method may: a VPL exactly
 * at the origin (where the split buffers keep background pixels), exactly
 * at a scene vertex (a G-buffer point), on an axis with an axis-aligned
 * normal, two VPLs at one point. Drawn as one more method beside the
 * registered ones. */
#define FZ_MAX_VPLS 64
typedef struct fz_vpl_spec {
    uint32_t count;
    gi_vpl v[FZ_MAX_VPLS];
} fz_vpl_spec;
static fz_vpl_spec fz_spec;

static pf_result fz_bytes_create(void **state, const gi_params *params, pf_error *err)
{
    (void)params;
    (void)err;
    *state = &fz_spec;
    return PF_OK;
}

static pf_result fz_bytes_update(void *state, const gi_vpl_inputs *in, gi_vpl_set *out, pf_error *err)
{
    const fz_vpl_spec *sp = state;
    out->count = 0;
    uint32_t n = sp->count < in->budget ? sp->count : in->budget;
    pf_result r = gi_vpl_set_reserve(out, n, err);
    if (r != PF_OK) return r;
    for (uint32_t i = 0; i < n; i++) {
        out->v[i] = sp->v[i];
        out->v[i].moved = in->frame == 0; /* static after the first frame */
    }
    out->count = n;
    return PF_OK;
}

static void fz_bytes_destroy(void *state) { (void)state; }

static const gi_vpl_method fz_method_bytes = {.name = "bytes",
                                              .paper = "fuzz_frame: VPLs from the input",
                                              .create = fz_bytes_create,
                                              .update = fz_bytes_update,
                                              .destroy = fz_bytes_destroy};

static void fz_build_vpls(fz_in *in, const pf_scene *s, float scale, uint32_t count)
{
    static const pf_vec3 axes[6] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
    fz_spec.count = count;
    for (uint32_t i = 0; i < count; i++) {
        gi_vpl *v = &fz_spec.v[i];
        uint8_t mode = fz_u8(in);
        switch (mode % 4) {
        case 0: v->pos = fz_vec(in, scale); break;
        case 1: v->pos = s->positions[fz_u8(in) % s->vertex_count]; break; /* exactly on the scene */
        case 2: v->pos = pf_v3(0.0f, 0.0f, 0.0f); break;                    /* where background pixels are */
        default: v->pos = pf_v3(0.0f, fz_sym(in, scale), 0.0f); break;       /* on the y axis */
        }
        v->nrm = (mode / 4) % 2 ? fz_unit_dir(in) : axes[(mode / 8) % 6];
        v->intensity = pf_v3(fz_unit8(in), fz_unit8(in), fz_unit8(in));
        v->intensity = pf_v3_scale(v->intensity, powf(10.0f, 4.0f * fz_unit8(in) - 2.0f)); /* up to 100 */
        v->id = i;
        v->moved = 1;
    }
}

int LLVMFuzzerInitialize(int *argc, char ***argv)
{
    (void)argc;
    (void)argv;
    pf_fpenv_set(); /* as main() does: FTZ/DAZ, round to nearest */
    fz_jobs = pf_jobs_create(2);
    if (!fz_jobs) abort();
    fz_best_isa = pf_isa_detect();
    fz_verbose = getenv("FUZZ_FRAME_VERBOSE") != NULL;
    /* every registered method, by its names list ("ir, iir, smc, ...") */
    char names[512];
    snprintf(names, sizeof names, "%s", gi_vpl_method_names());
    for (char *tok = strtok(names, ", "); tok && fz_method_count < FZ_MAX_METHODS; tok = strtok(NULL, ", ")) {
        const gi_vpl_method *m = gi_vpl_method_find(tok);
        if (m) fz_methods[fz_method_count++] = m;
    }
    if (fz_method_count == 0) abort();
    return 0;
}

/* ---------------------------------------------------------------- scene */

/* Appends triangle (a, b, c) with material m; normal mode: 0 face normal,
 * 1 random unit normals per vertex, 2 face normal flipped. */
static void fz_add_tri(pf_scene *s, pf_vec3 a, pf_vec3 b, pf_vec3 c, uint32_t m, uint8_t nmode, fz_in *in)
{
    uint32_t v0 = s->vertex_count, t = s->tri_count;
    pf_vec3 p[3] = {a, b, c};
    pf_vec3 fn = pf_v3_normalize_safe(pf_v3_cross(pf_v3_sub(b, a), pf_v3_sub(c, a)));
    if (!(pf_v3_length(fn) > 0.5f)) fn = pf_v3(0.0f, 1.0f, 0.0f);
    if (nmode % 3 == 2) fn = pf_v3_scale(fn, -1.0f);
    for (int k = 0; k < 3; k++) {
        s->positions[v0 + k] = p[k];
        s->normals[v0 + k] = nmode % 3 == 1 ? fz_unit_dir(in) : fn;
        s->uvs[v0 + k] = (pf_vec2){fz_sym(in, 4.0f), fz_sym(in, 4.0f)};
        s->indices[3 * t + k] = v0 + (uint32_t)k;
    }
    s->tri_material[t] = m;
    s->vertex_count += 3;
    s->tri_count++;
}

static const char *const fz_kind_name[] = {"ordinary", "zero-area", "collinear", "tiny", "huge", "quad"};

static void fz_build_triangles(pf_scene *s, fz_in *in, float scale)
{
    uint32_t count = 1 + fz_u8(in) % FZ_MAX_TRIS;
    /* a quad is two triangles */
    s->positions = calloc(6 * count + 1, sizeof(pf_vec3)); /* +1: Embree's padding */
    s->normals = calloc(6 * count, sizeof(pf_vec3));
    s->uvs = calloc(6 * count, sizeof(pf_vec2));
    s->indices = calloc(6 * count, sizeof(uint32_t));
    s->tri_material = calloc(2 * count, sizeof(uint32_t));
    if (!s->positions || !s->normals || !s->uvs || !s->indices || !s->tri_material) abort();
    const float huge = 0.99f * PF_SCENE_MAX_COORD;
    for (uint32_t i = 0; i < count; i++) {
        uint8_t kind = fz_u8(in) % 6;
        uint32_t m = fz_u8(in) % s->material_count;
        pf_vec3 a = fz_vec(in, scale), b = fz_vec(in, scale), c = fz_vec(in, scale);
        uint8_t nmode = fz_u8(in);
        switch (kind) {
        case 0: break;
        case 1: c = b; break;                                            /* zero area */
        case 2: c = pf_v3_add(a, pf_v3_scale(pf_v3_sub(b, a), 2.0f * c.x / scale)); break; /* collinear */
        case 3: /* tiny: within 1e-6 of the scale around a */
            b = pf_v3_add(a, pf_v3_scale(b, 1e-6f));
            c = pf_v3_add(a, pf_v3_scale(c, 1e-6f));
            break;
        case 4: /* huge, within the limit */
            a = pf_v3_scale(a, huge / scale);
            b = pf_v3_scale(b, huge / scale);
            c = pf_v3_scale(c, huge / scale);
            break;
        case 5: { /* an axis-aligned quad of half-size |b.x| around a, normal along axis c */
            int axis = (int)(fz_unit16(in) * 2.999f);
            float h = fabsf(b.x) + 0.01f * scale, sign = c.y < 0.0f ? -1.0f : 1.0f;
            pf_vec3 u = axis == 0 ? pf_v3(0, 0, h) : axis == 1 ? pf_v3(h, 0, 0) : pf_v3(0, h, 0);
            pf_vec3 v = axis == 0 ? pf_v3(0, h, 0) : axis == 1 ? pf_v3(0, 0, h) : pf_v3(h, 0, 0);
            v = pf_v3_scale(v, sign);
            pf_vec3 q0 = pf_v3_sub(pf_v3_sub(a, u), v), q1 = pf_v3_sub(pf_v3_add(a, u), v);
            pf_vec3 q2 = pf_v3_add(pf_v3_add(a, u), v), q3 = pf_v3_add(pf_v3_sub(a, u), v);
            fz_add_tri(s, q0, q1, q2, m, nmode, in);
            a = q0, b = q2, c = q3;
            break;
        }
        }
        fz_add_tri(s, a, b, c, m, nmode, in);
        if (fz_verbose)
            fprintf(stderr, "  tri %u: %s, material %u, (%g %g %g) (%g %g %g) (%g %g %g)\n", i, fz_kind_name[kind], m,
                    (double)a.x, (double)a.y, (double)a.z, (double)b.x, (double)b.y, (double)b.z, (double)c.x,
                    (double)c.y, (double)c.z);
    }
}

static void fz_build_materials(pf_scene *s, fz_in *in)
{
    s->material_count = 1 + fz_u8(in) % 3;
    s->materials = calloc(s->material_count, sizeof(pf_material));
    if (!s->materials) abort();
    int want_texture = 0;
    for (uint32_t i = 0; i < s->material_count; i++) {
        pf_material *m = &s->materials[i];
        snprintf(m->name, sizeof m->name, "fuzz%u", i);
        for (int k = 0; k < 4; k++) m->base_color[k] = fz_unit8(in);
        uint8_t flags = fz_u8(in), e = fz_u8(in);
        m->base_color_texture = -1;
        m->alpha_mode = flags & 1 ? PF_ALPHA_MASK : (flags & 2 ? PF_ALPHA_BLEND : PF_ALPHA_OPAQUE);
        m->alpha_cutoff = 0.5f;
        m->double_sided = (flags >> 2) & 1;
        if (flags & 8) { /* an emitter: an area light, radiance up to 100 */
            float le = 100.0f * (float)e / 255.0f;
            m->emission[0] = le * m->base_color[0];
            m->emission[1] = le;
            m->emission[2] = le * m->base_color[2];
        }
        if (flags & 16) {
            m->base_color_texture = 0;
            want_texture = 1;
        }
    }
    if (!want_texture) return;
    uint32_t w = 1 + fz_u8(in) % 8, h = 1 + fz_u8(in) % 8;
    uint8_t wrap = fz_u8(in), filt = fz_u8(in);
    uint8_t rgba[8 * 8 * 4];
    for (uint32_t i = 0; i < sizeof rgba; i++) rgba[i] = i < w * h * 4 ? fz_u8(in) : 0;
    s->images = calloc(1, sizeof(pf_image));
    s->textures = calloc(1, sizeof(pf_texture));
    if (!s->images || !s->textures) abort();
    s->image_count = s->texture_count = 1;
    pf_error err;
    if (pf_image_build_mips(&s->images[0], rgba, w, h, &err) != PF_OK) {
        fprintf(stderr, "fuzz_frame: pf_image_build_mips(%ux%u) failed: %s\n", w, h, err.message);
        abort(); /* a valid small image must build */
    }
    pf_texture *t = &s->textures[0];
    t->image = 0;
    t->wrap_s = (pf_wrap)(wrap % 3);
    t->wrap_t = (pf_wrap)((wrap / 3) % 3);
    t->mag_linear = filt & 1;
    t->min_linear = (filt >> 1) & 1;
    t->min_mipmap = (filt >> 2) & 1;
    t->mip_linear = (filt >> 3) & 1;
}

static void fz_build_lights(pf_scene *s, fz_in *in, float scale)
{
    uint32_t count = fz_u8(in) % (FZ_MAX_LIGHTS + 1);
    for (uint32_t i = 0; i < count; i++) {
        pf_light l;
        memset(&l, 0, sizeof l);
        l.type = (pf_light_type)(fz_u8(in) % 3);
        snprintf(l.name, sizeof l.name, "fuzz-light%u", i);
        l.position = fz_vec(in, 1.5f * scale);
        l.direction = fz_unit_dir(in);
        l.color = pf_v3(fz_unit8(in), fz_unit8(in), fz_unit8(in));
        l.intensity = powf(10.0f, 8.0f * fz_unit8(in) - 3.0f); /* 1e-3 .. 1e5 W/sr or W/m^2 */
        float outer = 0.5f * PF_PI * (float)(1 + fz_u8(in)) / 256.0f; /* (0, pi/2] */
        float inner = outer * (float)fz_u8(in) / 256.0f;                /* [0, outer) */
        l.inner_cone = inner;
        l.outer_cone = outer;
        if (pf_scene_add_light(s, &l, NULL) != PF_OK) abort();
        if (fz_verbose)
            fprintf(stderr, "  light %u: type %d at (%g %g %g) dir (%g %g %g) colour (%g %g %g) I %g cones %g %g\n", i,
                    (int)l.type, (double)l.position.x, (double)l.position.y, (double)l.position.z,
                    (double)l.direction.x, (double)l.direction.y, (double)l.direction.z, (double)l.color.x,
                    (double)l.color.y, (double)l.color.z, (double)l.intensity, (double)inner, (double)outer);
    }
}

/* ---------------------------------------------------------------- frame */

typedef struct fz_frame_cfg {
    uint32_t width, height;
    int raytrace, two_frames, move_light, move_camera, direct_only;
    uint32_t shadow_size, strata, points;
    rs_simd simd;
    pf_isa isa;
    gi_indirect_options io;
    int indirect_only;
} fz_frame_cfg;

static void fz_check_image(const gi_frame *f, const fz_frame_cfg *c, int frame)
{
    size_t n = (size_t)f->width * f->height * 3;
    for (size_t i = 0; i < n; i++) {
        float v = f->final[i];
        if (isfinite(v) && v >= 0.0f) continue;
        size_t px = i / 3;
        fprintf(stderr,
                "\nfuzz_frame: frame %d, final pixel (%zu, %zu) channel %zu is %g (direct %g); %ux%u, %s, method %s, "
                "%u VPLs, visibility %s, simd %s, isa %s\n",
                frame, px % f->width, px / f->width, i % 3, (double)v, (double)f->direct[i], f->width, f->height,
                c->raytrace ? "ray-traced" : "rasterized", c->io.method->name, c->io.vpls,
                c->io.visibility_raytrace ? "raytrace"
                : c->io.visibility_ism    ? "ism"
                : c->io.para_slope        ? "paraboloid-slope"
                                          : "paraboloid",
                rs_simd_name(c->simd), pf_isa_name(c->isa));
        if (f->indirect)
            fprintf(stderr, "  indirect: combined %g filtered %g\n", (double)f->ind.combined[i],
                    (double)f->ind.filtered[i]);
        abort();
    }
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    fz_in in = {data, size};
    fz_frame_cfg c;
    memset(&c, 0, sizeof c);

    /* ---- settings */
    c.width = 8 + fz_u8(&in) % 33;
    c.height = 6 + fz_u8(&in) % 25;
    uint8_t flags = fz_u8(&in), flags2 = fz_u8(&in);
    c.raytrace = flags & 1;
    c.two_frames = (flags >> 1) & 1;
    c.io.pipeline = (flags >> 2) & 1;
    c.io.no_interleave = (flags >> 3) & 1;
    c.indirect_only = (flags >> 4) & 1;
    c.direct_only = (flags >> 5) & 1 && !c.indirect_only;
    c.move_light = (flags >> 6) & 1;
    c.move_camera = (flags >> 7) & 1;
    /* paraboloid map resolution: mostly small, as the maps dominate the time */
    static const uint32_t para_res[4] = {32, 16, 64, 0 /* RS_PARA_DEFAULT_RES, 128 */};
    c.io.para_res = para_res[(flags2 >> 1) & 3];
    uint8_t method = fz_u8(&in); /* a quarter of the inputs: the "bytes" method */
    c.io.method = (method & 0xc0) == 0xc0 ? &fz_method_bytes : fz_methods[method % fz_method_count];
    c.io.vpls = 1 + fz_u8(&in) % 64;
    uint8_t vis = fz_u8(&in);
    c.io.visibility_raytrace = vis % 3 == 1;
    c.io.visibility_ism = vis % 3 == 2;
    c.io.para_slope = vis % 3 == 0 && (vis & 0x80); /* exact maps: the slope-scaled bias test for half */
    if (c.io.visibility_ism) {
        c.io.ism.resolution = 8u << ((vis / 3) % 3); /* 8, 16, 32 */
        c.io.ism.points = 1000u + 1000u * ((vis / 9) % 20);
        c.io.ism.bias_scale = 1.0f + (float)((vis / 180) % 4);
    }
    /* the SIMD paths and Embree ISAs this CPU has */
    rs_simd simds[3] = {RS_SIMD_SCALAR};
    uint32_t nsimd = 1;
    if (fz_best_isa >= PF_ISA_AVX2) simds[nsimd++] = RS_SIMD_AVX2;
    if (fz_best_isa >= PF_ISA_AVX512) simds[nsimd++] = RS_SIMD_AVX512;
    c.simd = simds[fz_u8(&in) % nsimd];
    c.isa = (pf_isa)(PF_ISA_SSE2 + fz_u8(&in) % ((uint32_t)fz_best_isa - PF_ISA_SSE2 + 1));
    uint8_t tiles = fz_u8(&in);
    c.io.tiles_n = 1 + tiles % 4;
    c.io.tiles_m = 1 + (tiles / 4) % 4;
    uint8_t filt = fz_u8(&in);
    const gi_filter_kind filters[] = {GI_FILTER_BOX, GI_FILTER_BILATERAL, GI_FILTER_NONE, GI_FILTER_GAUSSIAN,
                                      GI_FILTER_ATROUS};
    c.io.filter = filters[filt % 5];
    c.io.clamp = (filt / 4) % 2 ? 1.0f + 999.0f * (float)(filt / 8) / 31.0f : -1.0f; /* default 400 or 1..1000 */
    c.io.bounces = 1 + fz_u8(&in) % 4;
    c.shadow_size = 16u << (fz_u8(&in) % 4);
    uint8_t area = fz_u8(&in);
    c.strata = 1 + area % 3;
    c.points = 1 + (area / 3) % 8;
    static const float scales[] = {1e-3f, 1.0f, 1.0f, 10.0f, 100.0f, 1e4f, 1e6f};
    float scale = scales[fz_u8(&in) % (sizeof scales / sizeof scales[0])];
    pf_vec3 eye = fz_vec(&in, 2.0f * scale), target = fz_vec(&in, scale);
    float fovy = pf_radians(1.0f + 178.0f * fz_unit8(&in));
    for (size_t i = 0; i < sizeof fz_cheap / sizeof fz_cheap[0]; i++)
        if (!strcmp(fz_cheap[i].name, c.io.method->name))
            for (int k = 0; k < 6 && fz_cheap[i].params[k]; k++)
                if (gi_params_add(&c.io.params, fz_cheap[i].params[k], NULL) != PF_OK) abort();

    if (fz_verbose)
        fprintf(stderr,
                "fuzz_frame: %ux%u %s, method %s, %u VPLs (maps %u), %u bounces, tiles %ux%u%s, visibility %s, filter %d, "
                "clamp %g, pipeline %d, %s, simd %s, isa %s, shadow %u, strata %u, points %u, scale %g, %s frame(s)\n",
                c.width, c.height, c.raytrace ? "ray-traced" : "rasterized", c.io.method->name, c.io.vpls, c.io.para_res, c.io.bounces, c.io.tiles_n, c.io.tiles_m,
                c.io.no_interleave ? " (off)" : "",
                c.io.visibility_raytrace ? "raytrace" : c.io.visibility_ism ? "ism" : "paraboloid", (int)c.io.filter,
                (double)c.io.clamp, c.io.pipeline,
                c.direct_only ? "direct only" : c.indirect_only ? "indirect only" : "direct + indirect",
                rs_simd_name(c.simd), pf_isa_name(c.isa), c.shadow_size, c.strata, c.points, (double)scale,
                c.two_frames ? "2" : "1");

    /* ---- scene */
    pf_scene scene;
    memset(&scene, 0, sizeof scene);
    fz_build_materials(&scene, &in);
    fz_build_lights(&scene, &in, scale);
    fz_build_triangles(&scene, &in, scale);
    if (c.io.method == &fz_method_bytes) fz_build_vpls(&in, &scene, scale, c.io.vpls);
    pf_vec3 motion = fz_vec(&in, 0.1f * scale);
    pf_error err;
    memset(&err, 0, sizeof err);
    pf_camera cam;
    if (pf_scene_validate(&scene, &err) != PF_OK || pf_camera_look_at(&cam, eye, target, fovy, &err) != PF_OK) {
        if (fz_verbose) fprintf(stderr, "fuzz_frame: skipped: %s\n", err.message);
        pf_scene_free(&scene);
        return -1; /* not added to the corpus */
    }

    /* ---- Embree, rasterizer, frame */
    pf_rt *rt = NULL;
    rs_context *rs = NULL;
    gi_frame f;
    memset(&f, 0, sizeof f);
    int have_frame = 0;
    double t0 = pf_time_now();
    pf_result r = pf_rt_create(&rt, &scene, c.isa, 1, &err);
    double t_rt = pf_time_now();
    if (r == PF_OK && !c.raytrace) r = rs_context_create(&rs, &scene, fz_jobs, c.simd, &err);
    if (r == PF_OK) {
        gi_frame_desc fd = {.scene = &scene, .rt = rt, .jobs = fz_jobs, .raster = rs, .camera = &cam,
                            .width = c.width, .height = c.height, .shadow_size = c.shadow_size,
                            .area_strata = c.strata, .area_points = c.points,
                            .indirect = c.direct_only ? NULL : &c.io, .indirect_only = c.indirect_only};
        r = gi_frame_create(&f, &fd, &err);
        have_frame = r == PF_OK;
    }
    if (r != PF_OK) {
        /* A refusal with a message is a legitimate answer (e.g. imperfect
         * shadow maps refuse a scene whose triangles all have zero area,
         * which pf_scene_validate accepts and the loader never produces);
         * one without a message is a bug. */
        if (err.message[0] == 0) {
            fprintf(stderr, "fuzz_frame: set-up failed (%d) without a message\n", (int)r);
            abort();
        }
        if (fz_verbose) fprintf(stderr, "fuzz_frame: set-up refused: %s\n", err.message);
        if (have_frame) gi_frame_free(&f);
        rs_context_destroy(rs);
        pf_rt_destroy(rt);
        pf_scene_free(&scene);
        return -1;
    }

    /* ---- one or two frames */
    for (int frame = 0; frame < (c.two_frames ? 2 : 1); frame++) {
        if (frame == 1) {
            if (c.move_light && scene.light_count > 0)
                scene.lights[0].position = pf_v3_add(scene.lights[0].position, motion);
            if (c.move_camera) {
                pf_camera moved;
                if (pf_camera_look_at(&moved, pf_v3_add(eye, motion), target, fovy, &err) == PF_OK) f.camera = moved;
            }
        }
        if (c.raytrace) gi_frame_render_raytraced(&f);
        else gi_frame_render_raster(&f);
        fz_check_image(&f, &c, frame);
        if (fz_verbose) {
            fprintf(stderr, "fuzz_frame: frame %d stages (ms):", frame);
            for (uint32_t i = 0; i < f.times.count; i++)
                fprintf(stderr, " %s %.1f;", f.times.name[i], f.times.ms[i]);
            fputc('\n', stderr);
        }
    }
    if (fz_verbose)
        fprintf(stderr, "fuzz_frame: embree %.1f ms, set-up + frames %.1f ms\n", (t_rt - t0) * 1e3,
                (pf_time_now() - t_rt) * 1e3);

    if (have_frame) gi_frame_free(&f);
    rs_context_destroy(rs);
    pf_rt_destroy(rt);
    pf_scene_free(&scene);
    return 0;
}
