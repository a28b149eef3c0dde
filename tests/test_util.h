/* test_util: small helpers shared by the test programs: scenes built in
 * code, running the softgi binary, file paths. Header-only (static). */
#ifndef TEST_UTIL_H
#define TEST_UTIL_H

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>

#include "pf_gltf.h"
#include "pf_scene.h"

/* A scene of `quads` axis-aligned quads given as centre, two half-extent
 * axes (CCW: normal = a x b) and material; one default white material per
 * quad unless albedo is given. */
typedef struct tu_quad {
    pf_vec3 centre, a, b;
    float albedo[4];
    pf_alpha_mode alpha_mode;
    float alpha_cutoff;
} tu_quad;

static inline void tu_make_scene(pf_scene *s, const tu_quad *quads, uint32_t count)
{
    memset(s, 0, sizeof *s);
    s->vertex_count = 4 * count;
    s->tri_count = 2 * count;
    s->positions = calloc(s->vertex_count + 1, sizeof(pf_vec3));
    s->normals = calloc(s->vertex_count, sizeof(pf_vec3));
    s->uvs = calloc(s->vertex_count, sizeof(pf_vec2));
    s->indices = calloc(3 * s->tri_count, sizeof(uint32_t));
    s->tri_material = calloc(s->tri_count, sizeof(uint32_t));
    s->material_count = count;
    s->materials = calloc(count, sizeof(pf_material));
    for (uint32_t q = 0; q < count; q++) {
        const tu_quad *Q = &quads[q];
        pf_vec3 n = pf_v3_normalize(pf_v3_cross(Q->a, Q->b));
        const float sa[4] = {-1, 1, 1, -1}, sb[4] = {-1, -1, 1, 1};
        for (int k = 0; k < 4; k++) {
            s->positions[4 * q + k] = pf_v3_add(Q->centre, pf_v3_add(pf_v3_scale(Q->a, sa[k]), pf_v3_scale(Q->b, sb[k])));
            s->normals[4 * q + k] = n;
            s->uvs[4 * q + k] = (pf_vec2){0.5f * (sa[k] + 1), 0.5f * (sb[k] + 1)};
        }
        const uint32_t idx[6] = {0, 1, 2, 0, 2, 3};
        for (int k = 0; k < 6; k++) s->indices[6 * q + k] = 4 * q + idx[k];
        s->tri_material[2 * q] = s->tri_material[2 * q + 1] = q;
        pf_material *m = &s->materials[q];
        snprintf(m->name, sizeof m->name, "quad%u", q);
        memcpy(m->base_color, Q->albedo, sizeof m->base_color);
        m->base_color_texture = -1;
        m->alpha_mode = Q->alpha_mode;
        m->alpha_cutoff = Q->alpha_cutoff;
    }
}

/* The alpha-mask stack the rasterizer's and Embree's tests share: three
 * quads of half extent `half` facing +z at z = -1, -2, -3: alpha-masked
 * with alpha 0.2 under the cutoff 0.5 (a hole), alpha-masked with 0.8
 * (kept), opaque. */
static inline void tu_make_alpha_stack(pf_scene *s, float half)
{
    const tu_quad q[3] = {
        {{0, 0, -1}, {half, 0, 0}, {0, half, 0}, {1, 1, 1, 0.2f}, PF_ALPHA_MASK, 0.5f},   /* a hole */
        {{0, 0, -2}, {half, 0, 0}, {0, half, 0}, {1, 1, 1, 0.8f}, PF_ALPHA_MASK, 0.5f},   /* kept */
        {{0, 0, -3}, {half, 0, 0}, {0, half, 0}, {1, 1, 1, 1.0f}, PF_ALPHA_OPAQUE, 0.5f}, /* opaque */
    };
    tu_make_scene(s, q, 3);
}

/* Runs a shell command, captures stdout+stderr into out (NUL-terminated),
 * returns the exit status (or -1). */
static inline int tu_run(const char *cmd, char *out, size_t size)
{
    char full[8320];
    snprintf(full, sizeof full, "%s 2>&1", cmd);
    FILE *p = popen(full, "r");
    if (!p) return -1;
    size_t n = fread(out, 1, size - 1, p);
    out[n] = 0;
    int st = pclose(p);
    return WIFEXITED(st) ? WEXITSTATUS(st) : -1;
}

static inline int tu_file_exists(const char *path)
{
    struct stat st;
    return stat(path, &st) == 0;
}

#ifdef SOFTGI_BINARY
/* Runs `softgi ARGS`, output (stdout + stderr) into out; fails the test if
 * the program ended abnormally (a crash, or a status other than 0, 1, 2).
 * Needs <cmocka.h> included before this header. */
static inline int tu_softgi_run(const char *args, char *out, size_t size)
{
    char cmd[8192];
    snprintf(cmd, sizeof cmd, "%s %s", SOFTGI_BINARY, args);
    int st = tu_run(cmd, out, size);
    if (st < 0 || st > 2) fail_msg("'%s' ended abnormally (status %d):\n%s", cmd, st, out);
    return st;
}

/* Runs `softgi ARGS` and checks its exit status and (unless NULL) that the
 * output contains `needle`. */
static inline void tu_softgi_expect(const char *args, int status, const char *needle)
{
    char out[16384];
    int st = tu_softgi_run(args, out, sizeof out);
    if (st != status || (needle && !strstr(out, needle)))
        fail_msg("softgi %s\n  exit %d (want %d), output:\n%s\n  (want it to contain '%s')", args, st, status, out,
                 needle ? needle : "");
}
#endif

/* A fresh temporary folder /tmp/<tag>-XXXXXX into buf (0 on success), and
 * its recursive removal (0 on success): cmocka group setup/teardown bodies. */
static inline int tu_tmpdir_create(char *buf, size_t size, const char *tag)
{
    snprintf(buf, size, "/tmp/%s-XXXXXX", tag);
    return mkdtemp(buf) ? 0 : -1;
}

static inline int tu_tmpdir_remove(const char *dir)
{
    char cmd[4200];
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
    return system(cmd) == 0 ? 0 : -1;
}

/* Loads a scene for a test: 0 with a SKIP message when the file is absent
 * (the shared scenes live beside the repo, not in it), 1 when loaded; a
 * file that exists but fails to load fails the test. Needs <cmocka.h>
 * included before this header. */
static inline int tu_load_or_skip(pf_scene *s, const char *path)
{
    if (!tu_file_exists(path)) {
        print_message("SKIP: %s is absent (the shared scenes are not checked out beside the repo)\n", path);
        return 0;
    }
    pf_error err;
    if (pf_gltf_load(s, path, NULL, &err) != PF_OK) fail_msg("%s", err.message);
    return 1;
}

#endif
