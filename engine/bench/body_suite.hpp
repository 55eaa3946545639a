#pragma once
// `nf_gpu bench --suite body`: the body stage on synthetic animals (cat, dog, fox, panda, tiger and lion, three seeds each, none shared, drawn wider than their
// families: proportions within 25 %, fur lengths within 40 % of the preset the knowledge is given),
// from the NeuS mesh the pipeline itself produces: label accuracy against the ground truth,
// per-region recall, eye-centre error, chamfer after each fitting stage, and time per stage; then
// the defur and frames stages: M_bald's chamfer to the true bald body (beside M_NeuS's), the
// tangent field's smoothness and its angle to the true growth direction, and each step's time.
#include "engine/bench/suites.hpp"

namespace nf::bench {

json run_body_suite(gpu::Context& context, const Options& options);

}  // namespace nf::bench
