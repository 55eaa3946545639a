#include "engine/gpu/reduce.hpp"

#include "engine/gpu/chunking.hpp"
#include "engine/gpu/kernel.hpp"

namespace nf::gpu {
namespace {

struct ReducePush {
  std::uint32_t n, per_group, out_offset;
};

constexpr std::uint32_t kMaxGroups = 1024;  // partials per chunk; the final pass is one workgroup

std::string variant(ReduceOp op, ScalarType type) {
  const char* o = op == ReduceOp::Sum ? "sum" : op == ReduceOp::Min ? "min" : "max";
  const char* t = type == ScalarType::F32 ? "f32" : type == ScalarType::U32 ? "u32" : "i32";
  return std::string("gpu/reduce:") + o + "_" + t;
}

}  // namespace

void reduce(Stream& stream, ReduceOp op, ScalarType type, BufferRange input, BufferRange output) {
  Context& context = stream.context();
  const std::uint32_t wg = primitive_workgroup(context, 256);
  const Kernel& kernel = context.kernel(variant(op, type), {{0, wg}});
  const std::uint64_t n = input.size / 4;
  const std::uint64_t chunk = max_binding_elements(context, 4);
  const std::uint64_t chunks = std::max<std::uint64_t>(1, (n + chunk - 1) / chunk);
  const std::uint32_t per_thread = context.tuning().items_per_thread * 4;
  const BufferRange partials = stream.scratch(chunks * kMaxGroups * 4, "reduce partials");
  std::uint32_t slots = 0;
  for (std::uint64_t c = 0; c < chunks; ++c) {
    const std::uint64_t first = c * chunk, count = std::min(chunk, n - std::min(n, first));
    const std::uint64_t want = (count + std::uint64_t(wg) * per_thread - 1) / (std::uint64_t(wg) * per_thread);
    const std::uint32_t groups = std::uint32_t(std::clamp<std::uint64_t>(want, 1, kMaxGroups));
    const std::uint32_t per_group = std::uint32_t((count + groups - 1) / groups);
    const ReducePush push{std::uint32_t(count), std::max(per_group, 1u), slots};
    // Bind at least one element so an empty input still yields the identity from group 0.
    const BufferRange in = count ? sub_range(input, 4, first, count) : BufferRange{input.buffer, input.offset, 0};
    stream.dispatch_groups(kernel, {in, partials}, push, Elements(groups));
    slots += groups;
  }
  const ReducePush final_push{slots, slots, 0};
  stream.dispatch_groups(kernel, {sub_range(partials, 4, 0, slots), sub_range(output, 4, 0, 1)}, final_push,
                         Elements(1));
}

}  // namespace nf::gpu
