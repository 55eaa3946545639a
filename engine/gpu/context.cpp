#include "engine/gpu/context.hpp"

#include <algorithm>
#include <cctype>
#include <cstdlib>
#include <cstring>
#include <tuple>

#if defined(__has_feature)
#if __has_feature(address_sanitizer)
#define NF_ASAN_BUILD 1
#include <dlfcn.h>
#include <link.h>
#endif
#endif

#include "engine/core/error.hpp"
#include "engine/core/text.hpp"
#include "engine/core/log.hpp"
#include "engine/gpu/context_impl.hpp"
#include "engine/gpu/shader_registry.hpp"

namespace nf::gpu {
namespace {

constexpr const char* kValidationLayer = "VK_LAYER_KHRONOS_validation";
constexpr const char* kNoDeviceAdvice =
    "no Vulkan device found. nf_gpu needs a Vulkan 1.2 driver: on Debian install lavapipe (CPU) with "
    "'apt-get install mesa-vulkan-drivers', or your GPU vendor's Vulkan driver";

bool env_flag(const char* name) {
  const char* v = std::getenv(name);
  return v && *v && std::strcmp(v, "0") != 0;
}

VKAPI_ATTR VkBool32 VKAPI_CALL on_validation_message(VkDebugUtilsMessageSeverityFlagBitsEXT severity,
                                                     VkDebugUtilsMessageTypeFlagsEXT,
                                                     const VkDebugUtilsMessengerCallbackDataEXT* data, void* user) {
  auto* impl = static_cast<Context::Impl*>(user);
  std::string text = (severity & VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT) ? "validation error: " : "validation warning: ";
  text += data->pMessage ? data->pMessage : "(no message)";
  {
    std::lock_guard lock(impl->validation_mutex);
    impl->validation_messages.push_back(text);
  }
  log::error(text);
  return VK_FALSE;
}

bool instance_has_layer(const char* name) {
  std::uint32_t count = 0;
  vkEnumerateInstanceLayerProperties(&count, nullptr);
  std::vector<VkLayerProperties> layers(count);
  vkEnumerateInstanceLayerProperties(&count, layers.data());
  for (const auto& l : layers)
    if (!std::strcmp(l.layerName, name)) return true;
  return false;
}

bool instance_has_extension(const char* name) {
  std::uint32_t count = 0;
  vkEnumerateInstanceExtensionProperties(nullptr, &count, nullptr);
  std::vector<VkExtensionProperties> extensions(count);
  vkEnumerateInstanceExtensionProperties(nullptr, &count, extensions.data());
  for (const auto& e : extensions)
    if (!std::strcmp(e.extensionName, name)) return true;
  return false;
}

VkInstance create_instance(bool validation, bool debug_utils) {
  VkApplicationInfo app{VK_STRUCTURE_TYPE_APPLICATION_INFO};
  app.pApplicationName = "nf_gpu";
  app.pEngineName = "nf_gpu";
  app.apiVersion = VK_API_VERSION_1_2;
  std::vector<const char*> layers, extensions;
  if (validation) layers.push_back(kValidationLayer);
  if (debug_utils) extensions.push_back(VK_EXT_DEBUG_UTILS_EXTENSION_NAME);
  VkInstanceCreateInfo info{VK_STRUCTURE_TYPE_INSTANCE_CREATE_INFO};
  info.pApplicationInfo = &app;
  info.enabledLayerCount = std::uint32_t(layers.size());
  info.ppEnabledLayerNames = layers.data();
  info.enabledExtensionCount = std::uint32_t(extensions.size());
  info.ppEnabledExtensionNames = extensions.data();
  VkInstance instance = VK_NULL_HANDLE;
  const VkResult r = vkCreateInstance(&info, nullptr, &instance);
  if (r == VK_ERROR_INCOMPATIBLE_DRIVER) throw DeviceError(kNoDeviceAdvice);
  NF_VK_CHECK(r);
  return instance;
}

// AddressSanitizer builds only: marks every shared object loaded now (the Vulkan drivers among
// them) as never to be unloaded. The loader dlcloses its drivers at vkDestroyInstance; a driver's
// once-only state (lavapipe in Mesa 22.3.6-1+deb12u2 keeps 128 bytes from a pthread_once
// initialiser in a static) then loses its last pointer and LeakSanitizer reports it as a leak from
// an unknown module. Kept loaded, that state stays reachable, while a real leak is still reported,
// with a stack that can be symbolised.
void keep_drivers_loaded_for_leak_checks() {
#if defined(NF_ASAN_BUILD)
  dl_iterate_phdr(
      [](dl_phdr_info* info, size_t, void*) -> int {
        if (info->dlpi_name != nullptr && info->dlpi_name[0] != '\0')
          if (void* handle = dlopen(info->dlpi_name, RTLD_NOW | RTLD_NOLOAD | RTLD_NODELETE)) dlclose(handle);
        return 0;
      },
      nullptr);
#endif
}

std::vector<VkPhysicalDevice> physical_devices(VkInstance instance) {
  std::uint32_t count = 0;
  NF_VK_CHECK(vkEnumeratePhysicalDevices(instance, &count, nullptr));
  keep_drivers_loaded_for_leak_checks();  // the drivers are loaded by now
  std::vector<VkPhysicalDevice> devices(count);
  NF_VK_CHECK(vkEnumeratePhysicalDevices(instance, &count, devices.data()));
  return devices;
}

int type_rank(const std::string& type) {
  if (type == "discrete") return 0;
  if (type == "integrated") return 1;
  if (type == "virtual") return 2;
  if (type == "cpu") return 3;
  return 4;
}

// NF_DEVICE picks by index or name; otherwise a discrete GPU first, then integrated, then lavapipe.
std::uint32_t choose_device(const std::vector<DeviceInfo>& devices, const std::string& selector) {
  std::vector<std::uint32_t> usable;
  for (const auto& d : devices) {
    const auto major = std::stoi(d.api_version), minor = std::stoi(d.api_version.substr(d.api_version.find('.') + 1));
    if (major > 1 || minor >= 2) usable.push_back(d.index);
  }
  if (!selector.empty()) {
    std::string names;
    for (const auto& d : devices) names += "\n  " + std::to_string(d.index) + ": " + d.name + " (" + d.type + ")";
    const bool numeric = std::all_of(selector.begin(), selector.end(), [](unsigned char c) { return std::isdigit(c); });
    for (const auto& d : devices) {
      if ((numeric && std::to_string(d.index) == selector) ||
          (!numeric && to_lower(d.name).find(to_lower(selector)) != std::string::npos)) {
        if (std::find(usable.begin(), usable.end(), d.index) == usable.end())
          throw DeviceError("NF_DEVICE='" + selector + "' selects '" + d.name + "', which supports only Vulkan " +
                            d.api_version + "; nf_gpu needs 1.2");
        return d.index;
      }
    }
    throw UsageError("NF_DEVICE='" + selector + "' matches no Vulkan device; devices are:" + names);
  }
  if (usable.empty()) throw DeviceError(kNoDeviceAdvice);
  return *std::min_element(usable.begin(), usable.end(), [&](std::uint32_t a, std::uint32_t b) {
    return type_rank(devices[a].type) < type_rank(devices[b].type);
  });
}

std::uint32_t find_memory_type(const VkPhysicalDeviceMemoryProperties& mp, VkMemoryPropertyFlags required) {
  for (std::uint32_t i = 0; i < mp.memoryTypeCount; ++i)
    if ((mp.memoryTypes[i].propertyFlags & required) == required) return i;
  return ~0u;
}

}  // namespace

ContextOptions ContextOptions::from_env() {
  ContextOptions o;
  if (const char* d = std::getenv("NF_DEVICE")) o.device = d;
  o.validation = env_flag("NF_VALIDATION");
  o.force_descriptor_pool = env_flag("NF_NO_PUSH_DESCRIPTORS");
  o.force_staging = env_flag("NF_FORCE_STAGING");
  o.no_shared_float_atomics = env_flag("NF_NO_SHARED_FLOAT_ATOMICS");
  if (const char* v = std::getenv("NF_SHARED_MEMORY"); v && *v) {
    char* end = nullptr;
    const unsigned long bytes = std::strtoul(v, &end, 10);
    if (*end != '\0' || bytes < 16384 || bytes > (1ul << 30))
      throw InputError(std::string("NF_SHARED_MEMORY is '") + v + "'; it must be a byte count of at least 16384");
    o.shared_memory_cap = std::uint32_t(bytes);
  }
  for (auto [name, field, scale] : {std::tuple{"NF_FAULT_DEVICE_LOST", &o.fault_device_lost_at, 1ull},
                                    {"NF_FAULT_DEVICE_MEMORY_MB", &o.fault_memory_bytes, 1ull << 20}})
    if (const char* v = std::getenv(name); v && *v) {
      char* end = nullptr;
      const unsigned long long n = std::strtoull(v, &end, 10);
      if (*end != '\0' || n == 0 || n > (1ull << 40)) throw InputError(std::string(name) + " is '" + v + "'; it must be a positive integer");
      *field = n * scale;
    }
  return o;
}

std::vector<DeviceInfo> Context::enumerate_devices() {
  VkInstance instance = create_instance(false, false);
  std::vector<DeviceInfo> infos;
  try {
    const auto devices = physical_devices(instance);
    for (std::uint32_t i = 0; i < devices.size(); ++i) infos.push_back(describe_device(devices[i], i));
  } catch (...) {
    vkDestroyInstance(instance, nullptr);
    throw;
  }
  vkDestroyInstance(instance, nullptr);
  return infos;
}

Context::Context(const ContextOptions& options) : impl_(std::make_unique<Impl>()) {
  Impl& m = *impl_;
  m.owner = this;
  m.options = options;
  if (options.validation && !instance_has_layer(kValidationLayer))
    throw DeviceError("NF_VALIDATION=1 needs the Khronos validation layer: apt-get install vulkan-validationlayers");
  const bool debug_utils = instance_has_extension(VK_EXT_DEBUG_UTILS_EXTENSION_NAME);
  m.instance = create_instance(options.validation, debug_utils);
  try {
    if (debug_utils) {
      m.set_object_name = reinterpret_cast<PFN_vkSetDebugUtilsObjectNameEXT>(
          vkGetInstanceProcAddr(m.instance, "vkSetDebugUtilsObjectNameEXT"));
    }
    if (options.validation && debug_utils) {
      VkDebugUtilsMessengerCreateInfoEXT info{VK_STRUCTURE_TYPE_DEBUG_UTILS_MESSENGER_CREATE_INFO_EXT};
      info.messageSeverity = VK_DEBUG_UTILS_MESSAGE_SEVERITY_WARNING_BIT_EXT | VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT;
      info.messageType = VK_DEBUG_UTILS_MESSAGE_TYPE_VALIDATION_BIT_EXT;
      info.pfnUserCallback = on_validation_message;
      info.pUserData = &m;
      auto create = reinterpret_cast<PFN_vkCreateDebugUtilsMessengerEXT>(
          vkGetInstanceProcAddr(m.instance, "vkCreateDebugUtilsMessengerEXT"));
      NF_VK_CHECK(create(m.instance, &info, nullptr, &m.messenger));
    }

    const auto devices = physical_devices(m.instance);
    if (devices.empty()) throw DeviceError(kNoDeviceAdvice);
    std::vector<DeviceInfo> infos;
    for (std::uint32_t i = 0; i < devices.size(); ++i) infos.push_back(describe_device(devices[i], i));
    const std::uint32_t chosen = choose_device(infos, options.device);
    m.physical = devices[chosen];
    m.info = infos[chosen];
    apply_quirks(m.info, m.tuning, options);

    // A queue family with compute.
    std::uint32_t family_count = 0;
    vkGetPhysicalDeviceQueueFamilyProperties(m.physical, &family_count, nullptr);
    std::vector<VkQueueFamilyProperties> families(family_count);
    vkGetPhysicalDeviceQueueFamilyProperties(m.physical, &family_count, families.data());
    m.queue_family = ~0u;
    for (std::uint32_t i = 0; i < family_count && m.queue_family == ~0u; ++i)
      if (families[i].queueFlags & VK_QUEUE_COMPUTE_BIT) m.queue_family = i;
    if (m.queue_family == ~0u) throw DeviceError("device '" + m.info.name + "' has no compute queue");
    if (families[m.queue_family].timestampValidBits == 0) m.info.features.timestamps = false;

    // Enable exactly the optional features the kernels may use and the device has.
    const DeviceFeatures& f = m.info.features;
    VkPhysicalDeviceShaderAtomicFloatFeaturesEXT atomic_float{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_SHADER_ATOMIC_FLOAT_FEATURES_EXT};
    atomic_float.shaderBufferFloat32Atomics = f.float32_atomic_add_buffer;
    atomic_float.shaderBufferFloat32AtomicAdd = f.float32_atomic_add_buffer;
    atomic_float.shaderSharedFloat32Atomics = f.float32_atomic_add_shared;
    atomic_float.shaderSharedFloat32AtomicAdd = f.float32_atomic_add_shared;
    VkPhysicalDeviceVulkan12Features f12{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_2_FEATURES};
    f12.shaderFloat16 = f.float16;
    VkPhysicalDeviceVulkan11Features f11{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_1_FEATURES};
    f11.pNext = &f12;
    VkPhysicalDeviceFeatures2 features{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_FEATURES_2, &f11};
    features.features.shaderInt64 = f.int64;
    std::vector<const char*> extensions;
    if (f.float32_atomic_add_buffer || f.float32_atomic_add_shared) {
      extensions.push_back(VK_EXT_SHADER_ATOMIC_FLOAT_EXTENSION_NAME);
      f12.pNext = &atomic_float;
    }
    if (m.tuning.use_push_descriptors) extensions.push_back(VK_KHR_PUSH_DESCRIPTOR_EXTENSION_NAME);

    const float priority = 1.0f;
    VkDeviceQueueCreateInfo queue_info{VK_STRUCTURE_TYPE_DEVICE_QUEUE_CREATE_INFO};
    queue_info.queueFamilyIndex = m.queue_family;
    queue_info.queueCount = 1;
    queue_info.pQueuePriorities = &priority;
    VkDeviceCreateInfo device_info{VK_STRUCTURE_TYPE_DEVICE_CREATE_INFO, &features};
    device_info.queueCreateInfoCount = 1;
    device_info.pQueueCreateInfos = &queue_info;
    device_info.enabledExtensionCount = std::uint32_t(extensions.size());
    device_info.ppEnabledExtensionNames = extensions.data();
    NF_VK_CHECK(vkCreateDevice(m.physical, &device_info, nullptr, &m.device));
    vkGetDeviceQueue(m.device, m.queue_family, 0, &m.queue);

    VkCommandPoolCreateInfo pool_info{VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO};
    pool_info.flags = VK_COMMAND_POOL_CREATE_RESET_COMMAND_BUFFER_BIT;
    pool_info.queueFamilyIndex = m.queue_family;
    NF_VK_CHECK(vkCreateCommandPool(m.device, &pool_info, nullptr, &m.command_pool));

    VkPipelineCacheCreateInfo cache_info{VK_STRUCTURE_TYPE_PIPELINE_CACHE_CREATE_INFO};
    NF_VK_CHECK(vkCreatePipelineCache(m.device, &cache_info, nullptr, &m.pipeline_cache));

    // The shared layout: as many storage-buffer slots as the device allows, up to 16.
    // Uniform buffers exist for data every lane reads at the same address (weights): on lavapipe a
    // uniform-buffer load at a uniform offset is one scalar load, a storage-buffer load is a loop
    // over the lanes.
    m.storage_slots = std::min<std::uint32_t>(kUniformBindingBase, m.info.limits.max_storage_buffers_per_stage);
    m.uniform_slots = std::min<std::uint32_t>(4, m.info.limits.max_uniform_buffers_per_stage);
    // Uniform texel buffers exist for data each lane reads at its own address: on lavapipe a texel
    // fetch is a straight-line gather, a storage-buffer load a per-lane loop with bounds checks.
    m.texel_slots = std::min<std::uint32_t>(4, m.info.limits.max_sampled_images_per_stage);
    std::vector<VkDescriptorSetLayoutBinding> bindings;
    for (std::uint32_t b = 0; b < m.storage_slots; ++b)
      bindings.push_back({b, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 1, VK_SHADER_STAGE_COMPUTE_BIT, nullptr});
    for (std::uint32_t b = 0; b < m.uniform_slots; ++b)
      bindings.push_back({kUniformBindingBase + b, VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER, 1, VK_SHADER_STAGE_COMPUTE_BIT, nullptr});
    for (std::uint32_t b = 0; b < m.texel_slots; ++b)
      bindings.push_back({kTexelBindingBase + b, VK_DESCRIPTOR_TYPE_UNIFORM_TEXEL_BUFFER, 1, VK_SHADER_STAGE_COMPUTE_BIT,
                          nullptr});
    VkDescriptorSetLayoutCreateInfo set_info{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_LAYOUT_CREATE_INFO};
    if (m.tuning.use_push_descriptors) set_info.flags = VK_DESCRIPTOR_SET_LAYOUT_CREATE_PUSH_DESCRIPTOR_BIT_KHR;
    set_info.bindingCount = std::uint32_t(bindings.size());
    set_info.pBindings = bindings.data();
    NF_VK_CHECK(vkCreateDescriptorSetLayout(m.device, &set_info, nullptr, &m.set_layout));
    m.push_constant_bytes = std::min<std::uint32_t>(128, m.info.limits.max_push_constants_size);
    VkPushConstantRange push_range{VK_SHADER_STAGE_COMPUTE_BIT, 0, m.push_constant_bytes};
    VkPipelineLayoutCreateInfo layout_info{VK_STRUCTURE_TYPE_PIPELINE_LAYOUT_CREATE_INFO};
    layout_info.setLayoutCount = 1;
    layout_info.pSetLayouts = &m.set_layout;
    layout_info.pushConstantRangeCount = 1;
    layout_info.pPushConstantRanges = &push_range;
    NF_VK_CHECK(vkCreatePipelineLayout(m.device, &layout_info, nullptr, &m.pipeline_layout));
    if (m.tuning.use_push_descriptors) {
      m.push_descriptor = reinterpret_cast<PFN_vkCmdPushDescriptorSetKHR>(
          vkGetDeviceProcAddr(m.device, "vkCmdPushDescriptorSetKHR"));
      if (!m.push_descriptor) throw DeviceError("vkCmdPushDescriptorSetKHR missing though the extension is enabled");
    }

    vkGetPhysicalDeviceMemoryProperties(m.physical, &m.memory_properties);
    const auto host = VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT;
    if (find_memory_type(m.memory_properties, host) == ~0u)
      throw DeviceError("device '" + m.info.name + "' has no host-visible coherent memory");

    m.dummy = std::make_unique<RawBuffer>(*this, 256, "unused binding");
  } catch (...) {
    m.destroy();
    throw;
  }
  log::debug("device: ", m.info.name, " (", m.info.driver, ")");
}

Context::~Context() {
  if (impl_) impl_->destroy();
}

void Context::Impl::destroy() {
  if (device) vkDeviceWaitIdle(device);
  free_scratch.clear();
  dummy.reset();
  kernels.clear();
  if (pipeline_layout) vkDestroyPipelineLayout(device, pipeline_layout, nullptr);
  if (set_layout) vkDestroyDescriptorSetLayout(device, set_layout, nullptr);
  if (pipeline_cache) vkDestroyPipelineCache(device, pipeline_cache, nullptr);
  if (command_pool) vkDestroyCommandPool(device, command_pool, nullptr);
  if (device) vkDestroyDevice(device, nullptr);
  if (messenger) {
    auto destroy_messenger = reinterpret_cast<PFN_vkDestroyDebugUtilsMessengerEXT>(
        vkGetInstanceProcAddr(instance, "vkDestroyDebugUtilsMessengerEXT"));
    destroy_messenger(instance, messenger, nullptr);
  }
  if (instance) vkDestroyInstance(instance, nullptr);
  pipeline_layout = VK_NULL_HANDLE;
  set_layout = VK_NULL_HANDLE;
  pipeline_cache = VK_NULL_HANDLE;
  command_pool = VK_NULL_HANDLE;
  device = VK_NULL_HANDLE;
  messenger = VK_NULL_HANDLE;
  instance = VK_NULL_HANDLE;
}

const DeviceInfo& Context::info() const { return impl_->info; }
const DeviceTuning& Context::tuning() const { return impl_->tuning; }
bool Context::validation_enabled() const { return impl_->options.validation; }

std::vector<std::string> Context::take_validation_messages() {
  std::lock_guard lock(impl_->validation_mutex);
  return std::exchange(impl_->validation_messages, {});
}

std::map<std::string, PassTotal> Context::pass_totals() const {
  std::lock_guard lock(impl_->pass_mutex);
  return impl_->pass_totals;
}

void Context::reset_pass_totals() {
  std::lock_guard lock(impl_->pass_mutex);
  impl_->pass_totals.clear();
}

std::uint64_t Context::allocated_bytes() const { return impl_->allocated_bytes.load(); }
std::uint64_t Context::peak_allocated_bytes() const { return impl_->peak_bytes.load(); }
std::uint64_t Context::allocated_bytes_in_heap(std::uint32_t heap) const {
  return heap < impl_->heap_bytes.size() ? impl_->heap_bytes[heap].load() : 0;
}

void Context::Impl::name_object(VkObjectType type, std::uint64_t handle, const std::string& name) const {
  if (!set_object_name || name.empty()) return;
  VkDebugUtilsObjectNameInfoEXT name_info{VK_STRUCTURE_TYPE_DEBUG_UTILS_OBJECT_NAME_INFO_EXT};
  name_info.objectType = type;
  name_info.objectHandle = handle;
  name_info.pObjectName = name.c_str();
  set_object_name(device, &name_info);
}

void Context::Impl::run_immediate(const std::function<void(VkCommandBuffer)>& record) {
  VkCommandBufferAllocateInfo alloc{VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO};
  alloc.commandPool = command_pool;
  alloc.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
  alloc.commandBufferCount = 1;
  VkCommandBuffer cmd = VK_NULL_HANDLE;
  NF_VK_CHECK(vkAllocateCommandBuffers(device, &alloc, &cmd));
  VkFence fence = VK_NULL_HANDLE;
  try {
    VkCommandBufferBeginInfo begin{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
    begin.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
    NF_VK_CHECK(vkBeginCommandBuffer(cmd, &begin));
    record(cmd);
    VkMemoryBarrier to_host{VK_STRUCTURE_TYPE_MEMORY_BARRIER};
    to_host.srcAccessMask = VK_ACCESS_TRANSFER_WRITE_BIT;
    to_host.dstAccessMask = VK_ACCESS_HOST_READ_BIT;
    vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_PIPELINE_STAGE_HOST_BIT, 0, 1, &to_host, 0, nullptr,
                         0, nullptr);
    NF_VK_CHECK(vkEndCommandBuffer(cmd));
    VkFenceCreateInfo fence_info{VK_STRUCTURE_TYPE_FENCE_CREATE_INFO};
    NF_VK_CHECK(vkCreateFence(device, &fence_info, nullptr, &fence));
    VkSubmitInfo submit{VK_STRUCTURE_TYPE_SUBMIT_INFO};
    submit.commandBufferCount = 1;
    submit.pCommandBuffers = &cmd;
    {
      std::lock_guard lock(queue_mutex);
      NF_VK_CHECK(vkQueueSubmit(queue, 1, &submit, fence));
    }
    NF_VK_CHECK(vkWaitForFences(device, 1, &fence, VK_TRUE, ~0ull));
  } catch (...) {
    if (fence) vkDestroyFence(device, fence, nullptr);
    vkFreeCommandBuffers(device, command_pool, 1, &cmd);
    throw;
  }
  vkDestroyFence(device, fence, nullptr);
  vkFreeCommandBuffers(device, command_pool, 1, &cmd);
}

std::unique_ptr<RawBuffer> Context::Impl::acquire_scratch(std::uint64_t bytes) {
  // Pooled by power-of-two capacity so hot loops stop allocating after their first iteration.
  std::uint64_t capacity = 256;
  while (capacity < bytes) capacity *= 2;
  {
    std::lock_guard lock(scratch_mutex);
    const auto it = free_scratch.find(capacity);
    if (it != free_scratch.end()) {
      auto buffer = std::move(it->second);
      free_scratch.erase(it);
      return buffer;
    }
  }
  return std::make_unique<RawBuffer>(*owner, capacity, "scratch");
}

void Context::Impl::release_scratch(std::unique_ptr<RawBuffer> buffer) {
  std::lock_guard lock(scratch_mutex);
  free_scratch.emplace(buffer->bytes(), std::move(buffer));
}

void Context::Impl::note_allocation(std::uint32_t heap, std::int64_t delta) {
  heap_bytes[heap].fetch_add(std::uint64_t(delta));
  const std::uint64_t now = allocated_bytes.fetch_add(std::uint64_t(delta)) + std::uint64_t(delta);
  std::uint64_t peak = peak_bytes.load();
  while (now > peak && !peak_bytes.compare_exchange_weak(peak, now)) {
  }
}

bool use_gpu_layout(const Context& context, const char* env) {
  if (const char* v = std::getenv(env); v && *v) {
    if (std::strcmp(v, "0") != 0 && std::strcmp(v, "1") != 0)
      throw InputError(std::string(env) + " is '" + v + "'; use 0 or 1");
    if (std::strcmp(v, "1") == 0) return true;
  }
  return !context.info().is_cpu();
}

}  // namespace nf::gpu
