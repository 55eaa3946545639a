#pragma once
// The fur field's head on the GPU (forward and hand-written adjoint): the fur MLP's output rows to
// the strand prior's latent rows and the per-segment rendered confidence. Maths and layouts:
// fur_field_head_ref.hpp. Shaders: shaders/fur/fur_field_head_{fwd,bwd}.comp.
#include <span>
#include <vector>

#include "engine/fur/fur_field_head_ref.hpp"
#include "engine/gpu/buffer.hpp"
#include "engine/gpu/stream.hpp"

namespace nf::fur {

// InputError naming the field (strides, counts).
void validate(const FurHeadShape& shape);

void fur_head_forward(gpu::Stream& stream, const FurHeadShape& shape, gpu::BufferRange rows, gpu::BufferRange latents,
                      gpu::BufferRange confidence);
// grad_rows is overwritten (padding columns 0).
void fur_head_backward(gpu::Stream& stream, const FurHeadShape& shape, gpu::BufferRange rows, gpu::BufferRange grad_latents,
                       gpu::BufferRange grad_confidence, gpu::BufferRange grad_rows);

// Host conveniences; NaN/Inf refused naming the input.
struct FurHeadOutputs {
  std::vector<float> latents, confidence;
};
FurHeadOutputs fur_head(gpu::Context& context, const FurHeadShape& shape, std::span<const float> rows);
std::vector<float> fur_head_gradient(gpu::Context& context, const FurHeadShape& shape, std::span<const float> rows,
                                     std::span<const float> grad_latents, std::span<const float> grad_confidence);

}  // namespace nf::fur
