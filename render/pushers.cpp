#include "render/pushers.h"

#include <cmath>
#include <string>

namespace canopy {

Status checkPushers(const std::vector<CanopyPusher>& pushers) {
  // More than the cap is refused, not merged: which to merge is the host's call (the nearest to
  // the camera, the player) and a silent merge would hide it.
  if (pushers.size() > kMaxPushers)
    return Status::error(Result::InvalidArgument, "setCanopyPushers: " + std::to_string(pushers.size()) + " pushers given, at most " +
                                                      std::to_string(kMaxPushers) + " (kMaxPushers)");
  for (size_t i = 0; i < pushers.size(); ++i)
    CANOPY_TRY(checkParams(pushers[i], "setCanopyPushers: pushers[" + std::to_string(i) + "]."));
  return Status();
}

BendPlane bendPlaneOf(const SimulationPlane& plane) {
  const glm::vec3 Y(0.0f, 1.0f, 0.0f), right = toGlm(plane.right), up = toGlm(plane.up);
  BendPlane b;
  b.tile = plane.tileSize;
  glm::vec3 x = right - glm::dot(right, Y) * Y;
  if (glm::length(x) < 1e-3f) x = up - glm::dot(up, Y) * Y;  // a plane seen from straight above or below
  b.x = glm::length(x) < 1e-3f ? glm::vec3(1.0f, 0.0f, 0.0f) : glm::normalize(x);
  b.z = glm::normalize(glm::cross(b.x, Y));
  const glm::vec3 centre = toGlm(plane.origin) + 0.5f * plane.tileSize * (right + up);
  b.origin = centre - 0.5f * float(SIM_BEND_SCALE) * plane.tileSize * (b.x + b.z);
  return b;
}

float pusherHeight(const std::vector<CanopyPusher>& pushers, float previous) {
  if (pushers.empty()) return previous;
  double sum = 0;
  for (const CanopyPusher& p : pushers) sum += std::min(p.a.y, p.b.y);
  return float(sum / double(pushers.size()));
}

void mapPushers(const std::vector<CanopyPusher>& pushers, const SimulationPlane& plane, const LayerView& camera,
                std::vector<gpu::SimMotor>* motors, PusherCounts* counts) {
  motors->clear();
  *counts = PusherCounts{};
  const glm::vec3 origin = toGlm(plane.origin), right = toGlm(plane.right), up = toGlm(plane.up);
  const float tile = plane.tileSize;
  const glm::vec3 eye = viewPosition(camera.view), forward = viewForward(camera.view);
  auto onPlane = [&](glm::vec3 p) { return glm::vec2(glm::dot(p - origin, right), glm::dot(p - origin, up)) / tile; };
  const BendPlane ground = bendPlaneOf(plane);
  auto onGround = [&](glm::vec3 p) { return glm::vec2(glm::dot(p - ground.origin, ground.x), glm::dot(p - ground.origin, ground.z)) / tile; };
  for (const CanopyPusher& p : pushers) {
    const glm::vec3 a = toGlm(p.a), b = toGlm(p.b);
    // Wholly behind the camera: its nearest point's view depth below zero.
    if (std::max(glm::dot(a - eye, forward), glm::dot(b - eye, forward)) + p.radius < 0.0f) {
      counts->behind++;
      continue;
    }
    const glm::vec2 pa = onPlane(a), pb = onPlane(b), ga = onGround(a), gb = onGround(b);
    const float R = p.radius / tile;
    const glm::vec2 lo = glm::min(ga, gb) - R, hi = glm::max(ga, gb) + R;
    const float domain = float(SIM_BEND_SCALE);
    if (!(hi.x > 0.0f && hi.y > 0.0f && lo.x < domain && lo.y < domain) || !std::isfinite(R) || R <= 0.0f) {
      counts->outside++;
      continue;
    }
    const glm::vec2 shift = glm::floor(0.5f * (pa + pb));  // the fluid's tile: the plants read it through fract()
    const glm::vec2 v = onPlane(origin + toGlm(p.velocity)) * p.air;
    gpu::SimMotor m;
    m.segment = glm::vec4(pa - shift, pb - shift);
    m.flow = glm::vec4(R, p.blow / tile, v.x, v.y);
    m.bend = glm::vec4(p.bend * kPusherBendUnit, R, std::max(a.y, b.y) + p.radius, p.radius);
    m.ground = glm::vec4(ga, gb);
    motors->push_back(m);
    counts->mapped++;
  }
}

glm::vec2 sampleTiledWind(const float* field, uint32_t n, glm::vec2 a) {
  const glm::vec2 x = (a - glm::floor(a)) * float(n) - 0.5f;
  const glm::vec2 fl = glm::floor(x), t = x - fl;
  const int i0 = int(fl.x), j0 = int(fl.y), N = int(n);
  auto at = [&](int i, int j) {
    const size_t c = size_t(((j % N) + N) % N) * n + size_t(((i % N) + N) % N);
    return glm::vec2(field[2 * c], field[2 * c + 1]);
  };
  return glm::mix(glm::mix(at(i0, j0), at(i0 + 1, j0), t.x), glm::mix(at(i0, j0 + 1), at(i0 + 1, j0 + 1), t.x), t.y);
}

glm::vec3 windAtWorld(const float* field, uint32_t n, const SimulationPlane& plane, glm::vec3 p) {
  const glm::vec3 origin = toGlm(plane.origin), right = toGlm(plane.right), up = toGlm(plane.up);
  const glm::vec2 a = glm::vec2(glm::dot(p - origin, right), glm::dot(p - origin, up)) / plane.tileSize;
  const glm::vec2 v = sampleTiledWind(field, n, a) * plane.tileSize;  // domain units/s -> world units/s
  return v.x * right + v.y * up;
}

}  // namespace canopy
