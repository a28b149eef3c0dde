/* pf_decode: placeholder until the libspng/TurboJPEG decoder lands (see pf_decode.h). */
#include "pf_decode.h"

#include <stdlib.h>

pf_image_format pf_decode_format(const void *bytes, size_t size)
{
    (void)bytes;
    (void)size;
    return PF_IMAGE_UNKNOWN;
}

pf_result pf_decode_probe(const void *bytes, size_t size, const pf_decode_limits *limits, pf_image_format *format,
                          uint32_t *w, uint32_t *h, pf_error *err)
{
    (void)bytes; (void)size; (void)limits; (void)format; (void)w; (void)h;
    return pf_error_set(err, PF_ERR_UNSUPPORTED, "image decoding is not implemented yet");
}

pf_result pf_decode_rgba8(const void *bytes, size_t size, const pf_decode_limits *limits, uint8_t **rgba,
                          uint32_t *w, uint32_t *h, pf_error *err)
{
    (void)bytes; (void)size; (void)limits; (void)w; (void)h;
    *rgba = NULL;
    return pf_error_set(err, PF_ERR_UNSUPPORTED, "image decoding is not implemented yet");
}
