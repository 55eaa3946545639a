#pragma once
// NeuS volume rendering under the gradient-check protocol.
#include <memory>

#include "engine/gradcheck/harness.hpp"

namespace nf::neus {

std::unique_ptr<gradcheck::DifferentiableKernel> make_volume_render_check();

}  // namespace nf::neus
