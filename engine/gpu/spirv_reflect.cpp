#include "engine/gpu/spirv_reflect.hpp"

#include <algorithm>
#include <functional>
#include <unordered_map>

#include "engine/core/error.hpp"

namespace nf::gpu {
namespace {

// SPIR-V opcodes and enums used here (stable across SPIR-V versions; spec section 3).
enum : std::uint32_t {
  OpCapability = 17, OpExecutionMode = 16, OpTypeBool = 20, OpTypeInt = 21, OpTypeFloat = 22,
  OpTypeVector = 23, OpTypeMatrix = 24, OpTypeImage = 25, OpTypeSampledImage = 27, OpTypeArray = 28,
  OpTypeStruct = 30, OpTypePointer = 32,
  OpConstant = 43, OpSpecConstantTrue = 48, OpSpecConstantFalse = 49, OpSpecConstant = 50,
  OpSpecConstantComposite = 51, OpVariable = 59, OpDecorate = 71, OpMemberDecorate = 72,
  OpExecutionModeId = 331,
  DecSpecId = 1, DecBuiltIn = 11, DecNonWritable = 24, DecNonReadable = 25, DecBinding = 33,
  DecDescriptorSet = 34, DecOffset = 35, DecArrayStride = 6, DecMatrixStride = 7,
  BuiltInWorkgroupSize = 25, ExecModeLocalSize = 17, ExecModeLocalSizeId = 38,
  StorageUniformConstant = 0, StorageUniform = 2, StoragePushConstant = 9, StorageStorageBuffer = 12,
  DimBuffer = 5, CapFloat16 = 9, CapInt64 = 11, CapAtomicFloat32AddEXT = 6033,
};

struct Type {
  std::uint32_t op = 0;
  std::vector<std::uint32_t> operands;  // words after the result id
};

const char* binding_kind_name(BindingKind kind) {
  switch (kind) {
    case BindingKind::uniform: return "uniform buffer";
    case BindingKind::texel: return "texel buffer";
    default: return "storage buffer";
  }
}

}  // namespace

KernelLayout reflect_spirv(std::span<const std::uint32_t> words, const std::string& name) {
  if (words.size() < 5 || words[0] != 0x07230203u)
    throw InternalError("shader '" + name + "' is not a SPIR-V module (bad magic number)");
  KernelLayout layout;
  std::unordered_map<std::uint32_t, Type> types;
  std::unordered_map<std::uint32_t, std::uint32_t> constants;       // id -> 32-bit value
  std::unordered_map<std::uint32_t, std::uint32_t> spec_ids;        // id -> SpecId
  std::unordered_map<std::uint32_t, std::uint32_t> bindings, sets;  // variable id -> value
  std::unordered_map<std::uint32_t, bool> non_writable, non_readable;  // variables
  std::unordered_map<std::uint32_t, std::uint32_t> members_non_writable, members_non_readable;  // per struct
  std::unordered_map<std::uint64_t, std::uint32_t> member_offset;   // (struct << 32 | member) -> offset
  std::unordered_map<std::uint32_t, std::uint32_t> array_stride;
  std::unordered_map<std::uint64_t, std::uint32_t> matrix_stride;
  std::unordered_map<std::uint32_t, std::vector<std::uint32_t>> spec_composites;
  std::uint32_t workgroup_size_id = 0;
  struct Var { std::uint32_t id, type, storage; };
  std::vector<Var> variables;

  for (std::size_t i = 5; i < words.size();) {
    const std::uint32_t count = words[i] >> 16, op = words[i] & 0xffffu;
    if (count == 0 || i + count > words.size()) throw InternalError("shader '" + name + "': truncated SPIR-V");
    const std::uint32_t* w = &words[i];
    switch (op) {
      case OpCapability:
        if (w[1] == CapAtomicFloat32AddEXT) layout.uses_float32_atomic_add = true;
        if (w[1] == CapFloat16) layout.uses_float16 = true;
        if (w[1] == CapInt64) layout.uses_int64 = true;
        break;
      case OpExecutionMode:
        if (w[2] == ExecModeLocalSize) layout.local_size = {w[3], w[4], w[5]};
        break;
      case OpExecutionModeId:
        if (w[2] == ExecModeLocalSizeId) throw InternalError("shader '" + name + "': LocalSizeId is not supported");
        break;
      case OpTypeBool: case OpTypeInt: case OpTypeFloat: case OpTypeVector: case OpTypeMatrix:
      case OpTypeArray: case OpTypeStruct: case OpTypePointer: case OpTypeImage: case OpTypeSampledImage:
        types[w[1]] = Type{op, std::vector<std::uint32_t>(w + 2, w + count)};
        break;
      case OpConstant: case OpSpecConstant:
        constants[w[2]] = w[3];
        if (op == OpSpecConstant) spec_ids.try_emplace(w[2], 0xffffffffu);
        break;
      case OpSpecConstantTrue: case OpSpecConstantFalse:
        constants[w[2]] = op == OpSpecConstantTrue;
        spec_ids.try_emplace(w[2], 0xffffffffu);
        break;
      case OpSpecConstantComposite:
        spec_composites[w[2]] = std::vector<std::uint32_t>(w + 3, w + count);
        break;
      case OpVariable:
        variables.push_back({w[2], w[1], w[3]});
        break;
      case OpDecorate:
        if (w[2] == DecBinding) bindings[w[1]] = w[3];
        else if (w[2] == DecDescriptorSet) sets[w[1]] = w[3];
        else if (w[2] == DecNonWritable) non_writable[w[1]] = true;
        else if (w[2] == DecNonReadable) non_readable[w[1]] = true;
        else if (w[2] == DecSpecId) spec_ids[w[1]] = w[3];
        else if (w[2] == DecArrayStride) array_stride[w[1]] = w[3];
        else if (w[2] == DecBuiltIn && w[3] == BuiltInWorkgroupSize) workgroup_size_id = w[1];
        break;
      case OpMemberDecorate:
        if (w[3] == DecOffset) member_offset[(std::uint64_t(w[1]) << 32) | w[2]] = w[4];
        else if (w[3] == DecMatrixStride) matrix_stride[(std::uint64_t(w[1]) << 32) | w[2]] = w[4];
        else if (w[3] == DecNonWritable) ++members_non_writable[w[1]];
        else if (w[3] == DecNonReadable) ++members_non_readable[w[1]];
        break;
      default:
        break;
    }
    i += count;
  }

  for (const auto& [id, spec] : spec_ids)
    if (spec != 0xffffffffu) layout.spec_defaults[spec] = constants[id];

  // Workgroup size given by specialisation constants (layout(local_size_x_id = N) in GLSL).
  if (workgroup_size_id) {
    const auto it = spec_composites.find(workgroup_size_id);
    if (it != spec_composites.end() && it->second.size() == 3) {
      for (int axis = 0; axis < 3; ++axis) {
        const std::uint32_t c = it->second[axis];
        layout.local_size[axis] = constants[c];
        const auto s = spec_ids.find(c);
        if (s != spec_ids.end() && s->second != 0xffffffffu) layout.local_size_spec_id[axis] = std::int32_t(s->second);
      }
    }
  }

  // Byte size of a type inside an explicitly laid-out block.
  std::function<std::uint32_t(std::uint32_t, std::uint32_t, std::uint32_t)> size_of =
      [&](std::uint32_t type_id, std::uint32_t parent, std::uint32_t member) -> std::uint32_t {
    const auto t = types.find(type_id);
    if (t == types.end()) throw InternalError("shader '" + name + "': unknown type in push constants");
    const auto& o = t->second.operands;
    switch (t->second.op) {
      case OpTypeBool: return 4;
      case OpTypeInt: case OpTypeFloat: return o[0] / 8;
      case OpTypeVector: return o[1] * size_of(o[0], 0, 0);
      case OpTypeMatrix: return o[1] * matrix_stride[(std::uint64_t(parent) << 32) | member];
      case OpTypeArray: return constants[o[1]] * array_stride[type_id];
      case OpTypeStruct: {
        std::uint32_t end = 0;
        for (std::uint32_t m = 0; m < o.size(); ++m)
          end = std::max(end, member_offset[(std::uint64_t(type_id) << 32) | m] + size_of(o[m], type_id, m));
        return end;
      }
      default: throw InternalError("shader '" + name + "': unsupported type in push constants");
    }
  };

  for (const Var& v : variables) {
    const auto ptr = types.find(v.type);
    if (ptr == types.end() || ptr->second.op != OpTypePointer) continue;
    const std::uint32_t pointee = ptr->second.operands[1];
    if (v.storage == StoragePushConstant) {
      layout.push_constant_size = size_of(pointee, 0, 0);
    } else if (v.storage == StorageUniformConstant) {
      // Only sampled buffer images (samplerBuffer / textureBuffer) are supported: uniform texel buffers.
      if (!bindings.count(v.id)) continue;
      if (sets[v.id] != 0) throw InternalError("shader '" + name + "': only descriptor set 0 is supported");
      std::uint32_t image = pointee;
      if (types.count(image) && types[image].op == OpTypeSampledImage) image = types[image].operands[0];
      const auto t = types.find(image);
      // OpTypeImage operands after the result: sampled type, Dim, Depth, Arrayed, MS, Sampled, format.
      if (t == types.end() || t->second.op != OpTypeImage || t->second.operands[1] != DimBuffer ||
          t->second.operands[5] != 1)
        throw InternalError("shader '" + name + "': binding " + std::to_string(bindings[v.id]) +
                            " is an image or sampler; only samplerBuffer (a uniform texel buffer) is supported");
      layout.bindings.push_back({bindings[v.id], BindingKind::texel, true, false});
    } else if (v.storage == StorageStorageBuffer || v.storage == StorageUniform) {
      if (!bindings.count(v.id)) continue;
      if (sets[v.id] != 0) throw InternalError("shader '" + name + "': only descriptor set 0 is supported");
      // Access qualifiers sit on the variable, or on members of the block type: the block is
      // read-only (write-only) only when every member is. SPIR-V 1.3+ (Vulkan 1.1+) puts storage
      // buffers in StorageBuffer and uniform buffers in Uniform.
      const auto members = types.count(pointee) ? std::uint32_t(types[pointee].operands.size()) : 0u;
      const bool uniform = v.storage == StorageUniform;
      const bool ro = uniform || non_writable[v.id] || (members && members_non_writable[pointee] == members);
      const bool wo = !uniform && (non_readable[v.id] || (members && members_non_readable[pointee] == members));
      layout.bindings.push_back({bindings[v.id], uniform ? BindingKind::uniform : BindingKind::storage, !wo, !ro});
    }
  }
  std::sort(layout.bindings.begin(), layout.bindings.end(),
            [](const BindingInfo& a, const BindingInfo& b) { return a.binding < b.binding; });
  std::uint32_t next_storage = 0, next_uniform = kUniformBindingBase, next_texel = kTexelBindingBase;
  for (const BindingInfo& b : layout.bindings) {
    std::uint32_t& expected = b.kind == BindingKind::uniform ? next_uniform
                              : b.kind == BindingKind::texel ? next_texel
                                                             : next_storage;
    if (b.binding != expected)
      throw InternalError("shader '" + name + "': " + binding_kind_name(b.kind) + " at binding " +
                          std::to_string(b.binding) + "; storage buffers must use bindings 0..N-1, uniform "
                          "buffers " + std::to_string(kUniformBindingBase) + ".. and texel buffers " +
                          std::to_string(kTexelBindingBase) + ".., each without gaps");
    ++expected;
  }
  return layout;
}

}  // namespace nf::gpu
