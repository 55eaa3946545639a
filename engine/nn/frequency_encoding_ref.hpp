#pragma once
// CPU reference of the frequency encoding (see shaders/nn/frequency_encoding_fwd.comp for the row
// layout), one template for float and double. The float instantiation reduces modulo 2 pi the way
// the shader does; double uses std::sin/cos directly.
#include <cmath>
#include <cstdint>
#include <vector>

namespace nf::nn {

struct FrequencyEncodingConfig {
  std::uint32_t dims = 3;
  std::uint32_t frequencies = 10;
  bool include_input = true;
  std::uint32_t output_dim() const { return (include_input ? dims : 0) + 2 * dims * frequencies; }
  std::uint32_t output_stride() const { return (output_dim() + 3u) & ~3u; }
};

template <class T>
T reduce_two_pi(T t) {
  if constexpr (sizeof(T) == sizeof(float)) {
    const float k = std::floor(t * 0.15915494309189535f + 0.5f);
    return ((t - k * 6.25f) - k * 0.033203125f) - k * -1.7817820120692e-05f;
  } else {
    return t;
  }
}

// points: [batch][dims]; returns [batch][output_stride] with zero padding.
template <class T>
std::vector<T> frequency_encoding_forward_ref(const FrequencyEncodingConfig& c, const std::vector<T>& points,
                                              std::uint32_t batch) {
  const std::uint32_t stride = c.output_stride();
  std::vector<T> out(std::size_t(stride) * batch, T(0));
  for (std::uint32_t s = 0; s < batch; ++s) {
    T* row = &out[std::size_t(s) * stride];
    std::uint32_t i = 0;
    if (c.include_input)
      for (std::uint32_t d = 0; d < c.dims; ++d) row[i++] = points[std::size_t(s) * c.dims + d];
    for (std::uint32_t l = 0; l < c.frequencies; ++l) {
      for (std::uint32_t d = 0; d < c.dims; ++d)
        row[i + d] = std::sin(reduce_two_pi(std::ldexp(points[std::size_t(s) * c.dims + d], int(l))));
      for (std::uint32_t d = 0; d < c.dims; ++d)
        row[i + c.dims + d] = std::cos(reduce_two_pi(std::ldexp(points[std::size_t(s) * c.dims + d], int(l))));
      i += 2 * c.dims;
    }
  }
  return out;
}

// grad_out: [batch][output_stride]; returns dL/dpoints [batch][dims].
template <class T>
std::vector<T> frequency_encoding_backward_ref(const FrequencyEncodingConfig& c, const std::vector<T>& points,
                                               std::uint32_t batch, const std::vector<T>& grad_out) {
  const std::uint32_t stride = c.output_stride();
  std::vector<T> grad(points.size(), T(0));
  for (std::uint32_t s = 0; s < batch; ++s) {
    const T* g = &grad_out[std::size_t(s) * stride];
    const std::uint32_t base = c.include_input ? c.dims : 0;
    for (std::uint32_t d = 0; d < c.dims; ++d) {
      const T x = points[std::size_t(s) * c.dims + d];
      T acc = c.include_input ? g[d] : T(0);
      for (std::uint32_t l = 0; l < c.frequencies; ++l) {
        const T scale = std::ldexp(T(1), int(l));
        const T t = reduce_two_pi(x * scale);
        const std::uint32_t row = base + l * 2 * c.dims;
        acc += scale * (g[row + d] * std::cos(t) - g[row + c.dims + d] * std::sin(t));
      }
      grad[std::size_t(s) * c.dims + d] = acc;
    }
  }
  return grad;
}

}  // namespace nf::nn
