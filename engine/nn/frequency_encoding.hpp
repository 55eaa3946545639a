#pragma once
// GPU frequency encoding (NeRF positional encoding), forward and adjoint. Writes rows in the MLP
// layout (mlp_config.hpp): feed `encoded` straight into an Mlp whose input_dim is output_dim().
// Precision: arguments 2^l x are reduced modulo 2 pi in three parts, so |x| up to 1e3 with 10
// frequencies keeps float accuracy (tests/gradcheck); normalise inputs to [-1, 1] anyway.
#include "engine/gpu/buffer.hpp"
#include "engine/gpu/stream.hpp"
#include "engine/nn/frequency_encoding_ref.hpp"

namespace nf::nn {

class FrequencyEncoding {
 public:
  explicit FrequencyEncoding(const FrequencyEncodingConfig& config);
  const FrequencyEncodingConfig& config() const { return config_; }

  // points: [batch][dims]; encoded: [batch][output_stride].
  void forward(gpu::Stream& stream, gpu::BufferRange points, gpu::BufferRange encoded, std::uint32_t batch) const;
  // grad_points (+)= dL/dpoints from grad_encoded ([batch][output_stride]).
  void backward(gpu::Stream& stream, gpu::BufferRange points, gpu::BufferRange grad_encoded,
                gpu::BufferRange grad_points, std::uint32_t batch, bool accumulate) const;

 private:
  FrequencyEncodingConfig config_;
};

}  // namespace nf::nn
