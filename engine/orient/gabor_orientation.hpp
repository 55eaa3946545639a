#pragma once
// GPU Gabor filter bank: orientation and confidence per pixel from a DoG-filtered band of rows
// (maths: gabor_ref.hpp; filters and angle convention: gabor_bank.hpp).
// Shader: shaders/orient/gabor_orientation.comp.
#include <cstdint>

#include "engine/gpu/buffer.hpp"
#include "engine/gpu/stream.hpp"
#include "engine/orient/gabor_bank.hpp"

namespace nf::orient {

class GaborOrientationKernel {
 public:
  // Uploads the bank's weights (float) in the kernel's layout. pixels_per_invocation: 0 = by device.
  GaborOrientationKernel(gpu::Context& context, const GaborBank& bank, std::uint32_t pixels_per_invocation = 0);
  std::uint32_t radius() const { return apron_; }

  struct Band {
    std::uint32_t width = 0;
    std::uint32_t rows = 0;       // rows of `dog`
    std::uint32_t row_first = 0;  // row of `dog` where the output starts
    std::uint32_t out_rows = 0;
  };
  // dog: width * rows floats; mask: empty range, or width * out_rows bytes packed 4 per uint32
  // (nonzero = inside); orientation, confidence: width * out_rows floats.
  void record(gpu::Stream& stream, const Band& band, gpu::BufferRange dog, gpu::BufferRange mask,
              gpu::BufferRange orientation, gpu::BufferRange confidence) const;

 private:
  gpu::Context* context_;
  std::uint32_t pixels_ = 1, apron_ = 0, taps4_ = 0, orientations_ = 0;
  bool uniform_weights_ = false;  // the bank fits one uniform-buffer binding
  float bin_ = 0, inv_distance2_sum_ = 0;
  gpu::Buffer<std::int32_t> offsets_;
  gpu::Buffer<float> weights_;
};

}  // namespace nf::orient
