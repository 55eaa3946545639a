#pragma once
// `nf_gpu bench --suite splat`: the strand rasteriser forward and forward+backward on a synthetic
// cat's fur (15,000 strands x 100 points) at 512x512 and 1920x1080: seconds, Gaussians per second,
// GPU time per pass, an estimated share of the FMA roofline, and the error of the splatted hair
// silhouette against the independent ray-traced coverage of the same strands.
#include "engine/bench/suites.hpp"

namespace nf::bench {

json run_splat_suite(gpu::Context& context, const Options& options);

}  // namespace nf::bench
