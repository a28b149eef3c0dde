/* test_direct: direct light against the analytic answer.
 *
 * A white-ish Lambertian floor (y = 0, normal +Y) seen from above, lit by one
 * light at a time. For every pixel the rendered radiance must equal
 *   point:       L = albedo I cos(theta) / (pi r^2)
 *   spot:        the same times the KHR_lights_punctual cone factor
 *   directional: L = albedo E cos(theta) / pi
 * evaluated in double precision at the pixel's G-buffer position, within
 * 1e-4 relative (where the spot factor falls below 0.01 the comparison is
 * absolute, 1e-6 of the peak, because the smoothstep's t^2 loses relative
 * precision to cancellation there). */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>
#include <math.h>

#include "gi_frame.h"
#include "gi_light.h"
#include "pf_jobs.h"
#include "pf_rt.h"
#include "test_frame_fixture.h"
#include "test_util.h"

#define W 96
#define H 96

static const float k_albedo[3] = {0.8f, 0.6f, 0.4f};

typedef tu_fx fixture;

/* The floor under `light`, ray traced (Embree at the CPU's best ISA). */
static void setup_floor(fixture *fx, const pf_light *light)
{
    tu_quad floor = {{0, 0, 0}, {10, 0, 0}, {0, 0, -10}, {k_albedo[0], k_albedo[1], k_albedo[2], 1}, PF_ALPHA_OPAQUE, 0.5f};
    tu_make_scene(&fx->scene, &floor, 1);
    pf_error err;
    assert_int_equal(pf_scene_add_light(&fx->scene, light, &err), PF_OK);
    pf_camera cam;
    assert_int_equal(pf_camera_look_at(&cam, pf_v3(0.1f, 3.0f, 0.2f), pf_v3(0, 0, 0), pf_radians(70.0f), &err), PF_OK);
    tu_fx_desc d = {.threads = 2, .no_raster = 1, .isa = pf_isa_detect(), .w = W, .h = H, .cam = &cam,
                    .shadow_size = 1024};
    tu_fx_begin_with(fx, &d);
    gi_frame_render_raytraced(&fx->f);
}

static void teardown(fixture *fx) { tu_fx_end(fx); }

/* Analytic irradiance (double) at p on the floor (normal +Y). */
static double analytic_e(const pf_light *L, double px, double py, double pz, double *spot_factor)
{
    *spot_factor = 1.0;
    if (L->type == PF_LIGHT_DIRECTIONAL) {
        double c = -(double)L->direction.y;
        return c > 0 ? L->intensity * c : 0.0;
    }
    double dx = L->position.x - px, dy = L->position.y - py, dz = L->position.z - pz;
    double r2 = dx * dx + dy * dy + dz * dz, r = sqrt(r2);
    double c = dy / r;
    double e = c > 0 ? L->intensity * c / r2 : 0.0;
    if (L->type == PF_LIGHT_SPOT) {
        double cos_a = -(dx * L->direction.x + dy * L->direction.y + dz * L->direction.z) / r;
        double co = cos((double)L->outer_cone), ci = cos((double)L->inner_cone);
        double t = (cos_a - co) / fmax(0.001, ci - co);
        t = t < 0 ? 0 : (t > 1 ? 1 : t);
        *spot_factor = t * t;
        e *= t * t;
    }
    return e;
}

static void check_against_analytic(const pf_light *light, int *lit_pixels, int *dark_pixels)
{
    fixture fx;
    setup_floor(&fx, light);
    const rs_gbuffer *g = &fx.f.gbuf;
    double peak = 0.0;
    for (int i = 0; i < W * H; i++) {
        double f;
        double e = analytic_e(light, g->pos_x[i], g->pos_y[i], g->pos_z[i], &f);
        peak = fmax(peak, e);
    }
    *lit_pixels = *dark_pixels = 0;
    for (int i = 0; i < W * H; i++) {
        assert_int_not_equal(g->prim[i], RS_GBUFFER_EMPTY); /* the floor fills the view */
        assert_true(fabsf(g->pos_y[i]) < 1e-6f);
        double f;
        double e = analytic_e(light, g->pos_x[i], g->pos_y[i], g->pos_z[i], &f);
        for (int c = 0; c < 3; c++) {
            double col = c == 0 ? light->color.x : (c == 1 ? light->color.y : light->color.z);
            double want = k_albedo[c] * col * e / M_PI;
            double got = fx.f.direct[3 * i + c];
            double tol = f >= 0.01 ? 1e-4 * want : 1e-6 * peak;
            if (fabs(got - want) > tol)
                fail_msg("pixel %d channel %d: got %.9g, analytic %.9g (spot factor %.4g)", i, c, got, want, f);
            /* final = direct for a non-emissive surface */
            assert_true(fx.f.final[3 * i + c] == fx.f.direct[3 * i + c]);
        }
        if (e > 0) (*lit_pixels)++;
        else {
            (*dark_pixels)++;
            assert_true(fx.f.direct[3 * i] == 0.0f);
        }
    }
    teardown(&fx);
}

static void test_point_light(void **state)
{
    (void)state;
    pf_light L = {.type = PF_LIGHT_POINT, .position = {0.7f, 1.5f, -0.4f}, .color = {1.0f, 0.5f, 0.25f}, .intensity = 3.0f};
    int lit, dark;
    check_against_analytic(&L, &lit, &dark);
    assert_int_equal(lit, W * H);
}

static void test_spot_light(void **state)
{
    (void)state;
    pf_light L = {.type = PF_LIGHT_SPOT,
                  .position = {0.2f, 2.0f, 0.1f},
                  .direction = {0.0f, -1.0f, 0.0f},
                  .color = {1, 1, 1},
                  .intensity = 5.0f,
                  .inner_cone = pf_radians(20.0f),
                  .outer_cone = pf_radians(35.0f)};
    int lit, dark;
    check_against_analytic(&L, &lit, &dark);
    /* the cone must cut the view: both lit and unlit pixels exist */
    assert_true(lit > 100);
    assert_true(dark > 100);
    /* inside the inner cone the factor is exactly 1 */
    assert_float_equal(gi_light_spot_factor(&L, cosf(pf_radians(10.0f))), 1.0f, 0.0f);
    assert_float_equal(gi_light_spot_factor(&L, cosf(pf_radians(40.0f))), 0.0f, 0.0f);
    float mid = gi_light_spot_factor(&L, cosf(pf_radians(27.5f)));
    assert_true(mid > 0.1f && mid < 0.9f);
}

static void test_directional_light(void **state)
{
    (void)state;
    pf_light L = {.type = PF_LIGHT_DIRECTIONAL, .color = {0.9f, 1.0f, 1.1f}, .intensity = 2.5f};
    L.direction = pf_v3_normalize(pf_v3(1.0f, -2.0f, 0.5f));
    int lit, dark;
    check_against_analytic(&L, &lit, &dark);
    assert_int_equal(lit, W * H);
}

/* A light below the floor must not light its top (cos < 0), and an occluder
 * between light and floor must cast an exact shadow (ray-traced). */
static void test_shadow_and_backside(void **state)
{
    (void)state;
    tu_quad quads[2] = {
        {{0, 0, 0}, {10, 0, 0}, {0, 0, -10}, {1, 1, 1, 1}, PF_ALPHA_OPAQUE, 0.5f},
        {{0, 1, 0}, {0.25f, 0, 0}, {0, 0, -0.25f}, {1, 1, 1, 1}, PF_ALPHA_OPAQUE, 0.5f}, /* occluder 0.5x0.5 */
    };
    fixture fx;
    tu_make_scene(&fx.scene, quads, 2);
    pf_error err;
    pf_light L = {.type = PF_LIGHT_POINT, .position = {0, 2, 0}, .color = {1, 1, 1}, .intensity = 1};
    assert_int_equal(pf_scene_add_light(&fx.scene, &L, &err), PF_OK);
    pf_light below = {.type = PF_LIGHT_POINT, .position = {0, -1, 0}, .color = {1, 1, 1}, .intensity = 100};
    assert_int_equal(pf_scene_add_light(&fx.scene, &below, &err), PF_OK);
    pf_camera cam;
    /* look at the floor from the side, below the occluder */
    assert_int_equal(pf_camera_look_at(&cam, pf_v3(0, 0.5f, 3.0f), pf_v3(0, 0, 0), pf_radians(60.0f), &err), PF_OK);
    tu_fx_desc d = {.threads = 1, .no_raster = 1, .w = W, .h = H, .cam = &cam, .shadow_size = 1024};
    tu_fx_begin_with(&fx, &d);
    gi_frame_render_raytraced(&fx.f);
    int shadowed = 0, lit = 0;
    for (int i = 0; i < W * H; i++) {
        const rs_gbuffer *g = &fx.f.gbuf;
        if (g->prim[i] == RS_GBUFFER_EMPTY || g->prim[i] >= 2) continue; /* floor only */
        double x = g->pos_x[i], z = g->pos_z[i];
        /* the occluder's shadow from (0,2,0) through |x|,|z| <= 0.25 at y=1 is |x|,|z| <= 0.5 at y=0 */
        int in_shadow = fabs(x) < 0.499 && fabs(z) < 0.499;
        int out_shadow = fabs(x) > 0.501 || fabs(z) > 0.501;
        if (in_shadow) {
            assert_true(fx.f.direct[3 * i] == 0.0f);
            shadowed++;
        } else if (out_shadow) {
            double f, e = analytic_e(&L, x, 0, z, &f);
            assert_true(fabs(fx.f.direct[3 * i] - e / M_PI) <= 1e-4 * e / M_PI);
            lit++;
        }
    }
    assert_true(shadowed > 50);
    assert_true(lit > 50);
    teardown(&fx);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_point_light),
        cmocka_unit_test(test_spot_light),
        cmocka_unit_test(test_directional_light),
        cmocka_unit_test(test_shadow_and_backside),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
