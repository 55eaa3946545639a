// The Vulkan runtime: device choice, buffers and transfers, reflected kernels and the asserting
// dispatch, automatic barriers, timestamps, errors. ctest also runs this suite with the fallback
// paths forced (NF_NO_PUSH_DESCRIPTORS=1, NF_FORCE_STAGING=1) so CI exercises them on lavapipe.
#include <doctest/doctest.h>

#include <algorithm>
#include <array>
#include <cstdlib>
#include <numeric>
#include <string>
#include <vector>

#include "engine/core/error.hpp"
#include "engine/gpu/chunking.hpp"
#include "engine/gpu/kernel.hpp"
#include "engine/gpu/shader_registry.hpp"
#include "engine/gpu/stream.hpp"
#include "tests/support/gpu_test.hpp"

using namespace nf;
using namespace nf::gpu;

namespace {
struct CopyPush {
  std::uint32_t n;
};
struct WrongPush {
  std::uint32_t n, extra;
};
}  // namespace

TEST_CASE("the context describes its device and honours the forced fallbacks") {
  auto& ctx = test::context();
  const DeviceInfo& i = ctx.info();
  CHECK(!i.name.empty());
  CHECK(i.limits.max_storage_buffer_range > 0);
  CHECK(i.limits.max_push_constants_size >= 128);
  CHECK(i.limits.subgroup_size >= 1);
  CHECK(to_json(i)["limits"]["max_storage_buffer_range"] == i.limits.max_storage_buffer_range);
  if (const char* v = std::getenv("NF_NO_PUSH_DESCRIPTORS"); v && *v == '1') CHECK_FALSE(ctx.tuning().use_push_descriptors);
  if (const char* v = std::getenv("NF_FORCE_STAGING"); v && *v == '1') CHECK_FALSE(ctx.tuning().mapped_device_buffers);
  CHECK(ctx.validation_enabled() == (std::getenv("NF_VALIDATION") != nullptr));
}

TEST_CASE("NF_DEVICE selects by index and by name, and names the devices when nothing matches") {
  const auto devices = Context::enumerate_devices();
  REQUIRE(!devices.empty());
  ContextOptions by_index;
  by_index.device = std::to_string(devices.back().index);
  CHECK(Context(by_index).info().name == devices.back().name);
  ContextOptions by_name;
  by_name.device = devices.front().name.substr(0, 4);
  CHECK_NOTHROW(Context{by_name});
  ContextOptions none;
  none.device = "no-such-gpu-xyz";
  CHECK_THROWS_WITH_AS(Context{none}, doctest::Contains(devices.front().name.c_str()), UsageError);
}

TEST_CASE("NF_SHARED_MEMORY caps the shared memory kernels size their tiles by, and refuses nonsense") {
  ContextOptions capped;
  capped.shared_memory_cap = 16384;
  CHECK(Context(capped).info().limits.max_compute_shared_memory ==
        std::min<std::uint32_t>(16384, test::context().info().limits.max_compute_shared_memory));
  const char* before = std::getenv("NF_SHARED_MEMORY");
  const std::string saved = before ? before : "";
  setenv("NF_SHARED_MEMORY", "16384", 1);
  CHECK(ContextOptions::from_env().shared_memory_cap == 16384);
  for (const char* bad : {"1024", "16k", "-1"}) {
    setenv("NF_SHARED_MEMORY", bad, 1);
    CHECK_THROWS_WITH_AS(ContextOptions::from_env(), doctest::Contains("NF_SHARED_MEMORY"), InputError);
  }
  if (before) setenv("NF_SHARED_MEMORY", saved.c_str(), 1);
  else unsetenv("NF_SHARED_MEMORY");
}

TEST_CASE("buffers round-trip data, sub-ranges and fills, including empty buffers") {
  auto& ctx = test::context();
  const auto data = test::random_u32(10007, 1);
  Buffer<std::uint32_t> b(ctx, std::span<const std::uint32_t>(data), "round trip");
  CHECK(b.download() == data);
  CHECK(b.download(100, 5) == std::vector<std::uint32_t>(data.begin() + 100, data.begin() + 105));
  const std::vector<std::uint32_t> patch = {1, 2, 3};
  b.upload(patch, 10);
  CHECK(b.download(10, 3) == patch);
  b.fill_u32(7);
  CHECK(b.download() == std::vector<std::uint32_t>(10007, 7));
  Buffer<float> empty(ctx, 0, "empty");
  CHECK(empty.download().empty());
  CHECK_THROWS_AS(b.upload(patch, 10006), InternalError);
  CHECK_THROWS_AS(b.range(10000, 8), InternalError);
  CHECK(ctx.allocated_bytes() > 0);
  CHECK(ctx.peak_allocated_bytes() >= ctx.allocated_bytes());
}

TEST_CASE("memory is counted per heap: the heaps add up to the total, and a buffer's bytes return when it goes") {
  auto& ctx = test::context();
  const auto heaps_total = [&] {
    std::uint64_t sum = 0;
    for (std::uint32_t h = 0; h < 32; ++h) sum += ctx.allocated_bytes_in_heap(h);
    return sum;
  };
  CHECK(heaps_total() == ctx.allocated_bytes());
  const std::uint64_t before = ctx.allocated_bytes();
  std::vector<std::uint64_t> per_heap_before;
  for (std::uint32_t h = 0; h < 32; ++h) per_heap_before.push_back(ctx.allocated_bytes_in_heap(h));
  {
    RawBuffer b(ctx, 1 << 20, "counted");
    CHECK(ctx.allocated_bytes() >= before + (1 << 20));
    CHECK(heaps_total() == ctx.allocated_bytes());
    int grown = 0;
    for (std::uint32_t h = 0; h < 32; ++h) grown += ctx.allocated_bytes_in_heap(h) >= per_heap_before[h] + (1 << 20);
    CHECK(grown == 1);  // one heap holds it
  }
  CHECK(ctx.allocated_bytes() == before);
  CHECK(heaps_total() == before);
  for (std::uint32_t h = 0; h < 32; ++h) CHECK(ctx.allocated_bytes_in_heap(h) == per_heap_before[h]);  // freed from its own heap
  // A device-local buffer and a host-visible transfer (staging where the device needs it): every
  // heap's count comes back.
  {
    const std::vector<float> values(4096, 1.5f);
    Buffer<float> b(ctx, std::span<const float>(values), "counted upload");
    CHECK(b.download() == values);
  }
  for (std::uint32_t h = 0; h < 32; ++h) CHECK(ctx.allocated_bytes_in_heap(h) == per_heap_before[h]);
}

TEST_CASE("an allocation larger than the device allows is refused with a clear error") {
  auto& ctx = test::context();
  const std::uint64_t too_big = ctx.info().limits.max_allocation_size + 16;
  CHECK_THROWS_WITH_AS(RawBuffer(ctx, too_big, "huge"), doctest::Contains("'huge'"), DeviceError);
}

TEST_CASE("kernels are reflected from their embedded SPIR-V") {
  auto& ctx = test::context();
  const Kernel& k = ctx.kernel("bench/core_copy", {{0, 64}});
  CHECK(k.local_size()[0] == 64);
  CHECK(k.layout().push_constant_size == sizeof(CopyPush));
  REQUIRE(k.layout().bindings.size() == 2);
  CHECK(k.layout().bindings[0].read);
  CHECK_FALSE(k.layout().bindings[0].write);  // readonly
  CHECK_FALSE(k.layout().bindings[1].read);   // writeonly
  CHECK(k.layout().bindings[1].write);
  CHECK(&ctx.kernel("bench/core_copy", {{0, 64}}) == &k);  // cached
  CHECK(&ctx.kernel("bench/core_copy", {{0, 128}}) != &k);
  const auto names = shader_names();
  CHECK(std::find(names.begin(), names.end(), "gpu/reduce:sum_f32") != names.end());
  CHECK_THROWS_WITH_AS(ctx.kernel("gpu/no_such_kernel"), doctest::Contains("gpu/reduce"), InternalError);
  CHECK_THROWS_WITH_AS(ctx.kernel("bench/core_copy", {{5, 1}}), doctest::Contains("specialisation constant 5"),
                       InternalError);
  CHECK_THROWS_AS(ctx.kernel("bench/core_copy", {{0, 100000}}), DeviceError);
  // Uniform texel buffers (samplerBuffer) are read-only bindings from kTexelBindingBase on.
  const Kernel& texel = ctx.kernel("nn/mlp_weights_bwd");
  REQUIRE(texel.layout().bindings.size() == 3);
  CHECK(texel.layout().bindings[0].kind == BindingKind::storage);
  CHECK(texel.layout().bindings[1].kind == BindingKind::texel);
  CHECK(texel.layout().bindings[1].binding == kTexelBindingBase);
  CHECK(texel.layout().bindings[2].binding == kTexelBindingBase + 1);
  CHECK_FALSE(texel.layout().bindings[2].write);
  const std::uint32_t words[] = {0x12345678u, 0, 0, 0, 0};
  CHECK_THROWS_WITH_AS(reflect_spirv(words, "garbage"), doctest::Contains("garbage"), InternalError);
}

TEST_CASE("dispatch asserts binding count, push-constant size and binding ranges") {
  auto& ctx = test::context();
  const Kernel& k = ctx.kernel("bench/core_copy", {{0, 64}});
  Buffer<float> a(ctx, 64, "a"), b(ctx, 64, "b");
  Stream s(ctx);
  CHECK_THROWS_WITH_AS(s.dispatch(k, {a}, CopyPush{16}, Elements(16)), doctest::Contains("declares 2 buffer bindings"),
                       InternalError);
  CHECK_THROWS_WITH_AS(s.dispatch(k, {a, b}, WrongPush{16, 0}, Elements(16)),
                       doctest::Contains("declares 4 bytes of push constants"), InternalError);
  // A range that reaches past its buffer (built without the checked range() helper).
  const BufferRange past_end{&a, 64 * 4 - 16, 32};
  CHECK_THROWS_WITH_AS(s.dispatch(k, {past_end, b}, CopyPush{1}, Elements(1)), doctest::Contains("lies outside"),
                       InternalError);
  CHECK_THROWS_WITH_AS(s.copy(past_end, b.range(0, 8)), doctest::Contains("lies outside"), InternalError);
  CHECK_THROWS_WITH_AS(s.fill(past_end, 0), doctest::Contains("lies outside"), InternalError);
  CHECK_THROWS_WITH_AS(require_bytes(a.range(0, 4), 32, "probe"), doctest::Contains("probe: range of 16 bytes"),
                       InternalError);
  // A texel-buffer range is read as whole RGBA32F texels (a push block of the kernel's size).
  const Kernel& texel = ctx.kernel("nn/mlp_weights_bwd");
  REQUIRE(texel.layout().push_constant_size == sizeof(std::array<std::uint32_t, 8>));
  CHECK_THROWS_WITH_AS(s.dispatch(texel, {a, b.range(0, 3), b}, std::array<std::uint32_t, 8>{}, Elements(1)),
                       doctest::Contains("not a whole number of vec4 texels"), InternalError);
  const std::uint64_t range = ctx.info().limits.max_storage_buffer_range;
  if (range + 64 <= ctx.info().limits.max_allocation_size) {
    RawBuffer big(ctx, range + 64, "bigger than a binding");
    CHECK_THROWS_WITH_AS(s.dispatch(k, {big.whole(), b}, CopyPush{16}, Elements(16)),
                         doctest::Contains("maxStorageBufferRange"), DeviceError);
  }
  s.submit_and_wait();
}

TEST_CASE("chains of dependent dispatches get their barriers; independent ones run without") {
  auto& ctx = test::context();
  const Kernel& copy = ctx.kernel("bench/core_copy", {{0, 64}});
  const std::uint32_t n = 4096;  // vec4s
  std::vector<float> src(n * 4);
  std::iota(src.begin(), src.end(), 0.f);
  Buffer<float> a(ctx, std::span<const float>(src), "a"), b(ctx, n * 4, "b"), c(ctx, n * 4, "c");
  Stream s(ctx);
  for (int round = 0; round < 20; ++round) {  // a -> b -> c -> a ... read-after-write each time
    s.dispatch(copy, {a, b}, CopyPush{n}, Elements(n));
    s.dispatch(copy, {b, c}, CopyPush{n}, Elements(n));
    s.fill(a.whole(), 0);  // write-after-read on a
    s.dispatch(copy, {c, a}, CopyPush{n}, Elements(n));
  }
  CHECK(s.pending_dispatches() == 60);
  s.submit_and_wait();
  CHECK(a.download() == src);
  CHECK(s.pending_dispatches() == 0);
}

TEST_CASE("more groups than one dimension allows fold into y and every element is covered") {
  auto& ctx = test::context();
  const Kernel& copy = ctx.kernel("bench/core_copy", {{0, 1}});  // one invocation per group
  const std::uint32_t n = ctx.info().limits.max_workgroup_count[0] + 1000;
  // GPUs allow 2^31 - 1 groups along x: a vec4 per group would need 34 GB, past any binding.
  if (std::uint64_t(n) * 16 > ctx.info().limits.max_storage_buffer_range) {
    MESSAGE("skipped: " << n << " groups of one vec4 exceed this device's binding range");
    return;
  }
  std::vector<float> src(std::size_t(n) * 4);
  for (std::size_t i = 0; i < src.size(); ++i) src[i] = float(i % 1000);
  Buffer<float> a(ctx, std::span<const float>(src), "a"), b(ctx, src.size(), "b");
  Stream s(ctx);
  s.dispatch(copy, {a, b}, CopyPush{n}, Elements(n));
  s.submit_and_wait();
  CHECK(b.download() == src);
}

TEST_CASE("passes are timed on devices with timestamps and misuse of passes is reported") {
  auto& ctx = test::context();
  const Kernel& copy = ctx.kernel("bench/core_copy", {{0, 64}});
  Buffer<float> a(ctx, 1 << 16, "a"), b(ctx, 1 << 16, "b");
  Stream s(ctx);
  {
    ScopedPass pass(s, "test/copy");
    s.dispatch(copy, {a, b}, CopyPush{1 << 14}, Elements(1 << 14));
  }
  s.submit_and_wait();
  if (ctx.info().features.timestamps) {
    REQUIRE(s.last_pass_times().size() == 1);
    CHECK(s.last_pass_times()[0].name == "test/copy");
    CHECK(s.last_pass_times()[0].milliseconds >= 0);
    CHECK(ctx.pass_totals().count("test/copy") == 1);
  }
  CHECK_THROWS_AS(s.end_pass(), InternalError);
  s.begin_pass("outer");
  CHECK_THROWS_AS(s.begin_pass("inner"), InternalError);
  CHECK_THROWS_AS(s.submit_and_wait(), InternalError);
  s.end_pass();
  s.submit_and_wait();
}

TEST_CASE("chunk sizes respect the binding range and the offset alignment") {
  auto& ctx = test::context();
  const auto& l = ctx.info().limits;
  const std::uint64_t per = max_binding_elements(ctx, 4);
  CHECK(per * 4 <= l.max_storage_buffer_range);
  CHECK((per * 4) % l.min_storage_buffer_offset_alignment == 0);
  const std::uint64_t items = items_per_chunk(ctx, {1200, 1188, 2376});  // 100-point strands
  CHECK(items * 2376 <= l.max_storage_buffer_range);
  for (std::uint64_t b : {1200u, 1188u, 2376u}) CHECK((items * b) % l.min_storage_buffer_offset_alignment == 0);
}

TEST_CASE("the validation layer is live: a pipeline over the shared-memory limit is reported") {
  auto& ctx = test::context();
  if (!ctx.validation_enabled()) return;
  ctx.take_validation_messages();
  // 256 invocations x 64 items x 4 bytes of shared tile: far over any device's 32-48 KiB.
  try {
    ctx.kernel("gpu/scan_blocks:add", {{0, 256}, {1, 64}});
  } catch (const Error&) {
    // a driver may also refuse the pipeline outright; the layer must have spoken either way
  }
  const auto messages = ctx.take_validation_messages();
  REQUIRE(!messages.empty());
  CHECK(messages.front().find("maxComputeSharedMemorySize") != std::string::npos);
}
