/* gi_smc: Sequential Monte Carlo Instant Radiosity (Hedman 2017 Sec. 3, Algorithm 1).
 * NOT IMPLEMENTED YET: this placeholder registers the name so the CLI can
 * list it; create() fails with a clear error. */
#include <stddef.h>

#include "gi_vpl.h"

static pf_result gi__smc_create(void **state, const gi_params *params, pf_error *err)
{
    (void)params;
    *state = NULL;
    return pf_error_set(err, PF_ERR_ARGUMENT, "--method smc: not implemented yet");
}

static pf_result gi__smc_update(void *state, const gi_vpl_inputs *in, gi_vpl_set *out, pf_error *err)
{
    (void)state, (void)in, (void)out;
    return pf_error_set(err, PF_ERR_ARGUMENT, "--method smc: not implemented yet");
}

static void gi__smc_destroy(void *state) { (void)state; }

const gi_vpl_method gi_method_smc = {
    "smc", "Sequential Monte Carlo Instant Radiosity (Hedman 2017 Sec. 3, Algorithm 1)", gi__smc_create, gi__smc_update, gi__smc_destroy,
};
