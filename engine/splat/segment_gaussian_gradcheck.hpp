#pragma once
// The segment-to-Gaussian kernel under the gradient-check protocol, with its hard cases.
#include <memory>

#include "engine/gradcheck/harness.hpp"

namespace nf::splat {

std::unique_ptr<gradcheck::DifferentiableKernel> make_segment_gaussian_check();

}  // namespace nf::splat
