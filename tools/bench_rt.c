/* bench_rt: what keeping Embree's scene up to date for moved geometry costs
 * (pf_rt_update, pf_rt.h "Moving geometry"; issue 19 item 2), against
 * building the whole Embree scene again, and what the dynamic split costs
 * the queries. A measurement, not part of the build and never a test.
 *
 *   cmake --build build -j2     (libsoftgi_core.a)
 *   cc -O2 -std=c17 -ffp-contract=off -D_DEFAULT_SOURCE -Isrc/base -Isrc/base/simd -Isrc/scene \
 *       -Isrc/platform tools/bench_rt.c build/libsoftgi_core.a -o build/bench_rt \
 *       $(pkg-config --libs tinygltf libcjson spng libturbojpeg) -lembree3 -lmeshoptimizer -ltinyexr \
 *       -lstdc++ -lm -pthread
 *   ./build/bench_rt [--threads N] [--frames N] [--tris N] [--scenes DIR]
 *
 * Two cases:
 * - scenes/anim-box/anim-box.gltf (1296 triangles, 3 animated primitives:
 *   12, 132 and 512 triangles), posed by pf_anim_pose at the frames of
 *   anim-box.seq.json (t = 4 f / (frames - 1));
 * - Sibenik (DIR/sibenik/sibenik.gltf, 75284 triangles) with a moving
 *   object appended in memory: a UV sphere of about --tris triangles
 *   (default 4000), radius 1, flying through the nave while it turns
 *   (every vertex moves every frame), reported to pf_rt_update as one
 *   moved primitive.
 * For each: the median over the frames of
 *   rebuild all    pf_rt_create of the posed scene (device, one BVH over
 *                  every triangle: what softgi sequence did per moved
 *                  frame before pf_rt_update; the device alone is timed
 *                  apart as "of it, device")
 *   update REBUILD pf_rt_update(..., PF_RT_REBUILD): the moved primitives'
 *                  BVHs rebuilt, then the top scene
 *   update REFIT   pf_rt_update(..., PF_RT_REFIT) (its first frame, which
 *                  builds the refittable BVHs, left out of the median)
 * and the queries on the last pose: closest hits of 640x480 camera rays
 * and occlusion of 307200 random rays from inside the scene, one geometry
 * (pf_rt_create) against the split (pf_rt_create_dynamic), each the best
 * of 5. Embree builds with --threads threads (default 1). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "pf_anim.h"
#include "pf_fpenv.h"
#include "pf_gltf.h"
#include "pf_rt.h"
#include "pf_timer.h"

typedef struct bench_case {
    const char *name;
    pf_scene scene;
    pf_anim anim;          /* loaded, or made up for the appended object */
    pf_anim_moved *moved;  /* anim.prim_count */
    /* the appended object (Sibenik): its rest positions */
    uint32_t obj_first, obj_count;
    pf_vec3 *obj_rest;
    pf_vec3 path_a, path_b; /* its centre flies from a to b */
} bench_case;

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

static double median(double *v, uint32_t n)
{
    qsort(v, n, sizeof *v, cmp_double);
    return n ? (n & 1 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2])) : 0.0;
}

static void die(const char *what, const pf_error *e)
{
    fprintf(stderr, "bench_rt: %s: %s\n", what, e->message);
    exit(1);
}

/* A UV sphere (nu x nv quads, two triangles each) of radius 1 at the
 * origin appended to the scene, with a made-up anim naming it dynamic. */
static void append_sphere(bench_case *c, uint32_t tris)
{
    pf_scene *s = &c->scene;
    uint32_t nv = (uint32_t)sqrt(tris / 2.5) + 1, nu = (tris / 2 + nv - 1) / nv;
    uint32_t v0 = s->vertex_count, t0 = s->tri_count, nvtx = (nu + 1) * (nv + 1), ntri = 2 * nu * nv;
    s->positions = realloc(s->positions, sizeof(pf_vec3) * (v0 + nvtx + 1));
    s->normals = realloc(s->normals, sizeof(pf_vec3) * (v0 + nvtx));
    s->uvs = realloc(s->uvs, sizeof(pf_vec2) * (v0 + nvtx));
    s->indices = realloc(s->indices, 3 * sizeof(uint32_t) * (t0 + ntri));
    s->tri_material = realloc(s->tri_material, sizeof(uint32_t) * (t0 + ntri));
    c->obj_rest = malloc(sizeof(pf_vec3) * nvtx);
    if (!s->positions || !s->normals || !s->uvs || !s->indices || !s->tri_material || !c->obj_rest) {
        fprintf(stderr, "bench_rt: out of memory\n");
        exit(1);
    }
    for (uint32_t j = 0; j <= nv; j++)
        for (uint32_t i = 0; i <= nu; i++) {
            double th = 3.14159265358979 * j / nv, ph = 6.28318530717959 * i / nu;
            pf_vec3 n = pf_v3((float)(sin(th) * cos(ph)), (float)cos(th), (float)(sin(th) * sin(ph)));
            uint32_t k = j * (nu + 1) + i;
            c->obj_rest[k] = n;
            s->positions[v0 + k] = n;
            s->normals[v0 + k] = n;
            s->uvs[v0 + k] = (pf_vec2){(float)i / nu, (float)j / nv};
        }
    s->positions[v0 + nvtx] = s->positions[v0];
    uint32_t t = t0;
    for (uint32_t j = 0; j < nv; j++)
        for (uint32_t i = 0; i < nu; i++) {
            uint32_t a = v0 + j * (nu + 1) + i, b = a + 1, cc = a + nu + 1, d = cc + 1;
            const uint32_t q[6] = {a, cc, b, b, cc, d};
            memcpy(&s->indices[3 * (size_t)t], q, sizeof q);
            s->tri_material[t] = s->tri_material[t + 1] = 0;
            t += 2;
        }
    s->vertex_count += nvtx;
    s->tri_count += ntri;
    c->obj_first = v0;
    c->obj_count = nvtx;
    memset(&c->anim, 0, sizeof c->anim);
    c->anim.prim_count = c->anim.dynamic_count = 1;
    c->anim.prims = calloc(1, sizeof *c->anim.prims);
    c->anim.prims[0] = (pf_anim_prim){.vertex_first = v0, .vertex_count = nvtx, .tri_first = t0, .tri_count = ntri,
                                      .dynamic = 1};
}

/* Frame f of n: the scene posed (anim-box) or the object moved (Sibenik). */
static void pose(bench_case *c, uint32_t f, uint32_t n)
{
    double s = n > 1 ? (double)f / (n - 1) : 0.0;
    pf_error e;
    if (!c->obj_rest) {
        if (pf_anim_pose(&c->scene, c->moved, NULL, &c->anim, PF_ANIM_ALL, 4.0 * s, &e) != PF_OK) die("pose", &e);
        return;
    }
    pf_vec3 at = pf_v3_add(pf_v3_scale(c->path_a, (float)(1 - s)), pf_v3_scale(c->path_b, (float)s));
    float ca = (float)cos(3.0 * s), sa = (float)sin(3.0 * s);
    for (uint32_t k = 0; k < c->obj_count; k++) {
        pf_vec3 p = c->obj_rest[k];
        c->scene.positions[c->obj_first + k] = pf_v3(at.x + ca * p.x + sa * p.z, at.y + p.y, at.z - sa * p.x + ca * p.z);
    }
    const pf_anim_prim *ap = &c->anim.prims[0];
    c->moved[0] = (pf_anim_moved){.vertex_first = ap->vertex_first, .vertex_count = ap->vertex_count,
                                  .tri_first = ap->tri_first, .tri_count = ap->tri_count, .moved = 1};
    if (pf_scene_validate(&c->scene, &e) != PF_OK) die("the moved object", &e);
}

static uint64_t rng;
static float unit(void)
{
    rng = rng * 6364136223846793005ull + 1442695040888963407ull;
    return (float)(rng >> 40) * (1.0f / 16777216.0f);
}

static double time_queries(const pf_rt *rt, const pf_ray *rays, pf_hit *hits, uint8_t *occ, uint32_t n, int occlusion)
{
    double best = 1e30;
    for (int it = 0; it < 5; it++) {
        double t0 = pf_time_now();
        if (occlusion) pf_rt_occluded(rt, rays, occ, n);
        else pf_rt_intersect(rt, rays, hits, n);
        double t = pf_time_now() - t0;
        if (t < best) best = t;
    }
    return best;
}

static void run(bench_case *c, uint32_t threads, uint32_t frames, pf_isa isa)
{
    pf_error e;
    pf_scene *s = &c->scene;
    uint32_t dyn_tris = 0, dyn_prims = 0;
    for (uint32_t p = 0; p < c->anim.prim_count; p++)
        if (c->anim.prims[p].dynamic) dyn_tris += c->anim.prims[p].tri_count, dyn_prims++;
    c->moved = calloc(c->anim.prim_count, sizeof *c->moved);
    double *full = calloc(frames, sizeof(double)), *dev = calloc(frames, sizeof(double));
    double *reb = calloc(frames, sizeof(double)), *ref = calloc(frames, sizeof(double));
    pf_rt *rb, *rf;
    pose(c, 0, frames);
    if (pf_rt_create_dynamic(&rb, s, &c->anim, isa, threads, &e) != PF_OK) die("create", &e);
    if (pf_rt_create_dynamic(&rf, s, &c->anim, isa, threads, &e) != PF_OK) die("create", &e);
    double first_refit = 0.0;
    for (uint32_t f = 1; f < frames; f++) {
        pose(c, f, frames);
        double t0 = pf_time_now();
        pf_rt *one;
        if (pf_rt_create(&one, s, isa, threads, &e) != PF_OK) die("create", &e);
        full[f - 1] = pf_time_now() - t0;
        pf_rt_destroy(one);
        /* the device alone, near enough: a pf_rt over the first triangle */
        pf_rt *tiny;
        uint32_t saved = s->tri_count;
        s->tri_count = 1;
        t0 = pf_time_now();
        if (pf_rt_create(&tiny, s, isa, threads, &e) != PF_OK) die("create", &e);
        dev[f - 1] = pf_time_now() - t0;
        s->tri_count = saved;
        pf_rt_destroy(tiny);
        t0 = pf_time_now();
        if (pf_rt_update(rb, c->moved, c->anim.prim_count, PF_RT_REBUILD, &e) != PF_OK) die("update", &e);
        reb[f - 1] = pf_time_now() - t0;
        t0 = pf_time_now();
        if (pf_rt_update(rf, c->moved, c->anim.prim_count, PF_RT_REFIT, &e) != PF_OK) die("update", &e);
        ref[f - 1] = pf_time_now() - t0;
        if (f == 1) first_refit = ref[0];
    }
    uint32_t n = frames - 1;
    double m_full = median(full, n), m_dev = median(dev, n), m_reb = median(reb, n);
    double m_ref = n > 1 ? median(ref + 1, n - 1) : ref[0];

    /* queries on the last pose */
    enum { W = 640, H = 480 };
    pf_ray *rays = malloc(sizeof(pf_ray) * W * H), *rnd = malloc(sizeof(pf_ray) * W * H);
    pf_hit *hits = malloc(sizeof(pf_hit) * W * H);
    uint8_t *occ = malloc(W * H);
    pf_vec3 lo = s->bounds_min, ext = pf_v3_sub(s->bounds_max, s->bounds_min);
    float diag = sqrtf(pf_v3_dot(ext, ext));
    pf_camera cam;
    if (s->camera_count) cam = s->cameras[0];
    else if (pf_camera_look_at(&cam, pf_v3(-18, -11, 0), pf_v3(10, -8, 0), pf_radians(70), &e) != PF_OK)
        die("camera", &e);
    for (uint32_t y = 0; y < H; y++)
        for (uint32_t x = 0; x < W; x++)
            rays[y * W + x] = (pf_ray){cam.eye, 0.0f, pf_camera_ray_dir(&cam, W, H, x + 0.5f, y + 0.5f), INFINITY};
    rng = 1;
    for (uint32_t i = 0; i < W * H; i++) {
        pf_vec3 o = pf_v3(lo.x + ext.x * (0.1f + 0.8f * unit()), lo.y + ext.y * (0.1f + 0.8f * unit()),
                          lo.z + ext.z * (0.1f + 0.8f * unit()));
        float z = 2 * unit() - 1, ph = 6.2831853f * unit(), r = sqrtf(fmaxf(0.0f, 1 - z * z));
        rnd[i] = (pf_ray){o, 0.0f, pf_v3(r * cosf(ph), z, r * sinf(ph)), 0.3f * diag};
    }
    pf_rt *one;
    if (pf_rt_create(&one, s, isa, threads, &e) != PF_OK) die("create", &e);
    double q1 = time_queries(one, rays, hits, occ, W * H, 0), q2 = time_queries(rb, rays, hits, occ, W * H, 0);
    double o1 = time_queries(one, rnd, hits, occ, W * H, 1), o2 = time_queries(rb, rnd, hits, occ, W * H, 1);
    pf_rt_destroy(one);

    printf("%s: %u triangles, %u animated primitives (%u triangles), %u frames, %u build thread%s\n", c->name,
           s->tri_count, dyn_prims, dyn_tris, frames, threads, threads > 1 ? "s" : "");
    printf("  rebuild all (pf_rt_create) %8.3f ms   (of it, device %.3f ms)\n", m_full * 1e3, m_dev * 1e3);
    printf("  update REBUILD             %8.3f ms   %6.1fx faster\n", m_reb * 1e3, m_full / m_reb);
    printf("  update REFIT               %8.3f ms   %6.1fx faster (first REFIT %.3f ms)\n", m_ref * 1e3,
           m_full / m_ref, first_refit * 1e3);
    printf("  camera rays %ux%u          one geometry %7.2f ms, split %7.2f ms (%+.1f%%)\n", W, H, q1 * 1e3,
           q2 * 1e3, 100.0 * (q2 / q1 - 1.0));
    printf("  random occlusion rays      one geometry %7.2f ms, split %7.2f ms (%+.1f%%)\n", o1 * 1e3, o2 * 1e3,
           100.0 * (o2 / o1 - 1.0));
    pf_rt_destroy(rb);
    pf_rt_destroy(rf);
    free(rays);
    free(rnd);
    free(hits);
    free(occ);
    free(full);
    free(dev);
    free(reb);
    free(ref);
}

int main(int argc, char **argv)
{
    uint32_t threads = 1, frames = 48, tris = 4000;
    const char *scenes = "../shared/scenes";
    for (int i = 1; i < argc; i++) {
        if (!strcmp(argv[i], "--threads") && i + 1 < argc) threads = (uint32_t)atoi(argv[++i]);
        else if (!strcmp(argv[i], "--frames") && i + 1 < argc) frames = (uint32_t)atoi(argv[++i]);
        else if (!strcmp(argv[i], "--tris") && i + 1 < argc) tris = (uint32_t)atoi(argv[++i]);
        else if (!strcmp(argv[i], "--scenes") && i + 1 < argc) scenes = argv[++i];
        else {
            fprintf(stderr, "usage: bench_rt [--threads N] [--frames N] [--tris N] [--scenes DIR]\n");
            return 2;
        }
    }
    if (threads < 1 || frames < 3 || tris < 8) {
        fprintf(stderr, "bench_rt: --threads >= 1, --frames >= 3, --tris >= 8\n");
        return 2;
    }
    pf_fpenv_set();
    pf_isa isa = pf_isa_detect();
    pf_error e;

    static bench_case box;
    box.name = "anim-box";
    pf_gltf_options go = {.anim = &box.anim};
    if (pf_gltf_load(&box.scene, "scenes/anim-box/anim-box.gltf", &go, &e) != PF_OK) die("anim-box", &e);
    if (pf_scene_validate(&box.scene, &e) != PF_OK) die("anim-box", &e);
    run(&box, threads, frames, isa);

    static bench_case sib;
    char path[4096];
    snprintf(path, sizeof path, "%s/sibenik/sibenik.gltf", scenes);
    sib.name = "Sibenik + a moving sphere";
    if (pf_gltf_load(&sib.scene, path, NULL, &e) != PF_OK) die(path, &e);
    append_sphere(&sib, tris);
    sib.path_a = pf_v3(-12.0f, -11.0f, -2.0f); /* through the nave, a metre above the floor */
    sib.path_b = pf_v3(8.0f, -9.0f, 2.0f);
    if (pf_scene_validate(&sib.scene, &e) != PF_OK) die("Sibenik", &e);
    run(&sib, threads, frames, isa);
    printf("isa %s\n", pf_isa_name(isa));
    return 0;
}
