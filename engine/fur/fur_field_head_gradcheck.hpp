#pragma once
// The fur field's head (fur_field_head.hpp) in the gradient-check catalog.
#include <memory>

#include "engine/gradcheck/harness.hpp"

namespace nf::fur {

std::unique_ptr<gradcheck::DifferentiableKernel> make_fur_head_check();

}  // namespace nf::fur
