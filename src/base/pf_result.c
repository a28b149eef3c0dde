/* pf_result: error code names and message formatting (see pf_result.h). */
#include "pf_result.h"

#include <stdio.h>

static const char *const pf__result_names[PF_ERR_COUNT] = {
    [PF_OK] = "ok",
    [PF_ERR_IO] = "i/o error",
    [PF_ERR_PARSE] = "parse error",
    [PF_ERR_ACCESSOR] = "accessor out of range",
    [PF_ERR_INDEX_RANGE] = "index out of range",
    [PF_ERR_NONFINITE] = "non-finite or huge value",
    [PF_ERR_NO_TRIANGLES] = "no triangles",
    [PF_ERR_NO_CAMERA] = "no camera",
    [PF_ERR_TEXTURE] = "texture error",
    [PF_ERR_UNSUPPORTED] = "unsupported",
    [PF_ERR_OUT_OF_MEMORY] = "out of memory",
    [PF_ERR_EMBREE] = "embree error",
    [PF_ERR_ARGUMENT] = "bad argument",
};

const char *pf_result_name(pf_result code)
{
    if ((unsigned)code >= PF_ERR_COUNT) return "unknown error";
    return pf__result_names[code];
}

pf_result pf_error_set(pf_error *err, pf_result code, const char *fmt, ...)
{
    if (err) {
        err->code = code;
        va_list ap;
        va_start(ap, fmt);
        vsnprintf(err->message, sizeof err->message, fmt, ap);
        va_end(ap);
    }
    return code;
}

int pf_result_exit_code(pf_result code)
{
    if (code == PF_OK) return 0;
    if (code == PF_ERR_ARGUMENT) return 2;
    return 1;
}
