#pragma once
// A stream records many dispatches and copies into one command buffer, inserts the barriers their
// buffer accesses need (from each kernel's reflected read/write bindings), then submits and waits.
// Named passes get GPU timestamps; their totals feed `--profile`.
#include <cstdint>
#include <initializer_list>
#include <memory>
#include <string>
#include <type_traits>
#include <vector>

#include "engine/gpu/buffer.hpp"

namespace nf::gpu {

class Context;
class Kernel;

// Elements to cover along x (y, z); group counts are derived from the kernel's workgroup size.
// When x needs more groups than the device allows, they fold into y: kernels compute their linear
// index with nf_linear_index() from shaders/include/nf_index.glsl and bound-check against a count.
struct Elements {
  std::uint64_t x = 1;
  std::uint32_t y = 1;
  std::uint32_t z = 1;
  Elements(std::uint64_t x_ = 1, std::uint32_t y_ = 1, std::uint32_t z_ = 1) : x(x_), y(y_), z(z_) {}
};

struct PassTime {
  std::string name;
  double milliseconds = 0;
};

class Stream {
 public:
  explicit Stream(Context& context);
  ~Stream();
  Stream(const Stream&) = delete;
  Stream& operator=(const Stream&) = delete;

  Context& context() const { return *context_; }

  // Records a dispatch covering `elements`. Asserts binding count, push size, range limits.
  template <class Push>
  void dispatch(const Kernel& kernel, std::initializer_list<BufferRange> bindings, const Push& push, Elements elements) {
    static_assert(std::is_trivially_copyable_v<Push>, "push constants must be trivially copyable");
    record_dispatch(kernel, bindings.begin(), bindings.size(), &push, sizeof(Push), elements, false);
  }
  void dispatch(const Kernel& kernel, std::initializer_list<BufferRange> bindings, Elements elements) {
    record_dispatch(kernel, bindings.begin(), bindings.size(), nullptr, 0, elements, false);
  }
  // Records a dispatch of an explicit number of workgroups (no folding).
  void dispatch_groups(const Kernel& kernel, std::initializer_list<BufferRange> bindings, Elements groups) {
    record_dispatch(kernel, bindings.begin(), bindings.size(), nullptr, 0, groups, true);
  }
  template <class Push>
  void dispatch_groups(const Kernel& kernel, std::initializer_list<BufferRange> bindings, const Push& push,
                       Elements groups) {
    record_dispatch(kernel, bindings.begin(), bindings.size(), &push, sizeof(Push), groups, true);
  }

  void copy(BufferRange source, BufferRange destination);
  void fill(BufferRange range, std::uint32_t value);
  // A full memory barrier, for hazards the tracker cannot see (rarely needed).
  void barrier();

  // Temporary device memory valid until the next submit completes.
  BufferRange scratch(std::uint64_t bytes, const char* name = "scratch");

  // Named GPU-timed section; passes may not nest.
  void begin_pass(const std::string& name);
  void end_pass();

  // Submits what was recorded, waits for completion, and starts recording anew.
  void submit_and_wait();
  // Dispatches recorded since the last submit.
  std::uint32_t pending_dispatches() const;
  // Timings of the passes of the last submit.
  const std::vector<PassTime>& last_pass_times() const;

  struct Impl;

 private:
  void record_dispatch(const Kernel& kernel, const BufferRange* bindings, std::size_t count, const void* push,
                       std::size_t push_size, Elements elements, bool explicit_groups);
  Context* context_;
  std::unique_ptr<Impl> impl_;
};

// RAII helper for Stream::begin_pass / end_pass.
class ScopedPass {
 public:
  ScopedPass(Stream& stream, const std::string& name) : stream_(stream) { stream_.begin_pass(name); }
  ~ScopedPass() { stream_.end_pass(); }
  ScopedPass(const ScopedPass&) = delete;
  ScopedPass& operator=(const ScopedPass&) = delete;

 private:
  Stream& stream_;
};

}  // namespace nf::gpu
