/* gi_ssvp: Screen-space VPL propagation, two bounces (Aranha, Sec. III).
 * NOT IMPLEMENTED YET: this placeholder registers the name so the CLI can
 * list it; create() fails with a clear error. */
#include <stddef.h>

#include "gi_vpl.h"

static pf_result gi__ssvp_create(void **state, const gi_params *params, pf_error *err)
{
    (void)params;
    *state = NULL;
    return pf_error_set(err, PF_ERR_ARGUMENT, "--method ssvp: not implemented yet");
}

static pf_result gi__ssvp_update(void *state, const gi_vpl_inputs *in, gi_vpl_set *out, pf_error *err)
{
    (void)state, (void)in, (void)out;
    return pf_error_set(err, PF_ERR_ARGUMENT, "--method ssvp: not implemented yet");
}

static void gi__ssvp_destroy(void *state) { (void)state; }

const gi_vpl_method gi_method_ssvp = {
    "ssvp", "Screen-space VPL propagation, two bounces (Aranha, Sec. III)", gi__ssvp_create, gi__ssvp_update, gi__ssvp_destroy,
};
