#pragma once
// tinygltf (Debian's libtinygltf-dev, used header-only), configured once for every file that
// includes it: meshes only, so no image decoding or encoding (stb stays with image.cpp) and no
// external image files, and no default file-system callbacks (gltf_model.cpp supplies its own,
// which read buffers beside the .gltf and download nothing). tinygltf.cpp holds the implementation.
#define TINYGLTF_NO_STB_IMAGE
#define TINYGLTF_NO_STB_IMAGE_WRITE
#define TINYGLTF_NO_EXTERNAL_IMAGE
#define TINYGLTF_NO_FS
#include <tiny_gltf.h>
