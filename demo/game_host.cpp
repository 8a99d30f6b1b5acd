// canopy-game-host: a game-like host embedding Canopy through <canopy/canopy.h> alone, the way a
// small engine would (docs/embedding.md): its own instance, device and GLFW window with a
// swapchain, three frames in flight, a D32S8 (else D24S8) depth whose stencil it uses itself (one
// box is outlined through the stencil after Canopy's passes), a ground and boxes, N copies of a
// real glTF plant standing on the ground (CanopyDesc.instances, one vegetation) — or a scene file's
// species and copies in one vegetation (--scene-file: by default the six species of
// ../shared/assets, demo/scenes/six_species.json) — and a first-person camera that walks and looks
// around along a scripted path. The layers are sliced at load time (recordCanopyLoad), as behind a
// loading screen.
//
// Every frame checks itself when its slot comes round again: the host's depth before and after
// Canopy's passes (read back) — no pixel farther after them (Canopy never hides the host's
// geometry behind the vegetation) and the vegetation in front somewhere — and the stencil byte for
// byte unchanged; with --validate, validation and synchronization validation must stay silent.
//
// The sun casts shadows (docs/embedding.md "Shadows"): after each frame the host draws its boxes into
// its own shadow map, then Canopy draws the forest over them (recordCanopyShadow, swaying as the
// leaves on screen); the next frame's ground and boxes sample it (3x3 PCF).
//
//   canopy-game-host [--frames N] [--plants N] [--gltf FILE | --scene-file FILE] [--out DIR] [--write-every K] [--validate]
//                    [--no-push] [--no-leaves]
// Exit 0 when every check passes, 1 on a failure, 2 on bad arguments, 77 without a display.
#include "game_host.h"
#include "host_shadowed.frag.h"
#include "host_shadowed.vert.h"

namespace host {
const char* const kProgram = "canopy-game-host";
}  // namespace host

namespace game {

bool createInstanceAndDevice(Game& g, bool validate) {
  uint32_t n = 0, api = 0;
  const char** glfwExts = glfwGetRequiredInstanceExtensions(&n);
  HOST_CHECK(host::createInstance(host::kProgram, std::vector<const char*>(glfwExts, glfwExts + n), validate, &g.validationMessages, &api,
                             &g.instance, &g.messenger));
  HOST_CHECK(glfwCreateWindowSurface(g.instance, g.window, nullptr, &g.surface));
  // The first device Canopy can run on that presents to the window (queryDeviceRequirements says why not).
  if (!host::createHostDevice(g.instance, api, g.surface, {VK_KHR_SWAPCHAIN_EXTENSION_NAME}, &g.dev)) return false;
  // Depth with a stencil the host uses: D32S8, else D24S8, as a sampled depth attachment.
  for (VkFormat f : {VK_FORMAT_D32_SFLOAT_S8_UINT, VK_FORMAT_D24_UNORM_S8_UINT}) {
    VkFormatProperties fp;
    vkGetPhysicalDeviceFormatProperties(g.dev.physical, f, &fp);
    const VkFormatFeatureFlags need = VK_FORMAT_FEATURE_DEPTH_STENCIL_ATTACHMENT_BIT | VK_FORMAT_FEATURE_SAMPLED_IMAGE_BIT |
                                      VK_FORMAT_FEATURE_TRANSFER_SRC_BIT;
    if (!g.depthFormat && (fp.optimalTilingFeatures & need) == need) g.depthFormat = f;
  }
  if (!g.depthFormat) {
    std::fprintf(stderr, "canopy-game-host: no sampled depth-stencil format\n");
    return false;
  }
  if (!host::adoptHostDevice(g.dev, g.instance, api, kFrames, nullptr, &g.adopted)) return false;
  const uint32_t deviceApi = g.dev.apiVersion;
  std::printf("canopy-game-host: %s, Vulkan %u.%u, depth format %d, %u frames in flight\n", g.dev.name.c_str(),
              VK_API_VERSION_MAJOR(deviceApi), VK_API_VERSION_MINOR(deviceApi), int(g.depthFormat), kFrames);
  return true;
}

bool createSwapchain(Game& g) {
  uint32_t n = 0;
  vkGetPhysicalDeviceSurfaceFormatsKHR(g.dev.physical, g.surface, &n, nullptr);
  std::vector<VkSurfaceFormatKHR> formats(n);
  vkGetPhysicalDeviceSurfaceFormatsKHR(g.dev.physical, g.surface, &n, formats.data());
  VkSurfaceFormatKHR chosen = formats.at(0);
  for (const VkSurfaceFormatKHR& f : formats)
    if (f.format == VK_FORMAT_B8G8R8A8_UNORM || f.format == VK_FORMAT_R8G8B8A8_UNORM) chosen = f;
  VkSurfaceCapabilitiesKHR caps;
  HOST_CHECK(vkGetPhysicalDeviceSurfaceCapabilitiesKHR(g.dev.physical, g.surface, &caps));
  VkSwapchainCreateInfoKHR sci{VK_STRUCTURE_TYPE_SWAPCHAIN_CREATE_INFO_KHR};
  sci.surface = g.surface;
  sci.minImageCount = std::max(caps.minImageCount, kFrames);
  if (caps.maxImageCount) sci.minImageCount = std::min(sci.minImageCount, caps.maxImageCount);
  sci.imageFormat = chosen.format;
  sci.imageColorSpace = chosen.colorSpace;
  sci.imageExtent = caps.currentExtent.width != UINT32_MAX ? caps.currentExtent : VkExtent2D{kW, kH};
  sci.imageArrayLayers = 1;
  sci.imageUsage = VK_IMAGE_USAGE_TRANSFER_DST_BIT;  // the host's frame is blitted in
  sci.preTransform = caps.currentTransform;
  sci.compositeAlpha = VK_COMPOSITE_ALPHA_OPAQUE_BIT_KHR;
  sci.presentMode = VK_PRESENT_MODE_FIFO_KHR;
  sci.clipped = VK_TRUE;
  HOST_CHECK(vkCreateSwapchainKHR(g.dev.device, &sci, nullptr, &g.swapchain));
  g.swapFormat = chosen.format;
  vkGetSwapchainImagesKHR(g.dev.device, g.swapchain, &n, nullptr);
  g.swapImages.resize(n);
  vkGetSwapchainImagesKHR(g.dev.device, g.swapchain, &n, g.swapImages.data());
  g.presentReady.resize(n);
  for (VkSemaphore& s : g.presentReady) {
    VkSemaphoreCreateInfo si{VK_STRUCTURE_TYPE_SEMAPHORE_CREATE_INFO};
    HOST_CHECK(vkCreateSemaphore(g.dev.device, &si, nullptr, &s));
  }
  std::printf("swapchain %ux%u, %u images\n", sci.imageExtent.width, sci.imageExtent.height, n);
  return true;
}

// The outline pipeline (no depth test, drawn where the stencil is not the outlined box's); the
// scene's own (shadowed) is createShadows'.
bool createPipelines(Game& g) {
  HOST_CHECK(host::createBoxLayout(g.dev.device, &g.layout));
  VkPipelineDepthStencilStateCreateInfo ds = host::depthTested(VK_COMPARE_OP_LESS);
  ds.stencilTestEnable = VK_TRUE;
  ds.depthTestEnable = ds.depthWriteEnable = VK_FALSE;
  ds.front = {VK_STENCIL_OP_KEEP, VK_STENCIL_OP_KEEP, VK_STENCIL_OP_KEEP, VK_COMPARE_OP_NOT_EQUAL, 0xff, 0, 0};
  ds.back = ds.front;
  HOST_CHECK(host::createBoxPipeline(g.dev.device, g.layout, kColorFormat, g.depthFormat, g.depthFormat, ds, true, &g.outline));
  return true;
}

// The shadow map, its sampler and descriptor set, the shadowed scene pipeline (depth LESS, the
// stencil written from a dynamic reference, the map sampled) and the casters' depth-only pipeline (host_box.vert alone) into the map.
bool createShadows(Game& g) {
  HOST_CHECK(host::createImage(g.dev.device, g.dev.memory, kShadowSize, kShadowSize, VK_FORMAT_D32_SFLOAT,
                               VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT | VK_IMAGE_USAGE_SAMPLED_BIT | VK_IMAGE_USAGE_TRANSFER_DST_BIT,
                               VK_IMAGE_ASPECT_DEPTH_BIT, &g.shadowMap));
  VkSamplerCreateInfo si{VK_STRUCTURE_TYPE_SAMPLER_CREATE_INFO};
  si.magFilter = si.minFilter = VK_FILTER_NEAREST;
  si.addressModeU = si.addressModeV = si.addressModeW = VK_SAMPLER_ADDRESS_MODE_CLAMP_TO_EDGE;
  HOST_CHECK(vkCreateSampler(g.dev.device, &si, nullptr, &g.shadowSampler));
  VkDescriptorSetLayoutBinding b{0, VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, 1, VK_SHADER_STAGE_FRAGMENT_BIT, nullptr};
  VkDescriptorSetLayoutCreateInfo li{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_LAYOUT_CREATE_INFO};
  li.bindingCount = 1;
  li.pBindings = &b;
  HOST_CHECK(vkCreateDescriptorSetLayout(g.dev.device, &li, nullptr, &g.shadowSetLayout));
  VkDescriptorPoolSize ps{VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, 1};
  VkDescriptorPoolCreateInfo pi{VK_STRUCTURE_TYPE_DESCRIPTOR_POOL_CREATE_INFO};
  pi.maxSets = 1;
  pi.poolSizeCount = 1;
  pi.pPoolSizes = &ps;
  HOST_CHECK(vkCreateDescriptorPool(g.dev.device, &pi, nullptr, &g.shadowPool));
  VkDescriptorSetAllocateInfo ai{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_ALLOCATE_INFO};
  ai.descriptorPool = g.shadowPool;
  ai.descriptorSetCount = 1;
  ai.pSetLayouts = &g.shadowSetLayout;
  HOST_CHECK(vkAllocateDescriptorSets(g.dev.device, &ai, &g.shadowSet));
  VkDescriptorImageInfo ii{g.shadowSampler, g.shadowMap.view, VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL};
  VkWriteDescriptorSet w{VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET};
  w.dstSet = g.shadowSet;
  w.descriptorCount = 1;
  w.descriptorType = VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER;
  w.pImageInfo = &ii;
  vkUpdateDescriptorSets(g.dev.device, 1, &w, 0, nullptr);
  VkPushConstantRange range{VK_SHADER_STAGE_VERTEX_BIT, 0, 2 * sizeof(glm::mat4)};
  VkPipelineLayoutCreateInfo pl{VK_STRUCTURE_TYPE_PIPELINE_LAYOUT_CREATE_INFO};
  pl.setLayoutCount = 1;
  pl.pSetLayouts = &g.shadowSetLayout;
  pl.pushConstantRangeCount = 1;
  pl.pPushConstantRanges = &range;
  HOST_CHECK(vkCreatePipelineLayout(g.dev.device, &pl, nullptr, &g.shadedLayout));
  VkPipelineDepthStencilStateCreateInfo ds = host::depthTested(VK_COMPARE_OP_LESS);
  ds.stencilTestEnable = VK_TRUE;
  ds.front = {VK_STENCIL_OP_KEEP, VK_STENCIL_OP_REPLACE, VK_STENCIL_OP_KEEP, VK_COMPARE_OP_ALWAYS, 0xff, 0xff, 0};
  ds.back = ds.front;
  HOST_CHECK(host::createHostPipeline(g.dev.device, g.shadedLayout,
                                      {host_shadowed_vert, sizeof(host_shadowed_vert), host_shadowed_frag, sizeof(host_shadowed_frag)},
                                      kColorFormat, g.depthFormat, g.depthFormat, ds, true, &g.shaded));
  HOST_CHECK(host::createHostPipeline(g.dev.device, g.layout, {host_box_vert, sizeof(host_box_vert), nullptr, 0}, VK_FORMAT_UNDEFINED,
                                      VK_FORMAT_D32_SFLOAT, VK_FORMAT_UNDEFINED, host::depthTested(VK_COMPARE_OP_LESS_OR_EQUAL), false,
                                      &g.casters));
  return true;
}

bool createFrames(Game& g) {
  HOST_CHECK(host::createCommandPool(g.dev.device, g.dev.family, &g.pool));
  const VkDeviceSize bytes = VkDeviceSize(kW) * kH * (4 + 4 + 1 + 1 + 4) + VkDeviceSize(kLeaves) * 32;
  for (Slot& s : g.slots) {
    HOST_CHECK(host::createFrameSlot(g.dev.device, g.pool, &s.cmd, &s.fence));
    VkSemaphoreCreateInfo si{VK_STRUCTURE_TYPE_SEMAPHORE_CREATE_INFO};
    HOST_CHECK(vkCreateSemaphore(g.dev.device, &si, nullptr, &s.acquired));
    VkBufferCreateInfo bci{VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO};
    bci.size = bytes;
    bci.usage = VK_BUFFER_USAGE_TRANSFER_DST_BIT;
    HOST_CHECK(vkCreateBuffer(g.dev.device, &bci, nullptr, &s.readback.buffer));
    VkMemoryRequirements req;
    vkGetBufferMemoryRequirements(g.dev.device, s.readback.buffer, &req);
    VkMemoryAllocateInfo mai{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO};
    mai.allocationSize = req.size;
    const int32_t type = host::memoryType(g.dev.memory, req.memoryTypeBits, VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT);
    if (type < 0) return false;
    mai.memoryTypeIndex = uint32_t(type);
    HOST_CHECK(vkAllocateMemory(g.dev.device, &mai, nullptr, &s.readback.memory));
    HOST_CHECK(vkBindBufferMemory(g.dev.device, s.readback.buffer, s.readback.memory, 0));
    HOST_CHECK(vkMapMemory(g.dev.device, s.readback.memory, 0, VK_WHOLE_SIZE, 0, reinterpret_cast<void**>(&s.readback.mapped)));
  }
  return true;
}


// Depth and stencil of the host's target into the slot's readback at byte `at` (depth) and `sAt`.
void copyDepthStencil(Game& g, VkCommandBuffer cmd, Slot& s, VkDeviceSize at, VkDeviceSize sAt) {
  VkBufferImageCopy c{};
  c.imageExtent = {kW, kH, 1};
  c.bufferOffset = at;
  c.imageSubresource = {VK_IMAGE_ASPECT_DEPTH_BIT, 0, 0, 1};
  vkCmdCopyImageToBuffer(cmd, g.depth.image, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, s.readback.buffer, 1, &c);
  c.bufferOffset = sAt;
  c.imageSubresource = {VK_IMAGE_ASPECT_STENCIL_BIT, 0, 0, 1};
  vkCmdCopyImageToBuffer(cmd, g.depth.image, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, s.readback.buffer, 1, &c);
}

void drawBoxes(Game& g, VkCommandBuffer cmd, VkPipeline pipeline, bool clear, const std::vector<std::pair<BoxPush, uint32_t>>& boxes) {
  host::beginBoxPass(cmd, g.color.view, g.depth.view, true, clear, {{0.55f, 0.7f, 0.9f, 1.0f}}, 1.0f, kW, kH, pipeline);
  for (const auto& [b, stencil] : boxes) {
    vkCmdSetStencilReference(cmd, VK_STENCIL_FACE_FRONT_AND_BACK, stencil);
    vkCmdPushConstants(cmd, g.layout, VK_SHADER_STAGE_VERTEX_BIT | VK_SHADER_STAGE_FRAGMENT_BIT, 0, sizeof b, &b);
    vkCmdDraw(cmd, 36, 1, 0, 0);
  }
  vkCmdEndRendering(cmd);
}

// Checks the slot's last frame (its readback is complete once its fence was waited for).
void checkSlot(Game& g, Slot& s) {
  const size_t n = size_t(kW) * kH;
  const float* before = reinterpret_cast<const float*>(s.readback.mapped);
  const float* after = before + n;
  const uint8_t* sBefore = s.readback.mapped + 8 * n;
  const uint8_t* sAfter = sBefore + n;
  const uint8_t* rgba = sAfter + n;
  auto depthOf = [&](const float* z, size_t i) {
    if (g.depthFormat != VK_FORMAT_D24_UNORM_S8_UINT) return z[i];
    uint32_t raw;
    std::memcpy(&raw, &z[i], 4);
    return float(raw & 0xffffff) / float(0xffffff);
  };
  uint64_t farther = 0, nearer = 0, stencil = 0;
  for (size_t i = 0; i < n; ++i) {
    const float a = depthOf(before, i), b = depthOf(after, i);
    farther += b > a + 1e-6f;
    nearer += b < a - 1e-6f;
    stencil += sBefore[i] != sAfter[i];
  }
  // The leaves of that frame against the wind sampleCanopyWind reads at their places now (a copy
  // framesInFlight frames late): along the wind plane's right axis.
  const float* leaves = reinterpret_cast<const float*>(rgba + 4 * n);
  std::vector<canopy::Float3> at(kLeaves), wind(kLeaves);
  for (uint32_t i = 0; i < kLeaves; ++i) at[i] = {leaves[8 * i], leaves[8 * i + 1], leaves[8 * i + 2]};
  canopy::CanopyWind info;
  uint64_t fieldFrame = 0;
  if (canopy::sampleCanopyWind(g.ctx, at.data(), at.size(), wind.data(), &fieldFrame).ok() && fieldFrame > 0 &&
      canopy::canopyWind(g.ctx, &info).ok()) {
    const glm::vec3 axis(info.info.right[0], info.info.right[1], info.info.right[2]);
    for (uint32_t i = 0; i < kLeaves; ++i) {
      const double x = glm::dot(axis, glm::vec3(leaves[8 * i + 4], leaves[8 * i + 5], leaves[8 * i + 6]));
      const double y = glm::dot(axis, glm::vec3(wind[i].x, wind[i].y, wind[i].z));
      g.sx += x, g.sy += y, g.sxx += x * x, g.syy += y * y, g.sxy += x * y;
      g.leafSamples++;
    }
  }
  g.fartherPixels += farther;
  g.stencilChanged += stencil;
  g.checkedFrames++;
  g.framesWithVegetationInFront += nearer > n / 100;
  if (farther || stencil)
    std::fprintf(stderr, "canopy-game-host: frame %llu: %llu pixels farther after Canopy, %llu stencil bytes changed\n",
                 (unsigned long long)s.frame, (unsigned long long)farther, (unsigned long long)stencil);
  if (s.write && !g.outDir.empty()) {
    char name[64];
    std::snprintf(name, sizeof name, "/frame_%04llu.ppm", (unsigned long long)s.frame);
    std::ofstream o(g.outDir + name, std::ios::binary);
    o << "P6\n" << kW << " " << kH << "\n255\n";
    for (size_t i = 0; i < n; ++i) o.write(reinterpret_cast<const char*>(rgba + 4 * i), 3);
    // The band the character's push may reach: pixels whose world point (the depth after Canopy)
    // lies within 3 radii, horizontally, of where it has walked (255), the others 0.
    std::snprintf(name, sizeof name, "/band_%04llu.pgm", (unsigned long long)s.frame);
    std::ofstream m(g.outDir + name, std::ios::binary);
    m << "P5\n" << kW << " " << kH << "\n255\n";
    for (size_t i = 0; i < n; ++i) {
      const float x = (float(i % kW) + 0.5f) / float(kW) * 2.0f - 1.0f, y = (float(i / kW) + 0.5f) / float(kH) * 2.0f - 1.0f;
      const glm::vec4 w = s.invViewProj * glm::vec4(x, y, depthOf(after, i), 1.0f);
      const glm::vec2 at = glm::vec2(w.x, w.z) / w.w;
      bool near = false;
      for (size_t k = 0; k < s.walked && k < g.walked.size() && !near; ++k)
        near = glm::length(at - glm::vec2(g.walked[k])) <= 3.0f * g.walked[k].z;
      m.put(near ? char(255) : char(0));
    }
  }
}

bool wait(Game& g, Slot& s) {
  if (!s.pending) return true;
  HOST_CHECK(vkWaitForFences(g.dev.device, 1, &s.fence, VK_TRUE, UINT64_MAX));
  HOST_CHECK(vkResetFences(g.dev.device, 1, &s.fence));
  s.pending = false;
  checkSlot(g, s);
  return true;
}

// The sun's shadow map for the next frame: the host's boxes (its own casters), then the forest
// over them, each leaf where this frame shows it (recordCanopyShadow).
bool drawShadowMap(Game& g, const Scene& sc, VkCommandBuffer cmd) {
  barrier(cmd, g.shadowMap.image, VK_IMAGE_ASPECT_DEPTH_BIT, VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL,
          VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL, VK_PIPELINE_STAGE_2_FRAGMENT_SHADER_BIT, VK_ACCESS_2_SHADER_SAMPLED_READ_BIT,
          kDepthStage, kDepthAccess);
  {
    VkRenderingAttachmentInfo z{VK_STRUCTURE_TYPE_RENDERING_ATTACHMENT_INFO};
    z.imageView = g.shadowMap.view;
    z.imageLayout = VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL;
    z.loadOp = VK_ATTACHMENT_LOAD_OP_CLEAR;
    z.storeOp = VK_ATTACHMENT_STORE_OP_STORE;
    z.clearValue.depthStencil = {1.0f, 0};
    VkRenderingInfo ri{VK_STRUCTURE_TYPE_RENDERING_INFO};
    ri.renderArea = {{0, 0}, {kShadowSize, kShadowSize}};
    ri.layerCount = 1;
    ri.pDepthAttachment = &z;
    vkCmdBeginRendering(cmd, &ri);
    const VkViewport v{0, 0, float(kShadowSize), float(kShadowSize), 0, 1};
    const VkRect2D area{{0, 0}, {kShadowSize, kShadowSize}};
    vkCmdSetViewport(cmd, 0, 1, &v);
    vkCmdSetScissor(cmd, 0, 1, &area);
    vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, g.casters);
    for (const glm::mat4& b : sc.boxes) {
      const BoxPush push{g.light * b, glm::vec4(0.0f)};
      vkCmdPushConstants(cmd, g.layout, VK_SHADER_STAGE_VERTEX_BIT | VK_SHADER_STAGE_FRAGMENT_BIT, 0, sizeof push, &push);
      vkCmdDraw(cmd, 36, 1, 0, 0);
    }
    vkCmdEndRendering(cmd);
  }
  canopy::CanopyShadowInputs shadow;
  shadow.depth = canopy::canopyImage(
      g.shadowMap.image, g.shadowMap.view,
      VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT | VK_IMAGE_USAGE_SAMPLED_BIT | VK_IMAGE_USAGE_TRANSFER_DST_BIT, VK_FORMAT_D32_SFLOAT,
      {kDepthStage, kDepthAccess, VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL},
      {VK_PIPELINE_STAGE_2_FRAGMENT_SHADER_BIT, VK_ACCESS_2_SHADER_SAMPLED_READ_BIT, VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL});
  shadow.width = shadow.height = kShadowSize;
  shadow.lightViewProj = toCanopy(g.light);
  shadow.clear = false;  // over the boxes the host drew
  bool updated = false;
  const canopy::Status shadowStatus = canopy::recordCanopyShadow(g.ctx, cmd, shadow, &updated);
  if (!shadowStatus.ok()) {
    std::fprintf(stderr, "canopy-game-host: %s\n", shadowStatus.message().c_str());
    return false;
  }
  g.shadowUpdates += updated;
  return true;
}

// The frame's end: depth, stencil and colour after Canopy into the slot's readback, the colour
// blitted into the swapchain image, the submission and the present.
bool finishFrame(Game& g, Slot& s, VkCommandBuffer cmd, uint32_t image) {
  const VkImageAspectFlags ds = VK_IMAGE_ASPECT_DEPTH_BIT | VK_IMAGE_ASPECT_STENCIL_BIT;
  const VkDeviceSize n = VkDeviceSize(kW) * kH;
  barrier(cmd, g.depth.image, ds, VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, kDepthStage,
          kDepthAccess, kCopy, VK_ACCESS_2_TRANSFER_READ_BIT);
  copyDepthStencil(g, cmd, s, 4 * n, 9 * n);
  barrier(cmd, g.color.image, VK_IMAGE_ASPECT_COLOR_BIT, VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL,
          kColorStage, kColorAccess, kCopy, VK_ACCESS_2_TRANSFER_READ_BIT);
  VkBufferImageCopy c{};
  c.bufferOffset = 10 * n;
  c.imageExtent = {kW, kH, 1};
  c.imageSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1};
  vkCmdCopyImageToBuffer(cmd, g.color.image, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, s.readback.buffer, 1, &c);
  const VkImage swap = g.swapImages[image];
  barrier(cmd, swap, VK_IMAGE_ASPECT_COLOR_BIT, VK_IMAGE_LAYOUT_UNDEFINED, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, kCopy,
          VK_ACCESS_2_NONE, kCopy, VK_ACCESS_2_TRANSFER_WRITE_BIT);
  VkImageBlit blit{};
  blit.srcSubresource = blit.dstSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1};
  blit.srcOffsets[1] = {int32_t(kW), int32_t(kH), 1};
  blit.dstOffsets[1] = {int32_t(kW), int32_t(kH), 1};
  vkCmdBlitImage(cmd, g.color.image, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, swap, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, 1, &blit,
                 VK_FILTER_NEAREST);
  barrier(cmd, swap, VK_IMAGE_ASPECT_COLOR_BIT, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, VK_IMAGE_LAYOUT_PRESENT_SRC_KHR, kCopy,
          VK_ACCESS_2_TRANSFER_WRITE_BIT, VK_PIPELINE_STAGE_2_NONE, VK_ACCESS_2_NONE);
  // The readback for the host (after the fence).
  VkMemoryBarrier2 hostRead{VK_STRUCTURE_TYPE_MEMORY_BARRIER_2};
  hostRead.srcStageMask = kCopy;
  hostRead.srcAccessMask = VK_ACCESS_2_TRANSFER_WRITE_BIT;
  hostRead.dstStageMask = VK_PIPELINE_STAGE_2_HOST_BIT;
  hostRead.dstAccessMask = VK_ACCESS_2_HOST_READ_BIT;
  VkDependencyInfo di{VK_STRUCTURE_TYPE_DEPENDENCY_INFO};
  di.memoryBarrierCount = 1;
  di.pMemoryBarriers = &hostRead;
  vkCmdPipelineBarrier2(cmd, &di);
  HOST_CHECK(vkEndCommandBuffer(cmd));
  const VkPipelineStageFlags waitStage = VK_PIPELINE_STAGE_TRANSFER_BIT;
  VkSubmitInfo si{VK_STRUCTURE_TYPE_SUBMIT_INFO};
  si.waitSemaphoreCount = 1;
  si.pWaitSemaphores = &s.acquired;
  si.pWaitDstStageMask = &waitStage;
  si.commandBufferCount = 1;
  si.pCommandBuffers = &cmd;
  si.signalSemaphoreCount = 1;
  si.pSignalSemaphores = &g.presentReady[image];
  HOST_CHECK(vkQueueSubmit(g.dev.queue, 1, &si, s.fence));
  s.pending = true;
  VkPresentInfoKHR pi{VK_STRUCTURE_TYPE_PRESENT_INFO_KHR};
  pi.waitSemaphoreCount = 1;
  pi.pWaitSemaphores = &g.presentReady[image];
  pi.swapchainCount = 1;
  pi.pSwapchains = &g.swapchain;
  pi.pImageIndices = &image;
  const VkResult pr = vkQueuePresentKHR(g.dev.queue, &pi);
  if (pr != VK_SUCCESS && pr != VK_SUBOPTIMAL_KHR) HOST_CHECK(pr);
  return true;
}

bool frame(Game& g, const Scene& sc, uint64_t number, uint32_t index, uint32_t frames, bool write) {
  Slot& s = g.slots[number % kFrames];
  if (!wait(g, s)) return false;
  uint32_t image = 0;
  HOST_CHECK(vkAcquireNextImageKHR(g.dev.device, g.swapchain, UINT64_MAX, s.acquired, VK_NULL_HANDLE, &image));
  s.frame = number;
  s.write = write;
  const glm::mat4 view = walkView(sc, index, frames);
  const glm::mat4 proj = walkProjection();
  const glm::mat4 vp = proj * view;
  VkCommandBuffer cmd = s.cmd;
  VkCommandBufferBeginInfo bi{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
  bi.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
  HOST_CHECK(vkBeginCommandBuffer(cmd, &bi));
  const VkImageAspectFlags ds = VK_IMAGE_ASPECT_DEPTH_BIT | VK_IMAGE_ASPECT_STENCIL_BIT;
  // The previous frame's last uses (copies and the blit) before this frame overwrites the targets.
  barrier(cmd, g.color.image, VK_IMAGE_ASPECT_COLOR_BIT, VK_IMAGE_LAYOUT_UNDEFINED, VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL, kCopy,
          VK_ACCESS_2_TRANSFER_READ_BIT, kColorStage, kColorAccess);
  barrier(cmd, g.depth.image, ds, VK_IMAGE_LAYOUT_UNDEFINED, VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL, kCopy,
          VK_ACCESS_2_TRANSFER_READ_BIT, kDepthStage, kDepthAccess);
  // The sun's shadow map, once: cleared (nothing casts yet) into the state the scene samples it in.
  if (!g.shadowReady) {
    barrier(cmd, g.shadowMap.image, VK_IMAGE_ASPECT_DEPTH_BIT, VK_IMAGE_LAYOUT_UNDEFINED, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL,
            VK_PIPELINE_STAGE_2_NONE, VK_ACCESS_2_NONE, kCopy, VK_ACCESS_2_TRANSFER_WRITE_BIT);
    const VkClearDepthStencilValue far{1.0f, 0};
    const VkImageSubresourceRange range{VK_IMAGE_ASPECT_DEPTH_BIT, 0, 1, 0, 1};
    vkCmdClearDepthStencilImage(cmd, g.shadowMap.image, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, &far, 1, &range);
    barrier(cmd, g.shadowMap.image, VK_IMAGE_ASPECT_DEPTH_BIT, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL,
            kCopy, VK_ACCESS_2_TRANSFER_WRITE_BIT, VK_PIPELINE_STAGE_2_FRAGMENT_SHADER_BIT, VK_ACCESS_2_SHADER_SAMPLED_READ_BIT);
    g.shadowReady = true;
  }
  // The host's opaque scene: ground and boxes in the sun's light and the forest's and boxes'
  // shadows (the map the previous frame drew), the outlined box writing its stencil value.
  struct Placed {
    glm::mat4 model;
    uint32_t color, stencil;  // host_shadowed.vert's colour index; the stencil value
  };
  std::vector<Placed> placed;
  const float w = sc.half * 2.0f + sc.spacing;
  placed.push_back({glm::scale(glm::translate(glm::mat4(1.0f), glm::vec3(0, -0.05f, 0)), glm::vec3(w, 0.1f, w)), 0u, 0u});
  for (size_t i = 0; i < sc.boxes.size(); ++i) placed.push_back({sc.boxes[i], i == 0 ? 1u : 2u, i == 0 ? uint32_t(kOutlined) : 0u});
  // The character, drawn as a box around its capsule, and given to Canopy as a pusher.
  const canopy::CanopyPusher walker = character(sc, index, frames);
  const glm::vec3 ca(walker.a.x, walker.a.y, walker.a.z), cb(walker.b.x, walker.b.y, walker.b.z);
  placed.push_back({glm::scale(glm::translate(glm::mat4(1.0f), 0.5f * (ca + cb)),
                               glm::vec3(2.0f * walker.radius, cb.y - ca.y + 2.0f * walker.radius, 2.0f * walker.radius)),
                    1u, 0u});
  {
    const glm::vec3 mid = 0.5f * (ca + cb);
    const glm::vec4 q = vp * glm::vec4(mid, 1.0f);
    const float depth = -(view * glm::vec4(mid, 1.0f)).z;
    char line[96];
    std::snprintf(line, sizeof line, "%llu %.2f %.2f %.2f\n", (unsigned long long)number, double((q.x / q.w * 0.5f + 0.5f) * kW),
                  double((q.y / q.w * 0.5f + 0.5f) * kH), double(walker.radius * std::abs(proj[1][1]) * 0.5f * kH / std::max(depth, 1e-4f)));
    g.characterPath += line;
  }
  g.walked.push_back(glm::vec4(0.5f * (ca.x + cb.x), 0.5f * (ca.z + cb.z), walker.radius, 0.0f));
  s.walked = g.walked.size();
  s.invViewProj = glm::inverse(vp);
  const canopy::Status pushed = canopy::setCanopyPushers(g.ctx, g.push ? std::vector<canopy::CanopyPusher>{walker}
                                                                       : std::vector<canopy::CanopyPusher>{});
  if (!pushed.ok()) {
    std::fprintf(stderr, "canopy-game-host: %s\n", pushed.message().c_str());
    return false;
  }
  host::beginBoxPass(cmd, g.color.view, g.depth.view, true, true, {{0.55f, 0.7f, 0.9f, 1.0f}}, 1.0f, kW, kH, g.shaded);
  vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, g.shadedLayout, 0, 1, &g.shadowSet, 0, nullptr);
  for (const Placed& p : placed) {
    const glm::mat4 push[2] = {vp * p.model, g.light * p.model};
    vkCmdSetStencilReference(cmd, VK_STENCIL_FACE_FRONT_AND_BACK, p.stencil);
    vkCmdPushConstants(cmd, g.shadedLayout, VK_SHADER_STAGE_VERTEX_BIT, 0, sizeof push, push);
    vkCmdDraw(cmd, 36, 1, 0, p.color);
  }
  vkCmdEndRendering(cmd);
  // Depth and stencil before Canopy (the self-check).
  barrier(cmd, g.depth.image, ds, VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, kDepthStage,
          kDepthAccess, kCopy, VK_ACCESS_2_TRANSFER_READ_BIT);
  const VkDeviceSize n = VkDeviceSize(kW) * kH;
  copyDepthStencil(g, cmd, s, 0, 8 * n);
  // Canopy, outside any render pass; the host's images as they arrive and as it wants them back.
  canopy::CanopyFrameInputs in;
  in.frame.camera = {toCanopy(view), toCanopy(proj)};
  in.frame.dt = 1.0f / 30.0f;
  in.frame.frameNumber = number;
  const canopy::ResourceState colorState{kColorStage, kColorAccess, VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL},
      depthArrives{kCopy, VK_ACCESS_2_TRANSFER_READ_BIT, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL},
      depthLeaves{kDepthStage, kDepthAccess, VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL};
  in.color = canopy::canopyImage(g.color.image, g.color.view, kColorUsage, kColorFormat, colorState, colorState);
  in.depth = canopy::canopyImage(g.depth.image, g.depth.depthOnly, kDepthUsage, g.depthFormat, depthArrives, depthLeaves);
  const canopy::Status st = canopy::recordCanopy(g.ctx, cmd, in);
  if (!st.ok()) {
    std::fprintf(stderr, "canopy-game-host: %s\n", st.message().c_str());
    return false;
  }
  g.characterMapped += canopy::canopyStats(g.ctx).pushersMapped == (g.push ? 1u : 0u);
  // The outline of box 0, where the stencil is not its own: the stencil survived Canopy's passes.
  const glm::mat4 grown = sc.boxes[0] * glm::scale(glm::mat4(1.0f), glm::vec3(1.12f));
  drawBoxes(g, cmd, g.outline, false, {{{vp * grown, glm::vec4(1.0f, 0.85f, 0.1f, 1)}, uint32_t(kOutlined)}});
  // The falling leaves: moved by this frame's wind, then drawn over the scene.
  if (!recordLeaves(g, sc, s, cmd, number, view, vp)) return false;
  if (!drawShadowMap(g, sc, cmd)) return false;
  return finishFrame(g, s, cmd, image);
}

// A scene file's species (glTF files; a generated species needs canopy-demo's generator) and copies,
// centred on the origin for the walk; the walk's lanes and the boxes from the copies' extent.
bool makeSceneFromFile(const std::string& path, std::vector<canopy::Model*>* models, std::vector<canopy::CanopySpecies>* species,
                       canopy::CanopyDesc* desc, Scene* s) {
  canopy::CanopyScene file;
  canopy::Status st = canopy::readCanopyScene(path, &file);
  for (size_t i = 0; st.ok() && i < file.species.size(); ++i) {
    const canopy::CanopySceneSpecies& sp = file.species[i];
    if (sp.gltf.empty()) {
      st = canopy::Status::error(path + ": species '" + sp.name + "' is generated; this host loads glTF files only (canopy-demo "
                                 "--scene-file makes generated plants)");
      break;
    }
    canopy::Model* m = nullptr;
    st = canopy::loadModel(sp.gltf, {}, &m);
    if (!st.ok()) break;
    models->push_back(m);
    species->push_back({m, sp.flexibility, sp.responseSpeed});
  }
  if (st.ok()) st = canopy::canopySceneInstances(file, {models->begin(), models->end()}, &desc->instances);
  if (!st.ok()) {
    std::fprintf(stderr, "canopy-game-host: %s\n", st.message().c_str());
    return false;
  }
  glm::vec3 lo(INFINITY), hi(-INFINITY);
  float tallest = 0.0f;
  for (const canopy::CanopyInstance& c : desc->instances) {
    canopy::Float3 a, b;
    canopy::modelBounds((*models)[c.species], &a, &b);
    glm::mat4 t;
    std::memcpy(&t, c.transform.m, sizeof t);
    for (int k = 0; k < 8; ++k) {
      const glm::vec3 p(t * glm::vec4((k & 1) ? b.x : a.x, (k & 2) ? b.y : a.y, (k & 4) ? b.z : a.z, 1.0f));
      lo = glm::min(lo, p);
      hi = glm::max(hi, p);
    }
    tallest = std::max(tallest, (t * glm::vec4(0, b.y, 0, 1)).y - (t * glm::vec4(0, a.y, 0, 1)).y);
  }
  const glm::vec3 centre(0.5f * (lo.x + hi.x), 0.0f, 0.5f * (lo.z + hi.z));
  for (canopy::CanopyInstance& c : desc->instances) {
    glm::mat4 t;
    std::memcpy(&t, c.transform.m, sizeof t);
    c.transform = toCanopy(glm::translate(glm::mat4(1.0f), -centre) * t);
  }
  const float extent = std::max(hi.x - lo.x, hi.z - lo.z);
  s->plantMin = glm::vec3(0.0f);
  s->plantMax = glm::vec3(1.0f, std::min(tallest, 4.0f), 1.0f);  // eye height 0.45 of it
  s->spacing = extent / 6.0f;
  s->half = 0.5f * extent;
  s->corridor = glm::vec2(-0.5f * s->spacing, 0.0f);
  const float b = 0.1f * s->spacing;
  const int dx[6] = {1, -1, 2, 1, -1, 2}, dz[6] = {-1, -1, -1, 1, 1, 1};
  for (int k = 0; k < 6; ++k) {
    const glm::vec3 at(s->corridor.x + float(dx[k]) * 0.5f * s->spacing, 0.5f * b, s->corridor.y + float(dz[k]) * s->spacing);
    s->boxes.push_back(glm::scale(glm::translate(glm::mat4(1.0f), at), glm::vec3(b)));
  }
  return true;
}

// The loading screen: the uploads and the first re-slice at the walk's first camera, submitted
// and waited for before the first frame.
bool loadVegetation(Game& g, const Scene& sc, uint32_t frames) {
  VkCommandBufferAllocateInfo ai{VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO};
  ai.commandPool = g.pool;
  ai.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
  ai.commandBufferCount = 1;
  VkCommandBuffer cmd = VK_NULL_HANDLE;
  HOST_CHECK(vkAllocateCommandBuffers(g.dev.device, &ai, &cmd));
  VkCommandBufferBeginInfo bi{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
  bi.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
  HOST_CHECK(vkBeginCommandBuffer(cmd, &bi));
  const canopy::Status st = canopy::recordCanopyLoad(g.ctx, cmd, {toCanopy(walkView(sc, 0, frames)), toCanopy(walkProjection())});
  HOST_CHECK(vkEndCommandBuffer(cmd));
  bool ok = st.ok();
  if (!ok) std::fprintf(stderr, "canopy-game-host: %s\n", st.message().c_str());
  VkSubmitInfo si{VK_STRUCTURE_TYPE_SUBMIT_INFO};
  si.commandBufferCount = 1;
  si.pCommandBuffers = &cmd;
  HOST_CHECK(vkQueueSubmit(g.dev.queue, 1, &si, VK_NULL_HANDLE));
  HOST_CHECK(vkQueueWaitIdle(g.dev.queue));
  vkFreeCommandBuffers(g.dev.device, g.pool, 1, &cmd);
  return ok;
}

void shutdown(Game& g) {
  if (g.dev.device) vkDeviceWaitIdle(g.dev.device);
  for (Slot& s : g.slots)
    if (s.pending) checkSlot(g, s), s.pending = false;
  canopy::destroyCanopy(g.ctx);
  canopy::releaseDevice(g.adopted);
  if (g.dev.device) {
    for (Slot& s : g.slots) {
      vkDestroyFence(g.dev.device, s.fence, nullptr);
      vkDestroySemaphore(g.dev.device, s.acquired, nullptr);
      vkDestroyBuffer(g.dev.device, s.readback.buffer, nullptr);
      vkFreeMemory(g.dev.device, s.readback.memory, nullptr);
    }
    for (VkSemaphore s : g.presentReady) vkDestroySemaphore(g.dev.device, s, nullptr);
    vkDestroyCommandPool(g.dev.device, g.pool, nullptr);
    vkDestroyPipeline(g.dev.device, g.outline, nullptr);
    vkDestroyPipeline(g.dev.device, g.shaded, nullptr);
    vkDestroyPipeline(g.dev.device, g.casters, nullptr);
    vkDestroyPipelineLayout(g.dev.device, g.shadedLayout, nullptr);
    vkDestroyPipeline(g.dev.device, g.leafCompute, nullptr);
    vkDestroyPipeline(g.dev.device, g.leafDraw, nullptr);
    vkDestroyPipelineLayout(g.dev.device, g.leafComputeLayout, nullptr);
    vkDestroyPipelineLayout(g.dev.device, g.leafDrawLayout, nullptr);
    vkDestroyDescriptorPool(g.dev.device, g.leafPool, nullptr);
    vkDestroyDescriptorSetLayout(g.dev.device, g.leafSetLayout, nullptr);
    vkDestroySampler(g.dev.device, g.windSampler, nullptr);
    vkDestroyBuffer(g.dev.device, g.leaves, nullptr);
    vkFreeMemory(g.dev.device, g.leavesMemory, nullptr);
    vkDestroyDescriptorPool(g.dev.device, g.shadowPool, nullptr);
    vkDestroyDescriptorSetLayout(g.dev.device, g.shadowSetLayout, nullptr);
    vkDestroySampler(g.dev.device, g.shadowSampler, nullptr);
    host::destroyImage(g.dev.device, g.shadowMap);
    vkDestroyPipelineLayout(g.dev.device, g.layout, nullptr);
    host::destroyImage(g.dev.device, g.color);
    host::destroyImage(g.dev.device, g.depth);
    vkDestroySwapchainKHR(g.dev.device, g.swapchain, nullptr);
    vkDestroyDevice(g.dev.device, nullptr);
  }
  if (g.surface) vkDestroySurfaceKHR(g.instance, g.surface, nullptr);
  host::destroyInstance(g.instance, g.messenger);
  if (g.window) glfwDestroyWindow(g.window);
  glfwTerminate();
}

}  // namespace game

using namespace game;

int main(int argc, char** argv) {
  uint32_t frames = 48, plants = 64, writeEvery = 1;
  bool validate = false, load = true;
  std::string gltf = CANOPY_DEFAULT_PLANT, sceneFile;
  Game g;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto number = [&](uint32_t lo, uint32_t hi, uint32_t* out) {
      if (i + 1 >= argc) return false;
      char* end = nullptr;
      const long v = std::strtol(argv[++i], &end, 10);
      if (!end || *end || v < long(lo) || v > long(hi)) return false;
      *out = uint32_t(v);
      return true;
    };
    if (a == "--help" || a == "-h") {
      std::printf("usage: canopy-game-host [--frames N (1..10000, default 48)] [--plants N (1..4096, default 64)] [--gltf FILE]\n"
                  "                        [--scene-file FILE (a scene of glTF species instead of --gltf's copies)]\n"
                  "                        [--out DIR] [--write-every K (default 1)] [--validate]\n"
                  "                        [--no-push (the character not given to Canopy)] [--no-leaves (none drawn)]\n"
                  "                        [--no-load (no loading screen: recordCanopyLoad not called, the first frame slices)]\n");
      return 0;
    } else if (a == "--frames") {
      if (!number(1, 10000, &frames)) return std::fprintf(stderr, "canopy-game-host: --frames needs an integer in [1, 10000]\n"), 2;
    } else if (a == "--plants") {
      if (!number(1, 4096, &plants)) return std::fprintf(stderr, "canopy-game-host: --plants needs an integer in [1, 4096]\n"), 2;
    } else if (a == "--write-every") {
      if (!number(1, 10000, &writeEvery)) return std::fprintf(stderr, "canopy-game-host: --write-every needs an integer in [1, 10000]\n"), 2;
    } else if (a == "--gltf" && i + 1 < argc) {
      gltf = argv[++i];
    } else if (a == "--scene-file" && i + 1 < argc) {
      sceneFile = argv[++i];
    } else if (a == "--out" && i + 1 < argc) {
      g.outDir = argv[++i];
    } else if (a == "--validate") {
      validate = true;
    } else if (a == "--no-push") {
      g.push = false;
    } else if (a == "--no-leaves") {
      g.drawLeaves = false;
    } else if (a == "--no-load") {
      load = false;
    } else {
      std::fprintf(stderr, "canopy-game-host: unknown or incomplete argument '%s'\n", a.c_str());
      return 2;
    }
  }
  if (!std::filesystem::exists(gltf) && sceneFile.empty()) {
    std::printf("canopy-game-host: %s is absent (../shared/assets not present): skipped\n", gltf.c_str());
    return 77;
  }
  if (!g.outDir.empty()) std::filesystem::create_directories(g.outDir);
  if (!glfwInit() || !glfwVulkanSupported()) {
    std::printf("canopy-game-host: no display with Vulkan (run under xvfb-run): skipped\n");
    return 77;
  }
  glfwWindowHint(GLFW_CLIENT_API, GLFW_NO_API);
  glfwWindowHint(GLFW_RESIZABLE, GLFW_FALSE);
  g.window = glfwCreateWindow(int(kW), int(kH), "canopy-game-host", nullptr, nullptr);
  canopy::Model* model = nullptr;
  Scene scene;
  bool ok = g.window && createInstanceAndDevice(g, validate) && createSwapchain(g) &&
            host::createImage(g.dev.device, g.dev.memory, kW, kH, kColorFormat, kColorUsage, VK_IMAGE_ASPECT_COLOR_BIT, &g.color) == VK_SUCCESS &&
            host::createImage(g.dev.device, g.dev.memory, kW, kH, g.depthFormat, kDepthUsage,
                              VK_IMAGE_ASPECT_DEPTH_BIT | VK_IMAGE_ASPECT_STENCIL_BIT, &g.depth) == VK_SUCCESS &&
            createPipelines(g) && createShadows(g) && createFrames(g);
  if (ok && sceneFile.empty()) {
    const canopy::Status s = canopy::loadModel(gltf, {}, &model);
    if (!s.ok()) std::fprintf(stderr, "canopy-game-host: %s\n", s.message().c_str());
    ok = s.ok();
  }
  canopy::CanopyDesc desc;
  desc.width = kW;
  desc.height = kH;
  desc.colorFormat = kColorFormat;
  desc.depthFormat = g.depthFormat;
  desc.params.wind.speed = 5.0f;  // m/s, a moderate breeze along the world's +X (CanopyParams.wind)
  std::vector<canopy::Model*> models;
  std::vector<canopy::CanopySpecies> species;
  if (ok) ok = sceneFile.empty() ? makeScene(model, plants, &desc, &scene) : makeSceneFromFile(sceneFile, &models, &species, &desc, &scene);
  if (ok) {
    const canopy::Status s = sceneFile.empty() ? canopy::createCanopy(g.adopted, model, desc, &g.ctx)
                                               : canopy::createCanopy(g.adopted, species, desc, &g.ctx);
    if (!s.ok()) std::fprintf(stderr, "canopy-game-host: %s\n", s.message().c_str());
    ok = s.ok();
  }
  canopy::destroyModel(model);
  for (canopy::Model* m : models) canopy::destroyModel(m);
  g.light = sunViewProj(scene);
  if (ok && load) ok = loadVegetation(g, scene, frames);
  if (ok) ok = createLeaves(g, glm::vec4(0.0f, 0.0f, scene.half + 0.5f * scene.spacing, scene.plantMax.y - scene.plantMin.y));
  for (uint32_t f = 0; ok && f < frames && !glfwWindowShouldClose(g.window); ++f) {
    glfwPollEvents();
    ok = frame(g, scene, f + 1, f, frames, f % writeEvery == 0 || f + 1 == frames);
  }
  canopy::CanopyStats st{};
  if (g.ctx) st = canopy::canopyStats(g.ctx);
  if (!g.outDir.empty()) std::ofstream(g.outDir + "/character_path.txt") << g.characterPath;
  shutdown(g);
  std::printf("%u copies of %s (%u visible at the last re-slice, of %u of its %u species), %llu re-slices in %u frames\n",
              st.layers.instances, std::filesystem::path(sceneFile.empty() ? gltf : sceneFile).filename().c_str(),
              st.layers.lastVisibleInstances, st.layers.lastVisibleSpecies, st.layers.species, (unsigned long long)st.layers.rebuilds,
              frames);
  // The leaves follow the gusts: their velocities against the sampled wind at their places
  // (Pearson's correlation over every leaf of every frame that had a completed wind copy).
  const double N = double(g.leafSamples);
  const double cov = g.sxy / std::max(N, 1.0) - (g.sx / std::max(N, 1.0)) * (g.sy / std::max(N, 1.0));
  const double vx = g.sxx / std::max(N, 1.0) - std::pow(g.sx / std::max(N, 1.0), 2.0);
  const double vy = g.syy / std::max(N, 1.0) - std::pow(g.sy / std::max(N, 1.0), 2.0);
  const double correlation = vx > 0.0 && vy > 0.0 ? cov / std::sqrt(vx * vy) : 0.0;
  std::printf("wind: %u leaves moved by canopyWindAt in the host's compute shader; their velocity against sampleCanopyWind at their "
              "places: correlation %.3f over %llu leaf-frames (the leaves' mean %.3f, the wind's %.3f world units/s along the plane's "
              "right); the character (a capsule pusher) mapped onto the plane in %llu of %u frames\n",
              kLeaves, correlation, (unsigned long long)g.leafSamples, g.sx / std::max(N, 1.0), g.sy / std::max(N, 1.0),
              (unsigned long long)g.characterMapped, frames);
  const bool pass = ok && g.fartherPixels == 0 && g.stencilChanged == 0 && g.validationMessages == 0 &&
                    g.framesWithVegetationInFront > 0 && g.checkedFrames == frames && g.shadowUpdates == frames &&
                    correlation >= 0.8 && g.characterMapped == frames;
  std::printf("self-check: %llu frames checked, %llu with vegetation in front of the host's scene, %llu with the forest's shadow "
              "drawn, %llu pixels farther after Canopy, %llu stencil bytes changed, %d validation messages, leaves following the "
              "wind (correlation >= 0.8): %s: %s\n",
              (unsigned long long)g.checkedFrames, (unsigned long long)g.framesWithVegetationInFront, (unsigned long long)g.shadowUpdates,
              (unsigned long long)g.fartherPixels, (unsigned long long)g.stencilChanged, g.validationMessages,
              correlation >= 0.8 ? "yes" : "no", pass ? "PASS" : "FAIL");
  return pass ? 0 : 1;
}
