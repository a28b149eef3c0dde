/* gi_tcas: Independent Metropolis-Hastings RSM sampling, TCAS (Barak 2013 Sec. 4, Algorithm 1).
 * NOT IMPLEMENTED YET: this placeholder registers the name so the CLI can
 * list it; create() fails with a clear error. */
#include <stddef.h>

#include "gi_vpl.h"

static pf_result gi__tcas_create(void **state, const gi_params *params, pf_error *err)
{
    (void)params;
    *state = NULL;
    return pf_error_set(err, PF_ERR_ARGUMENT, "--method tcas: not implemented yet");
}

static pf_result gi__tcas_update(void *state, const gi_vpl_inputs *in, gi_vpl_set *out, pf_error *err)
{
    (void)state, (void)in, (void)out;
    return pf_error_set(err, PF_ERR_ARGUMENT, "--method tcas: not implemented yet");
}

static void gi__tcas_destroy(void *state) { (void)state; }

const gi_vpl_method gi_method_tcas = {
    "tcas", "Independent Metropolis-Hastings RSM sampling, TCAS (Barak 2013 Sec. 4, Algorithm 1)", gi__tcas_create, gi__tcas_update, gi__tcas_destroy,
};
