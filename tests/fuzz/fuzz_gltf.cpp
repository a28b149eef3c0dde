/* fuzz_gltf: libFuzzer target for the glTF loader (pf_gltf.h).
 *
 * Feeds each input to pf_gltf_load_memory as the whole file (.gltf or .glb,
 * decided by content), with base_dir NULL so no external file is ever read,
 * then frees the scene. The contract under test (pf_gltf.h): any input gives
 * PF_OK or a pf_error, never a crash, a leak, an out-of-bounds access or
 * undefined behaviour; a failed load leaves the scene empty. A successful one
 * must pass pf_scene_validate, since the renderer trusts loaded scenes.
 *
 * Built by tests/fuzz/CMakeLists.txt with -fsanitize=fuzzer,address,undefined
 * over its own instrumented copy of the loader and of tinygltf; run with
 * tools/fuzz.sh. */
#include <cstddef>
#include <cstdint>
#include <cstdlib>

#include "pf_gltf.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    pf_scene scene;
    pf_error err = {};
    pf_result r = pf_gltf_load_memory(&scene, data, size, nullptr, "fuzz", nullptr, &err);
    if (r == PF_OK) {
        /* the loader promises a valid scene: anything else is a bug */
        pf_error verr = {};
        if (pf_scene_validate(&scene, &verr) != PF_OK) abort();
    } else if (scene.tri_count != 0 || scene.positions != nullptr || scene.materials != nullptr ||
               err.message[0] == '\0') {
        abort(); /* failure must leave *out empty and say why */
    }
    pf_scene_free(&scene);
    return 0;
}
