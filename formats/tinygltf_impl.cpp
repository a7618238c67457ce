// tinygltf_impl.cpp - tinygltf's implementation (a header-only library), compiled on its own:
// it is most of the glTF adapter's compile time (over two minutes under the sanitizers), so
// it builds in parallel with the rest and is not rebuilt when gltf_load.cpp changes.
#define TINYGLTF_IMPLEMENTATION
#include "tinygltf_config.h"
