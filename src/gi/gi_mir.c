/* gi_mir: MIR-style resampled light paths (Hedman 2017 Sec. 5.1).
 * NOT IMPLEMENTED YET: this placeholder registers the name so the CLI can
 * list it; create() fails with a clear error. */
#include <stddef.h>

#include "gi_vpl.h"

static pf_result gi__mir_create(void **state, const gi_params *params, pf_error *err)
{
    (void)params;
    *state = NULL;
    return pf_error_set(err, PF_ERR_ARGUMENT, "--method mir: not implemented yet");
}

static pf_result gi__mir_update(void *state, const gi_vpl_inputs *in, gi_vpl_set *out, pf_error *err)
{
    (void)state, (void)in, (void)out;
    return pf_error_set(err, PF_ERR_ARGUMENT, "--method mir: not implemented yet");
}

static void gi__mir_destroy(void *state) { (void)state; }

const gi_vpl_method gi_method_mir = {
    "mir", "MIR-style resampled light paths (Hedman 2017 Sec. 5.1)", gi__mir_create, gi__mir_update, gi__mir_destroy,
};
