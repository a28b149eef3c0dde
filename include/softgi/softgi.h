/* softgi.h: softgi as a library. One header, one opaque context, plain C.
 *
 * What it does: loads a glTF 2.0 scene (.gltf or .glb), renders frames of it
 * with the many-light (VPL) global illumination `softgi render` computes,
 * into buffers the caller owns, and reads back any stage of the frame
 * (G-buffer planes, direct light, irradiance before and after the filter,
 * the final radiance) and what each stage took. The image is, bit for bit,
 * the one `softgi render` writes with the same options (docs/api.md).
 *
 *   softgi_desc d = {.width = 640, .height = 480};      zero means default
 *   softgi_error err;
 *   softgi_context *ctx = softgi_create(&d, &err);
 *   if (!ctx) { fprintf(stderr, "%s\n", err.message); return 1; }
 *   if (softgi_load_scene(ctx, "scene.glb", &err) != SOFTGI_OK) ...
 *   float *rgb = malloc(640 * 480 * 3 * sizeof(float));
 *   softgi_target t = {.rgb = rgb};
 *   if (softgi_render(ctx, &t, &err) != SOFTGI_OK) ...
 *   softgi_destroy(ctx);
 *
 * Conventions (the same as the program's; docs/scenes.md):
 * - right-handed world, +Y up, the glTF file's units; cameras look from
 *   `eye` at `target` with a vertical field of view in degrees;
 * - light units: point and spot lights in W/sr, directional lights in W/m^2
 *   (KHR_lights_punctual); colours linear RGB;
 * - images are row-major from the top row; linear radiance as 3 floats a
 *   pixel (RGB), the display image as 4 bytes a pixel (sRGB after the
 *   tone map x / (1 + x) at 2^exposure, alpha 255), as the PNG the program
 *   writes; strides count elements (floats or bytes) from one row to the
 *   next, 0 meaning tightly packed.
 *
 * Errors: every fallible call returns a softgi_result and, when `err` is
 * not NULL, fills it with the code and a one-line message meant for a user
 * ("scene.gltf: accessor 3 reads past the end of bufferView 1 ..."). `err`
 * may always be NULL. A failing call leaves the context usable (a failed
 * load leaves it without a scene). Nothing is printed.
 *
 * Lifetimes: the context owns everything it allocates (scene, Embree scene,
 * rasterizer, frame buffers, worker threads); softgi_destroy frees it all.
 * Strings a call returns stay valid until the next softgi_load_scene or
 * softgi_destroy on that context (static strings: forever).
 *
 * Threads: a context starts desc.threads - 1 worker threads; the calling
 * thread is the last worker. One context must not be used by two threads
 * at once; distinct contexts share nothing and may be used concurrently
 * (each with its own workers). softgi_load_scene, softgi_render (and
 * softgi_set_camera, when it moves the automatic light) set
 * flush-to-zero / denormals-are-zero / round-to-nearest on the calling
 * thread for the call's duration and restore the caller's setting after. */
#ifndef SOFTGI_H
#define SOFTGI_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/* Result codes: the program's table (src/base/pf_result.h), value for value. */
typedef enum softgi_result {
    SOFTGI_OK = 0,
    SOFTGI_ERR_IO,            /* file missing or unreadable                         */
    SOFTGI_ERR_PARSE,         /* not a glTF file softgi can parse                   */
    SOFTGI_ERR_ACCESSOR,      /* accessor or bufferView out of range / malformed     */
    SOFTGI_ERR_INDEX_RANGE,   /* vertex index or object reference out of range       */
    SOFTGI_ERR_NONFINITE,     /* NaN / inf / huge coordinate or value                */
    SOFTGI_ERR_NO_TRIANGLES,  /* nothing to render                                   */
    SOFTGI_ERR_NO_CAMERA,     /* no camera                                           */
    SOFTGI_ERR_TEXTURE,       /* missing or undecodable texture image                */
    SOFTGI_ERR_UNSUPPORTED,   /* valid glTF using something softgi cannot do         */
    SOFTGI_ERR_OUT_OF_MEMORY, /* allocation failed or the memory budget refused it  */
    SOFTGI_ERR_EMBREE,        /* Embree device / scene error                         */
    SOFTGI_ERR_ARGUMENT,      /* a bad value passed to the API, or a call out of order */
} softgi_result;

typedef struct softgi_error {
    softgi_result code;
    char message[512]; /* one line, no trailing newline */
} softgi_error;

/* Short stable name of a code ("i/o error", "bad argument"). */
const char *softgi_result_name(softgi_result code);
/* "0.1.0" */
const char *softgi_version(void);
/* The VPL methods softgi knows, comma separated ("ir, iir, smc, ..."). */
const char *softgi_method_names(void);

/* softgi_desc.flags */
#define SOFTGI_DIRECT_ONLY 1u   /* no VPLs: emission + direct light (--direct-only) */
#define SOFTGI_INDIRECT_ONLY 2u /* the VPLs' light alone (--indirect-only) */
#define SOFTGI_RAYTRACE 4u      /* Embree primary and shadow rays instead of the rasterizer (--raytrace) */
#define SOFTGI_NO_INTERLEAVE 8u /* one tile: every pixel sees every VPL (--no-interleave) */
#define SOFTGI_PIPELINE 16u     /* the next frame's VPL update overlaps this frame (--pipeline on); one
                                   frame is the same either way, later frames differ */
#define SOFTGI_COMPENSATE 32u   /* screen-space compensation of the energy the clamp removes
                                   (--compensate on) */
#define SOFTGI_FILTER_DISTANCE 64u /* the filter's position test as Laine 2007, |p2 - p| < alpha, instead
                                      of the distance from the pixel's tangent plane
                                      (--filter-test distance) */

/* softgi_desc.clamp: no bounded geometry term (--clamp 0). */
#define SOFTGI_CLAMP_OFF (-1.0f)

/* Progress of a frame (softgi_desc.progress), called on the thread that
 * called softgi_render: after every stage with `what` the stage's name (as
 * softgi_get_timings names it) and done = total = 0, and while a long stage
 * runs (the VPLs' maps of a large first frame) with done of total. It must
 * not call back into the context. */
typedef void (*softgi_progress_fn)(void *user, const char *what, uint32_t done, uint32_t total);

/* What a context renders. Zero-initialise it: every zero field means the
 * program's default (in brackets the `softgi render` option it equals). */
typedef struct softgi_desc {
    uint32_t width, height; /* image size, 1..16384 each; both 0: 640 x 480 (--size) */
    uint32_t threads;       /* threads including the caller's, 1..256; 0: the number of cores (--threads) */
    const char *isa;        /* "auto", "sse2", "sse4.2", "avx2", "avx512"; NULL: "auto" (--isa). The
                               image is the same for every ISA; pinning one is for benchmarks */
    uint64_t max_memory;    /* memory budget in bytes, at least 64 MiB; 0: half of the machine's
                               memory (--max-memory). Scenes and frames that would not fit are refused */
    const char *method;     /* VPL method (softgi_method_names); NULL: "ir" (--method) */
    uint32_t vpls;          /* VPL budget, 1..2^20; 0: 256 (--vpls) */
    uint32_t bounces;       /* light bounces of the VPLs, 1..64; 0: 3 (--bounces) */
    const char *const *params; /* the method's "KEY=VALUE" parameters (--param), param_count of them,
                                  at most 32; copied by softgi_create */
    uint32_t param_count;
    uint32_t flags;         /* SOFTGI_DIRECT_ONLY, SOFTGI_INDIRECT_ONLY, SOFTGI_RAYTRACE, SOFTGI_NO_INTERLEAVE,
                               SOFTGI_PIPELINE, SOFTGI_COMPENSATE, SOFTGI_FILTER_DISTANCE */
    /* the direct light */
    uint32_t shadow_size;   /* shadow-map texels per side, 16..8192; 0: 1024 (--shadow-size) */
    uint32_t area_strata;   /* ray-traced area lights: N x N samples a pixel, 1..16; 0: 4 (--area-strata) */
    uint32_t area_points;   /* rasterized area lights: K emitter points, 1..1024; 0: 32 (--area-points) */
    /* the many-light stages (ignored with SOFTGI_DIRECT_ONLY) */
    uint32_t tiles_n, tiles_m; /* interleaved tiles, 1..16 each, both or neither; 0: 4 x 4 (--tiles NxM) */
    float clamp;            /* bounded geometry term b = clamp / diagonal^2, > 0; 0: 400; SOFTGI_CLAMP_OFF:
                               none (--clamp C, --clamp 0) */
    const char *filter;     /* "box", "bilateral", "gaussian", "atrous", "none"; NULL: "box" (--filter) */
    const char *visibility; /* the VPLs' shadows: "paraboloid" (exact maps, receiver-plane test),
                               "paraboloid-slope" (exact maps, slope-scaled bias), "ism", "raytrace";
                               NULL: "paraboloid" (--visibility) */
    uint32_t ism_res;       /* visibility "ism" only: texels per side, a power of two 8..512; 0: 64 (--ism-res) */
    uint32_t ism_points;    /* visibility "ism" only: points a frame, 1000..1e8; 0: the default (--ism-points) */
    float ism_bias;         /* visibility "ism" only: bias scale, 1..64; 0: the default (--ism-bias) */
    uint32_t indirect_scale; /* the indirect stages at 1/N resolution, 1..4; 0: automatic, 2 from 1024x768
                                up, else 1 (--indirect-scale) */
    uint32_t temporal;      /* temporal accumulation over up to N frames, 2..256; 0: off (--temporal) */
    uint32_t vpl_cycle;     /* with temporal: C x vpls VPLs kept, one slice of vpls shaded a frame in turn,
                               2..64; 0: off (--vpl-cycle) */
    uint32_t cycle_maps;    /* with vpl_cycle: the progressive warm-up, the slices taken into the rotation one
                               by one, at most cycle_maps maps a frame drawn ahead; 0: every slice from the
                               first frame (--cycle-maps) */
    /* anti-aliasing */
    uint32_t aa;            /* jittered samples a pixel, averaged, 1..256; 0: 1, the pixel centres (--aa) */
    uint32_t taa;           /* temporal anti-aliasing over up to N frames, 2..256; 0: off (--taa, softgi
                               sequence and view) */
    /* progress of long frames (NULL: none) */
    softgi_progress_fn progress;
    void *progress_user;
} softgi_desc;

typedef struct softgi_context softgi_context;

/* Checks `desc` (NULL: every default), resolves the ISA and starts the
 * worker threads. NULL on failure, with the reason in *err. */
softgi_context *softgi_create(const softgi_desc *desc, softgi_error *err);
/* Frees everything the context owns and joins its threads. NULL is ignored. */
void softgi_destroy(softgi_context *ctx);

/* Loads a .gltf or .glb file (NULL: the Cornell box built into the
 * library, scenes/cornell-box), replacing the context's scene. The file is
 * untrusted input: every index and size is checked and the scene must fit
 * the memory budget together with a frame of the context's size, as for
 * `softgi render`. Without a camera in the file the scene is framed from
 * its bounds; without a light or an emissive triangle a point light is
 * added at the camera (the program's automatic camera and light,
 * docs/scenes.md; softgi_info says when). Then builds the Embree scene and
 * the rasterizer. */
softgi_result softgi_load_scene(softgi_context *ctx, const char *path, softgi_error *err);

/* A camera looking from eye at target (--camera ex,ey,ez:tx,ty,tz:fovy). */
typedef struct softgi_camera {
    float eye[3];
    float target[3];
    float fovy_deg; /* vertical field of view, (0, 180) */
} softgi_camera;

/* Replaces the scene's camera. Coordinates within +-1e7, eye != target.
 * Needs a loaded scene; holds until the next softgi_load_scene. Between
 * frames it moves the camera of a running frame (VPL methods keep their
 * state, as in `softgi sequence`). If the light is the automatic one it
 * moves with the camera, as `softgi render --camera` would place it. */
softgi_result softgi_set_camera(softgi_context *ctx, const softgi_camera *camera, softgi_error *err);

typedef enum softgi_light_type {
    SOFTGI_LIGHT_POINT = 0,
    SOFTGI_LIGHT_SPOT,
    SOFTGI_LIGHT_DIRECTIONAL,
} softgi_light_type;

/* One punctual light (--light point:..., spot:..., dir:...). */
typedef struct softgi_light {
    softgi_light_type type;
    float position[3];  /* point, spot: within +-1e7 */
    float direction[3]; /* spot, directional: the way the light travels; non-zero, normalised by softgi */
    float color[3];     /* linear RGB, >= 0 */
    float intensity;    /* point, spot: W/sr; directional: W/m^2; intensity x max(color) <= 1e12 */
    float inner_deg, outer_deg; /* spot: 0 <= inner < outer <= 90 */
} softgi_light;

/* Replaces the scene's punctual lights (emissive triangles stay lights) by
 * `count` lights, 1..64. Needs a loaded scene. The same number of lights
 * between frames moves them (only changed lights get new shadow maps); a
 * different number rebuilds the frame at the next render. */
softgi_result softgi_set_lights(softgi_context *ctx, const softgi_light *lights, uint32_t count, softgi_error *err);

/* Poses the loaded scene's glTF animations (node translation, rotation and
 * scale, skins, morph weights; docs/scenes.md) at `seconds` (finite,
 * 0..1e6), as `softgi render --time SECONDS --animation ANIMATION`.
 * `animation` NULL plays every animation of the file together (in file
 * order: where two animate the same property the later wins); else the
 * animation of that name, or of that index when it is all digits ("0").
 * Before an animation's first key its first value holds, after its last key
 * its last value. The vertex and triangle counts and order stay, so
 * triangle ids are stable. Geometry that moved updates the Embree scene,
 * the rasterizer and the frame in place (only what the moved geometry can
 * change is redrawn; docs/architecture.md "Moving geometry"): the frame
 * goes on, the VPL method keeps its state and is told what moved, as after
 * softgi_set_lights. The direct light and every map equal a fresh
 * context's posed there; the indirect image may differ from one by what
 * the method carries (as it does under a moving light). The
 * camera and the automatic light stay as loaded (chosen on the scene's
 * static pose), so set the camera first to have an automatic light placed
 * as the program places it. SOFTGI_ERR_ARGUMENT without a scene, for a
 * scene without animations, an unknown animation or a bad time;
 * SOFTGI_ERR_NONFINITE when the pose would put geometry beyond +-1e7 (the
 * scene stays as it was). Holds until the next softgi_load_scene. */
softgi_result softgi_set_time(softgi_context *ctx, double seconds, const char *animation, softgi_error *err);

/* Where softgi_render writes. Either pointer may be NULL (not wanted), not
 * both. Each must hold height rows of stride elements (the last row only
 * width pixels). */
typedef struct softgi_target {
    float *rgb;          /* linear radiance, 3 floats a pixel */
    size_t rgb_stride;   /* floats from one row to the next; 0: 3 x width */
    uint8_t *rgba8;      /* display image, 4 bytes a pixel (R, G, B, 255) */
    size_t rgba8_stride; /* bytes from one row to the next; 0: 4 x width */
    float exposure;      /* stops for rgba8: 2^exposure before the tone map (--exposure) */
    int auto_exposure;   /* 1: pick the exposure from the image instead (--exposure auto); the
                            exposure used is in softgi_info.exposure */
} softgi_target;

/* Renders the next frame of the loaded scene and writes it to `target`.
 * Frames after the first continue the VPL method's state (only new or
 * moved VPLs get new maps). A frame with a NaN, infinite or negative pixel
 * is an error (SOFTGI_ERR_NONFINITE) and nothing is written, as the
 * program refuses to write it. */
softgi_result softgi_render(softgi_context *ctx, const softgi_target *target, softgi_error *err);

/* The buffers of the last frame a learner or a tool may read. */
typedef enum softgi_stage {
    SOFTGI_STAGE_DEPTH = 0,  /* 1 channel: view depth, +inf where no surface */
    SOFTGI_STAGE_POSITION,   /* 3: world position (0 where no surface) */
    SOFTGI_STAGE_NORMAL,     /* 3: unit world normal, turned to the camera (0 where no surface) */
    SOFTGI_STAGE_ALBEDO,     /* 3: linear diffuse albedo (0 where no surface) */
    SOFTGI_STAGE_DIRECT,     /* 3: direct radiance (emission not included) */
    SOFTGI_STAGE_IRRADIANCE, /* 3: indirect irradiance (W/m^2) before the filter; needs VPLs */
    SOFTGI_STAGE_FILTERED,   /* 3: indirect irradiance after the filter; needs VPLs */
    SOFTGI_STAGE_FINAL,      /* 3: the composed linear radiance (what softgi_render writes) */
    SOFTGI_STAGE_COUNT
} softgi_stage;

/* Floats a pixel of `stage` has (1 or 3; 0 for an unknown stage). */
uint32_t softgi_stage_channels(softgi_stage stage);
/* Copies `stage` of the last frame into dst: height rows of `stride` floats
 * (0: channels x width). */
softgi_result softgi_read_stage(const softgi_context *ctx, softgi_stage stage, float *dst, size_t stride,
                                softgi_error *err);

/* One timed step. */
typedef struct softgi_timing {
    const char *name; /* static string: "load scene", "embree build", "raster setup", then the frame's stages
                         ("gbuffer raster", ..., "compose") as the program prints them */
    double ms;
} softgi_timing;

/* Fills up to `max` entries: the steps of the last softgi_load_scene, then
 * the stages of the last softgi_render, in the order they ran. Returns how
 * many there are (which may exceed max). Timings never change results. */
uint32_t softgi_get_timings(const softgi_context *ctx, softgi_timing *out, uint32_t max);

/* What a context is rendering. */
typedef struct softgi_info {
    uint32_t width, height, threads;
    const char *isa;      /* the resolved ISA, e.g. "avx2" */
    const char *method;   /* the VPL method, or NULL with SOFTGI_DIRECT_ONLY */
    int scene_loaded;
    uint32_t triangles;   /* of the loaded scene */
    uint32_t lights;      /* punctual lights */
    int auto_camera;      /* the camera was chosen from the scene's bounds */
    int auto_light;       /* the light was added at the camera */
    softgi_camera camera; /* the camera in use (a file's camera as eye, eye + forward, fovy) */
    const char *warnings; /* the loader's warnings, one a line; "" when none */
    uint32_t frames;      /* frames rendered since the scene was loaded */
    uint32_t vpls;        /* VPLs in the last frame */
    float exposure;       /* stops the last rgba8 output used */
    /* the last frame's many-light stages (0 / NULL without VPLs) */
    uint32_t maps_rendered;    /* VPL shadow maps rendered in the last frame (new or moved VPLs) */
    uint32_t tiles_n, tiles_m; /* interleaved tiles */
    float clamp_b;             /* the bounded geometry term b in 1/m^2 (infinity when off) */
    const char *visibility;    /* "paraboloid maps", "imperfect shadow maps" or "Embree rays" */
    uint32_t aa_samples;       /* jittered samples a pixel (1: none) */
    uint32_t indirect_scale;   /* the indirect stages ran at 1/indirect_scale of the resolution */
    uint32_t animations;       /* glTF animations of the loaded file (softgi_set_time) */
} softgi_info;

softgi_result softgi_get_info(const softgi_context *ctx, softgi_info *info, softgi_error *err);

/* softgi_dump_stages formats */
typedef enum softgi_dump_format {
    SOFTGI_DUMP_PNG = 1,  /* the captioned pictures, with legends (--dump-format png, the default) */
    SOFTGI_DUMP_EXR = 2,  /* the float data as 32-bit OpenEXR (--dump-format exr) */
    SOFTGI_DUMP_BOTH = 3, /* both (--dump-format both) */
} softgi_dump_format;

/* Writes every stage of the last frame into the folder `dir` (created if
 * missing) as `softgi render --dump-stages DIR` does: NN-name.png pictures
 * at `exposure` stops and/or NN-name.exr float data, and captions.txt
 * naming each stage and its paper section (docs/learn.md). */
softgi_result softgi_dump_stages(const softgi_context *ctx, const char *dir, float exposure,
                                 softgi_dump_format format, softgi_error *err);

/* The program's --hash of a linear image: FNV-1a 64 over the float bits of
 * the width x height x 3 floats (rows `stride` floats apart, 0: packed).
 * For golden-image tests: equal hashes, equal images. */
uint64_t softgi_image_hash(const float *rgb, uint32_t width, uint32_t height, size_t stride);

#ifdef __cplusplus
}
#endif

#endif
