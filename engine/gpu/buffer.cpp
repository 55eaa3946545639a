#include "engine/gpu/buffer.hpp"

#include <cstring>

#include "engine/gpu/context_impl.hpp"

namespace nf::gpu {
namespace {

constexpr VkMemoryPropertyFlags kHostMemory = VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT;

struct Allocation {
  VkBuffer buffer = VK_NULL_HANDLE;
  VkDeviceMemory memory = VK_NULL_HANDLE;
  std::uint64_t bytes = 0;
  std::uint32_t memory_type = 0;
};

// The first memory type the buffer accepts that has all `wanted` properties, else one with `fallback`.
std::uint32_t pick_memory_type(const Context::Impl& m, std::uint32_t allowed, VkMemoryPropertyFlags wanted,
                               VkMemoryPropertyFlags fallback) {
  for (VkMemoryPropertyFlags flags : {wanted, fallback})
    for (std::uint32_t i = 0; i < m.memory_properties.memoryTypeCount; ++i)
      if ((allowed & (1u << i)) && (m.memory_properties.memoryTypes[i].propertyFlags & flags) == flags) return i;
  return ~0u;
}

Allocation allocate(Context::Impl& m, std::uint64_t bytes, VkMemoryPropertyFlags wanted, VkMemoryPropertyFlags fallback,
                    const std::string& name) {
  Allocation a;
  // Vulkan forbids empty buffers; an empty nf buffer still owns a small allocation.
  a.bytes = std::max<std::uint64_t>(bytes, 16);
  a.bytes = (a.bytes + 3) & ~std::uint64_t(3);  // vkCmdFillBuffer works on whole words
  VkBufferCreateInfo info{VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO};
  info.size = a.bytes;
  info.usage = VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_UNIFORM_BUFFER_BIT |
               VK_BUFFER_USAGE_UNIFORM_TEXEL_BUFFER_BIT |
               VK_BUFFER_USAGE_TRANSFER_SRC_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT;
  info.sharingMode = VK_SHARING_MODE_EXCLUSIVE;
  NF_VK_CHECK(vkCreateBuffer(m.device, &info, nullptr, &a.buffer));
  VkMemoryRequirements req;
  vkGetBufferMemoryRequirements(m.device, a.buffer, &req);
  const std::uint32_t memory_type = pick_memory_type(m, req.memoryTypeBits, wanted, fallback);
  if (memory_type == ~0u) {
    vkDestroyBuffer(m.device, a.buffer, nullptr);
    throw DeviceError("buffer '" + name + "': no memory type of this device can hold it");
  }
  VkMemoryAllocateInfo alloc{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO};
  alloc.allocationSize = req.size;
  alloc.memoryTypeIndex = memory_type;
  a.memory_type = memory_type;
  // More than the memory heap holds (on lavapipe: the machine's RAM, where the driver would
  // overcommit and the kernel kill the process later) fails here, with the error below, counting
  // what nf_gpu holds in that heap. So does more than NF_FAULT_DEVICE_MEMORY_MB in all heaps
  // together, the tests' stand-in for a small device.
  const std::uint32_t heap_index = m.memory_properties.memoryTypes[memory_type].heapIndex;
  const std::uint64_t heap = m.memory_properties.memoryHeaps[heap_index].size;
  const std::uint64_t fault = m.options.fault_memory_bytes;
  const bool over_fault = fault && m.allocated_bytes.load() + req.size > fault;
  const bool over_heap = m.heap_bytes[heap_index].load() + req.size > heap;
  const VkResult r = over_fault || over_heap ? VK_ERROR_OUT_OF_DEVICE_MEMORY : vkAllocateMemory(m.device, &alloc, nullptr, &a.memory);
  if (r != VK_SUCCESS) {
    vkDestroyBuffer(m.device, a.buffer, nullptr);
    if (r == VK_ERROR_OUT_OF_DEVICE_MEMORY || r == VK_ERROR_OUT_OF_HOST_MEMORY) {
      const std::uint64_t held = over_fault ? m.allocated_bytes.load() : m.heap_bytes[heap_index].load();
      throw DeviceLimitError("buffer '" + name + "': out of memory allocating " + std::to_string(req.size) + " bytes (" +
                             detail::result_name(r) + "); nf_gpu holds " + std::to_string(held) + " bytes already" +
                             (over_fault ? ", the device " + std::to_string(fault) + " in all"
                                         : " in memory heap " + std::to_string(heap_index) + ", which holds " + std::to_string(heap) + " in all"));
    }
    NF_VK_CHECK(r);
  }
  a.bytes = req.size;
  m.note_allocation(heap_index, std::int64_t(req.size));
  const VkResult bound = vkBindBufferMemory(m.device, a.buffer, a.memory, 0);
  if (bound != VK_SUCCESS) {
    vkDestroyBuffer(m.device, a.buffer, nullptr);
    vkFreeMemory(m.device, a.memory, nullptr);
    m.note_allocation(heap_index, -std::int64_t(a.bytes));
    NF_VK_CHECK(bound);
  }
  m.name_object(VK_OBJECT_TYPE_BUFFER, std::uint64_t(a.buffer), name);
  return a;
}

void free_allocation(Context::Impl& m, Allocation& a) {
  if (a.buffer) vkDestroyBuffer(m.device, a.buffer, nullptr);
  if (a.memory) {
    vkFreeMemory(m.device, a.memory, nullptr);
    m.note_allocation(m.memory_properties.memoryTypes[a.memory_type].heapIndex, -std::int64_t(a.bytes));
  }
  a = {};
}

// A host-visible buffer for one transfer; freed when it goes out of scope.
struct Staging {
  Context::Impl& m;
  Allocation a;
  void* data = nullptr;
  Staging(Context::Impl& impl, std::uint64_t bytes)
      : m(impl), a(allocate(impl, bytes, kHostMemory, kHostMemory, "staging")) {
    const VkResult mapped = vkMapMemory(m.device, a.memory, 0, VK_WHOLE_SIZE, 0, &data);
    if (mapped != VK_SUCCESS) {
      free_allocation(m, a);  // a constructor that throws runs no destructor
      NF_VK_CHECK(mapped);
    }
  }
  ~Staging() { free_allocation(m, a); }
  Staging(const Staging&) = delete;
  Staging& operator=(const Staging&) = delete;
};

}  // namespace

void require_bytes(const BufferRange& range, std::uint64_t bytes, const std::string& what) {
  if (range.size < bytes)
    throw InternalError(what + ": range of " + std::to_string(range.size) + " bytes" +
                        (range.buffer ? " in '" + range.buffer->name() + "'" : std::string()) + ", " +
                        std::to_string(bytes) + " needed");
}

RawBuffer::RawBuffer(Context& context, std::uint64_t bytes, std::string name)
    : context_(&context), bytes_(bytes), name_(std::move(name)) {
  Context::Impl& m = context.impl();
  const DeviceLimits& lim = m.info.limits;
  if (bytes > lim.max_allocation_size)
    throw DeviceLimitError("buffer '" + name_ + "' needs " + std::to_string(bytes) + " bytes but device '" + m.info.name +
                      "' allows at most " + std::to_string(lim.max_allocation_size) +
                      " per allocation; split the data or lower its size");
  // Mapped device memory where the tuning asks for it (lavapipe, integrated GPUs), else device-local.
  const VkMemoryPropertyFlags device_local = VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT;
  const bool want_mapped = m.tuning.mapped_device_buffers;
  Allocation a = want_mapped ? allocate(m, bytes, device_local | kHostMemory, kHostMemory, name_)
                             : allocate(m, bytes, device_local, 0, name_);
  handles_ = new Handles{a.buffer, a.memory, a.bytes, a.memory_type};
  const VkMemoryPropertyFlags got = m.memory_properties.memoryTypes[a.memory_type].propertyFlags;
  if (want_mapped && (got & kHostMemory) == kHostMemory) {
    try {
      NF_VK_CHECK(vkMapMemory(m.device, a.memory, 0, VK_WHOLE_SIZE, 0, &mapped_));
    } catch (...) {
      release();
      throw;
    }
  }
}

RawBuffer::~RawBuffer() { release(); }

void RawBuffer::release() {
  if (!handles_) return;
  Context::Impl& m = context_->impl();
  if (mapped_) vkUnmapMemory(m.device, handles_->memory);
  Allocation a{handles_->buffer, handles_->memory, handles_->allocation_bytes, handles_->memory_type};
  free_allocation(m, a);
  delete handles_;
  handles_ = nullptr;
  mapped_ = nullptr;
}

RawBuffer::RawBuffer(RawBuffer&& other) noexcept
    : context_(other.context_), bytes_(other.bytes_), name_(std::move(other.name_)),
      handles_(std::exchange(other.handles_, nullptr)), mapped_(std::exchange(other.mapped_, nullptr)) {}

RawBuffer& RawBuffer::operator=(RawBuffer&& other) noexcept {
  if (this != &other) {
    release();
    context_ = other.context_;
    bytes_ = other.bytes_;
    name_ = std::move(other.name_);
    handles_ = std::exchange(other.handles_, nullptr);
    mapped_ = std::exchange(other.mapped_, nullptr);
  }
  return *this;
}

BufferRange RawBuffer::range_bytes(std::uint64_t offset, std::uint64_t bytes) const {
  if (offset + bytes > bytes_)
    throw InternalError("range [" + std::to_string(offset) + ", " + std::to_string(offset + bytes) +
                        ") lies outside buffer '" + name_ + "' of " + std::to_string(bytes_) + " bytes");
  return {this, offset, bytes};
}

void RawBuffer::write_bytes(std::uint64_t offset, const void* data, std::uint64_t bytes) {
  if (offset + bytes > bytes_) throw InternalError("write past the end of buffer '" + name_ + "'");
  if (bytes == 0) return;
  if (mapped_) {
    std::memcpy(static_cast<char*>(mapped_) + offset, data, bytes);
    return;
  }
  Context::Impl& m = context_->impl();
  Staging staging(m, bytes);
  std::memcpy(staging.data, data, bytes);
  m.run_immediate([&](VkCommandBuffer cmd) {
    VkBufferCopy region{0, offset, bytes};
    vkCmdCopyBuffer(cmd, staging.a.buffer, handles_->buffer, 1, &region);
  });
}

void RawBuffer::read_bytes(std::uint64_t offset, void* data, std::uint64_t bytes) const {
  if (offset + bytes > bytes_) throw InternalError("read past the end of buffer '" + name_ + "'");
  if (bytes == 0) return;
  if (mapped_) {
    std::memcpy(data, static_cast<const char*>(mapped_) + offset, bytes);
    return;
  }
  Context::Impl& m = context_->impl();
  Staging staging(m, bytes);
  m.run_immediate([&](VkCommandBuffer cmd) {
    VkBufferCopy region{offset, 0, bytes};
    vkCmdCopyBuffer(cmd, handles_->buffer, staging.a.buffer, 1, &region);
  });
  std::memcpy(data, staging.data, bytes);
}

void RawBuffer::fill_u32(std::uint32_t value) {
  Context::Impl& m = context_->impl();
  m.run_immediate([&](VkCommandBuffer cmd) { vkCmdFillBuffer(cmd, handles_->buffer, 0, VK_WHOLE_SIZE, value); });
}

}  // namespace nf::gpu
