#pragma once
// The input encodings under the gradient-check protocol.
#include <memory>

#include "engine/gradcheck/harness.hpp"

namespace nf::nn {

std::unique_ptr<gradcheck::DifferentiableKernel> make_frequency_encoding_check();
std::unique_ptr<gradcheck::DifferentiableKernel> make_hash_grid_check();

}  // namespace nf::nn
