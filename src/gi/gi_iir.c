/* gi_iir: Incremental Instant Radiosity (Laine 2007 Sec. 4).
 * NOT IMPLEMENTED YET: this placeholder registers the name so the CLI can
 * list it; create() fails with a clear error. */
#include <stddef.h>

#include "gi_vpl.h"

static pf_result gi__iir_create(void **state, const gi_params *params, pf_error *err)
{
    (void)params;
    *state = NULL;
    return pf_error_set(err, PF_ERR_ARGUMENT, "--method iir: not implemented yet");
}

static pf_result gi__iir_update(void *state, const gi_vpl_inputs *in, gi_vpl_set *out, pf_error *err)
{
    (void)state, (void)in, (void)out;
    return pf_error_set(err, PF_ERR_ARGUMENT, "--method iir: not implemented yet");
}

static void gi__iir_destroy(void *state) { (void)state; }

const gi_vpl_method gi_method_iir = {
    "iir", "Incremental Instant Radiosity (Laine 2007 Sec. 4)", gi__iir_create, gi__iir_update, gi__iir_destroy,
};
