#pragma once
// The strand geometry map (strand_geometry.hpp) in the gradient-check catalog.
#include <memory>

#include "engine/gradcheck/harness.hpp"

namespace nf::fur {

std::unique_ptr<gradcheck::DifferentiableKernel> make_strand_geometry_check();

}  // namespace nf::fur
