/* tinygltf_impl: the one translation unit holding tinygltf's and stb_image's
 * implementations for the fuzz build, so the sanitizers instrument them too
 * (the system libtinygltf.so and libstb.so are not instrumented and are not
 * linked here). stb_image_write is left out (TINYGLTF_NO_STB_IMAGE_WRITE, set
 * for every TU of the fuzz target): the loader never writes images. */
#define TINYGLTF_IMPLEMENTATION
#define STB_IMAGE_IMPLEMENTATION
#include <tiny_gltf.h>
