#pragma once
// `nf_gpu bench --suite nn`: training-step and inference throughput of the three networks the
// pipeline uses, as samples/s, GFLOP/s and share of the device's measured FMA rate; PyTorch on the
// CPU as a peer in the same run when available.
#include "engine/bench/suites.hpp"

namespace nf::bench {

json run_nn_suite(gpu::Context& context, const Options& options);

}  // namespace nf::bench
