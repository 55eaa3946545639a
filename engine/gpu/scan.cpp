#include "engine/gpu/scan.hpp"

#include "engine/gpu/chunking.hpp"
#include "engine/gpu/kernel.hpp"

namespace nf::gpu {
namespace {

struct BlockSumsPush {
  std::uint32_t n;
};
struct ScanBlocksPush {
  std::uint32_t n, has_block_offsets, has_carry, has_total;
};

struct ScanKernels {
  const Kernel& block_sums;
  const Kernel& blocks;
  std::uint64_t block_elements;
};

ScanKernels kernels(Context& context, bool flags) {
  const std::uint32_t items = context.tuning().items_per_thread;
  // scan_blocks keeps WG*ITEMS words in shared memory plus a uvec4 per invocation.
  std::uint32_t wg = primitive_workgroup(context, 256);
  while (wg > context.info().limits.subgroup_size &&
         std::uint64_t(wg) * items * 4 + std::uint64_t(wg) * 16 + 64 > context.info().limits.max_compute_shared_memory)
    wg /= 2;
  const std::vector<SpecConstant> spec{{0, wg}, {1, items}};
  const std::string v = flags ? ":flags" : ":add";
  return {context.kernel("gpu/scan_block_sums" + v, spec), context.kernel("gpu/scan_blocks" + v, spec),
          std::uint64_t(wg) * items};
}

// Scans one range that fits a binding. `carry` (optional) is added to every output.
void scan_range(Stream& stream, bool flags, BufferRange input, BufferRange output, BufferRange total,
                BufferRange carry) {
  const std::uint64_t n = input.size / 4;
  if (n == 0) return;
  const ScanKernels k = kernels(stream.context(), flags);
  const std::uint64_t blocks = (n + k.block_elements - 1) / k.block_elements;
  const std::uint32_t has_carry = carry.size ? 1u : 0u, has_total = total.size ? 1u : 0u;
  if (blocks == 1) {
    stream.dispatch_groups(k.blocks, {input, output, BufferRange{input.buffer, 0, 0}, carry, total},
                           ScanBlocksPush{std::uint32_t(n), 0u, has_carry, has_total}, Elements(1));
    return;
  }
  const BufferRange sums = stream.scratch(blocks * 4, "scan block sums");
  const Elements groups_of_blocks(blocks * k.block_sums.local_size()[0]);  // one workgroup per block
  stream.dispatch(k.block_sums, {input, sums}, BlockSumsPush{std::uint32_t(n)}, groups_of_blocks);
  scan_range(stream, false, sums, sums, {}, {});  // block sums -> block offsets, in place
  stream.dispatch(k.blocks, {input, output, sums, carry, total}, ScanBlocksPush{std::uint32_t(n), 1u, has_carry, has_total},
                  groups_of_blocks);
}

void scan_any(Stream& stream, bool flags, BufferRange input, BufferRange output, BufferRange total) {
  Context& context = stream.context();
  const std::uint64_t n = input.size / 4;
  if (output.size / 4 < n) throw InternalError("exclusive_scan: output smaller than input");
  if (n == 0) {
    if (total.size) stream.fill(sub_range(total, 4, 0, 1), 0);
    return;
  }
  const std::uint64_t chunk = max_binding_elements(context, 4);
  if (n <= chunk) {
    scan_range(stream, flags, input, sub_range(output, 4, 0, n), total.size ? sub_range(total, 4, 0, 1) : total, {});
    return;
  }
  // Chunks in order, each starting from the running total of the previous ones.
  const BufferRange running = stream.scratch(4, "scan carry"), chunk_total = stream.scratch(4, "scan chunk total");
  for (std::uint64_t first = 0; first < n; first += chunk) {
    const std::uint64_t count = std::min(chunk, n - first);
    scan_range(stream, flags, sub_range(input, 4, first, count), sub_range(output, 4, first, count), chunk_total,
               first ? running : BufferRange{});
    stream.copy(chunk_total, running);
  }
  if (total.size) stream.copy(running, sub_range(total, 4, 0, 1));
}

}  // namespace

void exclusive_scan(Stream& stream, BufferRange input, BufferRange output, BufferRange total) {
  scan_any(stream, false, input, output, total);
}

void exclusive_scan_flags(Stream& stream, BufferRange flags, BufferRange output, BufferRange total) {
  scan_any(stream, true, flags, output, total);
}

}  // namespace nf::gpu
