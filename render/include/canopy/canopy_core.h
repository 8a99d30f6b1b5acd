#pragma once
// Canopy's core types, shared by the public API (<canopy/canopy.h>, which includes this header) and
// Canopy's own engine: the version, Result and CanopyStatus, the small math types and camera, and the
// host's device (what Canopy needs of it and how it is adopted). C++17, Vulkan's headers only.
#include <cstdint>
#include <functional>
#include <string>
#include <vector>
#include <vulkan/vulkan.h>

// The version this header declares. createCanopy() refuses a library of another major version, or
// an older minor version, naming both; below 1.0 a minor version breaks the API, so 0.x needs the
// library's own minor version (docs/embedding.md "Versions").
#define CANOPY_VERSION_MAJOR 0
#define CANOPY_VERSION_MINOR 8
#define CANOPY_VERSION_PATCH 0
#define CANOPY_MAKE_VERSION(major, minor, patch) ((uint32_t(major) << 22) | (uint32_t(minor) << 12) | uint32_t(patch))
#define CANOPY_HEADER_VERSION CANOPY_MAKE_VERSION(CANOPY_VERSION_MAJOR, CANOPY_VERSION_MINOR, CANOPY_VERSION_PATCH)

namespace canopy {

// ---------------------------------------------------------------------------------------------
// Results

// Names that X11 (Xlib.h's Status, X.h's Success and None) defines as macros are not used by the
// public headers, so they compile after <X11/Xlib.h> in either order; 0.8's names stay as aliases
// where no such macro is defined (CHANGELOG: the migration).
enum class Result : uint32_t {
  Ok = 0,
  InvalidArgument,    // a parameter out of range or inconsistent (the message names it and the range)
  InvalidModel,       // the model file or data is malformed (the message names file and element)
  FileError,          // a file could not be read or written
  UnsupportedDevice,  // the device lacks a required version, extension, feature or format
  OutOfHostMemory,
  OutOfDeviceMemory,
  DeviceLost,
  VersionMismatch,    // header and library versions differ
  VulkanError,        // any other failing Vulkan call (named in the message)
#ifndef Success
  Success = Ok,  // 0.8's name of Ok
#endif
};
// The code's name ("UnsupportedDevice"), for logs.
const char* toString(Result result);

// Empty on success; else a Result and a message ("CanopyDesc.width = 0 is outside [1, 16384]").
class [[nodiscard]] CanopyStatus {
 public:
  CanopyStatus() = default;
  static CanopyStatus error(std::string message) { return error(Result::InvalidArgument, std::move(message)); }
  static CanopyStatus error(Result code, std::string message) {
    CanopyStatus s;
    s.code_ = code == Result::Ok ? Result::InvalidArgument : code;
    s.message_ = std::move(message);
    return s;
  }
  bool ok() const { return code_ == Result::Ok; }
  explicit operator bool() const { return ok(); }
  Result code() const { return code_; }
  const std::string& message() const { return message_; }
  // Prefixes context ("while creating X: ") so the message reads outermost first; keeps the code.
  CanopyStatus context(const std::string& what) const { return ok() ? *this : error(code_, what + ": " + message_); }

 private:
  Result code_ = Result::Ok;
  std::string message_;
};
#ifndef Status
using Status = CanopyStatus;  // 0.8's name of CanopyStatus
#endif

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

// What the projection's clip depth spans (docs/embedding.md "12. Host shapes").
enum class ClipDepth : uint32_t {
  ZeroToOne = 0,         // Vulkan's: depth = z_clip / w_clip (also a GL matrix drawn without depth clip control)
  NegativeOneToOne = 1,  // OpenGL's, drawn with VK_EXT_depth_clip_control's negativeOneToOne: depth =
                         // (z_clip / w_clip + 1) / 2; Canopy converts the matrix to that depth
};

// A camera: the view and projection of a frame (CanopyFrame.camera), as the host draws with them.
struct CanopyCamera {
  Float4x4 view;  // world -> view (right-handed, looking down -Z)
  Float4x4 proj;  // view -> Vulkan clip space (y down), following CanopyDesc.depthConvention; unjittered
  ClipDepth clipDepth = ClipDepth::ZeroToOne;
  // The host's viewport, as it passes it to vkCmdSetViewport: a rectangle of the targets, pixels
  // (a negative height flips y, as in Vulkan); depth 0..1 only. Width and height 0: the whole
  // targets. Canopy draws inside it alone (a scissor of the rectangle, rounded to whole pixels).
  VkViewport viewport{};
  // The frame's sub-pixel jitter (TAA, upscalers), pixels of the targets in [-1, 1], x right, y
  // down: the host's jittered projection moves every point by it, proj_jittered = T(2 jitter.x /
  // width, 2 jitter.y / height) * proj (viewport included). Canopy draws at the jittered position;
  // a jitter alone never re-slices the layers, and the motion vectors Canopy writes exclude it.
  float jitter[2] = {0.0f, 0.0f};
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

// Something Canopy uses when the host enabled it: its exact name and what it is used for.
struct OptionalRequirement {
  std::string name;    // exact: "VK_EXT_debug_utils", "VkPhysicalDeviceVulkan12Features.shaderOutputLayer"
  std::string reason;  // one line: what Canopy does with it
};
// What Canopy needs of the instance, the device and its queue, and what it uses when present
// (docs/embedding.md). Names are exact, to pass to Vulkan as they are; features are
// "Struct.member" of the structures enableDeviceFeatures() fills.
struct DeviceRequirements {
  uint32_t minApiVersion = VK_API_VERSION_1_2;               // of the instance and of the device
  std::vector<std::string> instanceExtensions;               // required instance extensions (none)
  std::vector<OptionalRequirement> optionalInstanceExtensions;  // VK_EXT_debug_utils (debug names)
  std::vector<std::string> deviceExtensions;                 // required: VK_KHR_push_descriptor; below
                                                             // 1.3 also synchronization2 and dynamic rendering
  std::vector<OptionalRequirement> optionalDeviceExtensions;
  std::vector<std::string> features;                         // required
  std::vector<std::vector<std::string>> featuresAnyOf;       // at least one of each group
  std::vector<OptionalRequirement> optionalFeatures;
  VkQueueFlags queueFlags = VK_QUEUE_GRAPHICS_BIT | VK_QUEUE_COMPUTE_BIT;  // one family with all of these
  // The feature structures enableDeviceFeatures() needs in the chain for this API version (and none
  // of a later version: a 1.2 device refuses VkPhysicalDeviceVulkan13Features).
  std::vector<std::string> featureStructs;
};
// Fills `out` for this instance and physical device through the host's loader (works before any
// VkDevice exists), and returns Result::UnsupportedDevice naming everything missing (the API
// version of either, an extension, a feature, a graphics + compute queue family) when they
// cannot run Canopy; `out` is filled either way. `instanceApiVersion` is VkApplicationInfo.apiVersion
// of the host's instance: on 1.3 (instance and device) synchronization2 and dynamic rendering are
// core, below it they are extensions.
CanopyStatus queryDeviceRequirements(PFN_vkGetInstanceProcAddr getInstanceProcAddr, VkInstance instance,
                               uint32_t instanceApiVersion, VkPhysicalDevice physicalDevice, DeviceRequirements* out);
// Switches Canopy's required features, and the optional ones the device supports, on in the host's
// feature chain for a device of `deviceApiVersion` (the version the device will run: the lower of
// VkApplicationInfo.apiVersion and the physical device's). The chain (head VkPhysicalDeviceFeatures2)
// must hold, for 1.3 and later: VkPhysicalDeviceVulkan12Features and VkPhysicalDeviceVulkan13Features;
// for 1.2: VkPhysicalDeviceVulkan12Features, VkPhysicalDeviceSynchronization2Features and
// VkPhysicalDeviceDynamicRenderingFeatures, and no VkPhysicalDeviceVulkan13Features
// (DeviceRequirements.featureStructs lists them). A missing or misplaced structure, or a version
// below 1.2 or above the physical device's, is an error naming it; nothing is allocated.
CanopyStatus enableDeviceFeatures(PFN_vkGetInstanceProcAddr getInstanceProcAddr, VkInstance instance,
                            VkPhysicalDevice physicalDevice, uint32_t deviceApiVersion, VkPhysicalDeviceFeatures2* chain);

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
  // What the device was created with (extensions and the pNext feature chain or pEnabledFeatures).
  // Copied during adoptDevice(): Canopy keeps no pointer into it, so it may live on the caller's
  // stack. Adoption is refused, naming what is missing, when a required extension or feature is
  // not enabled.
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
CanopyStatus adoptDevice(const AdoptDeviceDesc& desc, Device** out);
// Waits for no device: the host calls it once its GPU work using Canopy has completed.
void releaseDevice(Device* device);

}  // namespace canopy
