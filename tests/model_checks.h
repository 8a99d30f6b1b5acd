#pragma once
// What every loaded model must satisfy before it reaches the GPU (loader tests), and the GLB
// container the loader tests write their files in.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <vector>
#include <string>

#include "render/gltf_loader.h"

namespace canopy::test {

// A GLB of `text` (the JSON chunk) and `bin` (the BIN chunk), each padded to 4 bytes.
inline std::vector<unsigned char> toGlb(const std::string& text, const std::vector<unsigned char>& bin) {
  std::string j = text;
  while (j.size() % 4) j += ' ';
  std::vector<unsigned char> b = bin;
  while (b.size() % 4) b.push_back(0);
  std::vector<unsigned char> out = {'g', 'l', 'T', 'F'};
  auto u32 = [&](uint32_t v) {
    unsigned char x[4];
    std::memcpy(x, &v, 4);
    out.insert(out.end(), x, x + 4);
  };
  u32(2);
  u32(uint32_t(12 + 8 + j.size() + 8 + b.size()));
  u32(uint32_t(j.size()));
  u32(0x4E4F534Au);
  out.insert(out.end(), j.begin(), j.end());
  u32(uint32_t(b.size()));
  u32(0x004E4942u);
  out.insert(out.end(), b.begin(), b.end());
  return out;
}

inline void expectConsistent(const VegetationModel& m, const std::string& name) {
  ASSERT_EQ(m.indices.size() % 3, 0u) << name;
  ASSERT_EQ(m.triangleMaterial.size(), m.indices.size() / 3) << name;
  ASSERT_EQ(m.normals.size(), m.positions.size()) << name;
  ASSERT_EQ(m.uvs.size(), m.positions.size()) << name;
  for (uint32_t i : m.indices) ASSERT_LT(i, m.positions.size()) << name;
  for (uint32_t t : m.triangleMaterial) ASSERT_LT(t, m.materials.size()) << name;
  for (const glm::vec3& p : m.positions) ASSERT_TRUE(std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z)) << name;
  for (const ModelMaterial& mat : m.materials)
    if (mat.baseColorImage >= 0) {
      ASSERT_LT(size_t(mat.baseColorImage), m.images.size()) << name;
      const ModelImage& im = m.images[size_t(mat.baseColorImage)];
      ASSERT_EQ(im.rgba.size(), size_t(im.width) * im.height * 4) << name;
    }
}

}  // namespace canopy::test
