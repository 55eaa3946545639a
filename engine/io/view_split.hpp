#pragma once
// Which cameras are held out for scoring: every k-th (the k-th, 2k-th, ...), the same rule in
// every stage and in the bench, so that a stage's held-out views are never another's training
// views. k <= 1 holds none out (k = 1 would leave nothing to train on).
#include <cstdint>

namespace nf::io {

constexpr bool is_held_out(std::uint32_t camera, int hold_out_every) {
  return hold_out_every > 1 && camera % std::uint32_t(hold_out_every) == std::uint32_t(hold_out_every) - 1;
}

}  // namespace nf::io
