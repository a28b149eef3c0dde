/* pf_sequence: sequence files for `softgi sequence`: a scene, a
 * frame count, and camera and light keyframes, linearly interpolated.
 *
 * Format (JSON, parsed with cJSON; keys are case-sensitive, unknown or
 * repeated keys are errors so a typo never passes silently; "comment" is
 * allowed in every object and ignored):
 *
 *   {
 *     "name": "cornell-light-move",          optional; default: the file name
 *                                            without .json / .seq.json (no '/',
 *                                            not "." or "..")
 *     "scene": "cornell-box.gltf",           required: a .gltf/.glb path relative
 *                                            to this file (or absolute), or
 *                                            "embedded:cornell-box"
 *     "frames": 48,                          required: 1..PF_SEQUENCE_MAX_FRAMES
 *     "size": [640, 480],                    optional (--size wins; default 640x480)
 *     "output": "renders/light",             optional folder under out/ (see
 *                                            "Where frames go"; -o wins;
 *                                            default out/<name>)
 *     "camera": [                            optional (absent: the scene's camera
 *       {"frame": 0,  "eye": [x,y,z],        or --camera, held still); every key
 *        "target": [x,y,z], "fovy_deg": 39}, has all four fields
 *       {"frame": 47, ...}
 *     ],
 *     "lights": [                            optional (absent: the scene's lights)
 *       {"light": 0,                         animates the scene's light 0 ...
 *        "keys": [{"frame": 0, "position": [x,y,z]}, {"frame": 47, ...}]},
 *       {"type": "spot", "position": [..],   ... or a full light, like --light:
 *        "direction": [..], "color": [r,g,b],  type point|spot|directional (or
 *        "intensity": 5, "inner_cone_deg": 20, "dir"); position (point, spot),
 *        "outer_cone_deg": 30,                 direction (spot, directional),
 *        "keys": [...]}                        color (default [1,1,1]),
 *     ],                                       intensity (W/sr; W/m^2 for
 *                                              directional), cones in degrees
 *     "emitters": [                          optional static emissive quads added
 *       {"quad": [[x,y,z], [x,y,z],          to the scene (area lights, gi_area.h):
 *                 [x,y,z], [x,y,z]],         corners in order, counter-clockwise
 *        "emission": [r, g, b],              seen from the emitting side; emission
 *        "two_sided": false}                 is radiance W/(sr m^2); two_sided
 *     ],                                     (default false): emits from both faces
 *     "animation": {"play": "Walk",          optional: play the scene's glTF animations
 *                   "time": [0, 2]},          (pf_anim.h) over the frames; "play" a
 *                                            name or an index (absent: every animation
 *                                            together), "time" [start, end] seconds
 *                                            mapped onto frames 0 .. frames-1 (absent:
 *                                            [0, the played animations' last key])
 *     "track": [[x, y], ...]                 optional pixels for `softgi compare
 *   }                                        --track` (at most PF_SEQUENCE_MAX_TRACK)
 *
 * Either every entry of "lights" names a scene light ("light": index) or
 * every entry is a full light; full lights replace the scene's lights, in
 * order (as --light does). "lights": [] replaces them with none: the scene
 * is lit by emitters alone (its own emissive triangles and the file's
 * "emitters", which it then requires).
 *
 * Emitters (Hedman 2017 Sec. 5 lights Sibenik and the conference room with
 * an emissive quad; the shared scenes have none and may not be edited or
 * copied): each becomes two triangles with a material of its own
 * (pf_scene_add_emitter_quad: emission, baseColor 0.78 grey, double-sided
 * when two_sided), added by pf_sequence_apply_emitters right after the
 * scene is read and before it is validated, so the emitter is in the
 * bounds, in Embree's and the rasterizer's geometry, and counts as a light
 * (no automatic light is added). They do not move (no keys). Each quad must
 * be convex with its corners in order, planar within 1e-3 of its longer
 * diagonal, of area >= 1e-12 units^2, within +-PF_SCENE_MAX_COORD
 * (pf_scene_emitter_quad_check gives the exact rule); each emission channel
 * in [0, PF_SEQUENCE_MAX_EMISSION], not all zero; at most
 * PF_SEQUENCE_MAX_EMITTERS. A light key holds "frame" and any of position,
 * direction, color, intensity, inner_cone_deg, outer_cone_deg; each field is
 * its own track over the keys that name it, and a field no key names keeps
 * the light's own value.
 *
 * Animation: frame f of N plays time t = (1 - s) start + s end with
 * s = f / (N - 1) in double (exactly start at frame 0 and end at frame
 * N - 1; N = 1: start), pf_sequence_time_at. "play" is a string (1 to 63
 * characters, no control characters) naming an animation or an integer
 * 0..65535 indexing one; whether the scene has it is checked when the scene
 * is loaded (app_sequence.c). "time" holds two finite numbers with
 * 0 <= start <= end <= PF_SEQUENCE_MAX_TIME (the animation layer's limit).
 * Keys other than "play", "time" and "comment" are errors.
 *
 * Interpolation (pf_sequence_track_eval): keys sorted by frame (strictly
 * increasing in the file, within [0, frames)); before the first key and
 * after the last the end value holds; between keys a and b at frames fa < f
 * < fb, t = (f - fa) / (fb - fa) in double and v = (1 - t) a + t b, exact at
 * both keys. Positions, eye, target, colour, intensity and cones are
 * interpolated linearly; a direction is interpolated linearly and
 * renormalised (keys are stored normalised; consecutive keys may not be
 * opposite). A camera is rebuilt every frame with pf_camera_look_at from the
 * interpolated eye, target and fovy.
 *
 * Where frames go. Sequence files come from strangers too, so a file cannot
 * choose where softgi writes: "output" must be a relative folder without
 * ".." components and is placed under PF_SEQUENCE_OUTPUT_BASE ("out/",
 * relative to the working folder, like the default out/<name>); softgi
 * sequence creates it component by component without following symbolic
 * links and checks that its realpath lies inside out/. Only -o DIR (the
 * user's own choice) writes anywhere. (Before this rule "output" was
 * relative to the sequence file and could be absolute; no shipped sequence
 * used it.)
 *
 * Limits, against absurd or hostile files: frames 1..PF_SEQUENCE_MAX_FRAMES,
 * size 1..PF_SEQUENCE_MAX_SIZE a side, at most PF_SEQUENCE_MAX_LIGHTS lights
 * and PF_SEQUENCE_MAX_TRACK tracked pixels, at most one key per frame per
 * track, PF_SEQUENCE_MAX_FILE bytes; positions, eye and target within
 * +-PF_SCENE_MAX_COORD; intensity and each colour channel, and their product
 * at every frame (pf_sequence_light_at), in [0, PF_SEQUENCE_MAX_EMISSION]:
 * 1e30 x 1e30 would overflow float, and 1e38 alone overflows the first
 * irradiance computed from it.
 *
 * Errors: every bad input (unreadable file, JSON syntax error with line and
 * column, missing key, wrong type, non-integer or out-of-range frame, NaN or
 * huge number, keys out of order, a field on the wrong light type, ...) gives
 * PF_ERR_IO or PF_ERR_PARSE (PF_ERR_NONFINITE for non-finite numbers) and a
 * message "FILE: where: what", e.g.
 *   "light.seq.json: camera[2].frame: frames must increase (5 after 9)". */
#ifndef PF_SEQUENCE_H
#define PF_SEQUENCE_H

#include <stddef.h>
#include <stdint.h>

#include "pf_result.h"
#include "pf_scene.h"

#define PF_SEQUENCE_MAX_FRAMES 10000u
#define PF_SEQUENCE_MAX_LIGHTS 64u
#define PF_SEQUENCE_MAX_TRACK 64u
#define PF_SEQUENCE_MAX_EMITTERS 16u /* quads; the papers use one */
#define PF_SEQUENCE_MAX_SIZE 16384u
#define PF_SEQUENCE_MAX_FILE (16u << 20) /* bytes */
#define PF_SEQUENCE_MAX_TIME 1.0e6       /* seconds: PF_ANIM_MAX_TIME (pf_anim.h) */
/* intensity x colour per channel, W/sr (W/m^2 directional): the renderer's
 * one limit (PF_MAX_RADIANCE, pf_scene.h), the same as for glTF and --light
 * lights; far above any physical light in any unit the scenes use (the
 * conference room in cm needs 2e5), far below float overflow after 1/r^2
 * and flux sums */
#define PF_SEQUENCE_MAX_EMISSION ((double)PF_MAX_RADIANCE)
#define PF_SEQUENCE_OUTPUT_BASE "out" /* where a file's "output" folder goes */
#define PF_SEQUENCE_EMBEDDED_CORNELL "embedded:cornell-box"

/* One keyframed quantity: count keys at strictly increasing frames, each
 * with `dim` floats (value[k * dim + c]). */
typedef struct pf_sequence_track {
    uint32_t count, dim;
    uint32_t *frame;
    float *value;
} pf_sequence_track;

typedef enum pf_sequence_field {
    PF_SEQUENCE_POSITION = 0, /* 3 */
    PF_SEQUENCE_DIRECTION,    /* 3, unit */
    PF_SEQUENCE_COLOR,        /* 3 */
    PF_SEQUENCE_INTENSITY,    /* 1 */
    PF_SEQUENCE_INNER_CONE,   /* 1, degrees */
    PF_SEQUENCE_OUTER_CONE,   /* 1, degrees */
    PF_SEQUENCE_FIELD_COUNT
} pf_sequence_field;

typedef struct pf_sequence_light {
    int32_t scene_light; /* >= 0: animates that scene light; -1: `spec` is a full light */
    pf_light spec;       /* full light at its own values (cones in radians) */
    pf_sequence_track field[PF_SEQUENCE_FIELD_COUNT];
} pf_sequence_light;

/* A static emissive quad ("emitters"), checked by pf_scene_emitter_quad_check. */
typedef struct pf_sequence_emitter {
    pf_vec3 quad[4];   /* corners, counter-clockwise seen from the emitting side */
    pf_vec3 emission;  /* radiance, W/(sr m^2) */
    int two_sided;
} pf_sequence_emitter;

/* Owns everything; freed by pf_sequence_free. */
typedef struct pf_sequence {
    char file[4096];       /* the sequence file as given (for messages) */
    char name[128];
    char scene_path[4096]; /* resolved; empty when scene_embedded */
    int scene_embedded;    /* "embedded:cornell-box" */
    uint32_t frames;
    uint32_t width, height; /* 0: not given */
    char output[4096];      /* "out/<output>" (unchecked for links: app_sequence creates it with
                               pf_imageio_make_dir_inside); empty: not given */
    pf_sequence_track camera; /* dim 7: eye xyz, target xyz, fovy_deg; count 0: no camera keys */
    uint32_t light_count;
    pf_sequence_light *lights;
    int lights_replace;     /* the entries are full lights that replace the scene's ("lights": []: with none) */
    uint32_t emitter_count;
    pf_sequence_emitter emitters[PF_SEQUENCE_MAX_EMITTERS];
    uint32_t track_count;
    uint32_t track[PF_SEQUENCE_MAX_TRACK][2]; /* x, y */
    /* "animation": the scene's glTF animations played over the frames */
    int anim_set;                 /* the key is given */
    char anim_name[64];           /* "play" as a name; empty: an index or every animation */
    int32_t anim_index;           /* "play" as an index; -1: a name or every animation */
    int anim_time_set;            /* "time" given; else [0, the played animations' end] */
    double anim_start, anim_end;  /* seconds */
} pf_sequence;

/* ---------------------------------------------------------------- the frames' folder
 *
 * `softgi sequence` writes DIR/frame_NNNN.{pfm,png,view,depth.pfm},
 * DIR/track.txt and DIR/frames.txt, the manifest:
 *   softgi-frames 1
 *   frames N
 *   state running|complete
 * It is written "running" before the first frame and "complete" after the
 * last (each write atomic), and `softgi compare` reads exactly frames
 * 0..N-1 of a complete folder and refuses a running one. So softgi never
 * deletes anything: frame files of an older, longer run (or anyone's
 * frame_0099.png) stay in the folder and are simply not part of the
 * sequence. A folder without frames.txt (made by hand or by an older
 * softgi) is read up to its first missing frame_NNNN.pfm. */
#define PF_SEQUENCE_MANIFEST "frames.txt"
typedef struct pf_sequence_manifest {
    uint32_t frames;
    int complete;
} pf_sequence_manifest;
/* Writes DIR/frames.txt (atomically, pf_imageio). */
pf_result pf_sequence_manifest_write(const char *dir, const pf_sequence_manifest *m, pf_error *err);
/* Reads DIR/frames.txt: PF_OK and *present = 1, PF_OK and *present = 0
 * when the folder has none, or a parse error naming the file. */
pf_result pf_sequence_manifest_read(const char *dir, pf_sequence_manifest *m, int *present, pf_error *err);

/* Reads and parses a sequence file. On failure *seq is empty (freeing it
 * is harmless). */
pf_result pf_sequence_load(pf_sequence *seq, const char *path, pf_error *err);
/* Parses `size` bytes of JSON. `file` names it in messages and locates
 * relative paths (its folder); it is not opened. */
pf_result pf_sequence_parse(pf_sequence *seq, const char *json, size_t size, const char *file, pf_error *err);
void pf_sequence_free(pf_sequence *seq);

/* Adds the file's emitters to `scene` (pf_scene_add_emitter_quad), and for
 * "lights": [] removes the scene's punctual lights. Call it right after the
 * scene is read and before pf_scene_validate, Embree and the rasterizer
 * (app_scene_load_sequence, for `softgi sequence` and through it
 * `softgi evaluate`), so that the emitters also keep app_scene_load from
 * adding its automatic light.
 * Errors name the file: "FILE: emitters[i]: what". */
pf_result pf_sequence_apply_emitters(const pf_sequence *seq, pf_scene *scene, pf_error *err);

/* Track value at `frame` (dim floats into out); a track without keys
 * leaves out untouched. */
void pf_sequence_track_eval(const pf_sequence_track *track, uint32_t frame, float *out);

/* The animation time (seconds) of `frame`: start at frame 0, end at the
 * last frame, linear between (see "Animation" above). */
double pf_sequence_time_at(const pf_sequence *seq, uint32_t frame, double start, double end);

/* Eye, target and fovy (degrees) at `frame`. Returns 0 (and leaves the
 * outputs) when the sequence has no camera keys. */
int pf_sequence_camera_at(const pf_sequence *seq, uint32_t frame, pf_vec3 *eye, pf_vec3 *target, float *fovy_deg);

/* Light i at `frame`: its base (`scene_light` for an entry naming a scene
 * light, the entry's spec otherwise) with every keyed field interpolated.
 * Checks what only the base light decides: fields valid for its type, a
 * non-zero direction, 0 <= inner < outer <= 90 degrees, every value
 * finite, intensity x colour in [0, PF_SEQUENCE_MAX_EMISSION]. */
pf_result pf_sequence_light_at(const pf_sequence *seq, uint32_t i, uint32_t frame, const pf_light *scene_light,
                               pf_light *out, pf_error *err);

#endif
