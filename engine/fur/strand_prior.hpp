#pragma once
// The strand prior: an encoder from a strand (99 points after the root, TBN frame, unit length) to
// a latent z of 64 floats, and the decoder G from z to 99 segment vectors whose running sum (over
// 99) gives the strand's 100 points. G is what the fur stage runs for every strand; the encoder
// serves evaluation and warm starts. Both are the engine's GPU MLPs (engine/nn). Stored as one
// versioned nn weights file (engine/nn/weights_io.hpp) whose config holds both networks' shapes,
// the training settings and the record of how the weights were made.
#include <cstdint>
#include <filesystem>
#include <memory>
#include <vector>

#include "engine/core/json.hpp"
#include "engine/fur/strand_shapes.hpp"
#include "engine/nn/mlp.hpp"

namespace nf::fur {

inline constexpr std::uint32_t kStrandValues = kStrandSegments * 3;  // 297: points 1..99, or segments

struct StrandPriorConfig {
  std::uint32_t latent = 64;
  // 128 wide: 2.5x fewer multiply-adds than 256 for 0.1 percentage points of point error
  // (docs/strand-prior.md); the decoder runs for every strand of every fur step.
  std::vector<std::uint32_t> encoder_hidden{128, 128};
  std::vector<std::uint32_t> decoder_hidden{128, 128};
  nn::MlpConfig encoder() const;  // 297 -> hidden -> latent (ReLU, linear output)
  nn::MlpConfig decoder() const;  // latent -> hidden -> 297
  json to_json() const;
  static StrandPriorConfig from_json(const json& j, const std::string& source);
};

class StrandPrior {
 public:
  StrandPrior(gpu::Context& context, const StrandPriorConfig& config);
  const StrandPriorConfig& config() const { return config_; }
  nn::Mlp& encoder() { return *encoder_; }
  nn::Mlp& decoder() { return *decoder_; }
  const nn::Mlp& decoder() const { return *decoder_; }

  // Strands (N x 100 x 3, unit length, root at the origin) to latents (N x latent), and back.
  std::vector<float> encode(const std::vector<float>& strands);
  std::vector<float> decode(const std::vector<float>& latents);

  // The record of how the weights were made (command, seed, steps, errors), kept in the file.
  json record = json::object();

  void save(const std::filesystem::path& path) const;
  // Throws InputError naming the file and the field or tensor that is wrong.
  static std::unique_ptr<StrandPrior> load(gpu::Context& context, const std::filesystem::path& path);
  static std::unique_ptr<StrandPrior> from_bytes(gpu::Context& context, const std::string& bytes, const std::string& source);

 private:
  gpu::Context& context_;
  StrandPriorConfig config_;
  std::unique_ptr<nn::Mlp> encoder_, decoder_;
};

// The weights shipped in assets/strand_prior/ (embedded in the binary at build time).
std::unique_ptr<StrandPrior> shipped_strand_prior(gpu::Context& context);
const std::string& shipped_strand_prior_bytes();

// Encoder input rows ([N][pad4(297)]) from strands: points 1..99 of each.
std::vector<float> encoder_rows(const std::vector<float>& strands, std::uint32_t stride);
// Strands (N x 100 x 3) from decoder output rows ([N][stride], 99 segment vectors): p_k = sum_{i<k} d_i / 99.
std::vector<float> strands_from_rows(const std::vector<float>& rows, std::uint32_t stride, std::uint32_t count);
// The adjoint of strands_from_rows: dL/drows from dL/dpoints (points 1..99; the root is fixed).
std::vector<float> rows_gradient(const std::vector<float>& grad_points, std::uint32_t stride, std::uint32_t count);

}  // namespace nf::fur
