#pragma once
// The losses under the gradient-check protocol.
#include <memory>

#include "engine/gradcheck/harness.hpp"

namespace nf::nn {

std::unique_ptr<gradcheck::DifferentiableKernel> make_mse_loss_check();

}  // namespace nf::nn
