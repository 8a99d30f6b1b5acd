#include "engine/status.h"

namespace canopy {

const char* vkResultName(VkResult r) {
  switch (r) {
#define CASE(x) case x: return #x;
    CASE(VK_SUCCESS) CASE(VK_NOT_READY) CASE(VK_TIMEOUT) CASE(VK_EVENT_SET) CASE(VK_EVENT_RESET)
    CASE(VK_INCOMPLETE) CASE(VK_ERROR_OUT_OF_HOST_MEMORY) CASE(VK_ERROR_OUT_OF_DEVICE_MEMORY)
    CASE(VK_ERROR_INITIALIZATION_FAILED) CASE(VK_ERROR_DEVICE_LOST) CASE(VK_ERROR_MEMORY_MAP_FAILED)
    CASE(VK_ERROR_LAYER_NOT_PRESENT) CASE(VK_ERROR_EXTENSION_NOT_PRESENT)
    CASE(VK_ERROR_FEATURE_NOT_PRESENT) CASE(VK_ERROR_INCOMPATIBLE_DRIVER)
    CASE(VK_ERROR_TOO_MANY_OBJECTS) CASE(VK_ERROR_FORMAT_NOT_SUPPORTED)
    CASE(VK_ERROR_FRAGMENTED_POOL) CASE(VK_ERROR_UNKNOWN) CASE(VK_ERROR_OUT_OF_POOL_MEMORY)
    CASE(VK_ERROR_INVALID_EXTERNAL_HANDLE) CASE(VK_ERROR_FRAGMENTATION)
    CASE(VK_ERROR_SURFACE_LOST_KHR) CASE(VK_ERROR_NATIVE_WINDOW_IN_USE_KHR)
    CASE(VK_SUBOPTIMAL_KHR) CASE(VK_ERROR_OUT_OF_DATE_KHR) CASE(VK_ERROR_VALIDATION_FAILED_EXT)
#undef CASE
    default: return "VK_RESULT_UNKNOWN";
  }
}

Result resultOf(VkResult r) {
  switch (r) {
    case VK_ERROR_OUT_OF_HOST_MEMORY: return Result::OutOfHostMemory;
    case VK_ERROR_OUT_OF_DEVICE_MEMORY: return Result::OutOfDeviceMemory;
    case VK_ERROR_DEVICE_LOST: return Result::DeviceLost;
    case VK_ERROR_FEATURE_NOT_PRESENT:
    case VK_ERROR_EXTENSION_NOT_PRESENT:
    case VK_ERROR_FORMAT_NOT_SUPPORTED:
    case VK_ERROR_INCOMPATIBLE_DRIVER: return Result::UnsupportedDevice;
    default: return Result::VulkanError;
  }
}

const char* toString(Result r) {
  switch (r) {
    case Result::Success: return "Success";
    case Result::InvalidArgument: return "InvalidArgument";
    case Result::InvalidModel: return "InvalidModel";
    case Result::FileError: return "FileError";
    case Result::UnsupportedDevice: return "UnsupportedDevice";
    case Result::OutOfHostMemory: return "OutOfHostMemory";
    case Result::OutOfDeviceMemory: return "OutOfDeviceMemory";
    case Result::DeviceLost: return "DeviceLost";
    case Result::VersionMismatch: return "VersionMismatch";
    case Result::VulkanError: return "VulkanError";
  }
  return "Unknown";
}

uint32_t libraryVersion() { return CANOPY_HEADER_VERSION; }

Status vkError(const char* call, VkResult r) {
  return Status::error(resultOf(r), std::string(call) + " failed: " + vkResultName(r) + " (" + std::to_string(int(r)) + ")");
}

}  // namespace canopy
