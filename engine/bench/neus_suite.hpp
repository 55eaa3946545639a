#pragma once
// `nf_gpu bench --suite neus`: the surface stage's speed against error. Trains the draft NeuS on a
// synthetic cat (made by `synth`, with its ground-truth outer surface) and records the chamfer of
// the extracted mesh against gt/outer.ply at intervals of training time: the error-vs-time curve.
#include "engine/bench/suites.hpp"

namespace nf::bench {
json run_neus_suite(gpu::Context& context, const Options& options);
}
