#pragma once
// A compute kernel: one pipeline built from embedded SPIR-V, with its reflected layout.
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "engine/gpu/spirv_reflect.hpp"

namespace nf::gpu {

struct SpecConstant {
  std::uint32_t id = 0;
  std::uint32_t value = 0;
};

class Kernel {
 public:
  const std::string& name() const { return name_; }
  const KernelLayout& layout() const { return layout_; }
  // Workgroup size after specialisation.
  const std::array<std::uint32_t, 3>& local_size() const { return local_size_; }

  struct Handles;  // Vulkan pipeline, private to engine/gpu
  const Handles& handles() const { return *handles_; }

  Kernel(std::string name, KernelLayout layout, std::array<std::uint32_t, 3> local_size, Handles* handles)
      : name_(std::move(name)), layout_(std::move(layout)), local_size_(local_size), handles_(handles) {}
  ~Kernel();
  Kernel(const Kernel&) = delete;
  Kernel& operator=(const Kernel&) = delete;

 private:
  std::string name_;
  KernelLayout layout_;
  std::array<std::uint32_t, 3> local_size_;
  Handles* handles_;
};

}  // namespace nf::gpu
