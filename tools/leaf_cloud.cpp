#include "tools/leaf_cloud.h"

#include <algorithm>
#include <cmath>
#include <random>

namespace canopy {
namespace {

// A square trunk (material 1, "bark") from below the crown up to its centre: the rigid background.
void addTrunk(VegetationModel& m) {
  const glm::vec3 lo(-0.12f, m.boundsMin.y - 1.0f, -0.12f), hi(0.12f, 0.0f, 0.12f);
  const glm::vec3 normals[4] = {{0, 0, 1}, {1, 0, 0}, {0, 0, -1}, {-1, 0, 0}};
  const glm::vec3 corners[4] = {{lo.x, 0, hi.z}, {hi.x, 0, hi.z}, {hi.x, 0, lo.z}, {lo.x, 0, lo.z}};
  for (int side = 0; side < 4; ++side) {
    const glm::vec3 a = corners[side], b = corners[(side + 1) % 4];
    const uint32_t base = uint32_t(m.positions.size());
    const glm::vec3 p[4] = {{a.x, lo.y, a.z}, {b.x, lo.y, b.z}, {b.x, hi.y, b.z}, {a.x, hi.y, a.z}};
    for (int i = 0; i < 4; ++i) {
      m.positions.push_back(p[i]);
      m.normals.push_back(normals[side]);
      m.uvs.push_back({0, 0});
    }
    for (uint32_t i : {0u, 1u, 2u, 2u, 3u, 0u}) m.indices.push_back(base + i);
    m.triangleMaterial.push_back(1);
    m.triangleMaterial.push_back(1);
  }
  m.boundsMin = glm::min(m.boundsMin, lo);
}

}  // namespace

VegetationModel makeLeafCloud(uint64_t faces, uint32_t seed, bool trunk) {
  VegetationModel m;
  const uint64_t leaves = std::max<uint64_t>(1, faces / 2);
  m.path = "";
  m.materials.resize(3);
  m.materials[0].name = "leaf";
  m.materials[0].baseColorFactor = glm::vec4(0.25f, 0.6f, 0.2f, 1.0f);
  m.materials[0].alphaMode = AlphaMode::Mask;
  m.materials[1].name = "bark";
  m.materials[1].baseColorFactor = glm::vec4(0.35f, 0.22f, 0.12f, 1.0f);
  m.materials[2].name = "default";
  m.positions.reserve(leaves * 4);
  m.normals.reserve(leaves * 4);
  m.uvs.reserve(leaves * 4);
  m.indices.reserve(leaves * 6);
  m.triangleMaterial.assign(leaves * 2, 0);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  const float side = std::sqrt(8.0f * 3.14159265f / float(leaves));
  for (uint64_t l = 0; l < leaves; ++l) {
    glm::vec3 c;
    do c = {u(rng), u(rng), u(rng)};
    while (glm::dot(c, c) > 1.0f);
    glm::vec3 a = glm::normalize(glm::vec3(u(rng), u(rng), u(rng)) + glm::vec3(0, 0, 1e-3f));
    glm::vec3 b = glm::normalize(glm::cross(a, glm::vec3(u(rng), u(rng), u(rng) + 2.0f)));
    const glm::vec3 n = glm::normalize(glm::cross(a, b));
    a *= side;
    b *= side;
    const uint32_t base = uint32_t(m.positions.size());
    const glm::vec3 p[4] = {c, c + a, c + a + b, c + b};
    const glm::vec2 t[4] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
    for (int i = 0; i < 4; ++i) {
      m.positions.push_back(p[i]);
      m.normals.push_back(n);
      m.uvs.push_back(t[i]);
    }
    for (uint32_t i : {0u, 1u, 2u, 2u, 3u, 0u}) m.indices.push_back(base + i);
  }
  m.boundsMin = glm::vec3(-1.0f - side * 2);
  m.boundsMax = glm::vec3(1.0f + side * 2);
  if (trunk) addTrunk(m);
  return m;
}

}  // namespace canopy
