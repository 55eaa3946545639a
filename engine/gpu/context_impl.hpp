#pragma once
// Private to engine/gpu: the Vulkan state behind Context, Buffer, Kernel and Stream.
#include <array>
#include <atomic>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "engine/gpu/buffer.hpp"
#include "engine/gpu/context.hpp"
#include "engine/gpu/kernel.hpp"
#include "engine/gpu/vk_common.hpp"

namespace nf::gpu {

struct RawBuffer::Handles {
  VkBuffer buffer = VK_NULL_HANDLE;
  VkDeviceMemory memory = VK_NULL_HANDLE;
  std::uint64_t allocation_bytes = 0;
  std::uint32_t memory_type = 0;  // its heap's count is lowered when it is freed
};

struct Kernel::Handles {
  VkDevice device = VK_NULL_HANDLE;
  VkShaderModule module = VK_NULL_HANDLE;
  VkPipeline pipeline = VK_NULL_HANDLE;
};

struct Context::Impl {
  Context* owner = nullptr;
  ContextOptions options;
  VkInstance instance = VK_NULL_HANDLE;
  VkDebugUtilsMessengerEXT messenger = VK_NULL_HANDLE;
  VkPhysicalDevice physical = VK_NULL_HANDLE;
  VkDevice device = VK_NULL_HANDLE;
  VkQueue queue = VK_NULL_HANDLE;
  std::mutex queue_mutex;  // vkQueueSubmit needs external synchronisation
  std::uint32_t queue_family = 0;
  VkCommandPool command_pool = VK_NULL_HANDLE;
  VkPipelineCache pipeline_cache = VK_NULL_HANDLE;

  // One descriptor-set layout shared by every kernel: `storage_slots` storage buffers at bindings
  // 0.., `uniform_slots` uniform buffers at kUniformBindingBase.., `texel_slots` uniform texel
  // buffers at kTexelBindingBase.., and one pipeline layout with a
  // push-constant range of `push_constant_bytes`.
  VkDescriptorSetLayout set_layout = VK_NULL_HANDLE;
  VkPipelineLayout pipeline_layout = VK_NULL_HANDLE;
  std::uint32_t storage_slots = 0;
  std::uint32_t uniform_slots = 0;
  std::uint32_t texel_slots = 0;
  std::uint32_t push_constant_bytes = 0;

  PFN_vkCmdPushDescriptorSetKHR push_descriptor = nullptr;
  PFN_vkSetDebugUtilsObjectNameEXT set_object_name = nullptr;

  VkPhysicalDeviceMemoryProperties memory_properties{};  // memory types are picked per buffer

  DeviceInfo info;
  DeviceTuning tuning;

  std::mutex kernels_mutex;
  std::map<std::string, std::unique_ptr<Kernel>> kernels;

  mutable std::mutex validation_mutex;
  std::vector<std::string> validation_messages;

  mutable std::mutex pass_mutex;
  std::map<std::string, PassTotal> pass_totals;

  std::atomic<std::uint64_t> submits{0};
  std::atomic<bool> device_lost{false};  // after VK_ERROR_DEVICE_LOST nothing more is submitted

  std::atomic<std::uint64_t> allocated_bytes{0};  // all heaps: what nf_gpu reports as its memory
  std::atomic<std::uint64_t> peak_bytes{0};
  // Per memory heap: a discrete GPU's device-local and host heaps are separate budgets.
  std::array<std::atomic<std::uint64_t>, VK_MAX_MEMORY_HEAPS> heap_bytes{};

  std::mutex scratch_mutex;
  std::multimap<std::uint64_t, std::unique_ptr<RawBuffer>> free_scratch;  // by capacity
  std::unique_ptr<RawBuffer> dummy;  // bound where a kernel's optional binding is unused

  void destroy();  // releases every Vulkan object; safe on a half-built context
  void name_object(VkObjectType type, std::uint64_t handle, const std::string& name) const;
  // Records `record` into a one-shot command buffer, submits it and waits.
  void run_immediate(const std::function<void(VkCommandBuffer)>& record);
  std::unique_ptr<RawBuffer> acquire_scratch(std::uint64_t bytes);
  void release_scratch(std::unique_ptr<RawBuffer> buffer);
  void note_allocation(std::uint32_t heap, std::int64_t delta);
};

// Builds the description of one physical device (no logical device needed).
DeviceInfo describe_device(VkPhysicalDevice device, std::uint32_t index);
// Fills the tuning and info.quirks from the driver-quirk table and the options' env switches.
void apply_quirks(DeviceInfo& info, DeviceTuning& tuning, const ContextOptions& options);

}  // namespace nf::gpu
