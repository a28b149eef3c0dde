/* pf_sequence: sequence files (format and rules in pf_sequence.h).
 *
 * The parser walks the cJSON tree with a small context holding the file
 * name and the JSON path of the value being read ("lights[1].keys[0]"), so
 * every message says where the problem is. cJSON bounds nesting (1000) and
 * never reads past the buffer; everything it hands us is checked for type,
 * finiteness and range before use. */
#include "pf_sequence.h"

#include <cjson/cJSON.h>
#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "pf_imageio.h"

typedef struct pf__sq {
    const char *file;
    pf_error *err;
} pf__sq;

static pf_result pf__sq_fail(const pf__sq *c, pf_result code, const char *where, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 4, 5)))
#endif
    ;

static pf_result pf__sq_fail(const pf__sq *c, pf_result code, const char *where, const char *fmt, ...)
{
    char msg[384];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    if (where && where[0]) pf_error_set(c->err, code, "%s: %s: %s", c->file, where, msg);
    else pf_error_set(c->err, code, "%s: %s", c->file, msg);
    /* one line: strings echoed from the file (a key, a scene name) may hold
     * control characters (found by fuzz_sequence: a newline in "scene") */
    if (c->err)
        for (char *p = c->err->message; *p; p++)
            if ((unsigned char)*p < 0x20 || *p == 0x7f) *p = '?';
    return code;
}

static const char *pf__type_name(const cJSON *v)
{
    if (cJSON_IsNumber(v)) return "a number";
    if (cJSON_IsString(v)) return "a string";
    if (cJSON_IsBool(v)) return "a boolean";
    if (cJSON_IsNull(v)) return "null";
    if (cJSON_IsArray(v)) return "an array";
    if (cJSON_IsObject(v)) return "an object";
    return "an unknown value";
}

/* "where.key" or "key" */
static void pf__join(char *dst, size_t size, const char *where, const char *key)
{
    if (where && where[0]) snprintf(dst, size, "%s.%s", where, key);
    else snprintf(dst, size, "%s", key);
}

/* Every member of obj must be in `allowed` (or be "comment"), once. */
static pf_result pf__check_keys(const pf__sq *c, const cJSON *obj, const char *where, const char *const *allowed,
                                size_t n)
{
    for (const cJSON *m = obj->child; m; m = m->next) {
        const char *k = m->string ? m->string : "";
        int ok = !strcmp(k, "comment");
        for (size_t i = 0; i < n && !ok; i++) ok = !strcmp(k, allowed[i]);
        if (!ok) {
            char list[256] = "";
            for (size_t i = 0; i < n; i++) {
                strncat(list, allowed[i], sizeof list - strlen(list) - 1);
                if (i + 1 < n) strncat(list, ", ", sizeof list - strlen(list) - 1);
            }
            return pf__sq_fail(c, PF_ERR_PARSE, where, "unknown key '%.64s' (expected: %s)", k, list);
        }
        for (const cJSON *p = obj->child; p != m; p = p->next)
            if (p->string && !strcmp(p->string, k))
                return pf__sq_fail(c, PF_ERR_PARSE, where, "key '%.64s' given twice", k);
    }
    return PF_OK;
}

/* A finite number within [-limit, limit] (float range). */
static pf_result pf__number(const pf__sq *c, const cJSON *v, const char *where, double limit, double *out)
{
    if (!cJSON_IsNumber(v)) return pf__sq_fail(c, PF_ERR_PARSE, where, "expected a number, got %s", pf__type_name(v));
    double d = v->valuedouble;
    if (!isfinite(d) || !isfinite((float)d))
        return pf__sq_fail(c, PF_ERR_NONFINITE, where, "number is not finite in single precision");
    if (fabs(d) > limit) return pf__sq_fail(c, PF_ERR_NONFINITE, where, "|%g| exceeds %g", d, limit);
    *out = d;
    return PF_OK;
}

/* An integer in [lo, hi]. */
static pf_result pf__uint(const pf__sq *c, const cJSON *v, const char *where, uint32_t lo, uint32_t hi, uint32_t *out)
{
    if (!cJSON_IsNumber(v)) return pf__sq_fail(c, PF_ERR_PARSE, where, "expected an integer, got %s", pf__type_name(v));
    double d = v->valuedouble;
    if (!isfinite(d) || d != floor(d)) return pf__sq_fail(c, PF_ERR_PARSE, where, "expected an integer, got %g", d);
    if (d < (double)lo || d > (double)hi)
        return pf__sq_fail(c, PF_ERR_PARSE, where, "%.0f is out of range %u..%u", d, lo, hi);
    *out = (uint32_t)d;
    return PF_OK;
}

/* An array of exactly n numbers within +-limit. */
static pf_result pf__floats(const pf__sq *c, const cJSON *v, const char *where, int n, double limit, float *out)
{
    if (!cJSON_IsArray(v))
        return pf__sq_fail(c, PF_ERR_PARSE, where, "expected an array of %d numbers, got %s", n, pf__type_name(v));
    if (cJSON_GetArraySize(v) != n)
        return pf__sq_fail(c, PF_ERR_PARSE, where, "expected an array of %d numbers, got %d elements", n,
                           cJSON_GetArraySize(v));
    int i = 0;
    for (const cJSON *e = v->child; e; e = e->next, i++) {
        char w[320];
        snprintf(w, sizeof w, "%s[%d]", where, i);
        double d = 0.0;
        pf_result r = pf__number(c, e, w, limit, &d);
        if (r != PF_OK) return r;
        out[i] = (float)d;
    }
    return PF_OK;
}

static const cJSON *pf__get(const cJSON *obj, const char *key) { return cJSON_GetObjectItemCaseSensitive(obj, key); }

static pf_result pf__missing(const pf__sq *c, const char *where, const char *key)
{
    return pf__sq_fail(c, PF_ERR_PARSE, where, "missing key '%s'", key);
}

/* ---------------------------------------------------------------- tracks */

static pf_result pf__track_alloc(const pf__sq *c, pf_sequence_track *t, uint32_t cap, uint32_t dim)
{
    t->count = 0;
    t->dim = dim;
    t->frame = malloc(sizeof(uint32_t) * (cap ? cap : 1));
    t->value = malloc(sizeof(float) * dim * (cap ? cap : 1));
    if (!t->frame || !t->value) return pf__sq_fail(c, PF_ERR_OUT_OF_MEMORY, NULL, "out of memory");
    return PF_OK;
}

static void pf__track_free(pf_sequence_track *t)
{
    free(t->frame);
    free(t->value);
    memset(t, 0, sizeof *t);
}

void pf_sequence_track_eval(const pf_sequence_track *t, uint32_t frame, float *out)
{
    if (t->count == 0) return;
    const uint32_t d = t->dim;
    if (frame <= t->frame[0]) {
        memcpy(out, t->value, sizeof(float) * d);
        return;
    }
    if (frame >= t->frame[t->count - 1]) {
        memcpy(out, t->value + (size_t)(t->count - 1) * d, sizeof(float) * d);
        return;
    }
    /* binary search for frame[k] <= frame < frame[k+1] (a linear walk made
     * checking every frame of a file with 10000 keys quadratic) */
    uint32_t k = 0, hi = t->count - 1;
    while (hi - k > 1) {
        uint32_t mid = k + (hi - k) / 2;
        if (t->frame[mid] <= frame) k = mid;
        else hi = mid;
    }
    const float *a = t->value + (size_t)k * d, *b = a + d;
    /* (1 - t) a + t b: exactly a at t = 0 and exactly b at t = 1 */
    double s = (double)(frame - t->frame[k]) / (double)(t->frame[k + 1] - t->frame[k]);
    for (uint32_t i = 0; i < d; i++) out[i] = (float)((1.0 - s) * (double)a[i] + s * (double)b[i]);
}

/* The "frame" of key `key` at `where`, strictly after the previous key. */
static pf_result pf__key_frame(const pf__sq *c, const cJSON *key, const char *where, uint32_t frames, int have_prev,
                               uint32_t prev, uint32_t *out)
{
    char w[320];
    pf__join(w, sizeof w, where, "frame");
    const cJSON *v = pf__get(key, "frame");
    if (!v) return pf__missing(c, where, "frame");
    pf_result r = pf__uint(c, v, w, 0, frames - 1, out);
    if (r != PF_OK) return r;
    if (have_prev && *out <= prev)
        return pf__sq_fail(c, PF_ERR_PARSE, w, "frames must increase (%u after %u)", *out, prev);
    return PF_OK;
}

/* ---------------------------------------------------------------- camera */

static pf_result pf__camera(const pf__sq *c, pf_sequence *s, const cJSON *arr)
{
    if (!cJSON_IsArray(arr))
        return pf__sq_fail(c, PF_ERR_PARSE, "camera", "expected an array of keys, got %s", pf__type_name(arr));
    int n = cJSON_GetArraySize(arr);
    if (n == 0) return pf__sq_fail(c, PF_ERR_PARSE, "camera", "needs at least one key");
    if ((uint32_t)n > s->frames)
        return pf__sq_fail(c, PF_ERR_PARSE, "camera", "%d keys for %u frames", n, s->frames);
    pf_result r = pf__track_alloc(c, &s->camera, (uint32_t)n, 7);
    if (r != PF_OK) return r;
    static const char *const keys[] = {"frame", "eye", "target", "fovy_deg"};
    int i = 0;
    for (const cJSON *k = arr->child; k; k = k->next, i++) {
        char w[64], f[320];
        snprintf(w, sizeof w, "camera[%d]", i);
        if (!cJSON_IsObject(k)) return pf__sq_fail(c, PF_ERR_PARSE, w, "expected an object, got %s", pf__type_name(k));
        if ((r = pf__check_keys(c, k, w, keys, 4)) != PF_OK) return r;
        uint32_t frame;
        r = pf__key_frame(c, k, w, s->frames, i > 0, i > 0 ? s->camera.frame[i - 1] : 0, &frame);
        if (r != PF_OK) return r;
        float *v = s->camera.value + (size_t)i * 7;
        for (int q = 1; q < 4; q++)
            if (!pf__get(k, keys[q])) return pf__missing(c, w, keys[q]);
        pf__join(f, sizeof f, w, "eye");
        if ((r = pf__floats(c, pf__get(k, "eye"), f, 3, PF_SCENE_MAX_COORD, v)) != PF_OK) return r;
        pf__join(f, sizeof f, w, "target");
        if ((r = pf__floats(c, pf__get(k, "target"), f, 3, PF_SCENE_MAX_COORD, v + 3)) != PF_OK) return r;
        pf__join(f, sizeof f, w, "fovy_deg");
        double fov;
        if ((r = pf__number(c, pf__get(k, "fovy_deg"), f, 1e30, &fov)) != PF_OK) return r;
        if (!(fov > 0.0 && fov < 180.0))
            return pf__sq_fail(c, PF_ERR_PARSE, f, "field of view %g is not in (0, 180) degrees", fov);
        v[6] = (float)fov;
        if (v[0] == v[3] && v[1] == v[4] && v[2] == v[5])
            return pf__sq_fail(c, PF_ERR_PARSE, w, "eye and target must differ");
        s->camera.frame[i] = frame;
        s->camera.count++;
    }
    /* Between keys the eye may still sweep through the target: check every
     * frame, and with the renderer's own test (pf_camera_look_at), so a
     * camera the file accepts is one softgi can render (found by
     * fuzz_sequence: "fovy_deg": 1e-45 is > 0 but 0 in radians). */
    for (uint32_t f = 0; f < s->frames; f++) {
        float v[7];
        pf_sequence_track_eval(&s->camera, f, v);
        if (v[0] == v[3] && v[1] == v[4] && v[2] == v[5])
            return pf__sq_fail(c, PF_ERR_PARSE, "camera", "eye and target coincide at frame %u", f);
        pf_camera cam;
        pf_error e2;
        if (pf_camera_look_at(&cam, pf_v3(v[0], v[1], v[2]), pf_v3(v[3], v[4], v[5]), pf_radians(v[6]), &e2) != PF_OK)
            return pf__sq_fail(c, PF_ERR_PARSE, "camera", "frame %u: %s", f, e2.message);
    }
    return PF_OK;
}

/* ---------------------------------------------------------------- lights */

static const char *const pf__field_key[PF_SEQUENCE_FIELD_COUNT] = {
    "position", "direction", "color", "intensity", "inner_cone_deg", "outer_cone_deg"};
static const uint32_t pf__field_dim[PF_SEQUENCE_FIELD_COUNT] = {3, 3, 3, 1, 1, 1};

/* One field value at `where` into v (dim floats), checked. */
static pf_result pf__field_value(const pf__sq *c, pf_sequence_field fld, const cJSON *j, const char *where, float *v)
{
    pf_result r;
    double d = 0.0;
    switch (fld) {
    case PF_SEQUENCE_POSITION: return pf__floats(c, j, where, 3, PF_SCENE_MAX_COORD, v);
    case PF_SEQUENCE_DIRECTION: {
        if ((r = pf__floats(c, j, where, 3, 1e30, v)) != PF_OK) return r;
        /* normalised in double: the squares of float components near 1e30
         * would overflow float and turn the vector into zero */
        double len = sqrt((double)v[0] * v[0] + (double)v[1] * v[1] + (double)v[2] * v[2]);
        if (!(len > 1e-30)) return pf__sq_fail(c, PF_ERR_PARSE, where, "direction must not be zero");
        for (int k = 0; k < 3; k++) v[k] = (float)(v[k] / len);
        return PF_OK;
    }
    case PF_SEQUENCE_COLOR:
        if ((r = pf__floats(c, j, where, 3, PF_SEQUENCE_MAX_EMISSION, v)) != PF_OK) return r;
        if (v[0] < 0.0f || v[1] < 0.0f || v[2] < 0.0f)
            return pf__sq_fail(c, PF_ERR_PARSE, where, "colour must be >= 0");
        return PF_OK;
    case PF_SEQUENCE_INTENSITY:
        if ((r = pf__number(c, j, where, PF_SEQUENCE_MAX_EMISSION, &d)) != PF_OK) return r;
        if (d < 0.0) return pf__sq_fail(c, PF_ERR_PARSE, where, "intensity must be >= 0");
        v[0] = (float)d;
        return PF_OK;
    default: /* cones */
        if ((r = pf__number(c, j, where, 1e30, &d)) != PF_OK) return r;
        if (!(d >= 0.0 && d <= 90.0)) return pf__sq_fail(c, PF_ERR_PARSE, where, "cone angle %g is not in [0, 90] degrees", d);
        v[0] = (float)d;
        return PF_OK;
    }
}

static int pf__type_allows(pf_light_type type, pf_sequence_field f)
{
    switch (f) {
    case PF_SEQUENCE_POSITION: return type != PF_LIGHT_DIRECTIONAL;
    case PF_SEQUENCE_DIRECTION: return type != PF_LIGHT_POINT;
    case PF_SEQUENCE_INNER_CONE:
    case PF_SEQUENCE_OUTER_CONE: return type == PF_LIGHT_SPOT;
    default: return 1;
    }
}

static const char *pf__type_str(pf_light_type t)
{
    return t == PF_LIGHT_POINT ? "point" : t == PF_LIGHT_SPOT ? "spot" : "directional";
}

/* The full light of an entry with "type". */
static pf_result pf__light_spec(const pf__sq *c, const cJSON *e, const char *w, pf_light *L)
{
    char f[320];
    pf_result r;
    memset(L, 0, sizeof *L);
    const cJSON *t = pf__get(e, "type");
    pf__join(f, sizeof f, w, "type");
    if (!cJSON_IsString(t)) return pf__sq_fail(c, PF_ERR_PARSE, f, "expected a string, got %s", pf__type_name(t));
    if (!strcmp(t->valuestring, "point")) L->type = PF_LIGHT_POINT;
    else if (!strcmp(t->valuestring, "spot")) L->type = PF_LIGHT_SPOT;
    else if (!strcmp(t->valuestring, "directional") || !strcmp(t->valuestring, "dir")) L->type = PF_LIGHT_DIRECTIONAL;
    else return pf__sq_fail(c, PF_ERR_PARSE, f, "'%.64s': expected point, spot or directional", t->valuestring);
    snprintf(L->name, sizeof L->name, "sequence-%s", pf__type_str(L->type));
    L->color = pf_v3(1.0f, 1.0f, 1.0f);
    float v[3];
    for (int k = 0; k < PF_SEQUENCE_FIELD_COUNT; k++) {
        pf_sequence_field fld = (pf_sequence_field)k;
        const cJSON *j = pf__get(e, pf__field_key[k]);
        int need = (fld == PF_SEQUENCE_POSITION && L->type != PF_LIGHT_DIRECTIONAL) ||
                   (fld == PF_SEQUENCE_DIRECTION && L->type != PF_LIGHT_POINT) || fld == PF_SEQUENCE_INTENSITY ||
                   ((fld == PF_SEQUENCE_INNER_CONE || fld == PF_SEQUENCE_OUTER_CONE) && L->type == PF_LIGHT_SPOT);
        if (!j) {
            if (need) return pf__sq_fail(c, PF_ERR_PARSE, w, "missing key '%s' (a %s light needs it)", pf__field_key[k], pf__type_str(L->type));
            continue;
        }
        pf__join(f, sizeof f, w, pf__field_key[k]);
        if (!pf__type_allows(L->type, fld))
            return pf__sq_fail(c, PF_ERR_PARSE, f, "a %s light has no %s", pf__type_str(L->type), pf__field_key[k]);
        if ((r = pf__field_value(c, fld, j, f, v)) != PF_OK) return r;
        switch (fld) {
        case PF_SEQUENCE_POSITION: L->position = pf_v3(v[0], v[1], v[2]); break;
        case PF_SEQUENCE_DIRECTION: L->direction = pf_v3(v[0], v[1], v[2]); break;
        case PF_SEQUENCE_COLOR: L->color = pf_v3(v[0], v[1], v[2]); break;
        case PF_SEQUENCE_INTENSITY: L->intensity = v[0]; break;
        case PF_SEQUENCE_INNER_CONE: L->inner_cone = pf_radians(v[0]); break;
        default: L->outer_cone = pf_radians(v[0]); break;
        }
    }
    if (L->type == PF_LIGHT_SPOT && !(L->inner_cone < L->outer_cone))
        return pf__sq_fail(c, PF_ERR_PARSE, w, "inner_cone_deg must be below outer_cone_deg");
    return PF_OK;
}

static pf_result pf__light_keys(const pf__sq *c, pf_sequence *s, pf_sequence_light *sl, const cJSON *arr,
                                const char *w)
{
    char kw[320], f[400];
    pf__join(kw, sizeof kw, w, "keys");
    if (!cJSON_IsArray(arr))
        return pf__sq_fail(c, PF_ERR_PARSE, kw, "expected an array of keys, got %s", pf__type_name(arr));
    int n = cJSON_GetArraySize(arr);
    if ((uint32_t)n > s->frames) return pf__sq_fail(c, PF_ERR_PARSE, kw, "%d keys for %u frames", n, s->frames);
    pf_result r;
    for (int k = 0; k < PF_SEQUENCE_FIELD_COUNT; k++)
        if ((r = pf__track_alloc(c, &sl->field[k], (uint32_t)n, pf__field_dim[k])) != PF_OK) return r;
    static const char *const keys[] = {"frame",     "position",       "direction",     "color",
                                       "intensity", "inner_cone_deg", "outer_cone_deg"};
    uint32_t prev = 0;
    int i = 0;
    for (const cJSON *key = arr->child; key; key = key->next, i++) {
        char w2[360];
        snprintf(w2, sizeof w2, "%s[%d]", kw, i);
        if (!cJSON_IsObject(key))
            return pf__sq_fail(c, PF_ERR_PARSE, w2, "expected an object, got %s", pf__type_name(key));
        if ((r = pf__check_keys(c, key, w2, keys, 7)) != PF_OK) return r;
        uint32_t frame;
        if ((r = pf__key_frame(c, key, w2, s->frames, i > 0, prev, &frame)) != PF_OK) return r;
        prev = frame;
        int any = 0;
        for (int k = 0; k < PF_SEQUENCE_FIELD_COUNT; k++) {
            const cJSON *j = pf__get(key, pf__field_key[k]);
            if (!j) continue;
            any = 1;
            pf__join(f, sizeof f, w2, pf__field_key[k]);
            if (sl->scene_light < 0 && !pf__type_allows(sl->spec.type, (pf_sequence_field)k))
                return pf__sq_fail(c, PF_ERR_PARSE, f, "a %s light has no %s", pf__type_str(sl->spec.type),
                                   pf__field_key[k]);
            pf_sequence_track *t = &sl->field[k];
            float *v = t->value + (size_t)t->count * t->dim;
            if ((r = pf__field_value(c, (pf_sequence_field)k, j, f, v)) != PF_OK) return r;
            if (k == PF_SEQUENCE_DIRECTION && t->count > 0) {
                const float *p = v - 3;
                if (p[0] * v[0] + p[1] * v[1] + p[2] * v[2] < -0.999f)
                    return pf__sq_fail(c, PF_ERR_PARSE, f,
                                       "opposite to the previous direction key (no unique path between them)");
            }
            t->frame[t->count++] = frame;
        }
        if (!any)
            return pf__sq_fail(c, PF_ERR_PARSE, w2,
                               "a key needs at least one of position, direction, color, intensity, "
                               "inner_cone_deg, outer_cone_deg");
    }
    return PF_OK;
}

static pf_result pf__lights(const pf__sq *c, pf_sequence *s, const cJSON *arr)
{
    if (!cJSON_IsArray(arr))
        return pf__sq_fail(c, PF_ERR_PARSE, "lights", "expected an array, got %s", pf__type_name(arr));
    int n = cJSON_GetArraySize(arr);
    if (n == 0) { /* no punctual light: the file's emitters light the scene (checked in pf__top) */
        s->lights_replace = 1;
        return PF_OK;
    }
    if ((uint32_t)n > PF_SEQUENCE_MAX_LIGHTS)
        return pf__sq_fail(c, PF_ERR_PARSE, "lights", "%d lights (at most %u)", n, PF_SEQUENCE_MAX_LIGHTS);
    s->lights = calloc((size_t)n, sizeof *s->lights);
    if (!s->lights) return pf__sq_fail(c, PF_ERR_OUT_OF_MEMORY, NULL, "out of memory");
    s->light_count = (uint32_t)n;
    static const char *const ref_keys[] = {"light", "keys"};
    static const char *const spec_keys[] = {"type",      "position",       "direction",      "color",
                                            "intensity", "inner_cone_deg", "outer_cone_deg", "keys"};
    pf_result r;
    int i = 0;
    for (const cJSON *e = arr->child; e; e = e->next, i++) {
        char w[64], f[320];
        snprintf(w, sizeof w, "lights[%d]", i);
        pf_sequence_light *sl = &s->lights[i];
        if (!cJSON_IsObject(e)) return pf__sq_fail(c, PF_ERR_PARSE, w, "expected an object, got %s", pf__type_name(e));
        const cJSON *ref = pf__get(e, "light"), *type = pf__get(e, "type");
        if (ref && type) return pf__sq_fail(c, PF_ERR_PARSE, w, "give either 'light' (a scene light) or 'type' (a full light), not both");
        if (!ref && !type)
            return pf__sq_fail(c, PF_ERR_PARSE, w, "missing key 'light' (index of a scene light) or 'type' (a full light)");
        int replace = type != NULL;
        if (i == 0) s->lights_replace = replace;
        else if (replace != s->lights_replace)
            return pf__sq_fail(c, PF_ERR_PARSE, w,
                               "entries must all name scene lights ('light') or all be full lights ('type'), not a mix");
        if (ref) {
            if ((r = pf__check_keys(c, e, w, ref_keys, 2)) != PF_OK) return r;
            uint32_t idx;
            pf__join(f, sizeof f, w, "light");
            if ((r = pf__uint(c, ref, f, 0, PF_SEQUENCE_MAX_LIGHTS - 1, &idx)) != PF_OK) return r;
            for (int p = 0; p < i; p++)
                if (s->lights[p].scene_light == (int32_t)idx)
                    return pf__sq_fail(c, PF_ERR_PARSE, f, "scene light %u is animated twice (lights[%d])", idx, p);
            sl->scene_light = (int32_t)idx;
            const cJSON *keys = pf__get(e, "keys");
            if (!keys) return pf__missing(c, w, "keys");
            if (cJSON_IsArray(keys) && cJSON_GetArraySize(keys) == 0)
                return pf__sq_fail(c, PF_ERR_PARSE, f, "needs at least one key");
            if ((r = pf__light_keys(c, s, sl, keys, w)) != PF_OK) return r;
        } else {
            if ((r = pf__check_keys(c, e, w, spec_keys, 8)) != PF_OK) return r;
            sl->scene_light = -1;
            if ((r = pf__light_spec(c, e, w, &sl->spec)) != PF_OK) return r;
            const cJSON *keys = pf__get(e, "keys");
            if (keys && (r = pf__light_keys(c, s, sl, keys, w)) != PF_OK) return r;
            /* A full light is completely known: check every frame now. */
            for (uint32_t fr = 0; fr < s->frames; fr++) {
                pf_light L;
                pf_error e2;
                if (pf_sequence_light_at(s, (uint32_t)i, fr, NULL, &L, &e2) != PF_OK)
                    return pf__sq_fail(c, PF_ERR_PARSE, NULL, "%s", e2.message); /* "lights[i]: ... at frame f" */
            }
        }
    }
    return PF_OK;
}

pf_result pf_sequence_light_at(const pf_sequence *seq, uint32_t i, uint32_t frame, const pf_light *scene_light,
                               pf_light *out, pf_error *err)
{
    const pf_sequence_light *sl = &seq->lights[i];
    if (sl->scene_light >= 0 && !scene_light)
        return pf_error_set(err, PF_ERR_ARGUMENT, "lights[%u]: no scene light %d to animate", i, sl->scene_light);
    *out = sl->scene_light >= 0 ? *scene_light : sl->spec;
    float v[3];
    for (int k = 0; k < PF_SEQUENCE_FIELD_COUNT; k++) {
        const pf_sequence_track *t = &sl->field[k];
        if (t->count == 0) continue;
        if (!pf__type_allows(out->type, (pf_sequence_field)k))
            return pf_error_set(err, PF_ERR_PARSE, "lights[%u]: scene light %d is a %s light, it has no %s", i,
                                sl->scene_light, pf__type_str(out->type), pf__field_key[k]);
        pf_sequence_track_eval(t, frame, v);
        switch ((pf_sequence_field)k) {
        case PF_SEQUENCE_POSITION: out->position = pf_v3(v[0], v[1], v[2]); break;
        case PF_SEQUENCE_DIRECTION:
            out->direction = pf_v3_normalize_safe(pf_v3(v[0], v[1], v[2]));
            if (out->direction.x == 0.0f && out->direction.y == 0.0f && out->direction.z == 0.0f)
                return pf_error_set(err, PF_ERR_PARSE, "lights[%u]: direction is zero at frame %u", i, frame);
            break;
        case PF_SEQUENCE_COLOR: out->color = pf_v3(v[0], v[1], v[2]); break;
        case PF_SEQUENCE_INTENSITY: out->intensity = v[0]; break;
        case PF_SEQUENCE_INNER_CONE: out->inner_cone = pf_radians(v[0]); break;
        default: out->outer_cone = pf_radians(v[0]); break;
        }
    }
    if (out->type == PF_LIGHT_SPOT && !(out->inner_cone >= 0.0f && out->inner_cone < out->outer_cone &&
                                        out->outer_cone <= pf_radians(90.0f)))
        return pf_error_set(err, PF_ERR_PARSE, "lights[%u]: need 0 <= inner < outer <= 90 degrees at frame %u", i,
                            frame);
    /* What the renderer multiplies: each channel of intensity x colour must
     * be finite, >= 0 and at most PF_SEQUENCE_MAX_EMISSION (each factor alone
     * may be in range while the product overflows, e.g. 1e30 x 1e30; and a
     * scene light's colour meets the file's intensity only here). */
    const float col[3] = {out->color.x, out->color.y, out->color.z};
    for (int k = 0; k < 3; k++) {
        double e = (double)out->intensity * (double)col[k];
        if (!(e >= 0.0 && e <= PF_SEQUENCE_MAX_EMISSION) || !isfinite(out->intensity) || !isfinite(col[k]))
            return pf_error_set(err, PF_ERR_NONFINITE,
                                "lights[%u]: intensity %g x colour %g is not in [0, %g] at frame %u", i,
                                (double)out->intensity, (double)col[k], PF_SEQUENCE_MAX_EMISSION, frame);
    }
    if (!pf_v3_is_finite(out->position) || !pf_v3_is_finite(out->direction))
        return pf_error_set(err, PF_ERR_NONFINITE, "lights[%u]: position or direction not finite at frame %u", i,
                            frame);
    return PF_OK;
}

int pf_sequence_camera_at(const pf_sequence *seq, uint32_t frame, pf_vec3 *eye, pf_vec3 *target, float *fovy_deg)
{
    if (seq->camera.count == 0) return 0;
    float v[7];
    pf_sequence_track_eval(&seq->camera, frame, v);
    *eye = pf_v3(v[0], v[1], v[2]);
    *target = pf_v3(v[3], v[4], v[5]);
    *fovy_deg = v[6];
    return 1;
}

/* ---------------------------------------------------------------- emitters */

/* "emitters": static emissive quads (pf_sequence.h). The quad's shape and
 * emission are checked by the scene's own rule (pf_scene_emitter_quad_check),
 * so a file the parser accepts is one pf_sequence_apply_emitters adds. */
static pf_result pf__emitters(const pf__sq *c, pf_sequence *s, const cJSON *arr)
{
    if (!cJSON_IsArray(arr))
        return pf__sq_fail(c, PF_ERR_PARSE, "emitters", "expected an array, got %s", pf__type_name(arr));
    int n = cJSON_GetArraySize(arr);
    if (n == 0) return pf__sq_fail(c, PF_ERR_PARSE, "emitters", "is empty (leave it out for no emitters)");
    if ((uint32_t)n > PF_SEQUENCE_MAX_EMITTERS)
        return pf__sq_fail(c, PF_ERR_PARSE, "emitters", "%d emitters (at most %u)", n, PF_SEQUENCE_MAX_EMITTERS);
    static const char *const keys[] = {"quad", "emission", "two_sided"};
    pf_result r;
    int i = 0;
    for (const cJSON *e = arr->child; e; e = e->next, i++) {
        char w[64], f[320];
        snprintf(w, sizeof w, "emitters[%d]", i);
        pf_sequence_emitter *em = &s->emitters[i];
        if (!cJSON_IsObject(e)) return pf__sq_fail(c, PF_ERR_PARSE, w, "expected an object, got %s", pf__type_name(e));
        if ((r = pf__check_keys(c, e, w, keys, 3)) != PF_OK) return r;
        const cJSON *q = pf__get(e, "quad");
        if (!q) return pf__missing(c, w, "quad");
        pf__join(f, sizeof f, w, "quad");
        if (!cJSON_IsArray(q) || cJSON_GetArraySize(q) != 4)
            return pf__sq_fail(c, PF_ERR_PARSE, f, "expected 4 corners [[x,y,z], ...], got %s",
                               cJSON_IsArray(q) ? "another number of elements" : pf__type_name(q));
        int k = 0;
        for (const cJSON *p = q->child; p; p = p->next, k++) {
            char f2[340];
            float v[3];
            snprintf(f2, sizeof f2, "%s[%d]", f, k);
            if ((r = pf__floats(c, p, f2, 3, PF_SCENE_MAX_COORD, v)) != PF_OK) return r;
            em->quad[k] = pf_v3(v[0], v[1], v[2]);
        }
        const cJSON *j = pf__get(e, "emission");
        if (!j) return pf__missing(c, w, "emission");
        pf__join(f, sizeof f, w, "emission");
        float v[3];
        if ((r = pf__floats(c, j, f, 3, PF_SEQUENCE_MAX_EMISSION, v)) != PF_OK) return r;
        if (v[0] < 0.0f || v[1] < 0.0f || v[2] < 0.0f)
            return pf__sq_fail(c, PF_ERR_PARSE, f, "emission must be >= 0");
        if (v[0] == 0.0f && v[1] == 0.0f && v[2] == 0.0f)
            return pf__sq_fail(c, PF_ERR_PARSE, f, "emission is zero (an emitter must emit)");
        em->emission = pf_v3(v[0], v[1], v[2]);
        if ((j = pf__get(e, "two_sided"))) {
            pf__join(f, sizeof f, w, "two_sided");
            if (!cJSON_IsBool(j))
                return pf__sq_fail(c, PF_ERR_PARSE, f, "expected true or false, got %s", pf__type_name(j));
            em->two_sided = cJSON_IsTrue(j);
        }
        pf_error e2;
        pf__join(f, sizeof f, w, "quad");
        if ((r = pf_scene_emitter_quad_check(em->quad, em->emission, NULL, &e2)) != PF_OK)
            return pf__sq_fail(c, r, f, "%s", e2.message); /* f: "emitters[i].quad" */
        s->emitter_count = (uint32_t)i + 1;
    }
    return PF_OK;
}

pf_result pf_sequence_apply_emitters(const pf_sequence *seq, pf_scene *scene, pf_error *err)
{
    /* "lights": [] replaces the scene's punctual lights with none */
    if (seq->lights_replace && seq->light_count == 0) scene->light_count = 0;
    for (uint32_t i = 0; i < seq->emitter_count; i++) {
        const pf_sequence_emitter *em = &seq->emitters[i];
        pf_result r = pf_scene_add_emitter_quad(scene, em->quad, em->emission, em->two_sided, err);
        if (r != PF_OK) {
            char m[sizeof err->message];
            snprintf(m, sizeof m, "%s", err->message);
            return pf_error_set(err, r, "%s: emitters[%u]: %s", seq->file, i, m);
        }
    }
    return PF_OK;
}

/* ---------------------------------------------------------------- animation */

double pf_sequence_time_at(const pf_sequence *seq, uint32_t frame, double start, double end)
{
    if (seq->frames <= 1) return start;
    const double s = (double)frame / (double)(seq->frames - 1);
    const double t = (1.0 - s) * start + s * end; /* exactly start and end at the ends */
    return t < start ? start : t > end ? end : t; /* never outside by a rounding */
}

static int pf__has_control(const char *p);

static pf_result pf__animation(const pf__sq *c, pf_sequence *s, const cJSON *v)
{
    if (!cJSON_IsObject(v))
        return pf__sq_fail(c, PF_ERR_PARSE, "animation", "expected an object, got %s", pf__type_name(v));
    static const char *const keys[] = {"play", "time"};
    pf_result r = pf__check_keys(c, v, "animation", keys, 2);
    if (r != PF_OK) return r;
    s->anim_set = 1;
    s->anim_index = -1;
    const cJSON *play = pf__get(v, "play");
    if (play && cJSON_IsString(play)) {
        const char *nm = play->valuestring;
        if (!nm[0] || strlen(nm) >= sizeof s->anim_name || pf__has_control(nm))
            return pf__sq_fail(c, PF_ERR_PARSE, "animation.play",
                               "expected an animation's name (1 to %zu characters, no control characters) or index",
                               sizeof s->anim_name - 1);
        snprintf(s->anim_name, sizeof s->anim_name, "%s", nm);
    } else if (play) {
        uint32_t idx;
        if (!cJSON_IsNumber(play))
            return pf__sq_fail(c, PF_ERR_PARSE, "animation.play", "expected an animation's name or index, got %s",
                               pf__type_name(play));
        if ((r = pf__uint(c, play, "animation.play", 0, 65535, &idx)) != PF_OK) return r;
        s->anim_index = (int32_t)idx;
    }
    const cJSON *time = pf__get(v, "time");
    if (time) {
        float t[2];
        if ((r = pf__floats(c, time, "animation.time", 2, PF_SEQUENCE_MAX_TIME, t)) != PF_OK) return r;
        if (!(t[0] >= 0.0f && t[0] <= t[1]))
            return pf__sq_fail(c, PF_ERR_PARSE, "animation.time",
                               "[%g, %g]: expected [start, end] seconds with 0 <= start <= end <= %g", (double)t[0],
                               (double)t[1], PF_SEQUENCE_MAX_TIME);
        s->anim_time_set = 1;
        s->anim_start = t[0];
        s->anim_end = t[1];
    }
    return PF_OK;
}

/* ---------------------------------------------------------------- top level */

/* Folder of `file` with a trailing slash ("" for a bare name). */
static void pf__dir_of(const char *file, char *dir, size_t size)
{
    const char *slash = strrchr(file, '/');
    if (!slash) dir[0] = 0;
    else snprintf(dir, size, "%.*s/", (int)(slash - file), file);
}

static pf_result pf__path(const pf__sq *c, const cJSON *v, const char *where, char *dst, size_t size)
{
    if (!cJSON_IsString(v)) return pf__sq_fail(c, PF_ERR_PARSE, where, "expected a string, got %s", pf__type_name(v));
    const char *p = v->valuestring;
    if (!p[0]) return pf__sq_fail(c, PF_ERR_PARSE, where, "must not be empty");
    char dir[4096];
    pf__dir_of(c->file, dir, sizeof dir);
    int n = p[0] == '/' ? snprintf(dst, size, "%s", p) : snprintf(dst, size, "%s%s", dir, p);
    if (n < 0 || (size_t)n >= size) return pf__sq_fail(c, PF_ERR_PARSE, where, "path too long");
    return PF_OK;
}

static int pf__has_control(const char *p)
{
    for (; *p; p++)
        if ((unsigned char)*p < 0x20 || *p == 0x7f) return 1;
    return 0;
}

/* "output": a relative folder without ".." components, placed under
 * PF_SEQUENCE_OUTPUT_BASE (a sequence file from a stranger must not choose
 * where softgi writes; -o DIR is the user's choice). Symbolic links are
 * refused when the folder is created (pf_imageio_make_dir_inside). */
static pf_result pf__output(const pf__sq *c, const cJSON *v, char *dst, size_t size)
{
    if (!cJSON_IsString(v)) return pf__sq_fail(c, PF_ERR_PARSE, "output", "expected a string, got %s", pf__type_name(v));
    const char *p = v->valuestring;
    if (!p[0]) return pf__sq_fail(c, PF_ERR_PARSE, "output", "must not be empty");
    if (p[0] == '/')
        return pf__sq_fail(c, PF_ERR_PARSE, "output",
                           "'%.200s': must be a relative folder (it is placed under %s/; give -o DIR to write elsewhere)",
                           p, PF_SEQUENCE_OUTPUT_BASE);
    for (const char *q = p; *q;) {
        size_t n = strcspn(q, "/");
        if (n == 2 && q[0] == '.' && q[1] == '.')
            return pf__sq_fail(c, PF_ERR_PARSE, "output",
                               "'%.200s': must not contain '..' (it is placed under %s/; give -o DIR to write elsewhere)",
                               p, PF_SEQUENCE_OUTPUT_BASE);
        q += n;
        while (*q == '/') q++;
    }
    if (pf__has_control(p)) return pf__sq_fail(c, PF_ERR_PARSE, "output", "must not contain control characters");
    int n = snprintf(dst, size, "%s/%s", PF_SEQUENCE_OUTPUT_BASE, p);
    if (n < 0 || (size_t)n >= size) return pf__sq_fail(c, PF_ERR_PARSE, "output", "path too long");
    return PF_OK;
}

static pf_result pf__top(const pf__sq *c, pf_sequence *s, const cJSON *root)
{
    if (!cJSON_IsObject(root)) return pf__sq_fail(c, PF_ERR_PARSE, NULL, "expected a JSON object at the top, got %s", pf__type_name(root));
    static const char *const keys[] = {"name",   "scene",  "frames",   "size",  "output",
                                       "camera", "lights", "emitters", "track", "animation"};
    pf_result r = pf__check_keys(c, root, "", keys, 10);
    if (r != PF_OK) return r;

    const cJSON *v = pf__get(root, "name");
    if (v) {
        if (!cJSON_IsString(v)) return pf__sq_fail(c, PF_ERR_PARSE, "name", "expected a string, got %s", pf__type_name(v));
        const char *nm = v->valuestring;
        if (!nm[0] || strlen(nm) >= sizeof s->name || strchr(nm, '/') || !strcmp(nm, ".") || !strcmp(nm, "..") ||
            pf__has_control(nm))
            return pf__sq_fail(c, PF_ERR_PARSE, "name",
                               "expected 1 to %zu characters without '/' or control characters, not '.' or '..' "
                               "(it names the folder out/NAME)",
                               sizeof s->name - 1);
        snprintf(s->name, sizeof s->name, "%s", v->valuestring);
    }

    if (!(v = pf__get(root, "scene"))) return pf__missing(c, "", "scene");
    if (cJSON_IsString(v) && !strncmp(v->valuestring, "embedded:", 9)) {
        if (strcmp(v->valuestring, PF_SEQUENCE_EMBEDDED_CORNELL))
            return pf__sq_fail(c, PF_ERR_PARSE, "scene", "'%.64s': the only embedded scene is %s", v->valuestring,
                               PF_SEQUENCE_EMBEDDED_CORNELL);
        s->scene_embedded = 1;
    } else if ((r = pf__path(c, v, "scene", s->scene_path, sizeof s->scene_path)) != PF_OK)
        return r;

    if (!(v = pf__get(root, "frames"))) return pf__missing(c, "", "frames");
    if (cJSON_IsNumber(v) && v->valuedouble == 0.0) return pf__sq_fail(c, PF_ERR_PARSE, "frames", "must be at least 1");
    if ((r = pf__uint(c, v, "frames", 1, PF_SEQUENCE_MAX_FRAMES, &s->frames)) != PF_OK) return r;

    if ((v = pf__get(root, "size"))) {
        if (!cJSON_IsArray(v) || cJSON_GetArraySize(v) != 2)
            return pf__sq_fail(c, PF_ERR_PARSE, "size", "expected [width, height]");
        if ((r = pf__uint(c, v->child, "size[0]", 1, PF_SEQUENCE_MAX_SIZE, &s->width)) != PF_OK) return r;
        if ((r = pf__uint(c, v->child->next, "size[1]", 1, PF_SEQUENCE_MAX_SIZE, &s->height)) != PF_OK) return r;
    }
    if ((v = pf__get(root, "output")) && (r = pf__output(c, v, s->output, sizeof s->output)) != PF_OK) return r;
    if ((v = pf__get(root, "camera")) && (r = pf__camera(c, s, v)) != PF_OK) return r;
    if ((v = pf__get(root, "lights")) && (r = pf__lights(c, s, v)) != PF_OK) return r;
    if ((v = pf__get(root, "emitters")) && (r = pf__emitters(c, s, v)) != PF_OK) return r;
    if ((v = pf__get(root, "animation")) && (r = pf__animation(c, s, v)) != PF_OK) return r;
    if (s->lights_replace && s->light_count == 0 && s->emitter_count == 0)
        return pf__sq_fail(c, PF_ERR_PARSE, "lights",
                           "is empty, which means no punctual light: give \"emitters\" to light the scene, or leave "
                           "\"lights\" out to keep the scene's lights");

    if ((v = pf__get(root, "track"))) {
        if (!cJSON_IsArray(v)) return pf__sq_fail(c, PF_ERR_PARSE, "track", "expected an array of [x, y], got %s", pf__type_name(v));
        int n = cJSON_GetArraySize(v);
        if (n == 0 || (uint32_t)n > PF_SEQUENCE_MAX_TRACK)
            return pf__sq_fail(c, PF_ERR_PARSE, "track", "expected 1 to %u pixels, got %d", PF_SEQUENCE_MAX_TRACK, n);
        int i = 0;
        for (const cJSON *p = v->child; p; p = p->next, i++) {
            char w[64];
            snprintf(w, sizeof w, "track[%d]", i);
            if (!cJSON_IsArray(p) || cJSON_GetArraySize(p) != 2)
                return pf__sq_fail(c, PF_ERR_PARSE, w, "expected [x, y]");
            char w2[80];
            snprintf(w2, sizeof w2, "%s[0]", w);
            if ((r = pf__uint(c, p->child, w2, 0, PF_SEQUENCE_MAX_SIZE - 1, &s->track[i][0])) != PF_OK) return r;
            snprintf(w2, sizeof w2, "%s[1]", w);
            if ((r = pf__uint(c, p->child->next, w2, 0, PF_SEQUENCE_MAX_SIZE - 1, &s->track[i][1])) != PF_OK)
                return r;
            if (s->width && (s->track[i][0] >= s->width || s->track[i][1] >= s->height))
                return pf__sq_fail(c, PF_ERR_PARSE, w, "pixel (%u, %u) is outside the %ux%u image", s->track[i][0],
                                   s->track[i][1], s->width, s->height);
        }
        s->track_count = (uint32_t)n;
    }
    return PF_OK;
}

/* "dir/name.seq.json" -> "name" */
static void pf__default_name(const char *file, char *name, size_t size)
{
    const char *base = strrchr(file, '/');
    base = base ? base + 1 : file;
    snprintf(name, size, "%s", base);
    size_t n = strlen(name);
    if (n > 5 && !strcmp(name + n - 5, ".json")) name[n -= 5] = 0;
    if (n > 4 && !strcmp(name + n - 4, ".seq")) name[n -= 4] = 0;
    if (!name[0] || !strcmp(name, ".") || !strcmp(name, "..")) snprintf(name, size, "sequence");
}

/* 1-based line and column of offset `at` in json. */
static void pf__line_col(const char *json, size_t at, unsigned *line, unsigned *col)
{
    *line = 1, *col = 1;
    for (size_t i = 0; i < at; i++) {
        if (json[i] == '\n') (*line)++, *col = 1;
        else (*col)++;
    }
}

/* 2 when the text ends inside a string, 1 when it ends with an object or
 * array open, else 0: cJSON reports a truncated text at the last byte (or
 * at the open string's start), where it cannot be told from a bad last
 * character. */
static int pf__unclosed(const char *json, size_t size)
{
    long depth = 0;
    int in_str = 0;
    for (size_t i = 0; i < size; i++) {
        char ch = json[i];
        if (in_str) {
            if (ch == '\\') i++;
            else if (ch == '"') in_str = 0;
        } else if (ch == '"') in_str = 1;
        else if (ch == '{' || ch == '[') depth++;
        else if (ch == '}' || ch == ']') depth--;
    }
    return in_str ? 2 : depth > 0;
}

pf_result pf_sequence_parse(pf_sequence *seq, const char *json, size_t size, const char *file, pf_error *err)
{
    memset(seq, 0, sizeof *seq);
    pf__sq c = {file ? file : "sequence", err};
    snprintf(seq->file, sizeof seq->file, "%s", c.file);
    pf__default_name(c.file, seq->name, sizeof seq->name);
    if (size == 0) return pf__sq_fail(&c, PF_ERR_PARSE, NULL, "empty file (expected a JSON object)");
    if (memchr(json, 0, size)) return pf__sq_fail(&c, PF_ERR_PARSE, NULL, "contains a NUL byte (not a JSON text file)");
    const char *end = NULL;
    /* Length without a terminator: cJSON stops at `size`; trailing text is
     * checked below (require_null_terminated would demand a NUL in range). */
    cJSON *root = cJSON_ParseWithLengthOpts(json, size, &end, 0);
    if (!root) {
        size_t at = end && end >= json && end <= json + size ? (size_t)(end - json) : size;
        unsigned line, col;
        pf__line_col(json, at, &line, &col);
        int open = pf__unclosed(json, size); /* 2: inside a string, which cJSON reports at its start */
        if (open == 2 || (open && at + 1 >= size))
            return pf__sq_fail(&c, PF_ERR_PARSE, NULL, "JSON ends too early (truncated?) at line %u", line);
        return pf__sq_fail(&c, PF_ERR_PARSE, NULL, "JSON syntax error at line %u, column %u", line, col);
    }
    size_t at = end && end >= json && end <= json + size ? (size_t)(end - json) : size;
    while (at < size && (json[at] == ' ' || json[at] == '\t' || json[at] == '\n' || json[at] == '\r')) at++;
    pf_result r;
    if (at < size) {
        unsigned line, col;
        pf__line_col(json, at, &line, &col);
        r = pf__sq_fail(&c, PF_ERR_PARSE, NULL, "unexpected text after the JSON value at line %u, column %u", line, col);
    } else {
        r = pf__top(&c, seq, root);
    }
    cJSON_Delete(root);
    if (r != PF_OK) {
        char f[sizeof seq->file];
        memcpy(f, seq->file, sizeof f);
        pf_sequence_free(seq);
        memcpy(seq->file, f, sizeof f);
    }
    return r;
}

pf_result pf_sequence_load(pf_sequence *seq, const char *path, pf_error *err)
{
    memset(seq, 0, sizeof *seq);
    char *buf;
    size_t size;
    pf_result r = pf_imageio_read_file(path, PF_SEQUENCE_MAX_FILE - 1, "sequence file", &buf, &size, err);
    if (r == PF_OK) r = pf_sequence_parse(seq, buf, size, path, err);
    free(buf);
    return r;
}

void pf_sequence_free(pf_sequence *seq)
{
    pf__track_free(&seq->camera);
    for (uint32_t i = 0; i < seq->light_count; i++)
        for (int k = 0; k < PF_SEQUENCE_FIELD_COUNT; k++) pf__track_free(&seq->lights[i].field[k]);
    free(seq->lights);
    memset(seq, 0, sizeof *seq);
}

/* ---------------------------------------------------------------- manifest */

pf_result pf_sequence_manifest_write(const char *dir, const pf_sequence_manifest *m, pf_error *err)
{
    char path[4200], text[128];
    snprintf(path, sizeof path, "%s/%s", dir, PF_SEQUENCE_MANIFEST);
    int n = snprintf(text, sizeof text, "softgi-frames 1\nframes %u\nstate %s\n", m->frames,
                     m->complete ? "complete" : "running");
    return pf_imageio_write_file(path, text, (size_t)n, err);
}

pf_result pf_sequence_manifest_read(const char *dir, pf_sequence_manifest *m, int *present, pf_error *err)
{
    char path[4200], text[256];
    memset(m, 0, sizeof *m);
    *present = 0;
    snprintf(path, sizeof path, "%s/%s", dir, PF_SEQUENCE_MANIFEST);
    FILE *f = fopen(path, "rb");
    if (!f) {
        if (errno == ENOENT) return PF_OK;
        return pf_error_set(err, PF_ERR_IO, "%s: cannot open: %s", path, strerror(errno));
    }
    size_t n = fread(text, 1, sizeof text - 1, f);
    int big = fgetc(f) != EOF;
    fclose(f);
    text[n] = 0;
    unsigned frames = 0;
    char state[16] = "";
    int used = 0;
    if (big || strlen(text) != n ||
        sscanf(text, "softgi-frames 1\nframes %u\nstate %15s\n%n", &frames, state, &used) != 2 ||
        (size_t)used != n || frames < 1 || frames > PF_SEQUENCE_MAX_FRAMES ||
        (strcmp(state, "complete") && strcmp(state, "running")))
        return pf_error_set(err, PF_ERR_PARSE, "%s: not a softgi-frames 1 manifest", path);
    m->frames = frames;
    m->complete = !strcmp(state, "complete");
    *present = 1;
    return PF_OK;
}
