#pragma once
// The MLP under the gradient-check protocol: every activation, odd widths, batches that are not
// a multiple of the workgroup, Softplus at large beta*x.
#include <memory>

#include "engine/gradcheck/harness.hpp"

namespace nf::nn {

std::unique_ptr<gradcheck::DifferentiableKernel> make_mlp_check();

}  // namespace nf::nn
