#pragma once
// `nf_gpu bench --suite fur`: the fur stage's kernels at the fur stage's sizes (15,000 strands of
// 100 points a step): the strand geometry map, the geometric strand losses and the one-way chamfer
// (1.5 M strand points against 20,000 samples of M_NeuS), each forward + backward on device-resident
// data, beside its error against the CPU reference. The optimisation's own curves come with the
// fur stage.
#include "engine/bench/suites.hpp"

namespace nf::bench {

json run_fur_suite(gpu::Context& context, const Options& options);

}  // namespace nf::bench
