#!/usr/bin/env bash
# Installs what softgi needs to build and test on Debian 12 (bookworm), and
# only what is missing. Uses sudo when not run as root.
set -euo pipefail
pkgs=(build-essential cmake pkg-config
      libembree-dev      # Embree 3: every sampling-side ray
      libglfw3-dev       # GLFW 3: the viewer window
      libgl-dev          # OpenGL 1.x headers/library for the viewer's textured quad
      libgl1-mesa-dri    # Mesa's software OpenGL (llvmpipe): the viewer needs no GPU
      xvfb xauth         # xvfb-run: the viewer's headless test (tests/test_viewer.c)
      libtinygltf-dev    # tinygltf: glTF 2.0 scenes
      libstb-dev         # stb_image_write: PNG output
      libmeshoptimizer-dev   # meshoptimizer: simplified shadow geometry
      libcjson-dev      # cJSON: sequence files
      libcmocka-dev      # cmocka: the test framework
      libspng-dev        # libspng: PNG textures (untrusted input; maintained and fuzzed for it)
      libturbojpeg0-dev  # libjpeg-turbo (TurboJPEG API): JPEG textures (likewise)
      libtinyexr-dev     # tinyexr: OpenEXR output (-o/--hdr NAME.exr, float stage dumps) and compare's .exr input
      clang libclang-rt-14-dev nlohmann-json3-dev)  # the fuzz build (libFuzzer; tinygltf's JSON parser instrumented)
missing=()
for p in "${pkgs[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all packages present"
  exit 0
fi
echo "install-deps: installing ${missing[*]}"
SUDO=""
[ "$(id -u)" -eq 0 ] || SUDO="sudo"
$SUDO apt-get update -qq
DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y --no-install-recommends "${missing[@]}"
