/* test_security: the scene loader's trust boundary (docs/security.md).
 *
 * Each case is a regression test for a defect found by trying softgi as an
 * attacker would; each fails on the code before its fix:
 * - path traversal: a buffer or image uri of "../x", "%2e%2e/x", an absolute
 *   path or a symbolic link leaving the scene's folder is treated as a
 *   missing file, and the message says nothing about the file outside;
 * - JSON nested 15,000 deep (tinygltf's recursive conversion overflowed the
 *   stack) is refused;
 * - glTF 1.0 and GLB version 1 are refused; a 3-number baseColorFactor and
 *   negative object indices ("indices": -3) are errors, not dropped;
 * - out-of-range inputs: baseColorFactor outside [0, 1] is clamped with a
 *   warning, light intensities that would overflow float are refused;
 * - a camera whose znear lies beyond the whole scene is refused;
 * - memory bombs: images (by their headers), instanced triangles and external
 *   files are estimated against the memory budget before allocation. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cmocka.h>

#include "pf_budget.h"
#include "pf_gltf.h"
#include "pf_scene.h"
#include "test_util.h"

static char g_dir[512]; /* the group's temporary folder */

static void write_file(const char *path, const void *data, size_t size)
{
    FILE *f = fopen(path, "wb");
    assert_non_null(f);
    assert_int_equal(fwrite(data, 1, size, f), size);
    assert_int_equal(fclose(f), 0);
}

/* One triangle, its 36-byte position buffer at `uri`; `top` is spliced into
 * the top-level object (e.g. materials), `prim` into the primitive (e.g.
 * "material":0,), and `node`, when given, is a second node of the scene. */
static void gltf_make(char *out, size_t size, const char *uri, const char *top, const char *prim, const char *node)
{
    snprintf(out, size,
             "{\"asset\":{\"version\":\"2.0\"},%s"
             "\"buffers\":[{\"uri\":\"%s\",\"byteLength\":36}],"
             "\"bufferViews\":[{\"buffer\":0,\"byteLength\":36}],"
             "\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"count\":3,\"type\":\"VEC3\","
             "\"min\":[0,0,0],\"max\":[1,1,0]}],"
             "\"meshes\":[{\"primitives\":[{%s\"attributes\":{\"POSITION\":0}}]}],"
             "\"nodes\":[{\"mesh\":0}%s%s],\"scenes\":[{\"nodes\":[0%s]}],\"scene\":0}",
             top ? top : "", uri, prim ? prim : "", node ? "," : "", node ? node : "", node ? ",1" : "");
}
static void gltf_with_buffer(char *out, size_t size, const char *uri, const char *top)
{
    gltf_make(out, size, uri, top, NULL, NULL);
}

static const float k_tri[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};

static int group_setup(void **state)
{
    (void)state;
    if (tu_tmpdir_create(g_dir, sizeof g_dir, "softgi-security") != 0) return -1;
    char p[4200];
    snprintf(p, sizeof p, "%s/scene", g_dir);
    if (mkdir(p, 0755) != 0) return -1;
    snprintf(p, sizeof p, "%s/scene/sub", g_dir);
    if (mkdir(p, 0755) != 0) return -1;
    /* the secret outside the scene's folder has exactly the size the glTF
     * asks for, so the old loader read it and rendered its bytes */
    snprintf(p, sizeof p, "%s/secret.bin", g_dir);
    write_file(p, k_tri, sizeof k_tri);
    snprintf(p, sizeof p, "%s/scene/inside.bin", g_dir);
    write_file(p, k_tri, sizeof k_tri);
    char target[4200];
    snprintf(target, sizeof target, "%s/secret.bin", g_dir);
    snprintf(p, sizeof p, "%s/scene/link.bin", g_dir);
    if (symlink(target, p) != 0) return -1;
    return 0;
}

static int group_teardown(void **state)
{
    (void)state;
    return tu_tmpdir_remove(g_dir);
}

/* Writes `json` as scene/NAME and loads it. */
static pf_result load_scene_file(const char *name, const char *json, pf_scene *s, pf_error *err)
{
    char path[4200];
    snprintf(path, sizeof path, "%s/scene/%s", g_dir, name);
    write_file(path, json, strlen(json));
    return pf_gltf_load(s, path, NULL, err);
}

static void test_path_traversal(void **state)
{
    (void)state;
    char abs_uri[4200];
    snprintf(abs_uri, sizeof abs_uri, "%s/secret.bin", g_dir);
    const char *escaping[] = {"../secret.bin", "%2e%2e/secret.bin", "%2E%2E%2Fsecret.bin", "sub/../../secret.bin",
                              "./../secret.bin", abs_uri, "link.bin", "file:../secret.bin"};
    for (size_t i = 0; i < sizeof escaping / sizeof escaping[0]; i++) {
        char json[8192];
        gltf_with_buffer(json, sizeof json, escaping[i], NULL);
        pf_scene s;
        pf_error err;
        pf_result r = load_scene_file("escape.gltf", json, &s, &err);
        if (r == PF_OK) fail_msg("uri '%s' was read from outside the scene's folder", escaping[i]);
        /* the message says nothing about the file outside: no size, no resolved path */
        if (strstr(err.message, "36") || strstr(err.message, "mismatch") || strstr(err.message, "secret.bin ,"))
            fail_msg("uri '%s': the message reveals the outside file: %s", escaping[i], err.message);
        assert_true(s.tri_count == 0 && s.positions == NULL);
    }
    /* inside the folder, also through "sub/..": loads */
    const char *inside[] = {"inside.bin", "sub/../inside.bin", "%69nside.bin"};
    for (size_t i = 0; i < sizeof inside / sizeof inside[0]; i++) {
        char json[8192];
        gltf_with_buffer(json, sizeof json, inside[i], NULL);
        pf_scene s;
        pf_error err;
        if (load_scene_file("inside.gltf", json, &s, &err) != PF_OK) fail_msg("'%s': %s", inside[i], err.message);
        assert_int_equal(s.tri_count, 1);
        pf_scene_free(&s);
    }
    /* a missing file and a file outside give the same message */
    char json[8192];
    pf_scene s;
    pf_error e_out, e_missing;
    gltf_with_buffer(json, sizeof json, "../secret.bin", NULL);
    assert_int_not_equal(load_scene_file("a.gltf", json, &s, &e_out), PF_OK);
    gltf_with_buffer(json, sizeof json, "../absent.bin", NULL);
    assert_int_not_equal(load_scene_file("a.gltf", json, &s, &e_missing), PF_OK);
    char *a = strstr(e_out.message, "secret.bin"), *b = strstr(e_missing.message, "absent.bin");
    assert_non_null(a);
    assert_non_null(b);
    assert_string_equal(a + strlen("secret.bin"), b + strlen("absent.bin"));
}

/* A FIFO inside the folder must not block the loader. */
static void test_fifo_is_not_read(void **state)
{
    (void)state;
    char p[4200];
    snprintf(p, sizeof p, "%s/scene/pipe.bin", g_dir);
    assert_int_equal(mkfifo(p, 0600), 0);
    char json[8192];
    gltf_with_buffer(json, sizeof json, "pipe.bin", NULL);
    pf_scene s;
    pf_error err;
    assert_int_not_equal(load_scene_file("fifo.gltf", json, &s, &err), PF_OK);
    unlink(p);
}

static void test_deep_json(void **state)
{
    (void)state;
    enum { DEPTH = 15000 };
    size_t cap = 2 * DEPTH + 4096;
    char *json = malloc(cap);
    assert_non_null(json);
    char tail[2048];
    gltf_with_buffer(tail, sizeof tail, "inside.bin", NULL);
    /* {"extras": [[[[...]]]], <the rest>} */
    size_t n = (size_t)snprintf(json, cap, "{\"extras\":");
    for (int i = 0; i < DEPTH; i++) json[n++] = '[';
    for (int i = 0; i < DEPTH; i++) json[n++] = ']';
    n += (size_t)snprintf(json + n, cap - n, ",%s", tail + 1);
    pf_scene s;
    pf_error err;
    assert_int_equal(load_scene_file("deep.gltf", json, &s, &err), PF_ERR_PARSE);
    assert_non_null(strstr(err.message, "nested"));
    /* a moderately nested extras (20 levels) is fine */
    n = (size_t)snprintf(json, cap, "{\"extras\":");
    for (int i = 0; i < 20; i++) json[n++] = '[';
    for (int i = 0; i < 20; i++) json[n++] = ']';
    snprintf(json + n, cap - n, ",%s", tail + 1);
    assert_int_equal(load_scene_file("deep.gltf", json, &s, &err), PF_OK);
    pf_scene_free(&s);
    free(json);
}

static void test_versions(void **state)
{
    (void)state;
    char json[8192];
    pf_scene s;
    pf_error err;
    gltf_with_buffer(json, sizeof json, "inside.bin", NULL);
    char *v = strstr(json, "\"2.0\"");
    assert_non_null(v);
    v[1] = '1'; /* "1.0" */
    assert_int_equal(load_scene_file("v1.gltf", json, &s, &err), PF_ERR_UNSUPPORTED);
    assert_non_null(strstr(err.message, "1.0"));
    /* GLB version 1 header */
    unsigned char glb[20 + 64];
    memset(glb, ' ', sizeof glb);
    memcpy(glb, "glTF", 4);
    uint32_t u = 1;
    memcpy(glb + 4, &u, 4);
    u = sizeof glb;
    memcpy(glb + 8, &u, 4);
    u = 64;
    memcpy(glb + 12, &u, 4);
    u = 0x4E4F534Au;
    memcpy(glb + 16, &u, 4);
    assert_int_equal(pf_gltf_load_memory(&s, glb, sizeof glb, NULL, "v1.glb", NULL, &err), PF_ERR_UNSUPPORTED);
    assert_non_null(strstr(err.message, "version 1"));
    /* no asset.version at all */
    gltf_with_buffer(json, sizeof json, "inside.bin", NULL);
    v = strstr(json, "\"version\"");
    memcpy(v + 1, "vorsion", 7);
    assert_int_equal(load_scene_file("nov.gltf", json, &s, &err), PF_ERR_PARSE);
}

static void test_materials(void **state)
{
    (void)state;
    char json[8192], fixed[8192];
    pf_scene s;
    pf_error err;
    /* 3 numbers: tinygltf drops it silently; softgi refuses */
    gltf_with_buffer(json, sizeof json, "inside.bin",
                     "\"materials\":[{\"pbrMetallicRoughness\":{\"baseColorFactor\":[1,0,0]}}],");
    assert_int_equal(load_scene_file("bc3.gltf", json, &s, &err), PF_ERR_PARSE);
    assert_non_null(strstr(err.message, "baseColorFactor"));
    /* outside [0, 1] and negative: clamped with a warning */
    gltf_make(fixed, sizeof fixed, "inside.bin",
              "\"materials\":[{\"pbrMetallicRoughness\":{\"baseColorFactor\":[7,-2,0.5,1]},"
              "\"emissiveFactor\":[-1,2,0.25]}],",
              "\"material\":0,", NULL);
    assert_int_equal(load_scene_file("bcclamp.gltf", fixed, &s, &err), PF_OK);
    assert_true(s.materials[0].base_color[0] == 1.0f && s.materials[0].base_color[1] == 0.0f &&
                s.materials[0].base_color[2] == 0.5f);
    assert_true(s.materials[0].emission[0] == 0.0f && s.materials[0].emission[1] == 1.0f &&
                s.materials[0].emission[2] == 0.25f);
    assert_non_null(strstr(s.warnings, "baseColorFactor outside [0, 1] clamped"));
    assert_non_null(strstr(s.warnings, "emissiveFactor outside [0, 1] clamped"));
    pf_scene_free(&s);
    /* negative indices are errors, never "absent" */
    const char *negs[] = {"\"indices\":-3,", "\"material\":-2,", "\"mode\":4,\"indices\":1.5,"};
    for (size_t i = 0; i < 3; i++) {
        gltf_make(json, sizeof json, "inside.bin", NULL, negs[i], NULL);
        assert_int_equal(load_scene_file("neg.gltf", json, &s, &err), PF_ERR_INDEX_RANGE);
        assert_non_null(strstr(err.message, "non-negative integer"));
    }
}

static void test_lights_out_of_range(void **state)
{
    (void)state;
    const char *lights[] = {
        "{\"type\":\"point\",\"intensity\":1e38}",
        "{\"type\":\"point\",\"intensity\":1e11,\"color\":[1,1,1]}",
        "{\"type\":\"point\",\"intensity\":-1}",
    };
    for (size_t i = 0; i < 3; i++) {
        char extra[512], json[8192];
        snprintf(extra, sizeof extra,
                 "\"extensionsUsed\":[\"KHR_lights_punctual\"],"
                 "\"extensions\":{\"KHR_lights_punctual\":{\"lights\":[%s]}},",
                 lights[i]);
        gltf_make(json, sizeof json, "inside.bin", extra, NULL,
                  "{\"extensions\":{\"KHR_lights_punctual\":{\"light\":0}}}");
        pf_scene s;
        pf_error err;
        pf_result r = load_scene_file("light.gltf", json, &s, &err);
        if (r == PF_OK) fail_msg("light %s accepted", lights[i]);
    }
    /* the same limit for lights added by the command line or a test */
    pf_scene s;
    pf_error err;
    memset(&s, 0, sizeof s);
    tu_quad q = {.centre = {0, 0, 0}, .a = {1, 0, 0}, .b = {0, 1, 0}, .albedo = {1, 1, 1, 1}};
    tu_make_scene(&s, &q, 1);
    pf_light L = {.type = PF_LIGHT_POINT, .position = {0, 0, 1}, .color = {1, 1, 1}, .intensity = 1e38f};
    assert_int_equal(pf_scene_add_light(&s, &L, &err), PF_OK);
    assert_int_equal(pf_scene_validate(&s, &err), PF_ERR_NONFINITE);
    assert_non_null(strstr(err.message, "exceeds"));
    pf_scene_free(&s);
}

static void test_camera_znear_beyond_scene(void **state)
{
    (void)state;
    char json[8192];
    gltf_make(json, sizeof json, "inside.bin",
              "\"cameras\":[{\"type\":\"perspective\",\"perspective\":{\"yfov\":0.7,\"znear\":1e30}}],", NULL,
              "{\"camera\":0,\"translation\":[0,0,5]}");
    pf_scene s;
    pf_error err;
    assert_int_equal(load_scene_file("znear.gltf", json, &s, &err), PF_ERR_PARSE);
    assert_non_null(strstr(err.message, "znear"));
    /* a sane znear loads */
    char *z = strstr(json, "1e30");
    memcpy(z, "0.01", 4);
    assert_int_equal(load_scene_file("znear.gltf", json, &s, &err), PF_OK);
    pf_scene_free(&s);
}

/* A .glb holding `tris` triangles in one mesh instanced by `nodes` nodes. */
static unsigned char *instancing_glb(uint32_t tris, uint32_t nodes, size_t *size)
{
    size_t bin = (size_t)tris * 36;
    size_t jcap = 4096 + (size_t)nodes * 16;
    char *json = malloc(jcap);
    assert_non_null(json);
    size_t n = (size_t)snprintf(json, jcap,
                                "{\"asset\":{\"version\":\"2.0\"},\"buffers\":[{\"byteLength\":%zu}],"
                                "\"bufferViews\":[{\"buffer\":0,\"byteLength\":%zu}],"
                                "\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"count\":%u,"
                                "\"type\":\"VEC3\",\"min\":[0,0,0],\"max\":[%u,1,0]}],"
                                "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0}}]}],\"nodes\":[",
                                bin, bin, 3 * tris, tris + 1);
    for (uint32_t i = 0; i < nodes; i++) n += (size_t)snprintf(json + n, jcap - n, "%s{\"mesh\":0}", i ? "," : "");
    n += (size_t)snprintf(json + n, jcap - n, "],\"scenes\":[{\"nodes\":[");
    for (uint32_t i = 0; i < nodes; i++) n += (size_t)snprintf(json + n, jcap - n, "%s%u", i ? "," : "", i);
    n += (size_t)snprintf(json + n, jcap - n, "]}]}");
    while (n % 4) json[n++] = ' ';
    *size = 12 + 8 + n + 8 + bin;
    unsigned char *g = malloc(*size);
    assert_non_null(g);
    uint32_t u;
    memcpy(g, "glTF", 4);
    u = 2;
    memcpy(g + 4, &u, 4);
    u = (uint32_t)*size;
    memcpy(g + 8, &u, 4);
    u = (uint32_t)n;
    memcpy(g + 12, &u, 4);
    u = 0x4E4F534Au;
    memcpy(g + 16, &u, 4);
    memcpy(g + 20, json, n);
    u = (uint32_t)bin;
    memcpy(g + 20 + n, &u, 4);
    u = 0x004E4942u;
    memcpy(g + 24 + n, &u, 4);
    float *p = (float *)(void *)(g + 28 + n);
    for (uint32_t t = 0; t < tris; t++) {
        const float v[9] = {(float)t, 0, 0, (float)t + 1, 0, 0, (float)t, 1, 0};
        memcpy(p + 9 * (size_t)t, v, sizeof v);
    }
    free(json);
    return g;
}

static void test_budget_triangles(void **state)
{
    (void)state;
    size_t size;
    unsigned char *g = instancing_glb(1000, 200, &size); /* 200,000 triangles, ~100 MiB at 512 B each */
    pf_scene s;
    pf_error err;
    pf_gltf_options o = {.max_memory = 64ull << 20};
    assert_int_equal(pf_gltf_load_memory(&s, g, size, NULL, "bomb.glb", &o, &err), PF_ERR_OUT_OF_MEMORY);
    assert_non_null(strstr(err.message, "triangles"));
    assert_non_null(strstr(err.message, "--max-memory"));
    o.max_memory = 1ull << 30; /* fits */
    assert_int_equal(pf_gltf_load_memory(&s, g, size, NULL, "bomb.glb", &o, &err), PF_OK);
    assert_int_equal(s.tri_count, 200000);
    pf_scene_free(&s);
    free(g);
}

/* Sixteen images whose PNG headers say 8192x8192 (the pixels need not
 * exist: the budget is checked on the headers, before any decoding). */
static void test_budget_images(void **state)
{
    (void)state;
    static const unsigned char png_head[] = {0x89, 'P',  'N',  'G',  0x0d, 0x0a, 0x1a, 0x0a, 0, 0,   0,
                                             13,   'I',  'H',  'D',  'R',  0,    0,    0x20, 0, 0,   0,
                                             0x20, 0,    8,    6,    0,    0,    0,    0x00, 0, 0,   0};
    /* IHDR: 8192 x 8192, 8-bit RGBA; the CRC is computed below */
    unsigned char png[sizeof png_head];
    memcpy(png, png_head, sizeof png);
    uint32_t crc = 0xffffffffu;
    for (size_t i = 12; i < 29; i++) {
        crc ^= png[i];
        for (int k = 0; k < 8; k++) crc = crc & 1 ? (crc >> 1) ^ 0xedb88320u : crc >> 1;
    }
    crc ^= 0xffffffffu;
    png[29] = (unsigned char)(crc >> 24), png[30] = (unsigned char)(crc >> 16), png[31] = (unsigned char)(crc >> 8),
    png[32] = (unsigned char)crc;
    char p[4200];
    snprintf(p, sizeof p, "%s/scene/big.png", g_dir);
    write_file(p, png, sizeof png);
    char extra[4096];
    size_t n = (size_t)snprintf(extra, sizeof extra, "\"images\":[");
    for (int i = 0; i < 16; i++) n += (size_t)snprintf(extra + n, sizeof extra - n, "%s{\"uri\":\"big.png\"}", i ? "," : "");
    n += (size_t)snprintf(extra + n, sizeof extra - n, "],\"textures\":[");
    for (int i = 0; i < 16; i++) n += (size_t)snprintf(extra + n, sizeof extra - n, "%s{\"source\":%d}", i ? "," : "", i);
    n += (size_t)snprintf(extra + n, sizeof extra - n, "],\"materials\":[");
    for (int i = 0; i < 16; i++)
        n += (size_t)snprintf(extra + n, sizeof extra - n,
                              "%s{\"pbrMetallicRoughness\":{\"baseColorTexture\":{\"index\":%d}}}", i ? "," : "", i);
    snprintf(extra + n, sizeof extra - n, "],");
    /* sixteen primitives, one per material */
    char json[16384], prims[2048];
    size_t m = (size_t)snprintf(prims, sizeof prims, "\"primitives\":[");
    for (int i = 0; i < 16; i++)
        m += (size_t)snprintf(prims + m, sizeof prims - m, "%s{\"attributes\":{\"POSITION\":0},\"material\":%d}",
                              i ? "," : "", i);
    snprintf(prims + m, sizeof prims - m, "]");
    char base[8192];
    gltf_with_buffer(base, sizeof base, "inside.bin", extra);
    char *pr = strstr(base, "\"primitives\":[{\"attributes\":{\"POSITION\":0}}]");
    assert_non_null(pr);
    snprintf(json, sizeof json, "%.*s%s%s", (int)(pr - base), base, prims,
             pr + strlen("\"primitives\":[{\"attributes\":{\"POSITION\":0}}]"));
    snprintf(p, sizeof p, "%s/scene/images.gltf", g_dir);
    write_file(p, json, strlen(json));
    pf_scene s;
    pf_error err;
    pf_gltf_options o = {.max_memory = 2ull << 30}; /* 16 x 8192^2 x 4 x 4/3 = 5.3 GiB */
    assert_int_equal(pf_gltf_load(&s, p, &o, &err), PF_ERR_OUT_OF_MEMORY);
    assert_non_null(strstr(err.message, "8192x8192"));
    assert_non_null(strstr(err.message, "budget"));
}

static void test_budget_parse(void **state)
{
    (void)state;
    uint64_t b;
    pf_error err;
    assert_int_equal(pf_budget_parse("8G", &b, &err), PF_OK);
    assert_true(b == 8ull << 30);
    assert_int_equal(pf_budget_parse("512M", &b, &err), PF_OK);
    assert_true(b == 512ull << 20);
    assert_int_equal(pf_budget_parse("1.5GiB", &b, &err), PF_OK);
    assert_true(b == 3ull << 29);
    assert_int_equal(pf_budget_parse("1M", &b, &err), PF_ERR_ARGUMENT);   /* below 64M */
    assert_int_equal(pf_budget_parse("-5G", &b, &err), PF_ERR_ARGUMENT);
    assert_int_equal(pf_budget_parse("8X", &b, &err), PF_ERR_ARGUMENT);
    assert_int_equal(pf_budget_parse("nan", &b, &err), PF_ERR_ARGUMENT);
    assert_true(pf_budget_default() > 0 && pf_budget_default() <= pf_memory_machine());
    pf_budget bud;
    pf_budget_init(&bud, 100ull << 20);
    assert_int_equal(pf_budget_take(&bud, 60ull << 20, "a", &err), PF_OK);
    assert_int_equal(pf_budget_take(&bud, 60ull << 20, "b", &err), PF_ERR_OUT_OF_MEMORY);
    assert_int_equal(pf_budget_take(&bud, UINT64_MAX, "c", &err), PF_ERR_OUT_OF_MEMORY); /* no wrap-around */
    assert_true(pf_budget_mul(UINT64_MAX / 2, 3) == UINT64_MAX);
}

/* The frame's memory, end to end through the program: a sequence asking
 * for a 16384^2 frame, a scene with 2,000 point lights (a cube shadow map
 * each), and --max-memory itself. Each is refused in well under a second,
 * before anything big is allocated. */
static void test_budget_frames(void **state)
{
    (void)state;
    char path[1024], args[4096];
    /* 2,000 point lights in a small scene */
    size_t cap = 2000 * 160 + 8192;
    char *json = malloc(cap), *lights = malloc(cap), *nodes = malloc(cap);
    assert_true(json && lights && nodes);
    size_t nl = 0, nn = 0;
    for (int i = 0; i < 2000; i++) {
        nl += (size_t)snprintf(lights + nl, cap - nl, "%s{\"type\":\"point\",\"intensity\":0.01}", i ? "," : "");
        nn += (size_t)snprintf(nodes + nn, cap - nn,
                               ",{\"translation\":[0.2,0.2,%g],\"extensions\":{\"KHR_lights_punctual\":{\"light\":%d}}}",
                               0.1 + 0.0001 * i, i);
    }
    char *top = malloc(cap);
    assert_non_null(top);
    snprintf(top, cap, "\"extensions\":{\"KHR_lights_punctual\":{\"lights\":[%s]}},", lights);
    snprintf(json, cap,
             "{\"asset\":{\"version\":\"2.0\"},%s"
             "\"buffers\":[{\"uri\":\"inside.bin\",\"byteLength\":36}],"
             "\"bufferViews\":[{\"buffer\":0,\"byteLength\":36}],"
             "\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"count\":3,\"type\":\"VEC3\","
             "\"min\":[0,0,0],\"max\":[1,1,0]}],"
             "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0}}]}],"
             "\"nodes\":[{\"mesh\":0}%s],\"scenes\":[{\"nodes\":[0]}],\"scene\":0}",
             top, nodes);
    /* the scene lists only node 0; make every light node a root too */
    char *sc = strstr(json, "\"scenes\":[{\"nodes\":[0]}]");
    assert_non_null(sc);
    size_t head = (size_t)(sc - json);
    char *fixed = malloc(cap + 16384);
    assert_non_null(fixed);
    size_t n = (size_t)snprintf(fixed, cap + 16384, "%.*s\"scenes\":[{\"nodes\":[0", (int)head, json);
    for (int i = 1; i <= 2000; i++) n += (size_t)snprintf(fixed + n, cap + 16384 - n, ",%d", i);
    snprintf(fixed + n, cap + 16384 - n, "]}],\"scene\":0}");
    snprintf(path, sizeof path, "%s/scene/lights.gltf", g_dir);
    write_file(path, fixed, strlen(fixed));
    snprintf(args, sizeof args, "render %s --camera 0.5,0.5,3:0.5,0.5,0:40 --size 64x48 -o %s/lights.png", path, g_dir);
    tu_softgi_expect(args, 1, "2000 lights with shadow maps");
    snprintf(path, sizeof path, "%s/lights.png", g_dir);
    assert_false(tu_file_exists(path));
    /* the same scene fits with smaller shadow maps */
    snprintf(path, sizeof path, "%s/scene/lights.gltf", g_dir);
    snprintf(args, sizeof args,
             "render %s --camera 0.5,0.5,3:0.5,0.5,0:40 --size 64x48 --shadow-size 16 --direct-only -q -o %s/lights.png",
             path, g_dir);
    tu_softgi_expect(args, 0, NULL);
    free(json), free(lights), free(nodes), free(top), free(fixed);

    /* a sequence asking for a 16384^2 frame */
    snprintf(path, sizeof path, "%s/big.seq.json", g_dir);
    char tri[8192];
    gltf_with_buffer(tri, sizeof tri, "inside.bin", NULL);
    char scene_path[1024];
    snprintf(scene_path, sizeof scene_path, "%s/scene/tri.gltf", g_dir);
    write_file(scene_path, tri, strlen(tri));
    const char *seq = "{\"name\":\"big\",\"scene\":\"scene/tri.gltf\",\"frames\":2,\"size\":[16384,16384],"
                      "\"camera\":[{\"frame\":0,\"eye\":[0.3,0.3,2],\"target\":[0.3,0.3,0],\"fovy_deg\":40}],"
                      "\"lights\":[{\"type\":\"point\",\"color\":[1,1,1],\"intensity\":1,"
                      "\"position\":[0.3,0.3,1],\"keys\":[{\"frame\":0,\"position\":[0.3,0.3,1]}]}]}";
    write_file(path, seq, strlen(seq));
    snprintf(args, sizeof args, "sequence %s -o %s/bigseq", path, g_dir);
    tu_softgi_expect(args, 1, "exceeds the memory budget");
    /* --max-memory: parsed strictly, and honoured */
    tu_softgi_expect("render --max-memory lots", 2, "--max-memory");
    snprintf(args, sizeof args, "render --size 4096x4096 --max-memory 1G -o %s/m.png", g_dir);
    tu_softgi_expect(args, 1, "budget of 1024 MiB");
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_path_traversal),
        cmocka_unit_test(test_fifo_is_not_read),
        cmocka_unit_test(test_deep_json),
        cmocka_unit_test(test_versions),
        cmocka_unit_test(test_materials),
        cmocka_unit_test(test_lights_out_of_range),
        cmocka_unit_test(test_camera_znear_beyond_scene),
        cmocka_unit_test(test_budget_triangles),
        cmocka_unit_test(test_budget_images),
        cmocka_unit_test(test_budget_parse),
        cmocka_unit_test(test_budget_frames),
    };
    return cmocka_run_group_tests(tests, group_setup, group_teardown);
}
