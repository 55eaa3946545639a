#pragma once
// Shared by the test suites: one Vulkan context per test process (validation on when ctest sets
// NF_VALIDATION=1), and deterministic random data.
#include <cstdint>
#include <random>
#include <vector>

#include "engine/gpu/context.hpp"

namespace nf::test {

gpu::Context& context();
bool context_created();

inline std::vector<std::uint32_t> random_u32(std::size_t n, std::uint32_t seed, std::uint32_t max = 0xffffffffu) {
  std::mt19937 rng(seed);
  std::uniform_int_distribution<std::uint32_t> dist(0, max);
  std::vector<std::uint32_t> v(n);
  for (auto& x : v) x = dist(rng);
  return v;
}

inline std::vector<float> random_f32(std::size_t n, std::uint32_t seed, float lo = -1.f, float hi = 1.f) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> dist(lo, hi);
  std::vector<float> v(n);
  for (auto& x : v) x = dist(rng);
  return v;
}

}  // namespace nf::test
