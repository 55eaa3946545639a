#pragma once
// `nf_gpu bench --suite body`: the body stage on synthetic animals (cat, dog, lion; two seeds each),
// from the NeuS mesh the pipeline itself produces: label accuracy against the ground truth,
// per-region recall, eye-centre error, chamfer after each fitting stage, and time per stage.
#include "engine/bench/suites.hpp"

namespace nf::bench {

json run_body_suite(gpu::Context& context, const Options& options);

}  // namespace nf::bench
