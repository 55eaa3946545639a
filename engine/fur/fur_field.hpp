#pragma once
// The neural fur field (paper: Neural fur representation): a root p, normalised to [-1, 1] in the
// roots' box, is frequency-encoded (10 frequencies: 63 inputs), an MLP (64-128-256-256) gives the
// strand prior's latent z and the strand's rendered confidence (fur_field_head_ref.hpp), the prior's
// decoder G turns z into 99 segment vectors in the root's frame, and the strand geometry map
// (strand_geometry_ref.hpp) makes them 100 world points of the root's fur length. Every map has a
// GPU adjoint, so a loss on the points and confidences trains the MLP (and G when asked).
#include <cstdint>
#include <memory>
#include <vector>

#include <glm/glm.hpp>

#include "engine/core/json.hpp"
#include "engine/fur/fur_field_head.hpp"
#include "engine/fur/roots.hpp"
#include "engine/fur/strand_geometry.hpp"
#include "engine/fur/strand_prior.hpp"
#include "engine/nn/frequency_encoding.hpp"
#include "engine/nn/mlp.hpp"

namespace nf::fur {

struct FurFieldConfig {
  std::uint32_t frequencies = 10;
  std::vector<std::uint32_t> hidden{64, 128, 256, 256};  // the paper's
  nn::MlpConfig mlp(std::uint32_t latent) const;        // 3 + 6 f inputs -> hidden (ReLU) -> latent + 1
  json to_json() const;
};

// The box that maps roots to [-1, 1] per axis (a flat axis maps to 0).
struct RootBox {
  glm::vec3 lo{-1.f}, hi{1.f};
  glm::vec3 normalise(glm::vec3 p) const;
};
RootBox root_box(const Roots& roots);

// Per region (indexed by Roots::region), a factor on the roots' fur lengths: 1 keeps the
// knowledge's length, the fur stage learns it from the photos (fur_trainer.hpp). Regions past the
// end keep 1.
using LengthFactors = std::vector<float>;
inline float length_factor(const LengthFactors& f, std::int32_t region) {
  return region >= 0 && std::size_t(region) < f.size() ? f[std::size_t(region)] : 1.f;
}

// Frames rows (kFrameFloats per strand: root, length x its region's factor, T, B, N) and normalised
// roots of the roots listed in `ids`.
void strand_inputs(const Roots& roots, const std::vector<std::uint32_t>& ids, const RootBox& box, std::vector<float>& normalised,
                   std::vector<float>& frames, const LengthFactors& length_factors = {});

class FurField {
 public:
  // `prior` must outlive the field. The MLP starts from Kaiming-uniform weights of `seed`.
  FurField(gpu::Context& context, const FurFieldConfig& config, StrandPrior& prior, const RootBox& box, unsigned seed);

  const FurFieldConfig& config() const { return config_; }
  const RootBox& box() const { return box_; }
  nn::Mlp& mlp() { return *mlp_; }
  StrandPrior& prior() { return prior_; }
  std::uint32_t points_per_strand() const { return kStrandSegments + 1; }

  // Starts every root at the strand of `latent` (the prior's latent of a chosen strand): the last
  // layer's bias becomes that latent and its weights are scaled by `weight_scale`, so the field
  // begins near that strand everywhere and can still vary across roots.
  void start_at(const std::vector<float>& latent, float confidence_raw, float weight_scale);

  // Device buffers of one training batch of `strands` strands.
  struct Batch {
    Batch(FurField& field, std::uint32_t strands);
    std::uint32_t strands;
    gpu::Buffer<float> roots, frames, encoded, latents, confidence, points;  // inputs: roots (N x 3, normalised), frames (N x 13)
    gpu::Buffer<float> grad_points, grad_confidence, grad_rows, grad_frames, grad_latents, grad_head;
    nn::Mlp::Workspace field, decoder;
  };
  // Records the forward of the batch (roots and frames uploaded): points and confidence.
  void forward(gpu::Stream& stream, Batch& batch) const;
  // Records the adjoint from batch.grad_points and batch.grad_confidence: the MLP's parameter
  // gradients (and the decoder's, which only an optimiser of the decoder reads).
  void backward(gpu::Stream& stream, Batch& batch);

  // Strands of `ids` (any count) in chunks of `chunk` strands; `sink` receives each chunk's first
  // index into ids, count and points (count x 100 x 3) and confidences (count).
  void infer(const Roots& roots, const std::vector<std::uint32_t>& ids, std::uint32_t chunk,
             const std::function<void(std::size_t, std::uint32_t, const std::vector<float>&, const std::vector<float>&)>& sink);

  // The MLP's parameters (for checkpoints and the stage's weights file).
  std::vector<float> parameters() const;
  void set_parameters(const std::vector<float>& values);  // InputError on a size mismatch

  // The per-region length factors every strand of the field is grown with (empty: all 1).
  const LengthFactors& length_factors() const { return length_factors_; }
  void set_length_factors(LengthFactors factors);  // InputError unless finite and positive

 private:
  FurHeadShape head_shape(std::uint32_t strands) const;
  StrandGeometryShape geometry_shape(std::uint32_t strands) const;

  gpu::Context& context_;
  FurFieldConfig config_;
  StrandPrior& prior_;
  RootBox box_;
  nn::FrequencyEncoding encoding_;
  std::unique_ptr<nn::Mlp> mlp_;
  LengthFactors length_factors_;
};

}  // namespace nf::fur
