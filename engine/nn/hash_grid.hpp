#pragma once
// GPU multiresolution hash-grid encoding (instant-ngp): forward, adjoint into the table (float
// atomics after a subgroup pre-reduction on dense levels) and into the points. Writes rows in the
// MLP layout (mlp_config.hpp). Points are expected in [0, 1]^3 (clamped otherwise).
#include <vector>

#include "engine/gpu/buffer.hpp"
#include "engine/gpu/stream.hpp"
#include "engine/nn/hash_grid_ref.hpp"

namespace nf::nn {

// Where the encoding goes in its output rows: columns [offset, offset + output_dim()) of rows of
// `stride` floats (0: output_stride()), so it can sit beside other inputs of an MLP row (e.g. the
// raw position first). Forward zeroes the columns after it up to the row's end.
struct HashGridLayout {
  std::uint32_t stride = 0, offset = 0;
};

class HashGrid {
 public:
  explicit HashGrid(const HashGridConfig& config);  // throws InputError naming the bad field
  const HashGridConfig& config() const { return config_; }

  // instant-ngp's initialisation: uniform in [-1e-4, 1e-4].
  std::vector<float> initial_table(unsigned seed) const;

  // points: [batch][3]; table: parameter_count(); encoded: [batch][layout.stride] (see HashGridLayout).
  void forward(gpu::Stream& stream, gpu::BufferRange points, gpu::BufferRange table, gpu::BufferRange encoded,
               std::uint32_t batch, HashGridLayout layout = {}) const;
  // grad_table += dL/dtable (zero it first for a fresh gradient); grad_points, when not empty,
  // receives (or, with accumulate_points, gets added) dL/dpoints.
  void backward(gpu::Stream& stream, gpu::BufferRange points, gpu::BufferRange table, gpu::BufferRange grad_encoded,
                gpu::BufferRange grad_table, gpu::BufferRange grad_points, std::uint32_t batch,
                bool accumulate_points, HashGridLayout layout = {}) const;

 private:
  HashGridLayout resolve(HashGridLayout layout) const;  // throws InputError when the encoding does not fit
  HashGridConfig config_;
};

}  // namespace nf::nn
