#include "render/world_wind.h"

#include <algorithm>
#include <cmath>

namespace canopy {

glm::vec3 windDirectionOf(const Float3& v) {
  const glm::vec3 d = toGlm(v);
  const float len = glm::length(d);
  return len > 1e-12f && std::isfinite(len) ? d / len : glm::vec3(1.0f, 0.0f, 0.0f);
}

namespace {
// The shortest arc from a to b at s in [0, 1] (opposite directions turn about the vertical).
glm::vec3 arc(const glm::vec3& a, const glm::vec3& b, float s) {
  const float c = std::clamp(glm::dot(a, b), -1.0f, 1.0f);
  const float angle = std::acos(c);
  if (angle < 1e-4f) return b;
  glm::vec3 axis = glm::cross(a, b);
  if (glm::length(axis) < 1e-6f) {  // opposite: about the vertical, or about X for a vertical wind
    axis = glm::cross(a, glm::vec3(0.0f, 1.0f, 0.0f));
    if (glm::length(axis) < 1e-6f) axis = glm::vec3(1.0f, 0.0f, 0.0f);
  }
  axis = glm::normalize(axis);
  const float t = angle * s;
  // Rodrigues' rotation of a about the axis (a is perpendicular to it).
  const glm::vec3 r = a * std::cos(t) + glm::cross(axis, a) * std::sin(t) + axis * glm::dot(axis, a) * (1.0f - std::cos(t));
  return glm::normalize(r);
}
}  // namespace

void stepWorldWind(WorldWindState& s, const WorldWind& target, float dt) {
  if (!s.started) {
    s.started = true;
    s.target = target;
    s.direction = s.fromDirection = s.toDirection = windDirectionOf(target.direction);
    s.speed = s.fromSpeed = target.speed;
    s.elapsed = target.easeSeconds;
    return;
  }
  if (!(target.direction == s.target.direction) || target.speed != s.target.speed) {
    s.fromDirection = s.direction;  // from where it stands, mid-ease included: no pop
    s.fromSpeed = s.speed;
    s.toDirection = windDirectionOf(target.direction);
    s.elapsed = 0.0f;
  }
  s.target = target;
  s.elapsed += std::max(dt, 0.0f);
  const float x = target.easeSeconds > 0.0f ? std::clamp(s.elapsed / target.easeSeconds, 0.0f, 1.0f) : 1.0f;
  const float w = x * x * (3.0f - 2.0f * x);
  s.direction = arc(s.fromDirection, s.toDirection, w);
  s.speed = s.fromSpeed + (target.speed - s.fromSpeed) * w;
}

SimulationPlane worldWindPlane(const WorldWind& wind, const glm::vec3& direction, const glm::vec3& boundsMin, const glm::vec3& boundsMax) {
  const glm::vec3 Y(0.0f, 1.0f, 0.0f);
  const glm::vec3 right = glm::normalize(direction);
  glm::vec3 up = glm::cross(right, Y);  // horizontal, across the wind
  up = glm::length(up) > 1e-3f ? glm::normalize(up) : glm::vec3(1.0f, 0.0f, 0.0f);  // a vertical wind
  SimulationPlane p;
  // One tile over the whole vegetation seen from above (a field's gusts vary smoothly across the
  // screen, as the view plane's one tile did), at least tileMetres.
  const glm::vec3 extent = glm::max(boundsMax - boundsMin, glm::vec3(0.0f));
  p.tileSize = std::max(std::max(wind.tileMetres * wind.unitsPerMetre, std::max(extent.x, extent.z)), 1e-6f);
  const glm::vec3 centre = 0.5f * (boundsMin + boundsMax);
  p.right = toFloat3(right);
  p.up = toFloat3(up);
  p.origin = toFloat3(centre - 0.5f * p.tileSize * (right + up));
  return p;
}

SimulationParams worldWindSimulation(const SimulationParams& base, const WorldWind& wind, const SimulationPlane& plane, float speed) {
  SimulationParams p = base;
  p.wind.sides = kWindFromLeft;
  p.wind.strength = std::clamp(speed * wind.unitsPerMetre / std::max(plane.tileSize, 1e-12f), 0.0f, 1000.0f);
  p.wind.baseline = 1.0f;
  p.wind.modulation = wind.gustIntensity;
  p.wind.frequency = wind.gustFrequency;
  p.wind.gust = wind.turbulence;
  return p;
}

}  // namespace canopy
