#pragma once
// The one-way chamfer (strand_chamfer.hpp) in the gradient-check catalog.
#include <memory>

#include "engine/gradcheck/harness.hpp"

namespace nf::fur {

std::unique_ptr<gradcheck::DifferentiableKernel> make_strand_chamfer_check();

}  // namespace nf::fur
