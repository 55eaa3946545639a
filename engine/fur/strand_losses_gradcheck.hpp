#pragma once
// The geometric strand losses (strand_losses.hpp) in the gradient-check catalog.
#include <memory>

#include "engine/gradcheck/harness.hpp"

namespace nf::fur {

std::unique_ptr<gradcheck::DifferentiableKernel> make_strand_losses_check();

}  // namespace nf::fur
