#include "engine/camera.h"

#include <algorithm>
#include <cmath>
#include <glm/gtc/matrix_transform.hpp>

namespace canopy {

glm::mat4 toGlm(const Float4x4& m) {
  glm::mat4 r;
  for (int c = 0; c < 4; ++c)
    for (int row = 0; row < 4; ++row) r[c][row] = m.m[c * 4 + row];
  return r;
}

Float4x4 toFloat4x4(const glm::mat4& m) {
  Float4x4 r;
  for (int c = 0; c < 4; ++c)
    for (int row = 0; row < 4; ++row) r.m[c * 4 + row] = m[c][row];
  return r;
}

CanopyCamera toCamera(const LayerView& v) { return {toFloat4x4(v.view), toFloat4x4(v.proj)}; }
LayerView toLayerView(const CanopyCamera& c) { return {toGlm(c.view), toGlm(c.proj)}; }

glm::mat4 perspectiveVulkan(float fovY, float aspect, float zNear, float zFar) {
  glm::mat4 p = glm::perspectiveRH_ZO(fovY, aspect, zNear, zFar);
  p[1][1] *= -1.0f;  // Vulkan's clip space has y pointing down
  return p;
}

LayerView orbitView(const glm::vec3& bmin, const glm::vec3& bmax, float yawDegrees, float pitchDegrees,
                    float fovYDegrees, float aspect, float distanceScale) {
  const glm::vec3 centre = 0.5f * (bmin + bmax);
  const float radius = std::max(0.5f * glm::length(bmax - bmin), 1e-6f);
  const float fov = glm::radians(std::clamp(fovYDegrees, 1.0f, 170.0f));
  const float distance = distanceScale * radius / std::sin(0.5f * fov);
  const float yaw = glm::radians(yawDegrees), pitch = glm::radians(std::clamp(pitchDegrees, -89.0f, 89.0f));
  const glm::vec3 dir{std::sin(yaw) * std::cos(pitch), std::sin(pitch), std::cos(yaw) * std::cos(pitch)};
  LayerView v;
  v.view = glm::lookAtRH(centre + distance * dir, centre, glm::vec3(0, 1, 0));
  const float zNear = std::max(distance - radius * 1.5f, distance * 1e-3f);
  v.proj = perspectiveVulkan(fov, aspect, zNear, distance + radius * 1.5f);
  return v;
}

glm::vec3 viewPosition(const glm::mat4& view) { return glm::vec3(glm::inverse(view)[3]); }
glm::vec3 viewForward(const glm::mat4& view) { return -glm::normalize(glm::vec3(view[0][2], view[1][2], view[2][2])); }
glm::vec3 viewUp(const glm::mat4& view) { return glm::normalize(glm::vec3(view[0][1], view[1][1], view[2][1])); }

}  // namespace canopy
