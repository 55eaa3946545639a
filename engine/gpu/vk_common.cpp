#include "engine/gpu/vk_common.hpp"

#include "engine/core/error.hpp"

namespace nf::gpu::detail {

const char* result_name(VkResult result) {
  switch (result) {
#define NF_CASE(x) case x: return #x;
    NF_CASE(VK_SUCCESS) NF_CASE(VK_NOT_READY) NF_CASE(VK_TIMEOUT) NF_CASE(VK_EVENT_SET)
    NF_CASE(VK_EVENT_RESET) NF_CASE(VK_INCOMPLETE) NF_CASE(VK_ERROR_OUT_OF_HOST_MEMORY)
    NF_CASE(VK_ERROR_OUT_OF_DEVICE_MEMORY) NF_CASE(VK_ERROR_INITIALIZATION_FAILED)
    NF_CASE(VK_ERROR_DEVICE_LOST) NF_CASE(VK_ERROR_MEMORY_MAP_FAILED) NF_CASE(VK_ERROR_LAYER_NOT_PRESENT)
    NF_CASE(VK_ERROR_EXTENSION_NOT_PRESENT) NF_CASE(VK_ERROR_FEATURE_NOT_PRESENT)
    NF_CASE(VK_ERROR_INCOMPATIBLE_DRIVER) NF_CASE(VK_ERROR_TOO_MANY_OBJECTS)
    NF_CASE(VK_ERROR_FORMAT_NOT_SUPPORTED) NF_CASE(VK_ERROR_FRAGMENTED_POOL) NF_CASE(VK_ERROR_UNKNOWN)
    NF_CASE(VK_ERROR_OUT_OF_POOL_MEMORY) NF_CASE(VK_ERROR_INVALID_EXTERNAL_HANDLE)
    NF_CASE(VK_ERROR_FRAGMENTATION) NF_CASE(VK_ERROR_INVALID_OPAQUE_CAPTURE_ADDRESS)
    NF_CASE(VK_PIPELINE_COMPILE_REQUIRED) NF_CASE(VK_ERROR_INVALID_SHADER_NV)
#undef NF_CASE
    default: return "VK_RESULT_UNKNOWN";
  }
}

const char* driver_name(VkDriverId id) {
  switch (id) {
    case VK_DRIVER_ID_AMD_PROPRIETARY: return "AMD proprietary";
    case VK_DRIVER_ID_AMD_OPEN_SOURCE: return "AMD open source (AMDVLK)";
    case VK_DRIVER_ID_MESA_RADV: return "Mesa RADV";
    case VK_DRIVER_ID_NVIDIA_PROPRIETARY: return "NVIDIA proprietary";
    case VK_DRIVER_ID_INTEL_PROPRIETARY_WINDOWS: return "Intel proprietary";
    case VK_DRIVER_ID_INTEL_OPEN_SOURCE_MESA: return "Mesa ANV";
    case VK_DRIVER_ID_MESA_LLVMPIPE: return "Mesa lavapipe";
    case VK_DRIVER_ID_GOOGLE_SWIFTSHADER: return "SwiftShader";
    case VK_DRIVER_ID_MOLTENVK: return "MoltenVK";
    case VK_DRIVER_ID_MESA_TURNIP: return "Mesa Turnip";
    case VK_DRIVER_ID_MESA_NVK: return "Mesa NVK";
    case VK_DRIVER_ID_ARM_PROPRIETARY: return "ARM proprietary";
    case VK_DRIVER_ID_QUALCOMM_PROPRIETARY: return "Qualcomm proprietary";
    default: return "unknown driver";
  }
}

void throw_vk_error(VkResult result, const char* call, const char* file, int line) {
  std::string message = std::string(call) + " failed with " + result_name(result) + " at " + file + ":" +
                        std::to_string(line);
  if (result == VK_ERROR_DEVICE_LOST)
    throw DeviceLostError(message + " — the GPU device was lost (driver reset, timeout or a kernel fault)");
  if (result == VK_ERROR_OUT_OF_DEVICE_MEMORY || result == VK_ERROR_OUT_OF_HOST_MEMORY)
    throw DeviceLimitError(message + " — not enough memory");
  throw DeviceError(message);
}

}  // namespace nf::gpu::detail
