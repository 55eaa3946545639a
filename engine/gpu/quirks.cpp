// The driver-quirk table: behaviour keyed by VkDriverId, plus the env switches that force fallback
// paths so CI exercises them on lavapipe.
#include "engine/gpu/context_impl.hpp"

namespace nf::gpu {
namespace {

struct Quirk {
  VkDriverId driver;
  const char* what;
  void (*apply)(DeviceTuning&);
};

// CPU implementations share one heap between host and "device": mapping device memory avoids a
// staging copy. Workgroup barriers are costly there (each switches between the invocations'
// coroutines), so every invocation does more work: 32 items measured 1.5x faster sorts than 8.
void cpu_device(DeviceTuning& t) {
  t.mapped_device_buffers = true;
  t.items_per_thread = 32;
}

// gallivm's loop limiter (LP_MAX_TGSI_LOOP_ITERATIONS) ends any loop, with the loops nested in it,
// after 65,535 iterations (docs/gpu-runtime.md, "Long divergent loops on lavapipe").
void loop_limiter(DeviceTuning& t) { t.loop_iterations = 65535; }

const Quirk kQuirks[] = {
    {VK_DRIVER_ID_MESA_LLVMPIPE, "lavapipe: CPU device, mapped buffers, 32 items per invocation", cpu_device},
    {VK_DRIVER_ID_MESA_LLVMPIPE, "lavapipe: loops end after 65,535 iterations", loop_limiter},
    {VK_DRIVER_ID_GOOGLE_SWIFTSHADER, "SwiftShader: CPU device, mapped buffers, 32 items per invocation", cpu_device},
};

}  // namespace

void apply_quirks(DeviceInfo& info, DeviceTuning& tuning, const ContextOptions& options) {
  tuning = DeviceTuning{};
  // Integrated GPUs share memory with the host as well.
  if (info.type == "integrated") tuning.mapped_device_buffers = true;
  for (const Quirk& q : kQuirks) {
    if (q.driver == static_cast<VkDriverId>(info.driver_id)) {
      q.apply(tuning);
      info.quirks.emplace_back(q.what);
    }
  }
  tuning.use_push_descriptors = info.features.push_descriptors;
  if (!info.features.push_descriptors) info.quirks.emplace_back("no VK_KHR_push_descriptor: descriptor pools");
  if (options.force_descriptor_pool) {
    tuning.use_push_descriptors = false;
    info.quirks.emplace_back("NF_NO_PUSH_DESCRIPTORS: descriptor pools forced");
  }
  if (options.force_staging) {
    tuning.mapped_device_buffers = false;
    info.quirks.emplace_back("NF_FORCE_STAGING: staging copies forced");
  }
  if (options.no_shared_float_atomics && info.features.float32_atomic_add_shared) {
    info.features.float32_atomic_add_shared = false;  // not enabled on the device either
    info.quirks.emplace_back("NF_NO_SHARED_FLOAT_ATOMICS: shared-memory float atomics off");
  }
  // Kernels size their tiles from this limit; a cap lets CI run the sizes of small-memory GPUs.
  if (options.shared_memory_cap && options.shared_memory_cap < info.limits.max_compute_shared_memory) {
    info.limits.max_compute_shared_memory = options.shared_memory_cap;
    info.quirks.emplace_back("NF_SHARED_MEMORY: " + std::to_string(options.shared_memory_cap) + " bytes of shared memory");
  }
}

}  // namespace nf::gpu
