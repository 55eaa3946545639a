#pragma once
// GPU multiresolution hash-grid encoding (instant-ngp): forward, adjoint into the table (float
// atomics after a subgroup pre-reduction on dense levels) and into the points. Writes rows in the
// MLP layout (mlp_config.hpp). Points are expected in [0, 1]^3 (clamped otherwise).
#include <vector>

#include "engine/gpu/buffer.hpp"
#include "engine/gpu/stream.hpp"
#include "engine/nn/hash_grid_ref.hpp"

namespace nf::nn {

class HashGrid {
 public:
  explicit HashGrid(const HashGridConfig& config);  // throws InputError naming the bad field
  const HashGridConfig& config() const { return config_; }

  // instant-ngp's initialisation: uniform in [-1e-4, 1e-4].
  std::vector<float> initial_table(unsigned seed) const;

  // points: [batch][3]; table: parameter_count(); encoded: [batch][output_stride].
  void forward(gpu::Stream& stream, gpu::BufferRange points, gpu::BufferRange table, gpu::BufferRange encoded,
               std::uint32_t batch) const;
  // grad_table += dL/dtable (zero it first for a fresh gradient); grad_points, when not empty,
  // receives (or, with accumulate_points, gets added) dL/dpoints.
  void backward(gpu::Stream& stream, gpu::BufferRange points, gpu::BufferRange table, gpu::BufferRange grad_encoded,
                gpu::BufferRange grad_table, gpu::BufferRange grad_points, std::uint32_t batch,
                bool accumulate_points) const;

 private:
  HashGridConfig config_;
};

}  // namespace nf::nn
