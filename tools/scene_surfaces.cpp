#include "tools/scene_surfaces.h"

#include <algorithm>
#include <cmath>

#include "engine/hash.h"

namespace canopy::scenegen {
namespace {

constexpr float kPi = 3.14159265358979f;

// ---------------------------------------------------------------------------------------------
// Materials and their textures.

struct Palette {
  glm::vec3 base, vein, edge;
};


// Alpha-masked foliage texture: `halfWidth(v)` (u across in [0, 1], v along from the attachment
// at 0 to the tip at 1) decides the shape; the edge is antialiased over about one texel so that
// MASK's cutoff 0.5 lands on the true outline.
template <typename HalfWidth, typename Shade>
ModelImage drawFoliageTexture(const char* name, uint32_t size, HalfWidth halfWidth, Shade shade) {
  ModelImage img;
  img.name = name;
  img.width = img.height = size;
  img.rgba.resize(size_t(size) * size * 4);
  for (uint32_t y = 0; y < size; ++y)
    for (uint32_t x = 0; x < size; ++x) {
      const float u = (float(x) + 0.5f) / float(size), v = (float(y) + 0.5f) / float(size);
      const float hw = halfWidth(v), du = std::abs(u - 0.5f);
      const float alpha = std::clamp((hw - du) * float(size) + 0.5f, 0.0f, 1.0f);
      const glm::vec3 c = glm::clamp(shade(u, v, du, hw, x, y), glm::vec3(0.0f), glm::vec3(1.0f));
      uint8_t* p = &img.rgba[(size_t(y) * size + x) * 4];
      p[0] = uint8_t(c.r * 255.0f + 0.5f);
      p[1] = uint8_t(c.g * 255.0f + 0.5f);
      p[2] = uint8_t(c.b * 255.0f + 0.5f);
      p[3] = uint8_t(alpha * 255.0f + 0.5f);
    }
  return img;
}

ModelImage leafTexture(uint32_t size, const Palette& pal, uint64_t seed) {
  auto hw = [](float v) {
    if (v < 0.1f) return 0.03f;  // petiole
    const float t = (v - 0.1f) / 0.9f;
    return std::max(0.03f * (1.0f - t * 8.0f), 0.47f * std::pow(std::sin(kPi * t), 0.7f) * (1.0f - 0.3f * t));
  };
  auto shade = [&](float, float v, float du, float w, uint32_t x, uint32_t y) {
    glm::vec3 c = pal.base * (0.88f + 0.24f * hashNoise(x / 3, y / 3, seed));
    const float vein = std::abs(std::fmod(v * 9.0f - du * 7.0f + 10.0f, 1.0f) - 0.5f);
    if (du < 0.015f || (vein < 0.05f && v > 0.12f)) c = glm::mix(c, pal.vein, 0.55f);
    if (w - du < 0.04f) c = glm::mix(c, pal.edge, 0.5f);
    return c;
  };
  return drawFoliageTexture("leaf", size, hw, shade);
}

ModelImage grassTexture(uint32_t size, const Palette& pal, uint64_t seed) {
  auto hw = [](float v) { return 0.48f * (1.0f - std::pow(v, 1.6f)); };
  auto shade = [&](float, float v, float du, float, uint32_t x, uint32_t y) {
    glm::vec3 c = glm::mix(pal.base, pal.edge, v) * (0.9f + 0.2f * hashNoise(x / 2, y / 6, seed));
    if (du < 0.03f) c = glm::mix(c, pal.vein, 0.4f);
    return c;
  };
  return drawFoliageTexture("grass", size, hw, shade);
}

ModelImage kelpTexture(uint32_t size, const Palette& pal, uint64_t seed) {
  auto hw = [](float v) {
    const float taper = std::min(1.0f, v * 5.0f) * std::min(1.0f, (1.0f - v) * 3.0f);
    return std::max(0.06f, (0.36f + 0.1f * std::sin(v * 46.0f)) * taper);
  };
  auto shade = [&](float, float v, float du, float w, uint32_t x, uint32_t y) {
    glm::vec3 c = pal.base * (0.85f + 0.3f * hashNoise(x / 4, y / 4, seed));
    c = glm::mix(c, pal.vein, std::max(0.0f, 0.5f - du * 3.0f));  // lighter midline
    if (w - du < 0.05f) c = glm::mix(c, pal.edge, 0.6f);             // ruffled darker rim
    return c * (0.8f + 0.2f * v);
  };
  return drawFoliageTexture("kelp blade", size, hw, shade);
}

}  // namespace

float hashNoise(uint32_t x, uint32_t y, uint64_t seed) {
  return float(mix64(seed ^ (uint64_t(x) << 32 | y)) >> 40) * (1.0f / 16777216.0f);
}

// ---------------------------------------------------------------------------------------------
// Rigid geometry (appended directly to the model).

void pushVertex(VegetationModel& m, const glm::vec3& p, const glm::vec3& n, const glm::vec2& uv) {
  m.positions.push_back(p);
  m.normals.push_back(n);
  m.uvs.push_back(uv);
}

void pushQuad(VegetationModel& m, uint32_t material, uint32_t a, uint32_t b, uint32_t c, uint32_t d) {
  for (uint32_t i : {a, b, c, c, d, a}) m.indices.push_back(i);
  m.triangleMaterial.push_back(material);
  m.triangleMaterial.push_back(material);
}

// A truncated cone from a (radius ra) to b (radius rb) around the frame (side0, side1): 2 `sides`
// triangles, no caps (the ends are hidden in the parent branch or under the leaves).
void addCylinder(VegetationModel& m, uint32_t material, const glm::vec3& a, const glm::vec3& b, float ra, float rb,
                 const glm::vec3& side0, const glm::vec3& side1, uint32_t sides) {
  const uint32_t base = uint32_t(m.positions.size());
  for (uint32_t ring = 0; ring < 2; ++ring)
    for (uint32_t i = 0; i <= sides; ++i) {
      const float phi = 2.0f * kPi * float(i) / float(sides);
      const glm::vec3 n = std::cos(phi) * side0 + std::sin(phi) * side1;
      pushVertex(m, (ring ? b : a) + n * (ring ? rb : ra), n, {float(i) / float(sides), float(ring)});
    }
  for (uint32_t i = 0; i < sides; ++i) pushQuad(m, material, base + i, base + i + 1, base + sides + 2 + i, base + sides + 1 + i);
}

// A ground grid of n x n cells over [lo, hi] at height y, facing up.
void addGround(VegetationModel& m, uint32_t material, glm::vec2 lo, glm::vec2 hi, float y, uint32_t n) {
  const uint32_t base = uint32_t(m.positions.size());
  for (uint32_t j = 0; j <= n; ++j)
    for (uint32_t i = 0; i <= n; ++i) {
      const glm::vec2 t(float(i) / float(n), float(j) / float(n));
      const glm::vec2 p = glm::mix(lo, hi, t);
      pushVertex(m, {p.x, y, p.y}, {0, 1, 0}, t);
    }
  for (uint32_t j = 0; j < n; ++j)
    for (uint32_t i = 0; i < n; ++i) {
      const uint32_t a = base + j * (n + 1) + i;
      pushQuad(m, material, a, a + n + 1, a + n + 2, a + 1);
    }
}

// A lumpy dome (the kelp's rock): `rings` x `sides` quads.
void addRock(VegetationModel& m, uint32_t material, const glm::vec3& c, float radius, uint32_t rings, uint32_t sides,
             uint64_t seed) {
  const uint32_t base = uint32_t(m.positions.size());
  for (uint32_t r = 0; r <= rings; ++r)
    for (uint32_t s = 0; s <= sides; ++s) {
      const float theta = 0.5f * kPi * float(r) / float(rings), phi = 2.0f * kPi * float(s % sides) / float(sides);
      const glm::vec3 n(std::cos(theta) * std::cos(phi), std::sin(theta), std::cos(theta) * std::sin(phi));
      const float bump = r == rings ? 1.0f : 0.85f + 0.3f * hashNoise(r, s % sides, seed);
      pushVertex(m, c + n * radius * glm::vec3(1.0f, 0.6f, 1.0f) * bump, n, {float(s) / float(sides), float(r) / float(rings)});
    }
  for (uint32_t r = 0; r < rings; ++r)
    for (uint32_t s = 0; s < sides; ++s) {
      const uint32_t a = base + r * (sides + 1) + s;
      pushQuad(m, material, a, a + sides + 1, a + sides + 2, a + 1);
    }
}

void setMaterials(VegetationModel& m, uint32_t textureSize, uint64_t seed) {
  m.materials.resize(kSlotCount + 1);
  auto opaque = [&](uint32_t slot, const char* name, glm::vec3 c) {
    m.materials[slot].name = name;
    m.materials[slot].baseColorFactor = glm::vec4(c, 1.0f);
  };
  auto foliage = [&](uint32_t slot, const char* name, ModelImage img) {
    m.materials[slot].name = name;
    m.materials[slot].alphaMode = AlphaMode::Mask;
    m.materials[slot].alphaCutoff = 0.5f;
    m.materials[slot].doubleSided = true;
    m.materials[slot].baseColorImage = int32_t(m.images.size());
    m.images.push_back(std::move(img));
  };
  opaque(kBark, "bark", {0.32f, 0.22f, 0.13f});
  foliage(kLeaf, "leaf", leafTexture(textureSize, {{0.22f, 0.48f, 0.13f}, {0.45f, 0.65f, 0.25f}, {0.14f, 0.32f, 0.08f}}, seed));
  foliage(kGrass, "grass", grassTexture(textureSize, {{0.16f, 0.38f, 0.08f}, {0.4f, 0.6f, 0.2f}, {0.55f, 0.62f, 0.25f}}, seed + 1));
  opaque(kGround, "ground", {0.30f, 0.26f, 0.17f});
  opaque(kKelpStem, "kelp stem", {0.30f, 0.26f, 0.08f});
  foliage(kKelpBlade, "kelp blade",
          kelpTexture(textureSize, {{0.42f, 0.36f, 0.1f}, {0.6f, 0.55f, 0.2f}, {0.25f, 0.2f, 0.05f}}, seed + 2));
  opaque(kRock, "rock", {0.42f, 0.42f, 0.45f});
  m.materials[kSlotCount].name = "(default)";  // the loader's convention: one default material last
}

// Drops the materials (and images) no triangle uses, renumbering the rest.
void compactMaterials(VegetationModel& m) {
  const size_t count = m.materials.size();
  if (count == 0) return;
  std::vector<uint8_t> used(count, 0);
  for (uint32_t t : m.triangleMaterial) used[t] = 1;
  used[count - 1] = 1;  // keep the default material
  std::vector<uint32_t> remap(m.materials.size(), 0);
  std::vector<ModelMaterial> mats;
  std::vector<ModelImage> images;
  for (size_t i = 0; i < m.materials.size(); ++i) {
    if (!used[i]) continue;
    remap[i] = uint32_t(mats.size());
    ModelMaterial mat = m.materials[i];
    if (mat.baseColorImage >= 0) {
      images.push_back(std::move(m.images[size_t(mat.baseColorImage)]));
      mat.baseColorImage = int32_t(images.size() - 1);
    }
    mats.push_back(std::move(mat));
  }
  for (uint32_t& t : m.triangleMaterial) t = remap[t];
  m.materials = std::move(mats);
  m.images = std::move(images);
}

}  // namespace canopy::scenegen
