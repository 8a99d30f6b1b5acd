#include "tests/fuzz/gltf_fuzz.h"

#include <cmath>
#include <cstring>
#include <map>
#include <string>
#include <vector>

#include "render/gltf_loader.h"
#include "render/leaf_roots.h"
#include "render/material_split.h"

namespace canopy::fuzz {
namespace {

constexpr char kMarker[] = "\n#file:";

// A loaded model that breaks one of these would reach the GPU as garbage.
void check(bool ok) {
  if (!ok) __builtin_trap();
}

void checkModel(const VegetationModel& m) {
  check(m.indices.size() % 3 == 0);
  check(m.triangleMaterial.size() == m.indices.size() / 3);
  check(m.normals.size() == m.positions.size() && m.uvs.size() == m.positions.size());
  for (uint32_t i : m.indices) check(i < m.positions.size());
  for (uint32_t t : m.triangleMaterial) check(t < m.materials.size());
  for (const glm::vec3& p : m.positions) check(std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z));
  for (const ModelMaterial& mat : m.materials)
    if (mat.baseColorImage >= 0) {
      check(size_t(mat.baseColorImage) < m.images.size());
      const ModelImage& im = m.images[size_t(mat.baseColorImage)];
      check(im.rgba.size() == size_t(im.width) * im.height * 4);
    }
}

}  // namespace

int runGltfInput(const uint8_t* data, size_t size) {
  const std::string all(reinterpret_cast<const char*>(data), size);
  const size_t marker = std::strlen(kMarker);
  size_t cut = all.find(kMarker);
  const std::string modelBytes = all.substr(0, cut);
  std::map<std::string, std::vector<unsigned char>> files;
  while (cut != std::string::npos) {
    const size_t nameStart = cut + marker;
    const size_t nameEnd = all.find('\n', nameStart);
    if (nameEnd == std::string::npos) break;
    const size_t next = all.find(kMarker, nameEnd + 1);
    const std::string body = all.substr(nameEnd + 1, next == std::string::npos ? std::string::npos : next - nameEnd - 1);
    files[all.substr(nameStart, nameEnd - nameStart)] = std::vector<unsigned char>(body.begin(), body.end());
    cut = next;
  }
  const bool glb = modelBytes.size() >= 4 && std::memcmp(modelBytes.data(), "glTF", 4) == 0;
  // Limits sized for the fuzzer's memory (2 GiB RSS): a run must never be killed for memory.
  GltfLoadOptions opt;
  opt.maxFileBytes = 8u << 20;
  opt.maxVertices = 2'000'000;
  opt.maxTriangles = 2'000'000;
  opt.maxImageDimension = 4096;
  opt.maxImagePixels = 8u << 20;
  VegetationModel model;
  Status s = loadGltfFromMemory(glb ? "fuzz.glb" : "fuzz.gltf", std::vector<unsigned char>(modelBytes.begin(), modelBytes.end()),
                                files, opt, &model);
  if (!s.ok()) {
    check(!s.message().empty() && model.positions.empty());
    return 0;
  }
  checkModel(model);
  MaterialSplit split;
  if (!splitMaterials(model, {}, &split).ok()) return 0;
  check(split.role.size() == model.materials.size());
  std::vector<uint8_t> foliage(model.triangleCount());
  for (size_t t = 0; t < foliage.size(); ++t) foliage[t] = split.role[model.triangleMaterial[t]] == MaterialRole::Foliage;
  LeafRoots roots;
  if (!computeLeafRoots(model, foliage, {}, &roots).ok()) return 0;
  check(roots.rootOfVertex.size() == model.positions.size());
  for (uint32_t r : roots.rootOfVertex) check(r == kNoLeaf || r < model.positions.size());
  for (uint32_t r : roots.leafRoot) check(r < model.positions.size());
  return 0;
}

}  // namespace canopy::fuzz
