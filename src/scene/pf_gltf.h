/* pf_gltf: glTF 2.0 (.gltf and .glb) scene loading. A thin C++ shim over
 * tinygltf (pf_gltf.cpp) exposing this plain C API; nothing else in softgi
 * sees tinygltf.
 *
 * What it reads (glTF 2.0 spec; KHR_lights_punctual; KHR_materials_emissive_strength):
 * - the default scene (or scene 0; or every root node when the file has no
 *   scenes), node hierarchy flattened into world space (matrix or TRS);
 * - mesh primitives in TRIANGLES, TRIANGLE_STRIP and TRIANGLE_FAN mode,
 *   indexed by u8/u16/u32 or not indexed; POINTS/LINES are skipped with a
 *   warning; POSITION (float), NORMAL (float; flat normals generated when
 *   missing), TEXCOORD_0 (float or normalized u8/u16); sparse accessors;
 * - materials: baseColorFactor, baseColorTexture (+ sampler; mipmaps built at
 *   load), alphaMode/alphaCutoff, emissiveFactor (x emissive_strength),
 *   doubleSided; primitives without a material get the glTF default material;
 * - perspective cameras (orthographic ones are skipped with a warning);
 * - KHR_lights_punctual point, spot and directional lights.
 *
 * Every index, offset and count in the file is checked before use: a bad file
 * gives a pf_error naming the file, the object and what is wrong, never a
 * crash. Node cycles and absurd depths are rejected. */
#ifndef PF_GLTF_H
#define PF_GLTF_H

#include <stddef.h>
#include <stdint.h>

#include "pf_scene.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct pf_gltf_options {
    /* Zero-initialised means defaults. */
    int ignore_textures; /* skip images entirely (albedo = factor) */
    uint64_t max_memory; /* memory budget in bytes (pf_budget.h); 0: the default */
} pf_gltf_options;

/* Loads `path` (.gltf or .glb, decided by content) into *out (zeroed first).
 * On failure *out is left empty and err says why. */
pf_result pf_gltf_load(pf_scene *out, const char *path, const pf_gltf_options *opts, pf_error *err);

/* Loads from memory (used by the fuzzer and by embedded scenes). `base_dir`
 * resolves external uris; NULL forbids external files. `name` is used in
 * messages. */
pf_result pf_gltf_load_memory(pf_scene *out, const void *data, size_t size, const char *base_dir,
                              const char *name, const pf_gltf_options *opts, pf_error *err);

#ifdef __cplusplus
}
#endif

#endif
