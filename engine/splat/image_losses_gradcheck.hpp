#pragma once
// The image-space losses (silhouette, orientation) under the gradient-check protocol.
#include <memory>

#include "engine/gradcheck/harness.hpp"

namespace nf::splat {

std::unique_ptr<gradcheck::DifferentiableKernel> make_image_losses_check();

}  // namespace nf::splat
