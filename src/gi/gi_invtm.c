/* gi_invtm: Inverse transform sampling of reflective shadow maps (Ritschel 2011; Barak 2013 Sec. 4.2).
 * NOT IMPLEMENTED YET: this placeholder registers the name so the CLI can
 * list it; create() fails with a clear error. */
#include <stddef.h>

#include "gi_vpl.h"

static pf_result gi__invtm_create(void **state, const gi_params *params, pf_error *err)
{
    (void)params;
    *state = NULL;
    return pf_error_set(err, PF_ERR_ARGUMENT, "--method invtm: not implemented yet");
}

static pf_result gi__invtm_update(void *state, const gi_vpl_inputs *in, gi_vpl_set *out, pf_error *err)
{
    (void)state, (void)in, (void)out;
    return pf_error_set(err, PF_ERR_ARGUMENT, "--method invtm: not implemented yet");
}

static void gi__invtm_destroy(void *state) { (void)state; }

const gi_vpl_method gi_method_invtm = {
    "invtm", "Inverse transform sampling of reflective shadow maps (Ritschel 2011; Barak 2013 Sec. 4.2)", gi__invtm_create, gi__invtm_update, gi__invtm_destroy,
};
