#pragma once
// The per-region length factors (length_factors.hpp) through the strand geometry map, in the
// gradient-check catalog: the fur stage's lengths-from-photos gradient end to end (the GPU
// adjoint's length gradients reduced per region on the host, as the trainer does).
#include <memory>

#include "engine/gradcheck/harness.hpp"

namespace nf::fur {

std::unique_ptr<gradcheck::DifferentiableKernel> make_length_factors_check();

}  // namespace nf::fur
