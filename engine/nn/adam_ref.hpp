#pragma once
// CPU reference of one AdamW step with clipping and the non-finite skip (see adam.hpp).
#include <cmath>
#include <cstdint>
#include <vector>

#include "engine/nn/adam.hpp"

namespace nf::nn {

template <class T>
struct AdamStateRef {
  std::vector<T> m, v;
  std::uint32_t taken = 0, skipped = 0;
};

template <class T>
void adam_step_ref(std::vector<T>& params, const std::vector<T>& grads, AdamStateRef<T>& s, const AdamConfig& c,
                   const std::vector<ParamGroup>& groups, T lr) {
  s.m.resize(params.size(), T(0));
  s.v.resize(params.size(), T(0));
  T squares = 0;
  bool bad = false;
  for (T g : grads) {
    if (!std::isfinite(g)) bad = true;
    else squares += g * g;
  }
  if (bad) {
    ++s.skipped;
    return;
  }
  ++s.taken;
  const T norm = std::sqrt(squares);
  const T clip = c.max_grad_norm > 0 && norm > T(c.max_grad_norm) ? T(c.max_grad_norm) / norm : T(1);
  const T t = T(s.taken);
  for (const ParamGroup& gr : groups)
    for (std::uint64_t i = gr.offset; i < gr.offset + gr.count; ++i) {
      const T g = grads[i] * clip;
      s.m[i] = T(c.beta1) * s.m[i] + (T(1) - T(c.beta1)) * g;
      s.v[i] = T(c.beta2) * s.v[i] + (T(1) - T(c.beta2)) * g * g;
      const T m_hat = s.m[i] / (T(1) - std::pow(T(c.beta1), t));
      const T v_hat = s.v[i] / (T(1) - std::pow(T(c.beta2), t));
      params[i] -= lr * T(gr.lr_scale) * (m_hat / (std::sqrt(v_hat) + T(c.eps)) + T(gr.weight_decay) * params[i]);
    }
}

}  // namespace nf::nn
