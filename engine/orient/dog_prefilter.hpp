#pragma once
// GPU difference-of-Gaussians prefilter of the Gabor orientation maps (filters and edge rule:
// gabor_bank.hpp; CPU twin: dog_prefilter_ref). Shader: shaders/orient/dog_prefilter.comp.
#include <algorithm>
#include <cstdint>

#include "engine/gpu/buffer.hpp"
#include "engine/gpu/stream.hpp"
#include "engine/orient/gabor_bank.hpp"

namespace nf::orient {

class DogPrefilter {
 public:
  DogPrefilter(gpu::Context& context, const GaborParams& params);
  // Rows of context each side that an output row depends on.
  std::uint32_t radius() const { return std::max(low_radius_, has_high_ ? high_radius_ : 0u); }
  // Records grey -> dog over a band of width x rows (all ranges width * rows floats; low and high
  // are intermediates).
  void record(gpu::Stream& stream, std::uint32_t width, std::uint32_t rows, gpu::BufferRange grey,
              gpu::BufferRange low, gpu::BufferRange high, gpu::BufferRange dog) const;

 private:
  std::uint32_t low_radius_ = 0, high_radius_ = 0;
  bool has_high_ = false;
  gpu::Buffer<float> taps_;
};

}  // namespace nf::orient
