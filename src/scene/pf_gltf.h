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
 * - KHR_lights_punctual point, spot and directional lights;
 * - skins (JOINTS_n / WEIGHTS_n, inverseBindMatrices) and morph targets
 *   (POSITION and NORMAL deltas, node and mesh weights): skinned and morphed
 *   primitives are flattened in the file's static pose (joints at their
 *   node transforms, the default weights), as glTF 2.0 Sec. 3.7.3 and
 *   3.7.2.2 define them; a skinned mesh node's own transform is ignored;
 * - animations (glTF 2.0 Sec. 3.11), checked here and kept, with the rest
 *   pose of everything they can move, in pf_gltf_options.anim, so that
 *   pf_anim_pose can pose the flattened scene at a time (pf_anim.h). The
 *   scene as loaded is the static pose: no animation applied.
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

struct pf_anim;

typedef struct pf_gltf_options {
    /* Zero-initialised means defaults. */
    int ignore_textures; /* skip images entirely (albedo = factor) */
    uint64_t max_memory; /* memory budget in bytes (pf_budget.h); 0: the default */
    struct pf_anim *anim; /* not NULL: filled with what posing the scene at a time needs (pf_anim.h),
                             freed by pf_anim_free; empty (zero animations) for a file without
                             animations, and on failure */
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
