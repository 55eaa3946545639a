// The one translation unit that compiles tinygltf's implementation (with tinygltf.hpp's settings).
// tinygltf 2.7.0 under TINYGLTF_NO_FS still names std::ofstream (in file writers nf_gpu never
// calls) without including <fstream>.
#include <fstream>

#define TINYGLTF_IMPLEMENTATION
#include "engine/io/tinygltf.hpp"
