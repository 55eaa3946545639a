#pragma once
// Losses on network outputs in the MLP layout. Shaders: shaders/nn/loss_*.comp.
#include <cstdint>

#include "engine/gpu/buffer.hpp"
#include "engine/gpu/stream.hpp"

namespace nf::nn {

// Mean squared error of the first `dims` columns of `prediction` ([batch][stride], stride a
// multiple of 4) against
// `target` ([batch][dims]): writes dL/dprediction into `grad` ([batch][stride]) and the loss
// into `loss` (one float).
void mse_loss(gpu::Stream& stream, gpu::BufferRange prediction, gpu::BufferRange target, gpu::BufferRange grad,
              gpu::BufferRange loss, std::uint32_t batch, std::uint32_t dims, std::uint32_t stride);

}  // namespace nf::nn
