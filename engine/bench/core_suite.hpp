#pragma once
// The core roofline: copy bandwidth, fp32 FMA rate, dispatch and submit latency, and GPU primitive
// throughput (radix sort against std::sort and std::stable_sort in the same run, scan, reduce).
#include "engine/bench/suites.hpp"

namespace nf::bench {

json run_core_suite(gpu::Context& context, const Options& options);

}  // namespace nf::bench
