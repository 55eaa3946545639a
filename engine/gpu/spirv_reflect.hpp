#pragma once
// Just enough SPIR-V reflection for safe dispatch: which descriptor bindings a kernel uses and how
// (read, write), the push-constant block's size, the workgroup size (literal or specialisation
// constant) and the capabilities that need optional device features. The dispatch helper asserts
// against this, so a C++ struct that drifts from its GLSL twin fails loudly instead of corrupting.
#include <array>
#include <cstdint>
#include <map>
#include <span>
#include <string>
#include <vector>

namespace nf::gpu {

// Storage buffers take bindings 0..N-1, uniform buffers kUniformBindingBase.. and uniform texel
// buffers (samplerBuffer, read as RGBA32F) kTexelBindingBase.. (see context.cpp).
constexpr std::uint32_t kUniformBindingBase = 12;
constexpr std::uint32_t kTexelBindingBase = 16;

enum class BindingKind { storage, uniform, texel };

struct BindingInfo {
  std::uint32_t binding = 0;
  BindingKind kind = BindingKind::storage;  // uniform and texel bindings are read-only
  bool read = true;   // false when declared writeonly
  bool write = true;  // false when declared readonly
};

struct KernelLayout {
  std::vector<BindingInfo> bindings;      // sorted by binding (storage, uniform, texel), set 0 only
  std::uint32_t push_constant_size = 0;   // bytes; 0 when there is no push block
  std::array<std::uint32_t, 3> local_size{1, 1, 1};       // defaults from the module
  std::array<std::int32_t, 3> local_size_spec_id{-1, -1, -1};  // spec id per axis, -1 if literal
  std::map<std::uint32_t, std::uint32_t> spec_defaults;   // SpecId -> default (32-bit constants)
  bool uses_float32_atomic_add = false;
  bool uses_float16 = false;
  bool uses_int64 = false;
};

// Throws InternalError naming `name` if the module is malformed or uses descriptor sets other than 0.
KernelLayout reflect_spirv(std::span<const std::uint32_t> words, const std::string& name);

}  // namespace nf::gpu
