/* pf_scene: scene ownership, validation and camera/light helpers (pf_scene.h). */
#include "pf_scene.h"

#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "pf_budget.h"

void pf_scene_free(pf_scene *scene)
{
    if (!scene) return;
    free(scene->positions);
    free(scene->normals);
    free(scene->uvs);
    free(scene->indices);
    free(scene->tri_material);
    free(scene->materials);
    free(scene->textures);
    for (uint32_t i = 0; i < scene->image_count; i++) free(scene->images[i].texels);
    free(scene->images);
    free(scene->cameras);
    free(scene->lights);
    memset(scene, 0, sizeof *scene);
}


pf_result pf_scene_validate(pf_scene *s, pf_error *err)
{
    if (s->tri_count == 0 || s->vertex_count == 0)
        return pf_error_set(err, PF_ERR_NO_TRIANGLES, "the scene has no (non-degenerate) triangles to render");
    if (s->material_count == 0) return pf_error_set(err, PF_ERR_PARSE, "the scene has no materials");
    pf_vec3 lo = pf_v3(INFINITY, INFINITY, INFINITY), hi = pf_v3(-INFINITY, -INFINITY, -INFINITY);
    for (uint32_t v = 0; v < s->vertex_count; v++) {
        pf_vec3 p = s->positions[v];
        if (!pf_v3_is_finite(p))
            return pf_error_set(err, PF_ERR_NONFINITE, "vertex %u has a non-finite position (%g, %g, %g)", v,
                                (double)p.x, (double)p.y, (double)p.z);
        if (!pf_scene_coord_ok(p))
            return pf_error_set(err, PF_ERR_NONFINITE,
                                "vertex %u lies at (%g, %g, %g), beyond the supported range |x| <= %g", v,
                                (double)p.x, (double)p.y, (double)p.z, (double)PF_SCENE_MAX_COORD);
        if (!pf_v3_is_finite(s->normals[v]))
            return pf_error_set(err, PF_ERR_NONFINITE, "vertex %u has a non-finite normal", v);
        if (!isfinite(s->uvs[v].x) || !isfinite(s->uvs[v].y))
            return pf_error_set(err, PF_ERR_NONFINITE, "vertex %u has a non-finite texture coordinate", v);
        lo = pf_v3_min(lo, p);
        hi = pf_v3_max(hi, p);
    }
    for (uint32_t t = 0; t < s->tri_count; t++) {
        for (int k = 0; k < 3; k++)
            if (s->indices[3 * t + k] >= s->vertex_count)
                return pf_error_set(err, PF_ERR_INDEX_RANGE, "triangle %u uses vertex %u of %u", t,
                                    s->indices[3 * t + k], s->vertex_count);
        if (s->tri_material[t] >= s->material_count)
            return pf_error_set(err, PF_ERR_INDEX_RANGE, "triangle %u uses material %u of %u", t,
                                s->tri_material[t], s->material_count);
    }
    for (uint32_t m = 0; m < s->material_count; m++) {
        const pf_material *mat = &s->materials[m];
        for (int k = 0; k < 4; k++)
            if (!isfinite(mat->base_color[k]))
                return pf_error_set(err, PF_ERR_NONFINITE, "material %u has a non-finite baseColorFactor", m);
        for (int k = 0; k < 4; k++)
            if (!(mat->base_color[k] >= 0.0f && mat->base_color[k] <= 1.0f))
                return pf_error_set(err, PF_ERR_PARSE, "material %u has a baseColorFactor outside [0, 1]", m);
        for (int k = 0; k < 3; k++)
            if (!(mat->emission[k] >= 0.0f && mat->emission[k] <= PF_MAX_RADIANCE))
                return pf_error_set(err, PF_ERR_NONFINITE, "material %u has an emission outside [0, %g]", m,
                                    (double)PF_MAX_RADIANCE);
        if (mat->base_color_texture >= (int32_t)s->texture_count)
            return pf_error_set(err, PF_ERR_INDEX_RANGE, "material %u uses texture %d of %u", m,
                                mat->base_color_texture, s->texture_count);
    }
    for (uint32_t t = 0; t < s->texture_count; t++)
        if (s->textures[t].image >= s->image_count || !s->images[s->textures[t].image].texels)
            return pf_error_set(err, PF_ERR_TEXTURE, "texture %u has no image data", t);
    for (uint32_t c = 0; c < s->camera_count; c++) {
        const pf_camera *cam = &s->cameras[c];
        if (!pf_scene_coord_ok(cam->eye) || !pf_v3_is_finite(cam->forward) || !isfinite(cam->yfov))
            return pf_error_set(err, PF_ERR_NONFINITE, "camera %u has a non-finite or huge placement", c);
        if (!(cam->yfov > 0.0f && cam->yfov < PF_PI))
            return pf_error_set(err, PF_ERR_PARSE, "camera %u has yfov %g rad, outside (0, pi)", c,
                                (double)cam->yfov);
    }
    for (uint32_t l = 0; l < s->light_count; l++) {
        const pf_light *li = &s->lights[l];
        if (!pf_scene_coord_ok(li->position) || !pf_v3_is_finite(li->direction) || !pf_v3_is_finite(li->color) ||
            !isfinite(li->intensity))
            return pf_error_set(err, PF_ERR_NONFINITE, "light %u ('%s') has a non-finite or huge value", l,
                                li->name);
        if (li->intensity < 0.0f || li->color.x < 0.0f || li->color.y < 0.0f || li->color.z < 0.0f)
            return pf_error_set(err, PF_ERR_PARSE, "light %u ('%s') has a negative intensity or colour", l,
                                li->name);
        float cmax = fmaxf(li->color.x, fmaxf(li->color.y, li->color.z));
        if ((double)li->intensity * cmax > PF_MAX_RADIANCE)
            return pf_error_set(err, PF_ERR_NONFINITE,
                                "light %u ('%s'): intensity x colour %g exceeds softgi's limit %g (W/sr or W/m^2)", l,
                                li->name, (double)li->intensity * cmax, (double)PF_MAX_RADIANCE);
        if (li->type == PF_LIGHT_SPOT &&
            !(li->inner_cone >= 0.0f && li->inner_cone < li->outer_cone && li->outer_cone <= 0.5f * PF_PI))
            return pf_error_set(err, PF_ERR_PARSE,
                                "spot light %u ('%s') needs 0 <= innerConeAngle < outerConeAngle <= pi/2 "
                                "(got %g, %g rad)",
                                l, li->name, (double)li->inner_cone, (double)li->outer_cone);
    }
    s->bounds_min = lo;
    s->bounds_max = hi;
    return PF_OK;
}

pf_result pf_scene_add_light(pf_scene *s, const pf_light *light, pf_error *err)
{
    pf_light *grown = realloc(s->lights, (s->light_count + 1) * sizeof *grown);
    if (!grown) return pf_error_set(err, PF_ERR_OUT_OF_MEMORY, "out of memory adding a light");
    s->lights = grown;
    s->lights[s->light_count++] = *light;
    return PF_OK;
}

/* ---------------------------------------------------------------- emissive quads */

/* The quad's tests in double: the corners are floats, so their differences
 * and cross products are exact to about 1e-16 relative, far below the
 * tolerances (1e-6 d^2 for a turn, 1e-3 d for planarity). */
typedef struct pf__d3 {
    double x, y, z;
} pf__d3;
static pf__d3 pf__d3_of(pf_vec3 v) { return (pf__d3){v.x, v.y, v.z}; }
static pf__d3 pf__d3_sub(pf__d3 a, pf__d3 b) { return (pf__d3){a.x - b.x, a.y - b.y, a.z - b.z}; }
static double pf__d3_dot(pf__d3 a, pf__d3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
static pf__d3 pf__d3_cross(pf__d3 a, pf__d3 b)
{
    return (pf__d3){a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}

pf_result pf_scene_emitter_quad_check(const pf_vec3 corners[4], pf_vec3 emission, pf_vec3 *normal, pf_error *err)
{
    for (int i = 0; i < 4; i++) {
        pf_vec3 c = corners[i];
        if (!pf_v3_is_finite(c)) return pf_error_set(err, PF_ERR_NONFINITE, "corner %d is not finite", i);
        if (!pf_scene_coord_ok(c))
            return pf_error_set(err, PF_ERR_NONFINITE, "corner %d (%g, %g, %g) lies beyond |x| <= %g", i, (double)c.x,
                                (double)c.y, (double)c.z, (double)PF_SCENE_MAX_COORD);
    }
    const float e[3] = {emission.x, emission.y, emission.z};
    for (int k = 0; k < 3; k++) {
        if (!isfinite(e[k])) return pf_error_set(err, PF_ERR_NONFINITE, "emission is not finite");
        if (e[k] < 0.0f) return pf_error_set(err, PF_ERR_PARSE, "emission must be >= 0 (got %g)", (double)e[k]);
        if (e[k] > PF_MAX_RADIANCE)
            return pf_error_set(err, PF_ERR_NONFINITE, "emission %g exceeds softgi's limit %g W/(sr m^2)",
                                (double)e[k], (double)PF_MAX_RADIANCE);
    }
    if (e[0] == 0.0f && e[1] == 0.0f && e[2] == 0.0f)
        return pf_error_set(err, PF_ERR_PARSE, "emission is zero (an emitter must emit)");

    pf__d3 p[4];
    for (int i = 0; i < 4; i++) p[i] = pf__d3_of(corners[i]);
    /* The vector area of a planar quad is half the cross product of its
     * diagonals, whatever its shape; n points to the side from which the
     * corners run counter-clockwise. */
    pf__d3 d1 = pf__d3_sub(p[2], p[0]), d2 = pf__d3_sub(p[3], p[1]);
    double diag = sqrt(fmax(pf__d3_dot(d1, d1), pf__d3_dot(d2, d2)));
    pf__d3 n = pf__d3_cross(d1, d2);
    double nl = sqrt(pf__d3_dot(n, n));
    if (!(diag > 0.0)) return pf_error_set(err, PF_ERR_PARSE, "the four corners coincide");
    if (!(nl > 1e-6 * diag * diag))
        return pf_error_set(err, PF_ERR_PARSE,
                            "the quad has no area (corners repeated or collinear, or out of order as a bow-tie)");
    pf__d3 nh = {n.x / nl, n.y / nl, n.z / nl};
    /* planar: every corner near the plane through their mean */
    pf__d3 m = {0.25 * (p[0].x + p[1].x + p[2].x + p[3].x), 0.25 * (p[0].y + p[1].y + p[2].y + p[3].y),
                0.25 * (p[0].z + p[1].z + p[2].z + p[3].z)};
    for (int i = 0; i < 4; i++) {
        double dist = fabs(pf__d3_dot(pf__d3_sub(p[i], m), nh));
        if (dist > PF_SCENE_EMITTER_PLANARITY * diag)
            return pf_error_set(err, PF_ERR_PARSE,
                                "not planar: corner %d is %g from the quad's plane (at most %g x the diagonal %g)", i,
                                dist, PF_SCENE_EMITTER_PLANARITY, diag);
    }
    /* convex, corners in order: every corner turns the same way as n */
    for (int i = 0; i < 4; i++) {
        pf__d3 a = pf__d3_sub(p[i], p[(i + 3) % 4]), b = pf__d3_sub(p[(i + 1) % 4], p[i]);
        if (!(pf__d3_dot(pf__d3_cross(a, b), nh) > 1e-6 * diag * diag))
            return pf_error_set(err, PF_ERR_PARSE,
                                "corner %d: the quad is not convex with its corners in order (corners %d, %d, %d are "
                                "collinear or turn the other way)",
                                i, (i + 3) % 4, i, (i + 1) % 4);
    }
    if (!(0.5 * nl >= PF_SCENE_EMITTER_MIN_AREA))
        return pf_error_set(err, PF_ERR_PARSE, "the quad's area %g is below %g (units^2)", 0.5 * nl,
                            PF_SCENE_EMITTER_MIN_AREA);
    /* What the renderer computes in float (pf_scene_face_normal, gi_area):
     * both triangles' normals must agree with n. */
    static const int tri[2][3] = {{0, 1, 2}, {0, 2, 3}};
    for (int t = 0; t < 2; t++) {
        pf_vec3 a = corners[tri[t][0]];
        pf_vec3 fn = pf_v3_cross(pf_v3_sub(corners[tri[t][1]], a), pf_v3_sub(corners[tri[t][2]], a));
        float len = pf_v3_length(fn);
        if (!(isfinite(len) && len > 0.0f) ||
            !((double)fn.x * nh.x + (double)fn.y * nh.y + (double)fn.z * nh.z > 0.999 * (double)len))
            return pf_error_set(err, PF_ERR_PARSE, "triangle %d of the quad has no reliable normal in single precision",
                                t);
    }
    if (normal) *normal = pf_v3((float)nh.x, (float)nh.y, (float)nh.z);
    return PF_OK;
}

/* realloc of count elements, refusing a byte count size_t cannot hold */
static int pf__grow(void **ptr, size_t count, size_t size)
{
    if (count > SIZE_MAX / size) return 0;
    void *p = realloc(*ptr, count * size);
    if (!p) return 0;
    *ptr = p;
    return 1;
}

pf_result pf_scene_add_emitter_quad(pf_scene *s, const pf_vec3 corners[4], pf_vec3 emission, int two_sided,
                                    pf_error *err)
{
    pf_vec3 n;
    pf_result r = pf_scene_emitter_quad_check(corners, emission, &n, err);
    if (r != PF_OK) return r;
    /* 4 more vertices (+ 1 padding position), 2 triangles, 1 material */
    if (s->vertex_count > UINT32_MAX - 5 || s->tri_count > UINT32_MAX / 3 - 2 || s->material_count > UINT32_MAX - 1)
        return pf_error_set(err, PF_ERR_OUT_OF_MEMORY, "the scene is too large to add an emitter");
    const size_t nv = (size_t)s->vertex_count + 4, nt = (size_t)s->tri_count + 2;
    const size_t nm = (size_t)s->material_count + 1;
    /* Each array grows before any count changes: a failure leaves a valid
     * scene whose arrays are merely larger than needed. */
    if (!pf__grow((void **)&s->positions, nv + 1, sizeof *s->positions) ||
        !pf__grow((void **)&s->normals, nv, sizeof *s->normals) || !pf__grow((void **)&s->uvs, nv, sizeof *s->uvs) ||
        !pf__grow((void **)&s->indices, 3 * nt, sizeof *s->indices) ||
        !pf__grow((void **)&s->tri_material, nt, sizeof *s->tri_material) ||
        !pf__grow((void **)&s->materials, nm, sizeof *s->materials))
        return pf_error_set(err, PF_ERR_OUT_OF_MEMORY, "out of memory adding an emitter");

    pf_material *mat = &s->materials[s->material_count];
    memset(mat, 0, sizeof *mat);
    snprintf(mat->name, sizeof mat->name, "emitter-quad-%u", s->material_count);
    for (int k = 0; k < 3; k++) mat->base_color[k] = 0.78f;
    mat->base_color[3] = 1.0f;
    mat->base_color_texture = -1;
    mat->emission[0] = emission.x;
    mat->emission[1] = emission.y;
    mat->emission[2] = emission.z;
    mat->alpha_mode = PF_ALPHA_OPAQUE;
    mat->alpha_cutoff = 0.5f;
    mat->double_sided = two_sided != 0;

    static const pf_vec2 uv[4] = {{0.0f, 0.0f}, {1.0f, 0.0f}, {1.0f, 1.0f}, {0.0f, 1.0f}};
    const uint32_t v0 = s->vertex_count;
    for (uint32_t i = 0; i < 4; i++) {
        s->positions[v0 + i] = corners[i];
        s->normals[v0 + i] = n;
        s->uvs[v0 + i] = uv[i];
    }
    s->positions[v0 + 4] = corners[3]; /* padding: Embree may read 16 bytes at the last vertex */
    static const uint32_t idx[6] = {0, 1, 2, 0, 2, 3};
    for (int k = 0; k < 6; k++) s->indices[3 * (size_t)s->tri_count + k] = v0 + idx[k];
    s->tri_material[s->tri_count] = s->material_count;
    s->tri_material[s->tri_count + 1] = s->material_count;
    s->vertex_count += 4;
    s->tri_count += 2;
    s->material_count += 1;
    /* a loaded scene's estimate (pf_budget.h); 0 stays 0 for scenes built in memory */
    if (s->memory_bytes) s->memory_bytes += pf_budget_mul(2, PF_BUDGET_BYTES_PER_TRIANGLE);
    return PF_OK;
}

pf_result pf_camera_look_at(pf_camera *cam, pf_vec3 eye, pf_vec3 target, float yfov, pf_error *err)
{
    pf_vec3 f = pf_v3_normalize(pf_v3_sub(target, eye));
    if (!pf_v3_is_finite(eye) || !pf_v3_is_finite(target) || pf_v3_length(f) == 0.0f)
        return pf_error_set(err, PF_ERR_ARGUMENT, "camera eye and target must be finite and distinct");
    if (!(yfov > 0.0f && yfov < PF_PI))
        return pf_error_set(err, PF_ERR_ARGUMENT, "camera field of view must be in (0, 180) degrees");
    /* +Y up unless looking (almost) straight up or down: then +Z. */
    pf_vec3 up_hint = fabsf(f.y) > 0.999f ? pf_v3(0, 0, 1) : pf_v3(0, 1, 0);
    pf_vec3 r = pf_v3_normalize(pf_v3_cross(f, up_hint));
    memset(cam, 0, sizeof *cam);
    snprintf(cam->name, sizeof cam->name, "cli");
    cam->eye = eye;
    cam->forward = f;
    cam->right = r;
    cam->up = pf_v3_cross(r, f);
    cam->yfov = yfov;
    cam->znear = 0.01f;
    return PF_OK;
}

pf_vec3 pf_camera_ray_dir(const pf_camera *cam, uint32_t width, uint32_t height, float x, float y)
{
    float th = tanf(0.5f * cam->yfov);
    float aspect = (float)width / (float)height;
    float sx = (2.0f * x / (float)width - 1.0f) * th * aspect;
    float sy = (1.0f - 2.0f * y / (float)height) * th;
    return pf_v3_add(cam->forward, pf_v3_add(pf_v3_scale(cam->right, sx), pf_v3_scale(cam->up, sy)));
}

pf_vec3 pf_scene_face_normal(const pf_scene *s, uint32_t prim)
{
    const uint32_t *tri = &s->indices[3 * prim];
    pf_vec3 p0 = s->positions[tri[0]];
    return pf_v3_normalize(pf_v3_cross(pf_v3_sub(s->positions[tri[1]], p0), pf_v3_sub(s->positions[tri[2]], p0)));
}

void pf_scene_surface(const pf_scene *s, uint32_t prim, float u, float v, float lod, pf_surface *out)
{
    const uint32_t *tri = &s->indices[3 * prim];
    float w = 1.0f - u - v;
    pf_vec3 p0 = s->positions[tri[0]], p1 = s->positions[tri[1]], p2 = s->positions[tri[2]];
    out->p = pf_v3_add(pf_v3_add(pf_v3_scale(p0, w), pf_v3_scale(p1, u)), pf_v3_scale(p2, v));
    out->ng = pf_v3_normalize(pf_v3_cross(pf_v3_sub(p1, p0), pf_v3_sub(p2, p0)));
    pf_vec3 n0 = s->normals[tri[0]], n1 = s->normals[tri[1]], n2 = s->normals[tri[2]];
    out->ns = pf_v3_normalize(pf_v3_add(pf_v3_add(pf_v3_scale(n0, w), pf_v3_scale(n1, u)), pf_v3_scale(n2, v)));
    if (out->ns.x == 0.0f && out->ns.y == 0.0f && out->ns.z == 0.0f) out->ns = out->ng;
    pf_vec2 a = s->uvs[tri[0]], b = s->uvs[tri[1]], c = s->uvs[tri[2]];
    out->uv.x = w * a.x + u * b.x + v * c.x;
    out->uv.y = w * a.y + u * b.y + v * c.y;
    out->material = s->tri_material[prim];
    out->prim = prim;
    pf_material_sample(s, out->material, out->uv, lod, out->albedo);
}
