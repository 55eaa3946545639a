#pragma once
// The whole strand rasteriser (strand points and segment confidence -> the 5 image channels) under
// the gradient-check protocol, on tiny scenes: a few strands, images of a few tiles.
#include <memory>

#include "engine/gradcheck/harness.hpp"

namespace nf::splat {

std::unique_ptr<gradcheck::DifferentiableKernel> make_rasterizer_check();

}  // namespace nf::splat
