#pragma once
// `nf_gpu bench --suite fur`, its scene part: the whole pipeline on synthetic cat and lion scenes
// (36 views at 512x512), the fur stage's scores against training time at each preset, the baseline
// grooms (a) (the pipeline's M_bald and roots) and (b) (the true bald body and roots), and the
// ablations: the warm start off, each loss off in turn, the truth swapped in for the knowledge and
// for every earlier stage.
#include "engine/bench/suites.hpp"

namespace nf::bench {

json run_fur_scene_suite(gpu::Context& context, const Options& options);

}  // namespace nf::bench
