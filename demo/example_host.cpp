// canopy-example-host: a minimal "engine" that owns its Vulkan objects and embeds Canopy through
// the public header alone (<canopy/canopy.h>), the way an engine with its own device would.
//
// The host creates its own instance, device, queue, memory allocator, images and pipeline; it asks
// Canopy which device features to enable before creating the device, then adopts the device into
// Canopy. It renders with 2 frames in flight (a command buffer and a fence per frame, never waiting
// for the device between frames) and reverse-Z depth (cleared to 0, compared GREATER), its camera
// orbiting the plant 0.5 degrees a frame. Per frame it draws a ground plane and a box, lets Canopy record the animated vegetation into the same
// command buffer (recordCanopy), then draws one more box after Canopy, depth-tested against the
// depth Canopy wrote. It checks its own result: the post-vegetation box must be hidden exactly
// where the vegetation is in front of it.
//
//   canopy-example-host [--frames N] [--frames-in-flight N] [--out DIR] [--validate]
// Exit 0 when the check passes, 1 on a failure, 2 on bad arguments.
#include <canopy/canopy.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <glm/glm.hpp>
#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/type_ptr.hpp>

#include "host_vk.h"  // the host's own Vulkan helpers and box shaders (SPIR-V words, built by glslangValidator)

namespace host {
const char* const kProgram = "canopy-example-host";
}  // namespace host

namespace {

constexpr uint32_t kW = 320, kH = 240;
constexpr uint32_t kMaxFramesInFlight = 3;
constexpr VkFormat kDepthFormat = VK_FORMAT_D32_SFLOAT;
using host::kColorFormat;
using host::kColorUsage;
using host::kDepthUsage;

using host::BoxPush;
using host::barrier;

// ---- The host's own memory allocator (what VMA would be in a real engine) ----------------------

struct HostMemory {
  VkDevice device = VK_NULL_HANDLE;
  VkPhysicalDeviceMemoryProperties props{};
  uint64_t live = 0, total = 0;  // allocations made for Canopy (its DeviceMemoryAllocator)
};

VkResult hostAllocate(void* user, const VkMemoryRequirements& req, VkMemoryPropertyFlags required,
                      VkMemoryPropertyFlags preferred, canopy::DeviceMemoryRange* out) {
  auto& m = *static_cast<HostMemory*>(user);
  const int32_t type = host::memoryType(m.props, req.memoryTypeBits, required, preferred);
  if (type < 0) return VK_ERROR_OUT_OF_DEVICE_MEMORY;
  VkMemoryAllocateInfo ai{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO};
  ai.allocationSize = req.size;
  ai.memoryTypeIndex = uint32_t(type);
  VkDeviceMemory mem = VK_NULL_HANDLE;
  VkResult r = vkAllocateMemory(m.device, &ai, nullptr, &mem);
  if (r != VK_SUCCESS) return r;
  void* mapped = nullptr;
  if (m.props.memoryTypes[type].propertyFlags & VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT) {
    r = vkMapMemory(m.device, mem, 0, VK_WHOLE_SIZE, 0, &mapped);
    if (r != VK_SUCCESS) {
      vkFreeMemory(m.device, mem, nullptr);
      return r;
    }
  }
  *out = {mem, 0, req.size, mapped, uint32_t(type), 0};
  m.live++;
  m.total++;
  return VK_SUCCESS;
}

void hostFree(void* user, const canopy::DeviceMemoryRange& range) {
  auto& m = *static_cast<HostMemory*>(user);
  vkFreeMemory(m.device, range.memory, nullptr);  // unmaps implicitly
  m.live--;
}

// ---- The host's renderer -----------------------------------------------------------------------


struct Frame {
  VkCommandBuffer cmd = VK_NULL_HANDLE;
  VkFence fence = VK_NULL_HANDLE;
  VkBuffer readback = VK_NULL_HANDLE;  // colour then depth of the frame, when asked
  VkDeviceMemory readbackMemory = VK_NULL_HANDLE;
  void* mapped = nullptr;
  bool pending = false;  // submitted, not yet waited for
};

struct Host {
  VkInstance instance = VK_NULL_HANDLE;
  VkDebugUtilsMessengerEXT messenger = VK_NULL_HANDLE;
  host::HostDevice dev;  // its physical device, device, queue family and queue
  HostMemory memory;
  host::Image color, depth;
  VkCommandPool pool = VK_NULL_HANDLE;
  Frame frames[kMaxFramesInFlight];
  uint32_t framesInFlight = 2;  // frames recorded ahead of the GPU (--frames-in-flight)
  VkPipelineLayout layout = VK_NULL_HANDLE;
  VkPipeline boxes = VK_NULL_HANDLE;
  glm::mat4 view{1.0f}, proj{1.0f};
  int validationMessages = 0;
};

bool createInstanceAndDevice(Host& h, bool validate, uint32_t* apiVersion) {
  HOST_CHECK(host::createInstance(host::kProgram, {}, validate, &h.validationMessages, apiVersion, &h.instance, &h.messenger));
  if (!host::createHostDevice(h.instance, *apiVersion, VK_NULL_HANDLE, {}, &h.dev)) return false;
  h.memory.device = h.dev.device;
  h.memory.props = h.dev.memory;
  return true;
}

bool createTarget(Host& h, VkFormat format, VkImageUsageFlags usage, VkImageAspectFlags aspect, host::Image* t) {
  HOST_CHECK(host::createImage(h.dev.device, h.memory.props, kW, kH, format, usage, aspect, t));
  return true;
}

bool createPipeline(Host& h) {
  HOST_CHECK(host::createBoxLayout(h.dev.device, &h.layout));
  // Reverse-Z: near = 1, cleared to 0, nearer fragments have greater depth.
  const VkPipelineDepthStencilStateCreateInfo ds = host::depthTested(VK_COMPARE_OP_GREATER);
  HOST_CHECK(host::createBoxPipeline(h.dev.device, h.layout, kColorFormat, kDepthFormat, VK_FORMAT_UNDEFINED, ds, false, &h.boxes));
  return true;
}

// The host's reverse-Z perspective (right-handed view, Vulkan clip y down): depth 1 at zNear, 0 at zFar.
// The host's camera: on a circle of radius 3.3 around the plant, `yawDegrees` about the vertical.
glm::mat4 orbitView(float yawDegrees) {
  const glm::vec3 eye = glm::vec3(std::sin(glm::radians(yawDegrees)), 0.25f, std::cos(glm::radians(yawDegrees))) * 3.3f;
  return glm::lookAt(eye, glm::vec3(0.0f), glm::vec3(0, 1, 0));
}

glm::mat4 reverseZPerspective(float fovY, float aspect, float zNear, float zFar) {
  const float f = 1.0f / std::tan(fovY * 0.5f);
  glm::mat4 p(0.0f);
  p[0][0] = f / aspect;
  p[1][1] = -f;
  p[2][2] = zNear / (zFar - zNear);
  p[2][3] = -1.0f;
  p[3][2] = zNear * zFar / (zFar - zNear);
  return p;
}

BoxPush box(const Host& h, glm::vec3 centre, glm::vec3 size, glm::vec3 color) {
  const glm::mat4 model = glm::scale(glm::translate(glm::mat4(1.0f), centre), size);
  return {h.proj * h.view * model, glm::vec4(color, 1.0f)};
}

const VkPipelineStageFlags2 kColorStage = VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT;
const VkAccessFlags2 kColorAccess = VK_ACCESS_2_COLOR_ATTACHMENT_READ_BIT | VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT;
const VkPipelineStageFlags2 kDepthStage = VK_PIPELINE_STAGE_2_EARLY_FRAGMENT_TESTS_BIT | VK_PIPELINE_STAGE_2_LATE_FRAGMENT_TESTS_BIT;
const VkAccessFlags2 kDepthAccess = VK_ACCESS_2_DEPTH_STENCIL_ATTACHMENT_READ_BIT | VK_ACCESS_2_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT;

void drawBoxes(Host& h, VkCommandBuffer cmd, bool clear, const std::vector<BoxPush>& boxes) {
  // Reverse-Z: the depth is cleared to 0, far.
  host::beginBoxPass(cmd, h.color.view, h.depth.view, false, clear, {{0.45f, 0.6f, 0.8f, 1.0f}}, 0.0f, kW, kH, h.boxes);
  for (const BoxPush& b : boxes) {
    vkCmdPushConstants(cmd, h.layout, VK_SHADER_STAGE_VERTEX_BIT | VK_SHADER_STAGE_FRAGMENT_BIT, 0, sizeof b, &b);
    vkCmdDraw(cmd, 36, 1, 0, 0);
  }
  vkCmdEndRendering(cmd);
}

// A procedural plant built from the host's own arrays: a bark trunk and a crown of leaf quads in
// the unit sphere (createModel copies them).
canopy::Model* makePlant() {
  std::vector<float> pos;
  std::vector<uint32_t> idx, mat;
  auto quad = [&](glm::vec3 c, glm::vec3 u, glm::vec3 v, uint32_t m) {
    const uint32_t base = uint32_t(pos.size() / 3);
    for (glm::vec3 p : {c - u - v, c + u - v, c + u + v, c - u + v}) pos.insert(pos.end(), {p.x, p.y, p.z});
    for (uint32_t i : {0u, 1u, 2u, 0u, 2u, 3u}) idx.push_back(base + i);
    mat.insert(mat.end(), {m, m});
  };
  uint32_t seed = 21;
  auto rnd = [&] {
    seed = seed * 1664525u + 1013904223u;
    return float(seed >> 8) / float(1u << 24);
  };
  for (int i = 0; i < 6000; ++i) {
    glm::vec3 c;
    do c = glm::vec3(rnd(), rnd(), rnd()) * 2.0f - 1.0f;
    while (glm::length(c) > 1.0f);
    const glm::vec3 a = glm::normalize(glm::vec3(rnd() - 0.5f, rnd() - 0.5f, rnd() - 0.5f) + glm::vec3(1e-3f));
    const glm::vec3 b = glm::normalize(glm::cross(a, glm::vec3(0.3f, 1.0f, 0.2f)));
    quad(c, a * 0.05f, b * 0.035f, 0);
  }
  for (int side = 0; side < 4; ++side) {  // a square trunk from the ground into the crown
    const float ang = float(side) * 1.5707964f;
    const glm::vec3 n(std::cos(ang), 0.0f, std::sin(ang)), t(-n.z, 0.0f, n.x);
    quad(glm::vec3(0.0f, -1.2f, 0.0f) + n * 0.08f, t * 0.08f, glm::vec3(0, 0.75f, 0), 1);
  }
  canopy::MeshMaterial materials[2];
  materials[0].name = "leaves";
  materials[0].baseColor[0] = 0.25f;
  materials[0].baseColor[1] = 0.55f;
  materials[0].baseColor[2] = 0.2f;
  materials[0].doubleSided = true;
  materials[1].name = "bark";
  materials[1].baseColor[0] = 0.35f;
  materials[1].baseColor[1] = 0.25f;
  materials[1].baseColor[2] = 0.15f;
  canopy::MeshDesc md;
  md.name = "example plant";
  md.positions = pos.data();
  md.vertexCount = uint32_t(pos.size() / 3);
  md.indices = idx.data();
  md.indexCount = idx.size();
  md.triangleMaterials = mat.data();
  md.materials = materials;
  md.materialCount = 2;
  canopy::Model* model = nullptr;
  canopy::Status s = canopy::createModel(md, &model);
  if (!s.ok()) std::fprintf(stderr, "canopy-example-host: %s\n", s.message().c_str());
  return model;
}

canopy::Float4x4 toCanopy(const glm::mat4& m) {
  canopy::Float4x4 r;
  std::memcpy(r.m, glm::value_ptr(m), sizeof r.m);
  return r;
}

// What one recorded frame draws (the check renders four variants of the same pose).
struct Variant {
  bool canopy = true, postBox = true, readback = false;
  float dt = 1.0f / 30.0f;
};

bool recordFrame(Host& h, canopy::CanopyContext* ctx, Frame& f, uint64_t frameNumber, const Variant& v) {
  VkCommandBufferBeginInfo bi{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
  bi.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
  HOST_CHECK(vkBeginCommandBuffer(f.cmd, &bi));
  // The previous frame (maybe still executing) may be reading the targets: the barriers order it.
  barrier(f.cmd, h.color.image, VK_IMAGE_ASPECT_COLOR_BIT, VK_IMAGE_LAYOUT_UNDEFINED, VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL,
          VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT, VK_ACCESS_2_MEMORY_READ_BIT | VK_ACCESS_2_MEMORY_WRITE_BIT, kColorStage, kColorAccess);
  barrier(f.cmd, h.depth.image, VK_IMAGE_ASPECT_DEPTH_BIT, VK_IMAGE_LAYOUT_UNDEFINED,
          VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL, VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT,
          VK_ACCESS_2_MEMORY_READ_BIT | VK_ACCESS_2_MEMORY_WRITE_BIT, kDepthStage, kDepthAccess);
  drawBoxes(h, f.cmd, true,
            {box(h, {0, -1.95f, 0}, {8, 0.1f, 8}, {0.3f, 0.45f, 0.2f}), box(h, {1.6f, -1.5f, -0.8f}, {0.8f, 0.8f, 0.8f}, {0.6f, 0.6f, 0.65f})});
  if (v.canopy) {
    // The host's images arrive as its scene pass left them and must come back the same way.
    canopy::CanopyFrameInputs in;
    in.frame.camera = {toCanopy(h.view), toCanopy(h.proj)};
    in.frame.dt = v.dt;
    in.frame.frameNumber = frameNumber;
    const canopy::ResourceState colorState{kColorStage, kColorAccess, VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL},
        depthState{kDepthStage, kDepthAccess, VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL};
    in.color = canopy::canopyImage(h.color.image, h.color.view, kColorUsage, kColorFormat, colorState, colorState);
    in.depth = canopy::canopyImage(h.depth.image, h.depth.view, kDepthUsage, kDepthFormat, depthState, depthState);
    canopy::Status s = canopy::recordCanopy(ctx, f.cmd, in);
    if (!s.ok()) {
      std::fprintf(stderr, "canopy-example-host: %s\n", s.message().c_str());
      return false;
    }
  }
  if (v.postBox) drawBoxes(h, f.cmd, false, {box(h, {0.1f, -0.1f, 0.0f}, {0.9f, 0.9f, 0.9f}, {1.0f, 0.0f, 0.0f})});
  if (v.readback) {
    barrier(f.cmd, h.color.image, VK_IMAGE_ASPECT_COLOR_BIT, VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL,
            VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, kColorStage, kColorAccess, VK_PIPELINE_STAGE_2_COPY_BIT, VK_ACCESS_2_TRANSFER_READ_BIT);
    barrier(f.cmd, h.depth.image, VK_IMAGE_ASPECT_DEPTH_BIT, VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL,
            VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, kDepthStage, kDepthAccess, VK_PIPELINE_STAGE_2_COPY_BIT, VK_ACCESS_2_TRANSFER_READ_BIT);
    VkBufferImageCopy c{};
    c.imageSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1};
    c.imageExtent = {kW, kH, 1};
    vkCmdCopyImageToBuffer(f.cmd, h.color.image, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, f.readback, 1, &c);
    c.bufferOffset = VkDeviceSize(kW) * kH * 4;
    c.imageSubresource.aspectMask = VK_IMAGE_ASPECT_DEPTH_BIT;
    vkCmdCopyImageToBuffer(f.cmd, h.depth.image, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, f.readback, 1, &c);
    host::bufferBarrier(f.cmd, f.readback, VK_PIPELINE_STAGE_2_COPY_BIT, VK_ACCESS_2_TRANSFER_WRITE_BIT, VK_PIPELINE_STAGE_2_HOST_BIT,
                        VK_ACCESS_2_HOST_READ_BIT);
  }
  HOST_CHECK(vkEndCommandBuffer(f.cmd));
  VkSubmitInfo si{VK_STRUCTURE_TYPE_SUBMIT_INFO};
  si.commandBufferCount = 1;
  si.pCommandBuffers = &f.cmd;
  HOST_CHECK(vkQueueSubmit(h.dev.queue, 1, &si, f.fence));
  f.pending = true;
  return true;
}

// Waits for the frame slot's previous submission (the only wait of the frame loop).
bool acquire(Host& h, Frame& f) {
  if (!f.pending) return true;
  HOST_CHECK(vkWaitForFences(h.dev.device, 1, &f.fence, VK_TRUE, UINT64_MAX));
  HOST_CHECK(vkResetFences(h.dev.device, 1, &f.fence));
  f.pending = false;
  return true;
}

void writePpm(const std::string& path, const uint8_t* rgba) {
  std::ofstream o(path, std::ios::binary);
  o << "P6\n" << kW << " " << kH << "\n255\n";
  for (size_t i = 0; i < size_t(kW) * kH; ++i) o.write(reinterpret_cast<const char*>(rgba + 4 * i), 3);
}

bool run(Host& h, int frames, const std::string& outDir, bool validate, canopy::Device** adopted, canopy::CanopyContext** ctx) {
  uint32_t api = 0;
  if (!createInstanceAndDevice(h, validate, &api)) return false;
  const bool ok = [&] {
    // The host's own objects.
    if (!createTarget(h, kColorFormat, kColorUsage, VK_IMAGE_ASPECT_COLOR_BIT, &h.color))
      return false;
    // Sampled: Canopy reads the host's depth to put the host's scene between its layers.
    if (!createTarget(h, kDepthFormat, kDepthUsage, VK_IMAGE_ASPECT_DEPTH_BIT, &h.depth))
      return false;
    if (!createPipeline(h)) return false;
    HOST_CHECK(host::createCommandPool(h.dev.device, h.dev.family, &h.pool));
    for (Frame& f : h.frames) {
      HOST_CHECK(host::createFrameSlot(h.dev.device, h.pool, &f.cmd, &f.fence));
      VkBufferCreateInfo bci{VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO};
      bci.size = VkDeviceSize(kW) * kH * 8;
      bci.usage = VK_BUFFER_USAGE_TRANSFER_DST_BIT;
      HOST_CHECK(vkCreateBuffer(h.dev.device, &bci, nullptr, &f.readback));
      VkMemoryRequirements req;
      vkGetBufferMemoryRequirements(h.dev.device, f.readback, &req);
      canopy::DeviceMemoryRange r;
      HOST_CHECK(hostAllocate(&h.memory, req, VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT, 0, &r));
      h.memory.live--;  // the host's own, not Canopy's
      h.memory.total--;
      f.readbackMemory = r.memory;
      f.mapped = r.mapped;
      HOST_CHECK(vkBindBufferMemory(h.dev.device, f.readback, f.readbackMemory, 0));
    }

    // Canopy on the host's device, through the host's loader and allocator.
    canopy::DeviceMemoryAllocator alloc;
    alloc.user = &h.memory;
    alloc.allocate = hostAllocate;
    alloc.free = hostFree;
    if (!host::adoptHostDevice(h.dev, h.instance, api, h.framesInFlight, &alloc, adopted)) return false;
    canopy::Model* plant = makePlant();
    if (!plant) return false;
    h.view = orbitView(25.0f);
    h.proj = reverseZPerspective(glm::radians(45.0f), float(kW) / float(kH), 0.1f, 100.0f);
    canopy::CanopyDesc desc;
    desc.width = kW;
    desc.height = kH;
    desc.colorFormat = kColorFormat;
    desc.depthFormat = kDepthFormat;
    desc.depthConvention = canopy::DepthConvention::Reverse;
    desc.params.wind.speed = 5.0f;  // m/s, a moderate breeze along the world's +X (CanopyParams.wind)
    const canopy::Status s = canopy::createCanopy(*adopted, plant, desc, ctx);
    canopy::destroyModel(plant);  // Canopy keeps what it needs
    if (!s.ok()) {
      std::fprintf(stderr, "canopy-example-host: %s: %s\n", canopy::toString(s.code()), s.message().c_str());
      return false;
    }

    // The frame loop: frame i uses slot i % 2 and waits only for that slot's previous frame.
    uint64_t frameNumber = 0;
    auto submit = [&](const Variant& v) -> Frame* {
      ++frameNumber;
      Frame& f = h.frames[frameNumber % h.framesInFlight];
      if (!acquire(h, f) || !recordFrame(h, *ctx, f, frameNumber, v)) return nullptr;
      return &f;
    };
    // The camera orbits 0.5 degrees a frame (a game's camera moves): between re-slices Canopy shows
    // its layers reprojected, and the depth it writes must follow them. The check holds the last pose.
    for (int i = 0; i < frames; ++i) {
      h.view = orbitView(25.0f + 0.5f * float(i));
      if (!submit(Variant{})) return false;
    }
    // The check, on four variants of the last pose (dt = 0 holds the wind): both, the vegetation
    // alone, the post box alone, and neither. Each is read back after its own fence.
    const Variant variants[4] = {{true, true, true, 0.0f}, {true, false, true, 0.0f}, {false, true, true, 0.0f}, {false, false, true, 0.0f}};
    std::vector<std::vector<uint8_t>> rgba(4);
    std::vector<std::vector<float>> depth(4);
    for (int k = 0; k < 4; ++k) {
      Frame* f = submit(variants[k]);
      if (!f || !acquire(h, *f)) return false;
      const uint8_t* p = static_cast<const uint8_t*>(f->mapped);
      rgba[k].assign(p, p + size_t(kW) * kH * 4);
      depth[k].resize(size_t(kW) * kH);
      std::memcpy(depth[k].data(), p + size_t(kW) * kH * 4, depth[k].size() * 4);
    }
    size_t hidden = 0, shown = 0, wrong = 0;
    for (size_t i = 0; i < depth[0].size(); ++i) {
      const float veg = depth[1][i], postBox = depth[2][i], scene = depth[3][i];
      if (!(postBox > scene)) continue;  // reverse-Z: the post box is not drawn here
      const uint8_t* c = &rgba[0][i * 4];
      const bool red = c[0] > 100 && c[1] < 20 && c[2] < 20;
      if (veg > postBox) {  // the vegetation is in front: the box must be hidden
        hidden++;
        wrong += red;
      } else {
        shown++;
        wrong += !red;
      }
    }
    const canopy::CanopyStats st = canopy::canopyStats(*ctx);
    std::printf("canopy-example-host: own VkDevice '%s' (Canopy adopted it; %llu device allocations through the host's "
                "allocator), %u frames in flight, reverse-Z depth (cleared to 0, GREATER), %ux%u, %d frames + 4 check "
                "frames, layers re-sliced %llu times\n",
                h.dev.name.c_str(), (unsigned long long)h.memory.total, h.framesInFlight, kW, kH, frames,
                (unsigned long long)st.layers.rebuilds);
    std::printf("self-check: post-vegetation box %zu px behind vegetation (hidden), %zu px in front (shown), %zu px wrong: %s\n",
                hidden, shown, wrong, (hidden && shown && wrong <= (hidden + shown) / 100) ? "PASS" : "FAIL");
    if (!outDir.empty()) {
      std::error_code ec;
      std::filesystem::create_directories(outDir, ec);
      if (!ec) {
        writePpm(outDir + "/example_host.ppm", rgba[0].data());
        std::printf("wrote %s/example_host.ppm\n", outDir.c_str());
      }
    }
    return hidden > 0 && shown > 0 && wrong <= (hidden + shown) / 100;
  }();
  return ok;
}

void shutdown(Host& h, canopy::Device* adopted, canopy::CanopyContext* ctx) {
  // The host's own shutdown: its device idle, then Canopy's objects, then the host's.
  if (h.dev.device) vkDeviceWaitIdle(h.dev.device);
  canopy::destroyCanopy(ctx);
  canopy::releaseDevice(adopted);
  if (h.memory.live) std::fprintf(stderr, "canopy-example-host: Canopy left %llu allocations\n", (unsigned long long)h.memory.live);
  for (Frame& f : h.frames) {
    if (f.fence) vkDestroyFence(h.dev.device, f.fence, nullptr);
    if (f.readback) vkDestroyBuffer(h.dev.device, f.readback, nullptr);
    if (f.readbackMemory) vkFreeMemory(h.dev.device, f.readbackMemory, nullptr);
  }
  if (h.pool) vkDestroyCommandPool(h.dev.device, h.pool, nullptr);
  if (h.boxes) vkDestroyPipeline(h.dev.device, h.boxes, nullptr);
  if (h.layout) vkDestroyPipelineLayout(h.dev.device, h.layout, nullptr);
  if (h.dev.device) {
    host::destroyImage(h.dev.device, h.color);
    host::destroyImage(h.dev.device, h.depth);
    vkDestroyDevice(h.dev.device, nullptr);
  }
  host::destroyInstance(h.instance, h.messenger);
}

}  // namespace

int main(int argc, char** argv) {
  int frames = 10;
  std::string out;
  bool validate = false;
  Host h;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--help" || a == "-h") {
      std::printf("usage: canopy-example-host [--frames N (1..1000, default 10)] [--frames-in-flight N (1..3, default 2)] "
                  "[--out DIR] [--validate]\n");
      return 0;
    }
    if (a == "--frames" && i + 1 < argc) {
      char* end = nullptr;
      const long v = std::strtol(argv[++i], &end, 10);
      if (!end || *end || v < 1 || v > 1000) {
        std::fprintf(stderr, "canopy-example-host: --frames needs an integer in [1, 1000]\n");
        return 2;
      }
      frames = int(v);
    } else if (a == "--frames-in-flight" && i + 1 < argc) {
      const std::string v = argv[++i];
      if (v != "1" && v != "2" && v != "3") {
        std::fprintf(stderr, "canopy-example-host: --frames-in-flight needs 1, 2 or 3\n");
        return 2;
      }
      h.framesInFlight = uint32_t(v[0] - '0');
    } else if (a == "--out" && i + 1 < argc) {
      out = argv[++i];
    } else if (a == "--validate") {
      validate = true;
    } else {
      std::fprintf(stderr, "canopy-example-host: unknown or incomplete argument '%s'\n", a.c_str());
      return 2;
    }
  }
  canopy::Device* adopted = nullptr;
  canopy::CanopyContext* ctx = nullptr;
  const bool ok = run(h, frames, out, validate, &adopted, &ctx);
  shutdown(h, adopted, ctx);
  if (h.validationMessages > 0) {
    std::fprintf(stderr, "canopy-example-host: %d validation messages\n", h.validationMessages);
    return 1;
  }
  return ok ? 0 : 1;
}
