#pragma once
// What every loaded model must satisfy before it reaches the GPU (loader tests).
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "render/gltf_loader.h"

namespace canopy::test {

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
