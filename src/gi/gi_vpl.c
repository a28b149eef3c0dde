/* gi_vpl: the VPL-method registry, VPL sets, method parameters and the
 * Halton sequence the methods share (see gi_vpl.h). */
#include "gi_vpl.h"

#include <errno.h>
#include <stdio.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

static const gi_vpl_method *const gi__methods[] = {
    &gi_method_ir, &gi_method_iir, &gi_method_smc, &gi_method_mir, &gi_method_invtm, &gi_method_tcas, &gi_method_ssvp,
};
#define GI__METHOD_COUNT (sizeof gi__methods / sizeof gi__methods[0])

const gi_vpl_method *gi_vpl_method_find(const char *name)
{
    if (!name) return &gi_method_ir;
    for (size_t i = 0; i < GI__METHOD_COUNT; i++)
        if (!strcmp(name, gi__methods[i]->name)) return gi__methods[i];
    return NULL;
}

const char *gi_vpl_method_names(void) { return "ir, iir, smc, mir, invtm, tcas, ssvp"; }

double gi_halton(uint32_t i, uint32_t base)
{
    double f = 1.0, r = 0.0;
    while (i > 0) {
        f /= base;
        r += f * (double)(i % base);
        i /= base;
    }
    return r;
}

pf_result gi_vpl_set_reserve(gi_vpl_set *set, uint32_t count, pf_error *err)
{
    if (count <= set->cap) return PF_OK;
    gi_vpl *v = realloc(set->v, sizeof(gi_vpl) * count);
    if (!v) return pf_error_set(err, PF_ERR_OUT_OF_MEMORY, "out of memory for %u VPLs", count);
    set->v = v;
    set->cap = count;
    return PF_OK;
}

void gi_vpl_set_free(gi_vpl_set *set)
{
    free(set->v);
    memset(set, 0, sizeof *set);
}

/* ---------------------------------------------------------- parameters */

pf_result gi_params_add(gi_params *p, const char *kv, pf_error *err)
{
    const char *eq = strchr(kv, '=');
    if (!eq || eq == kv || !eq[1])
        return pf_error_set(err, PF_ERR_ARGUMENT, "--param '%s': expected KEY=VALUE", kv);
    if (p->count >= GI_MAX_PARAMS)
        return pf_error_set(err, PF_ERR_ARGUMENT, "--param: at most %d parameters", GI_MAX_PARAMS);
    /* the key is the prefix up to '=': store it in a static-free way by
     * pointing at kv and comparing lengths in gi__find */
    p->key[p->count] = kv;
    p->value[p->count] = eq + 1;
    p->count++;
    return PF_OK;
}

static int gi__key_is(const char *stored, const char *key)
{
    size_t n = strlen(key);
    return !strncmp(stored, key, n) && (stored[n] == '=' || stored[n] == '\0');
}

static const char *gi__find(const gi_params *p, const char *key)
{
    const char *v = NULL;
    for (uint32_t i = 0; p && i < p->count; i++)
        if (gi__key_is(p->key[i], key)) v = p->value[i]; /* the last one wins */
    return v;
}

pf_result gi_params_check(const gi_params *p, const char *method, const char *const *known, pf_error *err)
{
    for (uint32_t i = 0; p && i < p->count; i++) {
        int ok = 0;
        for (const char *const *k = known; *k && !ok; k++) ok = gi__key_is(p->key[i], *k);
        if (!ok) {
            size_t n = strcspn(p->key[i], "=");
            char names[512] = "";
            for (const char *const *k = known; *k; k++) {
                if (names[0]) strncat(names, ", ", sizeof names - strlen(names) - 1);
                strncat(names, *k, sizeof names - strlen(names) - 1);
            }
            return pf_error_set(err, PF_ERR_ARGUMENT, "--param %.*s: method %s has no such parameter (it has: %s)",
                                (int)n, p->key[i], method, names[0] ? names : "none");
        }
    }
    return PF_OK;
}

pf_result gi_param_choice(const gi_params *p, const char *key, const char *const *names, uint32_t *out,
                          pf_error *err)
{
    const char *v = gi__find(p, key);
    if (!v) return PF_OK;
    char list[256] = "";
    for (uint32_t i = 0; names[i]; i++) {
        if (!strcmp(v, names[i])) {
            *out = i;
            return PF_OK;
        }
        size_t n = strlen(list);
        snprintf(list + n, sizeof list - n, "%s%s", i ? ", " : "", names[i]);
    }
    return pf_error_set(err, PF_ERR_ARGUMENT, "--param %s=%s: expected one of %s", key, v, list);
}

pf_result gi_param_u32(const gi_params *p, const char *key, uint32_t lo, uint32_t hi, uint32_t *out, pf_error *err)
{
    const char *v = gi__find(p, key);
    if (!v) return PF_OK;
    char *end = NULL;
    errno = 0;
    unsigned long long x = strtoull(v, &end, 10);
    if (v[0] == '-' || v[0] == '+' || end == v || *end || errno || x < lo || x > hi)
        return pf_error_set(err, PF_ERR_ARGUMENT, "--param %s=%s: expected an integer in [%u, %u]", key, v, lo, hi);
    *out = (uint32_t)x;
    return PF_OK;
}

pf_result gi_param_f32(const gi_params *p, const char *key, float lo, float hi, float *out, pf_error *err)
{
    const char *v = gi__find(p, key);
    if (!v) return PF_OK;
    char *end = NULL;
    errno = 0;
    float x = strtof(v, &end);
    if (end == v || *end || errno || !isfinite(x) || x < lo || x > hi)
        return pf_error_set(err, PF_ERR_ARGUMENT, "--param %s=%s: expected a number in [%g, %g]", key, v, (double)lo,
                            (double)hi);
    *out = x;
    return PF_OK;
}
