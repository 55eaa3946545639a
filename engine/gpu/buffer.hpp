#pragma once
// Device buffers. Memory is host-mapped where the device prefers it (lavapipe, integrated GPUs),
// device-local with staging copies otherwise; the API is the same. A buffer may exceed
// maxStorageBufferRange; a kernel binding may not, and primitives chunk over such buffers.
#include <cstdint>
#include <cstring>
#include <span>
#include <string>
#include <vector>

#include "engine/core/error.hpp"

namespace nf::gpu {

class Context;
class RawBuffer;

// A byte range of a buffer, the unit bound to a kernel binding.
struct BufferRange {
  const RawBuffer* buffer = nullptr;
  std::uint64_t offset = 0;  // bytes
  std::uint64_t size = 0;    // bytes
};

// Throws InternalError naming `what` when `range` holds fewer than `bytes` bytes: wrappers call it
// so that a kernel never indexes past the range it was given.
void require_bytes(const BufferRange& range, std::uint64_t bytes, const std::string& what);

class RawBuffer {
 public:
  // `name` appears in errors and in validation messages.
  RawBuffer(Context& context, std::uint64_t bytes, std::string name);
  ~RawBuffer();
  RawBuffer(const RawBuffer&) = delete;
  RawBuffer& operator=(const RawBuffer&) = delete;
  RawBuffer(RawBuffer&& other) noexcept;
  RawBuffer& operator=(RawBuffer&& other) noexcept;

  std::uint64_t bytes() const { return bytes_; }
  const std::string& name() const { return name_; }
  bool mapped() const { return mapped_ != nullptr; }
  Context& context() const { return *context_; }

  // Host transfers. Blocking; the caller makes sure no submitted work still uses the range.
  void write_bytes(std::uint64_t offset, const void* data, std::uint64_t bytes);
  void read_bytes(std::uint64_t offset, void* data, std::uint64_t bytes) const;
  void fill_u32(std::uint32_t value);

  BufferRange range_bytes(std::uint64_t offset, std::uint64_t bytes) const;
  BufferRange whole() const { return {this, 0, bytes_}; }

  struct Handles;  // Vulkan objects, private to engine/gpu
  const Handles& handles() const { return *handles_; }

 private:
  void release();
  Context* context_ = nullptr;
  std::uint64_t bytes_ = 0;
  std::string name_;
  Handles* handles_ = nullptr;
  void* mapped_ = nullptr;
};

// A typed view over RawBuffer: counts in elements.
template <class T>
class Buffer : public RawBuffer {
 public:
  Buffer(Context& context, std::uint64_t count, std::string name)
      : RawBuffer(context, count * sizeof(T), std::move(name)), count_(count) {}
  Buffer(Context& context, std::span<const T> values, std::string name)
      : Buffer(context, values.size(), std::move(name)) {
    upload(values);
  }

  std::uint64_t size() const { return count_; }

  void upload(std::span<const T> values, std::uint64_t first = 0) {
    if (first + values.size() > count_)
      throw InternalError("upload of " + std::to_string(values.size()) + " elements at " + std::to_string(first) +
                          " overflows buffer '" + name() + "' of " + std::to_string(count_));
    write_bytes(first * sizeof(T), values.data(), values.size() * sizeof(T));
  }
  std::vector<T> download(std::uint64_t first = 0, std::uint64_t count = ~0ull) const {
    if (count == ~0ull) count = first <= count_ ? count_ - first : 0;
    if (first + count > count_)
      throw InternalError("download past the end of buffer '" + name() + "'");
    std::vector<T> out(count);
    read_bytes(first * sizeof(T), out.data(), count * sizeof(T));
    return out;
  }
  BufferRange range(std::uint64_t first, std::uint64_t count) const {
    return range_bytes(first * sizeof(T), count * sizeof(T));
  }
  operator BufferRange() const { return whole(); }

 private:
  std::uint64_t count_;
};

}  // namespace nf::gpu
