// canopy-game-host's world: the plants on their grid, the boxes, the walking camera, the
// character that parts the grass and the sun (demo/game_host.h).
#include "game_host.h"

namespace game {

// The camera's projection: 60 degrees vertical, Vulkan clip (y down).
glm::mat4 walkProjection() {
  return glm::perspectiveRH_ZO(glm::radians(60.0f), float(kW) / float(kH), 0.05f, 200.0f) *
         glm::mat4(1, 0, 0, 0, 0, -1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1);
}

// The walking camera: along the corridor between two rows, at eye height, looking around.
glm::mat4 walkView(const Scene& s, uint32_t frame, uint32_t frames) {
  const float t = frames > 1 ? float(frame) / float(frames - 1) : 0.0f;
  const float height = s.plantMax.y - s.plantMin.y;
  const glm::vec3 eye(s.corridor.x, 0.45f * height, s.half + 0.5f * s.spacing - t * 1.6f * s.half);
  const float yaw = glm::radians(25.0f * std::sin(t * 6.2831853f));
  const glm::vec3 dir(std::sin(yaw), -0.08f, -std::cos(yaw));
  return glm::lookAt(eye, eye + dir, glm::vec3(0, 1, 0));
}

// The character walking ahead of the camera, weaving into the plants either side of its corridor:
// a capsule (a pusher, setCanopyPushers) whose path parts the vegetation it walks through.
canopy::CanopyPusher character(const Scene& s, uint32_t frame, uint32_t frames) {
  const float R = 0.12f * s.spacing;
  auto at = [&](float f) {
    const float t = frames > 1 ? f / float(frames - 1) : 0.0f;
    return glm::vec3(s.corridor.x + 0.9f * s.spacing * std::sin(t * 9.42f), R,
                     s.half + 0.5f * s.spacing - t * 1.6f * s.half - 2.5f * s.spacing);
  };
  const glm::vec3 p = at(float(frame)), ahead = at(float(frame) + 1.0f);
  canopy::CanopyPusher c;
  c.a = {p.x, p.y, p.z};
  c.b = {p.x, p.y + 2.5f * R, p.z};
  c.radius = R;
  const glm::vec3 v = (ahead - p) * 30.0f;  // the frames are 1/30 s apart
  c.velocity = {v.x, v.y, v.z};
  c.bend = 2.0f;
  return c;
}

// The sun: an orthographic view around the ground and everything standing on it (Vulkan clip, depth
// 0 near the sun).
glm::mat4 sunViewProj(const Scene& s) {
  const float w = s.half + 0.5f * s.spacing, height = s.plantMax.y - s.plantMin.y;
  const glm::vec3 l = glm::normalize(glm::vec3(0.5f, 1.0f, 0.35f)), centre(0.0f, 0.5f * height, 0.0f);
  const float reach = glm::length(glm::vec3(w, height, w));
  const glm::mat4 view = glm::lookAt(centre + l * (2.0f * reach), centre, glm::vec3(0, 1, 0));
  glm::vec3 lo(INFINITY), hi(-INFINITY);
  for (int k = 0; k < 8; ++k) {
    const glm::vec3 q(view * glm::vec4(k & 1 ? w : -w, k & 2 ? height : 0.0f, k & 4 ? w : -w, 1.0f));
    lo = glm::min(lo, q);
    hi = glm::max(hi, q);
  }
  return glm::orthoRH_ZO(lo.x, hi.x, lo.y, hi.y, -hi.z - 0.01f * reach, -lo.z + 0.01f * reach) * view;
}

// N copies of the plant on a square grid, each turned and scaled its own way, standing on the
// ground (y = 0); a few boxes among them.
bool makeScene(const canopy::Model* model, uint32_t plants, canopy::CanopyDesc* desc, Scene* s) {
  canopy::Float3 lo, hi;
  canopy::modelBounds(model, &lo, &hi);
  s->plantMin = glm::vec3(lo.x, lo.y, lo.z);
  s->plantMax = glm::vec3(hi.x, hi.y, hi.z);
  const glm::vec3 size = s->plantMax - s->plantMin;
  const uint32_t side = uint32_t(std::ceil(std::sqrt(double(plants))));
  s->spacing = 1.3f * std::max(size.x, size.z);
  s->half = 0.5f * float(side - 1) * s->spacing;
  s->corridor = glm::vec2(-s->half + (float(side / 2) - 0.5f) * s->spacing);
  uint32_t seed = 7;
  auto rnd = [&] {
    seed = seed * 1664525u + 1013904223u;
    return float(seed >> 8) / float(1u << 24);
  };
  const glm::vec3 foot(0.5f * (s->plantMin.x + s->plantMax.x), s->plantMin.y, 0.5f * (s->plantMin.z + s->plantMax.z));
  for (uint32_t i = 0; i < plants; ++i) {
    const glm::vec3 at(float(i % side) * s->spacing - s->half, 0.0f, float(i / side) * s->spacing - s->half);
    const glm::mat4 t = glm::translate(glm::mat4(1.0f), at) * glm::rotate(glm::mat4(1.0f), rnd() * 6.2831853f, glm::vec3(0, 1, 0)) *
                        glm::scale(glm::mat4(1.0f), glm::vec3(0.8f + 0.4f * rnd())) * glm::translate(glm::mat4(1.0f), -foot);
    canopy::CanopyInstance inst;
    inst.transform = toCanopy(t);
    inst.tint = {0.85f + 0.3f * rnd(), 0.85f + 0.3f * rnd(), 0.85f + 0.2f * rnd()};
    desc->instances.push_back(inst);
  }
  // Boxes where the lanes cross, off the walk (the first outlined through the stencil).
  const float b = 0.3f * size.y;
  const int dx[6] = {1, -1, 2, 1, -1, 2}, dz[6] = {-1, -1, -1, 1, 1, 1};
  for (int k = 0; k < 6; ++k) {
    const glm::vec3 at(s->corridor.x + float(dx[k]) * s->spacing, 0.5f * b, s->corridor.y + float(dz[k]) * s->spacing);
    s->boxes.push_back(glm::scale(glm::translate(glm::mat4(1.0f), at), glm::vec3(b)));
  }
  return true;
}

}  // namespace game
