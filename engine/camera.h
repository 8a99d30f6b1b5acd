#pragma once
// Camera helpers for the layer views: right-handed view matrices (camera looks down -Z) and
// projections into Vulkan clip space (y down, depth 0..1).
#include <glm/glm.hpp>

#include "engine/status.h"

namespace canopy {

struct LayerView {
  glm::mat4 view{1.0f};  // world -> view
  glm::mat4 proj{1.0f};  // view -> Vulkan clip space
};

// Conversions between the public API's plain types and glm.
inline glm::vec3 toGlm(const Float3& v) { return {v.x, v.y, v.z}; }
inline Float3 toFloat3(const glm::vec3& v) { return {v.x, v.y, v.z}; }
glm::mat4 toGlm(const Float4x4& m);
Float4x4 toFloat4x4(const glm::mat4& m);
// The public camera of a layer view, and back.
CanopyCamera toCamera(const LayerView& view);
LayerView toLayerView(const CanopyCamera& camera);

// Perspective projection for Vulkan; fovY in radians, zNear > 0, zFar > zNear.
glm::mat4 perspectiveVulkan(float fovY, float aspect, float zNear, float zFar);

// A camera orbiting the centre of the box [bmin, bmax]: yaw about +Y (0 = looking along -Z from
// the +Z side, glTF's front), pitch up from the horizon, both in degrees; distance chosen so the
// bounding sphere fills the vertical field of view (fovYDegrees), times distanceScale.
LayerView orbitView(const glm::vec3& bmin, const glm::vec3& bmax, float yawDegrees, float pitchDegrees,
                    float fovYDegrees, float aspect, float distanceScale = 1.0f);

// Camera position and unit forward/up vectors of a view matrix.
glm::vec3 viewPosition(const glm::mat4& view);
glm::vec3 viewForward(const glm::mat4& view);
glm::vec3 viewUp(const glm::mat4& view);

}  // namespace canopy
