/* test_sequence: sequence files (pf_sequence) and `softgi sequence`.
 *
 * - the shipped sequence files parse, with the cameras, lights and scene
 *   paths they promise (the shared scenes' paths resolve from a clean clone
 *   with shared/ beside it);
 * - every kind of bad input gives its code and a message naming the place;
 * - interpolation is exact at keys and at midpoints;
 * - "emitters": good and bad entries (every error path names its place),
 *   the quads they add to a scene (counts, material, face normal, bounds,
 *   "lights": [] clearing the scene's lights), the scene function's own
 *   checks and overflow guard, and the area-light table
 *   (gi_area_lights_build) finding the quad with its area and power and an
 *   irradiance that matches the analytic form factor of a square, and end
 *   to end a Cornell-box sequence lit by its emitter alone;
 * - end to end on a tiny embedded-Cornell sequence: the frame files exist,
 *   `softgi compare` reads the folder, a moving camera under a static light
 *   moves no VPL after frame 0, a moving light moves all of them, and the
 *   --hash over all frames is the same with 1 and 2 threads. */
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gi_area.h"
#include "pf_sequence.h"
#include "pf_imageio.h"
#include "test_util.h"


static char g_tmp[256];

/* ---------------------------------------------------------------- helpers */

static void parse_ok(pf_sequence *s, const char *json)
{
    pf_error err;
    pf_result r = pf_sequence_parse(s, json, strlen(json), "dir/t.seq.json", &err);
    if (r != PF_OK) fail_msg("unexpected error: %s\nfor: %s", err.message, json);
}

static void expect_bad(const char *json, pf_result code, const char *needle)
{
    pf_sequence s;
    pf_error err;
    memset(&err, 0, sizeof err);
    pf_result r = pf_sequence_parse(&s, json, strlen(json), "t.seq.json", &err);
    if (r == PF_OK) fail_msg("accepted: %s", json);
    if (r != code || !strstr(err.message, needle) || strncmp(err.message, "t.seq.json: ", 12) != 0)
        fail_msg("for %s\n  got code %d '%s'\n  want code %d and '%s'", json, (int)r, err.message, (int)code, needle);
    assert_int_equal(s.frames, 0); /* emptied */
    assert_null(s.lights);
    pf_sequence_free(&s);
}

static void write_file(const char *path, const char *text)
{
    FILE *f = fopen(path, "w");
    assert_non_null(f);
    fputs(text, f);
    assert_int_equal(fclose(f), 0);
}

/* ---------------------------------------------------------------- shipped files */

static void test_shipped_files(void **state)
{
    (void)state;
    static const struct {
        const char *file;
        int moving_camera, moving_light;
    } files[] = {
        {"scenes/cornell-box/camera-orbit.seq.json", 1, 0},
        {"scenes/cornell-box/light-move.seq.json", 0, 1},
        {"scenes/sequences/sibenik-camera.seq.json", 1, 0},
        {"scenes/sequences/sibenik-light.seq.json", 0, 1},
        {"scenes/sequences/conference-camera.seq.json", 1, 0},
        {"scenes/sequences/conference-light.seq.json", 0, 1},
        {"scenes/sequences/sibenik-area.seq.json", 1, 0},
        {"scenes/sequences/conference-area.seq.json", 1, 0},
    };
    for (size_t i = 0; i < sizeof files / sizeof files[0]; i++) {
        char path[1024];
        snprintf(path, sizeof path, "%s/%s", SOFTGI_SOURCE_DIR, files[i].file);
        pf_sequence s;
        pf_error err;
        if (pf_sequence_load(&s, path, &err) != PF_OK) fail_msg("%s", err.message);
        assert_true(s.frames >= 30 && s.frames <= 60);
        assert_false(s.scene_embedded);
        assert_true(tu_file_exists(s.scene_path) || strstr(s.scene_path, "shared/scenes"));
        if (strstr(s.scene_path, "shared/scenes")) {
            /* from a clean clone: <repo>/scenes/sequences/../../../shared/scenes = <repo>/../shared/scenes */
            char shared[1024];
            snprintf(shared, sizeof shared, "%s/../shared/scenes", SOFTGI_SOURCE_DIR);
            if (tu_file_exists(shared)) assert_true(tu_file_exists(s.scene_path));
            else print_message("SKIP: %s is absent; %s not checked\n", shared, s.scene_path);
        }
        /* the camera or a light moves, as the name says */
        int cam_moves = 0, light_moves = 0;
        pf_vec3 e0, t0, e, t;
        float f0, f;
        pf_light L0, L;
        pf_light base;
        memset(&base, 0, sizeof base);
        base.color = pf_v3(1, 1, 1);
        base.intensity = 1;
        int has_cam = pf_sequence_camera_at(&s, 0, &e0, &t0, &f0);
        for (uint32_t fr = 1; fr < s.frames; fr++) {
            if (has_cam && pf_sequence_camera_at(&s, fr, &e, &t, &f) &&
                (memcmp(&e, &e0, sizeof e) || memcmp(&t, &t0, sizeof t) || f != f0))
                cam_moves = 1;
            for (uint32_t l = 0; l < s.light_count; l++) {
                assert_int_equal(pf_sequence_light_at(&s, l, 0, &base, &L0, &err), PF_OK);
                assert_int_equal(pf_sequence_light_at(&s, l, fr, &base, &L, &err), PF_OK);
                if (memcmp(&L.position, &L0.position, sizeof L.position)) light_moves = 1;
            }
        }
        if (cam_moves != files[i].moving_camera || light_moves != files[i].moving_light)
            fail_msg("%s: camera moves %d, light moves %d", files[i].file, cam_moves, light_moves);
        /* the area-lit ones: one emitter facing down, no punctual light */
        if (strstr(files[i].file, "-area.")) {
            assert_int_equal(s.emitter_count, 1);
            assert_true(s.lights_replace && s.light_count == 0);
            pf_vec3 n;
            assert_int_equal(pf_scene_emitter_quad_check(s.emitters[0].quad, s.emitters[0].emission, &n, &err), PF_OK);
            assert_true(n.y < -0.999f);
        } else
            assert_int_equal(s.emitter_count, 0);
        pf_sequence_free(&s);
    }
}

/* ---------------------------------------------------------------- the format */

#define HEAD "{\"scene\": \"embedded:cornell-box\", \"frames\": 10, "

static void test_parse_fields(void **state)
{
    (void)state;
    pf_sequence s;
    parse_ok(&s, "{\"scene\": \"box.gltf\", \"frames\": 5}");
    assert_string_equal(s.scene_path, "dir/box.gltf");
    assert_string_equal(s.name, "t");
    assert_int_equal(s.frames, 5);
    assert_int_equal(s.width, 0);
    assert_int_equal(s.camera.count, 0);
    assert_int_equal(s.light_count, 0);
    pf_sequence_free(&s);

    parse_ok(&s, "{\"comment\": \"x\", \"name\": \"walk\", \"scene\": \"/abs/s.glb\", \"frames\": 3, \"size\": [64, 48],"
                 " \"output\": \"renders/walk\", \"track\": [[0, 0], [63, 47]]}");
    assert_string_equal(s.scene_path, "/abs/s.glb");
    assert_string_equal(s.name, "walk");
    assert_string_equal(s.output, "out/renders/walk"); /* under out/, not beside the file */
    assert_int_equal(s.width, 64);
    assert_int_equal(s.height, 48);
    assert_int_equal(s.track_count, 2);
    assert_int_equal(s.track[1][0], 63);
    assert_int_equal(s.track[1][1], 47);
    pf_sequence_free(&s);

    /* a huge direction is normalised in double (its float squares would overflow to a zero vector) */
    parse_ok(&s, HEAD "\"lights\": [{\"type\": \"dir\", \"direction\": [1e30, 1e30, 1e30], \"intensity\": 1}]}");
    assert_float_equal(s.lights[0].spec.direction.x, 0.57735027f, 1e-6f);
    pf_sequence_free(&s);

    parse_ok(&s, HEAD "\"lights\": [{\"type\": \"spot\", \"position\": [0,1,0], \"direction\": [0,-2,0],"
                      " \"inner_cone_deg\": 10, \"outer_cone_deg\": 20, \"intensity\": 3},"
                      " {\"type\": \"directional\", \"direction\": [0,0,-1], \"color\": [1,0.5,0.25], \"intensity\": 2}]}");
    assert_true(s.scene_embedded);
    assert_true(s.lights_replace);
    assert_int_equal(s.light_count, 2);
    assert_int_equal(s.lights[0].spec.type, PF_LIGHT_SPOT);
    assert_true(s.lights[0].spec.direction.y == -1.0f);
    assert_true(fabsf(s.lights[0].spec.outer_cone - pf_radians(20.0f)) < 1e-7f);
    assert_int_equal(s.lights[1].spec.type, PF_LIGHT_DIRECTIONAL);
    assert_true(s.lights[1].spec.color.z == 0.25f);
    pf_sequence_free(&s);

    /* "animation": a name or an index, a time range mapped onto the frames */
    parse_ok(&s, HEAD "\"animation\": {\"play\": \"walk\", \"time\": [0.5, 2], \"comment\": \"x\"}}");
    assert_true(s.anim_set && s.anim_time_set);
    assert_string_equal(s.anim_name, "walk");
    assert_int_equal(s.anim_index, -1);
    assert_true(pf_sequence_time_at(&s, 0, s.anim_start, s.anim_end) == 0.5);
    assert_true(pf_sequence_time_at(&s, 9, s.anim_start, s.anim_end) == 2.0);
    assert_true(fabs(pf_sequence_time_at(&s, 3, s.anim_start, s.anim_end) - 1.0) < 1e-12);
    pf_sequence_free(&s);
    parse_ok(&s, HEAD "\"animation\": {\"play\": 3}}");
    assert_true(s.anim_set && !s.anim_time_set);
    assert_int_equal(s.anim_index, 3);
    assert_string_equal(s.anim_name, "");
    pf_sequence_free(&s);
    parse_ok(&s, "{\"scene\": \"a.gltf\", \"frames\": 1, \"animation\": {}}");
    assert_true(s.anim_set);
    assert_int_equal(s.anim_index, -1);
    assert_true(pf_sequence_time_at(&s, 0, 1.5, 3.0) == 1.5); /* one frame: the start */
    pf_sequence_free(&s);

    /* the default name drops .seq.json */
    pf_error err;
    const char *j = "{\"scene\": \"a.gltf\", \"frames\": 1}";
    assert_int_equal(pf_sequence_parse(&s, j, strlen(j), "x/y/orbit.seq.json", &err), PF_OK);
    assert_string_equal(s.name, "orbit");
    assert_string_equal(s.scene_path, "x/y/a.gltf");
    pf_sequence_free(&s);
}

static void test_bad_inputs(void **state)
{
    (void)state;
    static const struct {
        const char *json;
        pf_result code;
        const char *needle;
    } bad[] = {
        /* not JSON / not an object */
        {"", PF_ERR_PARSE, "empty file"},
        {"{\"scene\": \"a.gltf\", \"frames\": 1", PF_ERR_PARSE, "ends too early"},
        {"{\"scene\": \"a.gl", PF_ERR_PARSE, "ends too early"},
        {"{\"camera\": [{\"frame\": 0,", PF_ERR_PARSE, "ends too early"},
        {"{\"scene\": 'a'}", PF_ERR_PARSE, "syntax error at line 1, column 11"},
        {"{\n  \"scene\": \"a\",\n  frames: 3\n}", PF_ERR_PARSE, "syntax error at line 3"},
        {"{\"scene\": \"a\", \"frames\": NaN}", PF_ERR_PARSE, "syntax error"},
        {"{\"scene\": \"a\", \"frames\": 1} {}", PF_ERR_PARSE, "unexpected text after the JSON value"},
        {"{\"scene\": \"a\", \"frames\": 1}]", PF_ERR_PARSE, "unexpected text after the JSON value"},
        {"[1, 2]", PF_ERR_PARSE, "expected a JSON object at the top, got an array"},
        {"42", PF_ERR_PARSE, "expected a JSON object at the top, got a number"},
        {"null", PF_ERR_PARSE, "got null"},
        /* top-level keys */
        {"{\"frames\": 1}", PF_ERR_PARSE, "missing key 'scene'"},
        {"{\"scene\": \"a\"}", PF_ERR_PARSE, "missing key 'frames'"},
        {"{\"scene\": \"a\", \"frames\": 1, \"frame\": 2}", PF_ERR_PARSE, "unknown key 'frame'"},
        {"{\"scene\": \"a\", \"frames\": 1, \"frames\": 2}", PF_ERR_PARSE, "key 'frames' given twice"},
        {"{\"scene\": 3, \"frames\": 1}", PF_ERR_PARSE, "scene: expected a string, got a number"},
        {"{\"scene\": \"\", \"frames\": 1}", PF_ERR_PARSE, "scene: must not be empty"},
        {"{\"scene\": \"embedded:sponza\", \"frames\": 1}", PF_ERR_PARSE, "only embedded scene"},
        {"{\"scene\": \"a\", \"frames\": 0}", PF_ERR_PARSE, "frames: must be at least 1"},
        {"{\"scene\": \"a\", \"frames\": -3}", PF_ERR_PARSE, "frames: -3 is out of range"},
        {"{\"scene\": \"a\", \"frames\": 2.5}", PF_ERR_PARSE, "frames: expected an integer, got 2.5"},
        {"{\"scene\": \"a\", \"frames\": \"10\"}", PF_ERR_PARSE, "frames: expected an integer, got a string"},
        {"{\"scene\": \"a\", \"frames\": 10001}", PF_ERR_PARSE, "frames: 10001 is out of range 1..10000"},
        {"{\"scene\": \"a\", \"frames\": 1e300}", PF_ERR_PARSE, "out of range"},
        {"{\"scene\": \"a\", \"frames\": true}", PF_ERR_PARSE, "got a boolean"},
        {HEAD "\"size\": [64]}", PF_ERR_PARSE, "size: expected [width, height]"},
        {HEAD "\"size\": [0, 48]}", PF_ERR_PARSE, "size[0]: 0 is out of range"},
        {HEAD "\"size\": [64, 99999]}", PF_ERR_PARSE, "size[1]: 99999 is out of range"},
        {HEAD "\"size\": {\"w\": 1}}", PF_ERR_PARSE, "size: expected [width, height]"},
        {HEAD "\"output\": []}", PF_ERR_PARSE, "output: expected a string, got an array"},
        /* animation */
        {HEAD "\"animation\": \"walk\"}", PF_ERR_PARSE, "animation: expected an object, got a string"},
        {HEAD "\"animation\": {\"clip\": 0}}", PF_ERR_PARSE, "animation: unknown key 'clip' (expected: play, time)"},
        {HEAD "\"animation\": {\"play\": \"\"}}", PF_ERR_PARSE, "animation.play: expected an animation's name"},
        {HEAD "\"animation\": {\"play\": -1}}", PF_ERR_PARSE, "animation.play: -1 is out of range 0..65535"},
        {HEAD "\"animation\": {\"play\": 2.5}}", PF_ERR_PARSE, "animation.play: expected an integer, got 2.5"},
        {HEAD "\"animation\": {\"play\": true}}", PF_ERR_PARSE, "animation.play: expected an animation's name or "
                                                              "index, got a boolean"},
        {HEAD "\"animation\": {\"time\": [1]}}", PF_ERR_PARSE, "animation.time: expected an array of 2 numbers"},
        {HEAD "\"animation\": {\"time\": [2, 1]}}", PF_ERR_PARSE, "[2, 1]: expected [start, end] seconds"},
        {HEAD "\"animation\": {\"time\": [-1, 1]}}", PF_ERR_PARSE, "0 <= start <= end <= 1e+06"},
        {HEAD "\"animation\": {\"time\": [0, 2e6]}}", PF_ERR_NONFINITE, "animation.time[1]: |2e+06| exceeds 1e+06"},
        {HEAD "\"animation\": {\"time\": [0, \"1\"]}}", PF_ERR_PARSE, "animation.time[1]: expected a number"},
        {HEAD "\"animation\": {\"play\": 0, \"play\": 1}}", PF_ERR_PARSE, "key 'play' given twice"},
        {HEAD "\"name\": \"a/b\"}", PF_ERR_PARSE, "name: expected 1 to"},
        {HEAD "\"name\": \"..\"}", PF_ERR_PARSE, "name: expected 1 to"},
        /* output: a relative folder under out/, never absolute or with '..' */
        {HEAD "\"output\": \"/tmp/x\"}", PF_ERR_PARSE, "output: '/tmp/x': must be a relative folder"},
        {HEAD "\"output\": \"../x\"}", PF_ERR_PARSE, "output: '../x': must not contain '..'"},
        {HEAD "\"output\": \"a/../../x\"}", PF_ERR_PARSE, "must not contain '..'"},
        {HEAD "\"output\": \"a/..\"}", PF_ERR_PARSE, "must not contain '..'"},
        {HEAD "\"output\": \"\"}", PF_ERR_PARSE, "output: must not be empty"},
        {HEAD "\"output\": \"a\\nb\"}", PF_ERR_PARSE, "output: must not contain control characters"},
        /* found by fuzz_sequence: a field of view > 0 that is 0 in radians; eye and target too close to
           give a direction (the renderer's pf_camera_look_at decides both) */
        {HEAD "\"camera\": [{\"frame\": 0, \"eye\": [0,0,0], \"target\": [0,0,1], \"fovy_deg\": 1e-45}]}",
         PF_ERR_PARSE, "camera: frame 0: camera field of view must be in (0, 180) degrees"},
        {HEAD "\"camera\": [{\"frame\": 0, \"eye\": [0,0,0], \"target\": [0,0,1e-30], \"fovy_deg\": 40}]}",
         PF_ERR_PARSE, "camera: frame 0: camera eye and target must be finite and distinct"},
        /* light emission: each factor and their product bounded (PF_MAX_RADIANCE, 1e10) */
        {HEAD "\"lights\": [{\"type\": \"point\", \"position\": [0,0,0], \"intensity\": 1e38}]}", PF_ERR_NONFINITE,
         "lights[0].intensity: |1e+38| exceeds 1e+10"},
        {HEAD "\"lights\": [{\"type\": \"point\", \"position\": [0,0,0], \"intensity\": 1e30,"
              " \"color\": [1e30, 1, 1]}]}", PF_ERR_NONFINITE, "exceeds 1e+10"},
        {HEAD "\"lights\": [{\"type\": \"point\", \"position\": [0,0,0], \"intensity\": 1e7,"
              " \"color\": [1e7, 1, 1]}]}", PF_ERR_PARSE, "intensity 1e+07 x colour 1e+07 is not in [0, 1e+10]"},
        {HEAD "\"lights\": [{\"type\": \"point\", \"position\": [0,0,0], \"intensity\": 1,"
              " \"keys\": [{\"frame\": 0, \"intensity\": 1e7}, {\"frame\": 1, \"color\": [1, 1e6, 1]}]}]}",
         PF_ERR_PARSE, "x colour 1e+06 is not in"},
        {HEAD "\"lights\": [{\"type\": \"point\", \"position\": [0,0,0], \"intensity\": -1}]}", PF_ERR_PARSE,
         "intensity must be >= 0"},
        {HEAD "\"name\": 5}", PF_ERR_PARSE, "name: expected a string"},
        /* camera */
        {HEAD "\"camera\": {}}", PF_ERR_PARSE, "camera: expected an array of keys, got an object"},
        {HEAD "\"camera\": []}", PF_ERR_PARSE, "camera: needs at least one key"},
        {HEAD "\"camera\": [3]}", PF_ERR_PARSE, "camera[0]: expected an object, got a number"},
        {HEAD "\"camera\": [{\"eye\": [0,0,0], \"target\": [0,0,1], \"fovy_deg\": 40}]}", PF_ERR_PARSE,
         "camera[0]: missing key 'frame'"},
        {HEAD "\"camera\": [{\"frame\": 0, \"target\": [0,0,1], \"fovy_deg\": 40}]}", PF_ERR_PARSE,
         "camera[0]: missing key 'eye'"},
        {HEAD "\"camera\": [{\"frame\": 0, \"eye\": [0,0,0], \"target\": [0,0,1]}]}", PF_ERR_PARSE,
         "camera[0]: missing key 'fovy_deg'"},
        {HEAD "\"camera\": [{\"frame\": 0, \"eye\": [0,0], \"target\": [0,0,1], \"fovy_deg\": 40}]}", PF_ERR_PARSE,
         "camera[0].eye: expected an array of 3 numbers, got 2 elements"},
        {HEAD "\"camera\": [{\"frame\": 0, \"eye\": [0,\"0\",0], \"target\": [0,0,1], \"fovy_deg\": 40}]}",
         PF_ERR_PARSE, "camera[0].eye[1]: expected a number, got a string"},
        {HEAD "\"camera\": [{\"frame\": 0, \"eye\": [0,0,1e39], \"target\": [0,0,1], \"fovy_deg\": 40}]}",
         PF_ERR_NONFINITE, "camera[0].eye[2]: number is not finite in single precision"},
        {HEAD "\"camera\": [{\"frame\": 0, \"eye\": [0,0,2e7], \"target\": [0,0,1], \"fovy_deg\": 40}]}",
         PF_ERR_NONFINITE, "camera[0].eye[2]: |2e+07| exceeds 1e+07"},
        {HEAD "\"camera\": [{\"frame\": 0, \"eye\": [0,0,0], \"target\": [0,0,1], \"fovy_deg\": 180}]}",
         PF_ERR_PARSE, "camera[0].fovy_deg: field of view 180 is not in (0, 180) degrees"},
        {HEAD "\"camera\": [{\"frame\": 0, \"eye\": [0,0,0], \"target\": [0,0,1], \"fovy_deg\": -1}]}",
         PF_ERR_PARSE, "not in (0, 180)"},
        {HEAD "\"camera\": [{\"frame\": 0, \"eye\": [1,2,3], \"target\": [1,2,3], \"fovy_deg\": 40}]}",
         PF_ERR_PARSE, "camera[0]: eye and target must differ"},
        {HEAD "\"camera\": [{\"frame\": 0, \"eye\": [0,0,0], \"target\": [0,0,2], \"fovy_deg\": 40},"
              " {\"frame\": 2, \"eye\": [0,0,2], \"target\": [0,0,0], \"fovy_deg\": 40}]}",
         PF_ERR_PARSE, "camera: eye and target coincide at frame 1"},
        {HEAD "\"camera\": [{\"frame\": 10, \"eye\": [0,0,0], \"target\": [0,0,1], \"fovy_deg\": 40}]}",
         PF_ERR_PARSE, "camera[0].frame: 10 is out of range 0..9"},
        {HEAD "\"camera\": [{\"frame\": 5, \"eye\": [0,0,0], \"target\": [0,0,1], \"fovy_deg\": 40},"
              " {\"frame\": 3, \"eye\": [0,0,0], \"target\": [0,0,1], \"fovy_deg\": 40}]}",
         PF_ERR_PARSE, "camera[1].frame: frames must increase (3 after 5)"},
        {HEAD "\"camera\": [{\"frame\": 5, \"eye\": [0,0,0], \"target\": [0,0,1], \"fovy_deg\": 40},"
              " {\"frame\": 5, \"eye\": [0,0,0], \"target\": [0,0,1], \"fovy_deg\": 40}]}",
         PF_ERR_PARSE, "frames must increase (5 after 5)"},
        {HEAD "\"camera\": [{\"frame\": 0, \"eye\": [0,0,0], \"target\": [0,0,1], \"fovy_deg\": 40, \"fov\": 3}]}",
         PF_ERR_PARSE, "camera[0]: unknown key 'fov'"},
        /* lights */
        {HEAD "\"lights\": {}}", PF_ERR_PARSE, "lights: expected an array, got an object"},
        {HEAD "\"lights\": []}", PF_ERR_PARSE, "lights: is empty, which means no punctual light: give \"emitters\""},
        /* emitters (QUAD: a good unit square in y = 1 facing down) */
#define QUAD "[[0,1,0], [1,1,0], [1,1,1], [0,1,1]]"
        {HEAD "\"emitters\": {}}", PF_ERR_PARSE, "emitters: expected an array, got an object"},
        {HEAD "\"emitters\": []}", PF_ERR_PARSE, "emitters: is empty"},
        {HEAD "\"emitters\": [1]}", PF_ERR_PARSE, "emitters[0]: expected an object, got a number"},
        {HEAD "\"emitters\": [{\"emission\": [1,1,1]}]}", PF_ERR_PARSE, "emitters[0]: missing key 'quad'"},
        {HEAD "\"emitters\": [{\"quad\": " QUAD "}]}", PF_ERR_PARSE, "emitters[0]: missing key 'emission'"},
        {HEAD "\"emitters\": [{\"quad\": " QUAD ", \"emission\": [1,1,1], \"keys\": []}]}", PF_ERR_PARSE,
         "emitters[0]: unknown key 'keys' (expected: quad, emission, two_sided)"},
        {HEAD "\"emitters\": [{\"quad\": " QUAD ", \"emission\": [1,1,1], \"quad\": " QUAD "}]}", PF_ERR_PARSE,
         "emitters[0]: key 'quad' given twice"},
        {HEAD "\"emitters\": [{\"quad\": \"square\", \"emission\": [1,1,1]}]}", PF_ERR_PARSE,
         "emitters[0].quad: expected 4 corners [[x,y,z], ...], got a string"},
        {HEAD "\"emitters\": [{\"quad\": [[0,1,0], [1,1,0], [1,1,1]], \"emission\": [1,1,1]}]}", PF_ERR_PARSE,
         "emitters[0].quad: expected 4 corners [[x,y,z], ...], got another number of elements"},
        {HEAD "\"emitters\": [{\"quad\": [[0,1,0], [1,1], [1,1,1], [0,1,1]], \"emission\": [1,1,1]}]}",
         PF_ERR_PARSE, "emitters[0].quad[1]: expected an array of 3 numbers, got 2 elements"},
        {HEAD "\"emitters\": [{\"quad\": [[0,1,0], [1,1,0], [\"1\",1,1], [0,1,1]], \"emission\": [1,1,1]}]}",
         PF_ERR_PARSE, "emitters[0].quad[2][0]: expected a number, got a string"},
        {HEAD "\"emitters\": [{\"quad\": [[0,2e7,0], [1,1,0], [1,1,1], [0,1,1]], \"emission\": [1,1,1]}]}",
         PF_ERR_NONFINITE, "emitters[0].quad[0][1]: |2e+07| exceeds 1e+07"},
        {HEAD "\"emitters\": [{\"quad\": [[0,1,0], [1,1,0], [1,1,1], [0,1,1e999]], \"emission\": [1,1,1]}]}",
         PF_ERR_NONFINITE, "emitters[0].quad[3][2]: number is not finite"},
        {HEAD "\"emitters\": [{\"quad\": " QUAD ", \"emission\": [1,1]}]}", PF_ERR_PARSE,
         "emitters[0].emission: expected an array of 3 numbers, got 2 elements"},
        {HEAD "\"emitters\": [{\"quad\": " QUAD ", \"emission\": [1,-1,1]}]}", PF_ERR_PARSE,
         "emitters[0].emission: emission must be >= 0"},
        {HEAD "\"emitters\": [{\"quad\": " QUAD ", \"emission\": [0,0,0]}]}", PF_ERR_PARSE,
         "emitters[0].emission: emission is zero"},
        {HEAD "\"emitters\": [{\"quad\": " QUAD ", \"emission\": [1,2e10,1]}]}", PF_ERR_NONFINITE,
         "emitters[0].emission[1]: |2e+10| exceeds 1e+10"},
        {HEAD "\"emitters\": [{\"quad\": " QUAD ", \"emission\": [1,1,1], \"two_sided\": 1}]}", PF_ERR_PARSE,
         "emitters[0].two_sided: expected true or false, got a number"},
        {HEAD "\"emitters\": [{\"quad\": [[1,1,1], [1,1,1], [1,1,1], [1,1,1]], \"emission\": [1,1,1]}]}",
         PF_ERR_PARSE, "emitters[0].quad: the four corners coincide"},
        {HEAD "\"emitters\": [{\"quad\": [[0,1,0], [1,1,0], [2,1,0], [3,1,0]], \"emission\": [1,1,1]}]}",
         PF_ERR_PARSE, "emitters[0].quad: the quad has no area"},
        {HEAD "\"emitters\": [{\"quad\": [[0,1,0], [1,1,1], [1,1,0], [0,1,1]], \"emission\": [1,1,1]}]}",
         PF_ERR_PARSE, "emitters[0].quad: the quad has no area (corners repeated or collinear, or out of order as a bow-tie)"},
        {HEAD "\"emitters\": [{\"quad\": [[0,0,0], [3,1,0], [3,0,0], [0,2,0]], \"emission\": [1,1,1]}]}",
         PF_ERR_PARSE, "emitters[0].quad: corner 1: the quad is not convex"},
        {HEAD "\"emitters\": [{\"quad\": [[0,0,0], [4,0,0], [1,1,0], [0,4,0]], \"emission\": [1,1,1]}]}",
         PF_ERR_PARSE, "emitters[0].quad: corner 2: the quad is not convex with its corners in order (corners 1, 2, 3"},
        {HEAD "\"emitters\": [{\"quad\": [[0,1,0], [1,1,0], [1,1,1], [1,1,1.5]], \"emission\": [1,1,1]}]}",
         PF_ERR_PARSE, "emitters[0].quad: corner 2: the quad is not convex with its corners in order (corners 1, 2, 3 are collinear"},
        {HEAD "\"emitters\": [{\"quad\": [[0,1,0], [1,1,0], [1,1,1], [0,1.1,1]], \"emission\": [1,1,1]}]}",
         PF_ERR_PARSE, "emitters[0].quad: not planar: corner"},
        {HEAD "\"emitters\": [{\"quad\": [[0,0,0], [1e-7,0,0], [1e-7,1e-7,0], [0,1e-7,0]], \"emission\": [1,1,1]}]}",
         PF_ERR_PARSE, "emitters[0].quad: the quad's area 1e-14 is below 1e-12"},
        {HEAD "\"emitters\": [{\"quad\": " QUAD ", \"emission\": [1,1,1]}, 7]}", PF_ERR_PARSE,
         "emitters[1]: expected an object, got a number"},
#undef QUAD
        {HEAD "\"lights\": [1]}", PF_ERR_PARSE, "lights[0]: expected an object, got a number"},
        {HEAD "\"lights\": [{}]}", PF_ERR_PARSE, "lights[0]: missing key 'light' (index of a scene light) or 'type'"},
        {HEAD "\"lights\": [{\"light\": 0, \"type\": \"point\"}]}", PF_ERR_PARSE, "not both"},
        {HEAD "\"lights\": [{\"light\": 0}]}", PF_ERR_PARSE, "lights[0]: missing key 'keys'"},
        {HEAD "\"lights\": [{\"light\": -1, \"keys\": [{\"frame\": 0, \"intensity\": 1}]}]}", PF_ERR_PARSE,
         "lights[0].light: -1 is out of range"},
        {HEAD "\"lights\": [{\"light\": 0.5, \"keys\": [{\"frame\": 0, \"intensity\": 1}]}]}", PF_ERR_PARSE,
         "lights[0].light: expected an integer"},
        {HEAD "\"lights\": [{\"light\": 0, \"keys\": []}]}", PF_ERR_PARSE, "lights[0].light: needs at least one key"},
        {HEAD "\"lights\": [{\"light\": 0, \"keys\": {}}]}", PF_ERR_PARSE, "lights[0].keys: expected an array"},
        {HEAD "\"lights\": [{\"light\": 0, \"keys\": [{\"frame\": 0}]}]}", PF_ERR_PARSE,
         "lights[0].keys[0]: a key needs at least one of position"},
        {HEAD "\"lights\": [{\"light\": 0, \"keys\": [{\"position\": [0,0,0]}]}]}", PF_ERR_PARSE,
         "lights[0].keys[0]: missing key 'frame'"},
        {HEAD "\"lights\": [{\"light\": 0, \"keys\": [{\"frame\": 0, \"pos\": [0,0,0]}]}]}", PF_ERR_PARSE,
         "lights[0].keys[0]: unknown key 'pos'"},
        {HEAD "\"lights\": [{\"light\": 0, \"keys\": [{\"frame\": 4, \"intensity\": 1}, {\"frame\": 2, \"intensity\": 2}]}]}",
         PF_ERR_PARSE, "lights[0].keys[1].frame: frames must increase (2 after 4)"},
        {HEAD "\"lights\": [{\"light\": 0, \"keys\": [{\"frame\": 0, \"intensity\": -1}]}]}", PF_ERR_PARSE,
         "lights[0].keys[0].intensity: intensity must be >= 0"},
        {HEAD "\"lights\": [{\"light\": 0, \"keys\": [{\"frame\": 0, \"color\": [1,-1,1]}]}]}", PF_ERR_PARSE,
         "lights[0].keys[0].color: colour must be >= 0"},
        {HEAD "\"lights\": [{\"light\": 0, \"keys\": [{\"frame\": 0, \"direction\": [0,0,0]}]}]}", PF_ERR_PARSE,
         "lights[0].keys[0].direction: direction must not be zero"},
        {HEAD "\"lights\": [{\"light\": 0, \"keys\": [{\"frame\": 0, \"direction\": [0,0,1]}, {\"frame\": 1, \"direction\": [0,0,-3]}]}]}",
         PF_ERR_PARSE, "lights[0].keys[1].direction: opposite to the previous direction key"},
        {HEAD "\"lights\": [{\"light\": 0, \"keys\": [{\"frame\": 0, \"outer_cone_deg\": 91}]}]}", PF_ERR_PARSE,
         "cone angle 91 is not in [0, 90] degrees"},
        {HEAD "\"lights\": [{\"light\": 0, \"keys\": [{\"frame\": 0, \"intensity\": 1}]},"
              " {\"light\": 0, \"keys\": [{\"frame\": 0, \"intensity\": 2}]}]}",
         PF_ERR_PARSE, "lights[1].light: scene light 0 is animated twice"},
        {HEAD "\"lights\": [{\"light\": 0, \"keys\": [{\"frame\": 0, \"intensity\": 1}]},"
              " {\"type\": \"point\", \"position\": [0,0,0], \"intensity\": 1}]}",
         PF_ERR_PARSE, "lights[1]: entries must all name scene lights ('light') or all be full lights"},
        {HEAD "\"lights\": [{\"type\": \"area\", \"intensity\": 1}]}", PF_ERR_PARSE,
         "lights[0].type: 'area': expected point, spot or directional"},
        {HEAD "\"lights\": [{\"type\": 1}]}", PF_ERR_PARSE, "lights[0].type: expected a string, got a number"},
        {HEAD "\"lights\": [{\"type\": \"point\", \"intensity\": 1}]}", PF_ERR_PARSE,
         "lights[0]: missing key 'position' (a point light needs it)"},
        {HEAD "\"lights\": [{\"type\": \"point\", \"position\": [0,0,0]}]}", PF_ERR_PARSE,
         "lights[0]: missing key 'intensity'"},
        {HEAD "\"lights\": [{\"type\": \"point\", \"position\": [0,0,0], \"intensity\": 1, \"direction\": [0,1,0]}]}",
         PF_ERR_PARSE, "lights[0].direction: a point light has no direction"},
        {HEAD "\"lights\": [{\"type\": \"directional\", \"direction\": [0,-1,0], \"intensity\": 1, \"position\": [0,1,0]}]}",
         PF_ERR_PARSE, "lights[0].position: a directional light has no position"},
        {HEAD "\"lights\": [{\"type\": \"spot\", \"position\": [0,0,0], \"direction\": [0,-1,0], \"intensity\": 1}]}",
         PF_ERR_PARSE, "missing key 'inner_cone_deg'"},
        {HEAD "\"lights\": [{\"type\": \"spot\", \"position\": [0,0,0], \"direction\": [0,-1,0], \"intensity\": 1,"
              " \"inner_cone_deg\": 30, \"outer_cone_deg\": 20}]}",
         PF_ERR_PARSE, "lights[0]: inner_cone_deg must be below outer_cone_deg"},
        {HEAD "\"lights\": [{\"type\": \"spot\", \"position\": [0,0,0], \"direction\": [0,-1,0], \"intensity\": 1,"
              " \"inner_cone_deg\": 10, \"outer_cone_deg\": 20, \"keys\": [{\"frame\": 0, \"inner_cone_deg\": 10},"
              " {\"frame\": 9, \"inner_cone_deg\": 40}]}]}",
         PF_ERR_PARSE, "t.seq.json: lights[0]: need 0 <= inner < outer <= 90 degrees at frame 3"},
        {HEAD "\"lights\": [{\"type\": \"point\", \"position\": [0,0,0], \"intensity\": 1,"
              " \"keys\": [{\"frame\": 0, \"direction\": [0,1,0]}]}]}",
         PF_ERR_PARSE, "lights[0].keys[0].direction: a point light has no direction"},
        {HEAD "\"lights\": [{\"type\": \"point\", \"position\": [0,0,0], \"intensity\": 1, \"extra\": 1}]}",
         PF_ERR_PARSE, "lights[0]: unknown key 'extra'"},
        /* tracked pixels */
        {HEAD "\"track\": []}", PF_ERR_PARSE, "track: expected 1 to 64 pixels, got 0"},
        {HEAD "\"track\": [[1]]}", PF_ERR_PARSE, "track[0]: expected [x, y]"},
        {HEAD "\"track\": [[1, -2]]}", PF_ERR_PARSE, "track[0][1]: -2 is out of range"},
        {HEAD "\"size\": [64, 48], \"track\": [[64, 0]]}", PF_ERR_PARSE,
         "track[0]: pixel (64, 0) is outside the 64x48 image"},
        {HEAD "\"track\": 3}", PF_ERR_PARSE, "track: expected an array of [x, y], got a number"},
    };
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) expect_bad(bad[i].json, bad[i].code, bad[i].needle);

    /* found by fuzz_sequence: a raw newline in a string the message echoes; messages stay one line */
    static const char raw[] = "{\"scene\": \"embedded:cornel\xff\xff&\np/x\", \"frames\": 1}";
    pf_sequence s;
    pf_error err;
    assert_int_equal(pf_sequence_parse(&s, raw, sizeof raw - 1, "t.seq.json", &err), PF_ERR_PARSE);
    assert_null(strchr(err.message, '\n'));
    assert_non_null(strstr(err.message, "scene: 'embedded:cornel"));
    pf_sequence_free(&s);

    /* a NUL byte inside the text, and deep nesting (cJSON's limit, no stack overflow) */
    const char nul[] = "{\"scene\": \"a\"\0, \"frames\": 1}";
    assert_int_equal(pf_sequence_parse(&s, nul, sizeof nul - 1, "t.seq.json", &err), PF_ERR_PARSE);
    assert_non_null(strstr(err.message, "NUL byte"));
    size_t depth = 100000;
    char *deep = malloc(2 * depth + 1);
    assert_non_null(deep);
    memset(deep, '[', depth);
    memset(deep + depth, ']', depth);
    deep[2 * depth] = 0;
    assert_int_equal(pf_sequence_parse(&s, deep, 2 * depth, "t.seq.json", &err), PF_ERR_PARSE);
    free(deep);
    /* every prefix of a valid file fails cleanly (never crashes, never passes) */
    const char *good = HEAD "\"camera\": [{\"frame\": 0, \"eye\": [0,0,0], \"target\": [0,0,1], \"fovy_deg\": 40}],"
                            " \"lights\": [{\"light\": 0, \"keys\": [{\"frame\": 3, \"position\": [1,2,3]}]}]}";
    size_t n = strlen(good);
    for (size_t k = 0; k < n; k++) {
        char *p = malloc(k + 1); /* exact size: ASan catches any read past it */
        memcpy(p, good, k);
        assert_int_not_equal(pf_sequence_parse(&s, p, k, "t.seq.json", &err), PF_OK);
        pf_sequence_free(&s);
        free(p);
    }
    parse_ok(&s, good);
    pf_sequence_free(&s);

    /* files */
    assert_int_equal(pf_sequence_load(&s, "/nonexistent/x.seq.json", &err), PF_ERR_IO);
    assert_non_null(strstr(err.message, "/nonexistent/x.seq.json: cannot open"));
}

/* ---------------------------------------------------------------- emitters */

static void test_emitters_parse(void **state)
{
    (void)state;
    pf_sequence s;
    parse_ok(&s, HEAD "\"lights\": [], \"emitters\": ["
                      "{\"comment\": \"down\", \"quad\": [[0,2,0], [1,2,0], [1,2,1], [0,2,1]], \"emission\": [17, 12, 4]},"
                      "{\"quad\": [[0,0,0], [0,1,0], [0,1,1], [0,0,1]], \"emission\": [1e10, 0, 0], \"two_sided\": true},"
                      "{\"quad\": [[0,0,5], [2,0,5], [2,3,5], [0,3,5]], \"emission\": [1, 1, 1], \"two_sided\": false}]}");
    assert_int_equal(s.emitter_count, 3);
    assert_true(s.lights_replace);
    assert_int_equal(s.light_count, 0);
    assert_null(s.lights);
    assert_true(s.emitters[0].quad[2].x == 1.0f && s.emitters[0].quad[2].y == 2.0f && s.emitters[0].quad[2].z == 1.0f);
    assert_true(s.emitters[0].emission.x == 17.0f && s.emitters[0].emission.z == 4.0f);
    assert_false(s.emitters[0].two_sided);
    assert_true(s.emitters[1].two_sided);
    assert_true(s.emitters[1].emission.x == 1e10f);
    assert_false(s.emitters[2].two_sided);
    pf_sequence_free(&s);
    assert_int_equal(s.emitter_count, 0);

    /* emitters with the scene's lights kept (no "lights") */
    parse_ok(&s, HEAD "\"emitters\": [{\"quad\": [[0,2,0], [1,2,0], [1,2,1], [0,2,1]], \"emission\": [1, 1, 1]}]}");
    assert_int_equal(s.emitter_count, 1);
    assert_false(s.lights_replace);
    pf_sequence_free(&s);

    /* a file's limit: PF_SEQUENCE_MAX_EMITTERS, then one too many */
    for (uint32_t n = PF_SEQUENCE_MAX_EMITTERS; n <= PF_SEQUENCE_MAX_EMITTERS + 1; n++) {
        char json[8192];
        size_t len = (size_t)snprintf(json, sizeof json, HEAD "\"emitters\": [");
        for (uint32_t i = 0; i < n; i++)
            len += (size_t)snprintf(json + len, sizeof json - len,
                                    "%s{\"quad\": [[0,%u,0], [1,%u,0], [1,%u,1], [0,%u,1]], \"emission\": [1,1,1]}",
                                    i ? ", " : "", i, i, i, i);
        snprintf(json + len, sizeof json - len, "]}");
        if (n == PF_SEQUENCE_MAX_EMITTERS) {
            parse_ok(&s, json);
            assert_int_equal(s.emitter_count, n);
            assert_true(s.emitters[n - 1].quad[0].y == (float)(n - 1));
            pf_sequence_free(&s);
        } else
            expect_bad(json, PF_ERR_PARSE, "emitters: 17 emitters (at most 16)");
    }

    /* a failure after good emitters leaves nothing behind */
    pf_error err;
    const char *j = HEAD "\"emitters\": [{\"quad\": [[0,2,0], [1,2,0], [1,2,1], [0,2,1]], \"emission\": [1, 1, 1]}],"
                         " \"track\": 3}";
    assert_int_equal(pf_sequence_parse(&s, j, strlen(j), "t.seq.json", &err), PF_ERR_PARSE);
    assert_int_equal(s.emitter_count, 0);
    pf_sequence_free(&s);
}

/* One triangle in y = 0 with one grey material: a scene built in memory. */
static void tiny_scene(pf_scene *sc)
{
    memset(sc, 0, sizeof *sc);
    sc->vertex_count = 3;
    sc->positions = calloc(4, sizeof *sc->positions);
    sc->normals = calloc(3, sizeof *sc->normals);
    sc->uvs = calloc(3, sizeof *sc->uvs);
    sc->tri_count = 1;
    sc->indices = calloc(3, sizeof *sc->indices);
    sc->tri_material = calloc(1, sizeof *sc->tri_material);
    sc->material_count = 1;
    sc->materials = calloc(1, sizeof *sc->materials);
    assert_true(sc->positions && sc->normals && sc->uvs && sc->indices && sc->tri_material && sc->materials);
    sc->positions[1] = pf_v3(0, 0, 1);
    sc->positions[2] = pf_v3(1, 0, 0);
    for (int i = 0; i < 3; i++) {
        sc->normals[i] = pf_v3(0, 1, 0);
        sc->indices[i] = (uint32_t)i;
    }
    for (int k = 0; k < 4; k++) sc->materials[0].base_color[k] = 0.5f;
    sc->materials[0].base_color_texture = -1;
}

static void test_emitter_geometry(void **state)
{
    (void)state;
    pf_error err;
    pf_scene sc;
    tiny_scene(&sc);
    /* a 2 x 1 panel at y = 3 facing down (counter-clockwise from below) */
    const pf_vec3 q[4] = {pf_v3(-1, 3, 0), pf_v3(1, 3, 0), pf_v3(1, 3, 1), pf_v3(-1, 3, 1)};
    assert_int_equal(pf_scene_add_emitter_quad(&sc, q, pf_v3(5, 4, 3), 0, &err), PF_OK);
    assert_int_equal(sc.vertex_count, 7);
    assert_int_equal(sc.tri_count, 3);
    assert_int_equal(sc.material_count, 2);
    for (int i = 0; i < 4; i++) {
        assert_memory_equal(&sc.positions[3 + i], &q[i], sizeof q[i]);
        assert_true(sc.normals[3 + i].x == 0.0f && sc.normals[3 + i].y == -1.0f && sc.normals[3 + i].z == 0.0f);
    }
    assert_true(sc.uvs[3].x == 0.0f && sc.uvs[3].y == 0.0f && sc.uvs[5].x == 1.0f && sc.uvs[5].y == 1.0f);
    assert_true(pf_v3_is_finite(sc.positions[7])); /* the padding element exists */
    static const uint32_t idx[6] = {3, 4, 5, 3, 5, 6};
    assert_memory_equal(&sc.indices[3], idx, sizeof idx);
    assert_int_equal(sc.tri_material[1], 1);
    assert_int_equal(sc.tri_material[2], 1);
    const pf_material *m = &sc.materials[1];
    assert_true(m->emission[0] == 5.0f && m->emission[1] == 4.0f && m->emission[2] == 3.0f);
    assert_true(m->base_color[0] == 0.78f && m->base_color[3] == 1.0f && m->base_color_texture == -1);
    assert_false(m->double_sided);
    assert_int_equal(m->alpha_mode, PF_ALPHA_OPAQUE);
    /* both triangles face down: the emitting side */
    for (uint32_t t = 1; t < 3; t++) {
        pf_vec3 n = pf_scene_face_normal(&sc, t);
        assert_true(n.y < -0.9999f);
    }
    /* the caller validates: the bounds now hold the panel */
    assert_int_equal(pf_scene_validate(&sc, &err), PF_OK);
    assert_true(sc.bounds_min.x == -1.0f && sc.bounds_max.x == 1.0f && sc.bounds_max.y == 3.0f &&
                sc.bounds_min.y == 0.0f && sc.bounds_max.z == 1.0f);
    /* a second one, two-sided: its own material */
    const pf_vec3 w[4] = {pf_v3(2, 0, 0), pf_v3(2, 1, 0), pf_v3(2, 1, 1), pf_v3(2, 0, 1)};
    assert_int_equal(pf_scene_add_emitter_quad(&sc, w, pf_v3(1, 1, 1), 1, &err), PF_OK);
    assert_int_equal(sc.material_count, 3);
    assert_true(sc.materials[2].double_sided);
    assert_true(pf_scene_face_normal(&sc, 3).x > 0.9999f); /* (0,1,0) x (0,1,1) = +X */
    assert_int_equal(pf_scene_validate(&sc, &err), PF_OK);
    assert_true(sc.bounds_max.x == 2.0f);

    /* refused: the scene is left as it was */
    const pf_vec3 bad_nan[4] = {pf_v3(NAN, 0, 0), q[1], q[2], q[3]};
    const pf_vec3 bad_huge[4] = {q[0], q[1], pf_v3(1, 3e7f, 1), q[3]};
    const pf_vec3 flat[4] = {q[0], q[0], q[0], q[0]};
    const struct {
        const pf_vec3 *q;
        float e;
        pf_result code;
        const char *needle;
    } bad[] = {
        {bad_nan, 1, PF_ERR_NONFINITE, "corner 0 is not finite"},
        {bad_huge, 1, PF_ERR_NONFINITE, "corner 2 (1, 3e+07, 1) lies beyond |x| <= 1e+07"},
        {flat, 1, PF_ERR_PARSE, "the four corners coincide"},
        {q, NAN, PF_ERR_NONFINITE, "emission is not finite"},
        {q, -1, PF_ERR_PARSE, "emission must be >= 0"},
        {q, 0, PF_ERR_PARSE, "emission is zero"},
        {q, 2e10f, PF_ERR_NONFINITE, "exceeds softgi's limit"},
    };
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        memset(&err, 0, sizeof err);
        assert_int_equal(pf_scene_add_emitter_quad(&sc, bad[i].q, pf_v3(bad[i].e, bad[i].e, bad[i].e), 0, &err), bad[i].code);
        if (!strstr(err.message, bad[i].needle)) fail_msg("case %zu: '%s' lacks '%s'", i, err.message, bad[i].needle);
        assert_int_equal(sc.vertex_count, 11);
        assert_int_equal(sc.tri_count, 5);
        assert_int_equal(sc.material_count, 3);
    }
    /* the counts' overflow guard, before any allocation */
    uint32_t vc = sc.vertex_count;
    sc.vertex_count = UINT32_MAX - 4;
    assert_int_equal(pf_scene_add_emitter_quad(&sc, q, pf_v3(1, 1, 1), 0, &err), PF_ERR_OUT_OF_MEMORY);
    assert_non_null(strstr(err.message, "too large"));
    assert_int_equal(sc.vertex_count, UINT32_MAX - 4);
    sc.vertex_count = vc;
    pf_scene_free(&sc);

    /* into an empty scene (NULL arrays): a scene of one emitter */
    memset(&sc, 0, sizeof sc);
    assert_int_equal(pf_scene_add_emitter_quad(&sc, q, pf_v3(1, 1, 1), 0, &err), PF_OK);
    assert_int_equal(sc.vertex_count, 4);
    assert_int_equal(sc.tri_count, 2);
    assert_int_equal(sc.material_count, 1);
    assert_int_equal(pf_scene_validate(&sc, &err), PF_OK);
    pf_scene_free(&sc);
}

/* pf_sequence_apply_emitters on a glTF scene with a point light: the quad
 * is added, "lights": [] clears the light, validation passes, and the
 * bounds hold the quad. */
static void test_emitter_apply(void **state)
{
    (void)state;
    char path[1024];
    snprintf(path, sizeof path, "%s/scenes/cornell-box/cornell-box.gltf", SOFTGI_SOURCE_DIR);
    pf_error err;
    pf_scene sc;
    pf_gltf_options go;
    memset(&go, 0, sizeof go);
    if (pf_gltf_load(&sc, path, &go, &err) != PF_OK) fail_msg("%s", err.message);
    assert_true(sc.light_count >= 1);
    assert_int_equal(pf_scene_validate(&sc, &err), PF_OK);
    const uint32_t tris = sc.tri_count, mats = sc.material_count;
    const float top = sc.bounds_max.y + 1.0f;
    char json[1024];
    snprintf(json, sizeof json,
             HEAD "\"lights\": [], \"emitters\": [{\"quad\": [[0,%.9g,0], [0.5,%.9g,0], [0.5,%.9g,0.5], "
                  "[0,%.9g,0.5]], \"emission\": [3, 2, 1], \"two_sided\": true}]}",
             (double)top, (double)top, (double)top, (double)top);
    pf_sequence s;
    parse_ok(&s, json);
    assert_int_equal(pf_sequence_apply_emitters(&s, &sc, &err), PF_OK);
    assert_int_equal(sc.light_count, 0);
    assert_int_equal(sc.tri_count, tris + 2);
    assert_int_equal(sc.material_count, mats + 1);
    assert_true(sc.materials[mats].emission[0] == 3.0f && sc.materials[mats].double_sided);
    assert_int_equal(pf_scene_validate(&sc, &err), PF_OK);
    assert_true(sc.bounds_max.y == top);
    pf_sequence_free(&s);

    /* without "lights" the scene's lights stay */
    pf_scene_free(&sc);
    if (pf_gltf_load(&sc, path, &go, &err) != PF_OK) fail_msg("%s", err.message);
    const uint32_t lights = sc.light_count;
    parse_ok(&s, HEAD "\"emitters\": [{\"quad\": [[0,2,0], [1,2,0], [1,2,1], [0,2,1]], \"emission\": [1, 1, 1]}]}");
    assert_int_equal(pf_sequence_apply_emitters(&s, &sc, &err), PF_OK);
    assert_int_equal(sc.light_count, lights);
    pf_sequence_free(&s);
    pf_scene_free(&sc);
}

/* The area-light table sees the quad as softgi's other emitters: two
 * triangles of total area A and power faces x pi A Le; and its estimator
 * gives the irradiance of the analytic form factor of a square on a point
 * below its centre (e.g. Howell's catalogue, C-11 per corner rectangle):
 *   E = 4 Le X / sqrt(1 + X^2) atan(X / sqrt(1 + X^2)),  X = a / (2 h). */
static void test_emitter_area_light(void **state)
{
    (void)state;
    pf_error err;
    for (int two = 0; two <= 1; two++) {
        pf_scene sc;
        tiny_scene(&sc);
        const float a = 2.0f, h = 1.5f, le = 3.0f;
        const pf_vec3 q[4] = {pf_v3(-1, h, -1), pf_v3(1, h, -1), pf_v3(1, h, 1), pf_v3(-1, h, 1)};
        assert_int_equal(pf_scene_add_emitter_quad(&sc, q, pf_v3(le, le, le), two, &err), PF_OK);
        assert_int_equal(pf_scene_validate(&sc, &err), PF_OK);
        gi_area_lights al;
        assert_int_equal(gi_area_lights_build(&al, &sc, &err), PF_OK);
        assert_int_equal(al.count, 2);
        float area = 0.0f;
        for (uint32_t i = 0; i < al.count; i++) {
            area += al.tri[i].area;
            assert_true(al.tri[i].normal.y < -0.9999f);
            assert_int_equal(al.tri[i].two_sided, (uint32_t)two);
            assert_true(al.tri[i].radiance.x == le);
        }
        assert_float_equal(area, a * a, 1e-5f);
        const double power = (two ? 2.0 : 1.0) * PF_PI * (double)(a * a) * le;
        if (fabs(al.total_power - power) > 1e-4 * power) fail_msg("power %g, expected %g", al.total_power, power);
        assert_float_equal(al.power_rgb.x, (float)power, 1e-3f * (float)power);
        /* irradiance at the floor point under the centre, facing up: a
         * stratified estimate (deterministic) against the form factor */
        const uint32_t n = 256;
        double sum = 0.0;
        for (uint32_t i = 0; i < n * n; i++) {
            double u0 = fmod(0.5 + (double)i * 0.6180339887498949, 1.0); /* golden-ratio sequence */
            float u1 = ((float)(i % n) + 0.5f) / (float)n, u2 = ((float)(i / n) + 0.5f) / (float)n;
            gi_area_sample smp;
            gi_area_sample_point(&al, u0, u1, u2, &smp);
            pf_vec3 e, wi;
            float dist;
            if (gi_area_sample_irradiance(&smp, pf_v3(0, 0, 0), pf_v3(0, 1, 0), &e, &wi, &dist)) sum += e.x;
        }
        const double x = a / (2.0 * h), r = x / sqrt(1.0 + x * x);
        const double expect = 4.0 * le * r * atan(r);
        const double got = sum / (double)(n * n);
        if (fabs(got - expect) > 0.01 * expect) fail_msg("two_sided %d: irradiance %g, form factor gives %g", two, got, expect);
        gi_area_lights_free(&al);
        pf_scene_free(&sc);
    }
}

/* ---------------------------------------------------------------- interpolation */

static void test_interpolation(void **state)
{
    (void)state;
    pf_sequence s;
    parse_ok(&s, "{\"scene\": \"embedded:cornell-box\", \"frames\": 21, \"camera\": ["
                 "{\"frame\": 4, \"eye\": [0.1, 0.2, 0.3], \"target\": [1, 1, 1], \"fovy_deg\": 30},"
                 "{\"frame\": 8, \"eye\": [2.1, -0.2, 4.3], \"target\": [3, 1, 1], \"fovy_deg\": 50},"
                 "{\"frame\": 18, \"eye\": [-1, 0, 0], \"target\": [0, 0, 7], \"fovy_deg\": 70}],"
                 " \"lights\": [{\"light\": 1, \"keys\": ["
                 "{\"frame\": 0, \"position\": [0, 0, 0], \"intensity\": 2},"
                 "{\"frame\": 10, \"position\": [10, -20, 0.5]},"
                 "{\"frame\": 20, \"intensity\": 4, \"direction\": [1, 0, 0]}]}]}");
    pf_vec3 e, t;
    float f;
    /* exact at keys; held before the first and after the last */
    assert_true(pf_sequence_camera_at(&s, 4, &e, &t, &f));
    assert_true(e.x == 0.1f && e.y == 0.2f && e.z == 0.3f && t.x == 1.0f && f == 30.0f);
    assert_true(pf_sequence_camera_at(&s, 0, &e, &t, &f));
    assert_true(e.x == 0.1f && f == 30.0f);
    assert_true(pf_sequence_camera_at(&s, 8, &e, &t, &f));
    assert_true(e.x == 2.1f && e.y == -0.2f && e.z == 4.3f && t.x == 3.0f && f == 50.0f);
    assert_true(pf_sequence_camera_at(&s, 18, &e, &t, &f));
    assert_true(e.x == -1.0f && t.z == 7.0f && f == 70.0f);
    assert_true(pf_sequence_camera_at(&s, 20, &e, &t, &f));
    assert_true(e.x == -1.0f && t.z == 7.0f && f == 70.0f);
    /* midpoints: (a + b) / 2 rounded once */
    assert_true(pf_sequence_camera_at(&s, 6, &e, &t, &f));
    assert_true(e.x == (float)(0.5 * (double)0.1f + 0.5 * (double)2.1f));
    assert_true(e.y == (float)(0.5 * (double)0.2f + 0.5 * (double)-0.2f));
    assert_true(t.x == 2.0f && f == 40.0f);
    assert_true(pf_sequence_camera_at(&s, 13, &e, &t, &f));
    assert_true(t.z == 4.0f && f == 60.0f);
    /* a quarter of the way */
    assert_true(pf_sequence_camera_at(&s, 5, &e, &t, &f));
    assert_true(f == 35.0f && t.x == 1.5f);

    /* light fields are separate tracks; unkeyed fields keep the base */
    pf_light base, L;
    pf_error err;
    memset(&base, 0, sizeof base);
    base.type = PF_LIGHT_SPOT;
    base.position = pf_v3(9, 9, 9);
    base.direction = pf_v3(0, -1, 0);
    base.color = pf_v3(0.5f, 0.5f, 0.5f);
    base.intensity = 7;
    base.inner_cone = 0.1f;
    base.outer_cone = 0.2f;
    assert_int_equal(pf_sequence_light_at(&s, 0, 5, &base, &L, &err), PF_OK);
    assert_true(L.position.x == 5.0f && L.position.y == -10.0f && L.position.z == 0.25f);
    assert_true(L.intensity == 2.5f); /* keys at 0 and 20 */
    assert_true(L.direction.x == 1.0f && L.direction.y == 0.0f); /* one key: held */
    assert_true(L.color.x == 0.5f && L.outer_cone == 0.2f);
    assert_int_equal(pf_sequence_light_at(&s, 0, 10, &base, &L, &err), PF_OK);
    assert_true(L.position.x == 10.0f && L.position.y == -20.0f && L.position.z == 0.5f);
    assert_true(L.intensity == 3.0f); /* the midpoint */
    assert_int_equal(pf_sequence_light_at(&s, 0, 20, &base, &L, &err), PF_OK);
    assert_true(L.position.x == 10.0f && L.intensity == 4.0f);
    /* a direction key on a point light is caught once the base is known */
    base.type = PF_LIGHT_POINT;
    assert_int_equal(pf_sequence_light_at(&s, 0, 5, &base, &L, &err), PF_ERR_PARSE);
    assert_non_null(strstr(err.message, "is a point light, it has no direction"));
    pf_sequence_free(&s);

    /* directions: normalised linear interpolation */
    parse_ok(&s, HEAD "\"lights\": [{\"type\": \"directional\", \"direction\": [0,-1,0], \"intensity\": 1,"
                      " \"keys\": [{\"frame\": 0, \"direction\": [0, -5, 0]}, {\"frame\": 2, \"direction\": [1, 0, 0]}]}]}");
    assert_int_equal(pf_sequence_light_at(&s, 0, 1, NULL, &L, &err), PF_OK);
    assert_true(fabsf(L.direction.x - 0.70710678f) < 1e-6f && fabsf(L.direction.y + 0.70710678f) < 1e-6f);
    assert_int_equal(pf_sequence_light_at(&s, 0, 0, NULL, &L, &err), PF_OK);
    assert_true(L.direction.x == 0.0f && L.direction.y == -1.0f);
    pf_sequence_free(&s);

    /* a track without keys leaves the output alone */
    pf_sequence_track empty;
    memset(&empty, 0, sizeof empty);
    float v = 42.0f;
    pf_sequence_track_eval(&empty, 3, &v);
    assert_true(v == 42.0f);
}

/* ---------------------------------------------------------------- end to end */

static const char *k_camera_seq =
    "{\"scene\": \"embedded:cornell-box\", \"frames\": 6, \"size\": [64, 48],\n"
    " \"camera\": [{\"frame\": 0, \"eye\": [0.278, 0.273, -0.8], \"target\": [0.278, 0.273, 0.28], \"fovy_deg\": 39.3},\n"
    "            {\"frame\": 5, \"eye\": [0.1, 0.3, -0.7], \"target\": [0.278, 0.25, 0.28], \"fovy_deg\": 42}],\n"
    " \"track\": [[10, 10], [40, 30]]}\n";
static const char *k_light_seq =
    "{\"scene\": \"embedded:cornell-box\", \"frames\": 6, \"size\": [64, 48],\n"
    " \"lights\": [{\"light\": 0, \"keys\": [{\"frame\": 0, \"position\": [0.278, 0.5388, 0.2795]},\n"
    "                                   {\"frame\": 5, \"position\": [0.15, 0.45, 0.2]}]}]}\n";

#define FAST "--vpls 64 --shadow-size 256 --isa sse2"

/* Runs `softgi sequence`, checks exit 0, returns the moved counts per frame
 * (-1 where a frame line is missing) and the hash. */
static void run_sequence(const char *seq, const char *dir, const char *extra, int moved[6], char hash[17])
{
    char args[2048], out[32768];
    snprintf(args, sizeof args, "sequence '%s' -o '%s' " FAST " --hash %s", seq, dir, extra);
    int st = tu_softgi_run(args, out, sizeof out);
    if (st != 0) fail_msg("softgi %s: exit %d\n%s", args, st, out);
    for (int f = 0; f < 6; f++) {
        char key[32];
        snprintf(key, sizeof key, "frame %04d ", f);
        const char *line = strstr(out, key);
        const char *m = line ? strstr(line, "moved ") : NULL;
        moved[f] = m ? atoi(m + 6) : -1;
    }
    const char *h = strstr(out, "hash ");
    if (!h || sscanf(h, "hash %16s", hash) != 1) fail_msg("no hash in:\n%s", out);
}

static void test_end_to_end(void **state)
{
    (void)state;
    char cam[512], light[512], d1[512], d2[512], d3[512], d4[512], path[1024];
    snprintf(cam, sizeof cam, "%s/cam.seq.json", g_tmp);
    snprintf(light, sizeof light, "%s/light.seq.json", g_tmp);
    write_file(cam, k_camera_seq);
    write_file(light, k_light_seq);
    snprintf(d1, sizeof d1, "%s/cam1", g_tmp);
    snprintf(d2, sizeof d2, "%s/cam2", g_tmp);
    snprintf(d3, sizeof d3, "%s/light1", g_tmp);
    snprintf(d4, sizeof d4, "%s/light2", g_tmp);

    /* static light, moving camera: VPLs made at frame 0 and kept */
    int moved[6];
    char h1[17], h2[17];
    run_sequence(cam, d1, "--threads 1", moved, h1);
    if (moved[0] <= 0) fail_msg("frame 0 moved %d VPLs", moved[0]);
    for (int f = 1; f < 6; f++)
        if (moved[f] != 0) fail_msg("camera sequence: frame %d moved %d VPLs (want 0)", f, moved[f]);
    run_sequence(cam, d2, "--threads 2", moved, h2);
    assert_string_equal(h1, h2);

    /* moving light: Instant Radiosity regenerates every VPL every frame */
    int moved_l[6];
    char h3[17], h4[17];
    run_sequence(light, d3, "--threads 1", moved_l, h3);
    for (int f = 0; f < 6; f++)
        if (moved_l[f] != moved[0]) fail_msg("light sequence: frame %d moved %d VPLs (want all %d)", f, moved_l[f], moved[0]);
    run_sequence(light, d4, "--threads 2", moved_l, h4);
    assert_string_equal(h3, h4);
    assert_string_not_equal(h1, h3);
    /* the ray-traced frame keeps the same guarantees */
    char h5[17], h6[17], d5[512];
    snprintf(d5, sizeof d5, "%s/light-rt", g_tmp);
    run_sequence(light, d5, "--threads 1 --raytrace", moved_l, h5);
    for (int f = 0; f < 6; f++) assert_int_equal(moved_l[f], moved[0]);
    run_sequence(light, d5, "--threads 2 --raytrace", moved_l, h6);
    assert_string_equal(h5, h6);
    assert_string_not_equal(h3, h5);

    /* the files compare reads */
    static const char *const suffix[] = {".pfm", ".png", ".view", ".depth.pfm"};
    for (int f = 0; f < 6; f++)
        for (int k = 0; k < 4; k++) {
            snprintf(path, sizeof path, "%s/frame_%04d%s", d1, f, suffix[k]);
            if (!tu_file_exists(path)) fail_msg("missing %s", path);
        }
    snprintf(path, sizeof path, "%s/frame_0006.pfm", d1);
    assert_false(tu_file_exists(path));
    snprintf(path, sizeof path, "%s/track.txt", d1);
    FILE *tf = fopen(path, "r");
    assert_non_null(tf);
    char line[64];
    assert_non_null(fgets(line, sizeof line, tf));
    assert_string_equal(line, "10,10\n");
    fclose(tf);

    char args[4096], out[32768];
    snprintf(args, sizeof args, "compare --reference '%s' --name t2:'%s' --track 10,10 --track 40,30", d1, d2);
    int st = tu_softgi_run(args, out, sizeof out);
    if (st != 0 || !strstr(out, "| t2 | 6 | 0 | 0 |")) fail_msg("softgi %s: exit %d\n%s", args, st, out);
    snprintf(args, sizeof args, "compare --reference '%s' --name light:'%s'", d1, d3);
    st = tu_softgi_run(args, out, sizeof out);
    if (st != 0 || !strstr(out, "| light | 6 |")) fail_msg("softgi %s: exit %d\n%s", args, st, out);

    /* a shorter run into the same folder deletes nothing: the older frames
     * stay, frames.txt lists this run's 2, track.txt is replaced by an empty
     * list (no "track" in this file), and compare reads only the 2 frames */
    char shortseq[512];
    snprintf(shortseq, sizeof shortseq, "%s/short.seq.json", g_tmp);
    write_file(shortseq, "{\"scene\": \"embedded:cornell-box\", \"frames\": 2, \"size\": [64, 48]}");
    snprintf(args, sizeof args, "sequence '%s' -o '%s' -q --direct-only --shadow-size 64", shortseq, d2);
    st = tu_softgi_run(args, out, sizeof out);
    if (st != 0) fail_msg("softgi %s: exit %d\n%s", args, st, out);
    snprintf(path, sizeof path, "%s/frame_0001.view", d2);
    assert_true(tu_file_exists(path));
    snprintf(path, sizeof path, "%s/frame_0002.pfm", d2);
    assert_true(tu_file_exists(path));
    snprintf(path, sizeof path, "%s/frame_0005.depth.pfm", d2);
    assert_true(tu_file_exists(path));
    snprintf(path, sizeof path, "%s/track.txt", d2);
    tf = fopen(path, "r");
    assert_non_null(tf);
    assert_null(fgets(line, sizeof line, tf));
    fclose(tf);
    snprintf(path, sizeof path, "%s/frames.txt", d2);
    tf = fopen(path, "r");
    assert_non_null(tf);
    char manifest[128] = "";
    assert_true(fread(manifest, 1, sizeof manifest - 1, tf) > 0);
    fclose(tf);
    assert_string_equal(manifest, "softgi-frames 1\nframes 2\nstate complete\n");
    snprintf(args, sizeof args, "compare --reference '%s' --name short:'%s'", d1, d2);
    st = tu_softgi_run(args, out, sizeof out);
    if (st != 0 || !strstr(out, "| short | 2 |") || !strstr(out, "has 6 frames; comparing the first 2"))
        fail_msg("softgi %s: exit %d\n%s", args, st, out);
}

/* A sequence lit by its emitter alone ("lights": [] and "emitters"): the
 * scene's point light is gone, the emitter lights the frame, and the output
 * is the same with 1 and 2 threads. (Needs the app_scene_load_sequence
 * hook.) */
static void test_emitter_end_to_end(void **state)
{
    (void)state;
    static const char *const k_area =
        "{\"scene\": \"embedded:cornell-box\", \"frames\": 3, \"size\": [40, 30],"
        " \"camera\": [{\"frame\": 0, \"eye\": [0.278, 0.273, -0.8], \"target\": [0.278, 0.273, 0.28], \"fovy_deg\": 39},"
        "              {\"frame\": 2, \"eye\": [0.3, 0.28, -0.8], \"target\": [0.278, 0.273, 0.28], \"fovy_deg\": 39}],"
        " \"lights\": [],"
        " \"emitters\": [{\"quad\": [[0.2, 0.54, 0.2], [0.35, 0.54, 0.2], [0.35, 0.54, 0.35], [0.2, 0.54, 0.35]],"
        "                 \"emission\": [20, 20, 20]}]}";
    char seq[512], d1[512], d2[512], args[2048], out[32768], path[1024];
    snprintf(seq, sizeof seq, "%s/area.seq.json", g_tmp);
    write_file(seq, k_area);
    snprintf(d1, sizeof d1, "%s/area1", g_tmp);
    snprintf(d2, sizeof d2, "%s/area2", g_tmp);
    char h1[17], h2[17];
    for (int run = 0; run < 2; run++) {
        snprintf(args, sizeof args, "sequence '%s' -o '%s' " FAST " --hash --threads %d", seq, run ? d2 : d1, run + 1);
        int st = tu_softgi_run(args, out, sizeof out);
        if (st != 0) fail_msg("softgi %s: exit %d\n%s", args, st, out);
        if (!strstr(out, " triangles, 0 lights,")) fail_msg("want no punctual light (the emitter alone):\n%s", out);
        const char *h = strstr(out, "hash ");
        if (!h || sscanf(h, "hash %16s", run ? h2 : h1) != 1) fail_msg("no hash in:\n%s", out);
    }
    assert_string_equal(h1, h2);
    /* lit: the frame's mean is well above black */
    snprintf(path, sizeof path, "%s/frame_0000.pfm", d1);
    float *rgb = NULL;
    uint32_t w = 0, h = 0;
    pf_error err;
    if (pf_imageio_read_pfm(path, &rgb, &w, &h, &err) != PF_OK) fail_msg("%s", err.message);
    double sum = 0.0;
    for (size_t i = 0; i < (size_t)w * h * 3; i++) sum += rgb[i];
    free(rgb);
    if (!(sum / ((double)w * h * 3) > 0.05)) fail_msg("frame 0 mean %g: the emitter does not light the box", sum / ((double)w * h * 3));
}

static void test_cli_errors(void **state)
{
    (void)state;
    char seq[512], args[2048];
    tu_softgi_expect("sequence", 2, "give the sequence file");
    tu_softgi_expect("sequence /nonexistent/a.seq.json", 1, "/nonexistent/a.seq.json: cannot open the sequence file");

    snprintf(seq, sizeof seq, "%s/bad.seq.json", g_tmp);
    write_file(seq, "{\"scene\": \"embedded:cornell-box\", \"frames\": 3,");
    snprintf(args, sizeof args, "sequence '%s'", seq);
    tu_softgi_expect(args, 1, "bad.seq.json: JSON ends too early");
    /* a bad emitter: one line naming the file and the place, exit 1 */
    write_file(seq, "{\"scene\": \"embedded:cornell-box\", \"frames\": 3, \"emitters\": [{\"quad\": "
                    "[[0,1,0], [1,1,0], [1,1,1], [0,1.1,1]], \"emission\": [1,1,1]}]}");
    tu_softgi_expect(args, 1, "bad.seq.json: emitters[0].quad: not planar: corner");

    write_file(seq, "{\"scene\": \"missing.gltf\", \"frames\": 3}");
    tu_softgi_expect(args, 1, "missing.gltf");

    write_file(seq, "{\"scene\": \"embedded:cornell-box\", \"frames\": 3,"
                    " \"lights\": [{\"light\": 4, \"keys\": [{\"frame\": 0, \"intensity\": 2}]}]}");
    tu_softgi_expect(args, 1, "lights[0]: the scene has no light 4 (it has 1)");

    write_file(seq, "{\"scene\": \"embedded:cornell-box\", \"frames\": 3,"
                    " \"lights\": [{\"light\": 0, \"keys\": [{\"frame\": 0, \"direction\": [0,1,0]}]}]}");
    tu_softgi_expect(args, 1, "is a point light, it has no direction");

    write_file(seq, "{\"scene\": \"embedded:cornell-box\", \"frames\": 3, \"camera\": [{\"frame\": 0,"
                    " \"eye\": [0,0,0], \"target\": [0,0,1], \"fovy_deg\": 40}]}");
    snprintf(args, sizeof args, "sequence '%s' --camera 0,0,0:0,0,1:40", seq);
    tu_softgi_expect(args, 2, "--camera: ");

    write_file(seq, "{\"scene\": \"embedded:cornell-box\", \"frames\": 3, \"lights\": [{\"type\": \"point\","
                    " \"position\": [0.2,0.3,0.2], \"intensity\": 1}]}");
    snprintf(args, sizeof args, "sequence '%s' --light point:0,0,0:1,1,1:1", seq);
    tu_softgi_expect(args, 2, "--light: ");

    write_file(seq, "{\"scene\": \"embedded:cornell-box\", \"frames\": 3, \"track\": [[60, 40]]}");
    snprintf(args, sizeof args, "sequence '%s' --size 32x24", seq);
    tu_softgi_expect(args, 2, "track[0]: pixel (60, 40) is outside the 32x24 image");

    /* with a "size" in the file, --size scales the tracked pixels */
    char dir[512], path[1024], line[64];
    write_file(seq, "{\"scene\": \"embedded:cornell-box\", \"frames\": 1, \"size\": [64, 48],"
                    " \"track\": [[60, 40]]}");
    snprintf(dir, sizeof dir, "%s/scaled", g_tmp);
    snprintf(args, sizeof args, "sequence '%s' --size 32x24 -q --direct-only --shadow-size 64 -o '%s'", seq, dir);
    tu_softgi_expect(args, 0, "");
    snprintf(path, sizeof path, "%s/track.txt", dir);
    FILE *tf = fopen(path, "r");
    assert_non_null(tf);
    assert_non_null(fgets(line, sizeof line, tf));
    fclose(tf);
    assert_string_equal(line, "30,20\n");
}

static int read_all(const char *path, char *buf, size_t size, size_t *n);

/* "animation": the scene posed at every frame's time, the renderer updated
 * in place where it moved; the same bytes with 1 and 2 threads and for
 * --frames ranges; with the direct light alone (what carries no state from
 * frame to frame) a frame at time t equals `softgi render --time t`, so the
 * updated Embree scene, rasterizer and shadow maps are a fresh build's; bad
 * animations refused with one line. */
static void test_animation(void **state)
{
    (void)state;
    char seq[512], d1[512], d2[512], d3[512], args[4096], out[32768], p1[1024], p2[1024];
    snprintf(seq, sizeof seq, "%s/anim.seq.json", g_tmp);
    snprintf(args, sizeof args,
             "{\"scene\": \"%s/gltf/anim/anim_hierarchy.gltf\", \"frames\": 4, \"size\": [32, 24],"
             " \"animation\": {\"play\": \"wave\", \"time\": [0, 1.5]}}",
             SOFTGI_TEST_DATA);
    write_file(seq, args);
    snprintf(d1, sizeof d1, "%s/anim1", g_tmp);
    snprintf(d2, sizeof d2, "%s/anim2", g_tmp);
    snprintf(d3, sizeof d3, "%s/anim3", g_tmp);
    char h1[17] = "", h2[17] = "";
    for (int run = 0; run < 2; run++) {
        snprintf(args, sizeof args, "sequence '%s' -o '%s' " FAST " --hash --threads %d", seq, run ? d2 : d1,
                 run + 1);
        int st = tu_softgi_run(args, out, sizeof out);
        if (st != 0) fail_msg("softgi %s: exit %d\n%s", args, st, out);
        const char *h = strstr(out, "hash ");
        if (!h || sscanf(h, "hash %16s", run ? h2 : h1) != 1) fail_msg("no hash in:\n%s", out);
        /* t = 0, 0.5, 1, 1.5: frames 1 and 2 move both primitives of the hand, frame 3 (after the last key) none */
        if (!strstr(out, "frame 0001") || !strstr(out, "(2 objects moved: renderer updated)") ||
            !strstr(out, "pose (+ update when moved)"))
            fail_msg("softgi %s:\n%s", args, out);
        const char *f3 = strstr(out, "frame 0003");
        if (!f3 || strstr(f3, "moved: renderer updated")) fail_msg("frame 3 (after the last key) moved:\n%s", out);
    }
    assert_string_equal(h1, h2);
    /* a range: the full run's bytes */
    snprintf(args, sizeof args, "sequence '%s' -o '%s' " FAST " --frames 2:4 -q", seq, d3);
    tu_softgi_expect(args, 0, "");
    size_t n1 = 0, n2 = 0;
    static char b1[32 * 24 * 12 + 64], b2[32 * 24 * 12 + 64];
    for (int f = 2; f < 4; f++) {
        snprintf(p1, sizeof p1, "%s/frame_%04d.pfm", d1, f);
        snprintf(p2, sizeof p2, "%s/frame_%04d.pfm", d3, f);
        assert_true(read_all(p1, b1, sizeof b1, &n1) && read_all(p2, b2, sizeof b2, &n2));
        assert_true(n1 == n2 && !memcmp(b1, b2, n1));
    }
    /* --direct-only: frame 2 (t = 1, after two updates) = `softgi render --time 1` */
    snprintf(args, sizeof args, "sequence '%s' -o '%s' " FAST " --direct-only -q", seq, d3);
    tu_softgi_expect(args, 0, "");
    snprintf(p2, sizeof p2, "%s/render-t1.pfm", g_tmp);
    snprintf(args, sizeof args,
             "render '%s/gltf/anim/anim_hierarchy.gltf' --size 32x24 " FAST " --direct-only --time 1 -q -o '%s'",
             SOFTGI_TEST_DATA, p2);
    tu_softgi_expect(args, 0, "");
    snprintf(p1, sizeof p1, "%s/frame_0002.pfm", d3);
    assert_true(read_all(p1, b1, sizeof b1, &n1) && read_all(p2, b2, sizeof b2, &n2));
    if (!(n1 == n2 && !memcmp(b1, b2, n1))) fail_msg("%s differs from softgi render --time 1", p1);

    /* refused */
    snprintf(args, sizeof args, "sequence '%s' -o '%s' -q", seq, d3);
    write_file(seq, "{\"scene\": \"embedded:cornell-box\", \"frames\": 2, \"animation\": {}}");
    tu_softgi_expect(args, 2, "anim.seq.json: animation: embedded:cornell-box: the scene has no animations");
    char text[1024];
    snprintf(text, sizeof text,
             "{\"scene\": \"%s/gltf/anim/anim_linear.gltf\", \"frames\": 2, \"animation\": {\"play\": \"walk\"}}",
             SOFTGI_TEST_DATA);
    write_file(seq, text);
    tu_softgi_expect(args, 2, "anim_linear.gltf: no animation named 'walk' (the file has 4: 0 'slide'");
    snprintf(text, sizeof text,
             "{\"scene\": \"%s/gltf/anim/anim_linear.gltf\", \"frames\": 2, \"animation\": {\"play\": 7}}",
             SOFTGI_TEST_DATA);
    write_file(seq, text);
    tu_softgi_expect(args, 2, "anim_linear.gltf: no animation 7 (the file has 4");
    snprintf(text, sizeof text,
             "{\"scene\": \"%s/gltf/anim/anim_far.gltf\", \"frames\": 3, \"size\": [16, 12], \"animation\": {}}",
             SOFTGI_TEST_DATA);
    write_file(seq, text);
    snprintf(args, sizeof args, "sequence '%s' -o '%s' -q " FAST, seq, d3);
    tu_softgi_expect(args, 1, "anim.seq.json: frame 1: every animation at 0.5 s puts mesh 0 primitive 0 (node 0)");
}

static int read_all(const char *path, char *buf, size_t size, size_t *n)
{
    FILE *f = fopen(path, "rb");
    if (!f) return 0;
    *n = fread(buf, 1, size, f);
    fclose(f);
    return 1;
}

/* `sequence --reference` renders each frame with the path tracer: frame 0 is
 * byte-identical to `softgi reference` of the same camera and light, and
 * the run is the same for 1 and 2 threads. `evaluate` then builds its table
 * from references and a method's frames, and rejects bad options. */
static void test_reference_and_evaluate(void **state)
{
    (void)state;
    char seq[512], args[4096], out[32768], dir[512], a[1024], b[1024];
    snprintf(seq, sizeof seq, "%s/light.seq.json", g_tmp);
    write_file(seq, k_light_seq);
    char hash1[17] = "", hash2[17] = "";
    for (int t = 1; t <= 2; t++) {
        snprintf(dir, sizeof dir, "%s/ref%d", g_tmp, t);
        snprintf(args, sizeof args,
                 "sequence '%s' --reference --spp 4 --indirect-only --size 32x24 --isa sse2 --threads %d --hash -o '%s'",
                 seq, t, dir);
        int st = tu_softgi_run(args, out, sizeof out);
        if (st != 0) fail_msg("softgi %s: exit %d\n%s", args, st, out);
        assert_non_null(strstr(out, "path-traced reference"));
        const char *h = strstr(out, "hash ");
        assert_non_null(h);
        assert_int_equal(sscanf(h, "hash %16s", t == 1 ? hash1 : hash2), 1);
    }
    assert_string_equal(hash1, hash2);
    snprintf(a, sizeof a, "%s/single.pfm", g_tmp);
    snprintf(args, sizeof args,
             "reference --spp 4 --indirect-only --size 32x24 --isa sse2 -q -o '%s/single.png' --hdr '%s'", g_tmp, a);
    tu_softgi_expect(args, 0, "");
    snprintf(b, sizeof b, "%s/ref1/frame_0000.pfm", g_tmp);
    static char ia[1 << 16], ib[1 << 16];
    size_t na = 0, nb = 0;
    assert_true(read_all(a, ia, sizeof ia, &na));
    assert_true(read_all(b, ib, sizeof ib, &nb));
    assert_int_equal(na, nb);
    assert_memory_equal(ia, ib, na);
    tu_softgi_expect("sequence x.seq.json --reference --raytrace --spp 0", 2, "--spp");
    tu_softgi_expect("sequence x.seq.json --track-spp 64", 2, "--track-spp: only with sequence --reference");
    tu_softgi_expect("sequence x.seq.json --reference --reuse-frames", 2, "--reuse-frames: only with");

    /* --track-spp: the tracked pixels get exactly the reference's value at
     * that many samples, the others keep --spp's; --reuse-frames redoes only
     * the tracked pixels of the frames already there */
    char tseq[512], r4[600], r64[600];
    snprintf(tseq, sizeof tseq, "%s/track.seq.json", g_tmp);
    write_file(tseq, "{\"scene\": \"embedded:cornell-box\", \"frames\": 2, \"size\": [32, 24],"
                     " \"track\": [[10, 10], [20, 5]]}");
    snprintf(dir, sizeof dir, "%s/tracked", g_tmp);
    snprintf(args, sizeof args,
             "sequence '%s' --reference --spp 4 --track-spp 64 --indirect-only --isa sse2 -q -o '%s'", tseq, dir);
    tu_softgi_expect(args, 0, "");
    for (int k = 0; k < 2; k++) {
        snprintf(k ? r64 : r4, 600, "%s/r%d.pfm", g_tmp, k ? 64 : 4);
        snprintf(args, sizeof args,
                 "reference --spp %d --indirect-only --size 32x24 --isa sse2 -q -o '%s/r.png' --hdr '%s'", k ? 64 : 4,
                 g_tmp, k ? r64 : r4);
        tu_softgi_expect(args, 0, "");
    }
    float *img[4] = {NULL, NULL, NULL, NULL};
    uint32_t w, h;
    pf_error err;
    snprintf(a, sizeof a, "%s/frame_0000.pfm", dir);
    assert_int_equal(pf_imageio_read_pfm(a, &img[0], &w, &h, &err), PF_OK);
    assert_int_equal(pf_imageio_read_pfm(r4, &img[1], &w, &h, &err), PF_OK);
    assert_int_equal(pf_imageio_read_pfm(r64, &img[2], &w, &h, &err), PF_OK);
    size_t t1 = 3 * (10 * 32 + 10), t2 = 3 * (5 * 32 + 20), other = 3 * (12 * 32 + 16);
    assert_memory_equal(&img[0][t1], &img[2][t1], 3 * sizeof(float));
    assert_memory_equal(&img[0][t2], &img[2][t2], 3 * sizeof(float));
    assert_memory_equal(&img[0][other], &img[1][other], 3 * sizeof(float));
    assert_memory_not_equal(&img[1][t1], &img[2][t1], 3 * sizeof(float)); /* the samples differ: not vacuous */
    snprintf(args, sizeof args,
             "sequence '%s' --reference --spp 4 --track-spp 8 --reuse-frames --indirect-only --isa sse2 -q -o '%s'",
             tseq, dir);
    tu_softgi_expect(args, 0, "");
    assert_int_equal(pf_imageio_read_pfm(a, &img[3], &w, &h, &err), PF_OK);
    assert_memory_equal(&img[3][other], &img[1][other], 3 * sizeof(float));
    assert_memory_not_equal(&img[3][t1], &img[0][t1], 3 * sizeof(float));
    for (int k = 0; k < 4; k++) free(img[k]);
    tu_softgi_expect("render --reference", 2, "--reference is an option of sequence");

    /* evaluate: table with the method's row; the reference is reused */
    snprintf(dir, sizeof dir, "%s/ev", g_tmp);
    snprintf(args, sizeof args,
             "evaluate --sequences '%s' --methods ir,ir+reseed=1 --size 32x24 --spp 4 --vpls 32 --isa sse2 --out '%s'",
             seq, dir);
    int st = tu_softgi_run(args, out, sizeof out);
    if (st != 0) fail_msg("softgi %s: exit %d\n%s", args, st, out);
    assert_non_null(strstr(out, "reference: 4 spp"));
    st = tu_softgi_run(args, out, sizeof out);
    if (st != 0) fail_msg("softgi %s: exit %d\n%s", args, st, out);
    assert_non_null(strstr(out, "reference: reusing"));
    snprintf(a, sizeof a, "%s/table.md", dir);
    static char table[1 << 16];
    size_t nt = 0;
    assert_true(read_all(a, table, sizeof table - 1, &nt));
    table[nt] = 0;
    assert_non_null(strstr(table, "## light"));
    assert_non_null(strstr(table, "| ir | 6 |"));
    assert_non_null(strstr(table, "| ir+reseed=1 | 6 |")); /* a method entry with a parameter of its own */
    assert_null(strstr(table, "n/a"));
    snprintf(a, sizeof a, "%s/light/plot.svg", dir);
    FILE *pf = fopen(a, "r");
    assert_non_null(pf);
    fclose(pf);
    /* a method that computes no indirect light gets n/a and the reason,
     * never numbers: here the only light is switched off */
    char dark[512];
    snprintf(dark, sizeof dark, "%s/dark.seq.json", g_tmp);
    write_file(dark, "{\"scene\": \"embedded:cornell-box\", \"frames\": 2, \"size\": [32, 24],"
                     " \"lights\": [{\"light\": 0, \"keys\": [{\"frame\": 0, \"intensity\": 0}]}]}");
    snprintf(args, sizeof args,
             "evaluate --sequences '%s' --methods ir --size 32x24 --spp 4 --vpls 32 --isa sse2 -q --out '%s'", dark, dir);
    tu_softgi_expect(args, 0, "");
    snprintf(a, sizeof a, "%s/table.md", dir);
    assert_true(read_all(a, table, sizeof table - 1, &nt));
    table[nt] = 0;
    assert_non_null(strstr(table, "| ir | n/a | n/a | n/a | n/a | n/a |"));
    assert_non_null(strstr(table, "no frame of these methods holds any indirect light"));
    tu_softgi_expect("evaluate --methods ir,nosuch", 2, "unknown method 'nosuch'");
    tu_softgi_expect("evaluate --methods nosuch+k=1", 2, "unknown method 'nosuch+k=1'");
    tu_softgi_expect("evaluate --frobnicate", 2, "unknown option '--frobnicate'");
    tu_softgi_expect("evaluate --methods", 2, "--methods needs a value");
    tu_softgi_expect("evaluate --methods ir,,iir", 2, "empty item");
}

static int setup(void **state)
{
    (void)state;
    return tu_tmpdir_create(g_tmp, sizeof g_tmp, "softgi-test-sequence");
}

static int teardown(void **state)
{
    (void)state;
    return tu_tmpdir_remove(g_tmp);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_shipped_files), cmocka_unit_test(test_parse_fields),
        cmocka_unit_test(test_bad_inputs),    cmocka_unit_test(test_interpolation),
        cmocka_unit_test(test_end_to_end),    cmocka_unit_test(test_cli_errors),
        cmocka_unit_test(test_reference_and_evaluate), cmocka_unit_test(test_emitters_parse),
        cmocka_unit_test(test_emitter_geometry),       cmocka_unit_test(test_emitter_apply),
        cmocka_unit_test(test_emitter_area_light),     cmocka_unit_test(test_emitter_end_to_end),
        cmocka_unit_test(test_animation),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
