#include "tools/gltf_writer.h"

#include <cerrno>
#include <cstdio>
#include <cstring>

#include <nlohmann/json.hpp>

#include "tools/image_io.h"

namespace canopy {
namespace {

using json = nlohmann::json;

constexpr uint32_t kArrayBuffer = 34962, kElementArrayBuffer = 34963;
constexpr uint32_t kFloat = 5126, kUnsignedInt = 5125;

// One piece of the BIN chunk: either a pointer into the model or owned bytes.
struct Piece {
  const void* data = nullptr;
  uint64_t bytes = 0;
  std::vector<uint8_t> owned;
};

}  // namespace

Status writeGlb(const std::string& path, const VegetationModel& m) {
  const size_t nv = m.positions.size(), nt = m.triangleMaterial.size();
  if (m.normals.size() != nv || m.uvs.size() != nv || m.indices.size() != nt * 3)
    return Status::error("writeGlb '" + path + "': positions, normals, uvs, indices and triangle materials disagree in size");
  if (m.materials.empty()) return Status::error("writeGlb '" + path + "': the model has no materials");
  std::vector<std::vector<uint32_t>> byMaterial(m.materials.size());
  for (size_t t = 0; t < nt; ++t) {
    const uint32_t mat = m.triangleMaterial[t];
    if (mat >= m.materials.size())
      return Status::error("writeGlb '" + path + "': triangle " + std::to_string(t) + " uses material " + std::to_string(mat) +
                           " of " + std::to_string(m.materials.size()));
    for (int k = 0; k < 3; ++k) {
      const uint32_t i = m.indices[t * 3 + k];
      if (i >= nv) return Status::error("writeGlb '" + path + "': index " + std::to_string(i) + " past the vertex count");
      byMaterial[mat].push_back(i);
    }
  }
  size_t materialCount = m.materials.size();
  if (byMaterial.back().empty()) materialCount--;  // the loader's default material

  json doc;
  doc["asset"] = {{"version", "2.0"}, {"generator", "canopy"}};
  std::vector<Piece> pieces;
  uint64_t offset = 0;
  json views = json::array(), accessors = json::array();
  auto addView = [&](Piece piece, int target) {
    const uint64_t padded = (piece.bytes + 3) / 4 * 4;
    json v = {{"buffer", 0}, {"byteOffset", offset}, {"byteLength", piece.bytes}};
    if (target) v["target"] = target;
    views.push_back(v);
    offset += padded;
    pieces.push_back(std::move(piece));
    return int(views.size() - 1);
  };
  auto addAccessor = [&](int view, uint32_t componentType, uint64_t count, const char* type) {
    accessors.push_back({{"bufferView", view}, {"componentType", componentType}, {"count", count}, {"type", type}});
    return int(accessors.size() - 1);
  };
  json attributes;
  if (nv > 0) {
    const int pos = addAccessor(addView({m.positions.data(), nv * sizeof(glm::vec3), {}}, kArrayBuffer), kFloat, nv, "VEC3");
    glm::vec3 lo(1e30f), hi(-1e30f);
    for (const glm::vec3& p : m.positions) {
      lo = glm::min(lo, p);
      hi = glm::max(hi, p);
    }
    accessors[size_t(pos)]["min"] = {lo.x, lo.y, lo.z};  // required for POSITION
    accessors[size_t(pos)]["max"] = {hi.x, hi.y, hi.z};
    attributes["POSITION"] = pos;
    attributes["NORMAL"] = addAccessor(addView({m.normals.data(), nv * sizeof(glm::vec3), {}}, kArrayBuffer), kFloat, nv, "VEC3");
    attributes["TEXCOORD_0"] = addAccessor(addView({m.uvs.data(), nv * sizeof(glm::vec2), {}}, kArrayBuffer), kFloat, nv, "VEC2");
  }
  json primitives = json::array();
  for (size_t mat = 0; mat < materialCount; ++mat) {
    if (byMaterial[mat].empty()) continue;
    const uint64_t count = byMaterial[mat].size();
    Piece piece;
    piece.bytes = count * sizeof(uint32_t);
    piece.owned.resize(piece.bytes);
    std::memcpy(piece.owned.data(), byMaterial[mat].data(), piece.bytes);
    std::vector<uint32_t>().swap(byMaterial[mat]);
    const int idx = addAccessor(addView(std::move(piece), kElementArrayBuffer), kUnsignedInt, count, "SCALAR");
    primitives.push_back({{"attributes", attributes}, {"indices", idx}, {"material", mat}, {"mode", 4}});
  }
  json images = json::array(), textures = json::array(), materials = json::array();
  for (size_t i = 0; i < m.images.size(); ++i) {
    Piece piece;
    CANOPY_TRY(encodePng(m.images[i].width, m.images[i].height, m.images[i].rgba, &piece.owned));
    piece.bytes = piece.owned.size();
    const int view = addView(std::move(piece), 0);
    images.push_back({{"name", m.images[i].name}, {"bufferView", view}, {"mimeType", "image/png"}});
    textures.push_back({{"source", i}, {"sampler", 0}});
  }
  for (size_t i = 0; i < materialCount; ++i) {
    const ModelMaterial& mat = m.materials[i];
    json pbr = {{"baseColorFactor", {mat.baseColorFactor.r, mat.baseColorFactor.g, mat.baseColorFactor.b, mat.baseColorFactor.a}},
                {"metallicFactor", 0.0},
                {"roughnessFactor", 0.9}};
    if (mat.baseColorImage >= 0) {
      if (size_t(mat.baseColorImage) >= m.images.size())
        return Status::error("writeGlb '" + path + "': material '" + mat.name + "' uses image " +
                             std::to_string(mat.baseColorImage) + " of " + std::to_string(m.images.size()));
      pbr["baseColorTexture"] = {{"index", mat.baseColorImage}};
    }
    json jm = {{"name", mat.name}, {"pbrMetallicRoughness", pbr}, {"doubleSided", mat.doubleSided}};
    if (mat.alphaMode == AlphaMode::Mask) {
      jm["alphaMode"] = "MASK";
      jm["alphaCutoff"] = mat.alphaCutoff;
    } else if (mat.alphaMode == AlphaMode::Blend) {
      jm["alphaMode"] = "BLEND";
    }
    materials.push_back(jm);
  }
  doc["buffers"] = json::array({json{{"byteLength", offset}}});
  doc["bufferViews"] = views;
  doc["accessors"] = accessors;
  doc["meshes"] = json::array({json{{"name", "vegetation"}, {"primitives", primitives}}});
  doc["nodes"] = json::array({json{{"name", "vegetation"}, {"mesh", 0}}});
  doc["scenes"] = json::array({json{{"nodes", json::array({0})}}});
  doc["scene"] = 0;
  doc["materials"] = materials;
  if (!images.empty()) {
    doc["images"] = images;
    doc["textures"] = textures;
    doc["samplers"] = json::array({json{{"magFilter", 9729}, {"minFilter", 9987}, {"wrapS", 33071}, {"wrapT", 33071}}});
  }
  std::string text = doc.dump();
  text.append((4 - text.size() % 4) % 4, ' ');
  const uint64_t total = 12 + 8 + text.size() + 8 + offset;
  if (total > 0xffffffffull)
    return Status::error("writeGlb '" + path + "': " + std::to_string(total >> 20) +
                         " MiB is over the .glb format's 4 GiB limit; generate fewer faces");

  FILE* f = std::fopen(path.c_str(), "wb");
  if (!f) return Status::error("writeGlb: cannot create '" + path + "': " + std::strerror(errno));
  auto put32 = [&](uint32_t v) { return std::fwrite(&v, 4, 1, f) == 1; };
  bool ok = put32(0x46546c67u) && put32(2) && put32(uint32_t(total));                       // "glTF", version, length
  ok = ok && put32(uint32_t(text.size())) && put32(0x4e4f534au) && std::fwrite(text.data(), 1, text.size(), f) == text.size();  // JSON
  ok = ok && put32(uint32_t(offset)) && put32(0x004e4942u);                                  // BIN
  const uint8_t zeros[4] = {0, 0, 0, 0};
  for (const Piece& p : pieces) {
    if (!ok) break;
    const void* data = p.owned.empty() ? p.data : p.owned.data();
    ok = std::fwrite(data, 1, p.bytes, f) == p.bytes;
    const uint64_t pad = (4 - p.bytes % 4) % 4;
    if (ok && pad) ok = std::fwrite(zeros, 1, pad, f) == pad;
  }
  ok = (std::fclose(f) == 0) && ok;
  if (!ok) {
    std::remove(path.c_str());
    return Status::error("writeGlb: error writing '" + path + "' (disk full?)");
  }
  return Status();
}

}  // namespace canopy
