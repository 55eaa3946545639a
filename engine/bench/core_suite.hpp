#pragma once
// The core roofline: copy bandwidth, fp32 FMA rate, dispatch and submit latency, and GPU primitive
// throughput (radix sort against std::sort and std::stable_sort in the same run, scan, reduce).
#include "engine/bench/suites.hpp"

namespace nf::bench {

json run_core_suite(gpu::Context& context, const Options& options);

// The device's measured fp32 FMA rate (GFLOP/s, median of a few runs): the roofline other suites
// report their share of.
double measure_fma_gflops(gpu::Context& context, bool quick);
// The device's memory traffic (GB/s read + written) of a vec4 copy kernel: the bandwidth roof.
double measure_copy_traffic_gbps(gpu::Context& context, bool quick);

}  // namespace nf::bench
