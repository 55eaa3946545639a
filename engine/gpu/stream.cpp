#include "engine/gpu/stream.hpp"

#include <algorithm>
#include <map>
#include <tuple>

#include "engine/core/error.hpp"
#include "engine/core/log.hpp"
#include "engine/gpu/context_impl.hpp"

namespace nf::gpu {
namespace {

constexpr std::uint32_t kMaxTimestamps = 1024;
constexpr std::uint64_t kWaitTimeoutNs = 600ull * 1000 * 1000 * 1000;
constexpr std::uint32_t kSetsPerPool = 256;

struct Access {
  VkBuffer buffer;
  std::uint64_t begin, end;
  bool write;
};

// A range must lie inside its buffer, or its descriptor would reach past the allocation.
// `describe` names the range; it is called only to write an error (dispatches are a hot path).
template <class Describe>
void check_inside(const BufferRange& r, const Describe& describe) {
  if (r.size && r.buffer && r.offset + r.size > r.buffer->bytes())
    throw InternalError(std::string(describe()) + ": range [" + std::to_string(r.offset) + ", " + std::to_string(r.offset + r.size) +
                        ") lies outside buffer '" + r.buffer->name() + "' of " + std::to_string(r.buffer->bytes()) +
                        " bytes");
}

struct OpenPass {
  std::string name;
  std::uint32_t begin_query;
  std::uint32_t end_query = ~0u;
};

}  // namespace

struct Stream::Impl {
  Context::Impl& m;
  VkCommandBuffer cmd = VK_NULL_HANDLE;
  VkFence fence = VK_NULL_HANDLE;
  VkQueryPool queries = VK_NULL_HANDLE;
  std::uint32_t queries_used = 0;
  bool pass_open = false;
  bool warned_queries = false;
  std::vector<OpenPass> passes;
  std::vector<PassTime> last_times;
  std::vector<Access> pending;  // accesses since the last barrier
  VkPipeline bound_pipeline = VK_NULL_HANDLE;
  std::vector<VkDescriptorPool> pools;  // fallback path only
  std::uint32_t sets_in_current_pool = kSetsPerPool;
  std::vector<std::unique_ptr<RawBuffer>> scratch;
  // Texel-buffer views of this recording, one per (buffer, offset, size); freed once it completed.
  std::map<std::tuple<VkBuffer, std::uint64_t, std::uint64_t>, VkBufferView> views;
  std::uint32_t dispatches = 0;
  std::vector<std::string> kernels;  // this recording's kernels in order (repeats folded), for errors
  bool in_flight = false;  // submitted and not yet known complete
  bool recording = false;

  explicit Impl(Context::Impl& impl) : m(impl) {}

  void begin_recording() {
    VkCommandBufferBeginInfo begin{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
    begin.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
    NF_VK_CHECK(vkBeginCommandBuffer(cmd, &begin));
    recording = true;
    if (queries) vkCmdResetQueryPool(cmd, queries, 0, kMaxTimestamps);
    queries_used = 0;
    passes.clear();
    pending.clear();
    bound_pipeline = VK_NULL_HANDLE;
    dispatches = 0;
    kernels.clear();
  }

  // What this recording ran, for a device error: its passes and its last kernels.
  std::string running() const {
    std::string out;
    for (const OpenPass& p : passes) out += (out.empty() ? "pass '" : ", pass '") + p.name + "'";
    if (!kernels.empty()) {
      out += out.empty() ? "kernels " : " (kernels ";
      const std::size_t first = kernels.size() > 6 ? kernels.size() - 6 : 0;
      if (first) out += "..., ";
      for (std::size_t k = first; k < kernels.size(); ++k) out += (k > first ? ", " : "") + kernels[k];
      if (!passes.empty()) out += ")";
    }
    return out.empty() ? "no recorded work" : out;
  }

  void full_barrier() {
    VkMemoryBarrier b{VK_STRUCTURE_TYPE_MEMORY_BARRIER};
    b.srcAccessMask = VK_ACCESS_SHADER_WRITE_BIT | VK_ACCESS_TRANSFER_WRITE_BIT;
    // Uniform-buffer reads are not covered by SHADER_READ: name them, or constant caches may
    // serve stale data after a storage write (e.g. transposed weights read as a uniform buffer).
    b.dstAccessMask = VK_ACCESS_SHADER_READ_BIT | VK_ACCESS_UNIFORM_READ_BIT | VK_ACCESS_SHADER_WRITE_BIT |
                      VK_ACCESS_TRANSFER_READ_BIT | VK_ACCESS_TRANSFER_WRITE_BIT;
    const VkPipelineStageFlags stages = VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT | VK_PIPELINE_STAGE_TRANSFER_BIT;
    vkCmdPipelineBarrier(cmd, stages, stages, 0, 1, &b, 0, nullptr, 0, nullptr);
    pending.clear();
  }

  // Inserts a barrier when any new access conflicts (RAW, WAR, WAW) with one since the last barrier.
  void track(const std::vector<Access>& accesses) {
    bool conflict = false;
    for (const Access& a : accesses)
      for (const Access& p : pending)
        if (a.buffer == p.buffer && a.begin < p.end && p.begin < a.end && (a.write || p.write)) conflict = true;
    if (conflict) full_barrier();
    pending.insert(pending.end(), accesses.begin(), accesses.end());
  }

  // An RGBA32F view of [offset, offset + size) of `buffer`, made once per recording.
  VkBufferView view_of(VkBuffer buffer, std::uint64_t offset, std::uint64_t size) {
    const auto key = std::make_tuple(buffer, offset, size);
    if (const auto it = views.find(key); it != views.end()) return it->second;
    VkBufferViewCreateInfo info{VK_STRUCTURE_TYPE_BUFFER_VIEW_CREATE_INFO};
    info.buffer = buffer;
    info.format = VK_FORMAT_R32G32B32A32_SFLOAT;
    info.offset = offset;
    info.range = size;
    VkBufferView view;
    NF_VK_CHECK(vkCreateBufferView(m.device, &info, nullptr, &view));
    views.emplace(key, view);
    return view;
  }

  void destroy_views() {
    for (const auto& [key, view] : views) vkDestroyBufferView(m.device, view, nullptr);
    views.clear();
  }

  VkDescriptorSet allocate_set() {
    if (sets_in_current_pool == kSetsPerPool) {
      const VkDescriptorPoolSize sizes[] = {
          {VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, kSetsPerPool * m.storage_slots},
          {VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER, kSetsPerPool * std::max(1u, m.uniform_slots)},
          {VK_DESCRIPTOR_TYPE_UNIFORM_TEXEL_BUFFER, kSetsPerPool * std::max(1u, m.texel_slots)}};
      VkDescriptorPoolCreateInfo info{VK_STRUCTURE_TYPE_DESCRIPTOR_POOL_CREATE_INFO};
      info.maxSets = kSetsPerPool;
      info.poolSizeCount = 3;
      info.pPoolSizes = sizes;
      VkDescriptorPool pool;
      NF_VK_CHECK(vkCreateDescriptorPool(m.device, &info, nullptr, &pool));
      pools.push_back(pool);
      sets_in_current_pool = 0;
    }
    VkDescriptorSetAllocateInfo alloc{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_ALLOCATE_INFO};
    alloc.descriptorPool = pools.back();
    alloc.descriptorSetCount = 1;
    alloc.pSetLayouts = &m.set_layout;
    VkDescriptorSet set;
    NF_VK_CHECK(vkAllocateDescriptorSets(m.device, &alloc, &set));
    ++sets_in_current_pool;
    return set;
  }
};

Stream::Stream(Context& context) : context_(&context), impl_(std::make_unique<Impl>(context.impl())) {
  Impl& s = *impl_;
  Context::Impl& m = s.m;
  VkCommandBufferAllocateInfo alloc{VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO};
  alloc.commandPool = m.command_pool;
  alloc.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
  alloc.commandBufferCount = 1;
  NF_VK_CHECK(vkAllocateCommandBuffers(m.device, &alloc, &s.cmd));
  VkFenceCreateInfo fence_info{VK_STRUCTURE_TYPE_FENCE_CREATE_INFO};
  NF_VK_CHECK(vkCreateFence(m.device, &fence_info, nullptr, &s.fence));
  if (m.info.features.timestamps) {
    VkQueryPoolCreateInfo q{VK_STRUCTURE_TYPE_QUERY_POOL_CREATE_INFO};
    q.queryType = VK_QUERY_TYPE_TIMESTAMP;
    q.queryCount = kMaxTimestamps;
    NF_VK_CHECK(vkCreateQueryPool(m.device, &q, nullptr, &s.queries));
  }
  s.begin_recording();
}

Stream::~Stream() {
  Impl& s = *impl_;
  Context::Impl& m = s.m;
  if (s.in_flight && vkWaitForFences(m.device, 1, &s.fence, VK_TRUE, kWaitTimeoutNs) != VK_SUCCESS) {
    // The GPU may still use these objects (hung or lost device): leak them rather than free them.
    for (auto& b : s.scratch) (void)b.release();
    return;
  }
  // The command buffer first: destroying a view it still records would invalidate it.
  if (s.recording) vkEndCommandBuffer(s.cmd);
  vkFreeCommandBuffers(m.device, m.command_pool, 1, &s.cmd);
  s.destroy_views();
  for (auto pool : s.pools) vkDestroyDescriptorPool(m.device, pool, nullptr);
  if (s.queries) vkDestroyQueryPool(m.device, s.queries, nullptr);
  vkDestroyFence(m.device, s.fence, nullptr);
  for (auto& b : s.scratch) m.release_scratch(std::move(b));
}

void Stream::record_dispatch(const Kernel& kernel, const BufferRange* bindings, std::size_t count, const void* push,
                             std::size_t push_size, Elements elements, bool explicit_groups) {
  Impl& s = *impl_;
  Context::Impl& m = s.m;
  const KernelLayout& layout = kernel.layout();
  const DeviceLimits& lim = m.info.limits;
  if (count != layout.bindings.size())
    throw InternalError("kernel '" + kernel.name() + "' declares " + std::to_string(layout.bindings.size()) +
                        " buffer bindings but the dispatch passes " + std::to_string(count));
  if (push_size != layout.push_constant_size)
    throw InternalError("kernel '" + kernel.name() + "' declares " + std::to_string(layout.push_constant_size) +
                        " bytes of push constants but the dispatch passes " + std::to_string(push_size) +
                        " (the C++ struct and the GLSL block differ)");

  // Group counts.
  std::array<std::uint64_t, 3> groups{};
  if (explicit_groups) {
    groups = {elements.x, elements.y, elements.z};
  } else {
    const auto& local = kernel.local_size();
    groups = {(elements.x + local[0] - 1) / local[0], (elements.y + local[1] - 1) / local[1],
              (elements.z + local[2] - 1) / local[2]};
    if (groups[0] > lim.max_workgroup_count[0]) {
      if (groups[1] != 1)
        throw InternalError("kernel '" + kernel.name() + "': too many groups along x to fold into y");
      groups[1] = (groups[0] + lim.max_workgroup_count[0] - 1) / lim.max_workgroup_count[0];
      groups[0] = (groups[0] + groups[1] - 1) / groups[1];
    }
  }
  if (groups[0] == 0 || groups[1] == 0 || groups[2] == 0) return;  // nothing to do
  for (int axis = 0; axis < 3; ++axis)
    if (groups[axis] > lim.max_workgroup_count[axis])
      throw DeviceLimitError("kernel '" + kernel.name() + "': " + std::to_string(groups[axis]) + " workgroups on axis " +
                        std::to_string(axis) + " exceed the device limit " +
                        std::to_string(lim.max_workgroup_count[axis]));

  // Descriptors, with range checks, and the accesses they imply.
  std::vector<VkDescriptorBufferInfo> infos(count);
  std::vector<VkBufferView> texel_views(count, VK_NULL_HANDLE);
  std::vector<Access> accesses;
  for (std::size_t b = 0; b < count; ++b) {
    const BufferRange& r = bindings[b];
    const BindingKind kind = layout.bindings[b].kind;
    if (r.size == 0) {  // an unused optional binding: the kernel never touches it
      infos[b] = {m.dummy->handles().buffer, 0, VK_WHOLE_SIZE};
      if (kind == BindingKind::texel) texel_views[b] = s.view_of(m.dummy->handles().buffer, 0, m.dummy->bytes());
      continue;
    }
    if (!r.buffer) throw InternalError("kernel '" + kernel.name() + "': binding " + std::to_string(b) + " is null");
    check_inside(r, [&] { return "kernel '" + kernel.name() + "' binding " + std::to_string(b); });
    const auto what = [&] { return "kernel '" + kernel.name() + "': binding " + std::to_string(b) + " ('" + r.buffer->name() + "')"; };
    if (kind == BindingKind::texel) {
      constexpr std::uint64_t kTexelBytes = 16;  // RGBA32F
      if (r.size % kTexelBytes)
        throw InternalError(what() + " spans " + std::to_string(r.size) + " bytes, not a whole number of vec4 texels");
      if (r.size / kTexelBytes > lim.max_texel_buffer_elements)
        throw DeviceLimitError(what() + " spans " + std::to_string(r.size / kTexelBytes) +
                          " texels, more than the device's maxTexelBufferElements " +
                          std::to_string(lim.max_texel_buffer_elements) + "; process it in chunks");
      if (lim.min_texel_buffer_offset_alignment && r.offset % lim.min_texel_buffer_offset_alignment)
        throw InternalError(what() + " offset " + std::to_string(r.offset) +
                            " is not a multiple of the device's minTexelBufferOffsetAlignment " +
                            std::to_string(lim.min_texel_buffer_offset_alignment));
      texel_views[b] = s.view_of(r.buffer->handles().buffer, r.offset, r.size);
    } else {
      const bool uniform = kind == BindingKind::uniform;
      const std::uint64_t max_range = uniform ? lim.max_uniform_buffer_range : lim.max_storage_buffer_range;
      const std::uint64_t alignment =
          uniform ? lim.min_uniform_buffer_offset_alignment : lim.min_storage_buffer_offset_alignment;
      if (r.size > max_range)
        throw DeviceLimitError(what() + " spans " + std::to_string(r.size) + " bytes, more than the device's " +
                          (uniform ? "maxUniformBufferRange " : "maxStorageBufferRange ") + std::to_string(max_range) +
                          "; process it in chunks");
      if (r.offset % alignment)
        throw InternalError(what() + " offset " + std::to_string(r.offset) + " is not a multiple of the device's " +
                            (uniform ? "minUniformBufferOffsetAlignment " : "minStorageBufferOffsetAlignment ") +
                            std::to_string(alignment));
    }
    infos[b] = {r.buffer->handles().buffer, r.offset, r.size};
    const BindingInfo& access = layout.bindings[b];
    if (access.read || access.write)
      accesses.push_back({r.buffer->handles().buffer, r.offset, r.offset + r.size, access.write});
  }
  s.track(accesses);

  if (s.bound_pipeline != kernel.handles().pipeline) {
    vkCmdBindPipeline(s.cmd, VK_PIPELINE_BIND_POINT_COMPUTE, kernel.handles().pipeline);
    s.bound_pipeline = kernel.handles().pipeline;
  }
  std::vector<VkWriteDescriptorSet> writes(count, VkWriteDescriptorSet{VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET});
  for (std::size_t b = 0; b < count; ++b) {
    const BindingKind kind = layout.bindings[b].kind;
    writes[b].dstBinding = layout.bindings[b].binding;
    writes[b].descriptorCount = 1;
    if (kind == BindingKind::texel) {
      writes[b].descriptorType = VK_DESCRIPTOR_TYPE_UNIFORM_TEXEL_BUFFER;
      writes[b].pTexelBufferView = &texel_views[b];
    } else {
      writes[b].descriptorType =
          kind == BindingKind::uniform ? VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER : VK_DESCRIPTOR_TYPE_STORAGE_BUFFER;
      writes[b].pBufferInfo = &infos[b];
    }
  }
  if (count > 0) {
    if (m.tuning.use_push_descriptors) {
      m.push_descriptor(s.cmd, VK_PIPELINE_BIND_POINT_COMPUTE, m.pipeline_layout, 0, std::uint32_t(count), writes.data());
    } else {
      const VkDescriptorSet set = s.allocate_set();
      for (auto& w : writes) w.dstSet = set;
      vkUpdateDescriptorSets(m.device, std::uint32_t(count), writes.data(), 0, nullptr);
      vkCmdBindDescriptorSets(s.cmd, VK_PIPELINE_BIND_POINT_COMPUTE, m.pipeline_layout, 0, 1, &set, 0, nullptr);
    }
  }
  if (push_size) vkCmdPushConstants(s.cmd, m.pipeline_layout, VK_SHADER_STAGE_COMPUTE_BIT, 0, std::uint32_t(push_size), push);
  vkCmdDispatch(s.cmd, std::uint32_t(groups[0]), std::uint32_t(groups[1]), std::uint32_t(groups[2]));
  ++s.dispatches;
  if (s.kernels.empty() || s.kernels.back() != kernel.name()) s.kernels.push_back(kernel.name());
}

void Stream::copy(BufferRange source, BufferRange destination) {
  Impl& s = *impl_;
  if (source.size != destination.size)
    throw InternalError("copy from '" + source.buffer->name() + "' to '" + destination.buffer->name() +
                        "': sizes differ (" + std::to_string(source.size) + " vs " + std::to_string(destination.size) + ")");
  if (source.size == 0) return;
  check_inside(source, [] { return "copy source"; });
  check_inside(destination, [] { return "copy destination"; });
  s.track({{source.buffer->handles().buffer, source.offset, source.offset + source.size, false},
           {destination.buffer->handles().buffer, destination.offset, destination.offset + destination.size, true}});
  VkBufferCopy region{source.offset, destination.offset, source.size};
  vkCmdCopyBuffer(s.cmd, source.buffer->handles().buffer, destination.buffer->handles().buffer, 1, &region);
}

void Stream::fill(BufferRange range, std::uint32_t value) {
  Impl& s = *impl_;
  if (range.size == 0) return;
  if (range.offset % 4 || range.size % 4)
    throw InternalError("fill of '" + range.buffer->name() + "': offset and size must be multiples of 4 bytes");
  check_inside(range, [] { return "fill"; });
  s.track({{range.buffer->handles().buffer, range.offset, range.offset + range.size, true}});
  vkCmdFillBuffer(s.cmd, range.buffer->handles().buffer, range.offset, range.size, value);
}

void Stream::barrier() { impl_->full_barrier(); }

BufferRange Stream::scratch(std::uint64_t bytes, const char*) {
  Impl& s = *impl_;
  auto buffer = s.m.acquire_scratch(bytes);
  const BufferRange r{buffer.get(), 0, bytes};
  s.scratch.push_back(std::move(buffer));
  return r;
}

void Stream::begin_pass(const std::string& name) {
  Impl& s = *impl_;
  if (s.pass_open) throw InternalError("pass '" + name + "' begun inside pass '" + s.passes.back().name + "'");
  s.pass_open = true;
  if (!s.queries || s.queries_used + 2 > kMaxTimestamps) {
    if (s.queries && !s.warned_queries) {
      log::warn("more than ", kMaxTimestamps / 2, " timed passes in one submit; later passes are not timed");
      s.warned_queries = true;
    }
    s.passes.push_back({name, ~0u});
    return;
  }
  vkCmdWriteTimestamp(s.cmd, VK_PIPELINE_STAGE_BOTTOM_OF_PIPE_BIT, s.queries, s.queries_used);
  s.passes.push_back({name, s.queries_used++});
}

void Stream::end_pass() {
  Impl& s = *impl_;
  if (!s.pass_open) throw InternalError("end_pass without begin_pass");
  s.pass_open = false;
  OpenPass& p = s.passes.back();
  if (p.begin_query == ~0u) return;
  vkCmdWriteTimestamp(s.cmd, VK_PIPELINE_STAGE_BOTTOM_OF_PIPE_BIT, s.queries, s.queries_used);
  p.end_query = s.queries_used++;
}

void Stream::submit_and_wait() {
  Impl& s = *impl_;
  Context::Impl& m = s.m;
  if (s.pass_open) throw InternalError("submit inside the open pass '" + s.passes.back().name + "'");
  // Make device writes visible to the host before it reads mapped memory.
  VkMemoryBarrier to_host{VK_STRUCTURE_TYPE_MEMORY_BARRIER};
  to_host.srcAccessMask = VK_ACCESS_SHADER_WRITE_BIT | VK_ACCESS_TRANSFER_WRITE_BIT;
  to_host.dstAccessMask = VK_ACCESS_HOST_READ_BIT;
  vkCmdPipelineBarrier(s.cmd, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT | VK_PIPELINE_STAGE_TRANSFER_BIT,
                       VK_PIPELINE_STAGE_HOST_BIT, 0, 1, &to_host, 0, nullptr, 0, nullptr);
  s.recording = false;
  NF_VK_CHECK(vkEndCommandBuffer(s.cmd));
  VkSubmitInfo submit{VK_STRUCTURE_TYPE_SUBMIT_INFO};
  submit.commandBufferCount = 1;
  submit.pCommandBuffers = &s.cmd;
  // A lost device (or NF_FAULT_DEVICE_LOST's pretend one, from its n-th submit on) is reported with
  // the passes and kernels that were running; a device that never answers counts as lost.
  const std::uint64_t submit_number = ++m.submits;
  const bool fault = m.options.fault_device_lost_at && submit_number >= m.options.fault_device_lost_at;
  const auto lost = [&](const std::string& how) {
    m.device_lost = true;
    return DeviceLostError("the GPU device was lost (" + how + ") while running " + s.running() + " on '" + m.info.name + "'");
  };
  if (m.device_lost) throw lost("earlier in this run");
  {
    std::lock_guard lock(m.queue_mutex);
    const VkResult submitted = fault ? VK_ERROR_DEVICE_LOST : vkQueueSubmit(m.queue, 1, &submit, s.fence);
    if (submitted == VK_ERROR_DEVICE_LOST) throw lost(fault ? "VK_ERROR_DEVICE_LOST, injected by NF_FAULT_DEVICE_LOST" : "VK_ERROR_DEVICE_LOST");
    NF_VK_CHECK(submitted);
  }
  s.in_flight = true;
  const VkResult waited = vkWaitForFences(m.device, 1, &s.fence, VK_TRUE, kWaitTimeoutNs);
  if (waited == VK_TIMEOUT) throw lost("no answer within 600 s: a hung kernel or a driver reset");
  if (waited == VK_ERROR_DEVICE_LOST) throw lost("VK_ERROR_DEVICE_LOST");
  NF_VK_CHECK(waited);
  s.in_flight = false;

  s.last_times.clear();
  if (s.queries_used > 0) {
    std::vector<std::uint64_t> ticks(s.queries_used);
    NF_VK_CHECK(vkGetQueryPoolResults(m.device, s.queries, 0, s.queries_used, ticks.size() * 8, ticks.data(), 8,
                                      VK_QUERY_RESULT_64_BIT | VK_QUERY_RESULT_WAIT_BIT));
    std::lock_guard lock(m.pass_mutex);
    for (const OpenPass& p : s.passes) {
      if (p.begin_query == ~0u || p.end_query == ~0u) continue;
      const double ms = double(ticks[p.end_query] - ticks[p.begin_query]) * m.info.limits.timestamp_period_ns * 1e-6;
      s.last_times.push_back({p.name, ms});
      PassTotal& t = m.pass_totals[p.name];
      t.milliseconds += ms;
      t.count += 1;
    }
  }

  NF_VK_CHECK(vkResetFences(m.device, 1, &s.fence));
  NF_VK_CHECK(vkResetCommandBuffer(s.cmd, 0));
  for (auto pool : s.pools) NF_VK_CHECK(vkResetDescriptorPool(m.device, pool, 0));
  if (!s.pools.empty()) {
    for (std::size_t i = 1; i < s.pools.size(); ++i) vkDestroyDescriptorPool(m.device, s.pools[i], nullptr);
    s.pools.resize(1);
    s.sets_in_current_pool = 0;
  }
  for (auto& b : s.scratch) m.release_scratch(std::move(b));
  s.scratch.clear();
  s.destroy_views();
  s.begin_recording();
}

std::uint32_t Stream::pending_dispatches() const { return impl_->dispatches; }
const std::vector<PassTime>& Stream::last_pass_times() const { return impl_->last_times; }

}  // namespace nf::gpu
