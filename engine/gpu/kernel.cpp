#include "engine/gpu/kernel.hpp"

#include <algorithm>

#include "engine/core/error.hpp"
#include "engine/gpu/context_impl.hpp"
#include "engine/gpu/shader_registry.hpp"

namespace nf::gpu {

Kernel::~Kernel() {
  if (!handles_) return;
  if (handles_->pipeline) vkDestroyPipeline(handles_->device, handles_->pipeline, nullptr);
  if (handles_->module) vkDestroyShaderModule(handles_->device, handles_->module, nullptr);
  delete handles_;
}

const Kernel& Context::kernel(const std::string& shader_name, const std::vector<SpecConstant>& spec) {
  Impl& m = *impl_;
  std::string key = shader_name;
  for (const auto& s : spec) key += "#" + std::to_string(s.id) + "=" + std::to_string(s.value);
  std::lock_guard lock(m.kernels_mutex);
  if (auto it = m.kernels.find(key); it != m.kernels.end()) return *it->second;

  const auto words = find_shader(shader_name);
  KernelLayout layout = reflect_spirv(words, shader_name);
  const DeviceInfo& d = m.info;
  const auto count_kind = [&](BindingKind kind) {
    return std::int64_t(std::count_if(layout.bindings.begin(), layout.bindings.end(),
                                      [kind](const BindingInfo& b) { return b.kind == kind; }));
  };
  const std::int64_t storages = count_kind(BindingKind::storage), uniforms = count_kind(BindingKind::uniform),
                     texels = count_kind(BindingKind::texel);
  if (storages > std::int64_t(m.storage_slots) || uniforms > std::int64_t(m.uniform_slots) ||
      texels > std::int64_t(m.texel_slots))
    throw DeviceError("kernel '" + shader_name + "' uses " + std::to_string(storages) + " storage, " +
                      std::to_string(uniforms) + " uniform and " + std::to_string(texels) +
                      " texel buffers; the shared layout on '" + d.name + "' has " + std::to_string(m.storage_slots) +
                      ", " + std::to_string(m.uniform_slots) + " and " + std::to_string(m.texel_slots));
  if (layout.push_constant_size > m.push_constant_bytes)
    throw DeviceError("kernel '" + shader_name + "' needs " + std::to_string(layout.push_constant_size) +
                      " bytes of push constants; device '" + d.name + "' allows " + std::to_string(m.push_constant_bytes));
  if (layout.uses_float32_atomic_add && !d.features.float32_atomic_add_buffer)
    throw DeviceError("kernel '" + shader_name + "' needs float atomic add (VK_EXT_shader_atomic_float), which '" +
                      d.name + "' lacks");
  if (layout.uses_float16 && !d.features.float16)
    throw DeviceError("kernel '" + shader_name + "' needs shaderFloat16, which '" + d.name + "' lacks");
  if (layout.uses_int64 && !d.features.int64)
    throw DeviceError("kernel '" + shader_name + "' needs shaderInt64, which '" + d.name + "' lacks");

  // Specialisation: every constant the module declares gets its default unless overridden.
  std::map<std::uint32_t, std::uint32_t> values = layout.spec_defaults;
  for (const auto& s : spec) {
    if (!values.count(s.id))
      throw InternalError("kernel '" + shader_name + "' has no specialisation constant " + std::to_string(s.id));
    values[s.id] = s.value;
  }
  std::array<std::uint32_t, 3> local = layout.local_size;
  for (int axis = 0; axis < 3; ++axis)
    if (layout.local_size_spec_id[axis] >= 0) local[axis] = values[std::uint32_t(layout.local_size_spec_id[axis])];
  const std::uint64_t invocations = std::uint64_t(local[0]) * local[1] * local[2];
  for (int axis = 0; axis < 3; ++axis)
    if (local[axis] == 0 || local[axis] > d.limits.max_workgroup_size[axis])
      throw DeviceError("kernel '" + shader_name + "': workgroup size " + std::to_string(local[axis]) + " on axis " +
                        std::to_string(axis) + " exceeds the device limit " +
                        std::to_string(d.limits.max_workgroup_size[axis]));
  if (invocations > d.limits.max_workgroup_invocations)
    throw DeviceError("kernel '" + shader_name + "': " + std::to_string(invocations) +
                      " invocations per workgroup exceed the device limit " +
                      std::to_string(d.limits.max_workgroup_invocations));

  std::vector<VkSpecializationMapEntry> entries;
  std::vector<std::uint32_t> data;
  for (const auto& [id, value] : values) {
    entries.push_back({id, std::uint32_t(data.size() * 4), 4});
    data.push_back(value);
  }
  VkSpecializationInfo spec_info{std::uint32_t(entries.size()), entries.data(), data.size() * 4, data.data()};

  auto* handles = new Kernel::Handles{m.device, VK_NULL_HANDLE, VK_NULL_HANDLE};
  try {
    VkShaderModuleCreateInfo module_info{VK_STRUCTURE_TYPE_SHADER_MODULE_CREATE_INFO};
    module_info.codeSize = words.size() * 4;
    module_info.pCode = words.data();
    NF_VK_CHECK(vkCreateShaderModule(m.device, &module_info, nullptr, &handles->module));
    VkComputePipelineCreateInfo pipeline_info{VK_STRUCTURE_TYPE_COMPUTE_PIPELINE_CREATE_INFO};
    pipeline_info.stage = {VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO};
    pipeline_info.stage.stage = VK_SHADER_STAGE_COMPUTE_BIT;
    pipeline_info.stage.module = handles->module;
    pipeline_info.stage.pName = "main";
    pipeline_info.stage.pSpecializationInfo = entries.empty() ? nullptr : &spec_info;
    pipeline_info.layout = m.pipeline_layout;
    NF_VK_CHECK(vkCreateComputePipelines(m.device, m.pipeline_cache, 1, &pipeline_info, nullptr, &handles->pipeline));
    m.name_object(VK_OBJECT_TYPE_PIPELINE, std::uint64_t(handles->pipeline), key);
  } catch (...) {
    if (handles->module) vkDestroyShaderModule(m.device, handles->module, nullptr);
    delete handles;
    throw;
  }
  auto kernel = std::make_unique<Kernel>(shader_name, std::move(layout), local, handles);
  const Kernel& ref = *kernel;
  m.kernels.emplace(key, std::move(kernel));
  return ref;
}

}  // namespace nf::gpu
