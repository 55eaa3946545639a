#pragma once
// The Vulkan instance and device nf_gpu computes on. One Context per process is the norm; it owns
// the shared descriptor layout, the kernel cache, the scratch-buffer pool and the pass profiler.
#include <cstdint>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "engine/gpu/device_info.hpp"
#include "engine/gpu/kernel.hpp"  // SpecConstant: a default argument needs the complete type

namespace nf::gpu {

class RawBuffer;

struct ContextOptions {
  std::string device;                  // NF_DEVICE: index or case-insensitive name substring; "" = best
  bool validation = false;             // NF_VALIDATION=1: Khronos validation layer, messages recorded
  bool force_descriptor_pool = false;  // NF_NO_PUSH_DESCRIPTORS=1: exercise the fallback path
  bool force_staging = false;          // NF_FORCE_STAGING=1: no mapped device memory, copy via staging
  bool no_shared_float_atomics = false;  // NF_NO_SHARED_FLOAT_ATOMICS=1: as if the device lacked them
  std::uint32_t shared_memory_cap = 0;   // NF_SHARED_MEMORY=<bytes>: report at most this much shared memory
  // Fault injection, for the tests of the failure paths on any device:
  std::uint64_t fault_device_lost_at = 0;  // NF_FAULT_DEVICE_LOST=<n>: the n-th submit and later ones lose the device
  std::uint64_t fault_memory_bytes = 0;    // NF_FAULT_DEVICE_MEMORY_MB=<m>: the device holds only m MiB
  static ContextOptions from_env();
};

struct PassTotal {
  double milliseconds = 0;
  std::uint64_t count = 0;
};

class Context {
 public:
  explicit Context(const ContextOptions& options = ContextOptions::from_env());
  ~Context();
  Context(const Context&) = delete;
  Context& operator=(const Context&) = delete;

  // Every Vulkan device the loader sees, best first is not implied: enumeration order.
  static std::vector<DeviceInfo> enumerate_devices();

  const DeviceInfo& info() const;
  const DeviceTuning& tuning() const;

  // A compute kernel built from embedded SPIR-V, cached by name and specialisation.
  const Kernel& kernel(const std::string& shader_name, const std::vector<SpecConstant>& spec = {});

  // Validation-layer messages (warnings and errors) since the last call; empty without validation.
  std::vector<std::string> take_validation_messages();
  bool validation_enabled() const;

  // GPU time per named pass, accumulated over every stream submitted on this context.
  std::map<std::string, PassTotal> pass_totals() const;
  void reset_pass_totals();

  // Device memory held by nf_gpu buffers now and at most since start (bytes).
  std::uint64_t allocated_bytes() const;
  std::uint64_t peak_allocated_bytes() const;
  // The same in one memory heap (0 past the device's heaps): what the out-of-memory check counts.
  std::uint64_t allocated_bytes_in_heap(std::uint32_t heap) const;

  struct Impl;
  Impl& impl() { return *impl_; }
  const Impl& impl() const { return *impl_; }

 private:
  std::unique_ptr<Impl> impl_;
};

// Whether kernels with a CPU and a GPU layout take the GPU one: on GPUs, or anywhere when the
// environment variable `env` is 1 (so that CI runs the GPU layout on lavapipe). Throws InputError
// naming the variable for a value other than 0 or 1.
bool use_gpu_layout(const Context& context, const char* env);

}  // namespace nf::gpu
