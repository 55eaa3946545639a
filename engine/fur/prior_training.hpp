#pragma once
// Training the strand prior on procedural strands (strand_shapes.hpp), and measuring it: point
// error after encoding and decoding, and after fitting the latent by gradient descent through the
// decoder alone (what the fur stage does). A step: encoder forward, latent noise (a fixed-variance
// VAE: nearby latents must decode to similar strands) and a small L2 pull of the latents to the
// origin, decoder forward, the loss on the points (the running sum of the decoded segments) and on
// the segments, both adjoints, AdamW on both networks. The networks run on the GPU; the running
// sum, the loss and the noise are host work of a few microseconds per strand.
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "engine/core/json.hpp"
#include "engine/fur/strand_prior.hpp"

namespace nf::fur {

struct PriorTrainingOptions {
  StrandPriorConfig shape;
  std::uint32_t steps = 6000;
  std::uint32_t batch = 2048;
  std::uint64_t seed = 1;
  float lr = 1e-3f, lr_floor = 0.05f;  // cosine from lr to lr * lr_floor after a warm-up
  std::uint32_t warmup = 200;
  float latent_noise = 0.05f;   // standard deviation added to the latents while training
  float latent_l2 = 1e-3f;      // weight of the mean squared latent
  float segment_weight = 0.05f; // weight of the segment-vector loss beside the point loss
  std::uint32_t curve_every = 50;
};

struct PriorTraining {
  std::unique_ptr<StrandPrior> prior;
  json curve = json::array();  // [step, seconds, loss, mean point error of the batch]
  double seconds = 0;
  std::uint32_t skipped_steps = 0;
};

// `progress(step, loss)` is called every curve_every steps (for a progress line); may be empty.
PriorTraining train_strand_prior(gpu::Context& context, const PriorTrainingOptions& options,
                                 const std::function<void(std::uint32_t, double)>& progress = {});

// Encode then decode.
PointError reconstruction_error(StrandPrior& prior, const std::vector<float>& strands);

// The latents that best decode to `strands`: Adam on the latents through the decoder alone, from
// the encoder's latents (`from_encoder`) or from zero, `iterations` steps. Returns the error after.
struct LatentFit {
  std::vector<float> latents;
  PointError error;
  std::vector<double> curve;  // mean point error after each iteration
};
LatentFit fit_latents(StrandPrior& prior, const std::vector<float>& strands, std::uint32_t iterations, float lr,
                      bool from_encoder);

}  // namespace nf::fur
