#include "tools/camera_paths.h"

#include <algorithm>
#include <cmath>

#include <glm/gtc/matrix_transform.hpp>

namespace canopy {
namespace {

struct Named {
  CameraMotion motion;
  const char* name;
};
constexpr Named kNames[] = {{CameraMotion::Still, "still"},   {CameraMotion::Orbit, "orbit"}, {CameraMotion::Dolly, "dolly"},
                            {CameraMotion::Strafe, "strafe"}, {CameraMotion::Turn, "turn"},   {CameraMotion::Zoom, "zoom"},
                            {CameraMotion::Walk, "walk"}};

glm::vec3 direction(float yawDegrees, float pitchDegrees) {
  const float yaw = glm::radians(yawDegrees), pitch = glm::radians(std::clamp(pitchDegrees, -89.0f, 89.0f));
  return {std::sin(yaw) * std::cos(pitch), std::sin(pitch), std::cos(yaw) * std::cos(pitch)};
}

// Eye, the point looked at and the field of view; near and far planes around the vegetation.
LayerView lookFrom(const glm::vec3& eye, const glm::vec3& target, float fovYDegrees, float aspect, const glm::vec3& centre,
                   float radius) {
  LayerView v;
  v.view = glm::lookAtRH(eye, target, glm::vec3(0, 1, 0));
  const float d = glm::length(centre - eye);
  const float zNear = std::max(d - 1.5f * radius, 1e-3f * d);  // as orbitView
  v.proj = perspectiveVulkan(glm::radians(std::clamp(fovYDegrees, 1.0f, 170.0f)), aspect, zNear, d + 1.5f * radius);
  return v;
}

}  // namespace

Status parseCameraMotion(const std::string& name, CameraMotion* out) {
  std::string all;
  for (const Named& n : kNames) {
    if (name == n.name) {
      *out = n.motion;
      return Status();
    }
    all += std::string(all.empty() ? "" : ", ") + n.name;
  }
  return Status::error("camera path '" + name + "' is not one of " + all);
}

const char* cameraMotionName(CameraMotion m) {
  for (const Named& n : kNames)
    if (n.motion == m) return n.name;
  return "?";
}

float pingPong(float t, float rate, float a) {
  const float x = t * rate;
  if (a <= 0.0f) return x;
  // Period 4a: 0 -> a -> 0 -> -a -> 0.
  const float u = std::fmod(std::fmod(x, 4.0f * a) + 4.0f * a, 4.0f * a);
  return u < a ? u : (u < 3.0f * a ? 2.0f * a - u : u - 4.0f * a);
}

LayerView cameraPathView(const CameraPath& p, const glm::vec3& bmin, const glm::vec3& bmax, float aspect, uint32_t frame) {
  const glm::vec3 centre = 0.5f * (bmin + bmax);
  const float radius = std::max(0.5f * glm::length(bmax - bmin), 1e-6f);
  const float fov = std::clamp(p.fovY, 1.0f, 170.0f);
  const float start = p.distanceScale * radius / std::sin(0.5f * glm::radians(fov));
  const float t = float(frame);
  const glm::vec3 toEye = direction(p.yaw, p.pitch);
  switch (p.motion) {
    case CameraMotion::Still: break;
    case CameraMotion::Orbit:
      return lookFrom(centre + start * direction(p.yaw + p.degreesPerFrame * t, p.pitch), centre, fov, aspect, centre, radius);
    case CameraMotion::Dolly: {
      // |pingPong| goes 0 -> a -> 0: towards the vegetation and back, never closer than 1.2 radii.
      const float reach = std::max(start - 1.2f * radius, 0.0f);
      const float d = start - std::fabs(pingPong(t, p.radiiPerFrame * radius, reach));
      return lookFrom(centre + std::max(d, 1.2f * radius) * toEye, centre, fov, aspect, centre, radius);
    }
    case CameraMotion::Strafe: {
      const glm::vec3 right = glm::normalize(glm::cross(-toEye, glm::vec3(0, 1, 0)));
      const glm::vec3 shift = pingPong(t, p.radiiPerFrame * radius, radius) * right;
      return lookFrom(centre + start * toEye + shift, centre + shift, fov, aspect, centre, radius);
    }
    case CameraMotion::Turn: {
      const glm::vec3 eye = centre + start * toEye;
      const glm::vec3 look = direction(p.yaw + pingPong(t, p.degreesPerFrame, p.amplitudeDegrees) + 180.0f, -p.pitch);
      return lookFrom(eye, eye + look, fov, aspect, centre, radius);
    }
    case CameraMotion::Zoom:
      return lookFrom(centre + start * toEye, centre, fov + pingPong(t, p.degreesPerFrame, p.amplitudeDegrees), aspect, centre,
                      radius);
    case CameraMotion::Walk: {
      // Eye height a sixth of the way up the box, from the front edge (+Z) towards the back, at most
      // the box's depth and back again; the gaze swings left and right, a little down.
      const float depth = std::max(bmax.z - bmin.z, 1e-6f);
      const float walked = std::fabs(pingPong(t, p.radiiPerFrame * radius, depth));
      const glm::vec3 eye{centre.x, bmin.y + (bmax.y - bmin.y) / 6.0f, bmax.z - walked};
      const glm::vec3 look = direction(180.0f + pingPong(t, p.degreesPerFrame, p.amplitudeDegrees), -8.0f);
      LayerView v;
      v.view = glm::lookAtRH(eye, eye + look, glm::vec3(0, 1, 0));
      v.proj = perspectiveVulkan(glm::radians(fov), aspect, 0.002f * radius, 2.5f * radius);
      return v;
    }
  }
  return lookFrom(centre + start * toEye, centre, fov, aspect, centre, radius);
}

}  // namespace canopy
