#pragma once
// Every differentiable kernel of the engine. Adding a kernel: implement DifferentiableKernel next to
// its host wrapper (see engine/splat/segment_gaussian_gradcheck.cpp) and list it in catalog.cpp.
#include <memory>
#include <vector>

#include "engine/gradcheck/harness.hpp"

namespace nf::gradcheck {

std::vector<std::unique_ptr<DifferentiableKernel>> all_kernels();

}  // namespace nf::gradcheck
