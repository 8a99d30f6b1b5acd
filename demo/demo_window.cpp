// canopy-demo --window: the animated scene in a GLFW window. The host renders offscreen through
// its render graph (demo_app.cpp) and blits into the acquired swapchain image; a resize or an
// out-of-date swapchain recreates the swapchain and the host targets at the new size (Canopy's
// context is sized to them), a minimised window waits for events.
//
// Controls: left drag orbits, wheel zooms, right drag puts a fluid motor under the cursor (the
// foliage there is pushed away), keys as printed by --help and on start.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>

#define GLFW_INCLUDE_VULKAN
#include <GLFW/glfw3.h>

#include "demo/demo_app.h"
#include "tools/image_io.h"

namespace canopy::demo {
namespace {

std::string g_glfwError;

struct Swapchain {
  VkSwapchainKHR swapchain = VK_NULL_HANDLE;
  VkFormat format = VK_FORMAT_UNDEFINED;
  VkExtent2D extent{};
  std::vector<Image> images;               // wrapped swapchain images (no view, no memory)
  std::vector<VkSemaphore> rendered;       // one per image: signalled by the frame's submit, waited by present
  VkPresentModeKHR presentMode = VK_PRESENT_MODE_FIFO_KHR;
};

void destroySwapchain(Device& d, Swapchain& s) {
  for (VkSemaphore x : s.rendered) vkDestroySemaphore(d.device, x, nullptr);
  if (s.swapchain) vkDestroySwapchainKHR(d.device, s.swapchain, nullptr);
  s = Swapchain();
}

// Returns ok with extent 0x0 when the window is minimised (nothing created).
Status createSwapchain(Device& d, VkSurfaceKHR surface, GLFWwindow* win, bool vsync, Swapchain* out) {
  VkSurfaceCapabilitiesKHR caps;
  if (vkGetPhysicalDeviceSurfaceCapabilitiesKHR(d.physical, surface, &caps) != VK_SUCCESS)
    return Status::error("cannot query the window surface");
  int fw = 0, fh = 0;
  glfwGetFramebufferSize(win, &fw, &fh);
  VkExtent2D extent = caps.currentExtent;
  if (extent.width == 0xffffffffu) {
    extent.width = std::clamp(uint32_t(std::max(fw, 0)), caps.minImageExtent.width, caps.maxImageExtent.width);
    extent.height = std::clamp(uint32_t(std::max(fh, 0)), caps.minImageExtent.height, caps.maxImageExtent.height);
  }
  out->extent = extent;
  if (extent.width == 0 || extent.height == 0 || fw == 0 || fh == 0) {
    out->extent = {0, 0};
    return Status();
  }
  uint32_t n = 0;
  vkGetPhysicalDeviceSurfaceFormatsKHR(d.physical, surface, &n, nullptr);
  std::vector<VkSurfaceFormatKHR> formats(n);
  vkGetPhysicalDeviceSurfaceFormatsKHR(d.physical, surface, &n, formats.data());
  if (formats.empty()) return Status::error("the window surface offers no formats");
  VkSurfaceFormatKHR format = formats[0];
  for (const VkSurfaceFormatKHR& f : formats)  // sRGB like the offscreen target: the blit keeps the colours
    if ((f.format == VK_FORMAT_B8G8R8A8_SRGB || f.format == VK_FORMAT_R8G8B8A8_SRGB) &&
        f.colorSpace == VK_COLOR_SPACE_SRGB_NONLINEAR_KHR) {
      format = f;
      break;
    }
  vkGetPhysicalDeviceSurfacePresentModesKHR(d.physical, surface, &n, nullptr);
  std::vector<VkPresentModeKHR> modes(n);
  vkGetPhysicalDeviceSurfacePresentModesKHR(d.physical, surface, &n, modes.data());
  VkPresentModeKHR mode = VK_PRESENT_MODE_FIFO_KHR;  // vsync, always available
  if (!vsync)
    for (VkPresentModeKHR m : {VK_PRESENT_MODE_IMMEDIATE_KHR, VK_PRESENT_MODE_MAILBOX_KHR})
      if (std::find(modes.begin(), modes.end(), m) != modes.end()) {
        mode = m;
        break;
      }
  const VkImageUsageFlags need = VK_IMAGE_USAGE_TRANSFER_DST_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT;
  if ((caps.supportedUsageFlags & need) != need)
    return Status::error("the window surface does not allow transfer to and from its images");
  VkSwapchainCreateInfoKHR ci{VK_STRUCTURE_TYPE_SWAPCHAIN_CREATE_INFO_KHR};
  ci.surface = surface;
  ci.minImageCount = caps.maxImageCount ? std::min(caps.minImageCount + 1, caps.maxImageCount) : caps.minImageCount + 1;
  ci.imageFormat = format.format;
  ci.imageColorSpace = format.colorSpace;
  ci.imageExtent = extent;
  ci.imageArrayLayers = 1;
  ci.imageUsage = need;
  ci.imageSharingMode = VK_SHARING_MODE_EXCLUSIVE;
  ci.preTransform = caps.currentTransform;
  ci.compositeAlpha = (caps.supportedCompositeAlpha & VK_COMPOSITE_ALPHA_OPAQUE_BIT_KHR)
                          ? VK_COMPOSITE_ALPHA_OPAQUE_BIT_KHR
                          : VkCompositeAlphaFlagBitsKHR(caps.supportedCompositeAlpha & -caps.supportedCompositeAlpha);
  ci.presentMode = mode;
  ci.clipped = VK_TRUE;
  ci.oldSwapchain = out->swapchain;
  VkSwapchainKHR sc = VK_NULL_HANDLE;
  const VkResult r = vkCreateSwapchainKHR(d.device, &ci, nullptr, &sc);
  Swapchain old = *out;
  destroySwapchain(d, old);  // retired either way
  *out = Swapchain();
  if (r != VK_SUCCESS) return Status::error("vkCreateSwapchainKHR failed (" + std::to_string(int(r)) + ")");
  out->swapchain = sc;
  out->format = format.format;
  out->extent = extent;
  out->presentMode = mode;
  vkGetSwapchainImagesKHR(d.device, sc, &n, nullptr);
  std::vector<VkImage> images(n);
  vkGetSwapchainImagesKHR(d.device, sc, &n, images.data());
  for (VkImage img : images) {
    Image w;
    w.image = img;
    w.format = format.format;
    w.extent = {extent.width, extent.height, 1};
    out->images.push_back(w);
    VkSemaphoreCreateInfo si{VK_STRUCTURE_TYPE_SEMAPHORE_CREATE_INFO};
    VkSemaphore s = VK_NULL_HANDLE;
    if (vkCreateSemaphore(d.device, &si, nullptr, &s) != VK_SUCCESS) return Status::error("vkCreateSemaphore failed");
    out->rendered.push_back(s);
  }
  return Status();
}

// What the user changes while the window runs (keys, mouse, screenshot requests).
struct UserControls {
  const Options* options = nullptr;
  CanopyParams params;
  bool paramsChanged = false;
  CameraRig rig;
  bool paused = false, autoOrbit = false, screenshotRequested = false, close = false;
  double lastX = 0, lastY = 0;
  uint32_t layoutIndex = 1, sideIndex = 0;
};

const char* kLayouts[] = {"3", "5(3-1-1)", "7(3-2-2)"};
const uint32_t kSides[] = {kWindFromLeft, kWindFromBottom, kWindFromRight, kWindFromTop};
const char* kSideNames[] = {"left", "bottom", "right", "top"};
const char* kDebugNames[] = {"none", "layers (false colour)", "velocity field", "warp grid"};

void onKey(GLFWwindow* win, int key, int, int action, int) {
  if (action != GLFW_PRESS && action != GLFW_REPEAT) return;
  UserControls& l = *static_cast<UserControls*>(glfwGetWindowUserPointer(win));
  WindParams& wind = l.params.simulation.wind;
  bool changed = true;
  switch (key) {
    case GLFW_KEY_ESCAPE:
    case GLFW_KEY_Q: l.close = true; changed = false; break;
    case GLFW_KEY_LEFT:
    case GLFW_KEY_RIGHT:
      if (l.params.windMode == WindMode::World) {  // 45 degrees about the vertical, eased in (WorldWind.easeSeconds)
        const float a = glm::radians(key == GLFW_KEY_RIGHT ? 45.0f : -45.0f);
        const Float3 d = l.params.wind.direction;
        l.params.wind.direction = Float3{d.x * std::cos(a) - d.z * std::sin(a), d.y, d.x * std::sin(a) + d.z * std::cos(a)};
        std::printf("wind toward (%.2f, %.2f, %.2f)\n", l.params.wind.direction.x, l.params.wind.direction.y, l.params.wind.direction.z);
        break;
      }
      l.sideIndex = (l.sideIndex + (key == GLFW_KEY_RIGHT ? 1 : 3)) % 4;
      wind.sides = kSides[l.sideIndex];
      std::printf("wind from the %s\n", kSideNames[l.sideIndex]);
      break;
    case GLFW_KEY_UP:
    case GLFW_KEY_DOWN:
      if (l.params.windMode == WindMode::World) {
        l.params.wind.speed = std::clamp(l.params.wind.speed * (key == GLFW_KEY_UP ? 1.25f : 0.8f), 0.01f, 100.0f);
        std::printf("wind speed %.2f m/s\n", l.params.wind.speed);
        break;
      }
      wind.strength = std::clamp(wind.strength * (key == GLFW_KEY_UP ? 1.25f : 0.8f), 0.01f, 1000.0f);
      l.params.composite.debugVelocityScale = std::max(0.05f, wind.strength);
      std::printf("wind strength %.3f units/s\n", wind.strength);
      break;
    case GLFW_KEY_F:
    case GLFW_KEY_G:
      if (l.params.windMode == WindMode::World) {
        l.params.wind.gustFrequency = std::clamp(l.params.wind.gustFrequency * (key == GLFW_KEY_F ? 1.25f : 0.8f), 0.01f, 100.0f);
        std::printf("gust frequency %.3f Hz\n", l.params.wind.gustFrequency);
        break;
      }
      wind.frequency = std::clamp(wind.frequency * (key == GLFW_KEY_F ? 1.25f : 0.8f), 0.01f, 100.0f);
      std::printf("wind frequency %.3f Hz\n", wind.frequency);
      break;
    case GLFW_KEY_L:
      l.layoutIndex = (l.layoutIndex + 1) % 3;
      if (!parseLayerLayout(kLayouts[l.layoutIndex], &l.params.layers.layout).ok()) break;
      std::printf("layers %s\n", kLayouts[l.layoutIndex]);
      break;
    case GLFW_KEY_D:
      l.params.dynamics.delay = l.params.dynamics.delay == DelayMode::Exact ? DelayMode::Approximate : DelayMode::Exact;
      std::printf("%s delay\n", l.params.dynamics.delay == DelayMode::Exact ? "exact" : "approximate");
      break;
    case GLFW_KEY_V: {
      const uint32_t v = (uint32_t(l.params.composite.debugView) + 1) % 4;
      l.params.composite.debugView = CompositeDebugView(v);
      std::printf("debug view: %s\n", kDebugNames[v]);
      break;
    }
    case GLFW_KEY_J:
    case GLFW_KEY_K: {  // the light turns 15 degrees about the vertical
      Float3& d = l.params.layers.lightDirection;
      const float a = glm::radians(key == GLFW_KEY_K ? 15.0f : -15.0f), c = std::cos(a), s = std::sin(a);
      d = Float3{c * d.x + s * d.z, d.y, -s * d.x + c * d.z};
      std::printf("light towards (%.2f, %.2f, %.2f)\n", d.x, d.y, d.z);
      break;
    }
    case GLFW_KEY_M:
      l.params.animation = l.params.animation == AnimationMode::Layers2D ? AnimationMode::PerVertex : AnimationMode::Layers2D;
      std::printf("%s\n", l.params.animation == AnimationMode::PerVertex ? "per-vertex baseline (Habel)" : "2D layers");
      break;
    case GLFW_KEY_I: {  // impostors off -> far region -> by projected size (re-slices at once)
      ImpostorSettings& im = l.params.layers.impostors;
      im.mode = ImpostorMode((uint32_t(im.mode) + 1) % 3);
      if (im.mode != ImpostorMode::Off) l.params.layers.rebuildBudgetMs = 0.0f;
      const char* names[] = {"off", "far region", "by projected size"};
      std::printf("impostors: %s (switch at %g px)\n", names[uint32_t(im.mode)], im.switchPixels);
      break;
    }
    case GLFW_KEY_B:
      l.params.layers.impostors.debugView = !l.params.layers.impostors.debugView;
      std::printf("impostor debug view (colour by box level) %s\n", l.params.layers.impostors.debugView ? "on" : "off");
      break;
    case GLFW_KEY_T:
      l.params.layers.translucency = !l.params.layers.translucency;
      std::printf("translucency %s\n", l.params.layers.translucency ? "on" : "off");
      break;
    case GLFW_KEY_SPACE: l.paused = !l.paused; changed = false; std::printf(l.paused ? "paused\n" : "running\n"); break;
    case GLFW_KEY_O: l.autoOrbit = !l.autoOrbit; changed = false; break;
    case GLFW_KEY_P: l.screenshotRequested = true; changed = false; break;
    default: changed = false;
  }
  l.paramsChanged = l.paramsChanged || changed;
  std::fflush(stdout);
}

void onScroll(GLFWwindow* win, double, double dy) {
  UserControls& l = *static_cast<UserControls*>(glfwGetWindowUserPointer(win));
  l.rig.distance = std::clamp(l.rig.distance * std::pow(0.9f, float(dy)), 0.1f, 10.0f);
}

// The simulation-plane coordinates (domain units, wrapped into the simulated tile) under the
// cursor: the ray through the pixel meets the plane (same mapping as the velocity debug view).
bool cursorOnPlane(const gpu::AnimFrame& a, double px, double py, float* sx, float* sy) {
  if (a.width <= 0 || a.height <= 0) return false;
  const glm::vec2 ndc(float(px) / a.width * 2.0f - 1.0f, float(py) / a.height * 2.0f - 1.0f);
  const glm::vec4 n4 = a.invViewProj * glm::vec4(ndc, 0.0f, 1.0f), f4 = a.invViewProj * glm::vec4(ndc, 1.0f, 1.0f);
  const glm::vec3 o = glm::vec3(n4) / n4.w, dir = glm::vec3(f4) / f4.w - o;
  const glm::vec3 normal = glm::cross(glm::vec3(a.simRight), glm::vec3(a.simUp));
  const float den = glm::dot(dir, normal);
  if (std::abs(den) < 1e-8f) return false;
  const float t = glm::dot(glm::vec3(a.simOrigin) - o, normal) / den;
  if (t <= 0) return false;
  const glm::vec3 x = o + t * dir - glm::vec3(a.simOrigin);
  *sx = glm::fract(glm::dot(x, glm::vec3(a.simRight)) / a.simOrigin.w);
  *sy = glm::fract(glm::dot(x, glm::vec3(a.simUp)) / a.simOrigin.w);
  return true;
}

bool notBlank(const std::vector<uint8_t>& rgba) {
  for (size_t i = 4; i < rgba.size(); i += 4)
    if (std::abs(int(rgba[i]) - rgba[0]) + std::abs(int(rgba[i + 1]) - rgba[1]) + std::abs(int(rgba[i + 2]) - rgba[2]) > 24)
      return true;
  return false;
}

std::string titleOf(const std::string& label, double fps, const std::vector<PassTiming>& t, const UserControls& l) {
  std::map<std::string, double> groups;  // by the pass name's prefix: "sim", "layers", "dynamics", "composite"
  for (const PassTiming& p : t) groups[p.name.substr(0, p.name.find(':'))] += p.milliseconds;
  char b[512];
  if (l.params.animation == AnimationMode::PerVertex) {
    std::snprintf(b, sizeof b, "Canopy - %s - %.1f FPS - per-vertex baseline - %.2f ms%s", label.c_str(), fps,
                  groups["per-vertex"], l.paused ? " - paused" : "");
    return b;
  }
  std::snprintf(b, sizeof b, "Canopy - %s - %.1f FPS - %s - sim %.2f, layers %.2f, dynamics %.2f, composite %.2f ms%s",
                label.c_str(), fps, toString(l.params.layers.layout).c_str(), groups["sim"], groups["layers"],
                groups["dynamics"], groups["composite"], l.paused ? " - paused" : "");
  return b;
}

}  // namespace

// The window, or nullptr (with the reason printed) when there is no display, no Vulkan loader for
// windows or no window: the demo then runs headless.
GLFWwindow* openWindow(const Options& o) {
  if (!std::getenv("DISPLAY") && !std::getenv("WAYLAND_DISPLAY")) {
    std::fprintf(stderr, "canopy-demo: no display (DISPLAY and WAYLAND_DISPLAY are unset): running headless instead\n");
    return nullptr;
  }
  glfwSetErrorCallback([](int, const char* text) { g_glfwError = text ? text : "?"; });
  if (!glfwInit()) {
    std::fprintf(stderr, "canopy-demo: cannot open the display (%s): running headless instead\n", g_glfwError.c_str());
    return nullptr;
  }
  if (!glfwVulkanSupported()) {
    std::fprintf(stderr, "canopy-demo: GLFW finds no Vulkan loader for windows (%s): running headless instead\n",
                 g_glfwError.c_str());
    glfwTerminate();
    return nullptr;
  }
  glfwWindowHint(GLFW_CLIENT_API, GLFW_NO_API);
  GLFWwindow* win = glfwCreateWindow(int(o.width), int(o.height), "Canopy", nullptr, nullptr);
  if (!win) {
    std::fprintf(stderr, "canopy-demo: cannot create a window (%s): running headless instead\n", g_glfwError.c_str());
    glfwTerminate();
    return nullptr;
  }
  return win;
}

// Input: orbit with the left button (and the auto-orbit over `elapsed` seconds), a motor under the
// cursor with the right one; changed parameters applied.
void applyInput(GLFWwindow* win, UserControls& live, Host& host, VkExtent2D extent, double elapsed) {
  double cx = 0, cy = 0;
  glfwGetCursorPos(win, &cx, &cy);
  int ww = 1, wh = 1;
  glfwGetWindowSize(win, &ww, &wh);
  const double sx = double(extent.width) / std::max(ww, 1), sy = double(extent.height) / std::max(wh, 1);
  if (glfwGetMouseButton(win, GLFW_MOUSE_BUTTON_LEFT) == GLFW_PRESS) {
    live.rig.yaw -= float(cx - live.lastX) * 0.3f;
    live.rig.pitch = std::clamp(live.rig.pitch + float(cy - live.lastY) * 0.3f, -80.0f, 85.0f);
  }
  if (live.autoOrbit) live.rig.yaw += float(elapsed) * 10.0f;
  live.lastX = cx;
  live.lastY = cy;
  std::vector<Motor> motors;
  float mx = 0, my = 0;
  if (glfwGetMouseButton(win, GLFW_MOUSE_BUTTON_RIGHT) == GLFW_PRESS &&
      cursorOnPlane(canopyDynamics(host.canopy).current, cx * sx, cy * sy, &mx, &my))
    motors.push_back({mx, my, 0.08f, 3.0f * std::max(0.3f, live.params.simulation.wind.strength)});
  if (motors.size() != live.params.simulation.motors.size() ||
      (!motors.empty() && (motors[0].x != live.params.simulation.motors[0].x || motors[0].y != live.params.simulation.motors[0].y))) {
    live.params.simulation.motors = motors;
    live.paramsChanged = true;
  }
  if (live.paramsChanged) {
    const Status ps = setCanopyParams(host.canopy, live.params);
    if (!ps.ok()) std::fprintf(stderr, "canopy-demo: %s\n", ps.message().c_str());
    live.params = canopyParams(host.canopy);
    live.paramsChanged = false;
  }
}

// Submits the slot's command buffer (waiting for the image's acquire, signalling its render) and
// presents swapchain image `index`; *recreate when the swapchain is out of date or suboptimal.
Status submitAndPresent(Device& dev, FrameRing& ring, Swapchain& sc, uint32_t slot, uint32_t index, bool* recreate) {
  VkSemaphoreSubmitInfo wait{VK_STRUCTURE_TYPE_SEMAPHORE_SUBMIT_INFO}, signal{VK_STRUCTURE_TYPE_SEMAPHORE_SUBMIT_INFO};
  wait.semaphore = ring.acquired[slot];
  wait.stageMask = VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT;
  signal.semaphore = sc.rendered[index];
  signal.stageMask = VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT;
  VkCommandBufferSubmitInfo cbi{VK_STRUCTURE_TYPE_COMMAND_BUFFER_SUBMIT_INFO};
  cbi.commandBuffer = ring.cmds[slot];
  VkSubmitInfo2 submit{VK_STRUCTURE_TYPE_SUBMIT_INFO_2};
  submit.waitSemaphoreInfoCount = 1;
  submit.pWaitSemaphoreInfos = &wait;
  submit.commandBufferInfoCount = 1;
  submit.pCommandBufferInfos = &cbi;
  submit.signalSemaphoreInfoCount = 1;
  submit.pSignalSemaphoreInfos = &signal;
  auto queueSubmit2 = reinterpret_cast<PFN_vkQueueSubmit2>(vkGetDeviceProcAddr(dev.device, "vkQueueSubmit2"));
  if (!queueSubmit2) queueSubmit2 = reinterpret_cast<PFN_vkQueueSubmit2>(vkGetDeviceProcAddr(dev.device, "vkQueueSubmit2KHR"));
  if (!queueSubmit2 || queueSubmit2(dev.queue, 1, &submit, ring.fences[slot]) != VK_SUCCESS) return Status::error("vkQueueSubmit2 failed");
  VkPresentInfoKHR pi{VK_STRUCTURE_TYPE_PRESENT_INFO_KHR};
  pi.waitSemaphoreCount = 1;
  pi.pWaitSemaphores = &sc.rendered[index];
  pi.swapchainCount = 1;
  pi.pSwapchains = &sc.swapchain;
  pi.pImageIndices = &index;
  const VkResult r = vkQueuePresentKHR(dev.queue, &pi);
  if (r == VK_ERROR_OUT_OF_DATE_KHR || r == VK_SUBOPTIMAL_KHR) *recreate = true;
  else if (r != VK_SUCCESS) return Status::error("vkQueuePresentKHR failed (" + std::to_string(int(r)) + ")");
  return Status();
}

// The slot's presented frame (already finished) read back and written as PNG: at --screenshot's path
// for the last frame, else outDir/screenshot_N.png; a blank one is an error.
Status saveScreenshot(const Options& o, Host& host, uint32_t slot, UserControls& live, uint32_t* screenshots) {
  std::vector<uint8_t> rgba;
  readPixels(host, slot, &rgba);
  std::string path = o.screenshot;
  if (live.screenshotRequested || path.empty()) {
    std::filesystem::create_directories(o.outDir);
    path = o.outDir + "/screenshot_" + std::to_string((*screenshots)++) + ".png";
  }
  live.screenshotRequested = false;
  std::error_code ec;
  if (std::filesystem::path(path).has_parent_path()) std::filesystem::create_directories(std::filesystem::path(path).parent_path(), ec);
  CANOPY_TRY(writePng(path, host.width, host.height, rgba));
  std::printf("screenshot %s: %ux%u read back from the swapchain image\n", path.c_str(), host.width, host.height);
  if (!notBlank(rgba)) return Status::error("the screenshot " + path + " is blank (one colour)");
  return Status();
}

// The device for the window: GLFW's instance extensions, the swapchain, validation (each message
// counted in *messages and printed) as the options ask.
DeviceDesc windowDeviceDesc(const Options& o, int* messages) {
  uint32_t extCount = 0;
  const char** exts = glfwGetRequiredInstanceExtensions(&extCount);
  DeviceDesc dd;
  dd.applicationName = "canopy-demo";
  dd.preferredDevice = o.device;
  dd.instanceExtensions.assign(exts, exts + extCount);
  dd.deviceExtensions = {VK_KHR_SWAPCHAIN_EXTENSION_NAME};
  if (o.validate) {
    dd.enableValidation = dd.requireValidation = true;
    dd.validationSink = [messages](VkDebugUtilsMessageSeverityFlagBitsEXT, const char* id, const char* text) {
      ++*messages;
      std::fprintf(stderr, "validation: %s: %s\n", id ? id : "", text);
    };
  }
  return dd;
}

int runWindow(const Options& o, const VegetationModel& model, const std::string& label) {
  GLFWwindow* win = openWindow(o);
  if (!win) return -1;
  int messages = 0;
  const DeviceDesc dd = windowDeviceDesc(o, &messages);
  Device dev;
  VkSurfaceKHR surface = VK_NULL_HANDLE;
  Swapchain sc;
  Host host;
  FrameRing ring;  // two frames in flight: the loop waits only for the slot's previous frame
  uint64_t frameNumber = 0;
  UserControls live;
  live.options = &o;
  live.rig = defaultRig(o);
  uint64_t frames = 0;
  Status s = [&]() -> Status {
    CANOPY_TRY(createDevice(dd, &dev));
    if (glfwCreateWindowSurface(dev.instance, win, nullptr, &surface) != VK_SUCCESS)
      return Status::error("cannot create a Vulkan surface for the window (" + g_glfwError + ")");
    VkBool32 presentable = VK_FALSE;
    vkGetPhysicalDeviceSurfaceSupportKHR(dev.physical, dev.queueFamily, surface, &presentable);
    if (!presentable) return Status::error(std::string(dev.properties.deviceName) + " cannot present to this window");
    CANOPY_TRY(createFrameRing(dev, &ring));

    glfwSetWindowUserPointer(win, &live);
    glfwSetKeyCallback(win, onKey);
    glfwSetScrollCallback(win, onScroll);
    std::printf("canopy-demo window: %s. Left drag orbit, wheel zoom, right drag push foliage; arrows wind direction "
                "and strength, F/G frequency, L layout, D delay, V debug view, space pause, O auto-orbit, P screenshot, "
                "Esc quit.\n",
                label.c_str());
    std::fflush(stdout);

    bool recreate = true;
    double lastTitle = 0, orbitClock = glfwGetTime();
    std::vector<double> recentWall;
    auto lastFrameEnd = std::chrono::steady_clock::now();
    std::vector<PassTiming> lastTimings;
    uint32_t screenshots = 0;
    while (!glfwWindowShouldClose(win) && !live.close) {
      glfwPollEvents();
      if (recreate) {
        vkDeviceWaitIdle(dev.device);  // resize path: the swapchain and targets are recreated
        CANOPY_TRY(createSwapchain(dev, surface, win, o.vsync, &sc));
        if (sc.extent.width == 0) {  // minimised: nothing to draw until it comes back
          glfwWaitEvents();
          continue;
        }
        if (!host.device || host.width != sc.extent.width || host.height != sc.extent.height ||
            host.presentFormat != sc.format) {
          if (!host.canopy) {
            // With a read-back copy of every presented frame: P (or --screenshot) saves what was on screen.
            CANOPY_TRY(createHost(dev, model, o, sc.extent.width, sc.extent.height, true, sc.format, &host));
            live.params = canopyParams(host.canopy);
          } else {  // the scene, the simulation and the live parameters are kept
            CANOPY_TRY(resizeHost(host, sc.extent.width, sc.extent.height, sc.format));
            std::printf("Canopy resized to %ux%u: scene and simulation kept (%llu steps so far)\n", sc.extent.width,
                        sc.extent.height, (unsigned long long)canopyStats(host.canopy).simulation.steps);
          }
          std::printf("swapchain %ux%u (%s)\n", sc.extent.width, sc.extent.height,
                      sc.presentMode == VK_PRESENT_MODE_FIFO_KHR ? "vsync" : "no vsync");
          std::fflush(stdout);
        }
        recreate = false;
      }
      const double now = glfwGetTime();
      applyInput(win, live, host, sc.extent, now - orbitClock);
      orbitClock = now;

      // The slot's previous frame (two frames ago) must be done before its command buffer, fence,
      // acquire semaphore and read-back buffer are reused; the frame just before may still run.
      const uint32_t slot = uint32_t(frameNumber % Host::kFramesInFlight);
      auto retire = [&](uint32_t k) -> Status {
        bool waited = false;
        CANOPY_TRY(waitFrameSlot(dev, ring, k, &waited));
        return waited ? host.timer[k].read(dev, &lastTimings) : Status();
      };
      CANOPY_TRY(retire(slot));
      uint32_t index = 0;
      VkResult r = vkAcquireNextImageKHR(dev.device, sc.swapchain, UINT64_MAX, ring.acquired[slot], VK_NULL_HANDLE, &index);
      if (r == VK_ERROR_OUT_OF_DATE_KHR) {
        recreate = true;
        continue;
      }
      if (r != VK_SUCCESS && r != VK_SUBOPTIMAL_KHR) return Status::error("vkAcquireNextImageKHR failed (" + std::to_string(int(r)) + ")");
      CanopyFrame f;
      f.camera = toCamera(cameraView(live.rig, model, sc.extent.width, sc.extent.height));
      f.dt = live.paused ? 0.0f : 1.0f / o.fps;
      f.frameNumber = ++frameNumber;
      CANOPY_TRY(recordFrameSlot(host, ring, slot, f, &sc.images[index]));
      CANOPY_TRY(submitAndPresent(dev, ring, sc, slot, index, &recreate));
      ring.pending[slot] = true;
      // Frame interval, wall clock (with frames in flight a frame's own submit-to-fence overlaps the next).
      const auto frameEnd = std::chrono::steady_clock::now();
      if (frames > 0) recentWall.push_back(std::chrono::duration<double, std::milli>(frameEnd - lastFrameEnd).count());
      lastFrameEnd = frameEnd;
      frames++;

      const bool last = o.frames && frames >= o.frames;
      if (live.screenshotRequested || (last && !o.screenshot.empty())) {
        CANOPY_TRY(retire(slot));  // this frame's pixels: wait for it alone
        CANOPY_TRY(saveScreenshot(o, host, slot, live, &screenshots));
      }
      if (now - lastTitle > 0.5) {
        const double fps = 1000.0 / std::max(median(recentWall), 1e-3);
        glfwSetWindowTitle(win, titleOf(label, fps, lastTimings, live).c_str());
        recentWall.clear();
        lastTitle = now;
      }
      if (o.resizeAt && frames == o.resizeAt) {
        glfwSetWindowSize(win, int(o.width) * 3 / 4, int(o.height) * 3 / 4);
        std::printf("resizing the window to %ux%u\n", o.width * 3 / 4, o.height * 3 / 4);
        recreate = true;  // also reported as out of date / suboptimal by the driver
      }
      int fw = 0, fh = 0;
      glfwGetFramebufferSize(win, &fw, &fh);
      if (uint32_t(fw) != sc.extent.width || uint32_t(fh) != sc.extent.height) recreate = true;
      if (last) break;
    }
    return Status();
  }();
  if (dev.device) vkDeviceWaitIdle(dev.device);
  if (!s.ok()) std::fprintf(stderr, "canopy-demo: %s\n", s.message().c_str());
  else std::printf("window closed after %llu frames\n", (unsigned long long)frames);
  destroyHost(host);
  if (dev.device) {
    destroyFrameRing(dev, ring);  // after the device idled above (shutdown)
    destroySwapchain(dev, sc);
  }
  if (surface) vkDestroySurfaceKHR(dev.instance, surface, nullptr);
  destroyDevice(dev);
  glfwDestroyWindow(win);
  glfwTerminate();
  if (messages > 0) {
    std::fprintf(stderr, "canopy-demo: %d validation messages\n", messages);
    return 1;
  }
  return s.ok() ? 0 : 1;
}

}  // namespace canopy::demo
