/* tinygltf_impl: the one translation unit holding tinygltf's and stb_image's
 * implementations in the fuzz build (SOFTGI_FUZZ=ON, top-level
 * CMakeLists.txt), where it is compiled into softgi_core instead of linking
 * the system libtinygltf.so, so the sanitizers and libFuzzer's coverage
 * instrument the JSON parser and the image decoder too. stb_image_write is
 * left out (TINYGLTF_NO_STB_IMAGE_WRITE, set for all of softgi_core in that
 * build): PNG output still comes from the system libstb. */
#define TINYGLTF_IMPLEMENTATION
#define STB_IMAGE_IMPLEMENTATION
#include <tiny_gltf.h>
