#pragma once
// canopy-game-host's pieces (demo/game_host.cpp: the window, frames and self-check;
// demo/game_host_scene.cpp: the plants, boxes, walk, character and sun; demo/game_host_leaves.cpp:
// the falling leaves Canopy's wind carries). Canopy through <canopy/canopy.h> only.
#include <canopy/canopy.h>

#define GLFW_INCLUDE_VULKAN
#include <GLFW/glfw3.h>

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

#include "host_vk.h"  // the example hosts' Vulkan helpers and box shaders

namespace game {


constexpr uint32_t kW = 320, kH = 240, kFrames = 3;
using host::kColorFormat;
using host::kColorUsage;
using host::kDepthUsage;
constexpr uint8_t kOutlined = 1;  // the stencil value of the outlined box
constexpr uint32_t kShadowSize = 1024;  // the sun's shadow map, texels a side
constexpr uint32_t kLeaves = 4096;      // falling leaves carried by Canopy's wind (host_leaves.*)

inline const VkPipelineStageFlags2 kColorStage = VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT;
inline const VkAccessFlags2 kColorAccess = VK_ACCESS_2_COLOR_ATTACHMENT_READ_BIT | VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT;
inline const VkPipelineStageFlags2 kDepthStage = VK_PIPELINE_STAGE_2_EARLY_FRAGMENT_TESTS_BIT | VK_PIPELINE_STAGE_2_LATE_FRAGMENT_TESTS_BIT;
inline const VkAccessFlags2 kDepthAccess = VK_ACCESS_2_DEPTH_STENCIL_ATTACHMENT_READ_BIT | VK_ACCESS_2_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT;
inline const VkPipelineStageFlags2 kCopy = VK_PIPELINE_STAGE_2_ALL_TRANSFER_BIT;

using host::BoxPush;
using host::barrier;

struct Readback {
  VkBuffer buffer = VK_NULL_HANDLE;
  VkDeviceMemory memory = VK_NULL_HANDLE;
  uint8_t* mapped = nullptr;
};

struct Slot {
  VkCommandBuffer cmd = VK_NULL_HANDLE;
  VkFence fence = VK_NULL_HANDLE;
  VkSemaphore acquired = VK_NULL_HANDLE;
  // Depth and stencil before and after Canopy's passes, and the colour: [zBefore|zAfter|sBefore|sAfter|rgba].
  Readback readback;
  bool pending = false, write = false;
  uint64_t frame = 0;
  glm::mat4 invViewProj{1.0f};  // the frame's camera (the band mask: each pixel's world point)
  size_t walked = 0;            // how much of the character's path that frame had walked
};

struct Game {
  GLFWwindow* window = nullptr;
  VkInstance instance = VK_NULL_HANDLE;
  VkDebugUtilsMessengerEXT messenger = VK_NULL_HANDLE;
  VkSurfaceKHR surface = VK_NULL_HANDLE;
  host::HostDevice dev;  // its physical device, device, queue family, queue and memory types
  VkSwapchainKHR swapchain = VK_NULL_HANDLE;
  VkFormat swapFormat = VK_FORMAT_UNDEFINED;
  std::vector<VkImage> swapImages;
  std::vector<VkSemaphore> presentReady;  // per swapchain image
  VkFormat depthFormat = VK_FORMAT_UNDEFINED;
  host::Image color, depth;
  VkCommandPool pool = VK_NULL_HANDLE;
  Slot slots[kFrames];
  VkPipelineLayout layout = VK_NULL_HANDLE;
  VkPipeline outline = VK_NULL_HANDLE;
  // The sun's shadow map (D32, depth only): the host's boxes, then the forest (recordCanopyShadow);
  // sampled by the next frame's shadowed pipeline (host_shadowed.*, descriptor set 0: the map).
  host::Image shadowMap;
  VkSampler shadowSampler = VK_NULL_HANDLE;
  VkDescriptorSetLayout shadowSetLayout = VK_NULL_HANDLE;
  VkDescriptorPool shadowPool = VK_NULL_HANDLE;
  VkDescriptorSet shadowSet = VK_NULL_HANDLE;
  VkPipelineLayout shadedLayout = VK_NULL_HANDLE;
  VkPipeline shaded = VK_NULL_HANDLE, casters = VK_NULL_HANDLE;
  glm::mat4 light{1.0f};
  bool shadowReady = false;
  uint64_t shadowUpdates = 0;
  // Falling leaves (host_leaves.comp moves them by canopyWindAt, host_leaves.vert/frag draw them):
  // two vec4 a leaf in one host-visible buffer, the wind image and the buffer in one descriptor set.
  VkBuffer leaves = VK_NULL_HANDLE;
  VkDeviceMemory leavesMemory = VK_NULL_HANDLE;
  VkSampler windSampler = VK_NULL_HANDLE;
  VkDescriptorSetLayout leafSetLayout = VK_NULL_HANDLE;
  VkDescriptorPool leafPool = VK_NULL_HANDLE;
  VkDescriptorSet leafSet = VK_NULL_HANDLE;
  VkPipelineLayout leafComputeLayout = VK_NULL_HANDLE, leafDrawLayout = VK_NULL_HANDLE;
  VkPipeline leafCompute = VK_NULL_HANDLE, leafDraw = VK_NULL_HANDLE;
  glm::vec4 leafArea{0.0f};  // the area's centre (x, z), half width, the canopy's top
  // The leaves' self-check: each leaf's velocity against sampleCanopyWind at its place, along the
  // wind plane's right axis, pooled over leaves and frames (a correlation), and the frames whose
  // character (a pusher) Canopy mapped onto its plane.
  double sx = 0, sy = 0, sxx = 0, syy = 0, sxy = 0;
  uint64_t leafSamples = 0, characterMapped = 0;
  canopy::Device* adopted = nullptr;
  canopy::CanopyContext* ctx = nullptr;
  int validationMessages = 0;
  // The self-check's totals.
  uint64_t fartherPixels = 0, stencilChanged = 0, checkedFrames = 0, framesWithVegetationInFront = 0;
  std::string outDir;
  // --no-push: the character is drawn but not given to Canopy; --no-leaves: no leaves drawn (the
  // two together let a test compare frames with and without the character's push).
  bool push = true, drawLeaves = true;
  std::string characterPath;  // per frame: x y (pixels, rows from the top) and radius (pixels) of the character's middle
  std::vector<glm::vec4> walked;  // the character's path so far: x, z, its radius
};

struct Scene {
  glm::vec3 plantMin{0}, plantMax{0};
  float spacing = 1, half = 1;  // the grid's cell and half its extent
  glm::vec2 corridor{0.0f};      // x and z of the middle lanes between the rows and columns
  std::vector<glm::mat4> boxes;  // model matrices (unit cube of side 1); [0] is outlined
};

inline canopy::Float4x4 toCanopy(const glm::mat4& m) {
  canopy::Float4x4 r;
  std::memcpy(r.m, glm::value_ptr(m), sizeof r.m);
  return r;
}

// The walk's projection (60 degrees vertical, Vulkan clip) and its view at `frame` of `frames`.
glm::mat4 walkProjection();
glm::mat4 walkView(const Scene& s, uint32_t frame, uint32_t frames);
// The character (a capsule pusher) at `frame` of `frames`.
canopy::CanopyPusher character(const Scene& s, uint32_t frame, uint32_t frames);
// The sun's orthographic view-projection around the scene.
glm::mat4 sunViewProj(const Scene& s);
// `plants` copies of `model` on a grid (desc->instances) and the boxes among them.
bool makeScene(const canopy::Model* model, uint32_t plants, canopy::CanopyDesc* desc, Scene* s);
// The leaves' buffer, descriptor set and pipelines over `area` (centre x, z, half width, top).
bool createLeaves(Game& g, const glm::vec4& area);
// This frame's leaves: moved by Canopy's wind (compute), drawn over the scene, copied to the slot's
// readback for the self-check.
bool recordLeaves(Game& g, const Scene& sc, Slot& s, VkCommandBuffer cmd, uint64_t number, const glm::mat4& view, const glm::mat4& vp);

}  // namespace game
