#pragma once
// What nf_gpu knows about a Vulkan device: identity, limits, features and the driver quirks applied.
// Plain data, no Vulkan types, so any module can read it.
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "engine/core/json.hpp"

namespace nf::gpu {

struct DeviceLimits {
  std::uint64_t max_storage_buffer_range = 0;
  std::uint64_t max_allocation_size = 0;
  std::uint64_t max_buffer_size = 0;
  std::uint64_t min_storage_buffer_offset_alignment = 0;
  std::uint32_t max_push_constants_size = 0;
  std::uint32_t max_compute_shared_memory = 0;
  std::array<std::uint32_t, 3> max_workgroup_count{};
  std::array<std::uint32_t, 3> max_workgroup_size{};
  std::uint32_t max_workgroup_invocations = 0;
  std::uint32_t max_storage_buffers_per_stage = 0;
  std::uint64_t max_uniform_buffer_range = 0;
  std::uint64_t min_uniform_buffer_offset_alignment = 0;
  std::uint32_t max_uniform_buffers_per_stage = 0;
  std::uint64_t max_texel_buffer_elements = 0;
  std::uint64_t min_texel_buffer_offset_alignment = 0;
  std::uint32_t max_sampled_images_per_stage = 0;  // uniform texel buffers count here
  std::uint32_t subgroup_size = 0;
  double timestamp_period_ns = 0;  // nanoseconds per timestamp tick
};

struct DeviceFeatures {
  bool float32_atomic_add_buffer = false;
  bool float32_atomic_add_shared = false;
  bool float16 = false;
  bool int64 = false;
  bool timestamps = false;
  bool push_descriptors = false;
  std::vector<std::string> subgroup_operations;  // "basic", "arithmetic", ...
};

struct DeviceInfo {
  std::uint32_t index = 0;         // position in the Vulkan enumeration (what NF_DEVICE=<index> picks)
  std::string name;
  std::string type;                // "discrete", "integrated", "virtual", "cpu", "other"
  std::string driver;              // driver family, from the driverID
  std::uint32_t driver_id = 0;     // VkDriverId
  std::string driver_info;         // version string reported by the driver
  std::string api_version;
  std::uint64_t device_memory_bytes = 0;  // largest device-local heap
  DeviceLimits limits;
  DeviceFeatures features;
  std::vector<std::string> quirks;  // driver-quirk table entries applied, with why
  bool is_cpu() const { return type == "cpu"; }
};

// How the engine drives this device; filled from the quirk table and env switches.
struct DeviceTuning {
  bool mapped_device_buffers = false;  // device memory is host-visible: upload/download by memcpy
  bool use_push_descriptors = true;    // else descriptor sets from a per-stream pool
  std::uint32_t items_per_thread = 4;  // work per invocation for memory-bound primitives
  // Iterations after which the driver ends a loop nest without an error (0: no such limit).
  // Kernels whose loops run with the data size split their work so it stays below this.
  std::uint32_t loop_iterations = 0;
};

json to_json(const DeviceInfo& info);

}  // namespace nf::gpu
