// Built against an installed Canopy with only <canopy/canopy.h>: creates its own Vulkan device,
// adopts it, builds a model from its own arrays, creates and destroys a context, and checks two
// refusals a host must be able to act on: a device created without Canopy's features, and a
// header version the library does not provide.
#include <canopy/canopy.h>

#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

namespace {

int fail(const char* what, const canopy::Status& s) {
  std::fprintf(stderr, "consumer: %s: %s: %s\n", what, canopy::toString(s.code()), s.message().c_str());
  return 1;
}

}  // namespace

int main() {
  VkApplicationInfo app{VK_STRUCTURE_TYPE_APPLICATION_INFO};
  app.apiVersion = VK_API_VERSION_1_2;
  VkInstanceCreateInfo ici{VK_STRUCTURE_TYPE_INSTANCE_CREATE_INFO};
  ici.pApplicationInfo = &app;
  VkInstance instance = VK_NULL_HANDLE;
  if (vkCreateInstance(&ici, nullptr, &instance) != VK_SUCCESS) return std::fprintf(stderr, "consumer: no instance\n"), 1;
  uint32_t n = 1;
  VkPhysicalDevice pd = VK_NULL_HANDLE;
  vkEnumeratePhysicalDevices(instance, &n, &pd);
  canopy::DeviceRequirements req;
  canopy::Status s = canopy::queryDeviceRequirements(vkGetInstanceProcAddr, instance, app.apiVersion, pd, &req);
  if (!s.ok()) return fail("queryDeviceRequirements", s);

  float priority = 1.0f;
  VkDeviceQueueCreateInfo qci{VK_STRUCTURE_TYPE_DEVICE_QUEUE_CREATE_INFO};
  qci.queueCount = 1;
  qci.pQueuePriorities = &priority;  // family 0: graphics + compute on lavapipe and desktop GPUs
  std::vector<const char*> exts;
  for (const std::string& e : req.deviceExtensions) exts.push_back(e.c_str());
  auto makeDevice = [&](VkPhysicalDeviceFeatures2* features, VkDeviceCreateInfo* dci, VkDevice* out) {
    *dci = VkDeviceCreateInfo{VK_STRUCTURE_TYPE_DEVICE_CREATE_INFO, features};
    dci->queueCreateInfoCount = 1;
    dci->pQueueCreateInfos = &qci;
    dci->enabledExtensionCount = uint32_t(exts.size());
    dci->ppEnabledExtensionNames = exts.data();
    return vkCreateDevice(pd, dci, nullptr, out);
  };
  // What the host hands Canopy about a device it made.
  auto adoptDesc = [&](VkDevice device, const VkDeviceCreateInfo* dci) {
    canopy::AdoptDeviceDesc ad;
    ad.getInstanceProcAddr = vkGetInstanceProcAddr;
    ad.instance = instance;
    ad.instanceApiVersion = app.apiVersion;
    ad.physicalDevice = pd;
    ad.device = device;
    ad.deviceCreateInfo = dci;
    vkGetDeviceQueue(device, 0, 0, &ad.queue);
    return ad;
  };

  // 1. A device without Canopy's features is refused, naming what is missing.
  {
    VkPhysicalDeviceVulkan12Features f12{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_2_FEATURES};
    VkPhysicalDeviceFeatures2 f2{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_FEATURES_2, &f12};
    VkDeviceCreateInfo dci;
    VkDevice bare = VK_NULL_HANDLE;
    if (makeDevice(&f2, &dci, &bare) != VK_SUCCESS) return std::fprintf(stderr, "consumer: no bare device\n"), 1;
    canopy::Device* refused = nullptr;
    s = canopy::adoptDevice(adoptDesc(bare, &dci), &refused);
    vkDestroyDevice(bare, nullptr);
    if (s.ok() || s.code() != canopy::Result::UnsupportedDevice || s.message().find("scalarBlockLayout") == std::string::npos)
      return std::fprintf(stderr, "consumer: a device without scalarBlockLayout was not refused as expected (%s)\n",
                          s.message().c_str()), 1;
    std::printf("consumer: refused as expected: %s\n", s.message().c_str());
  }

  // 2. The real device: features switched on by Canopy in the host's own chain.
  VkPhysicalDeviceDynamicRenderingFeatures dyn{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_DYNAMIC_RENDERING_FEATURES};
  VkPhysicalDeviceSynchronization2Features sync2{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_SYNCHRONIZATION_2_FEATURES, &dyn};
  VkPhysicalDeviceVulkan12Features f12{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_2_FEATURES, &sync2};
  VkPhysicalDeviceFeatures2 f2{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_FEATURES_2, &f12};
  s = canopy::enableDeviceFeatures(vkGetInstanceProcAddr, instance, pd, VK_API_VERSION_1_2, &f2);
  if (!s.ok()) return fail("enableDeviceFeatures", s);
  VkDeviceCreateInfo dci;
  VkDevice device = VK_NULL_HANDLE;
  if (makeDevice(&f2, &dci, &device) != VK_SUCCESS) return std::fprintf(stderr, "consumer: no device\n"), 1;
  canopy::Device* dev = nullptr;
  s = canopy::adoptDevice(adoptDesc(device, &dci), &dev);
  if (!s.ok()) return fail("adoptDevice", s);

  // A small plant from the host's arrays: 200 leaf quads on a ring.
  std::vector<float> pos;
  std::vector<uint32_t> idx;
  for (int i = 0; i < 200; ++i) {
    const float x = float(i % 20) * 0.1f - 1.0f, y = float(i / 20) * 0.2f;
    const float q[12] = {x, y, 0, x + 0.08f, y, 0, x + 0.08f, y + 0.08f, 0.02f, x, y + 0.08f, 0.02f};
    const uint32_t b = uint32_t(pos.size() / 3);
    pos.insert(pos.end(), q, q + 12);
    for (uint32_t k : {0u, 1u, 2u, 0u, 2u, 3u}) idx.push_back(b + k);
  }
  canopy::MeshDesc md;
  md.positions = pos.data();
  md.vertexCount = uint32_t(pos.size() / 3);
  md.indices = idx.data();
  md.indexCount = idx.size();
  canopy::Model* model = nullptr;
  s = canopy::createModel(md, &model);
  if (!s.ok()) return fail("createModel", s);

  canopy::CanopyDesc desc;
  desc.width = 64;
  desc.height = 48;
  canopy::CanopyContext* ctx = nullptr;
  // 3. A header version the library does not provide is refused with both versions named.
  canopy::CanopyDesc future = desc;
  future.headerVersion = CANOPY_MAKE_VERSION(CANOPY_VERSION_MAJOR + 1, 0, 0);
  s = canopy::createCanopy(dev, model, future, &ctx);
  if (s.ok() || s.code() != canopy::Result::VersionMismatch) return std::fprintf(stderr, "consumer: version mismatch not refused\n"), 1;
  std::printf("consumer: refused as expected: %s\n", s.message().c_str());
  // Below 1.0 an older minor version is another API too (docs/embedding.md "Versions").
  if (CANOPY_VERSION_MAJOR == 0 && CANOPY_VERSION_MINOR > 0) {
    canopy::CanopyDesc older = desc;
    older.headerVersion = CANOPY_MAKE_VERSION(CANOPY_VERSION_MAJOR, CANOPY_VERSION_MINOR - 1, 0);
    s = canopy::createCanopy(dev, model, older, &ctx);
    if (s.ok() || s.code() != canopy::Result::VersionMismatch)
      return std::fprintf(stderr, "consumer: an older minor header version not refused\n"), 1;
    std::printf("consumer: refused as expected: %s\n", s.message().c_str());
  }

  s = canopy::createCanopy(dev, model, desc, &ctx);
  canopy::destroyModel(model);
  if (!s.ok()) return fail("createCanopy", s);
  std::printf("consumer: Canopy %u.%u context created on the host's device (%u leaves)\n", CANOPY_VERSION_MAJOR,
              CANOPY_VERSION_MINOR, canopy::canopyStats(ctx).layers.leafCount);
  canopy::destroyCanopy(ctx);
  canopy::releaseDevice(dev);
  vkDestroyDevice(device, nullptr);
  vkDestroyInstance(instance, nullptr);
  return 0;
}
