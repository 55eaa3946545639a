#include "engine/gpu/device_info.hpp"

#include <cstring>

#include "engine/gpu/context_impl.hpp"

namespace nf::gpu {
namespace {

std::string type_name(VkPhysicalDeviceType type) {
  switch (type) {
    case VK_PHYSICAL_DEVICE_TYPE_DISCRETE_GPU: return "discrete";
    case VK_PHYSICAL_DEVICE_TYPE_INTEGRATED_GPU: return "integrated";
    case VK_PHYSICAL_DEVICE_TYPE_VIRTUAL_GPU: return "virtual";
    case VK_PHYSICAL_DEVICE_TYPE_CPU: return "cpu";
    default: return "other";
  }
}

bool has_extension(VkPhysicalDevice device, const char* name) {
  std::uint32_t count = 0;
  vkEnumerateDeviceExtensionProperties(device, nullptr, &count, nullptr);
  std::vector<VkExtensionProperties> extensions(count);
  vkEnumerateDeviceExtensionProperties(device, nullptr, &count, extensions.data());
  for (const auto& e : extensions)
    if (!std::strcmp(e.extensionName, name)) return true;
  return false;
}

}  // namespace

DeviceInfo describe_device(VkPhysicalDevice device, std::uint32_t index) {
  VkPhysicalDeviceSubgroupProperties subgroup{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_SUBGROUP_PROPERTIES};
  VkPhysicalDeviceVulkan12Properties props12{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_2_PROPERTIES};
  VkPhysicalDeviceMaintenance3Properties maint3{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_MAINTENANCE_3_PROPERTIES};
  subgroup.pNext = &props12;
  props12.pNext = &maint3;
  VkPhysicalDeviceProperties2 props{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_PROPERTIES_2, &subgroup};
  vkGetPhysicalDeviceProperties2(device, &props);
  const VkPhysicalDeviceLimits& l = props.properties.limits;

  DeviceInfo info;
  info.index = index;
  info.name = props.properties.deviceName;
  info.type = type_name(props.properties.deviceType);
  info.driver_id = props12.driverID;
  info.driver = detail::driver_name(props12.driverID);
  info.driver_info = props12.driverInfo;
  const std::uint32_t v = props.properties.apiVersion;
  info.api_version = std::to_string(VK_API_VERSION_MAJOR(v)) + "." + std::to_string(VK_API_VERSION_MINOR(v)) + "." +
                     std::to_string(VK_API_VERSION_PATCH(v));

  DeviceLimits& lim = info.limits;
  lim.max_storage_buffer_range = l.maxStorageBufferRange;
  lim.max_allocation_size = maint3.maxMemoryAllocationSize;
  lim.max_buffer_size = maint3.maxMemoryAllocationSize;  // maintenance4's maxBufferSize is optional
  lim.min_storage_buffer_offset_alignment = l.minStorageBufferOffsetAlignment;
  lim.max_push_constants_size = l.maxPushConstantsSize;
  lim.max_compute_shared_memory = l.maxComputeSharedMemorySize;
  for (int i = 0; i < 3; ++i) {
    lim.max_workgroup_count[i] = l.maxComputeWorkGroupCount[i];
    lim.max_workgroup_size[i] = l.maxComputeWorkGroupSize[i];
  }
  lim.max_workgroup_invocations = l.maxComputeWorkGroupInvocations;
  lim.max_storage_buffers_per_stage = l.maxPerStageDescriptorStorageBuffers;
  lim.max_uniform_buffer_range = l.maxUniformBufferRange;
  lim.min_uniform_buffer_offset_alignment = l.minUniformBufferOffsetAlignment;
  lim.max_uniform_buffers_per_stage = l.maxPerStageDescriptorUniformBuffers;
  lim.max_texel_buffer_elements = l.maxTexelBufferElements;
  lim.min_texel_buffer_offset_alignment = l.minTexelBufferOffsetAlignment;
  lim.max_sampled_images_per_stage = l.maxPerStageDescriptorSampledImages;
  lim.subgroup_size = subgroup.subgroupSize;
  lim.timestamp_period_ns = l.timestampPeriod;

  VkPhysicalDeviceShaderAtomicFloatFeaturesEXT atomic_float{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_SHADER_ATOMIC_FLOAT_FEATURES_EXT};
  VkPhysicalDeviceVulkan12Features f12{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_2_FEATURES};
  const bool has_atomic_float = has_extension(device, VK_EXT_SHADER_ATOMIC_FLOAT_EXTENSION_NAME);
  if (has_atomic_float) f12.pNext = &atomic_float;
  VkPhysicalDeviceFeatures2 features{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_FEATURES_2, &f12};
  vkGetPhysicalDeviceFeatures2(device, &features);

  DeviceFeatures& f = info.features;
  f.float32_atomic_add_buffer = has_atomic_float && atomic_float.shaderBufferFloat32AtomicAdd;
  f.float32_atomic_add_shared = has_atomic_float && atomic_float.shaderSharedFloat32AtomicAdd;
  f.float16 = f12.shaderFloat16;
  f.int64 = features.features.shaderInt64;
  f.push_descriptors = has_extension(device, VK_KHR_PUSH_DESCRIPTOR_EXTENSION_NAME);

  std::uint32_t family_count = 0;
  vkGetPhysicalDeviceQueueFamilyProperties(device, &family_count, nullptr);
  std::vector<VkQueueFamilyProperties> families(family_count);
  vkGetPhysicalDeviceQueueFamilyProperties(device, &family_count, families.data());
  for (const auto& q : families)
    if ((q.queueFlags & VK_QUEUE_COMPUTE_BIT) && q.timestampValidBits > 0) f.timestamps = true;

  const std::pair<VkSubgroupFeatureFlagBits, const char*> ops[] = {
      {VK_SUBGROUP_FEATURE_BASIC_BIT, "basic"},       {VK_SUBGROUP_FEATURE_VOTE_BIT, "vote"},
      {VK_SUBGROUP_FEATURE_ARITHMETIC_BIT, "arithmetic"}, {VK_SUBGROUP_FEATURE_BALLOT_BIT, "ballot"},
      {VK_SUBGROUP_FEATURE_SHUFFLE_BIT, "shuffle"},   {VK_SUBGROUP_FEATURE_SHUFFLE_RELATIVE_BIT, "shuffle_relative"},
      {VK_SUBGROUP_FEATURE_CLUSTERED_BIT, "clustered"}, {VK_SUBGROUP_FEATURE_QUAD_BIT, "quad"}};
  for (const auto& [bit, name] : ops)
    if ((subgroup.supportedOperations & bit) && (subgroup.supportedStages & VK_SHADER_STAGE_COMPUTE_BIT))
      f.subgroup_operations.emplace_back(name);

  VkPhysicalDeviceMemoryProperties memory;
  vkGetPhysicalDeviceMemoryProperties(device, &memory);
  for (std::uint32_t h = 0; h < memory.memoryHeapCount; ++h)
    if (memory.memoryHeaps[h].flags & VK_MEMORY_HEAP_DEVICE_LOCAL_BIT)
      info.device_memory_bytes = std::max<std::uint64_t>(info.device_memory_bytes, memory.memoryHeaps[h].size);
  return info;
}

json to_json(const DeviceInfo& info) {
  const DeviceLimits& l = info.limits;
  const DeviceFeatures& f = info.features;
  return json{
      {"index", info.index},
      {"name", info.name},
      {"type", info.type},
      {"driver", info.driver},
      {"driver_id", info.driver_id},
      {"driver_info", info.driver_info},
      {"api_version", info.api_version},
      {"device_memory_bytes", info.device_memory_bytes},
      {"limits",
       {{"max_storage_buffer_range", l.max_storage_buffer_range},
        {"max_allocation_size", l.max_allocation_size},
        {"min_storage_buffer_offset_alignment", l.min_storage_buffer_offset_alignment},
        {"max_push_constants_size", l.max_push_constants_size},
        {"max_compute_shared_memory", l.max_compute_shared_memory},
        {"max_workgroup_count", l.max_workgroup_count},
        {"max_workgroup_size", l.max_workgroup_size},
        {"max_workgroup_invocations", l.max_workgroup_invocations},
        {"max_storage_buffers_per_stage", l.max_storage_buffers_per_stage},
        {"max_uniform_buffer_range", l.max_uniform_buffer_range},
        {"min_uniform_buffer_offset_alignment", l.min_uniform_buffer_offset_alignment},
        {"max_texel_buffer_elements", l.max_texel_buffer_elements},
        {"min_texel_buffer_offset_alignment", l.min_texel_buffer_offset_alignment},
        {"subgroup_size", l.subgroup_size},
        {"timestamp_period_ns", l.timestamp_period_ns}}},
      {"features",
       {{"float32_atomic_add_buffer", f.float32_atomic_add_buffer},
        {"float32_atomic_add_shared", f.float32_atomic_add_shared},
        {"float16", f.float16},
        {"int64", f.int64},
        {"timestamps", f.timestamps},
        {"push_descriptors", f.push_descriptors},
        {"subgroup_operations", f.subgroup_operations}}},
      {"quirks", info.quirks},
  };
}

}  // namespace nf::gpu
