/* test_ssvp: Screen-space VPL propagation (Aranha, Sec. III; gi_ssvp.c) and
 * its k-means (gi_kmeans.c).
 * - Eq. 2 distances against hand-computed values;
 * - k-means with the Eq. 2 metric recovers authored groups (two of them
 *   touching at a corner, told apart only by their normals), ends on a fixed
 *   point (every VPL at its nearest centroid, every centroid its members'
 *   mean), and plain Euclidean k-means (w2 = 0) does not separate the corner;
 * - reused centroids keep the assignment unchanged over 30 frames of a static
 *   scene (one iteration each), and the method moves nothing after frame 1;
 * - flux: in a closed box lit by a point light the first-bounce VPLs carry
 *   the light's 4 pi I (0.5%), and the second bounce what the clusters
 *   reflect (pi sum I_1 within Monte Carlo error), for 6 to 64 clusters
 *   (issue 14 item 6: it grew with the cluster count);
 * - the second bounce's image energy on the Cornell box against the clamped
 *   path tracer's, at 16 and 64 clusters (the paper's model) and 4 and 64
 *   (origin=members);
 * - the VPL sets of 30 frames with a moving light are identical with 1 and 2
 *   threads, and with whole cluster maps or only the texels read (lazy_maps);
 * - on scenes/cornell-box the second bounce adds light where the point light
 *   does not reach (Fig. 4's claim), and both bounce counts agree with
 *   Instant Radiosity's unbiased estimate;
 * - --filter gaussian: edge-aware (no blur across a depth step) and smoothing;
 * - bad --param values and budgets give clear errors. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>
#include <math.h>

#include "gi_frame.h"
#include "gi_kmeans.h"
#include "gi_reference.h"
#include "pf_gltf.h"
#include "test_frame_fixture.h"
#include "test_util.h"

#define CORNELL SOFTGI_SOURCE_DIR "/scenes/cornell-box/cornell-box.gltf"

/* ------------------------------------------------------------ k-means */

static void test_kmeans_metric(void **state)
{
    (void)state;
    gi_kmeans_options o = gi_kmeans_defaults();
    assert_true(o.w1 == 0.6f && o.w2 == 0.4f && o.max_iter == 5);
    pf_vec3 up = pf_v3(0, 1, 0), x = pf_v3(1, 0, 0), down = pf_v3(0, -1, 0);
    /* same normal: w1 |V - C| */
    assert_float_equal(gi_kmeans_distance(&o, pf_v3(3, 4, 0), up, pf_v3(0, 0, 0), up), 0.6f * 5.0f, 1e-6);
    /* perpendicular and opposite normals: + w2 */
    assert_float_equal(gi_kmeans_distance(&o, pf_v3(0, 0, 0), up, pf_v3(0, 0, 0), x), 0.4f, 1e-6);
    assert_float_equal(gi_kmeans_distance(&o, pf_v3(0, 0, 0), up, pf_v3(0, 0, 0), down), 0.4f, 1e-6);
    /* 60 degrees: w2 (1 - 0.5) */
    pf_vec3 n60 = pf_v3(sqrtf(3.0f) / 2.0f, 0.5f, 0);
    assert_float_equal(gi_kmeans_distance(&o, pf_v3(0, 0, 0), up, pf_v3(0, 0, 0), n60), 0.2f, 1e-6);
    /* scale divides the distance term only */
    o.scale = 10.0f;
    assert_float_equal(gi_kmeans_distance(&o, pf_v3(3, 4, 0), up, pf_v3(0, 0, 0), x), 0.6f * 0.5f + 0.4f, 1e-6);
}

#define GROUP 40
/* Three groups of 40 VPLs: a floor patch (normal +y) and a wall patch
 * (normal +x) meeting at the edge x = y = 0, and a ceiling patch far away. */
static void authored_groups(pf_vec3 *pos, pf_vec3 *nrm, uint32_t *truth)
{
    for (uint32_t k = 0; k < GROUP; k++) {
        float a = (float)(k % 8) / 8.0f * 0.5f, b = (float)(k / 8) / 5.0f * 0.5f;
        pos[k] = pf_v3(a, 0, b), nrm[k] = pf_v3(0, 1, 0), truth[k] = 0;
        pos[GROUP + k] = pf_v3(0, a, b), nrm[GROUP + k] = pf_v3(1, 0, 0), truth[GROUP + k] = 1;
        pos[2 * GROUP + k] = pf_v3(3 + a, 3, 3 + b), nrm[2 * GROUP + k] = pf_v3(0, -1, 0), truth[2 * GROUP + k] = 2;
    }
}

/* 1 when `assign` is the same partition as `truth`. */
static int same_partition(const uint32_t *assign, const uint32_t *truth, uint32_t n, uint32_t k)
{
    uint32_t map[8];
    for (uint32_t j = 0; j < k; j++) map[j] = 0xffffffffu;
    for (uint32_t i = 0; i < n; i++) {
        if (map[truth[i]] == 0xffffffffu) map[truth[i]] = assign[i];
        if (map[truth[i]] != assign[i]) return 0;
    }
    for (uint32_t a = 0; a < k; a++)
        for (uint32_t b = a + 1; b < k; b++)
            if (map[a] == map[b]) return 0;
    return 1;
}

static void test_kmeans_recovers_groups(void **state)
{
    (void)state;
    enum { N = 3 * GROUP, K = 3 };
    pf_vec3 pos[N], nrm[N], cpos[K], cnrm[K];
    uint32_t truth[N], assign[N], members[K];
    float scratch[N];
    authored_groups(pos, nrm, truth);
    gi_kmeans_options o = gi_kmeans_defaults();
    o.scale = 1.0f;
    uint32_t it = gi_kmeans_run(&o, pos, nrm, N, cpos, cnrm, K, 0, assign, members, scratch);
    assert_true(it >= 1 && it <= 5);
    if (!same_partition(assign, truth, N, K)) fail_msg("Eq. 2 k-means did not recover the three groups");
    for (uint32_t j = 0; j < K; j++) assert_int_equal(members[j], GROUP);
    /* a fixed point: one more assign/update changes nothing */
    uint32_t again[N];
    memcpy(again, assign, sizeof again);
    assert_int_equal(gi_kmeans_assign(&o, pos, nrm, N, cpos, cnrm, K, again), 0);
    assert_int_equal(gi_kmeans_update(pos, nrm, N, again, cpos, cnrm, K, members), 0);
    /* centroids: the groups' means, with their normals */
    for (uint32_t j = 0; j < K; j++) {
        uint32_t g = 0;
        for (uint32_t i = 0; i < N; i++)
            if (assign[i] == j) g = truth[i];
        pf_vec3 mean = pf_v3(0, 0, 0);
        for (uint32_t i = 0; i < N; i++)
            if (truth[i] == g) mean = pf_v3_add(mean, pos[i]);
        mean = pf_v3_scale(mean, 1.0f / GROUP);
        assert_true(pf_v3_length(pf_v3_sub(mean, cpos[j])) < 1e-5f);
        assert_true(pf_v3_dot(cnrm[j], nrm[g * GROUP]) > 0.99999f);
    }
    /* starting from last frame's centroids, perturbed: the same partition */
    for (uint32_t j = 0; j < K; j++) cpos[j] = pf_v3_add(cpos[j], pf_v3(0.05f, -0.03f, 0.02f));
    gi_kmeans_run(&o, pos, nrm, N, cpos, cnrm, K, 1, assign, members, scratch);
    assert_true(same_partition(assign, truth, N, K));
    /* the normal term is what separates the corner: without it (w2 = 0) the
     * floor and wall VPLs on the shared edge (a = 0: same positions,
     * perpendicular normals) are at the same distance from every centroid
     * and always land in one cluster */
    o.w2 = 0.0f;
    gi_kmeans_run(&o, pos, nrm, N, cpos, cnrm, K, 0, assign, members, scratch);
    assert_false(same_partition(assign, truth, N, K));
}

/* ------------------------------------------------------ method helpers */

typedef struct ctx {
    pf_scene scene;
    pf_rt *rt;
    pf_jobs *jobs;
    gi_area_lights area;
    void *st;
    gi_vpl_inputs in;
} ctx;

static void ctx_begin(ctx *c, uint32_t threads, const char *const *kv, uint32_t nkv, uint32_t budget)
{
    pf_error err;
    assert_int_equal(pf_scene_validate(&c->scene, &err), PF_OK);
    assert_int_equal(pf_rt_create(&c->rt, &c->scene, PF_ISA_SSE2, 1, &err), PF_OK); /* the tests' pin */
    c->jobs = pf_jobs_create(threads);
    memset(&c->area, 0, sizeof c->area);
    gi_params p;
    memset(&p, 0, sizeof p);
    for (uint32_t i = 0; i < nkv; i++) assert_int_equal(gi_params_add(&p, kv[i], &err), PF_OK);
    if (gi_method_ssvp.create(&c->st, &p, &err) != PF_OK) fail_msg("%s", err.message);
    gi_vpl_inputs in = {&c->scene, c->rt, c->jobs, NULL, 0, budget, 2, NULL, 0, 0, &c->area, NULL, 0, 0, 0, 0};
    c->in = in;
}

static void ctx_end(ctx *c)
{
    gi_method_ssvp.destroy(c->st);
    pf_jobs_destroy(c->jobs);
    pf_rt_destroy(c->rt);
    pf_scene_free(&c->scene);
}

static void update(ctx *c, gi_vpl_set *out)
{
    pf_error err;
    if (gi_method_ssvp.update(c->st, &c->in, out, &err) != PF_OK) fail_msg("%s", err.message);
    c->in.frame++;
}

static int vpls_equal(const gi_vpl_set *a, const gi_vpl_set *b)
{
    if (a->count != b->count) return 0;
    for (uint32_t i = 0; i < a->count; i++) {
        const gi_vpl *x = &a->v[i], *y = &b->v[i];
        if (x->id != y->id || x->moved != y->moved || memcmp(&x->pos, &y->pos, sizeof x->pos) ||
            memcmp(&x->nrm, &y->nrm, sizeof x->nrm) || memcmp(&x->intensity, &y->intensity, sizeof x->intensity))
            return 0;
    }
    return 1;
}

/* A closed 2 x 2 x 2 box of inward-facing quads (albedo 0.5, 0.25, 0.75 per
 * channel) with a point light inside. */
static void closed_box(pf_scene *s)
{
    const float al[4] = {0.5f, 0.25f, 0.75f, 1.0f};
    tu_quad q[6] = {
        {{-1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {0}, PF_ALPHA_OPAQUE, 0.5f}, /* x = -1, normal +x */
        {{1, 0, 0}, {0, 0, 1}, {0, 1, 0}, {0}, PF_ALPHA_OPAQUE, 0.5f},  /* x = +1, normal -x */
        {{0, -1, 0}, {0, 0, 1}, {1, 0, 0}, {0}, PF_ALPHA_OPAQUE, 0.5f}, /* y = -1, normal +y */
        {{0, 1, 0}, {1, 0, 0}, {0, 0, 1}, {0}, PF_ALPHA_OPAQUE, 0.5f},  /* y = +1, normal -y */
        {{0, 0, -1}, {1, 0, 0}, {0, 1, 0}, {0}, PF_ALPHA_OPAQUE, 0.5f}, /* z = -1, normal +z */
        {{0, 0, 1}, {0, 1, 0}, {1, 0, 0}, {0}, PF_ALPHA_OPAQUE, 0.5f},  /* z = +1, normal -z */
    };
    for (int k = 0; k < 6; k++) memcpy(q[k].albedo, al, sizeof al);
    tu_make_scene(s, q, 6);
    pf_light L;
    memset(&L, 0, sizeof L);
    snprintf(L.name, sizeof L.name, "bulb");
    L.type = PF_LIGHT_POINT;
    L.position = pf_v3(0.1f, 0.2f, -0.15f);
    L.color = pf_v3(1, 1, 1);
    L.intensity = 2.0f;
    pf_error err;
    assert_int_equal(pf_scene_add_light(s, &L, &err), PF_OK);
}

/* ---------------------------------------------------------------- flux */

static void test_flux_closed_box(void **state)
{
    (void)state;
    ctx c;
    closed_box(&c.scene);
    /* 6 clusters: one per wall */
    const char *kv[] = {"clusters=6", "first=256", "second=1536", "map_res=128"};
    ctx_begin(&c, 2, kv, 4, 2048);
    gi_vpl_set v = {0};
    update(&c, &v);
    const double albedo[3] = {0.5, 0.25, 0.75};
    double phi1[3] = {0, 0, 0}, i1[3] = {0, 0, 0}, phi2[3] = {0, 0, 0};
    uint32_t n1 = 0, n2 = 0;
    for (uint32_t i = 0; i < v.count; i++) {
        const gi_vpl *p = &v.v[i];
        const float I[3] = {p->intensity.x, p->intensity.y, p->intensity.z};
        for (int ch = 0; ch < 3; ch++) {
            /* I = Phi albedo / pi */
            double phi = I[ch] * M_PI / albedo[ch];
            if (p->id & 0x80000000u) phi2[ch] += phi;
            else phi1[ch] += phi, i1[ch] += I[ch];
        }
        if (p->id & 0x80000000u) n2++;
        else n1++;
    }
    /* every Hammersley sample hits a wall: n = 256 VPLs */
    assert_int_equal(n1, 256);
    assert_true(n2 > 1500);
    for (int ch = 0; ch < 3; ch++) {
        double want = 4.0 * M_PI * 2.0;
        /* the RSM's cube texels tile the sphere exactly (gi_rsm.h); the 256
         * stratified Hammersley samples weigh them equally, though their
         * solid angles vary by up to 5x over a face: within 0.5% */
        if (fabs(phi1[ch] - want) > 5e-3 * want) fail_msg("first-bounce flux %.6g, want 4 pi I = %.6g", phi1[ch], want);
        /* each wall's cluster radiates pi sum I over its hemisphere, all of
         * which lands on the box (stratified disc samples: a few %) */
        double want2 = M_PI * i1[ch];
        if (fabs(phi2[ch] - want2) > 0.04 * want2)
            fail_msg("channel %d: second-bounce flux %.6g, want pi sum I_1 = %.6g", ch, phi2[ch], want2);
    }
    gi_vpl_set_free(&v);
    ctx_end(&c);
}

/* The closed box's second-bounce flux over pi sum I_1 (what the first
 * bounce reflects, all of which lands on the box), per channel, with K
 * clusters, 256 + 256 VPLs and `extra` as a further --param (may be NULL). */
static void box_second_flux(uint32_t clusters, const char *extra, double ratio[3])
{
    ctx c;
    closed_box(&c.scene);
    char kk[32];
    snprintf(kk, sizeof kk, "clusters=%u", clusters);
    const char *kv[] = {kk, "first=256", "second=256", "lazy_maps=1", extra};
    ctx_begin(&c, 2, kv, extra ? 5 : 4, 512);
    gi_vpl_set v = {0};
    update(&c, &v);
    const double albedo[3] = {0.5, 0.25, 0.75};
    double i1[3] = {0, 0, 0}, phi2[3] = {0, 0, 0};
    for (uint32_t i = 0; i < v.count; i++) {
        const gi_vpl *p = &v.v[i];
        const float I[3] = {p->intensity.x, p->intensity.y, p->intensity.z};
        for (int ch = 0; ch < 3; ch++) {
            if (p->id & 0x80000000u) phi2[ch] += I[ch] * M_PI / albedo[ch]; /* I = Phi albedo / pi */
            else i1[ch] += I[ch];
        }
    }
    for (int ch = 0; ch < 3; ch++) ratio[ch] = phi2[ch] / (M_PI * i1[ch]);
    gi_vpl_set_free(&v);
    ctx_end(&c);
}

/* Issue 14 item 6: the second bounce's flux does not depend on the number of
 * clusters. Each cluster gets m = 256 / K samples (42 down to 4); the
 * Hammersley points that started at the disc's centre (u = k / m) made
 * the flux 1 + 2 / m times what the clusters reflect (1.048x at K = 6) and
 * about 1.58x at K = 64 (m = 4). */
static void test_second_flux_cluster_count(void **state)
{
    (void)state;
    static const uint32_t ks[] = {6, 16, 32, 64};
    static const struct {
        const char *param;
        double tol;
    } modes[] = {
        {NULL, 0.01},                /* disc=cosine: exact for a cluster on one wall */
        {"disc=paraboloid", 0.05},   /* the paper's disc: unbiased, noisier */
        {"origin=members", 0.01},    /* from the members: exact in a closed box */
    };
    for (size_t md = 0; md < sizeof modes / sizeof modes[0]; md++)
        for (size_t k = 0; k < sizeof ks / sizeof ks[0]; k++) {
            double r[3];
            box_second_flux(ks[k], modes[md].param, r);
            print_message("closed box, %s, %2u clusters: second-bounce flux / pi sum I_1 = %.4f %.4f %.4f\n",
                          modes[md].param ? modes[md].param : "defaults", ks[k], r[0], r[1], r[2]);
            for (int ch = 0; ch < 3; ch++)
                if (fabs(r[ch] - 1.0) > modes[md].tol)
                    fail_msg("%s, %u clusters, channel %d: flux ratio %.4f, want 1 +- %.2f",
                             modes[md].param ? modes[md].param : "defaults", ks[k], ch, r[ch], modes[md].tol);
        }
}

/* -------------------------------------------------- static scene, reuse */

static void test_static_reuse(void **state)
{
    (void)state;
    ctx c;
    pf_error err;
    assert_int_equal(pf_gltf_load(&c.scene, CORNELL, NULL, &err), PF_OK);
    ctx_begin(&c, 2, NULL, 0, 512);
    gi_vpl_set first = {0}, v = {0};
    update(&c, &first);
    assert_true(first.count > 300);
    for (uint32_t i = 0; i < first.count; i++) assert_int_equal(first.v[i].moved, 1);
    /* the method: nothing moves and nothing changes over 30 frames */
    for (int fr = 1; fr < 30; fr++) {
        update(&c, &v);
        assert_int_equal(v.count, first.count);
        for (uint32_t i = 0; i < v.count; i++) {
            gi_vpl a = first.v[i];
            a.moved = 0;
            if (memcmp(&a, &v.v[i], sizeof a)) fail_msg("frame %d: VPL %u changed or moved", fr, i);
        }
    }
    /* the k-means alone on the first-bounce VPLs: after the first frame,
     * reused centroids converge at once and keep every assignment */
    pf_vec3 pos[512], nrm[512], cpos[8], cnrm[8];
    uint32_t n = 0, assign[512], assign0[512], members[8];
    float scratch[512];
    for (uint32_t i = 0; i < first.count; i++)
        if (!(first.v[i].id & 0x80000000u)) pos[n] = first.v[i].pos, nrm[n] = first.v[i].nrm, n++;
    gi_kmeans_options o = gi_kmeans_defaults();
    o.scale = pf_v3_length(pf_v3_sub(c.scene.bounds_max, c.scene.bounds_min));
    uint32_t it = gi_kmeans_run(&o, pos, nrm, n, cpos, cnrm, 8, 0, assign0, members, scratch);
    /* frame 1 may stop at 5 iterations short of convergence; frame 2 goes on
     * from there; from then on nothing changes */
    it = gi_kmeans_run(&o, pos, nrm, n, cpos, cnrm, 8, 1, assign0, members, scratch);
    if (it > 1) it = gi_kmeans_run(&o, pos, nrm, n, cpos, cnrm, 8, 1, assign0, members, scratch);
    for (int fr = 0; fr < 30; fr++) {
        it = gi_kmeans_run(&o, pos, nrm, n, cpos, cnrm, 8, 1, assign, members, scratch);
        assert_int_equal(it, 1);
        assert_memory_equal(assign, assign0, n * sizeof(uint32_t));
    }
    /* every cluster holds VPLs of one wall or block face mostly: the Eq. 2
     * normal term keeps normals within 90 degrees of the centroid's */
    for (uint32_t i = 0; i < n; i++) assert_true(pf_v3_dot(nrm[i], cnrm[assign[i]]) > 0.0f);
    gi_vpl_set_free(&first);
    gi_vpl_set_free(&v);
    ctx_end(&c);
}

/* ------------------------------------------------------- determinism */

static void run_frames(uint32_t threads, gi_vpl_set *sets, int frames, const char *const *kv, uint32_t nkv)
{
    ctx c;
    pf_error err;
    assert_int_equal(pf_gltf_load(&c.scene, CORNELL, NULL, &err), PF_OK);
    ctx_begin(&c, threads, kv, nkv, 512);
    pf_vec3 p0 = c.scene.lights[0].position;
    for (int fr = 0; fr < frames; fr++) {
        /* the light circles under the ceiling; static every third frame */
        float a = 0.2f * (float)(fr - fr / 3);
        c.scene.lights[0].position = pf_v3_add(p0, pf_v3(0.1f * cosf(a), -0.05f, 0.1f * sinf(a)));
        update(&c, &sets[fr]);
    }
    ctx_end(&c);
}

static void test_threads_30_frames(void **state)
{
    (void)state;
    enum { F = 30 };
    gi_vpl_set a[F], b[F];
    memset(a, 0, sizeof a), memset(b, 0, sizeof b);
    run_frames(1, a, F, NULL, 0);
    run_frames(2, b, F, NULL, 0);
    uint32_t moved = 0, unmoved = 0;
    for (int fr = 0; fr < F; fr++) {
        if (!vpls_equal(&a[fr], &b[fr])) fail_msg("frame %d: VPL sets differ between 1 and 2 threads", fr);
        for (uint32_t i = 0; i < a[fr].count; i++) {
            if (a[fr].v[i].moved) moved++;
            else unmoved++;
        }
        gi_vpl_set_free(&a[fr]), gi_vpl_set_free(&b[fr]);
    }
    /* the test exercised both moving and static frames */
    assert_true(moved > 0 && unmoved > 0);
}

/* lazy_maps=1 traces only the texels the samples read: the same VPLs */
static void test_lazy_maps_identical(void **state)
{
    (void)state;
    enum { F = 6 };
    gi_vpl_set a[F], b[F];
    memset(a, 0, sizeof a), memset(b, 0, sizeof b);
    const char *lazy[] = {"lazy_maps=1"};
    run_frames(2, a, F, NULL, 0);
    run_frames(2, b, F, lazy, 1);
    for (int fr = 0; fr < F; fr++) {
        assert_true(a[fr].count > 300);
        if (!vpls_equal(&a[fr], &b[fr])) fail_msg("frame %d: lazy maps give other VPLs", fr);
        gi_vpl_set_free(&a[fr]), gi_vpl_set_free(&b[fr]);
    }
}

/* One update with one thread of the scene in c->scene (which it frees):
 * the VPLs SSVP makes with these parameters, budget and VPL cycle. */
static void single_update(ctx *c, const char *const *kv, uint32_t nkv, uint32_t budget, uint32_t cycle,
                          gi_vpl_set *out)
{
    ctx_begin(c, 1, kv, nkv, budget);
    c->in.cycle = cycle;
    update(c, out);
    ctx_end(c);
}

/* The default second-bounce origin follows VPL cycling: the paper's
 * centroid when a frame shades its whole set, the unbiased members under a
 * cycle (gi_vpl_inputs.cycle > 1); an origin given with --param keeps its
 * value either way. */
static void cycle_set(const char *const *kv, uint32_t nkv, uint32_t cycle, gi_vpl_set *out)
{
    ctx c;
    pf_error err;
    assert_int_equal(pf_gltf_load(&c.scene, CORNELL, NULL, &err), PF_OK);
    single_update(&c, kv, nkv, 512, cycle, out);
}

static void test_origin_follows_cycle(void **state)
{
    (void)state;
    const char *centroid[] = {"origin=centroid"}, *members[] = {"origin=members"};
    gi_vpl_set d1 = {0}, d4 = {0}, c1 = {0}, c4 = {0}, m1 = {0}, m4 = {0};
    cycle_set(NULL, 0, 1, &d1), cycle_set(NULL, 0, 4, &d4);
    cycle_set(centroid, 1, 1, &c1), cycle_set(centroid, 1, 4, &c4);
    cycle_set(members, 1, 1, &m1), cycle_set(members, 1, 4, &m4);
    assert_true(d1.count > 300);
    assert_false(vpls_equal(&c1, &m1)); /* the two origins give other second-bounce VPLs */
    assert_true(vpls_equal(&d1, &c1));  /* no cycle: the paper's */
    assert_true(vpls_equal(&d4, &m4));  /* a cycle: members */
    assert_true(vpls_equal(&c4, &c1));  /* a given origin ignores the cycle */
    assert_true(vpls_equal(&m4, &m1));
    gi_vpl_set *all[] = {&d1, &d4, &c1, &c4, &m1, &m4};
    for (int k = 0; k < 6; k++) gi_vpl_set_free(all[k]);
}

/* ------------------------------------------ second bounce on the Cornell box */

typedef struct frame_means {
    double shadow, all; /* mean indirect irradiance (luminance) in shadowed / all pixels */
    uint32_t shadow_px;
} frame_means;

static frame_means cornell_indirect(const gi_vpl_method *m, uint32_t vpls, uint32_t bounces, const char *const *kv,
                                    uint32_t nkv)
{
    tu_fx x;
    pf_error err;
    tu_load(&x.scene, CORNELL);
    enum { W = 128, H = 128 };
    gi_indirect_options io;
    memset(&io, 0, sizeof io);
    io.method = m;
    io.vpls = vpls;
    io.bounces = bounces;
    io.visibility_raytrace = 1;
    io.filter = GI_FILTER_NONE;
    for (uint32_t i = 0; i < nkv; i++) assert_int_equal(gi_params_add(&io.params, kv[i], &err), PF_OK);
    tu_fx_desc d = {.threads = 2, .w = W, .h = H, .shadow_size = 256, .io = &io};
    tu_fx_begin_with(&x, &d);
    gi_frame *f = &x.f;
    gi_frame_render_raster(f);
    frame_means r = {0, 0, 0};
    uint32_t all = 0;
    for (uint32_t i = 0; i < W * H; i++) {
        if (f->gbuf.prim[i] == RS_GBUFFER_EMPTY) continue;
        const float *e = f->ind.filtered + 3 * i, *dl = f->direct + 3 * i;
        double lum = 0.2126 * e[0] + 0.7152 * e[1] + 0.0722 * e[2];
        r.all += lum, all++;
        if (dl[0] == 0.0f && dl[1] == 0.0f && dl[2] == 0.0f) r.shadow += lum, r.shadow_px++;
    }
    r.all /= all;
    r.shadow /= r.shadow_px ? r.shadow_px : 1;
    tu_fx_end(&x);
    return r;
}

static void test_second_bounce_adds_light(void **state)
{
    (void)state;
    /* the paper's configuration: 256 + 256 VPLs, 8 clusters, 256^2 maps */
    frame_means one = cornell_indirect(&gi_method_ssvp, 512, 1, NULL, 0);
    frame_means two = cornell_indirect(&gi_method_ssvp, 512, 2, NULL, 0);
    print_message("ssvp Cornell box, mean indirect irradiance: shadowed %.4f -> %.4f (%u px), all %.4f -> %.4f\n",
                  one.shadow, two.shadow, two.shadow_px, one.all, two.all);
    assert_true(two.shadow_px > 500); /* the ceiling and behind the blocks */
    assert_true(two.shadow > 1.15 * one.shadow);
    assert_true(two.all > 1.15 * one.all);
    /* against Instant Radiosity (random walks, unbiased) with the same
     * bounces: SSVP's estimates agree within 10% on the whole image */
    frame_means ir1 = cornell_indirect(&gi_method_ir, 2048, 1, NULL, 0);
    frame_means ir2 = cornell_indirect(&gi_method_ir, 2048, 2, NULL, 0);
    print_message("ir: all %.4f (1 bounce), %.4f (2 bounces)\n", ir1.all, ir2.all);
    assert_true(fabs(one.all - ir1.all) < 0.10 * ir1.all);
    assert_true(fabs(two.all - ir2.all) < 0.10 * ir2.all);
}

/* ------------------------------- second bounce against the path tracer */

/* scenes/cornell-box with its point light moved to the middle of the box
 * (under the ceiling the path tracer needs far more samples), 1 W/sr. */
static void cornell_mid_light(pf_scene *s)
{
    tu_load(s, CORNELL);
    assert_true(s->light_count >= 1);
    s->light_count = 1;
    s->lights[0].type = PF_LIGHT_POINT;
    s->lights[0].position = pf_v3(0.278f, 0.35f, 0.15f);
    s->lights[0].color = pf_v3(1, 1, 1);
    s->lights[0].intensity = 1.0f;
}

enum { RW = 64, RH = 48 };

static double image_mean(const float *rgb)
{
    double m = 0.0;
    for (uint32_t i = 0; i < RW * RH; i++)
        m += 0.2126 * rgb[3 * i] + 0.7152 * rgb[3 * i + 1] + 0.0722 * rgb[3 * i + 2];
    return m / (RW * RH);
}

/* The mean of the indirect image (radiance, indirect only) with `bounces`
 * bounces: SSVP with 256 + `second` VPLs, `clusters` and `extra` (a further
 * --param or NULL), ray-traced visibility, the default clamp, no filter; or
 * the path tracer (ssvp 0, 512 spp) with the same clamp. */
static double cornell_mid_mean(int ssvp, uint32_t bounces, uint32_t clusters, uint32_t second, const char *extra)
{
    tu_fx x;
    pf_error err;
    cornell_mid_light(&x.scene);
    static float img[3 * RW * RH];
    double mean;
    if (!ssvp) {
        tu_fx_desc d = {.threads = 2, .w = RW, .h = RH, .no_raster = 1};
        tu_fx_begin_with(&x, &d);
        gi_reference_options ro;
        memset(&ro, 0, sizeof ro);
        ro.spp = 512;
        ro.bounces = bounces;
        ro.indirect_only = 1;
        ro.clamp = 400.0f; /* the frame's default bound */
        assert_int_equal(gi_reference_render(img, &x.scene, x.rt, x.jobs, &x.scene.cameras[0], RW, RH, &ro, &err),
                         PF_OK);
        mean = image_mean(img);
    } else {
        gi_indirect_options io;
        memset(&io, 0, sizeof io);
        io.method = &gi_method_ssvp;
        char kk[32];
        snprintf(kk, sizeof kk, "clusters=%u", clusters);
        char ks[32];
        snprintf(ks, sizeof ks, "second=%u", second);
        const char *kv[] = {kk, "first=256", ks, extra};
        for (uint32_t i = 0; i < (extra ? 4u : 3u); i++)
            assert_int_equal(gi_params_add(&io.params, kv[i], &err), PF_OK);
        io.vpls = 256 + second;
        io.bounces = bounces;
        io.visibility_raytrace = 1;
        io.clamp = -1.0f; /* default: 400 */
        io.filter = GI_FILTER_NONE;
        tu_fx_desc d = {.threads = 2, .w = RW, .h = RH, .shadow_size = 256, .io = &io, .indirect_only = 1};
        tu_fx_begin_with(&x, &d);
        gi_frame_render_raster(&x.f);
        mean = image_mean(x.f.final);
    }
    tu_fx_end(&x);
    return mean;
}

/* Issue 14 item 6: the second bounce's energy in the image (the 2-bounce
 * image mean minus the 1-bounce one, the same 256 first-bounce VPLs in both)
 * against the clamped path tracer's (bounces 2 minus 1, clamp 400), and not
 * growing with the cluster count. It grew from 1.2x at 16 clusters to 2.0x at
 * 64 (160x120, docs/ssvp.md). The paper's cluster model (origin=centroid)
 * is checked at 16 and 64 clusters: at 4 and 8, the floor and the block tops
 * form one cluster whose centroid lies inside the short block, and that
 * light is lost (documented). origin=members is unbiased at any count. */
static void test_second_bounce_vs_reference(void **state)
{
    (void)state;
    double ref1 = cornell_mid_mean(0, 1, 0, 0, NULL), ref2 = cornell_mid_mean(0, 2, 0, 0, NULL);
    print_message("path tracer, 512 spp: indirect image mean %.5f (1 bounce), %.5f (2 bounces)\n", ref1, ref2);
    assert_true(ref2 > 1.2 * ref1);
    /* the paper's 256 + 256 VPLs (16 and 4 samples per cluster); members
     * with 2048 (less noise) */
    static const struct {
        uint32_t clusters, second;
        const char *param;
    } cases[] = {{16, 256, NULL}, {64, 256, NULL}, {4, 2048, "origin=members"}, {64, 2048, "origin=members"}};
    double r[4];
    for (int k = 0; k < 4; k++) {
        double s1 = cornell_mid_mean(1, 1, cases[k].clusters, cases[k].second, cases[k].param);
        double s2 = cornell_mid_mean(1, 2, cases[k].clusters, cases[k].second, cases[k].param);
        r[k] = (s2 - s1) / (ref2 - ref1);
        print_message("ssvp %2u clusters, 256 + %u VPLs %s: first bounce %.4f x, second bounce %.4f x the path "
                      "tracer's\n",
                      cases[k].clusters, cases[k].second, cases[k].param ? cases[k].param : "(defaults)", s1 / ref1,
                      r[k]);
        assert_true(fabs(s1 / ref1 - 1.0) < 0.05);
    }
    for (int k = 0; k < 4; k++)
        if (fabs(r[k] - 1.0) > 0.06) fail_msg("case %d: the second bounce is %.4f x the path tracer's", k, r[k]);
    /* independent of the cluster count (the paper's model with 256
     * second-bounce VPLs moves a few % with the clusters' shapes) */
    if (fabs(r[1] - r[0]) > 0.10) fail_msg("defaults: 16 and 64 clusters give %.4f and %.4f", r[0], r[1]);
    if (fabs(r[3] - r[2]) > 0.05) fail_msg("origin=members: 4 and 64 clusters give %.4f and %.4f", r[2], r[3]);
}

/* ------------------------------------------------------ gaussian filter */

static void test_gaussian_filter(void **state)
{
    (void)state;
    tu_fx fx;
    tu_quad q[2] = {
        {{-1, 0, -3}, {1, 0, 0}, {0, 2, 0}, {1, 1, 1, 1}, PF_ALPHA_OPAQUE, 0.5f},
        {{1, 0, -4}, {1, 0, 0}, {0, 2, 0}, {1, 1, 1, 1}, PF_ALPHA_OPAQUE, 0.5f},
    };
    tu_make_scene(&fx.scene, q, 2);
    pf_error err;
    pf_camera cam;
    assert_int_equal(pf_camera_look_at(&cam, pf_v3(0, 0, 0), pf_v3(0, 0, -1), pf_radians(40), &err), PF_OK);
    enum { W = 96, H = 64 };
    gi_indirect_options io;
    memset(&io, 0, sizeof io);
    io.visibility_raytrace = 1;
    io.filter = GI_FILTER_GAUSSIAN;
    io.alpha_rel = 0.05f;
    tu_fx_begin(&fx, 2, RS_SIMD_SCALAR, W, H, &cam, &io, 0);
    gi_frame *f = &fx.f;
    gi_stage_gbuffer_raster(f);
    gi_stage_gbuffer_resolve(f);
    /* near wall 1.0, far wall 3.0, each with a +-0.5 checkerboard of pixels */
    double var_in = 0.0, var_out = 0.0;
    for (uint32_t y = 0; y < H; y++)
        for (uint32_t x = 0; x < W; x++) {
            size_t i = (size_t)y * W + x;
            float base = f->gbuf.prim[i] < 2 ? 1.0f : 3.0f, p = ((x + y) & 1) ? 0.5f : -0.5f;
            for (int ch = 0; ch < 3; ch++) f->ind.combined[3 * i + ch] = base + p;
        }
    gi_stage_filter(f);
    int interior = 0;
    for (uint32_t y = 4; y + 4 < H; y++)
        for (uint32_t x = 4; x + 4 < W; x++) {
            size_t i = (size_t)y * W + x;
            if (f->gbuf.prim[i] == RS_GBUFFER_EMPTY) continue;
            float want = f->gbuf.prim[i] < 2 ? 1.0f : 3.0f, got = f->ind.filtered[3 * i];
            /* never takes the other wall: the result stays within this wall's range */
            assert_true(got >= want - 0.5f && got <= want + 0.5f);
            int mixed = 0;
            for (int dy = -4; dy <= 4; dy++)
                for (int dx = -4; dx <= 4; dx++) {
                    uint32_t pj = f->gbuf.prim[i + dy * W + dx];
                    mixed |= pj == RS_GBUFFER_EMPTY || (pj < 2) != (f->gbuf.prim[i] < 2);
                }
            if (!mixed) {
                double din = f->ind.combined[3 * i] - want, dout = got - want;
                var_in += din * din, var_out += dout * dout;
                interior++;
            }
        }
    assert_true(interior > 1000);
    /* a 9 x 9 Gaussian of sigma 2 shrinks a checkerboard's variance > 100x */
    assert_true(var_out < var_in / 100.0);
    tu_fx_end(&fx);
}

/* ------------------------------------------------------------- errors */

static void expect_create_error(const char *kv, const char *needle)
{
    gi_params p;
    memset(&p, 0, sizeof p);
    pf_error err;
    assert_int_equal(gi_params_add(&p, kv, &err), PF_OK);
    void *st = (void *)1;
    assert_int_not_equal(gi_method_ssvp.create(&st, &p, &err), PF_OK);
    assert_null(st);
    if (!strstr(err.message, needle)) fail_msg("--param %s: message '%s' lacks '%s'", kv, err.message, needle);
}

/* The first- and second-bounce VPLs SSVP makes in the closed box with
 * these parameters and budget. */
static void bounce_counts(const char *const *kv, uint32_t nkv, uint32_t budget, uint32_t *n1, uint32_t *n2)
{
    ctx c;
    gi_vpl_set v = {0};
    closed_box(&c.scene);
    single_update(&c, kv, nkv, budget, 0, &v);
    *n1 = *n2 = 0;
    for (uint32_t i = 0; i < v.count; i++) {
        if (v.v[i].id & 0x80000000u) (*n2)++;
        else (*n1)++;
    }
    gi_vpl_set_free(&v);
}

static void test_errors(void **state)
{
    (void)state;
    expect_create_error("clusters=0", "clusters");
    expect_create_error("clusters=65", "clusters");
    expect_create_error("clusters=x", "clusters");
    expect_create_error("first=0", "first");
    expect_create_error("map_res=4", "map_res");
    expect_create_error("rsm_res=100000", "rsm_res");
    expect_create_error("iters=0", "iters");
    expect_create_error("cluster=8", "cluster");
    expect_create_error("lazy_maps=2", "lazy_maps");
    expect_create_error("disc=uniform", "cosine, paraboloid");
    expect_create_error("origin=light", "centroid, members");
    /* explicit counts over the VPL budget: an error at update, no VPLs */
    ctx c;
    closed_box(&c.scene);
    const char *kv[] = {"first=200", "second=200"};
    ctx_begin(&c, 1, kv, 2, 256);
    gi_vpl_set v = {0};
    pf_error err;
    assert_int_not_equal(gi_method_ssvp.update(c.st, &c.in, &v, &err), PF_OK);
    assert_non_null(strstr(err.message, "budget"));
    assert_int_equal(v.count, 0);
    gi_vpl_set_free(&v);
    ctx_end(&c);
    /* defaults halve to fit a smaller budget */
    uint32_t n1, n2;
    bounce_counts(NULL, 0, 256, &n1, &n2);
    assert_int_equal(n1, 128);
    assert_true(n2 > 100 && n2 <= 128);
    /* ... and follow a larger one (a VPL cycle's C x 256): half each, not
     * the paper's 256 + 256 (which made a 16-slice cycle 16 slivers of one
     * 512-VPL set) */
    bounce_counts(NULL, 0, 4096, &n1, &n2);
    assert_int_equal(n1, 2048);
    assert_true(n2 > 1900 && n2 <= 2048);
    /* one count given: the other keeps its paper default */
    const char *kv1[] = {"first=64"};
    bounce_counts(kv1, 1, 4096, &n1, &n2);
    assert_int_equal(n1, 64);
    assert_true(n2 > 200 && n2 <= 256);
    /* the CLI */
    tu_softgi_expect("render --filter blur", 2, "gaussian");
    tu_softgi_expect("render --method ssvp --param clusters=0 --size 32x32 --output /tmp/test-ssvp-x.png", 2,
                     "clusters");
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_kmeans_metric),     cmocka_unit_test(test_kmeans_recovers_groups),
        cmocka_unit_test(test_flux_closed_box),   cmocka_unit_test(test_second_flux_cluster_count),
        cmocka_unit_test(test_static_reuse),
        cmocka_unit_test(test_threads_30_frames), cmocka_unit_test(test_lazy_maps_identical),
        cmocka_unit_test(test_origin_follows_cycle),
        cmocka_unit_test(test_second_bounce_adds_light), cmocka_unit_test(test_second_bounce_vs_reference),
        cmocka_unit_test(test_gaussian_filter),   cmocka_unit_test(test_errors),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
