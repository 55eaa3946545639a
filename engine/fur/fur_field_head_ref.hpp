#pragma once
// CPU reference of the fur field's head (one template for float and double): the fur MLP's output
// rows split into the strand prior's latent rows and each strand's rendered confidence. The GPU
// kernels (shaders/fur/fur_field_head_{fwd,bwd}.comp) are checked against it, and it against
// finite differences.
//
// Per strand s, the MLP row y_s ([in_stride] floats) holds the latent z_s in columns 0..latent-1
// and the confidence's raw value q_s in column `latent`. The head writes
//     latent row s = z_s (padded to latent_stride with zeros: the decoder's input layout)
//     c_s = softplus(q_s) = max(q, 0) + log(1 + exp(-|q|))   (positive, no overflow)
// and gives c_s to each of the strand's S segments (the rasteriser's per-segment confidence: the
// paper's tau is this, composited). Adjoint:
//     dL/dz_s = dL/d(latent row s),  dL/dq_s = sigmoid(q_s) sum_j dL/dc_{s,j},  other columns 0.
#include <cmath>
#include <cstdint>
#include <vector>

namespace nf::fur {

struct FurHeadShape {
  std::uint32_t strands = 0;
  std::uint32_t latent = 64;
  std::uint32_t in_stride = 68;      // the fur MLP's output row (>= latent + 1)
  std::uint32_t latent_stride = 64;  // the decoder's input row (>= latent)
  std::uint32_t segments = 99;       // confidences per strand
};

template <class T>
T softplus_ref(T q) {
  return std::max(q, T(0)) + std::log1p(std::exp(-std::abs(q)));
}

template <class T>
void fur_head_forward_ref(const std::vector<T>& rows, const FurHeadShape& shape, std::vector<T>& latents,
                          std::vector<T>& confidence) {
  latents.assign(std::size_t(shape.strands) * shape.latent_stride, T(0));
  confidence.assign(std::size_t(shape.strands) * shape.segments, T(0));
  for (std::uint32_t s = 0; s < shape.strands; ++s) {
    const T* y = &rows[std::size_t(s) * shape.in_stride];
    for (std::uint32_t j = 0; j < shape.latent; ++j) latents[std::size_t(s) * shape.latent_stride + j] = y[j];
    const T c = softplus_ref(y[shape.latent]);
    for (std::uint32_t j = 0; j < shape.segments; ++j) confidence[std::size_t(s) * shape.segments + j] = c;
  }
}

template <class T>
void fur_head_backward_ref(const std::vector<T>& rows, const FurHeadShape& shape, const std::vector<T>& grad_latents,
                           const std::vector<T>& grad_confidence, std::vector<T>& grad_rows) {
  grad_rows.assign(rows.size(), T(0));
  for (std::uint32_t s = 0; s < shape.strands; ++s) {
    T* g = &grad_rows[std::size_t(s) * shape.in_stride];
    for (std::uint32_t j = 0; j < shape.latent; ++j) g[j] = grad_latents[std::size_t(s) * shape.latent_stride + j];
    T sum = 0;
    for (std::uint32_t j = 0; j < shape.segments; ++j) sum += grad_confidence[std::size_t(s) * shape.segments + j];
    const T q = rows[std::size_t(s) * shape.in_stride + shape.latent];
    g[shape.latent] = sum / (T(1) + std::exp(-q));
  }
}

}  // namespace nf::fur
