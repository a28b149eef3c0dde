/* fuzz_sequence: libFuzzer target for sequence files (pf_sequence.h), JSON
 * that `softgi sequence` and `softgi evaluate` take from anyone.
 *
 * Each input goes to pf_sequence_parse as the whole file. Invariants,
 * checked with abort():
 *   - failure: a one-line message starting with the file name, a known
 *     code, and an emptied sequence (no frames, no lights);
 *   - success: frames 1..PF_SEQUENCE_MAX_FRAMES, sizes <= PF_SEQUENCE_MAX_SIZE,
 *     a name without '/' that is not "." or "..", an "output" that is
 *     "out/" + a relative path without ".." components, tracked pixels inside
 *     the size;
 *   - at a few frames (first, last, middle, every key frame and its
 *     neighbours): the camera is finite, within +-PF_SCENE_MAX_COORD, with a
 *     fovy in (0, 180), eye != target, and pf_camera_look_at accepts it;
 *     every full light evaluates (the parser checked every frame) and every
 *     light naming a scene light evaluates on a point, spot or directional
 *     base light, or fails with a message; what evaluates is finite, its
 *     intensity x colour in [0, PF_SEQUENCE_MAX_EMISSION], directions unit,
 *     spot cones ordered within 90 degrees;
 *   - "animation": a name or an index, 0 <= start <= end <= the limit,
 *     frame times exactly start and end at the ends and non-decreasing;
 *   - pf_sequence_track_eval (a binary search) equals a linear walk over the
 *     keys, bit for bit;
 *   - "emitters": at most PF_SEQUENCE_MAX_EMITTERS, each accepted again by
 *     pf_scene_emitter_quad_check, and pf_sequence_apply_emitters adds them
 *     all to a one-triangle scene that pf_scene_validate then accepts, with
 *     finite unit face normals on every added triangle, the bounds holding
 *     every corner, and no punctual light left after "lights": [].
 * Seeds: tests/fuzz/seeds/sequence. Build (by hand, or tests/fuzz/CMakeLists.txt):
 *   clang -g -O1 -fsanitize=fuzzer,address,undefined -Isrc/platform tests/fuzz/fuzz_sequence.c \
 *     src/app/pf_sequence.c src/platform/pf_imageio.c src/scene/pf_scene.c \
 *     src/base/pf_result.c src/base/pf_budget.c src/scene/pf_texture.c $(pkg-config --cflags --libs libcjson stb) -lm -o fuzz_sequence */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "pf_sequence.h"

#define CHECK(cond)                                                                                                \
    do {                                                                                                           \
        if (!(cond)) {                                                                                             \
            fprintf(stderr, "fuzz_sequence: invariant failed: %s (line %d)\n", #cond, __LINE__);                  \
            abort();                                                                                               \
        }                                                                                                          \
    } while (0)

#define FILE_NAME "fuzz.seq.json"

/* The linear walk pf_sequence_track_eval replaced, as the reference. */
static void linear_eval(const pf_sequence_track *t, uint32_t frame, float *out)
{
    if (t->count == 0) return;
    const uint32_t d = t->dim;
    if (frame <= t->frame[0]) {
        memcpy(out, t->value, sizeof(float) * d);
        return;
    }
    if (frame >= t->frame[t->count - 1]) {
        memcpy(out, t->value + (size_t)(t->count - 1) * d, sizeof(float) * d);
        return;
    }
    uint32_t k = 0;
    while (t->frame[k + 1] <= frame) k++;
    const float *a = t->value + (size_t)k * d, *b = a + d;
    double s = (double)(frame - t->frame[k]) / (double)(t->frame[k + 1] - t->frame[k]);
    for (uint32_t i = 0; i < d; i++) out[i] = (float)((1.0 - s) * (double)a[i] + s * (double)b[i]);
}

static void check_track(const pf_sequence_track *t, uint32_t frame)
{
    if (t->count == 0) return;
    CHECK(t->dim >= 1 && t->dim <= 7);
    for (uint32_t k = 1; k < t->count; k++) CHECK(t->frame[k - 1] < t->frame[k]);
    float a[8], b[8];
    memset(a, 0, sizeof a);
    memset(b, 0, sizeof b);
    pf_sequence_track_eval(t, frame, a);
    linear_eval(t, frame, b);
    CHECK(memcmp(a, b, sizeof a) == 0);
}

static void check_light(const pf_light *L)
{
    CHECK(pf_v3_is_finite(L->position) && pf_v3_is_finite(L->direction) && pf_v3_is_finite(L->color));
    CHECK(isfinite(L->intensity) && L->intensity >= 0.0f);
    const float c[3] = {L->color.x, L->color.y, L->color.z};
    for (int k = 0; k < 3; k++) {
        double e = (double)L->intensity * c[k];
        CHECK(c[k] >= 0.0f && e >= 0.0 && e <= PF_SEQUENCE_MAX_EMISSION);
    }
    if (L->type != PF_LIGHT_POINT) CHECK(fabsf(pf_v3_length(L->direction) - 1.0f) < 1e-3f);
    if (L->type == PF_LIGHT_SPOT)
        CHECK(L->inner_cone >= 0.0f && L->inner_cone < L->outer_cone && L->outer_cone <= pf_radians(90.0f) + 1e-6f);
}

static void check_frame(const pf_sequence *s, uint32_t f, const pf_light *bases, int nbases)
{
    if (f >= s->frames) return;
    pf_vec3 eye, target;
    float fovy;
    check_track(&s->camera, f);
    if (pf_sequence_camera_at(s, f, &eye, &target, &fovy)) {
        CHECK(pf_v3_is_finite(eye) && pf_v3_is_finite(target) && isfinite(fovy));
        CHECK(fabsf(eye.x) <= PF_SCENE_MAX_COORD && fabsf(eye.y) <= PF_SCENE_MAX_COORD &&
              fabsf(eye.z) <= PF_SCENE_MAX_COORD);
        CHECK(fovy > 0.0f && fovy < 180.0f);
        CHECK(!(eye.x == target.x && eye.y == target.y && eye.z == target.z));
        pf_camera cam;
        pf_error e;
        CHECK(pf_camera_look_at(&cam, eye, target, pf_radians(fovy), &e) == PF_OK);
        CHECK(pf_v3_is_finite(cam.forward) && pf_v3_is_finite(cam.up) && pf_v3_is_finite(cam.right));
    }
    for (uint32_t i = 0; i < s->light_count; i++) {
        const pf_sequence_light *sl = &s->lights[i];
        for (int k = 0; k < PF_SEQUENCE_FIELD_COUNT; k++) check_track(&sl->field[k], f);
        pf_light L;
        pf_error e;
        memset(&e, 0, sizeof e);
        if (sl->scene_light < 0) {
            CHECK(pf_sequence_light_at(s, i, f, NULL, &L, &e) == PF_OK);
            check_light(&L);
            continue;
        }
        for (int b = 0; b < nbases; b++) {
            pf_result r = pf_sequence_light_at(s, i, f, &bases[b], &L, &e);
            if (r == PF_OK) check_light(&L);
            else CHECK(e.message[0] != 0 && (unsigned)r < PF_ERR_COUNT);
        }
    }
}

/* The emitters go into a scene exactly as softgi sequence adds them. */
static void check_emitters(const pf_sequence *s)
{
    pf_error e;
    for (uint32_t i = 0; i < s->emitter_count; i++) {
        pf_vec3 n;
        CHECK(pf_scene_emitter_quad_check(s->emitters[i].quad, s->emitters[i].emission, &n, &e) == PF_OK);
        CHECK(pf_v3_is_finite(n) && fabsf(pf_v3_length(n) - 1.0f) < 1e-4f);
    }
    /* one triangle, one material, one point light */
    pf_scene sc;
    memset(&sc, 0, sizeof sc);
    sc.vertex_count = 3;
    sc.tri_count = 1;
    sc.material_count = 1;
    sc.light_count = 1;
    sc.positions = calloc(4, sizeof *sc.positions);
    sc.normals = calloc(3, sizeof *sc.normals);
    sc.uvs = calloc(3, sizeof *sc.uvs);
    sc.indices = calloc(3, sizeof *sc.indices);
    sc.tri_material = calloc(1, sizeof *sc.tri_material);
    sc.materials = calloc(1, sizeof *sc.materials);
    sc.lights = calloc(1, sizeof *sc.lights);
    CHECK(sc.positions && sc.normals && sc.uvs && sc.indices && sc.tri_material && sc.materials && sc.lights);
    sc.positions[1] = pf_v3(1.0f, 0.0f, 0.0f);
    sc.positions[2] = pf_v3(0.0f, 0.0f, 1.0f);
    for (int k = 0; k < 3; k++) {
        sc.indices[k] = (uint32_t)k;
        sc.normals[k] = pf_v3(0.0f, 1.0f, 0.0f);
    }
    sc.materials[0].base_color_texture = -1;
    sc.lights[0].type = PF_LIGHT_POINT;
    sc.lights[0].color = pf_v3(1.0f, 1.0f, 1.0f);
    CHECK(pf_sequence_apply_emitters(s, &sc, &e) == PF_OK);
    CHECK(sc.vertex_count == 3 + 4 * s->emitter_count && sc.tri_count == 1 + 2 * s->emitter_count);
    CHECK(sc.material_count == 1 + s->emitter_count);
    CHECK(sc.light_count == (s->lights_replace && s->light_count == 0 ? 0u : 1u));
    CHECK(pf_scene_validate(&sc, &e) == PF_OK);
    for (uint32_t t = 1; t < sc.tri_count; t++) {
        pf_vec3 n = pf_scene_face_normal(&sc, t);
        CHECK(pf_v3_is_finite(n) && fabsf(pf_v3_length(n) - 1.0f) < 1e-3f);
        const pf_material *m = &sc.materials[sc.tri_material[t]];
        CHECK(m->emission[0] + m->emission[1] + m->emission[2] > 0.0f);
    }
    for (uint32_t i = 0; i < s->emitter_count; i++)
        for (int k = 0; k < 4; k++) {
            pf_vec3 c = s->emitters[i].quad[k];
            CHECK(c.x >= sc.bounds_min.x && c.y >= sc.bounds_min.y && c.z >= sc.bounds_min.z);
            CHECK(c.x <= sc.bounds_max.x && c.y <= sc.bounds_max.y && c.z <= sc.bounds_max.z);
        }
    pf_scene_free(&sc);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    pf_sequence s;
    pf_error err;
    memset(&err, 0, sizeof err);
    pf_result r = pf_sequence_parse(&s, (const char *)data, size, FILE_NAME, &err);
    if (r != PF_OK) {
        CHECK((unsigned)r < PF_ERR_COUNT && err.code == r);
        CHECK(!strncmp(err.message, FILE_NAME ": ", strlen(FILE_NAME ": ")));
        CHECK(memchr(err.message, 0, sizeof err.message) != NULL && !strchr(err.message, '\n'));
        CHECK(s.frames == 0 && s.lights == NULL && s.light_count == 0 && s.camera.count == 0);
        pf_sequence_free(&s);
        return 0;
    }
    CHECK(s.frames >= 1 && s.frames <= PF_SEQUENCE_MAX_FRAMES);
    CHECK(s.width <= PF_SEQUENCE_MAX_SIZE && s.height <= PF_SEQUENCE_MAX_SIZE);
    CHECK(s.name[0] && !strchr(s.name, '/') && strcmp(s.name, ".") && strcmp(s.name, ".."));
    if (s.output[0]) {
        CHECK(!strncmp(s.output, "out/", 4) && s.output[4] && s.output[4] != '/');
        for (const char *p = s.output; *p;) {
            size_t n = strcspn(p, "/");
            CHECK(!(n == 2 && p[0] == '.' && p[1] == '.'));
            p += n;
            while (*p == '/') p++;
        }
    }
    CHECK(s.light_count <= PF_SEQUENCE_MAX_LIGHTS && s.track_count <= PF_SEQUENCE_MAX_TRACK);
    CHECK(s.emitter_count <= PF_SEQUENCE_MAX_EMITTERS);
    if (s.lights_replace && s.light_count == 0) CHECK(s.emitter_count > 0);
    if (s.emitter_count) check_emitters(&s);
    for (uint32_t i = 0; i < s.track_count && s.width; i++) CHECK(s.track[i][0] < s.width && s.track[i][1] < s.height);
    /* "animation": a name xor an index (or neither), times within the limit,
     * frame times from start (frame 0) to end (the last frame), monotonic */
    if (s.anim_set) {
        CHECK(!(s.anim_name[0] && s.anim_index >= 0) && s.anim_index >= -1 && s.anim_index <= 65535);
        for (const char *p = s.anim_name; *p; p++) CHECK((unsigned char)*p >= 0x20 && *p != 0x7f);
        const double t0 = s.anim_time_set ? s.anim_start : 0.0, t1 = s.anim_time_set ? s.anim_end : 1.0;
        CHECK(t0 >= 0.0 && t0 <= t1 && t1 <= PF_SEQUENCE_MAX_TIME);
        CHECK(pf_sequence_time_at(&s, 0, t0, t1) == t0);
        CHECK(s.frames == 1 || pf_sequence_time_at(&s, s.frames - 1, t0, t1) == t1);
        double prev = t0;
        for (uint32_t f = 1; f < s.frames && f < 64; f++) {
            double t = pf_sequence_time_at(&s, f, t0, t1);
            CHECK(t >= prev - 1e-12 * (t1 + 1.0) && t >= t0 && t <= t1); /* monotonic up to rounding */
            prev = t;
        }
    } else {
        CHECK(!s.anim_name[0] && !s.anim_time_set);
    }

    /* scene lights of each type to animate */
    pf_light bases[3];
    memset(bases, 0, sizeof bases);
    bases[0].type = PF_LIGHT_POINT;
    bases[0].position = pf_v3(0.0f, 1.0f, 0.0f);
    bases[1].type = PF_LIGHT_SPOT;
    bases[1].position = pf_v3(0.0f, 1.0f, 0.0f);
    bases[1].direction = pf_v3(0.0f, -1.0f, 0.0f);
    bases[1].inner_cone = pf_radians(10.0f);
    bases[1].outer_cone = pf_radians(20.0f);
    bases[2].type = PF_LIGHT_DIRECTIONAL;
    bases[2].direction = pf_v3(0.0f, -1.0f, 0.0f);
    for (int b = 0; b < 3; b++) {
        bases[b].color = pf_v3(1.0f, 1.0f, 1.0f);
        bases[b].intensity = 1.0f;
    }

    /* frames: ends, middle, and around every camera key */
    check_frame(&s, 0, bases, 3);
    check_frame(&s, s.frames - 1, bases, 3);
    check_frame(&s, s.frames / 2, bases, 3);
    for (uint32_t k = 0; k < s.camera.count && k < 16; k++) {
        uint32_t f = s.camera.frame[k];
        check_frame(&s, f, bases, 3);
        check_frame(&s, f + 1, bases, 3);
        if (f) check_frame(&s, f - 1, bases, 3);
    }
    pf_sequence_free(&s);
    return 0;
}
