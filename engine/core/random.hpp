#pragma once
// Counter-based randomness: splitmix64 (Steele, Lea and Flood 2014), the one definition every
// module's seeded draws go through, so that a (seed, step) pair names the same numbers everywhere.
#include <cstdint>

namespace nf {

// splitmix64's output function (Stafford's variant 13): a bijective 64-bit mix.
constexpr std::uint64_t mix64(std::uint64_t z) {
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}

inline constexpr std::uint64_t kGoldenGamma = 0x9E3779B97F4A7C15ull;  // splitmix64's increment

// The splitmix64 value of counter `z` (a stream's value at state z).
constexpr std::uint64_t splitmix64(std::uint64_t z) { return mix64(z + kGoldenGamma); }

// A splitmix64 stream: next() advances the state by the golden gamma and mixes it.
struct SplitMix64 {
  std::uint64_t state;
  std::uint64_t next() { return mix64(state += kGoldenGamma); }
  double uniform() { return double(next() >> 11) * (1.0 / 9007199254740992.0); }  // [0, 1)
};

}  // namespace nf
