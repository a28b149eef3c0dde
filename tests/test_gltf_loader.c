/* test_gltf_loader: pf_gltf_load / pf_gltf_load_memory against the authored
 * files of tools/make_test_gltf.py (tests/data/gltf) and the fuzzer's
 * regression inputs (tests/data/gltf/regress).
 *
 * Good files: exact world-space positions, normals, uvs, triangle counts,
 * materials, sampled texels, cameras and lights; the expected numbers are
 * derived in the comments of make_test_gltf.py next to each file. Triangles
 * are looked up by their corner positions (the loader may order them as it
 * likes) but must keep their winding: a match is a cyclic rotation of the
 * expected corners, never a reversal.
 *
 * Bad files: the exact pf_result and a message that names the file and the
 * offending object; *out must come back empty. */
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>

#include <dirent.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <unistd.h>

#include "pf_gltf.h"

#define GLTF_DIR SOFTGI_TEST_DATA "/gltf"
#define DATA(name) GLTF_DIR "/" name

/* Positions that go through node transforms built from sqrt(1/2) quaternions
 * are within a few ulps; untransformed ones must be exact but share the bound. */
#define POS_EPS 1e-5f
#define DIR_EPS 1e-5f

/* ------------------------------------------------------------------ helpers */

static int near3(pf_vec3 a, pf_vec3 b, float eps)
{
    return fabsf(a.x - b.x) <= eps && fabsf(a.y - b.y) <= eps && fabsf(a.z - b.z) <= eps;
}

#define assert_vec3_near(v, X, Y, Z, eps)                                                                          \
    do {                                                                                                           \
        pf_vec3 v_ = (v);                                                                                          \
        if (!near3(v_, pf_v3((X), (Y), (Z)), (eps)))                                                               \
            fail_msg("%s = (%.9g, %.9g, %.9g), expected (%.9g, %.9g, %.9g)", #v, (double)v_.x, (double)v_.y,       \
                     (double)v_.z, (double)(X), (double)(Y), (double)(Z));                                         \
    } while (0)

#define assert_rgba_near(c, R, G, B, A, eps)                                                                       \
    do {                                                                                                           \
        const float *c_ = (c);                                                                                     \
        if (fabsf(c_[0] - (R)) > (eps) || fabsf(c_[1] - (G)) > (eps) || fabsf(c_[2] - (B)) > (eps) ||            \
            fabsf(c_[3] - (A)) > (eps))                                                                            \
            fail_msg("%s = (%.7g, %.7g, %.7g, %.7g), expected (%.7g, %.7g, %.7g, %.7g)", #c, (double)c_[0],        \
                     (double)c_[1], (double)c_[2], (double)c_[3], (double)(R), (double)(G), (double)(B),           \
                     (double)(A));                                                                                 \
    } while (0)

static int contains_ci(const char *hay, const char *needle)
{
    size_t n = strlen(needle);
    for (const char *p = hay; *p; p++)
        if (strncasecmp(p, needle, n) == 0) return 1;
    return n == 0;
}

static pf_vec3 corner(const pf_scene *s, uint32_t t, int k) { return s->positions[s->indices[3 * t + k]]; }

/* Index of the triangle whose corners are (a, b, c) up to a cyclic rotation
 * (same winding), or -1. Sets *reversed when only the mirrored order exists. */
static int find_tri(const pf_scene *s, pf_vec3 a, pf_vec3 b, pf_vec3 c, int *reversed)
{
    pf_vec3 want[3] = {a, b, c};
    if (reversed) *reversed = 0;
    for (uint32_t t = 0; t < s->tri_count; t++)
        for (int r = 0; r < 3; r++) {
            if (near3(corner(s, t, 0), want[r], POS_EPS) && near3(corner(s, t, 1), want[(r + 1) % 3], POS_EPS) &&
                near3(corner(s, t, 2), want[(r + 2) % 3], POS_EPS))
                return (int)t;
            if (reversed && near3(corner(s, t, 0), want[r], POS_EPS) &&
                near3(corner(s, t, 2), want[(r + 1) % 3], POS_EPS) &&
                near3(corner(s, t, 1), want[(r + 2) % 3], POS_EPS))
                *reversed = 1;
        }
    return -1;
}

static int require_tri_(const pf_scene *s, pf_vec3 a, pf_vec3 b, pf_vec3 c, const char *file, int line)
{
    int reversed = 0;
    int t = find_tri(s, a, b, c, &reversed);
    if (t < 0) {
        fprintf(stderr, "%s:%d: triangle (%g %g %g) (%g %g %g) (%g %g %g) %s; the scene has %u:\n", file, line,
                (double)a.x, (double)a.y, (double)a.z, (double)b.x, (double)b.y, (double)b.z, (double)c.x,
                (double)c.y, (double)c.z, reversed ? "found with REVERSED winding" : "not found", s->tri_count);
        for (uint32_t i = 0; i < s->tri_count && i < 16; i++) {
            pf_vec3 p0 = corner(s, i, 0), p1 = corner(s, i, 1), p2 = corner(s, i, 2);
            fprintf(stderr, "  %u: (%g %g %g) (%g %g %g) (%g %g %g)\n", i, (double)p0.x, (double)p0.y, (double)p0.z,
                    (double)p1.x, (double)p1.y, (double)p1.z, (double)p2.x, (double)p2.y, (double)p2.z);
        }
        _fail(file, line);
    }
    return t;
}
#define require_tri(s, a, b, c) require_tri_((s), (a), (b), (c), __FILE__, __LINE__)

/* Corner k of triangle t whose position is p, or fails. */
static uint32_t vertex_at_(const pf_scene *s, uint32_t t, pf_vec3 p, const char *file, int line)
{
    for (int k = 0; k < 3; k++)
        if (near3(corner(s, t, k), p, POS_EPS)) return s->indices[3 * t + k];
    fprintf(stderr, "%s:%d: triangle %u has no corner at (%g %g %g)\n", file, line, t, (double)p.x, (double)p.y,
            (double)p.z);
    _fail(file, line);
    return 0;
}
#define vertex_at(s, t, p) vertex_at_((s), (t), (p), __FILE__, __LINE__)

/* First triangle whose three corners all lie at height z, or fails. */
static uint32_t tri_at_z_(const pf_scene *s, float z, const char *file, int line)
{
    for (uint32_t t = 0; t < s->tri_count; t++)
        if (corner(s, t, 0).z == z && corner(s, t, 1).z == z && corner(s, t, 2).z == z) return t;
    fprintf(stderr, "%s:%d: no triangle at z = %g\n", file, line, (double)z);
    _fail(file, line);
    return 0;
}
#define tri_at_z(s, z) tri_at_z_((s), (z), __FILE__, __LINE__)

static const pf_material *tri_mat(const pf_scene *s, uint32_t t) { return &s->materials[s->tri_material[t]]; }

static const pf_light *light_named(const pf_scene *s, const char *name)
{
    for (uint32_t i = 0; i < s->light_count; i++)
        if (strcmp(s->lights[i].name, name) == 0) return &s->lights[i];
    fail_msg("no light named '%s' among %u", name, s->light_count);
    return NULL;
}

/* What every loaded scene must satisfy whatever the file: references in
 * range, finite data, unit normals, the padding vertex readable, every
 * triangle non-degenerate and CCW about its vertex normals (all authored
 * files have normals that agree with their winding), bounds that hold every
 * vertex, and pf_scene_validate agreeing. */
static void check_invariants(pf_scene *s)
{
    assert_non_null(s->positions);
    assert_non_null(s->normals);
    assert_non_null(s->uvs);
    assert_non_null(s->indices);
    assert_non_null(s->tri_material);
    assert_true(s->material_count >= 1);
    assert_non_null(s->materials);
    volatile float pad = s->positions[s->vertex_count].x; /* ASan: the padding element exists */
    (void)pad;
    for (uint32_t v = 0; v < s->vertex_count; v++) {
        assert_true(pf_v3_is_finite(s->positions[v]));
        assert_float_equal(pf_v3_length(s->normals[v]), 1.0f, 1e-5f);
        assert_true(isfinite(s->uvs[v].x) && isfinite(s->uvs[v].y));
        pf_vec3 p = s->positions[v];
        assert_true(p.x >= s->bounds_min.x && p.y >= s->bounds_min.y && p.z >= s->bounds_min.z);
        assert_true(p.x <= s->bounds_max.x && p.y <= s->bounds_max.y && p.z <= s->bounds_max.z);
    }
    for (uint32_t t = 0; t < s->tri_count; t++) {
        for (int k = 0; k < 3; k++) assert_true(s->indices[3 * t + k] < s->vertex_count);
        assert_true(s->tri_material[t] < s->material_count);
        pf_vec3 a = corner(s, t, 0), b = corner(s, t, 1), c = corner(s, t, 2);
        pf_vec3 g = pf_v3_cross(pf_v3_sub(b, a), pf_v3_sub(c, a));
        assert_true(pf_v3_length(g) > 0.0f);
        for (int k = 0; k < 3; k++)
            if (!(pf_v3_dot(g, s->normals[s->indices[3 * t + k]]) > 0.0f))
                fail_msg("triangle %u is clockwise about the normal of its corner %d", t, k);
    }
    for (uint32_t m = 0; m < s->material_count; m++) {
        int32_t tex = s->materials[m].base_color_texture;
        assert_true(tex >= -1 && tex < (int32_t)s->texture_count);
    }
    for (uint32_t t = 0; t < s->texture_count; t++) assert_true(s->textures[t].image < s->image_count);
    pf_vec3 lo = s->bounds_min, hi = s->bounds_max;
    pf_error err = {0};
    assert_int_equal(pf_scene_validate(s, &err), PF_OK);
    assert_vec3_near(s->bounds_min, lo.x, lo.y, lo.z, 0.0f);
    assert_vec3_near(s->bounds_max, hi.x, hi.y, hi.z, 0.0f);
}

static void load_ok_opts(pf_scene *s, const char *path, const pf_gltf_options *opts)
{
    pf_error err = {0};
    memset(s, 0xAB, sizeof *s); /* "zeroed first": garbage in *out must not matter */
    pf_result r = pf_gltf_load(s, path, opts, &err);
    if (r != PF_OK) fail_msg("%s: %s (%s)", path, err.message, pf_result_name(r));
    check_invariants(s);
}
static void load_ok(pf_scene *s, const char *path) { load_ok_opts(s, path, NULL); }

static void assert_scene_empty(const pf_scene *s)
{
    assert_int_equal(s->vertex_count, 0);
    assert_int_equal(s->tri_count, 0);
    assert_int_equal(s->material_count, 0);
    assert_int_equal(s->texture_count, 0);
    assert_int_equal(s->image_count, 0);
    assert_int_equal(s->camera_count, 0);
    assert_int_equal(s->light_count, 0);
    assert_null(s->positions);
    assert_null(s->normals);
    assert_null(s->uvs);
    assert_null(s->indices);
    assert_null(s->tri_material);
    assert_null(s->materials);
    assert_null(s->textures);
    assert_null(s->images);
    assert_null(s->cameras);
    assert_null(s->lights);
}

static void *read_file(const char *path, size_t *size)
{
    FILE *f = fopen(path, "rb");
    if (!f) fail_msg("cannot open %s (run tools/make_test_gltf.py)", path);
    fseek(f, 0, SEEK_END);
    long n = ftell(f);
    fseek(f, 0, SEEK_SET);
    unsigned char *buf = malloc((size_t)n + 1);
    assert_non_null(buf);
    assert_int_equal(fread(buf, 1, (size_t)n, f), (size_t)n);
    fclose(f);
    *size = (size_t)n;
    return buf;
}

/* ------------------------------------------------------------------ geometry */

static void test_triangle_file(const char *path)
{
    pf_scene s;
    load_ok(&s, path);
    assert_int_equal(s.tri_count, 1);
    assert_int_equal(s.vertex_count, 3);
    assert_int_equal(s.dropped_degenerate, 0);
    assert_int_equal(s.camera_count, 0);
    assert_int_equal(s.light_count, 0);
    int t = require_tri(&s, pf_v3(0, 0, 0), pf_v3(1, 0, 0), pf_v3(0, 1, 0));
    for (uint32_t v = 0; v < 3; v++) {
        assert_true(s.positions[v].x == 0.0f || s.positions[v].x == 1.0f); /* untransformed: exact */
        assert_vec3_near(s.normals[v], 0, 0, 1, 0.0f);
        assert_true(s.uvs[v].x == 0.0f && s.uvs[v].y == 0.0f); /* no TEXCOORD_0 */
    }
    const pf_material *m = tri_mat(&s, (uint32_t)t);
    assert_string_equal(m->name, "tri");
    assert_rgba_near(m->base_color, 0.5f, 0.25f, 1.0f, 1.0f, 0.0f);
    assert_int_equal(m->base_color_texture, -1);
    assert_vec3_near(pf_v3(m->emission[0], m->emission[1], m->emission[2]), 0, 0, 0, 0.0f);
    assert_int_equal(m->alpha_mode, PF_ALPHA_OPAQUE);
    assert_int_equal(m->double_sided, 1);
    assert_vec3_near(s.bounds_min, 0, 0, 0, 0.0f);
    assert_vec3_near(s.bounds_max, 1, 1, 0, 0.0f);
    float c[4];
    pf_material_sample(&s, s.tri_material[t], (pf_vec2){0.3f, 0.6f}, 0.0f, c);
    assert_rgba_near(c, 0.5f, 0.25f, 1.0f, 1.0f, 0.0f);
    pf_scene_free(&s);
    assert_scene_empty(&s); /* pf_scene_free leaves a reusable empty scene */
}

static void test_triangle(void **state)
{
    (void)state;
    test_triangle_file(DATA("triangle.gltf"));
}

static void test_triangle_glb(void **state)
{
    (void)state;
    test_triangle_file(DATA("triangle.glb"));
}

static void check_quad(const char *path, uint32_t vertex_count)
{
    pf_scene s;
    load_ok(&s, path);
    assert_int_equal(s.tri_count, 2);
    assert_int_equal(s.vertex_count, vertex_count);
    assert_int_equal(s.dropped_degenerate, 0);
    int t0 = require_tri(&s, pf_v3(0, 0, 0), pf_v3(1, 0, 0), pf_v3(1, 1, 0));
    int t1 = require_tri(&s, pf_v3(0, 0, 0), pf_v3(1, 1, 0), pf_v3(0, 1, 0));
    assert_true(t0 != t1);
    for (uint32_t v = 0; v < s.vertex_count; v++) assert_vec3_near(s.normals[v], 0, 0, 1, 0.0f);
    /* no material: the glTF default (white) */
    assert_rgba_near(tri_mat(&s, 0)->base_color, 1, 1, 1, 1, 0.0f);
    assert_vec3_near(s.bounds_min, 0, 0, 0, 0.0f);
    assert_vec3_near(s.bounds_max, 1, 1, 0, 0.0f);
    pf_scene_free(&s);
}

static void test_quad_u8(void **state)
{
    (void)state;
    check_quad(DATA("quad_u8.gltf"), 4);
}
static void test_quad_u16(void **state)
{
    (void)state;
    check_quad(DATA("quad_u16.gltf"), 4);
}
static void test_quad_u32(void **state)
{
    (void)state;
    check_quad(DATA("quad_u32.gltf"), 4);
}
static void test_quad_noindex(void **state)
{
    (void)state;
    check_quad(DATA("quad_noindex.gltf"), 6);
}

static void test_hierarchy_trs(void **state)
{
    (void)state;
    pf_scene s;
    load_ok(&s, DATA("hierarchy_trs.gltf"));
    assert_int_equal(s.tri_count, 2); /* one mesh instanced by two nodes */
    /* T(10,0,0) R_z(90) S(2) T(0,1,0) */
    int a = require_tri(&s, pf_v3(8, 0, 0), pf_v3(8, 2, 0), pf_v3(6, 0, 0));
    int b = require_tri(&s, pf_v3(0, 0, 5), pf_v3(1, 0, 5), pf_v3(0, 1, 5));
    for (int k = 0; k < 3; k++) {
        assert_vec3_near(s.normals[s.indices[3 * a + k]], 0, 0, 1, DIR_EPS);
        assert_vec3_near(s.normals[s.indices[3 * b + k]], 0, 0, 1, DIR_EPS);
    }
    assert_vec3_near(s.bounds_min, 0, 0, 0, POS_EPS);
    assert_vec3_near(s.bounds_max, 8, 2, 5, POS_EPS);
    pf_scene_free(&s);
}

static void test_hierarchy_matrix(void **state)
{
    (void)state;
    pf_scene s;
    load_ok(&s, DATA("hierarchy_matrix.gltf"));
    assert_int_equal(s.tri_count, 1);
    /* column-major T(0,0,-5) R_x(90) times T(1,2,3); a transposed read gives other numbers */
    int t = require_tri(&s, pf_v3(1, -3, -3), pf_v3(2, -3, -3), pf_v3(1, -3, -2));
    for (int k = 0; k < 3; k++) assert_vec3_near(s.normals[s.indices[3 * t + k]], 0, -1, 0, DIR_EPS);
    pf_scene_free(&s);
}

static void test_negative_scale(void **state)
{
    (void)state;
    pf_scene s;
    load_ok(&s, DATA("negative_scale.gltf"));
    assert_int_equal(s.tri_count, 2);
    /* S(-1,1,1): corners (0,0,0) (-1,0,0) (0,1,0) come back in the order that is
     * CCW about the (inverse-transpose) normal +Z. */
    int a = require_tri(&s, pf_v3(0, 0, 0), pf_v3(0, 1, 0), pf_v3(-1, 0, 0));
    for (int k = 0; k < 3; k++) assert_vec3_near(s.normals[s.indices[3 * a + k]], 0, 0, 1, DIR_EPS);
    /* S(1,1,-1) then T(0,0,-3), no NORMAL: flat normal -Z, CCW about it. */
    int b = require_tri(&s, pf_v3(0, 0, -3), pf_v3(0, 1, -3), pf_v3(1, 0, -3));
    for (int k = 0; k < 3; k++) assert_vec3_near(s.normals[s.indices[3 * b + k]], 0, 0, -1, DIR_EPS);
    pf_scene_free(&s);
}

static void test_flat_normals(void **state)
{
    (void)state;
    pf_scene s;
    load_ok(&s, DATA("flat_normals.gltf"));
    assert_int_equal(s.tri_count, 2);
    assert_int_equal(s.vertex_count, 6); /* unwelded: each triangle its own corners */
    int a = require_tri(&s, pf_v3(0, 0, 0), pf_v3(1, 0, 0), pf_v3(1, 1, 0));
    int b = require_tri(&s, pf_v3(0, 0, 0), pf_v3(1, 1, 0), pf_v3(0, 1, 1));
    const float r3 = 0.57735026918962576f;
    for (int k = 0; k < 3; k++) {
        assert_vec3_near(s.normals[s.indices[3 * a + k]], 0, 0, 1, DIR_EPS);
        assert_vec3_near(s.normals[s.indices[3 * b + k]], r3, -r3, r3, DIR_EPS);
    }
    for (int k = 0; k < 3; k++)
        for (int j = 0; j < 3; j++) assert_true(s.indices[3 * a + k] != s.indices[3 * b + j]);
    pf_scene_free(&s);
}

static void test_normals_nonuniform(void **state)
{
    (void)state;
    pf_scene s;
    load_ok(&s, DATA("normals_nonuniform.gltf"));
    assert_int_equal(s.tri_count, 1);
    int t = require_tri(&s, pf_v3(2, 0, 0), pf_v3(0, 1, 0), pf_v3(2, 0, 1));
    /* inverse transpose of S(2,1,1) on (1,1,0)/sqrt2: (1,2,0)/sqrt5, not (2,1,0)/sqrt5 */
    for (int k = 0; k < 3; k++)
        assert_vec3_near(s.normals[s.indices[3 * t + k]], 0.44721359549995794f, 0.89442719099991588f, 0, DIR_EPS);
    pf_scene_free(&s);
}

static void test_texcoords(void **state)
{
    (void)state;
    pf_scene s;
    load_ok(&s, DATA("texcoords.gltf"));
    assert_int_equal(s.tri_count, 3);
    static const float expect[3][3][2] = {
        {{0.25f, 0.5f}, {0.75f, 0.5f}, {0.5f, 1.0f}},                   /* float */
        {{0.0f, 1.0f}, {1.0f, 0.2f}, {0.2f, 0.0f}},                     /* normalized u8: 51/255 */
        {{0.0f, 1.0f}, {1.0f, 0.50000763f}, {0.50000763f, 0.0f}},       /* normalized u16: 32768/65535 */
    };
    for (int p = 0; p < 3; p++) {
        float z = (float)p;
        uint32_t t = tri_at_z(&s, z);
        pf_vec3 pos[3] = {pf_v3(0, 0, z), pf_v3(1, 0, z), pf_v3(0, 1, z)};
        for (int k = 0; k < 3; k++) {
            pf_vec2 uv = s.uvs[vertex_at(&s, t, pos[k])];
            if (fabsf(uv.x - expect[p][k][0]) > 1e-6f || fabsf(uv.y - expect[p][k][1]) > 1e-6f)
                fail_msg("primitive %d corner %d: uv (%.9g, %.9g), expected (%.9g, %.9g)", p, k, (double)uv.x,
                         (double)uv.y, (double)expect[p][k][0], (double)expect[p][k][1]);
        }
    }
    pf_scene_free(&s);
}

static void test_strip_fan(void **state)
{
    (void)state;
    pf_scene s;
    load_ok(&s, DATA("strip_fan.gltf"));
    assert_int_equal(s.tri_count, 5);
    /* strip (glTF 3.7.2.1): {v_i, v_{i+1+i%2}, v_{i+2-i%2}} */
    require_tri(&s, pf_v3(0, 0, 0), pf_v3(1, 0, 0), pf_v3(0, 1, 0));
    require_tri(&s, pf_v3(1, 0, 0), pf_v3(1, 1, 0), pf_v3(0, 1, 0));
    require_tri(&s, pf_v3(0, 1, 0), pf_v3(1, 1, 0), pf_v3(0, 2, 0));
    /* fan: {v_{i+1}, v_{i+2}, v_0} */
    int f0 = require_tri(&s, pf_v3(6, 0, 0), pf_v3(6, 1, 0), pf_v3(5, 0, 0));
    int f1 = require_tri(&s, pf_v3(6, 1, 0), pf_v3(5, 1, 0), pf_v3(5, 0, 0));
    for (int k = 0; k < 3; k++) {
        assert_vec3_near(s.normals[s.indices[3 * f0 + k]], 0, 0, 1, 0.0f);
        assert_vec3_near(s.normals[s.indices[3 * f1 + k]], 0, 0, 1, 0.0f);
    }
    /* the POINTS primitive is skipped with a warning, and adds no bounds */
    assert_true(s.warnings[0] != '\0');
    assert_vec3_near(s.bounds_max, 6, 2, 0, 0.0f);
    pf_scene_free(&s);
}

static void test_sparse(void **state)
{
    (void)state;
    pf_scene s;
    load_ok(&s, DATA("sparse.gltf"));
    assert_int_equal(s.tri_count, 2);
    require_tri(&s, pf_v3(0, 0, 0), pf_v3(1, 0, 0), pf_v3(0, 3, 0)); /* vertex 2 replaced */
    require_tri(&s, pf_v3(0, 0, 0), pf_v3(1, 0, 5), pf_v3(0, 1, 5)); /* no bufferView: zeros + sparse */
    pf_scene_free(&s);
}

static void test_interleaved(void **state)
{
    (void)state;
    pf_scene s;
    load_ok(&s, DATA("interleaved.gltf"));
    assert_int_equal(s.tri_count, 2);
    assert_int_equal(s.vertex_count, 4);
    require_tri(&s, pf_v3(0, 0, 0), pf_v3(1, 0, 0), pf_v3(1, 1, 0));
    require_tri(&s, pf_v3(0, 0, 0), pf_v3(1, 1, 0), pf_v3(0, 1, 0));
    for (uint32_t v = 0; v < s.vertex_count; v++) {
        pf_vec3 p = s.positions[v];
        assert_vec3_near(s.normals[v], 0, 0, 1, 0.0f);
        assert_true(s.uvs[v].x == p.x && s.uvs[v].y == 1.0f - p.y); /* byteOffset 24 within stride 32 */
    }
    pf_scene_free(&s);
}

static void test_normals_unnormalized(void **state)
{
    (void)state;
    pf_scene s;
    load_ok(&s, DATA("normals_unnormalized.gltf"));
    assert_int_equal(s.tri_count, 1);
    for (uint32_t v = 0; v < s.vertex_count; v++) assert_vec3_near(s.normals[v], 0, 0, 1, DIR_EPS);
    pf_scene_free(&s);
}

static void test_degenerate(void **state)
{
    (void)state;
    pf_scene s;
    load_ok(&s, DATA("degenerate.gltf"));
    assert_int_equal(s.tri_count, 2);
    assert_int_equal(s.dropped_degenerate, 3); /* repeated index, collinear, coincident */
    require_tri(&s, pf_v3(0, 0, 0), pf_v3(1, 0, 0), pf_v3(0, 1, 0));
    require_tri(&s, pf_v3(1, 0, 0), pf_v3(1, 1, 0), pf_v3(0, 1, 0));
    pf_scene_free(&s);
}

static void test_scene_select(void **state)
{
    (void)state;
    pf_scene s;
    load_ok(&s, DATA("scene_select.gltf"));
    assert_int_equal(s.tri_count, 1); /* only the default scene (1) */
    require_tri(&s, pf_v3(0, 0, 7), pf_v3(1, 0, 7), pf_v3(0, 1, 7));
    pf_scene_free(&s);
}

/* ------------------------------------------------------------------ materials */

static void test_alpha_mask(void **state)
{
    (void)state;
    pf_scene s;
    load_ok(&s, DATA("alpha_mask.gltf"));
    const pf_material *m = tri_mat(&s, tri_at_z(&s, 0.0f));
    assert_string_equal(m->name, "mask_025");
    assert_int_equal(m->alpha_mode, PF_ALPHA_MASK);
    assert_float_equal(m->alpha_cutoff, 0.25f, 0.0f);
    assert_rgba_near(m->base_color, 1, 1, 1, 0.75f, 0.0f);
    assert_int_equal(m->double_sided, 0);
    m = tri_mat(&s, tri_at_z(&s, 1.0f));
    assert_string_equal(m->name, "mask_default");
    assert_int_equal(m->alpha_mode, PF_ALPHA_MASK);
    assert_float_equal(m->alpha_cutoff, 0.5f, 0.0f); /* glTF default cutoff */
    m = tri_mat(&s, tri_at_z(&s, 2.0f));
    assert_string_equal(m->name, "blend");
    assert_int_equal(m->alpha_mode, PF_ALPHA_BLEND);
    m = tri_mat(&s, tri_at_z(&s, 3.0f));
    assert_string_equal(m->name, "opaque_double");
    assert_int_equal(m->alpha_mode, PF_ALPHA_OPAQUE);
    assert_int_equal(m->double_sided, 1);
    pf_scene_free(&s);
}

static void test_emissive(void **state)
{
    (void)state;
    pf_scene s;
    load_ok(&s, DATA("emissive.gltf"));
    const pf_material *m = tri_mat(&s, tri_at_z(&s, 0.0f));
    assert_string_equal(m->name, "strong"); /* (1, 0.5, 0.25) x emissiveStrength 4 */
    assert_vec3_near(pf_v3(m->emission[0], m->emission[1], m->emission[2]), 4, 2, 1, 0.0f);
    m = tri_mat(&s, tri_at_z(&s, 1.0f));
    assert_string_equal(m->name, "plain");
    assert_vec3_near(pf_v3(m->emission[0], m->emission[1], m->emission[2]), 0.5f, 0.25f, 0.125f, 0.0f);
    m = tri_mat(&s, tri_at_z(&s, 2.0f));
    assert_string_equal(m->name, "dark");
    assert_vec3_near(pf_v3(m->emission[0], m->emission[1], m->emission[2]), 0, 0, 0, 0.0f);
    assert_rgba_near(m->base_color, 1, 1, 1, 1, 0.0f);
    pf_scene_free(&s);
}

static void test_default_material(void **state)
{
    (void)state;
    pf_scene s;
    load_ok(&s, DATA("default_material.gltf"));
    assert_int_equal(s.tri_count, 2);
    assert_true(s.material_count >= 2);
    uint32_t red = tri_at_z(&s, 0.0f), def = tri_at_z(&s, 1.0f);
    assert_true(s.tri_material[red] != s.tri_material[def]);
    const pf_material *m = tri_mat(&s, red);
    assert_string_equal(m->name, "red");
    assert_rgba_near(m->base_color, 1, 0, 0, 1, 0.0f);
    m = tri_mat(&s, def); /* glTF 2.0 Sec. 3.9.6: the default material */
    assert_rgba_near(m->base_color, 1, 1, 1, 1, 0.0f);
    assert_int_equal(m->base_color_texture, -1);
    assert_vec3_near(pf_v3(m->emission[0], m->emission[1], m->emission[2]), 0, 0, 0, 0.0f);
    assert_int_equal(m->alpha_mode, PF_ALPHA_OPAQUE);
    assert_float_equal(m->alpha_cutoff, 0.5f, 0.0f);
    assert_int_equal(m->double_sided, 0);
    float c[4];
    pf_material_sample(&s, s.tri_material[def], (pf_vec2){0.5f, 0.5f}, 0.0f, c);
    assert_rgba_near(c, 1, 1, 1, 1, 0.0f);
    pf_scene_free(&s);
}

/* ------------------------------------------------------------------ textures */

/* The 2x2 checker (make_test_gltf.py CHECKER_RGBA), decoded: sRGB 128 is
 * 0.2158605 linear; alpha is linear, 128/255. Mip level 1 is the linear mean
 * re-encoded to sRGB8: (150, 150, 150, 223) -> 0.3049873, 223/255. */
#define GREY 0.2158605f
#define HALF_A (128.0f / 255.0f)
#define MIP1 0.3049873f
#define MIP1_A (223.0f / 255.0f)
#define TEX_EPS 1e-5f

static const uint8_t checker[16] = {255, 0, 0, 255, 0, 255, 0, 128, 0, 0, 255, 255, 128, 128, 128, 255};

static void sample(const pf_scene *s, uint32_t mat, float u, float v, float lod, float out[4])
{
    pf_material_sample(s, mat, (pf_vec2){u, v}, lod, out);
}

static void check_checker_image(const pf_image *img)
{
    assert_int_equal(img->width, 2);
    assert_int_equal(img->height, 2);
    assert_int_equal(img->level_count, 2);
    assert_int_equal(img->level_w[0], 2);
    assert_int_equal(img->level_h[0], 2);
    assert_int_equal(img->level_w[1], 1);
    assert_int_equal(img->level_h[1], 1);
    assert_int_equal(img->level_offset[0], 0);
    assert_int_equal(img->level_offset[1], 4);
    assert_memory_equal(img->texels, checker, 16);
    static const uint8_t mip1[4] = {150, 150, 150, 223};
    assert_memory_equal(img->texels + 16, mip1, 4);
}

static uint32_t mat_named(const pf_scene *s, const char *name, float z)
{
    uint32_t t = tri_at_z(s, z);
    assert_string_equal(s->materials[s->tri_material[t]].name, name);
    return s->tri_material[t];
}

static void test_texture_samplers(void **state)
{
    (void)state;
    pf_scene s;
    float c[4];
    load_ok(&s, DATA("texture_datauri.gltf"));
    assert_int_equal(s.tri_count, 8);
    assert_int_equal(s.image_count, 1); /* one image shared by eight textures */
    check_checker_image(&s.images[0]);

    /* uvs read from the file */
    uint32_t t0 = tri_at_z(&s, 0.0f);
    pf_vec2 uv = s.uvs[vertex_at(&s, t0, pf_v3(1, 0, 0))];
    assert_true(uv.x == 1.0f && uv.y == 0.0f);

    uint32_t m = mat_named(&s, "repeat_nearest", 0.0f);
    const pf_texture *tx = &s.textures[s.materials[m].base_color_texture];
    assert_int_equal(tx->wrap_s, PF_WRAP_REPEAT);
    assert_int_equal(tx->wrap_t, PF_WRAP_REPEAT);
    assert_int_equal(tx->mag_linear, 0);
    assert_int_equal(tx->min_linear, 0);
    assert_int_equal(tx->min_mipmap, 0);
    assert_rgba_near(s.materials[m].base_color, 1, 0.5f, 1, 1, 0.0f);
    /* factor (1, 0.5, 1, 1) times the texel; row 0 of the image is v in [0, 0.5) */
    sample(&s, m, 0.25f, 0.25f, 0.0f, c);
    assert_rgba_near(c, 1, 0, 0, 1, TEX_EPS);
    sample(&s, m, 0.75f, 0.25f, 0.0f, c);
    assert_rgba_near(c, 0, 0.5f, 0, HALF_A, TEX_EPS);
    sample(&s, m, 0.25f, 0.75f, 0.0f, c);
    assert_rgba_near(c, 0, 0, 1, 1, TEX_EPS);
    sample(&s, m, 0.75f, 0.75f, 0.0f, c);
    assert_rgba_near(c, GREY, 0.5f * GREY, GREY, 1, TEX_EPS);
    sample(&s, m, -0.25f, 0.25f, 0.0f, c); /* REPEAT: 0.75 */
    assert_rgba_near(c, 0, 0.5f, 0, HALF_A, TEX_EPS);
    sample(&s, m, 1.75f, 0.25f, 0.0f, c);
    assert_rgba_near(c, 0, 0.5f, 0, HALF_A, TEX_EPS);
    sample(&s, m, 0.25f, 0.25f, 3.0f, c); /* minFilter NEAREST: no mips even when minified */
    assert_rgba_near(c, 1, 0, 0, 1, TEX_EPS);

    m = mat_named(&s, "clamp_nearest", 1.0f);
    tx = &s.textures[s.materials[m].base_color_texture];
    assert_int_equal(tx->wrap_s, PF_WRAP_CLAMP);
    assert_int_equal(tx->wrap_t, PF_WRAP_CLAMP);
    sample(&s, m, -0.25f, 0.25f, 0.0f, c);
    assert_rgba_near(c, 1, 0, 0, 1, TEX_EPS);
    sample(&s, m, 1.75f, 0.25f, 0.0f, c);
    assert_rgba_near(c, 0, 1, 0, HALF_A, TEX_EPS);
    sample(&s, m, 0.25f, 1.75f, 0.0f, c);
    assert_rgba_near(c, 0, 0, 1, 1, TEX_EPS);
    sample(&s, m, 0.25f, -3.0f, 0.0f, c);
    assert_rgba_near(c, 1, 0, 0, 1, TEX_EPS);

    m = mat_named(&s, "mirror_nearest", 2.0f);
    tx = &s.textures[s.materials[m].base_color_texture];
    assert_int_equal(tx->wrap_s, PF_WRAP_MIRROR);
    assert_int_equal(tx->wrap_t, PF_WRAP_MIRROR);
    sample(&s, m, -0.25f, 0.25f, 0.0f, c); /* mirrors to 0.25 */
    assert_rgba_near(c, 1, 0, 0, 1, TEX_EPS);
    sample(&s, m, 1.75f, 0.25f, 0.0f, c); /* mirrors to 0.25 */
    assert_rgba_near(c, 1, 0, 0, 1, TEX_EPS);
    sample(&s, m, 1.25f, 0.25f, 0.0f, c); /* mirrors to 0.75 */
    assert_rgba_near(c, 0, 1, 0, HALF_A, TEX_EPS);
    sample(&s, m, 0.25f, 1.25f, 0.0f, c);
    assert_rgba_near(c, 0, 0, 1, 1, TEX_EPS);

    m = mat_named(&s, "linear_mips", 3.0f);
    tx = &s.textures[s.materials[m].base_color_texture];
    assert_int_equal(tx->wrap_s, PF_WRAP_REPEAT);
    assert_int_equal(tx->mag_linear, 1);
    assert_int_equal(tx->min_linear, 1);
    assert_int_equal(tx->min_mipmap, 1);
    assert_int_equal(tx->mip_linear, 1);
    /* bilinear after sRGB decode: half red, half green on row 0 */
    sample(&s, m, 0.5f, 0.25f, 0.0f, c);
    assert_rgba_near(c, 0.5f, 0.5f, 0, 0.5f * (1.0f + HALF_A), TEX_EPS);
    sample(&s, m, 0.5f, 0.5f, 0.0f, c);
    assert_rgba_near(c, 0.25f * (1 + GREY), 0.25f * (1 + GREY), 0.25f * (1 + GREY), 0.25f * (3 + HALF_A), TEX_EPS);
    sample(&s, m, 0.1f, 0.9f, 1.0f, c); /* level 1 */
    assert_rgba_near(c, MIP1, MIP1, MIP1, MIP1_A, TEX_EPS);
    sample(&s, m, 0.1f, 0.9f, 9.0f, c); /* past the last level: clamped to it */
    assert_rgba_near(c, MIP1, MIP1, MIP1, MIP1_A, TEX_EPS);

    m = mat_named(&s, "default_sampler", 4.0f); /* glTF: no sampler = REPEAT, auto filtering */
    tx = &s.textures[s.materials[m].base_color_texture];
    assert_int_equal(tx->wrap_s, PF_WRAP_REPEAT);
    assert_int_equal(tx->wrap_t, PF_WRAP_REPEAT);
    assert_int_equal(tx->mag_linear, 1);
    assert_int_equal(tx->min_linear, 1);
    assert_int_equal(tx->min_mipmap, 1);
    assert_int_equal(tx->mip_linear, 1);

    m = mat_named(&s, "mixed", 5.0f);
    tx = &s.textures[s.materials[m].base_color_texture];
    assert_int_equal(tx->wrap_s, PF_WRAP_CLAMP);
    assert_int_equal(tx->wrap_t, PF_WRAP_MIRROR);
    assert_int_equal(tx->mag_linear, 0);
    assert_int_equal(tx->min_linear, 0);
    assert_int_equal(tx->min_mipmap, 1);
    assert_int_equal(tx->mip_linear, 0);
    sample(&s, m, -0.25f, -0.25f, 0.0f, c);
    assert_rgba_near(c, 1, 0, 0, 1, TEX_EPS);
    sample(&s, m, 1.75f, 1.25f, 0.0f, c);
    assert_rgba_near(c, GREY, GREY, GREY, 1, TEX_EPS);
    sample(&s, m, 0.25f, 0.25f, 1.0f, c); /* NEAREST_MIPMAP_NEAREST at lod 1: level 1 */
    assert_rgba_near(c, MIP1, MIP1, MIP1, MIP1_A, TEX_EPS);

    m = mat_named(&s, "lin_mip_nearest", 6.0f);
    tx = &s.textures[s.materials[m].base_color_texture];
    assert_int_equal(tx->mag_linear, 1);
    assert_int_equal(tx->min_linear, 1);
    assert_int_equal(tx->min_mipmap, 1);
    assert_int_equal(tx->mip_linear, 0);

    m = mat_named(&s, "near_mip_linear", 7.0f);
    tx = &s.textures[s.materials[m].base_color_texture];
    assert_int_equal(tx->min_linear, 0);
    assert_int_equal(tx->min_mipmap, 1);
    assert_int_equal(tx->mip_linear, 1);

    for (uint32_t t = 0; t < s.texture_count; t++) assert_int_equal(s.textures[t].image, 0);
    pf_scene_free(&s);
}

static void check_checker_material(const pf_scene *s)
{
    float c[4];
    assert_int_equal(s->image_count, 1);
    check_checker_image(&s->images[0]);
    uint32_t m = s->tri_material[0];
    assert_string_equal(s->materials[m].name, "checker");
    assert_rgba_near(s->materials[m].base_color, 1, 1, 1, 1, 0.0f);
    assert_true(s->materials[m].base_color_texture >= 0);
    sample(s, m, 0.75f, 0.25f, 0.0f, c);
    assert_rgba_near(c, 0, 1, 0, HALF_A, TEX_EPS);
    sample(s, m, 0.25f, 0.75f, 0.0f, c);
    assert_rgba_near(c, 0, 0, 1, 1, TEX_EPS);
    sample(s, m, 0.75f, 0.75f, 0.0f, c);
    assert_rgba_near(c, GREY, GREY, GREY, 1, TEX_EPS);
    uint32_t v = vertex_at(s, 0, pf_v3(0, 1, 0));
    assert_true(s->uvs[v].x == 0.0f && s->uvs[v].y == 1.0f);
}

static void test_texture_bufferview(void **state)
{
    (void)state;
    pf_scene s;
    load_ok(&s, DATA("texture_bufferview.gltf"));
    check_checker_material(&s);
    pf_scene_free(&s);
    load_ok(&s, DATA("texture_bufferview.glb"));
    check_checker_material(&s);
    pf_scene_free(&s);
}

static void test_texture_external(void **state)
{
    (void)state;
    pf_scene s;
    load_ok(&s, DATA("texture_external.gltf"));
    check_checker_material(&s);
    pf_scene_free(&s);
}

/* PNG layouts other than RGBA8 arrive as RGBA8 texels (grey spread to RGB,
 * missing alpha 255, 16-bit rounded, palettes expanded with tRNS alpha). */
static void test_texture_formats(void **state)
{
    (void)state;
    static const struct {
        const char *name;
        uint8_t texels[16];
    } expect[] = {
        {"grey8", {0, 0, 0, 255, 64, 64, 64, 255, 128, 128, 128, 255, 255, 255, 255, 255}},
        {"rgb8", {255, 0, 0, 255, 0, 255, 0, 255, 0, 0, 255, 255, 128, 128, 128, 255}},
        {"grey_alpha8", {0, 0, 0, 255, 64, 64, 64, 128, 128, 128, 128, 0, 255, 255, 255, 255}},
        {"rgba16", {255, 0, 0, 255, 0, 255, 0, 128, 0, 0, 255, 255, 128, 128, 128, 255}},
        {"palette_trns", {255, 0, 0, 255, 0, 255, 0, 128, 0, 0, 255, 255, 128, 128, 128, 255}},
        {"grey1", {0, 0, 0, 255, 255, 255, 255, 255, 255, 255, 255, 255, 0, 0, 0, 255}},
    };
    pf_scene s;
    load_ok(&s, DATA("texture_formats.gltf"));
    assert_int_equal(s.image_count, 6);
    for (int i = 0; i < 6; i++) {
        uint32_t m = mat_named(&s, expect[i].name, (float)i);
        const pf_image *img = &s.images[s.textures[s.materials[m].base_color_texture].image];
        assert_int_equal(img->width, 2);
        assert_int_equal(img->height, 2);
        if (memcmp(img->texels, expect[i].texels, 16) != 0) {
            for (int k = 0; k < 16; k++) fprintf(stderr, "%d%s", img->texels[k], k < 15 ? "," : "\n");
            fail_msg("image '%s': level-0 texels differ (got the line above)", expect[i].name);
        }
    }
    pf_scene_free(&s);
}

static void test_ignore_textures(void **state)
{
    (void)state;
    pf_scene s;
    pf_gltf_options o = {.ignore_textures = 1};
    float c[4];
    load_ok_opts(&s, DATA("texture_datauri.gltf"), &o);
    assert_int_equal(s.image_count, 0);
    for (uint32_t m = 0; m < s.material_count; m++) assert_int_equal(s.materials[m].base_color_texture, -1);
    uint32_t m = mat_named(&s, "repeat_nearest", 0.0f);
    sample(&s, m, 0.25f, 0.25f, 0.0f, c);
    assert_rgba_near(c, 1, 0.5f, 1, 1, 0.0f); /* albedo = factor */
    pf_scene_free(&s);
    /* a missing image does not matter when images are skipped */
    load_ok_opts(&s, DATA("bad_missing_texture.gltf"), &o);
    assert_int_equal(s.tri_count, 1);
    pf_scene_free(&s);
}

/* ------------------------------------------------------------------ cameras, lights */

static void test_camera(void **state)
{
    (void)state;
    pf_scene s;
    load_ok(&s, DATA("camera.gltf"));
    assert_int_equal(s.camera_count, 1); /* the orthographic one is skipped */
    assert_true(contains_ci(s.warnings, "orthographic"));
    const pf_camera *c = &s.cameras[0];
    assert_string_equal(c->name, "main_cam");
    /* T(1,2,3) R_y(90) T(0,0,5): eye (6,2,3), -Z -> -X */
    assert_vec3_near(c->eye, 6, 2, 3, POS_EPS);
    assert_vec3_near(c->forward, -1, 0, 0, DIR_EPS);
    assert_vec3_near(c->up, 0, 1, 0, DIR_EPS);
    assert_vec3_near(c->right, 0, 0, -1, DIR_EPS); /* forward x up */
    assert_float_equal(c->yfov, 0.8f, 0.0f);
    assert_float_equal(c->znear, 0.1f, 0.0f);
    assert_float_equal(c->zfar, 100.0f, 0.0f);
    assert_float_equal(c->aspect, 1.5f, 0.0f);
    pf_scene_free(&s);
}

static void test_lights(void **state)
{
    (void)state;
    pf_scene s;
    load_ok(&s, DATA("lights.gltf"));
    assert_int_equal(s.light_count, 5);
    const pf_light *l = light_named(&s, "bulb");
    assert_int_equal(l->type, PF_LIGHT_POINT);
    assert_vec3_near(l->position, 1, 2, 3, POS_EPS);
    assert_vec3_near(l->color, 1, 0.5f, 0.25f, 0.0f);
    assert_float_equal(l->intensity, 10.0f, 0.0f);
    assert_float_equal(l->range, 5.0f, 0.0f);

    l = light_named(&s, "spot"); /* T(0,5,0) R_x(-90): -Z -> -Y */
    assert_int_equal(l->type, PF_LIGHT_SPOT);
    assert_vec3_near(l->position, 0, 5, 0, POS_EPS);
    assert_vec3_near(l->direction, 0, -1, 0, DIR_EPS);
    assert_vec3_near(l->color, 1, 1, 1, 0.0f);
    assert_float_equal(l->intensity, 20.0f, 0.0f);
    assert_float_equal(l->inner_cone, 0.25f, 0.0f);
    assert_float_equal(l->outer_cone, 0.5f, 0.0f);

    l = light_named(&s, "sun"); /* parent R_y(90) S(3): unit direction -X */
    assert_int_equal(l->type, PF_LIGHT_DIRECTIONAL);
    assert_vec3_near(l->direction, -1, 0, 0, DIR_EPS);
    assert_vec3_near(l->color, 0.5f, 0.5f, 1, 0.0f);
    assert_float_equal(l->intensity, 3.0f, 0.0f);

    l = light_named(&s, "bulb_default"); /* KHR_lights_punctual defaults */
    assert_int_equal(l->type, PF_LIGHT_POINT);
    assert_vec3_near(l->position, 0, 0, -2, POS_EPS);
    assert_vec3_near(l->color, 1, 1, 1, 0.0f);
    assert_float_equal(l->intensity, 1.0f, 0.0f);
    assert_float_equal(l->range, 0.0f, 0.0f);

    l = light_named(&s, "spot_default"); /* no rotation: along -Z; cones 0 and pi/4 */
    assert_int_equal(l->type, PF_LIGHT_SPOT);
    assert_vec3_near(l->position, 4, 0, 0, POS_EPS);
    assert_vec3_near(l->direction, 0, 0, -1, DIR_EPS);
    assert_float_equal(l->inner_cone, 0.0f, 0.0f);
    assert_float_equal(l->outer_cone, 0.78539816f, 1e-6f);
    pf_scene_free(&s);
}

/* ------------------------------------------------------------------ bad files */

typedef struct bad_case {
    const char *file;
    pf_result code;
    const char *what; /* case-insensitive substring naming the problem */
    const char *what2;
} bad_case;

static const bad_case bad_cases[] = {
    {"bad_truncated.glb", PF_ERR_PARSE, "binary", NULL},
    {"bad_truncated.gltf", PF_ERR_PARSE, "json", NULL},
    {"bad_json.gltf", PF_ERR_PARSE, "json", NULL},
    {"bad_accessor_past_view.gltf", PF_ERR_ACCESSOR, "accessor 1", "bufferView 1"},
    {"bad_view_past_buffer.gltf", PF_ERR_ACCESSOR, "bufferView 1", "buffer 0"},
    {"bad_stride.gltf", PF_ERR_ACCESSOR, "stride", NULL},
    {"bad_index_range.gltf", PF_ERR_INDEX_RANGE, "77", NULL},
    {"bad_nan.gltf", PF_ERR_NONFINITE, "finite", NULL},
    {"bad_inf.gltf", PF_ERR_NONFINITE, "finite", NULL},
    {"bad_huge.gltf", PF_ERR_NONFINITE, "1e+30", NULL},
    {"bad_huge_transform.gltf", PF_ERR_NONFINITE, "1e+30", NULL},
    {"bad_cycle.gltf", PF_ERR_PARSE, "cycle", NULL},
    {"bad_self_cycle.gltf", PF_ERR_PARSE, "cycle", NULL},
    {"bad_missing_bin.gltf", PF_ERR_IO, "does_not_exist.bin", NULL},
    {"bad_missing_texture.gltf", PF_ERR_TEXTURE, "missing_texture.png", NULL},
    {"bad_only_points.gltf", PF_ERR_NO_TRIANGLES, "triangle", NULL},
    {"bad_only_degenerate.gltf", PF_ERR_NO_TRIANGLES, "triangle", NULL},
    {"bad_mesh_index.gltf", PF_ERR_INDEX_RANGE, "mesh 5", NULL},
    {"bad_material_index.gltf", PF_ERR_INDEX_RANGE, "material 3", NULL},
    {"bad_accessor_index.gltf", PF_ERR_INDEX_RANGE, "accessor 9", NULL},
    {"bad_bufferview_index.gltf", PF_ERR_INDEX_RANGE, "bufferView 4", NULL},
    {"bad_texture_index.gltf", PF_ERR_INDEX_RANGE, "texture 6", NULL},
    {"bad_light_index.gltf", PF_ERR_INDEX_RANGE, "light", "1e+30"},
    {"bad_dag.gltf", PF_ERR_PARSE, "parent", NULL},
    {"subdir/bad_texture_not_beside.gltf", PF_ERR_TEXTURE, "checker.png", NULL},
};

/* Returns 1 when the case behaved; prints what differs otherwise. */
static int check_bad(const bad_case *bc)
{
    char path[1024];
    snprintf(path, sizeof path, "%s/%s", GLTF_DIR, bc->file);
    pf_scene s;
    memset(&s, 0xAB, sizeof s);
    pf_error err = {0};
    pf_result r = pf_gltf_load(&s, path, NULL, &err);
    int ok = 1;
    if (r != bc->code) {
        fprintf(stderr, "%s: code %s (%d), expected %s (%d); message: %s\n", bc->file, pf_result_name(r), (int)r,
                pf_result_name(bc->code), (int)bc->code, err.message);
        ok = 0;
    } else if (err.code != r) {
        fprintf(stderr, "%s: err.code %d differs from the returned %d\n", bc->file, (int)err.code, (int)r);
        ok = 0;
    }
    if (r != PF_OK) {
        if (!contains_ci(err.message, bc->file) || !contains_ci(err.message, bc->what) ||
            (bc->what2 && !contains_ci(err.message, bc->what2))) {
            fprintf(stderr, "%s: message \"%s\" should name the file, \"%s\"%s%s%s\n", bc->file, err.message,
                    bc->what, bc->what2 ? " and \"" : "", bc->what2 ? bc->what2 : "", bc->what2 ? "\"" : "");
            ok = 0;
        }
        if (s.tri_count != 0 || s.positions != NULL || s.materials != NULL || s.images != NULL) {
            fprintf(stderr, "%s: *out not left empty on failure\n", bc->file);
            ok = 0;
        } else {
            assert_scene_empty(&s);
        }
    }
    pf_scene_free(&s);
    return ok;
}

/* One test per bad file would hide the overall picture behind the first
 * failure; this checks all of them and lists every mismatch. */
static void test_bad_files(void **state)
{
    (void)state;
    int failures = 0;
    for (size_t i = 0; i < sizeof bad_cases / sizeof bad_cases[0]; i++) failures += !check_bad(&bad_cases[i]);
    if (failures) fail_msg("%d of %zu bad files not rejected as expected (see above)", failures,
                           sizeof bad_cases / sizeof bad_cases[0]);
}

/* External uris resolve against the glTF file's directory only, never the
 * working directory (tinygltf on its own also searches "."): with the working
 * directory holding checker.png, subdir/ still lacks it. */
static void test_uri_not_from_cwd(void **state)
{
    (void)state;
    static const bad_case bc = {"subdir/bad_texture_not_beside.gltf", PF_ERR_TEXTURE, "checker.png", NULL};
    char cwd[1024];
    assert_non_null(getcwd(cwd, sizeof cwd));
    assert_int_equal(chdir(GLTF_DIR), 0);
    int ok = check_bad(&bc);
    assert_int_equal(chdir(cwd), 0);
    if (!ok) fail_msg("an external image was found through the working directory");
}

static void test_missing_file(void **state)
{
    (void)state;
    pf_scene s;
    pf_error err = {0};
    pf_result r = pf_gltf_load(&s, DATA("no_such_file.gltf"), NULL, &err);
    assert_int_equal(r, PF_ERR_IO);
    assert_int_equal(err.code, PF_ERR_IO);
    assert_true(contains_ci(err.message, "no_such_file.gltf"));
    assert_scene_empty(&s);
    /* a directory is not a file either */
    r = pf_gltf_load(&s, GLTF_DIR, NULL, &err);
    assert_true(r == PF_ERR_IO || r == PF_ERR_PARSE);
    assert_scene_empty(&s);
    /* err may be NULL */
    assert_int_equal(pf_gltf_load(&s, DATA("no_such_file.gltf"), NULL, NULL), PF_ERR_IO);
    assert_int_equal(pf_gltf_load(&s, DATA("bad_nan.gltf"), NULL, NULL), PF_ERR_NONFINITE);
}

/* ------------------------------------------------------------------ from memory */

static void test_memory_loads(void **state)
{
    (void)state;
    size_t n;
    pf_scene s, f;
    pf_error err = {0};

    /* data-uri .gltf without a base directory: same scene as from the file */
    void *buf = read_file(DATA("hierarchy_trs.gltf"), &n);
    assert_int_equal(pf_gltf_load_memory(&s, buf, n, NULL, "mem.gltf", NULL, &err), PF_OK);
    check_invariants(&s);
    load_ok(&f, DATA("hierarchy_trs.gltf"));
    assert_int_equal(s.tri_count, f.tri_count);
    assert_int_equal(s.vertex_count, f.vertex_count);
    assert_memory_equal(s.positions, f.positions, f.vertex_count * sizeof(pf_vec3));
    assert_memory_equal(s.indices, f.indices, 3 * f.tri_count * sizeof(uint32_t));
    pf_scene_free(&s);
    pf_scene_free(&f);
    free(buf);

    /* .glb with its image in the BIN chunk */
    buf = read_file(DATA("texture_bufferview.glb"), &n);
    assert_int_equal(pf_gltf_load_memory(&s, buf, n, NULL, "mem.glb", NULL, &err), PF_OK);
    check_invariants(&s);
    check_checker_material(&s);
    pf_scene_free(&s);
    free(buf);

    /* external files need a base directory */
    buf = read_file(DATA("texture_external.gltf"), &n);
    assert_int_equal(pf_gltf_load_memory(&s, buf, n, GLTF_DIR, "ext.gltf", NULL, &err), PF_OK);
    check_checker_material(&s);
    pf_scene_free(&s);
    /* base_dir NULL forbids them even when they sit in the working directory
     * (tinygltf on its own also searches "."). */
    char cwd[1024];
    assert_non_null(getcwd(cwd, sizeof cwd));
    assert_int_equal(chdir(GLTF_DIR), 0);
    pf_result r = pf_gltf_load_memory(&s, buf, n, NULL, "ext.gltf", NULL, &err);
    assert_int_equal(chdir(cwd), 0);
    if (r != PF_ERR_IO || !contains_ci(err.message, "texture_external.bin"))
        fail_msg("external .bin with base_dir NULL: %s (%s), expected i/o error naming texture_external.bin",
                 err.message, pf_result_name(r));
    assert_scene_empty(&s);
    free(buf);

    /* messages use the given name */
    buf = read_file(DATA("bad_index_range.gltf"), &n);
    assert_int_equal(pf_gltf_load_memory(&s, buf, n, NULL, "fuzzy.gltf", NULL, &err), PF_ERR_INDEX_RANGE);
    assert_true(contains_ci(err.message, "fuzzy.gltf"));
    assert_scene_empty(&s);
    free(buf);

    /* junk, empty and NULL input */
    static const char junk[] = "hello, not a glTF";
    assert_int_equal(pf_gltf_load_memory(&s, junk, sizeof junk - 1, NULL, "junk", NULL, &err), PF_ERR_PARSE);
    assert_scene_empty(&s);
    assert_int_equal(pf_gltf_load_memory(&s, junk, 0, NULL, "empty", NULL, &err), PF_ERR_PARSE);
    assert_scene_empty(&s);
    r = pf_gltf_load_memory(&s, NULL, 0, NULL, NULL, NULL, &err);
    assert_true(r == PF_ERR_PARSE || r == PF_ERR_ARGUMENT);
    assert_scene_empty(&s);
    static const char glb_magic[] = "glTF\x02\0\0\0\x14\0\0\0";
    assert_int_equal(pf_gltf_load_memory(&s, glb_magic, 12, NULL, "magic", NULL, &err), PF_ERR_PARSE);
    assert_scene_empty(&s);
}

/* Every strict prefix of a good file is a bad file: no crash, a clean error,
 * an empty scene. (JSON ending in '}' has no valid strict prefix; a GLB
 * header states its length.) */
static void check_prefixes(const char *path)
{
    size_t n;
    unsigned char *buf = read_file(path, &n);
    while (n > 0 && (buf[n - 1] == '\n' || buf[n - 1] == ' ')) n--;
    for (size_t len = 0; len < n; len++) {
        /* a fresh copy of exactly len bytes so ASan sees any over-read */
        unsigned char *cut = malloc(len ? len : 1);
        assert_non_null(cut);
        memcpy(cut, buf, len);
        pf_scene s;
        pf_error err = {0};
        pf_result r = pf_gltf_load_memory(&s, cut, len, NULL, "prefix", NULL, &err);
        if (r == PF_OK) fail_msg("%s cut to %zu of %zu bytes loaded", path, len, n);
        assert_true(err.message[0] != '\0');
        assert_scene_empty(&s);
        free(cut);
    }
    free(buf);
}

static void test_truncations(void **state)
{
    (void)state;
    check_prefixes(DATA("texture_bufferview.glb"));
    check_prefixes(DATA("triangle.gltf"));
}

/* ------------------------------------------------------------------ fuzz regressions */

/* Inputs that once crashed the fuzzer (tests/fuzz/fuzz_gltf.cpp), loaded as
 * the fuzzer loads them: from memory, base_dir NULL. Each must give a clean
 * error; the ones listed here an exact one. */
static const bad_case regress_cases[] = {
    /* GLB whose image bufferView (offset 60, length 80) ends one byte past its
     * 139-byte buffer: tinygltf 2.7 hands the unchecked range to stb_image
     * (heap over-read in stbi__parse_png_file) before the loader sees it. */
    {"image_view_past_buffer.glb", PF_ERR_ACCESSOR, "bufferView 2", "buffer 0"},
    /* 200 bytes asking for an accessor of 2^28 zero VEC3s (no bufferView):
     * 8 GB and 15 s before the cap on data-less accessors. */
    {"implicit_accessor_huge.gltf", PF_ERR_ACCESSOR, "no bufferView", "268435456"},
};

static void test_fuzz_regression_cases(void **state)
{
    (void)state;
    int failures = 0;
    for (size_t i = 0; i < sizeof regress_cases / sizeof regress_cases[0]; i++) {
        const bad_case *bc = &regress_cases[i];
        char path[1024];
        snprintf(path, sizeof path, "%s/regress/%s", GLTF_DIR, bc->file);
        size_t n;
        void *buf = read_file(path, &n);
        pf_scene s;
        pf_error err = {0};
        pf_result r = pf_gltf_load_memory(&s, buf, n, NULL, bc->file, NULL, &err);
        if (r != bc->code || !contains_ci(err.message, bc->file) || !contains_ci(err.message, bc->what) ||
            (bc->what2 && !contains_ci(err.message, bc->what2))) {
            fprintf(stderr, "regress/%s: %s \"%s\", expected %s naming \"%s\"%s%s\n", bc->file, pf_result_name(r),
                    err.message, pf_result_name(bc->code), bc->what, bc->what2 ? " and " : "",
                    bc->what2 ? bc->what2 : "");
            failures++;
        }
        if (r != PF_OK) assert_scene_empty(&s);
        pf_scene_free(&s);
        free(buf);
    }
    if (failures) fail_msg("%d fuzz regression inputs not rejected as expected (see above)", failures);
}

static void test_fuzz_regressions(void **state)
{
    (void)state;
    DIR *d = opendir(GLTF_DIR "/regress");
    if (!d) skip();
    struct dirent *e;
    int count = 0;
    while ((e = readdir(d)) != NULL) {
        if (e->d_name[0] == '.') continue;
        char path[1024];
        snprintf(path, sizeof path, "%s/regress/%s", GLTF_DIR, e->d_name);
        size_t n;
        void *buf = read_file(path, &n);
        pf_scene s;
        pf_error err = {0};
        pf_result r = pf_gltf_load_memory(&s, buf, n, NULL, e->d_name, NULL, &err);
        if (r == PF_OK) {
            check_invariants(&s);
        } else {
            assert_true(err.message[0] != '\0');
            assert_scene_empty(&s);
        }
        pf_scene_free(&s);
        free(buf);
        count++;
    }
    closedir(d);
    print_message("%d fuzz regression inputs\n", count);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_triangle),
        cmocka_unit_test(test_triangle_glb),
        cmocka_unit_test(test_quad_u8),
        cmocka_unit_test(test_quad_u16),
        cmocka_unit_test(test_quad_u32),
        cmocka_unit_test(test_quad_noindex),
        cmocka_unit_test(test_hierarchy_trs),
        cmocka_unit_test(test_hierarchy_matrix),
        cmocka_unit_test(test_negative_scale),
        cmocka_unit_test(test_flat_normals),
        cmocka_unit_test(test_normals_nonuniform),
        cmocka_unit_test(test_texcoords),
        cmocka_unit_test(test_strip_fan),
        cmocka_unit_test(test_sparse),
        cmocka_unit_test(test_interleaved),
        cmocka_unit_test(test_normals_unnormalized),
        cmocka_unit_test(test_degenerate),
        cmocka_unit_test(test_scene_select),
        cmocka_unit_test(test_alpha_mask),
        cmocka_unit_test(test_emissive),
        cmocka_unit_test(test_default_material),
        cmocka_unit_test(test_texture_samplers),
        cmocka_unit_test(test_texture_bufferview),
        cmocka_unit_test(test_texture_external),
        cmocka_unit_test(test_texture_formats),
        cmocka_unit_test(test_ignore_textures),
        cmocka_unit_test(test_camera),
        cmocka_unit_test(test_lights),
        cmocka_unit_test(test_bad_files),
        cmocka_unit_test(test_uri_not_from_cwd),
        cmocka_unit_test(test_missing_file),
        cmocka_unit_test(test_memory_loads),
        cmocka_unit_test(test_truncations),
        cmocka_unit_test(test_fuzz_regression_cases),
        cmocka_unit_test(test_fuzz_regressions),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
