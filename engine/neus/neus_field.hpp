#pragma once
// The NeuS networks on the GPU and the recording of their training forward and adjoint:
//   SDF network:    position -> encoding (hash grid, or frequencies for --quality paper) ->
//                   Softplus(100) MLP -> [sdf, geometry features];
//   colour network: [features, normal, view direction] -> ReLU MLP -> sigmoid rgb.
// Normals are tetrahedral finite differences of the SDF (4 evaluations per sample, step h;
// shaders/include/nf_neus_field.glsl), so the Eikonal term reaches the parameters through plain
// first-order adjoints (no second-order kernels), the choice NeuS2 and instant-nsr-pl also offer.
// The SDF value is the mean of the four evaluations (exact to O(h^2)).
// Shaders: shaders/neus/field_{points,combine_fwd,combine_bwd,colour}.comp.
#include <cstdint>
#include <memory>
#include <optional>
#include <vector>

#include <glm/glm.hpp>

#include "engine/core/json.hpp"
#include "engine/gpu/buffer.hpp"
#include "engine/gpu/stream.hpp"
#include "engine/nn/frequency_encoding.hpp"
#include "engine/nn/hash_grid.hpp"
#include "engine/nn/mlp.hpp"

namespace nf::neus {

enum class FieldEncoding { HashGrid, Frequency };

struct NeusFieldConfig {
  FieldEncoding encoding = FieldEncoding::HashGrid;
  nn::HashGridConfig hash{16, 2, 17, 16, 1024};
  nn::FrequencyEncodingConfig frequency{3, 6, true};
  std::vector<std::uint32_t> sdf_hidden{64};
  std::uint32_t features = 15;  // geometry features handed to the colour network
  std::vector<std::uint32_t> colour_hidden{64, 64};
  float init_radius = 0.5f;  // geometric initialisation: a sphere of this radius (unit coordinates)

  nn::MlpConfig sdf_mlp() const;     // input: [x, y, z, encoding] (hash) or the frequency rows
  nn::MlpConfig colour_mlp() const;  // input: features + 3 + 3
  std::uint32_t colour_input_dim() const { return features + 6; }
  void validate() const;  // InputError naming the field
};
json to_json(const NeusFieldConfig& c);

class NeusField {
 public:
  NeusField(gpu::Context& context, const NeusFieldConfig& config, unsigned seed);
  const NeusFieldConfig& config() const { return config_; }
  gpu::Context& context() const { return context_; }

  // Parameter and gradient buffers: the hash table (absent for the frequency encoding) and the
  // two MLPs'.
  bool has_table() const { return table_ != nullptr; }
  gpu::Buffer<float>& table() { return *table_; }
  gpu::Buffer<float>& table_gradient() { return *table_gradient_; }
  nn::Mlp& sdf() { return *sdf_; }
  nn::Mlp& colour() { return *colour_; }

  // Device memory of one training batch of `rays` x `samples_per_ray` samples.
  struct Batch {
    Batch(NeusField& field, std::uint32_t rays, std::uint32_t samples_per_ray);
    std::uint32_t rays, samples_per_ray, n;  // n = rays * samples_per_ray
    // Filled by the caller: sample positions (unit sphere, xyz + unused w) and ray directions.
    gpu::Buffer<glm::vec4> samples, dirs;
    // Written by forward(): per sample sdf, cos (dir . gradient), rgb [n][3]; gradient [n] (xyz, |g|).
    gpu::Buffer<float> sdf, cos, rgb;
    gpu::Buffer<glm::vec4> gradient;
    gpu::Buffer<float> eikonal_partials;  // per-workgroup sums of (|g| - 1)^2
    // Internal.
    gpu::Buffer<float> encoder_points, sdf_input, sdf_grad_output, sdf_grad_input;
    gpu::Buffer<float> colour_input, colour_grad_output, colour_grad_input;
    nn::Mlp::Workspace sdf_workspace, colour_workspace;
  };

  // Records the training forward of the batch with finite-difference step h (unit coordinates).
  void forward(gpu::Stream& stream, Batch& batch, float h) const;
  // Records the adjoint into the parameter gradients (overwritten) from dL/dsdf, dL/dcos, dL/drgb
  // ([n], [n], [n][3]) plus eikonal_weight * mean_samples (|g| - 1)^2.
  void backward(gpu::Stream& stream, Batch& batch, float h, float eikonal_weight, gpu::BufferRange grad_sdf,
                gpu::BufferRange grad_cos, gpu::BufferRange grad_rgb);

  // SDF values at points in unit coordinates (inference, chunked; no finite differences).
  std::vector<float> sdf_at(const std::vector<glm::vec3>& points) const;
  // SDF, gradient (finite differences with step h) and rgb seen along `dirs`, for previews.
  struct Shading {
    std::vector<float> sdf;
    std::vector<glm::vec3> gradient, rgb;
  };
  Shading shade(const std::vector<glm::vec3>& points, const std::vector<glm::vec3>& dirs, float h);

  // All parameters as named tensors (for checkpoints and model files), and back; load checks sizes.
  std::vector<std::pair<std::string, std::vector<float>>> save_parameters() const;
  void load_parameters(const std::vector<std::pair<std::string, std::vector<float>>>& tensors);

 private:
  void encode(gpu::Stream& stream, gpu::BufferRange points, gpu::BufferRange rows, std::uint32_t count) const;

  gpu::Context& context_;
  NeusFieldConfig config_;
  std::optional<nn::HashGrid> hash_;
  std::optional<nn::FrequencyEncoding> frequency_;
  std::unique_ptr<gpu::Buffer<float>> table_, table_gradient_;
  std::unique_ptr<nn::Mlp> sdf_, colour_;
};

}  // namespace nf::neus
