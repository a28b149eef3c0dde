/* pf_anim: sampling glTF 2.0 animations and posing the flattened scene
 * (pf_anim.h; glTF 2.0 Sec. 3.11, 3.7.3, 3.7.2.2 and Appendix C).
 *
 * One pose, in order:
 *   1. pf_anim_evaluate: every node's TRS from its static values, then the
 *      selected animations' channels in file order (pf__anim_sample); the
 *      nodes' world matrices in the loader's walk order (parents first, in
 *      double); the morph weights; the skins' joint matrices;
 *   2. per dynamic primitive, pf_anim_prim_deform: morph deltas added, then
 *      the skin or the node's matrix; positions checked;
 *   3. the scene's vertices rewritten (flat primitives: face normals from
 *      the posed corners), what moved noted, the bounds recomputed.
 * The formulas of step 2 for a rigid primitive are the loader's
 * (pf_gltf.cpp, Builder::add_primitive) operation for operation, so the
 * static pose gives back the loaded bytes. */
#include "pf_anim.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* ---------------------------------------------------------------- ownership */

void pf_anim_prim_free(pf_anim_prim *p)
{
    free(p->local_pos);
    free(p->local_nrm);
    free(p->src);
    free(p->target_pos);
    free(p->target_nrm);
    free(p->joint);
    free(p->weight);
    p->local_pos = p->local_nrm = p->target_pos = p->target_nrm = NULL;
    p->src = NULL;
    p->joint = NULL;
    p->weight = NULL;
}

void pf_anim_free(pf_anim *a)
{
    if (!a) return;
    for (uint32_t i = 0; i < a->node_count && a->nodes; i++) {
        free(a->nodes[i].rest_weights);
        free(a->nodes[i].weights);
    }
    free(a->nodes);
    free(a->order);
    free(a->world);
    for (uint32_t i = 0; i < a->skin_count && a->skins; i++) {
        free(a->skins[i].joints);
        free(a->skins[i].ibm);
        free(a->skins[i].joint_mats);
    }
    free(a->skins);
    for (uint32_t i = 0; i < a->clip_count && a->clips; i++) {
        pf_anim_clip *c = &a->clips[i];
        for (uint32_t s = 0; s < c->sampler_count && c->samplers; s++) {
            free(c->samplers[s].times);
            free(c->samplers[s].values);
        }
        free(c->samplers);
        free(c->channels);
    }
    free(a->clips);
    for (uint32_t i = 0; i < a->prim_count && a->prims; i++) pf_anim_prim_free(&a->prims[i]);
    free(a->prims);
    free(a->scratch_pos);
    free(a->scratch_nrm);
    free(a->trs);
    memset(a, 0, sizeof *a);
    a->pose_clip = PF_ANIM_STATIC;
}

/* "0 'walk', 1 'run'" (cut short for a file with many) */
static void pf__anim_list(const pf_anim *a, char *buf, size_t size)
{
    size_t n = 0;
    buf[0] = 0;
    for (uint32_t i = 0; i < a->clip_count && n + 1 < size; i++) {
        int w = snprintf(buf + n, size - n, "%s%u '%.40s'", i ? ", " : "", i, a->clips[i].name);
        if (w < 0) break;
        n += (size_t)w;
        if (n >= size - 1 || (i >= 7 && i + 1 < a->clip_count)) {
            if (i + 1 < a->clip_count && size > 8) snprintf(buf + (n < size - 6 ? n : size - 6), 6, ", ...");
            break;
        }
    }
}

pf_result pf_anim_find(const pf_anim *a, const char *name, int64_t index, int32_t *clip, pf_error *err)
{
    char list[320];
    if (a->clip_count == 0)
        return pf_error_set(err, PF_ERR_ARGUMENT, "the scene has no animations");
    pf__anim_list(a, list, sizeof list);
    if (name) {
        for (uint32_t i = 0; i < a->clip_count; i++)
            if (!strcmp(a->clips[i].name, name)) {
                *clip = (int32_t)i;
                return PF_OK;
            }
        return pf_error_set(err, PF_ERR_ARGUMENT, "no animation named '%.64s' (the file has %u: %s)", name,
                            a->clip_count, list);
    }
    if (index < 0 || index >= (int64_t)a->clip_count)
        return pf_error_set(err, PF_ERR_ARGUMENT, "no animation %lld (the file has %u: %s)", (long long)index,
                            a->clip_count, list);
    *clip = (int32_t)index;
    return PF_OK;
}

double pf_anim_end(const pf_anim *a, int32_t clip)
{
    double end = 0.0;
    for (uint32_t i = 0; i < a->clip_count; i++)
        if ((clip == PF_ANIM_ALL || clip == (int32_t)i) && a->clips[i].end > end) end = a->clips[i].end;
    return end;
}

/* ---------------------------------------------------------------- transforms */

pf_mat4 pf_anim_trs_matrix(const double t[3], const double q[4], const double s[3])
{
    /* R from the unit quaternion, columns scaled by S, then T (glTF 2.0
     * Sec. 3.5.3: M = T * R * S). Written as the loader always wrote it. */
    pf_mat4 r = pf_mat4_identity();
    double x = q[0], y = q[1], z = q[2], w = q[3];
    double rot[9] = {1 - 2 * (y * y + z * z), 2 * (x * y + z * w),     2 * (x * z - y * w),
                     2 * (x * y - z * w),     1 - 2 * (x * x + z * z), 2 * (y * z + x * w),
                     2 * (x * z + y * w),     2 * (y * z - x * w),     1 - 2 * (x * x + y * y)};
    for (int c = 0; c < 3; c++)
        for (int rr = 0; rr < 3; rr++) r.m[c * 4 + rr] = rot[c * 3 + rr] * s[c];
    r.m[12] = t[0];
    r.m[13] = t[1];
    r.m[14] = t[2];
    return r;
}

/* ---------------------------------------------------------------- sampling */

/* The last key k with times[k] <= t, for times[0] <= t < times[n-1]. */
static uint32_t pf__anim_key(const float *times, uint32_t n, double t)
{
    uint32_t lo = 0, hi = n - 1;
    while (hi - lo > 1) {
        uint32_t mid = lo + (hi - lo) / 2;
        if ((double)times[mid] <= t) lo = mid;
        else hi = mid;
    }
    return lo;
}

/* Eberly 2011's slerp coefficients (pf_anim.h): for x = cos(theta) in
 * [0, 1], cd = sin((1-s) theta) / sin(theta) and ct = sin(s theta) /
 * sin(theta) as the nested series
 *   f(s) = s (1 + b_1(s) (1 + b_2(s) (1 + ...))),
 *   b_i(s) = (s^2 - i^2) / (i (2i + 1)) (x - 1),
 * here with u_i = 1 / (i (2i + 1)), v_i = i / (2i + 1), so b_i = (u_i s^2 -
 * v_i)(x - 1). 32 terms: at theta = 90 degrees (x = 0, the slowest case)
 * the truncation error is about 1e-11. */
#define PF__SLERP_TERMS 32
static void pf__slerp_coeffs(double x, double s, double *cd, double *ct)
{
    const double xm1 = x - 1.0, d = 1.0 - s, s2 = s * s, d2 = d * d;
    double ft = 1.0, fd = 1.0;
    for (int i = PF__SLERP_TERMS; i >= 1; i--) {
        const double u = 1.0 / ((double)i * (2.0 * i + 1.0)), v = (double)i / (2.0 * i + 1.0);
        ft = 1.0 + (u * s2 - v) * xm1 * ft;
        fd = 1.0 + (u * d2 - v) * xm1 * fd;
    }
    *ct = s * ft;
    *cd = d * fd;
}

/* q /= |q| in place; 0 when q is zero or not finite (q untouched). */
static int pf__quat_normalize(double q[4])
{
    double len = sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
    if (!(len > 0.0) || !isfinite(len)) return 0;
    for (int i = 0; i < 4; i++) q[i] /= len;
    return 1;
}

/* Sampler s at time t into out[dim] (double). Rotations come out unit. */
static void pf__anim_sample(const pf_anim_sampler *s, pf_anim_path path, double t, double *out)
{
    const uint32_t n = s->key_count, dim = s->dim;
    const int cubic = s->interp == PF_ANIM_CUBICSPLINE;
    const size_t stride = cubic ? 3u * dim : dim, at = cubic ? dim : 0; /* the value within a key */
#define PF__VAL(k, c) ((double)s->values[(size_t)(k) * stride + at + (c)])
    uint32_t k = 0;
    if (n == 1 || t <= (double)s->times[0]) k = 0;
    else if (t >= (double)s->times[n - 1]) k = n - 1;
    else k = pf__anim_key(s->times, n, t);
    const int between = n > 1 && t > (double)s->times[0] && t < (double)s->times[n - 1];
    if (!between || s->interp == PF_ANIM_STEP) {
        for (uint32_t c = 0; c < dim; c++) out[c] = PF__VAL(k, c);
    } else {
        /* t in [t_k, t_k+1): u = (t - t_k) / (t_k+1 - t_k), exact at t_k */
        const double t0 = s->times[k], t1 = s->times[k + 1], td = t1 - t0, u = (t - t0) / td;
        if (!cubic && path == PF_ANIM_ROTATION) {
            double a[4], b[4], dot = 0.0, cd, ct;
            for (int c = 0; c < 4; c++) a[c] = PF__VAL(k, c), b[c] = PF__VAL(k + 1, c);
            pf__quat_normalize(a); /* keys are non-zero (checked at load) */
            pf__quat_normalize(b);
            for (int c = 0; c < 4; c++) dot += a[c] * b[c];
            const double sign = dot < 0.0 ? -1.0 : 1.0; /* the shortest path: -b is the same rotation */
            pf__slerp_coeffs(dot * sign > 1.0 ? 1.0 : dot * sign, u, &cd, &ct);
            for (int c = 0; c < 4; c++) out[c] = cd * a[c] + sign * ct * b[c];
        } else if (!cubic) {
            for (uint32_t c = 0; c < dim; c++) out[c] = (1.0 - u) * PF__VAL(k, c) + u * PF__VAL(k + 1, c);
        } else {
            /* Appendix C: p(u) = (2u^3 - 3u^2 + 1) v_k + td (u^3 - 2u^2 + u) b_k
             *                  + (-2u^3 + 3u^2) v_k+1 + td (u^3 - u^2) a_k+1,
             * b_k the out-tangent of key k, a_k+1 the in-tangent of key k+1 */
            const double u2 = u * u, u3 = u2 * u;
            const double h00 = 2 * u3 - 3 * u2 + 1, h10 = u3 - 2 * u2 + u, h01 = -2 * u3 + 3 * u2, h11 = u3 - u2;
            for (uint32_t c = 0; c < dim; c++) {
                const double vk = PF__VAL(k, c), vk1 = PF__VAL(k + 1, c);
                const double bk = (double)s->values[(size_t)k * stride + 2u * dim + c];
                const double ak1 = (double)s->values[(size_t)(k + 1) * stride + c];
                out[c] = h00 * vk + td * h10 * bk + h01 * vk1 + td * h11 * ak1;
            }
        }
    }
    if (path == PF_ANIM_ROTATION && !pf__quat_normalize(out)) {
        /* a cubic through opposite keys can pass through zero: key k's value */
        for (int c = 0; c < 4; c++) out[c] = PF__VAL(k, c);
        pf__quat_normalize(out);
    }
#undef PF__VAL
}

void pf_anim_evaluate(pf_anim *a, int32_t clip, double t)
{
    /* 1. static TRS and weights */
    for (uint32_t i = 0; i < a->node_count; i++) {
        const pf_anim_node *n = &a->nodes[i];
        double *trs = a->trs + (size_t)i * 10;
        memcpy(trs, n->t, sizeof n->t);
        memcpy(trs + 3, n->r, sizeof n->r);
        memcpy(trs + 7, n->s, sizeof n->s);
        if (n->weight_count) memcpy(n->weights, n->rest_weights, sizeof(float) * n->weight_count);
    }
    /* 2. the channels, in file order */
    for (uint32_t ci = 0; clip != PF_ANIM_STATIC && ci < a->clip_count; ci++) {
        if (clip != PF_ANIM_ALL && clip != (int32_t)ci) continue;
        const pf_anim_clip *c = &a->clips[ci];
        for (uint32_t k = 0; k < c->channel_count; k++) {
            const pf_anim_channel *ch = &c->channels[k];
            const pf_anim_sampler *s = &c->samplers[ch->sampler];
            pf_anim_node *n = &a->nodes[ch->node];
            double *trs = a->trs + (size_t)ch->node * 10;
            if (ch->path == PF_ANIM_WEIGHTS) {
                double w[PF_ANIM_MAX_TARGETS];
                pf__anim_sample(s, ch->path, t, w);
                for (uint32_t q = 0; q < n->weight_count; q++) n->weights[q] = (float)w[q];
            } else {
                pf__anim_sample(s, ch->path, t, trs + (ch->path == PF_ANIM_TRANSLATION ? 0
                                                       : ch->path == PF_ANIM_ROTATION  ? 3
                                                                                       : 7));
            }
        }
    }
    /* 3. world matrices, parents first */
    for (uint32_t o = 0; o < a->order_count; o++) {
        const uint32_t i = a->order[o];
        const pf_anim_node *n = &a->nodes[i];
        const double *trs = a->trs + (size_t)i * 10;
        pf_mat4 local = n->has_matrix ? n->matrix : pf_anim_trs_matrix(trs, trs + 3, trs + 7);
        pf_mat4 parent = n->parent >= 0 ? a->world[n->parent] : pf_mat4_identity();
        a->world[i] = pf_mat4_mul(&parent, &local);
    }
    /* 4. joint matrices */
    for (uint32_t si = 0; si < a->skin_count; si++) {
        pf_anim_skin *sk = &a->skins[si];
        if (!sk->used) continue;
        for (uint32_t j = 0; j < sk->joint_count; j++)
            sk->joint_mats[j] = pf_mat4_mul(&a->world[sk->joints[j]], &sk->ibm[j]);
    }
}

/* ---------------------------------------------------------------- deforming */

/* The position and normal of file vertex v after the morph targets (in
 * double, rounded once; a target of weight 0 is skipped, so an unmorphed
 * vertex keeps its bits). */
static void pf__anim_morph(const pf_anim_prim *p, const float *w, uint32_t v, pf_vec3 *pos, pf_vec3 *nrm)
{
    *pos = p->local_pos[v];
    if (nrm) *nrm = p->local_nrm[v];
    int any = 0;
    for (uint32_t k = 0; k < p->target_count; k++) any |= w[k] != 0.0f;
    if (!any) return;
    double P[3] = {pos->x, pos->y, pos->z}, N[3] = {0, 0, 0};
    if (nrm) N[0] = nrm->x, N[1] = nrm->y, N[2] = nrm->z;
    for (uint32_t k = 0; k < p->target_count; k++) {
        if (w[k] == 0.0f) continue;
        const size_t at = (size_t)k * p->local_count + v;
        if (p->target_pos) {
            const pf_vec3 d = p->target_pos[at];
            P[0] += (double)w[k] * d.x, P[1] += (double)w[k] * d.y, P[2] += (double)w[k] * d.z;
        }
        if (nrm && p->target_nrm) {
            const pf_vec3 d = p->target_nrm[at];
            N[0] += (double)w[k] * d.x, N[1] += (double)w[k] * d.y, N[2] += (double)w[k] * d.z;
        }
    }
    *pos = pf_v3((float)P[0], (float)P[1], (float)P[2]);
    if (nrm) *nrm = pf_v3((float)N[0], (float)N[1], (float)N[2]);
}

/* pf_v3_normalize_safe, and zero where that is not finite: a denormal
 * largest component (a near-singular skin or pose matrix) overflows its
 * 1 / max without DAZ (found by fuzz_gltf; softgi itself runs with DAZ,
 * where such a vector is already zero). A zero normal then takes the
 * loader's fallback (a face normal, or (0, 1, 0)). Where the loader's own
 * normalisation succeeds this gives its bits. */
pf_vec3 pf_anim_unit(pf_vec3 v)
{
    pf_vec3 r = pf_v3_normalize_safe(v);
    return pf_v3_is_finite(r) ? r : pf_v3(0.0f, 0.0f, 0.0f);
}

/* Point and unit normal through matrix m: the loader's formulas (the
 * cofactor matrix for normals, negated when m mirrors). */
static void pf__anim_transform(const pf_mat4 *m, pf_vec3 p, const pf_vec3 *n, pf_vec3 *wp, pf_vec3 *wn)
{
    *wp = pf_mat4_point(m, p);
    if (!n) return;
    pf_vec3 r = pf_anim_unit(pf_mat4_normal(m, *n));
    if (pf_mat4_det3(m) < 0.0) r = pf_v3_scale(r, -1.0f); /* cofactor = det * M^-T */
    *wn = r;
}

/* A coordinate the renderer accepts (in double: no overflow to convert). */
static int pf__anim_ok(pf_vec3 p) { return pf_scene_coord_ok(p); }

uint32_t pf_anim_prim_deform(const pf_anim *a, const pf_anim_prim *p, pf_vec3 *pos, pf_vec3 *nrm)
{
    const float *w = p->target_count ? a->nodes[p->node].weights : NULL;
    const pf_vec3 *want_n = p->flat ? NULL : nrm;
    uint32_t bad = UINT32_MAX;
    for (uint32_t v = 0; v < p->local_count; v++) {
        pf_vec3 lp, ln;
        pf__anim_morph(p, w, v, &lp, want_n ? &ln : NULL);
        if (p->skin < 0) {
            pf__anim_transform(&a->world[p->node], lp, want_n ? &ln : NULL, &pos[v], want_n ? &nrm[v] : NULL);
        } else {
            /* sum_k w_k J_k over every influence (glTF 2.0 Sec. 3.7.3.3),
             * influences of weight 0 skipped */
            const pf_anim_skin *sk = &a->skins[p->skin];
            pf_mat4 S;
            memset(&S, 0, sizeof S);
            const size_t base = (size_t)v * 4u * p->joint_sets;
            for (uint32_t k = 0; k < 4u * p->joint_sets; k++) {
                const double wk = p->weight[base + k];
                if (wk == 0.0) continue;
                const pf_mat4 *J = &sk->joint_mats[p->joint[base + k]];
                for (int e = 0; e < 16; e++) S.m[e] += wk * J->m[e];
            }
            pf__anim_transform(&S, lp, want_n ? &ln : NULL, &pos[v], want_n ? &nrm[v] : NULL);
        }
        if (bad == UINT32_MAX && !pf__anim_ok(pos[v])) bad = v;
    }
    return bad;
}

/* ---------------------------------------------------------------- posing */

static int pf__v3_same(pf_vec3 a, pf_vec3 b) { return !memcmp(&a, &b, sizeof a); }

static void pf__anim_bounds(const pf_vec3 *p, uint32_t n, pf_vec3 *lo, pf_vec3 *hi)
{
    *lo = pf_v3(INFINITY, INFINITY, INFINITY);
    *hi = pf_v3(-INFINITY, -INFINITY, -INFINITY);
    for (uint32_t v = 0; v < n; v++) {
        *lo = pf_v3(fminf(lo->x, p[v].x), fminf(lo->y, p[v].y), fminf(lo->z, p[v].z));
        *hi = pf_v3(fmaxf(hi->x, p[v].x), fmaxf(hi->y, p[v].y), fmaxf(hi->z, p[v].z));
    }
}

/* Writes primitive p's posed vertices (a->scratch_*) into the scene;
 * returns whether a position or normal changed. Flat primitives: each
 * triangle's face normal from its posed corners, as the loader makes it;
 * welded ones: a zero normal takes the face normal of the first triangle
 * using it, else (0, 1, 0), as the loader does. */
static int pf__anim_write(pf_scene *s, const pf_anim *a, const pf_anim_prim *p)
{
    int changed = 0;
    for (uint32_t i = 0; i < p->vertex_count; i++) {
        const uint32_t v = p->vertex_first + i, src = p->src ? p->src[i] : i;
        changed |= !pf__v3_same(s->positions[v], a->scratch_pos[src]);
        s->positions[v] = a->scratch_pos[src];
    }
    if (p->flat) {
        for (uint32_t t = p->tri_first; t < p->tri_first + p->tri_count; t++) {
            const uint32_t *ix = &s->indices[3 * t];
            const pf_vec3 p0 = s->positions[ix[0]], p1 = s->positions[ix[1]], p2 = s->positions[ix[2]];
            pf_vec3 fn = pf_anim_unit(pf_v3_cross(pf_v3_sub(p1, p0), pf_v3_sub(p2, p0)));
            if (fn.x == 0.0f && fn.y == 0.0f && fn.z == 0.0f) fn = pf_v3(0.0f, 1.0f, 0.0f); /* degenerate now */
            for (int k = 0; k < 3; k++) {
                changed |= !pf__v3_same(s->normals[ix[k]], fn);
                s->normals[ix[k]] = fn;
            }
        }
        return changed;
    }
    int zero = 0;
    for (uint32_t i = 0; i < p->vertex_count; i++) {
        const pf_vec3 n = a->scratch_nrm[i];
        zero |= n.x == 0.0f && n.y == 0.0f && n.z == 0.0f;
    }
    pf_vec3 *nrm = a->scratch_nrm; /* fixed up in place, then written */
    if (zero) {
        for (uint32_t t = p->tri_first; t < p->tri_first + p->tri_count; t++) {
            const uint32_t *ix = &s->indices[3 * t];
            const pf_vec3 p0 = s->positions[ix[0]], p1 = s->positions[ix[1]], p2 = s->positions[ix[2]];
            const pf_vec3 fn = pf_anim_unit(pf_v3_cross(pf_v3_sub(p1, p0), pf_v3_sub(p2, p0)));
            for (int k = 0; k < 3; k++) {
                pf_vec3 *n = &nrm[ix[k] - p->vertex_first];
                if (n->x == 0.0f && n->y == 0.0f && n->z == 0.0f) *n = fn;
            }
        }
        for (uint32_t i = 0; i < p->vertex_count; i++)
            if (nrm[i].x == 0.0f && nrm[i].y == 0.0f && nrm[i].z == 0.0f) nrm[i] = pf_v3(0.0f, 1.0f, 0.0f);
    }
    for (uint32_t i = 0; i < p->vertex_count; i++) {
        const uint32_t v = p->vertex_first + i;
        changed |= !pf__v3_same(s->normals[v], nrm[i]);
        s->normals[v] = nrm[i];
    }
    return changed;
}

static const char *pf__anim_clip_name(const pf_anim *a, int32_t clip, char *buf, size_t size)
{
    if (clip == PF_ANIM_ALL) snprintf(buf, size, "every animation");
    else if (clip == PF_ANIM_STATIC) snprintf(buf, size, "the static pose");
    else snprintf(buf, size, "animation %d '%.40s'", clip, a->clips[clip].name);
    return buf;
}

pf_result pf_anim_pose(pf_scene *s, pf_anim_moved *moved, uint32_t *moved_count, pf_anim *a, int32_t clip, double t,
                       pf_error *err)
{
    if (moved_count) *moved_count = 0;
    if (!(t >= 0.0 && t <= PF_ANIM_MAX_TIME))
        return pf_error_set(err, PF_ERR_ARGUMENT, "time %g s: must be finite and in 0..%g seconds", t,
                            PF_ANIM_MAX_TIME);
    if (clip != PF_ANIM_ALL && clip != PF_ANIM_STATIC && (clip < 0 || (uint32_t)clip >= a->clip_count))
        return pf_error_set(err, PF_ERR_ARGUMENT, "animation %d: the scene has %u", clip, a->clip_count);
    pf_anim_evaluate(a, clip, t);
    uint32_t count = 0;
    for (uint32_t i = 0; i < a->prim_count; i++) {
        const pf_anim_prim *p = &a->prims[i];
        pf_anim_moved m = {p->vertex_first, p->vertex_count, p->tri_first, p->tri_count, 0,
                           {0, 0, 0}, {0, 0, 0}, {0, 0, 0}, {0, 0, 0}};
        if (moved) pf__anim_bounds(s->positions + p->vertex_first, p->vertex_count, &m.before_min, &m.before_max);
        if (p->dynamic) {
            uint32_t bad = pf_anim_prim_deform(a, p, a->scratch_pos, a->scratch_nrm);
            if (bad != UINT32_MAX) {
                char what[96];
                const pf_vec3 q = a->scratch_pos[bad];
                pf_error_set(err, PF_ERR_NONFINITE,
                             "%s at %g s puts mesh %u primitive %u (node %u) vertex %u at (%g, %g, %g), beyond the "
                             "supported range |x| <= %g",
                             pf__anim_clip_name(a, clip, what, sizeof what), t, p->mesh, p->prim, p->node, bad,
                             (double)q.x, (double)q.y, (double)q.z, (double)PF_SCENE_MAX_COORD);
                /* back to the previous pose, which posed without failing
                 * and gives the same bits again (pf_anim.h) */
                if (a->pose_clip != clip || a->pose_time != t) {
                    pf_error keep = *err;
                    pf_anim_pose(s, NULL, NULL, a, a->pose_clip, a->pose_time, NULL);
                    *err = keep;
                }
                return PF_ERR_NONFINITE;
            }
            m.moved = pf__anim_write(s, a, p);
        }
        if (moved) {
            pf__anim_bounds(s->positions + p->vertex_first, p->vertex_count, &m.after_min, &m.after_max);
            moved[i] = m;
        }
        count += m.moved != 0;
    }
    /* the scene's bounds, as pf_scene_validate computes them (every vertex,
     * emitters appended after loading included) */
    pf__anim_bounds(s->positions, s->vertex_count, &s->bounds_min, &s->bounds_max);
    a->pose_clip = clip;
    a->pose_time = t;
    if (moved_count) *moved_count = count;
    return PF_OK;
}
