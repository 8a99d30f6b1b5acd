// The compact chunked mesh (issue 16, render/mesh_chunks.h) on the CPU: positions within one
// quantisation step of the originals, normals and UVs within their encodings' precision, every
// triangle in exactly one chunk with its own vertices, chunk limits honoured, a leaf split by a
// chunk border keeping its root in both chunks, and clear refusals.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <random>
#include <set>

#include "render/mesh_chunks.h"
#include "render/material_split.h"
#include "tools/scene_generator.h"

using namespace canopy;

namespace {

// Leaf fans of `verts` vertices around a root (a leaf with many vertices crosses chunk borders
// when the chunk limit is small), scattered over a box of `extent`; material 0 foliage, plus a
// rigid quad of material 1.
VegetationModel fans(uint32_t leaves, uint32_t verts, float extent, uint32_t seed) {
  VegetationModel m;
  m.materials.resize(2);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  for (uint32_t l = 0; l < leaves; ++l) {
    const glm::vec3 c(u(rng) * extent, u(rng) * extent, u(rng) * extent);
    const uint32_t base = uint32_t(m.positions.size());
    for (uint32_t k = 0; k < verts; ++k) {
      const float a = 6.2831853f * float(k) / float(verts);
      m.positions.push_back(c + glm::vec3(std::cos(a), std::sin(a), 0.3f * u(rng)) * 0.05f * extent);
      m.normals.push_back(glm::normalize(glm::vec3(u(rng), u(rng), u(rng)) + glm::vec3(0, 0, 0.01f)));
      m.uvs.push_back(glm::vec2(u(rng), u(rng)) * 4.0f);
    }
    for (uint32_t k = 1; k + 1 < verts; ++k) {
      for (uint32_t i : {base, base + k, base + k + 1}) m.indices.push_back(i);
      m.triangleMaterial.push_back(0);
    }
  }
  const uint32_t b = uint32_t(m.positions.size());
  for (glm::vec3 p : {glm::vec3(-1, -1, -2), glm::vec3(1, -1, -2), glm::vec3(1, 1, -2), glm::vec3(-1, 1, -2)}) {
    m.positions.push_back(p * extent);
    m.normals.push_back({0, 0, 1});
    m.uvs.push_back({0, 0});
  }
  for (uint32_t i : {0u, 1u, 2u, 2u, 3u, 0u}) m.indices.push_back(b + i);
  m.triangleMaterial.push_back(1);
  m.triangleMaterial.push_back(1);
  return m;
}

struct Built {
  LeafRoots roots;
  std::vector<TriangleRange> ranges;
  CompactMesh mesh;
};

Status build(const VegetationModel& m, CompactMeshOptions o, Built* b) {
  std::vector<uint8_t> foliage(m.triangleCount());
  for (size_t t = 0; t < foliage.size(); ++t) foliage[t] = m.triangleMaterial[t] == 0;
  CANOPY_TRY(computeLeafRoots(m, foliage, LeafRootOptions{}, &b->roots));
  // The model's triangles are already foliage first, then rigid: one range each.
  const uint64_t nf = std::count(foliage.begin(), foliage.end(), uint8_t(1));
  b->ranges = {{0, true, 0, nf}, {1, false, nf, m.triangleCount() - nf}};
  return buildCompactMesh(m, {}, b->ranges, b->roots, o, &b->mesh);
}

}  // namespace

TEST(MeshChunks, DecodesWithinOneQuantisationStepAndKeepsEveryTriangle) {
  for (uint32_t maxV : {65535u, 200u, 7u}) {
    SCOPED_TRACE("maxChunkVertices " + std::to_string(maxV));
    const VegetationModel m = fans(300, 9, 50.0f, 3);
    Built b;
    CompactMeshOptions o;
    o.maxChunkVertices = maxV;
    o.rootAlignment = 4;
    Status s = build(m, o, &b);
    ASSERT_TRUE(s.ok()) << s.message();
    const CompactMesh& c = b.mesh;
    if (maxV < 65535) EXPECT_GT(c.chunks.size(), 4u) << "small chunks must cut the mesh many times";
    uint64_t nextTriangle = 0;
    double worstStep = 0, worstNormal = 0, worstUv = 0;
    for (const MeshChunk& ch : c.chunks) {
      EXPECT_EQ(ch.firstTriangle, nextTriangle) << "chunks cover the GPU order without gap or overlap";
      nextTriangle += ch.triangleCount;
      EXPECT_LE(ch.vertexCount, maxV);
      EXPECT_EQ(ch.firstRoot % 4, 0u) << "root blocks start aligned";
      EXPECT_EQ(ch.foliage, ch.material == 0);
      for (uint64_t t = 0; t < ch.triangleCount; ++t)
        for (int k = 0; k < 3; ++k) {
          const uint16_t local = c.indices[ch.firstIndex + t * 3 + k];
          ASSERT_LT(local, ch.vertexCount) << "an index leaves its chunk";
          const gpu::LayerVertex& v = c.vertices[ch.firstVertex + local];
          const uint32_t model = m.indices[(ch.firstTriangle + t) * 3 + k];
          const glm::vec3 p = decodePosition(ch, v), want = m.positions[model];
          // One step, or two float ulps of the coordinate where a tiny chunk's step is finer than
          // float resolution (origin + q * scale is evaluated in float, as the vertex shader does).
          for (int a = 0; a < 3; ++a) {
            const float ulp = std::nextafter(std::abs(want[a]), INFINITY) - std::abs(want[a]);
            const double tol = std::max<double>(ch.scale[a], 2.0 * ulp);
            worstStep = std::max(worstStep, std::abs(double(p[a]) - double(want[a])) / tol);
          }
          worstNormal = std::max<double>(worstNormal, glm::length(decodeNormal(v) - m.normals[model]));
          worstUv = std::max<double>(worstUv, glm::length(decodeUv(v) - m.uvs[model]));
          // The vertex's leaf: its root in the chunk's table is the model leaf's root, at full precision.
          const uint32_t leaf = b.roots.leafOfVertex[model];
          if (leaf == kNoLeaf) {
            EXPECT_EQ(chunkLeaf(v), LAYER_CHUNK_NO_LEAF);
          } else {
            ASSERT_LT(chunkLeaf(v), ch.rootCount);
            const gpu::LayerLeafRoot& r = c.roots[ch.firstRoot + chunkLeaf(v)];
            EXPECT_EQ(r.leaf, leaf);
            EXPECT_EQ(r.position, m.positions[b.roots.leafRoot[leaf]]);
          }
        }
    }
    EXPECT_EQ(nextTriangle, m.triangleCount());
    EXPECT_LE(worstStep, 1.0) << "positions must decode within one quantisation step";
    EXPECT_LE(worstNormal, 2e-4) << "octahedral snorm16 normals";
    EXPECT_LE(worstUv, 4.0 / 1024.0) << "half-float UVs in [-4, 4]: 11-bit mantissa";
    EXPECT_EQ(c.bytes(), c.vertices.size() * 16 + c.indices.size() * 2 + c.roots.size() * 16);
  }
}

TEST(MeshChunks, ALeafSplitByAChunkBorderKeepsItsRootInBothChunks) {
  // One leaf of 40 vertices with chunks of at most 10: its triangles land in several chunks.
  const VegetationModel m = fans(1, 40, 1.0f, 5);
  Built b;
  CompactMeshOptions o;
  o.maxChunkVertices = 10;
  ASSERT_TRUE(build(m, o, &b).ok());
  std::set<uint32_t> chunksWithLeaf;
  for (size_t i = 0; i < b.mesh.chunks.size(); ++i) {
    const MeshChunk& ch = b.mesh.chunks[i];
    if (!ch.foliage) continue;
    ASSERT_EQ(ch.rootCount, 1u);
    EXPECT_EQ(b.mesh.roots[ch.firstRoot].leaf, 0u);
    EXPECT_EQ(b.mesh.roots[ch.firstRoot].position, m.positions[b.roots.leafRoot[0]]);
    chunksWithLeaf.insert(uint32_t(i));
  }
  EXPECT_GE(chunksWithLeaf.size(), 4u);
}

TEST(MeshChunks, GeneratedSceneBytesPerFace) {
  SceneDesc sd;
  sd.faces = 20000;
  VegetationModel m;
  ASSERT_TRUE(generateScene(sd, &m).ok());
  std::vector<uint8_t> foliage(m.triangleCount());
  Built b;
  MaterialSplit split;
  ASSERT_TRUE(splitMaterials(m, MaterialSplitOptions{}, &split).ok());
  for (size_t t = 0; t < foliage.size(); ++t) foliage[t] = split.role[m.triangleMaterial[t]] == MaterialRole::Foliage;
  ASSERT_TRUE(computeLeafRoots(m, foliage, LeafRootOptions{}, &b.roots).ok());
  // Foliage and rigid triangles interleave in the generated model: one range per triangle run.
  std::vector<TriangleRange> ranges;
  for (uint64_t t = 0; t < m.triangleCount(); ++t) {
    if (ranges.empty() || ranges.back().material != m.triangleMaterial[t])
      ranges.push_back({m.triangleMaterial[t], foliage[t] != 0, t, 0});
    ranges.back().count++;
  }
  ASSERT_TRUE(buildCompactMesh(m, {}, ranges, b.roots, CompactMeshOptions{}, &b.mesh).ok());
  const double perFace = double(b.mesh.bytes()) / double(m.triangleCount());
  const double before = (28.0 * double(m.positions.size()) + 12.0 * double(m.triangleCount()) +
                         16.0 * double(b.roots.leafCount())) / double(m.triangleCount());
  std::printf("[ info ] shrub %zu faces: compact %.1f bytes per face, 28-byte vertices + 32-bit indices %.1f\n",
              m.triangleCount(), perFace, before);
  EXPECT_LT(perFace, 0.7 * before);
}

TEST(MeshChunks, RefusesBadOptionsAndUnrepresentableInput) {
  VegetationModel m = fans(4, 5, 1.0f, 1);
  Built b;
  CompactMeshOptions o;
  o.maxChunkVertices = 2;
  Status s = build(m, o, &b);
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.message().find("3..65535"), std::string::npos) << s.message();
  o.maxChunkVertices = 70000;
  EXPECT_FALSE(build(m, o, &b).ok());
  m.path = "big_uv.gltf";
  m.uvs[3] = glm::vec2(1e6f, 0.0f);
  s = build(m, CompactMeshOptions{}, &b);
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.message().find("big_uv.gltf"), std::string::npos) << s.message();
  EXPECT_NE(s.message().find("vertex 3"), std::string::npos) << s.message();
  EXPECT_NE(s.message().find("65504"), std::string::npos) << s.message();
}
