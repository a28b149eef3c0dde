/* rs_simplify: the simplified shadow copy of a scene (see rs_simplify.h).
 *
 * This work is based on: meshoptimizer 0.18 (Kapoulkine), whose
 * meshopt_simplify is an edge-collapse simplifier driven by quadric error
 * metrics (Garland & Heckbert, Surface Simplification Using Quadric Error
 * Metrics, SIGGRAPH 1997), and Laine et al. 2007 Sec. 6, who render shadow
 * maps from a separate copy of the scene. Deterministic: meshoptimizer is
 * single-threaded and its output depends only on its input arrays. */
#include "rs_simplify.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <meshoptimizer.h>

pf_result rs_simplify_scene(pf_scene *dst, const pf_scene *src, const rs_simplify_options *opts,
                            rs_simplify_report *report, pf_error *err)
{
    memset(dst, 0, sizeof *dst);
    rs_simplify_options o = {0};
    if (opts) o = *opts;
    if (o.ratio == 0.0f) o.ratio = 0.5f;
    if (o.max_error == 0.0f) o.max_error = 1.0f;
    if (!(o.ratio > 0.0f && o.ratio <= 1.0f))
        return pf_error_set(err, PF_ERR_ARGUMENT, "simplification ratio %g is outside (0, 1]", (double)o.ratio);
    if (!(o.max_error > 0.0f) || !isfinite(o.max_error))
        return pf_error_set(err, PF_ERR_ARGUMENT, "simplification error %g is not a positive number",
                            (double)o.max_error);
    if (!src || src->tri_count == 0)
        return pf_error_set(err, PF_ERR_NO_TRIANGLES, "simplify: the scene has no triangles");

    size_t index_count = (size_t)src->tri_count * 3, vcount = src->vertex_count;
    unsigned int *remap = malloc(vcount * sizeof(unsigned int));
    unsigned int *welded_idx = malloc(index_count * sizeof(unsigned int));
    unsigned int *simple_idx = malloc(index_count * sizeof(unsigned int));
    pf_vec3 *welded_pos = malloc((vcount + 1) * sizeof(pf_vec3));
    unsigned int *compact = malloc((vcount + 1) * sizeof(unsigned int));
    pf_result res = PF_OK;
    if (!remap || !welded_idx || !simple_idx || !welded_pos || !compact) {
        res = pf_error_set(err, PF_ERR_OUT_OF_MEMORY, "simplify: out of memory");
        goto done;
    }

    /* 1. weld by position only (bit-identical floats) */
    size_t unique = meshopt_generateVertexRemap(remap, src->indices, index_count, src->positions, vcount,
                                                sizeof(pf_vec3));
    meshopt_remapVertexBuffer(welded_pos, src->positions, vcount, sizeof(pf_vec3), remap);
    meshopt_remapIndexBuffer(welded_idx, src->indices, index_count, remap);

    /* 2. simplify */
    size_t target = (size_t)((double)src->tri_count * o.ratio) * 3;
    if (target < 3) target = 3;
    float rel_error = 0.0f;
    size_t out_count = index_count;
    if (o.ratio < 1.0f)
        out_count = meshopt_simplify(simple_idx, welded_idx, index_count, &welded_pos[0].x, unique, sizeof(pf_vec3),
                                     target, o.max_error, o.lock_border ? meshopt_SimplifyLockBorder : 0,
                                     &rel_error);
    else
        memcpy(simple_idx, welded_idx, index_count * sizeof(unsigned int));

    /* 3. compact: drop degenerate triangles, then unused vertices */
    size_t kept = 0;
    for (size_t t = 0; t < out_count / 3; t++) {
        unsigned int a = simple_idx[3 * t], b = simple_idx[3 * t + 1], c = simple_idx[3 * t + 2];
        if (a == b || b == c || c == a) continue;
        pf_vec3 n = pf_v3_cross(pf_v3_sub(welded_pos[b], welded_pos[a]), pf_v3_sub(welded_pos[c], welded_pos[a]));
        if (!(pf_v3_dot(n, n) > 0.0f)) continue;
        simple_idx[kept++] = a;
        simple_idx[kept++] = b;
        simple_idx[kept++] = c;
    }
    if (kept == 0) {
        res = pf_error_set(err, PF_ERR_NO_TRIANGLES, "simplify: nothing is left of the scene at ratio %g",
                           (double)o.ratio);
        goto done;
    }
    for (size_t v = 0; v < unique; v++) compact[v] = ~0u;
    uint32_t vout = 0;
    for (size_t k = 0; k < kept; k++) {
        unsigned int v = simple_idx[k];
        if (compact[v] == ~0u) compact[v] = vout++;
    }

    dst->vertex_count = vout;
    dst->tri_count = (uint32_t)(kept / 3);
    dst->positions = calloc((size_t)vout + 1, sizeof(pf_vec3));
    dst->normals = calloc(vout, sizeof(pf_vec3));
    dst->uvs = calloc(vout, sizeof(pf_vec2));
    dst->indices = malloc(kept * sizeof(uint32_t));
    dst->tri_material = calloc(dst->tri_count, sizeof(uint32_t));
    dst->material_count = 1;
    dst->materials = calloc(1, sizeof(pf_material));
    if (!dst->positions || !dst->normals || !dst->uvs || !dst->indices || !dst->tri_material || !dst->materials) {
        res = pf_error_set(err, PF_ERR_OUT_OF_MEMORY, "simplify: out of memory");
        goto done;
    }
    for (size_t v = 0; v < unique; v++)
        if (compact[v] != ~0u) dst->positions[compact[v]] = welded_pos[v];
    for (size_t k = 0; k < kept; k++) dst->indices[k] = compact[simple_idx[k]];
    /* smooth normals (area-weighted face normals): shadow geometry needs
     * none, but a pf_scene carries them */
    for (uint32_t t = 0; t < dst->tri_count; t++) {
        const uint32_t *ix = &dst->indices[3 * t];
        pf_vec3 a = dst->positions[ix[0]], b = dst->positions[ix[1]], c = dst->positions[ix[2]];
        pf_vec3 n = pf_v3_cross(pf_v3_sub(b, a), pf_v3_sub(c, a));
        for (int k = 0; k < 3; k++) dst->normals[ix[k]] = pf_v3_add(dst->normals[ix[k]], n);
    }
    for (uint32_t v = 0; v < vout; v++) {
        pf_vec3 n = pf_v3_normalize_safe(dst->normals[v]);
        dst->normals[v] = pf_v3_dot(n, n) > 0.0f ? n : pf_v3(0.0f, 1.0f, 0.0f);
    }
    pf_material *m = &dst->materials[0];
    snprintf(m->name, sizeof m->name, "shadow");
    for (int k = 0; k < 4; k++) m->base_color[k] = 1.0f;
    m->base_color_texture = -1;
    res = pf_scene_validate(dst, err);
    if (res == PF_OK && report) {
        report->tri_in = src->tri_count;
        report->tri_out = dst->tri_count;
        report->vertex_in = src->vertex_count;
        report->vertex_welded = (uint32_t)unique;
        report->vertex_out = vout;
        report->error_relative = rel_error;
        report->error_absolute = rel_error * meshopt_simplifyScale(&welded_pos[0].x, unique, sizeof(pf_vec3));
    }

done:
    if (res != PF_OK) pf_scene_free(dst);
    free(remap);
    free(welded_idx);
    free(simple_idx);
    free(welded_pos);
    free(compact);
    return res;
}
