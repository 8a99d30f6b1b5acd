#include "render/host_camera.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

#include "engine/camera.h"

namespace canopy {
namespace {

std::string num(float v) {
  char b[32];
  std::snprintf(b, sizeof b, "%g", double(v));
  return b;
}

// Column-major clip -> clip map: x' = ax x + bx w, y' = ay y + by w, z' = az z + bz w.
glm::mat4 clipMap(float ax, float bx, float ay, float by, float az, float bz) {
  glm::mat4 m(1.0f);
  m[0][0] = ax;
  m[3][0] = bx;
  m[1][1] = ay;
  m[3][1] = by;
  m[2][2] = az;
  m[3][2] = bz;
  return m;
}

}  // namespace

Status hostCamera(const CanopyCamera& cam, uint32_t width, uint32_t height, HostCamera* out) {
  HostCamera h;
  const float W = float(width), H = float(height);
  const VkViewport& v = cam.viewport;
  if (cam.clipDepth != ClipDepth::ZeroToOne && cam.clipDepth != ClipDepth::NegativeOneToOne)
    return Status::error("CanopyCamera.clipDepth = " + std::to_string(uint32_t(cam.clipDepth)) +
                         " is not ZeroToOne (0) or NegativeOneToOne (1)");
  for (float f : {v.x, v.y, v.width, v.height, v.minDepth, v.maxDepth, cam.jitter[0], cam.jitter[1]})
    if (!std::isfinite(f)) return Status::error("CanopyCamera.viewport or .jitter has a non-finite element");
  for (int i = 0; i < 2; ++i)
    if (std::abs(cam.jitter[i]) > 1.0f)
      return Status::error(std::string("CanopyCamera.jitter.") + (i ? "y" : "x") + " = " + num(cam.jitter[i]) +
                           " pixels is outside [-1, 1] (a sub-pixel offset)");
  glm::mat4 fold(1.0f);
  h.scissor = {{0, 0}, {width, height}};
  const bool whole = v.width == 0.0f && v.height == 0.0f;
  if (!whole) {
    const std::string where = "CanopyCamera.viewport = {" + num(v.x) + ", " + num(v.y) + ", " + num(v.width) + ", " + num(v.height) + "}";
    // The rectangle the viewport covers (a negative height starts at y and runs up, as in Vulkan).
    const float x0 = v.x, x1 = v.x + v.width, y0 = std::min(v.y, v.y + v.height), y1 = std::max(v.y, v.y + v.height);
    if (!(v.width > 0.0f) || v.height == 0.0f)
      return Status::error(where + ": width must be > 0 and height non-zero (or both 0: the whole targets)");
    if (x0 < 0.0f || y0 < 0.0f || x1 > W || y1 > H)
      return Status::error(where + " reaches outside the " + std::to_string(width) + "x" + std::to_string(height) + " targets");
    if (v.minDepth != 0.0f || v.maxDepth != 1.0f)
      return Status::error(where + ": minDepth = " + num(v.minDepth) + ", maxDepth = " + num(v.maxDepth) +
                           ": Canopy reads and writes the whole depth range (0 and 1 only)");
    // Vulkan's viewport transform: pixel = x + (ndc + 1) / 2 * width; as the whole targets' NDC,
    // ndc' = 2 pixel / W - 1 = (width / W) ndc + (2 x + width) / W - 1 (y likewise, height signed).
    fold = clipMap(v.width / W, (2.0f * v.x + v.width) / W - 1.0f, v.height / H, (2.0f * v.y + v.height) / H - 1.0f, 1.0f, 0.0f);
    // The pixels whose centres the viewport covers, at least one.
    const int32_t sx0 = int32_t(std::lround(x0)), sy0 = int32_t(std::lround(y0));
    const int32_t sx1 = std::max(int32_t(std::lround(x1)), sx0 + 1), sy1 = std::max(int32_t(std::lround(y1)), sy0 + 1);
    h.scissor = {{sx0, sy0}, {uint32_t(std::min<int32_t>(sx1, int32_t(width)) - sx0), uint32_t(std::min<int32_t>(sy1, int32_t(height)) - sy0)}};
  }
  // GL's clip depth (-w..w) to Vulkan's (0..w): z' = (z + w) / 2, the depth the host's
  // negativeOneToOne viewport writes.
  const glm::mat4 depth = cam.clipDepth == ClipDepth::NegativeOneToOne ? clipMap(1.0f, 0.0f, 1.0f, 0.0f, 0.5f, 0.5f) : glm::mat4(1.0f);
  fold = fold * depth;
  h.inViewport.view = cam.view;
  h.inViewport.proj = toFloat4x4(depth * toGlm(cam.proj));
  h.camera.view = cam.view;
  h.camera.proj = toFloat4x4(fold * toGlm(cam.proj));
  h.jitterPixels = glm::vec2(cam.jitter[0], cam.jitter[1]);
  h.jitter = clipMap(1.0f, 2.0f * cam.jitter[0] / W, 1.0f, 2.0f * cam.jitter[1] / H, 1.0f, 0.0f);
  *out = h;
  return Status();
}

}  // namespace canopy
