/* test_scenes: the authored scenes of scenes/ (written by tools/make_scenes.py) loaded through
 * pf_gltf_load, checked for what each scene promises in its README:
 *
 * - cornell-box: exactly the published Cornell Box Data geometry (every vertex in the file is a
 *   published vertex x 0.001, every published vertex is in the file), the published extents, the
 *   stated albedos, the published camera, one point light 1 cm under the light patch;
 * - closed-sphere: watertight (positions welded exactly, every edge shared by exactly two
 *   triangles in opposite directions, Euler characteristic 2), facing inward;
 * - box-room-hole: closed except for the window (boundary edges = the window's rim), facing
 *   inward, the camera looking at the floor patch that the sun reaches through the window;
 * - maze: closed outward-facing wall boxes, light above the walls, real occlusion;
 * - all: no dropped triangles, no warnings, vertex normals agree with the CCW winding.
 *
 * Counts and constants here are the generator's; change both together. */
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "pf_gltf.h"
#include "pf_scene.h"

#define CORNELL_PATH SOFTGI_SOURCE_DIR "/scenes/cornell-box/cornell-box.gltf"
#define SPHERE_PATH SOFTGI_SOURCE_DIR "/scenes/closed-sphere/closed-sphere.gltf"
#define ROOM_PATH SOFTGI_SOURCE_DIR "/scenes/box-room-hole/box-room-hole.gltf"
#define MAZE_PATH SOFTGI_SOURCE_DIR "/scenes/maze/maze.gltf"

#define EPS 1e-6f

/* ------------------------------------------------------------------------------------------ */
/* helpers                                                                                     */

static void load(pf_scene *s, const char *path)
{
    pf_error err;
    memset(&err, 0, sizeof err);
    pf_result r = pf_gltf_load(s, path, NULL, &err);
    if (r != PF_OK) print_error("%s\n", err.message);
    assert_int_equal(r, PF_OK);
}

static void assert_near(double got, double want, double tol)
{
    if (!(fabs(got - want) <= tol)) print_error("got %.9g, want %.9g (tolerance %g)\n", got, want, tol);
    assert_true(fabs(got - want) <= tol);
}

static void assert_v3_near(pf_vec3 got, pf_vec3 want, double tol)
{
    assert_near(got.x, want.x, tol);
    assert_near(got.y, want.y, tol);
    assert_near(got.z, want.z, tol);
}

static uint32_t find_material(const pf_scene *s, const char *name)
{
    for (uint32_t i = 0; i < s->material_count; i++)
        if (strcmp(s->materials[i].name, name) == 0) return i;
    print_error("no material named '%s'\n", name);
    fail();
    return 0;
}

static void assert_material(const pf_scene *s, const char *name, float r, float g, float b, float emission)
{
    const pf_material *m = &s->materials[find_material(s, name)];
    assert_near(m->base_color[0], r, EPS);
    assert_near(m->base_color[1], g, EPS);
    assert_near(m->base_color[2], b, EPS);
    assert_near(m->base_color[3], 1.0, EPS);
    assert_int_equal(m->base_color_texture, -1);
    for (int k = 0; k < 3; k++) assert_near(m->emission[k], emission, EPS);
}

static pf_vec3 tri_vertex(const pf_scene *s, uint32_t t, int k) { return s->positions[s->indices[3 * t + k]]; }

/* Unnormalised geometric normal from the counter-clockwise winding. */
static pf_vec3 tri_normal(const pf_scene *s, uint32_t t)
{
    pf_vec3 a = tri_vertex(s, t, 0), b = tri_vertex(s, t, 1), c = tri_vertex(s, t, 2);
    return pf_v3_cross(pf_v3_sub(b, a), pf_v3_sub(c, a));
}

static pf_vec3 tri_centroid(const pf_scene *s, uint32_t t)
{
    pf_vec3 sum = pf_v3_add(pf_v3_add(tri_vertex(s, t, 0), tri_vertex(s, t, 1)), tri_vertex(s, t, 2));
    return pf_v3_scale(sum, 1.0f / 3.0f);
}

static uint32_t count_material(const pf_scene *s, uint32_t material)
{
    uint32_t n = 0;
    for (uint32_t t = 0; t < s->tri_count; t++) n += s->tri_material[t] == material;
    return n;
}

/* Signed volume enclosed by the triangles of `material` (all when material == UINT32_MAX),
 * measured from `ref`: positive when closed and facing outward, negative when facing inward. An
 * open mesh whose hole is planar gives its closed volume when `ref` lies in the hole's plane (the
 * missing cap would add a zero-height tetrahedron fan). */
static double signed_volume(const pf_scene *s, uint32_t material, pf_vec3 ref)
{
    double v = 0.0;
    for (uint32_t t = 0; t < s->tri_count; t++) {
        if (material != UINT32_MAX && s->tri_material[t] != material) continue;
        double p[3][3];
        for (int k = 0; k < 3; k++) {
            pf_vec3 q = tri_vertex(s, t, k);
            p[k][0] = (double)q.x - ref.x;
            p[k][1] = (double)q.y - ref.y;
            p[k][2] = (double)q.z - ref.z;
        }
        v += p[0][0] * (p[1][1] * p[2][2] - p[1][2] * p[2][1]) - p[0][1] * (p[1][0] * p[2][2] - p[1][2] * p[2][0]) +
             p[0][2] * (p[1][0] * p[2][1] - p[1][1] * p[2][0]);
    }
    return v / 6.0;
}

/* ---- exact welding and edge census ---- */

typedef struct keyed_vertex { pf_vec3 p; uint32_t vertex; } keyed_vertex;

static int cmp_position(const void *pa, const void *pb)
{
    const keyed_vertex *a = pa, *b = pb;
    if (a->p.x != b->p.x) return a->p.x < b->p.x ? -1 : 1;
    if (a->p.y != b->p.y) return a->p.y < b->p.y ? -1 : 1;
    if (a->p.z != b->p.z) return a->p.z < b->p.z ? -1 : 1;
    return a->vertex < b->vertex ? -1 : (a->vertex > b->vertex);
}

static int same_position(pf_vec3 a, pf_vec3 b) { return a.x == b.x && a.y == b.y && a.z == b.z; }

/* weld[v] = id shared by all vertices with bit-identical positions; returns the id count. */
static uint32_t weld_positions(const pf_scene *s, uint32_t *weld)
{
    keyed_vertex *kv = malloc(sizeof *kv * s->vertex_count);
    assert_non_null(kv);
    for (uint32_t v = 0; v < s->vertex_count; v++) kv[v] = (keyed_vertex){s->positions[v], v};
    qsort(kv, s->vertex_count, sizeof *kv, cmp_position);
    uint32_t ids = 0;
    for (uint32_t i = 0; i < s->vertex_count; i++) {
        if (i > 0 && !same_position(kv[i].p, kv[i - 1].p)) ids++;
        weld[kv[i].vertex] = ids;
    }
    free(kv);
    return s->vertex_count ? ids + 1 : 0;
}

typedef struct edge_use { uint32_t lo, hi; int dir; } edge_use;

static int cmp_edge(const void *pa, const void *pb)
{
    const edge_use *a = pa, *b = pb;
    if (a->lo != b->lo) return a->lo < b->lo ? -1 : 1;
    if (a->hi != b->hi) return a->hi < b->hi ? -1 : 1;
    return a->dir - b->dir;
}

/* One undirected edge of the welded mesh: how many triangle sides use it, and the sum of their
 * directions (+1 lo->hi, -1 hi->lo): 0 when every use is matched by one the other way. */
typedef struct edge_info { uint32_t lo, hi, uses; int balance; } edge_info;

typedef struct edge_census {
    uint32_t vertex_ids; /* welded vertices */
    uint32_t count;
    edge_info *edges;
    pf_vec3 *id_position; /* position of each welded id */
} edge_census;

static void census_free(edge_census *c)
{
    free(c->edges);
    free(c->id_position);
}

/* Census of the triangles of `material` (all when UINT32_MAX). */
static edge_census census_make(const pf_scene *s, uint32_t material)
{
    edge_census c;
    memset(&c, 0, sizeof c);
    uint32_t *weld = malloc(sizeof *weld * s->vertex_count);
    edge_use *uses = malloc(sizeof *uses * 3 * (size_t)s->tri_count);
    assert_non_null(weld);
    assert_non_null(uses);
    c.vertex_ids = weld_positions(s, weld);
    c.id_position = calloc(c.vertex_ids ? c.vertex_ids : 1, sizeof *c.id_position);
    assert_non_null(c.id_position);
    for (uint32_t v = 0; v < s->vertex_count; v++) c.id_position[weld[v]] = s->positions[v];
    size_t n = 0;
    for (uint32_t t = 0; t < s->tri_count; t++) {
        if (material != UINT32_MAX && s->tri_material[t] != material) continue;
        for (int k = 0; k < 3; k++) {
            uint32_t a = weld[s->indices[3 * t + k]], b = weld[s->indices[3 * t + (k + 1) % 3]];
            assert_int_not_equal(a, b); /* no collapsed sides after welding */
            uses[n++] = a < b ? (edge_use){a, b, +1} : (edge_use){b, a, -1};
        }
    }
    qsort(uses, n, sizeof *uses, cmp_edge);
    c.edges = malloc(sizeof *c.edges * (n ? n : 1));
    assert_non_null(c.edges);
    for (size_t i = 0; i < n;) {
        edge_info e = {uses[i].lo, uses[i].hi, 0, 0};
        for (; i < n && uses[i].lo == e.lo && uses[i].hi == e.hi; i++) {
            e.uses++;
            e.balance += uses[i].dir;
        }
        c.edges[c.count++] = e;
    }
    free(uses);
    free(weld);
    return c;
}

/* Every triangle's vertex normals agree with the normal of its counter-clockwise winding. */
static void assert_normals_follow_winding(const pf_scene *s)
{
    for (uint32_t t = 0; t < s->tri_count; t++) {
        pf_vec3 g = tri_normal(s, t);
        for (int k = 0; k < 3; k++) {
            pf_vec3 n = s->normals[s->indices[3 * t + k]];
            assert_near(pf_v3_length(n), 1.0, 1e-5);
            if (!(pf_v3_dot(g, n) > 0.0f))
                print_error("triangle %u vertex %d: normal (%g %g %g) against winding (%g %g %g)\n", t, k, n.x, n.y,
                            n.z, g.x, g.y, g.z);
            assert_true(pf_v3_dot(g, n) > 0.0f);
        }
    }
}

/* Segment p->q crosses triangle t strictly inside (Moeller-Trumbore, both sides). */
static int segment_hits(const pf_scene *s, uint32_t t, pf_vec3 p, pf_vec3 q)
{
    pf_vec3 a = tri_vertex(s, t, 0), e1 = pf_v3_sub(tri_vertex(s, t, 1), a), e2 = pf_v3_sub(tri_vertex(s, t, 2), a);
    pf_vec3 d = pf_v3_sub(q, p);
    pf_vec3 h = pf_v3_cross(d, e2);
    float det = pf_v3_dot(e1, h);
    if (fabsf(det) < 1e-12f) return 0;
    float inv = 1.0f / det;
    pf_vec3 sv = pf_v3_sub(p, a);
    float u = pf_v3_dot(sv, h) * inv;
    if (u < 0.0f || u > 1.0f) return 0;
    pf_vec3 qv = pf_v3_cross(sv, e1);
    float v = pf_v3_dot(d, qv) * inv;
    if (v < 0.0f || u + v > 1.0f) return 0;
    float tt = pf_v3_dot(e2, qv) * inv;
    return tt > 1e-4f && tt < 1.0f - 1e-4f;
}

static int segment_blocked(const pf_scene *s, pf_vec3 p, pf_vec3 q)
{
    for (uint32_t t = 0; t < s->tri_count; t++)
        if (segment_hits(s, t, p, q)) return 1;
    return 0;
}

/* Where the camera's central ray meets the plane y = 0. */
static pf_vec3 camera_floor_hit(const pf_camera *c)
{
    assert_true(c->forward.y < 0.0f);
    float t = -c->eye.y / c->forward.y;
    return pf_v3_add(c->eye, pf_v3_scale(c->forward, t));
}

/* ------------------------------------------------------------------------------------------ */
/* all scenes                                                                                  */

static const struct {
    const char *path;
    uint32_t triangles;
} all_scenes[] = {
    {CORNELL_PATH, 30},
    {SPHERE_PATH, 1280},
    {ROOM_PATH, 58},
    {MAZE_PATH, 482},
};

static void test_all_scenes_load_clean(void **state)
{
    (void)state;
    for (size_t i = 0; i < sizeof all_scenes / sizeof all_scenes[0]; i++) {
        pf_scene s;
        load(&s, all_scenes[i].path);
        assert_int_equal(s.tri_count, all_scenes[i].triangles);
        assert_int_equal(s.dropped_degenerate, 0);
        if (s.warnings[0]) print_error("%s: %s\n", all_scenes[i].path, s.warnings);
        assert_string_equal(s.warnings, "");
        assert_int_equal(s.camera_count, 1);
        assert_int_equal(s.light_count, 1);
        assert_int_equal(s.texture_count, 0);
        for (uint32_t t = 0; t < s.tri_count; t++) assert_true(s.tri_material[t] < s.material_count);
        pf_scene_free(&s);
    }
}

static void test_all_scenes_normals_follow_winding(void **state)
{
    (void)state;
    for (size_t i = 0; i < sizeof all_scenes / sizeof all_scenes[0]; i++) {
        pf_scene s;
        load(&s, all_scenes[i].path);
        assert_normals_follow_winding(&s);
        pf_scene_free(&s);
    }
}

/* ------------------------------------------------------------------------------------------ */
/* cornell-box                                                                                 */

/* Cornell Box Data, http://www.graphics.cornell.edu/online/box/data.html, in mm: every quad of
 * the room (floor, ceiling, back, right, left wall) and of the two blocks (top + 4 sides). */
static const float cornell_quads_mm[][4][3] = {
    {{552.8f, 0.0f, 0.0f}, {0.0f, 0.0f, 0.0f}, {0.0f, 0.0f, 559.2f}, {549.6f, 0.0f, 559.2f}},
    {{556.0f, 548.8f, 0.0f}, {556.0f, 548.8f, 559.2f}, {0.0f, 548.8f, 559.2f}, {0.0f, 548.8f, 0.0f}},
    {{549.6f, 0.0f, 559.2f}, {0.0f, 0.0f, 559.2f}, {0.0f, 548.8f, 559.2f}, {556.0f, 548.8f, 559.2f}},
    {{0.0f, 0.0f, 559.2f}, {0.0f, 0.0f, 0.0f}, {0.0f, 548.8f, 0.0f}, {0.0f, 548.8f, 559.2f}},
    {{552.8f, 0.0f, 0.0f}, {549.6f, 0.0f, 559.2f}, {556.0f, 548.8f, 559.2f}, {556.0f, 548.8f, 0.0f}},
    {{130.0f, 165.0f, 65.0f}, {82.0f, 165.0f, 225.0f}, {240.0f, 165.0f, 272.0f}, {290.0f, 165.0f, 114.0f}},
    {{290.0f, 0.0f, 114.0f}, {290.0f, 165.0f, 114.0f}, {240.0f, 165.0f, 272.0f}, {240.0f, 0.0f, 272.0f}},
    {{130.0f, 0.0f, 65.0f}, {130.0f, 165.0f, 65.0f}, {290.0f, 165.0f, 114.0f}, {290.0f, 0.0f, 114.0f}},
    {{82.0f, 0.0f, 225.0f}, {82.0f, 165.0f, 225.0f}, {130.0f, 165.0f, 65.0f}, {130.0f, 0.0f, 65.0f}},
    {{240.0f, 0.0f, 272.0f}, {240.0f, 165.0f, 272.0f}, {82.0f, 165.0f, 225.0f}, {82.0f, 0.0f, 225.0f}},
    {{423.0f, 330.0f, 247.0f}, {265.0f, 330.0f, 296.0f}, {314.0f, 330.0f, 456.0f}, {472.0f, 330.0f, 406.0f}},
    {{423.0f, 0.0f, 247.0f}, {423.0f, 330.0f, 247.0f}, {472.0f, 330.0f, 406.0f}, {472.0f, 0.0f, 406.0f}},
    {{472.0f, 0.0f, 406.0f}, {472.0f, 330.0f, 406.0f}, {314.0f, 330.0f, 456.0f}, {314.0f, 0.0f, 456.0f}},
    {{314.0f, 0.0f, 456.0f}, {314.0f, 330.0f, 456.0f}, {265.0f, 330.0f, 296.0f}, {265.0f, 0.0f, 296.0f}},
    {{265.0f, 0.0f, 296.0f}, {265.0f, 330.0f, 296.0f}, {423.0f, 330.0f, 247.0f}, {423.0f, 0.0f, 247.0f}},
};
#define CORNELL_QUADS (sizeof cornell_quads_mm / sizeof cornell_quads_mm[0])

static pf_vec3 cornell_m(const float p[3]) { return pf_v3(p[0] * 0.001f, p[1] * 0.001f, p[2] * 0.001f); }

/* Which published quad a point is a corner of: 0..4 room, 5..9 short block, 10..14 tall block;
 * -1 for none. (No corner is shared between the room and a block.) */
static int published_quad_of(pf_vec3 p)
{
    for (size_t q = 0; q < CORNELL_QUADS; q++)
        for (int k = 0; k < 4; k++) {
            pf_vec3 d = pf_v3_sub(p, cornell_m(cornell_quads_mm[q][k]));
            if (fabsf(d.x) <= EPS && fabsf(d.y) <= EPS && fabsf(d.z) <= EPS) return (int)q;
        }
    return -1;
}

static int is_published_vertex(pf_vec3 p) { return published_quad_of(p) >= 0; }

/* Middle of a block's top face (quad 5 or 10), dropped to half the block's height. */
static pf_vec3 block_core(size_t top_quad)
{
    pf_vec3 sum = pf_v3(0.0f, 0.0f, 0.0f);
    for (int k = 0; k < 4; k++) sum = pf_v3_add(sum, cornell_m(cornell_quads_mm[top_quad][k]));
    sum = pf_v3_scale(sum, 0.25f);
    return pf_v3(sum.x, sum.y * 0.5f, sum.z);
}

static void test_cornell_box_geometry_is_the_published_data(void **state)
{
    (void)state;
    pf_scene s;
    load(&s, CORNELL_PATH);
    assert_int_equal(s.tri_count, 30); /* 5 room quads + 2 x 5 block quads, 2 triangles each */

    /* extents: x up to the red wall's 556.0, y to the ceiling's 548.8, z to the back wall's 559.2 */
    assert_v3_near(s.bounds_min, pf_v3(0.0f, 0.0f, 0.0f), EPS);
    assert_v3_near(s.bounds_max, pf_v3(0.556f, 0.5488f, 0.5592f), EPS);

    /* nothing invented, nothing missing */
    for (uint32_t v = 0; v < s.vertex_count; v++) {
        if (!is_published_vertex(s.positions[v]))
            print_error("vertex %u (%g %g %g) is not in the Cornell data\n", v, s.positions[v].x, s.positions[v].y,
                        s.positions[v].z);
        assert_true(is_published_vertex(s.positions[v]));
    }
    for (size_t q = 0; q < CORNELL_QUADS; q++)
        for (int k = 0; k < 4; k++) {
            pf_vec3 want = cornell_m(cornell_quads_mm[q][k]);
            int found = 0;
            for (uint32_t v = 0; v < s.vertex_count && !found; v++) {
                pf_vec3 d = pf_v3_sub(s.positions[v], want);
                found = fabsf(d.x) <= EPS && fabsf(d.y) <= EPS && fabsf(d.z) <= EPS;
            }
            assert_true(found);
        }

    /* The room is sealed except for its open front (z = 0) and the blocks' missing bottoms
     * (y = 0): every other edge joins two triangles wound in opposite directions. */
    edge_census c = census_make(&s, UINT32_MAX);
    uint32_t open = 0;
    for (uint32_t e = 0; e < c.count; e++) {
        if (c.edges[e].uses == 2) {
            assert_int_equal(c.edges[e].balance, 0);
            continue;
        }
        assert_int_equal(c.edges[e].uses, 1);
        pf_vec3 a = c.id_position[c.edges[e].lo], b = c.id_position[c.edges[e].hi];
        assert_true((a.z == 0.0f && b.z == 0.0f) || (a.y == 0.0f && b.y == 0.0f));
        open++;
    }
    assert_int_equal(open, 4 + 4 + 4); /* front rim; short and tall block footprints */
    census_free(&c);

    /* Room surfaces face the inside of the room, block faces face out of their (convex) block. */
    const pf_vec3 room_centre = pf_v3(0.278f, 0.2744f, 0.2796f);
    for (uint32_t t = 0; t < s.tri_count; t++) {
        pf_vec3 n = tri_normal(&s, t), m = tri_centroid(&s, t);
        int q = published_quad_of(tri_vertex(&s, t, 0));
        for (int k = 1; k < 3; k++) { /* all three corners belong to the same object */
            int qk = published_quad_of(tri_vertex(&s, t, k));
            assert_int_equal(q < 5 ? 0 : (q < 10 ? 1 : 2), qk < 5 ? 0 : (qk < 10 ? 1 : 2));
        }
        if (q < 5)
            assert_true(pf_v3_dot(n, pf_v3_sub(room_centre, m)) > 0.0f);
        else
            assert_true(pf_v3_dot(n, pf_v3_sub(m, block_core(q < 10 ? 5 : 10))) > 0.0f);
    }
    pf_scene_free(&s);
}

static void test_cornell_box_materials(void **state)
{
    (void)state;
    pf_scene s;
    load(&s, CORNELL_PATH);
    assert_int_equal(s.material_count, 3);
    /* The published spectra integrated against the CIE 1931 CMFs under white light, to linear
     * sRGB, white-balanced (scenes/cornell-box/README.md). */
    assert_material(&s, "white", 0.738f, 0.736f, 0.738f, 0.0f);
    assert_material(&s, "red", 0.472f, 0.047f, 0.049f, 0.0f);
    assert_material(&s, "green", 0.088f, 0.399f, 0.084f, 0.0f);

    uint32_t red = find_material(&s, "red"), green = find_material(&s, "green");
    assert_int_equal(count_material(&s, red), 2);
    assert_int_equal(count_material(&s, green), 2);
    assert_int_equal(count_material(&s, find_material(&s, "white")), 26);
    for (uint32_t t = 0; t < s.tri_count; t++)
        for (int k = 0; k < 3; k++) {
            pf_vec3 p = tri_vertex(&s, t, k);
            if (s.tri_material[t] == red) assert_true(p.x >= 0.5496f - EPS); /* the left wall, x ~ 0.55 */
            if (s.tri_material[t] == green) assert_true(p.x == 0.0f);       /* the right wall, x = 0 */
        }
    pf_scene_free(&s);
}

static void test_cornell_box_camera_and_light(void **state)
{
    (void)state;
    pf_scene s;
    load(&s, CORNELL_PATH);
    assert_int_equal(s.camera_count, 1);
    const pf_camera *c = &s.cameras[0];
    /* published: position (278, 273, -800) mm, direction +Z, up +Y, 35 mm lens, 25 mm film */
    assert_v3_near(c->eye, pf_v3(0.278f, 0.273f, -0.8f), EPS);
    assert_v3_near(c->forward, pf_v3(0.0f, 0.0f, 1.0f), EPS);
    assert_v3_near(c->up, pf_v3(0.0f, 1.0f, 0.0f), EPS);
    assert_v3_near(c->right, pf_v3(-1.0f, 0.0f, 0.0f), EPS); /* right-handed: the red wall (x ~ 0.55) is on the left */
    assert_near(c->yfov, 2.0 * atan(12.5 / 35.0), EPS);
    assert_near(c->aspect, 1.0, EPS);

    assert_int_equal(s.light_count, 1);
    const pf_light *l = &s.lights[0];
    assert_int_equal(l->type, PF_LIGHT_POINT);
    /* the centre of the published light patch 213..343 x 227..332 mm, 1 cm under the ceiling */
    assert_v3_near(l->position, pf_v3(0.278f, 0.5388f, 0.2795f), EPS);
    assert_v3_near(l->color, pf_v3(1.0f, 1.0f, 1.0f), EPS);
    assert_near(l->intensity, 1.0, EPS);
    /* irradiance on the floor right under it, E = I / r^2, is of order 1-10 W/m^2 */
    float e_floor = l->intensity / (l->position.y * l->position.y);
    assert_true(e_floor > 1.0f && e_floor < 10.0f);
    pf_scene_free(&s);
}

/* ------------------------------------------------------------------------------------------ */
/* closed-sphere                                                                               */

static void test_closed_sphere_is_watertight(void **state)
{
    (void)state;
    pf_scene s;
    load(&s, SPHERE_PATH);
    assert_int_equal(s.tri_count, 1280);
    edge_census c = census_make(&s, UINT32_MAX);
    for (uint32_t e = 0; e < c.count; e++) {
        if (c.edges[e].uses != 2 || c.edges[e].balance != 0)
            print_error("edge %u-%u: %u uses, balance %d\n", c.edges[e].lo, c.edges[e].hi, c.edges[e].uses,
                        c.edges[e].balance);
        assert_int_equal(c.edges[e].uses, 2);
        assert_int_equal(c.edges[e].balance, 0);
    }
    /* a closed genus-0 surface: V - E + F = 2 */
    assert_int_equal(c.vertex_ids, 642);
    assert_int_equal(c.count, 1920);
    assert_int_equal((int64_t)c.vertex_ids - (int64_t)c.count + (int64_t)s.tri_count, 2);
    census_free(&c);
    pf_scene_free(&s);
}

static void test_closed_sphere_faces_inward(void **state)
{
    (void)state;
    pf_scene s;
    load(&s, SPHERE_PATH);
    for (uint32_t v = 0; v < s.vertex_count; v++) {
        pf_vec3 p = s.positions[v];
        assert_near(pf_v3_length(p), 1.0, EPS);
        assert_true(pf_v3_dot(s.normals[v], p) < 0.0f);
    }
    for (uint32_t t = 0; t < s.tri_count; t++) assert_true(pf_v3_dot(tri_normal(&s, t), tri_centroid(&s, t)) < 0.0f);
    /* inward: negative volume, a little under the ball's 4 pi / 3 (the facets are chords) */
    double vol = signed_volume(&s, UINT32_MAX, pf_v3(0.0f, 0.0f, 0.0f));
    assert_true(vol < 0.0);
    assert_true(-vol > 0.97 * 4.0 * PF_PI / 3.0 && -vol < 4.0 * PF_PI / 3.0);
    assert_v3_near(s.bounds_min, pf_v3(-1.0f, -1.0f, -1.0f), EPS);
    assert_v3_near(s.bounds_max, pf_v3(1.0f, 1.0f, 1.0f), EPS);
    pf_scene_free(&s);
}

static void test_closed_sphere_material_camera_light(void **state)
{
    (void)state;
    pf_scene s;
    load(&s, SPHERE_PATH);
    assert_int_equal(s.material_count, 1);
    assert_material(&s, "white_emissive", 0.5f, 0.5f, 0.5f, 1.0f);
    assert_v3_near(s.cameras[0].eye, pf_v3(0.0f, 0.0f, 0.0f), EPS);
    assert_int_equal(s.lights[0].type, PF_LIGHT_POINT);
    assert_v3_near(s.lights[0].position, pf_v3(0.0f, 0.0f, 0.0f), EPS);
    assert_near(s.lights[0].intensity, 1.0, EPS);
    assert_v3_near(s.lights[0].color, pf_v3(1.0f, 1.0f, 1.0f), EPS);
    pf_scene_free(&s);
}

/* ------------------------------------------------------------------------------------------ */
/* box-room-hole                                                                               */

/* the window in the z = -2 wall */
#define WIN_X0 -0.75f
#define WIN_X1 0.75f
#define WIN_Y0 1.0f
#define WIN_Y1 2.2f
#define WIN_Z -2.0f

static int on_window_rim(pf_vec3 p)
{
    if (p.z != WIN_Z || p.x < WIN_X0 || p.x > WIN_X1 || p.y < WIN_Y0 || p.y > WIN_Y1) return 0;
    return p.x == WIN_X0 || p.x == WIN_X1 || p.y == WIN_Y0 || p.y == WIN_Y1;
}

static void test_box_room_is_closed_except_the_window(void **state)
{
    (void)state;
    pf_scene s;
    load(&s, ROOM_PATH);
    assert_int_equal(s.tri_count, 58);
    assert_v3_near(s.bounds_min, pf_v3(-2.0f, 0.0f, -2.0f), EPS);
    assert_v3_near(s.bounds_max, pf_v3(2.0f, 3.0f, 2.0f), EPS);
    edge_census c = census_make(&s, UINT32_MAX);
    double rim = 0.0;
    for (uint32_t e = 0; e < c.count; e++) {
        pf_vec3 a = c.id_position[c.edges[e].lo], b = c.id_position[c.edges[e].hi];
        if (c.edges[e].uses == 1) {
            /* boundary: only around the hole, both ends on the rim, along one side of it */
            assert_true(on_window_rim(a) && on_window_rim(b));
            assert_true(a.x == b.x || a.y == b.y);
            rim += pf_v3_length(pf_v3_sub(a, b));
        } else {
            assert_int_equal(c.edges[e].uses, 2);
            assert_int_equal(c.edges[e].balance, 0);
        }
    }
    assert_near(rim, 2.0 * ((WIN_X1 - WIN_X0) + (WIN_Y1 - WIN_Y0)), 1e-5);
    census_free(&c);
    /* Inward everywhere: measured from a point in the window's plane the open mesh encloses
     * exactly the room, 4 x 3 x 4 m, with a negative sign. */
    assert_near(signed_volume(&s, UINT32_MAX, pf_v3(0.0f, 1.6f, WIN_Z)), -48.0, 1e-4);
    assert_material(&s, "wall", 0.8f, 0.8f, 0.8f, 0.0f);
    assert_material(&s, "floor", 0.6f, 0.6f, 0.6f, 0.0f);
    pf_scene_free(&s);
}

static void test_box_room_sun_reaches_the_patch_the_camera_sees(void **state)
{
    (void)state;
    pf_scene s;
    load(&s, ROOM_PATH);
    const pf_light *sun = &s.lights[0];
    assert_int_equal(sun->type, PF_LIGHT_DIRECTIONAL);
    assert_near(sun->intensity, 3.0, EPS);
    assert_v3_near(sun->color, pf_v3(1.0f, 1.0f, 1.0f), EPS);
    const float k = 1.0f / sqrtf(14.0f);
    assert_v3_near(sun->direction, pf_v3(k, -2.0f * k, 3.0f * k), EPS);

    /* The camera stands inside the room and its central ray lands on the floor at a point that
     * the sun reaches through the window: going back from there against the sun's travel
     * direction meets the z = -2 wall inside the window, and nothing is in between. */
    const pf_camera *c = &s.cameras[0];
    assert_true(fabsf(c->eye.x) < 2.0f && c->eye.y > 0.0f && c->eye.y < 3.0f && fabsf(c->eye.z) < 2.0f);
    pf_vec3 h = camera_floor_hit(c);
    assert_true(h.x > -2.0f && h.x < 2.0f && h.z > -2.0f && h.z < 2.0f);
    float t = (h.z - WIN_Z) / sun->direction.z; /* h - t d lies on z = -2 */
    pf_vec3 w = pf_v3_sub(h, pf_v3_scale(sun->direction, t));
    assert_near(w.z, WIN_Z, 1e-5);
    assert_true(w.x > WIN_X0 && w.x < WIN_X1 && w.y > WIN_Y0 && w.y < WIN_Y1);
    pf_vec3 outside = pf_v3_sub(h, pf_v3_scale(sun->direction, t + 1.0f));
    assert_false(segment_blocked(&s, pf_v3_add(h, pf_v3(0.0f, 1e-3f, 0.0f)), outside));
    /* ... while a floor point the window does not serve is in shadow */
    pf_vec3 dark = pf_v3(-1.5f, 1e-3f, -1.5f);
    assert_true(segment_blocked(&s, dark, pf_v3_sub(dark, pf_v3_scale(sun->direction, 10.0f))));
    pf_scene_free(&s);
}

/* ------------------------------------------------------------------------------------------ */
/* maze                                                                                        */

static void test_maze_walls_are_closed_outward_boxes(void **state)
{
    (void)state;
    pf_scene s;
    load(&s, MAZE_PATH);
    assert_int_equal(s.tri_count, 482); /* 40 boxes x 12 + the floor's 2 */
    uint32_t wall = find_material(&s, "wall"), floor = find_material(&s, "floor");
    assert_material(&s, "wall", 0.75f, 0.75f, 0.75f, 0.0f);
    assert_material(&s, "floor", 0.6f, 0.6f, 0.6f, 0.0f);
    assert_int_equal(count_material(&s, wall), 480);
    assert_int_equal(count_material(&s, floor), 2);

    /* Boxes touch flush, so an edge may be shared by more than two triangles, but each box is
     * closed: every edge is used as often in one direction as in the other. */
    edge_census c = census_make(&s, wall);
    for (uint32_t e = 0; e < c.count; e++) {
        assert_true(c.edges[e].uses >= 2 && c.edges[e].uses % 2 == 0);
        assert_int_equal(c.edges[e].balance, 0);
    }
    census_free(&c);
    /* Outward, and never overlapping: the signed volume is the walls' true volume, 11.88 m^3
     * (118.8 m of 0.1 m thick, 1.5 m high wall). */
    assert_near(signed_volume(&s, wall, pf_v3(0.0f, 0.0f, 0.0f)), 11.88, 1e-3);

    for (uint32_t t = 0; t < s.tri_count; t++)
        for (int k = 0; k < 3; k++) {
            pf_vec3 p = tri_vertex(&s, t, k);
            if (s.tri_material[t] == wall) {
                assert_true(fabsf(p.x) <= 4.05f + EPS && fabsf(p.z) <= 4.05f + EPS);
                assert_true(p.y == 0.0f || p.y == 1.5f);
            } else {
                assert_true(p.y == 0.0f);
            }
        }
    pf_scene_free(&s);
}

static void test_maze_light_and_camera_overlook_an_occluded_maze(void **state)
{
    (void)state;
    pf_scene s;
    load(&s, MAZE_PATH);
    const pf_light *l = &s.lights[0];
    assert_int_equal(l->type, PF_LIGHT_POINT);
    assert_v3_near(l->position, pf_v3(0.5f, 4.0f, 0.5f), EPS);
    assert_near(l->intensity, 40.0, EPS);
    assert_true(l->position.y > 1.5f);

    const pf_camera *c = &s.cameras[0];
    assert_true(c->eye.y > 1.5f);
    pf_vec3 h = camera_floor_hit(c);
    assert_true(fabsf(h.x) < 4.0f && fabsf(h.z) < 4.0f);

    /* Heavy occlusion: of 16 x 16 floor points spread over the maze (none on a wall line), the
     * light sees some directly but far from all (about a third). */
    int lit = 0;
    for (int i = 0; i < 16; i++)
        for (int j = 0; j < 16; j++)
            lit += !segment_blocked(&s, pf_v3(-3.75f + 0.5f * (float)i, 1e-3f, -3.75f + 0.5f * (float)j), l->position);
    print_message("maze: %d of 256 floor points see the light\n", lit);
    assert_true(lit >= 26 && lit <= 154); /* 10% .. 60% */
    pf_scene_free(&s);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_all_scenes_load_clean),
        cmocka_unit_test(test_all_scenes_normals_follow_winding),
        cmocka_unit_test(test_cornell_box_geometry_is_the_published_data),
        cmocka_unit_test(test_cornell_box_materials),
        cmocka_unit_test(test_cornell_box_camera_and_light),
        cmocka_unit_test(test_closed_sphere_is_watertight),
        cmocka_unit_test(test_closed_sphere_faces_inward),
        cmocka_unit_test(test_closed_sphere_material_camera_light),
        cmocka_unit_test(test_box_room_is_closed_except_the_window),
        cmocka_unit_test(test_box_room_sun_reaches_the_patch_the_camera_sees),
        cmocka_unit_test(test_maze_walls_are_closed_outward_boxes),
        cmocka_unit_test(test_maze_light_and_camera_overlook_an_occluded_maze),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
