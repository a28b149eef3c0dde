/* pf_result: the one table of error codes and messages used at softgi's edges
 * (loaders, files, CLI, Embree, window). Hot loops never return errors; they
 * assert. A failing call fills a pf_error with a code and a one-line message
 * meant for the user, e.g. "scene.gltf: accessor 3 reads past the end of
 * bufferView 1 (needs 480 bytes, has 240)". */
#ifndef PF_RESULT_H
#define PF_RESULT_H

#include <stdarg.h>

#ifdef __cplusplus
extern "C" {
#endif

typedef enum pf_result {
    PF_OK = 0,
    PF_ERR_IO,            /* file missing or unreadable, write failed        */
    PF_ERR_PARSE,         /* not a glTF / JSON / sequence file we can parse   */
    PF_ERR_ACCESSOR,      /* accessor or bufferView out of range / malformed  */
    PF_ERR_INDEX_RANGE,   /* vertex index or object reference out of range    */
    PF_ERR_NONFINITE,     /* NaN / inf / huge coordinate                      */
    PF_ERR_NO_TRIANGLES,  /* nothing to render                                */
    PF_ERR_NO_CAMERA,     /* no camera in the scene and none given            */
    PF_ERR_TEXTURE,       /* missing or undecodable texture image             */
    PF_ERR_UNSUPPORTED,   /* valid glTF using something softgi cannot do      */
    PF_ERR_OUT_OF_MEMORY,
    PF_ERR_EMBREE,        /* Embree device / scene error                      */
    PF_ERR_ARGUMENT,      /* bad command-line value                           */
    PF_ERR_COUNT
} pf_result;

typedef struct pf_error {
    pf_result code;
    char message[512];
} pf_error;

/* Short stable name of a code, e.g. "accessor out of range". */
const char *pf_result_name(pf_result code);

/* Sets err->code and formats err->message; returns code so callers can
 * `return pf_error_set(err, PF_ERR_IO, "...")`. err may be NULL. */
pf_result pf_error_set(pf_error *err, pf_result code, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;

/* Process exit status for a result: 0 for PF_OK, 2 for bad usage, 1 otherwise. */
int pf_result_exit_code(pf_result code);

#ifdef __cplusplus
}
#endif

#endif
