#pragma once
// Canopy's core types, shared by the public API (<canopy/canopy.h>, which includes this header) and
// Canopy's own engine: the version, Result and Status, the small math types and camera, and the
// host's device (what Canopy needs of it and how it is adopted). C++17, Vulkan's headers only.
#include <cstdint>
#include <functional>
#include <string>
#include <vector>
#include <vulkan/vulkan.h>

// The version this header declares. createCanopy() refuses a library of another major version, or
// an older minor version, naming both (a host built against 0.2 cannot run on a 0.1 library).
#define CANOPY_VERSION_MAJOR 0
#define CANOPY_VERSION_MINOR 6
#define CANOPY_VERSION_PATCH 0
#define CANOPY_MAKE_VERSION(major, minor, patch) ((uint32_t(major) << 22) | (uint32_t(minor) << 12) | uint32_t(patch))
#define CANOPY_HEADER_VERSION CANOPY_MAKE_VERSION(CANOPY_VERSION_MAJOR, CANOPY_VERSION_MINOR, CANOPY_VERSION_PATCH)

namespace canopy {

// ---------------------------------------------------------------------------------------------
// Results

enum class Result : uint32_t {
  Success = 0,
  InvalidArgument,    // a parameter out of range or inconsistent (the message names it and the range)
  InvalidModel,       // the model file or data is malformed (the message names file and element)
  FileError,          // a file could not be read or written
  UnsupportedDevice,  // the device lacks a required version, extension, feature or format
  OutOfHostMemory,
  OutOfDeviceMemory,
  DeviceLost,
  VersionMismatch,    // header and library versions differ
  VulkanError,        // any other failing Vulkan call (named in the message)
};
// The code's name ("UnsupportedDevice"), for logs.
const char* toString(Result result);

// Empty on success; else a Result and a message ("CanopyDesc.width = 0 is outside [1, 16384]").
class [[nodiscard]] Status {
 public:
  Status() = default;
  static Status error(std::string message) { return error(Result::InvalidArgument, std::move(message)); }
  static Status error(Result code, std::string message) {
    Status s;
    s.code_ = code == Result::Success ? Result::InvalidArgument : code;
    s.message_ = std::move(message);
    return s;
  }
  bool ok() const { return code_ == Result::Success; }
  explicit operator bool() const { return ok(); }
  Result code() const { return code_; }
  const std::string& message() const { return message_; }
  // Prefixes context ("while creating X: ") so the message reads outermost first; keeps the code.
  Status context(const std::string& what) const { return ok() ? *this : error(code_, what + ": " + message_); }

 private:
  Result code_ = Result::Success;
  std::string message_;
};

// Progress of long work (leaf roots, mesh upload): (stage, done, total), called on the calling
// thread now and then, last with done == total.
using Progress = std::function<void(const char* stage, uint64_t done, uint64_t total)>;

// The library's version (CANOPY_MAKE_VERSION form), to compare with CANOPY_HEADER_VERSION.
uint32_t libraryVersion();

// ---------------------------------------------------------------------------------------------
// Small math types (column-major, like GLSL and glm: m[column * 4 + row]).

struct Float3 {
  float x = 0, y = 0, z = 0;
};
inline bool operator==(const Float3& a, const Float3& b) { return a.x == b.x && a.y == b.y && a.z == b.z; }
struct Float4x4 {
  float m[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
};

// A camera: the view and projection of a frame (CanopyFrame.camera).
struct CanopyCamera {
  Float4x4 view;  // world -> view (right-handed, looking down -Z)
  Float4x4 proj;  // view -> Vulkan clip space (y down), following CanopyDesc.depthConvention
};

// A resource's synchronization state: the stage and access of its last (or next) use and, for an
// image, its layout (the host's images in CanopyImage; Canopy's render graph plans from these).
struct ResourceState {
  VkPipelineStageFlags2 stage = VK_PIPELINE_STAGE_2_NONE;
  VkAccessFlags2 access = VK_ACCESS_2_NONE;
  VkImageLayout layout = VK_IMAGE_LAYOUT_UNDEFINED;
};

// ---------------------------------------------------------------------------------------------
// The host's device

struct Device;  // Canopy's view of one host VkDevice (opaque)

// What Canopy needs of a device, and what it uses when present.
struct DeviceRequirements {
  uint32_t minApiVersion = VK_API_VERSION_1_2;
  std::vector<std::string> extensions;          // required (on 1.2 also synchronization2, dynamic rendering)
  std::vector<std::string> optionalExtensions;  // used when enabled
  std::vector<std::string> features;            // required, as "VkPhysicalDeviceVulkan12Features.scalarBlockLayout"
  std::vector<std::string> optionalFeatures;    // used when enabled (single-pass layers, clip-distance fallback)
  std::string unsupported;  // why this physical device cannot run Canopy; empty when it can
};
// Reads the physical device through the host's loader. Works before any VkDevice exists.
// `instanceApiVersion` is VkApplicationInfo.apiVersion of the host's instance: on 1.3 (instance and
// device) synchronization2 and dynamic rendering are core, below it they are extensions.
Status queryDeviceRequirements(PFN_vkGetInstanceProcAddr getInstanceProcAddr, VkInstance instance,
                               uint32_t instanceApiVersion, VkPhysicalDevice physicalDevice, DeviceRequirements* out);
// Sets Canopy's required features, and the optional ones the device supports, in the host's
// feature chain (head VkPhysicalDeviceFeatures2 with VkPhysicalDeviceVulkan11Features,
// VkPhysicalDeviceVulkan12Features and either VkPhysicalDeviceVulkan13Features or
// VkPhysicalDeviceSynchronization2Features + VkPhysicalDeviceDynamicRenderingFeatures in pNext).
// A struct missing from the chain is an error naming it; nothing is allocated.
Status enableDeviceFeatures(PFN_vkGetInstanceProcAddr getInstanceProcAddr, VkInstance instance,
                            VkPhysicalDevice physicalDevice, VkPhysicalDeviceFeatures2* chain);

// A range of device memory handed out by a host allocator (e.g. VMA's vmaAllocateMemory).
struct DeviceMemoryRange {
  VkDeviceMemory memory = VK_NULL_HANDLE;
  VkDeviceSize offset = 0;
  VkDeviceSize size = 0;
  void* mapped = nullptr;       // host pointer at `offset` when host-visible and mapped, else null
  uint32_t memoryTypeIndex = 0;
  uint64_t hostHandle = 0;      // the host's own handle, given back to free()
};
// Optional: all of Canopy's device memory through the host's allocator. Without it Canopy
// sub-allocates from its own 64 MiB blocks. Called only from Canopy calls on this device.
struct DeviceMemoryAllocator {
  void* user = nullptr;
  // `required` property flags must hold; `preferred` are wished for (DEVICE_LOCAL, or
  // HOST_VISIBLE | HOST_COHERENT for uploads and readbacks, which must come back mapped).
  VkResult (*allocate)(void* user, const VkMemoryRequirements& requirements, VkMemoryPropertyFlags required,
                       VkMemoryPropertyFlags preferred, DeviceMemoryRange* out) = nullptr;
  void (*free)(void* user, const DeviceMemoryRange& range) = nullptr;
};

struct AdoptDeviceDesc {
  PFN_vkGetInstanceProcAddr getInstanceProcAddr = nullptr;  // every entry point is loaded through it
  VkInstance instance = VK_NULL_HANDLE;
  uint32_t instanceApiVersion = VK_API_VERSION_1_2;  // VkApplicationInfo.apiVersion of the instance
  VkPhysicalDevice physicalDevice = VK_NULL_HANDLE;
  VkDevice device = VK_NULL_HANDLE;
  // What the device was created with (extensions and the pNext feature chain or pEnabledFeatures);
  // read during adoptDevice() only. Adoption is refused, naming what is missing, when a required
  // extension or feature is not enabled.
  const VkDeviceCreateInfo* deviceCreateInfo = nullptr;
  VkQueue queue = VK_NULL_HANDLE;  // graphics + compute, the queue the host submits Canopy's work to
  uint32_t queueFamily = 0;
  const VkAllocationCallbacks* allocationCallbacks = nullptr;  // optional, for every Vulkan object
  VkPipelineCache pipelineCache = VK_NULL_HANDLE;              // optional
  const DeviceMemoryAllocator* memoryAllocator = nullptr;      // optional (copied)
  // Frames the host records ahead of the GPU, 1..3: resources Canopy replaces (a new layer count,
  // a resize, a destroyed context) are released this many frames after their last use.
  uint32_t framesInFlight = 2;
  const char* debugName = "canopy";
};
// Wraps the host's device. The VkDevice, instance and queue stay the host's; releaseDevice()
// destroys only what Canopy created (after every context on it was destroyed).
Status adoptDevice(const AdoptDeviceDesc& desc, Device** out);
// Waits for no device: the host calls it once its GPU work using Canopy has completed.
void releaseDevice(Device* device);

}  // namespace canopy
