#include "render/gltf_loader.h"

#include <limits.h>
#include <sys/stat.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <limits>
#include <map>
#include <memory>

#include <glm/gtc/matrix_inverse.hpp>
#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/quaternion.hpp>
#include <glm/gtc/type_ptr.hpp>
#include <nlohmann/json.hpp>
#include <tiny_gltf.h>

#include "engine/files.h"
#include "render/gltf_json_checks.h"
#include "render/gltf_accessors.h"
#include "render/gltf_compressed.h"
#include "render/gltf_files.h"
#include "render/gltf_prune.h"

// Our own decoder, private to this file (the tinygltf library carries its own copy).
#define STB_IMAGE_STATIC
#define STB_IMAGE_IMPLEMENTATION
#define STBI_NO_STDIO
#include <stb/stb_image.h>

namespace canopy {
namespace {

// Image bytes are kept encoded and decoded after validation: for bufferView images tinygltf
// passes a pointer into the buffer without checking the range, so the callback never touches it.
struct ImageContext {
  std::vector<std::vector<unsigned char>> encoded;  // by image index; empty for bufferView images
  std::vector<bool> fromBufferView;
};
bool imageCallback(tinygltf::Image* image, const int index, std::string*, std::string*, int, int,
                   const unsigned char* bytes, int size, void* user) {
  ImageContext& c = *static_cast<ImageContext*>(user);
  if (index < 0) return false;
  if (size_t(index) >= c.encoded.size()) {
    c.encoded.resize(size_t(index) + 1);
    c.fromBufferView.resize(size_t(index) + 1, false);
  }
  if (image->bufferView >= 0) {
    c.fromBufferView[size_t(index)] = true;
  } else if (bytes && size > 0) {
    c.encoded[size_t(index)].assign(bytes, bytes + size);
  }
  return true;
}


glm::mat4 nodeMatrix(const tinygltf::Node& n) {
  if (n.matrix.size() == 16) {
    glm::mat4 m;
    for (int i = 0; i < 16; ++i) glm::value_ptr(m)[i] = float(n.matrix[size_t(i)]);
    return m;
  }
  glm::mat4 t(1.0f), r(1.0f), s(1.0f);
  if (n.translation.size() == 3) t = glm::translate(glm::mat4(1.0f), glm::vec3(n.translation[0], n.translation[1], n.translation[2]));
  if (n.rotation.size() == 4)
    r = glm::mat4_cast(glm::normalize(glm::quat(float(n.rotation[3]), float(n.rotation[0]), float(n.rotation[1]), float(n.rotation[2]))));
  if (n.scale.size() == 3) s = glm::scale(glm::mat4(1.0f), glm::vec3(n.scale[0], n.scale[1], n.scale[2]));
  return t * r * s;
}

// What the steps of loadBytes share: the parsed document, the options, the model being filled.
struct Load {
  const tinygltf::Model& m;
  const GltfLoadOptions& opt;
  const FsContext& fs;
  const ImageContext& images;
  VegetationModel* out;
  GltfReader reader;
  const GltfReadParts& parts;
  uint32_t nextPlant = 0;  // the next plant ordinal past the scene roots' (each instance of EXT_mesh_gpu_instancing)
};

// The file through Canopy's checks of its framing and JSON, the parts the vegetation does not read
// replaced (render/gltf_prune.h), then tinygltf (external files through `fs`, images kept encoded
// in `images`). A parse warning goes to `warnings`.
Status parseFile(const std::vector<unsigned char>& bytes, FsContext& fs, const GltfLoadOptions& opt,
                 tinygltf::Model* m, ImageContext* images, GltfReadParts* parts, std::vector<MeshoptView>* meshopt,
                 std::vector<std::string>* warnings) {
  Status s;
  if (bytes.size() > std::numeric_limits<uint32_t>::max())
    return Status::error(std::to_string(bytes.size()) + " bytes: glTF files are limited to 4 GiB");
  if (bytes.empty()) return Status::error("the file is empty");
  const bool glb = bytes.size() >= 4 && std::memcmp(bytes.data(), "glTF", 4) == 0;
  const size_t json = glb ? 20 : 0;
  // glTF JSON is UTF-8 without a byte-order mark (tinygltf would accept one).
  if (bytes.size() >= json + 3 && bytes[json] == 0xEF && bytes[json + 1] == 0xBB && bytes[json + 2] == 0xBF)
    return Status::error("the JSON starts with a byte-order mark (glTF requires UTF-8 without one)");
  if (!glb) {
    // A .gltf is a JSON object; anything else is not glTF (a .glb starts with the magic "glTF").
    size_t first = 0;
    while (first < bytes.size() && (bytes[first] == ' ' || bytes[first] == '\t' || bytes[first] == '\r' || bytes[first] == '\n')) ++first;
    if (first < bytes.size() && std::strchr("[\"-0123456789tfn", bytes[first]) && bytes[first] != 0)
      if (bytes[first] != '{') return Status::error("the JSON document is not an object (a glTF file is one JSON object)");
    if (first == bytes.size() || bytes[first] != '{') {
      char head[64];
      std::snprintf(head, sizeof head, "%02x %02x %02x %02x", bytes[0], bytes.size() > 1 ? bytes[1] : 0,
                    bytes.size() > 2 ? bytes[2] : 0, bytes.size() > 3 ? bytes[3] : 0);
      return Status::error(std::string("not a glTF file: a .glb starts with the magic 'glTF' and a .gltf with a JSON object "
                                       "('{'); this file starts with the bytes ") + head);
    }
  }
  if (glb && !(s = checkGlb(bytes)).ok()) return s;
  uint32_t jsonLength = uint32_t(bytes.size());
  if (glb) std::memcpy(&jsonLength, bytes.data() + 12, 4);  // checkGlb: inside the file
  if (!(s = checkJsonDepth(bytes.data() + json, jsonLength, opt.maxJsonDepth)).ok()) return s;
  nlohmann::json doc;
  try {
    doc = nlohmann::json::parse(bytes.data() + json, bytes.data() + json + jsonLength);
  } catch (const nlohmann::json::exception& e) {
    // The parser's own words, without its "[json.exception.parse_error.101]" tag.
    std::string why = e.what();
    if (why.size() > 0 && why[0] == '[' && why.find("] ") != std::string::npos) why = why.substr(why.find("] ") + 2);
    return Status::error("the JSON is not well-formed: " + why);
  }
  if (!(s = checkGltfJsonFields(doc)).ok()) return s;
  uint64_t binBytes = 0;
  size_t binAt = json + jsonLength;  // the chunk after the JSON's (checkGlb: its header inside the file)
  if (glb && bytes.size() >= binAt + 8 && std::memcmp(bytes.data() + binAt + 4, "BIN\0", 4) == 0) {
    uint32_t n;
    std::memcpy(&n, bytes.data() + binAt, 4);
    binBytes = n;
  }
  if (!(s = prepareMeshopt(doc, opt, meshopt)).ok()) return s;
  if (!(s = keepReadParts(doc, glb, binBytes, parts)).ok()) return s;
  // The document tinygltf parses: the rewritten JSON (in a .glb, its JSON chunk, the rest as it was).
  std::vector<unsigned char> file;
  {
    std::string text = doc.dump();
    if (glb) {
      while (text.size() % 4) text += ' ';
      // The chunks after the JSON's, up to the header's length (bytes past it are not the file's).
      uint32_t declared;
      std::memcpy(&declared, bytes.data() + 8, 4);  // checkGlb: within the file, past the JSON chunk
      const size_t rest = declared > binAt ? declared - binAt : 0;
      const uint64_t total = 20 + uint64_t(text.size()) + rest;
      if (total > std::numeric_limits<uint32_t>::max()) return Status::error("glTF files are limited to 4 GiB");
      file.resize(size_t(total));
      std::memcpy(file.data(), bytes.data(), 8);  // magic and version
      const uint32_t len32 = uint32_t(total), jsonLen = uint32_t(text.size());
      std::memcpy(file.data() + 8, &len32, 4);
      std::memcpy(file.data() + 12, &jsonLen, 4);
      std::memcpy(file.data() + 16, "JSON", 4);
      std::memcpy(file.data() + 20, text.data(), text.size());
      if (rest) std::memcpy(file.data() + 20 + text.size(), bytes.data() + binAt, rest);
    } else {
      file.assign(text.begin(), text.end());
    }
  }

  tinygltf::TinyGLTF loader;
  loader.SetFsCallbacks({&fsFileExists, &fsExpand, &fsRead, &fsWrite, &fs});
  loader.SetImageLoader(&imageCallback, images);
  std::string err, warn;
  bool parsed = false;
  try {
    parsed = glb ? loader.LoadBinaryFromMemory(m, &err, &warn, file.data(), unsigned(file.size()), fs.baseDir)
                 : loader.LoadASCIIFromString(m, &err, &warn, reinterpret_cast<const char*>(file.data()),
                                              unsigned(file.size()), fs.baseDir);
  } catch (const std::bad_alloc&) {
    return Status::error(Result::OutOfHostMemory, "out of host memory while parsing the JSON");
  } catch (const std::exception& e) {
    return Status::error(std::string("the glTF parser failed: ") + e.what());
  }
  auto trim = [](std::string t) {
    while (!t.empty() && (t.back() == '\n' || t.back() == ' ')) t.pop_back();
    for (char& c : t) if (c == '\n') c = ';';
    return t;
  };
  if (!parsed)
    return Status::error(trim(err.empty() ? "not valid glTF" : err) + (fs.lastError.empty() ? "" : " (" + fs.lastError + ")"));
  if (!warn.empty()) warnings->push_back(trim(warn));

  return Status();
}

// The extensions the loader reads (a file may require these and no others).
constexpr const char* kImplementedExtensions[] = {"EXT_mesh_gpu_instancing", "EXT_meshopt_compression", "EXT_texture_webp",
                                                  "KHR_draco_mesh_compression", "KHR_materials_diffuse_transmission",
                                                  "KHR_materials_specular", "KHR_materials_transmission", "KHR_materials_volume",
                                                  "KHR_mesh_quantization", "KHR_texture_transform"};

// The document as a whole: glTF 2.x, a node forest, the default scene, buffers that loaded, no
// required extension the loader lacks.
Status checkDocument(const tinygltf::Model& m, const FsContext& fs) {
  // asset.version (and minVersion) must be 2.x.
  {
    auto major = [](const std::string& v, int* mj, int* mn) {
      return std::sscanf(v.c_str(), "%d.%d", mj, mn) == 2 && v.find_first_not_of("0123456789.") == std::string::npos &&
             std::count(v.begin(), v.end(), '.') == 1;
    };
    int mj = 0, mn = 0, mmj = 0, mmn = 0;
    if (!major(m.asset.version, &mj, &mn)) return Status::error("asset.version '" + m.asset.version + "' is not MAJOR.MINOR");
    if (mj != 2) return Status::error("asset.version " + m.asset.version + ": only glTF 2.x is supported");
    if (!m.asset.minVersion.empty()) {
      if (!major(m.asset.minVersion, &mmj, &mmn)) return Status::error("asset.minVersion '" + m.asset.minVersion + "' is not MAJOR.MINOR");
      if (mmj != 2 || mmn > mn) return Status::error("asset.minVersion " + m.asset.minVersion + " is not satisfiable by version " + m.asset.version);
    }
  }
  // The node graph must be a forest (no loops, no node with two parents), scene or not.
  {
    std::vector<int> parent(m.nodes.size(), -1);
    for (size_t i = 0; i < m.nodes.size(); ++i)
      for (int c : m.nodes[i].children) {
        if (c < 0 || size_t(c) >= m.nodes.size())
          return Status::error("nodes[" + std::to_string(i) + "]: child " + std::to_string(c) + " does not exist");
        if (parent[size_t(c)] >= 0 || size_t(c) == i)
          return Status::error("nodes[" + std::to_string(c) + "] has two parents or is its own child (node hierarchy is not a tree)");
        parent[size_t(c)] = int(i);
      }
    // Every node has at most one parent, so a loop is a parent chain that comes back to itself:
    // walk each chain once (state 1 = on the current walk, 2 = known to reach a root), O(nodes).
    std::vector<uint8_t> state(m.nodes.size(), 0);
    std::vector<size_t> walk;
    for (size_t i = 0; i < m.nodes.size(); ++i) {
      walk.clear();
      int p = int(i);
      while (p >= 0 && state[size_t(p)] == 0) {
        state[size_t(p)] = 1;
        walk.push_back(size_t(p));
        p = parent[size_t(p)];
      }
      if (p >= 0 && state[size_t(p)] == 1) return Status::error("nodes[" + std::to_string(p) + "] is part of a loop in the node hierarchy");
      for (size_t w : walk) state[w] = 2;
    }
  }
  if (m.defaultScene >= 0 && size_t(m.defaultScene) >= m.scenes.size())
    return Status::error("scene " + std::to_string(m.defaultScene) + " (the default scene) does not exist");
  // glTF 2.0 (3.12): a loader must refuse a file that requires an extension it does not implement.
  for (const std::string& e : m.extensionsRequired)
    if (e == "KHR_texture_basisu")
      return Status::error("extensionsRequired names 'KHR_texture_basisu' (KTX2 / Basis Universal textures), which Canopy does not "
                           "read: export the textures as PNG, JPEG or WebP (EXT_texture_webp)");
  for (const std::string& e : m.extensionsRequired)
    if (std::find(std::begin(kImplementedExtensions), std::end(kImplementedExtensions), e) == std::end(kImplementedExtensions)) {
      std::string known;
      for (const char* k : kImplementedExtensions) known += std::string(known.empty() ? "" : ", ") + k;
      return Status::error("extensionsRequired names '" + e + "', which Canopy does not implement (it implements " + known + ")");
    }

  // Buffers must hold what they declare (external files may be short).
  for (size_t i = 0; i < m.buffers.size(); ++i)
    if (m.buffers[i].data.empty() && !m.buffers[i].uri.empty())
      return Status::error("buffers[" + std::to_string(i) + "] ('" + m.buffers[i].uri + "') could not be loaded" +
                  (fs.lastError.empty() ? "" : ": " + fs.lastError));

  return Status();
}

// The nodes the scene traversal starts from: the default scene (or scene 0, or every root node
// when there is none). Meshes no node instantiates are not displayed (glTF), so they are not loaded
// and not checked.
Status sceneRoots(const tinygltf::Model& m, VegetationModel* out, std::vector<int>* roots) {
  if (m.nodes.empty() && !m.meshes.empty())
    out->warnings.push_back("no nodes: the file's " + std::to_string(m.meshes.size()) + " mesh(es) are not part of any scene");
  if (!m.scenes.empty()) {
    const int sc = m.defaultScene >= 0 ? m.defaultScene : 0;
    if (size_t(sc) >= m.scenes.size()) return Status::error("scene " + std::to_string(sc) + " does not exist");
    *roots = m.scenes[size_t(sc)].nodes;
  } else {
    std::vector<bool> isChild(m.nodes.size(), false);
    for (const auto& n : m.nodes)
      for (int c : n.children)
        if (c >= 0 && size_t(c) < m.nodes.size()) isChild[size_t(c)] = true;
    for (size_t i = 0; i < m.nodes.size(); ++i)
      if (!isChild[i]) roots->push_back(int(i));
  }

  return Status();
}

// One primitive of mesh `meshIndex` under the node transform `world`: its attributes and indices
// read within the budgets left, strips and fans as lists, appended to the model in world space.
Status appendPrimitive(Load& L, int meshIndex, size_t pi, const glm::mat4& world, const glm::mat3& normalMatrix) {
  const tinygltf::Model& m = L.m;
  const GltfLoadOptions& opt = L.opt;
  VegetationModel* out = L.out;
  GltfReader& reader = L.reader;
  const uint32_t defaultMaterial = uint32_t(m.materials.size());
  const tinygltf::Mesh& mesh = m.meshes[size_t(meshIndex)];
  const tinygltf::Primitive& pr = mesh.primitives[pi];
  const std::string pw = "meshes[" + std::to_string(meshIndex) + "].primitives[" + std::to_string(pi) + "]";
  // Points and lines are not vegetation's faces: left out (keepReadParts warned).
  if (pr.mode != TINYGLTF_MODE_TRIANGLES && pr.mode != TINYGLTF_MODE_TRIANGLE_STRIP && pr.mode != TINYGLTF_MODE_TRIANGLE_FAN && pr.mode != -1)
    return Status();
  auto pos = pr.attributes.find("POSITION");
  if (pos == pr.attributes.end()) {
    out->warnings.push_back(pw + ": no POSITION attribute, nothing to draw (skipped)");
    return Status();
  }
  std::vector<double> P, N, T, I;
  uint32_t nc;
  uint64_t vcount, count;
  // Budgets left for this primitive (instancing a mesh by many nodes counts every instance).
  const uint64_t vertexBudget = opt.maxVertices > out->positions.size() ? opt.maxVertices - out->positions.size() : 0;
  const uint64_t triangleBudget = opt.maxTriangles > out->triangleCount() ? opt.maxTriangles - out->triangleCount() : 0;
  const uint64_t indexBudget = triangleBudget > (UINT64_MAX - 2) / 3 ? UINT64_MAX : triangleBudget * 3 + 2;
  // KHR_mesh_quantization's types beside glTF's float: positions in (normalized) integers,
  // normals in normalized bytes or shorts, texture coordinates in any of them (GltfReader::read
  // converts each by its normalized flag; the node transform carries the dequantization).
  constexpr uint32_t kByte = TINYGLTF_COMPONENT_TYPE_BYTE, kUByte = TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE,
                     kShort = TINYGLTF_COMPONENT_TYPE_SHORT, kUShort = TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT,
                     kFloat = TINYGLTF_COMPONENT_TYPE_FLOAT;
  CANOPY_TRY(reader.read(pos->second, {TINYGLTF_TYPE_VEC3}, {kFloat, kByte, kUByte, kShort, kUShort}, vertexBudget, &P, &nc, &vcount)
                 .context(pw + ".POSITION"));
  if (auto it = pr.attributes.find("NORMAL"); it != pr.attributes.end()) {
    CANOPY_TRY(reader.read(it->second, {TINYGLTF_TYPE_VEC3}, {kFloat, kByte, kShort}, vertexBudget, &N, &nc, &count).context(pw + ".NORMAL"));
    if (count != vcount) return Status::error(pw + ".NORMAL: " + std::to_string(count) + " values for " + std::to_string(vcount) + " positions");
  }
  if (auto it = pr.attributes.find("TEXCOORD_0"); it != pr.attributes.end()) {
    CANOPY_TRY(reader.read(it->second, {TINYGLTF_TYPE_VEC2}, {kFloat, kByte, kUByte, kShort, kUShort}, vertexBudget, &T, &nc, &count)
                   .context(pw + ".TEXCOORD_0"));
    if (count != vcount) return Status::error(pw + ".TEXCOORD_0: " + std::to_string(count) + " values for " + std::to_string(vcount) + " positions");
    // KHR_texture_transform of the base colour texture (quantized coordinates from gltfpack, atlases):
    // applied here, so every texture of the material reads through it (Canopy keeps one UV set).
    if (pr.material >= 0 && size_t(pr.material) < m.materials.size()) {
      const tinygltf::TextureInfo& base = m.materials[size_t(pr.material)].pbrMetallicRoughness.baseColorTexture;
      TextureTransform t;
      CANOPY_TRY(textureTransform(base.extensions, "materials[" + std::to_string(pr.material) + "].pbrMetallicRoughness.baseColorTexture", &t));
      if (t.texCoord > 0)
        out->warnings.push_back("materials[" + std::to_string(pr.material) + "]: KHR_texture_transform.texCoord = " +
                                std::to_string(t.texCoord) + "; TEXCOORD_0 is used");
      if (!t.identity)
        for (uint64_t v = 0; v < vcount; ++v) {
          const double u = T[v * 2], w = T[v * 2 + 1];
          T[v * 2] = t.m[0] * u + t.m[1] * w + t.m[2];
          T[v * 2 + 1] = t.m[3] * u + t.m[4] * w + t.m[5];
        }
    }
  }
  std::vector<uint32_t> idx;
  int indices = pr.indices;
  if (auto z = L.parts.indicesWithoutView.find({meshIndex, int(pi)}); z != L.parts.indicesWithoutView.end()) indices = z->second;
  if (indices >= 0) {
    CANOPY_TRY(reader.read(indices, {TINYGLTF_TYPE_SCALAR},
                           {TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE, TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT, TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT},
                           indexBudget, &I, &nc, &count).context(pw + ".indices"));
    idx.resize(I.size());
    for (size_t k = 0; k < I.size(); ++k) {
      if (I[k] >= double(vcount))
        return Status::error(pw + ".indices[" + std::to_string(k) + "] = " + std::to_string(uint64_t(I[k])) +
                             " is past the vertex count " + std::to_string(vcount));
      idx[k] = uint32_t(I[k]);
    }
  } else {
    idx.resize(size_t(vcount));
    for (uint32_t k = 0; k < vcount; ++k) idx[k] = k;
  }
  // Strips and fans become lists; a trailing partial triangle is dropped.
  std::vector<uint32_t> tri;
  if (pr.mode == TINYGLTF_MODE_TRIANGLE_STRIP) {
    for (size_t k = 2; k < idx.size(); ++k)
      if (k % 2 == 0) tri.insert(tri.end(), {idx[k - 2], idx[k - 1], idx[k]});
      else tri.insert(tri.end(), {idx[k - 1], idx[k - 2], idx[k]});
  } else if (pr.mode == TINYGLTF_MODE_TRIANGLE_FAN) {
    for (size_t k = 2; k < idx.size(); ++k) tri.insert(tri.end(), {idx[0], idx[k - 1], idx[k]});
  } else {
    if (idx.size() % 3 != 0) out->warnings.push_back(pw + ": " + std::to_string(idx.size() % 3) + " trailing indices ignored");
    tri.assign(idx.begin(), idx.end() - long(idx.size() % 3));
  }
  uint32_t mat = defaultMaterial;
  if (pr.material >= 0) {
    if (size_t(pr.material) >= m.materials.size()) return Status::error(pw + ": material " + std::to_string(pr.material) + " does not exist");
    mat = uint32_t(pr.material);
  }
  if (vcount > vertexBudget)
    return Status::error(pw + ": the model exceeds " + std::to_string(opt.maxVertices) + " vertices (GltfLoadOptions.maxVertices)");
  if (out->positions.size() + vcount > std::numeric_limits<uint32_t>::max())
    return Status::error(pw + ": the model exceeds 2^32 vertices");
  if (out->triangleCount() + tri.size() / 3 > opt.maxTriangles)
    return Status::error(pw + ": the model exceeds " + std::to_string(opt.maxTriangles) + " triangles (GltfLoadOptions.maxTriangles)");
  const uint32_t base = uint32_t(out->positions.size());
  for (uint64_t v = 0; v < vcount; ++v) {
    glm::vec4 p = world * glm::vec4(float(P[v * 3]), float(P[v * 3 + 1]), float(P[v * 3 + 2]), 1.0f);
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
      return Status::error(pw + ".POSITION[" + std::to_string(v) + "] is not finite after the node transforms");
    out->positions.push_back(glm::vec3(p));
    glm::vec3 nrm(0.0f);
    if (!N.empty()) {
      nrm = normalMatrix * glm::vec3(float(N[v * 3]), float(N[v * 3 + 1]), float(N[v * 3 + 2]));
      const float len = glm::length(nrm);
      nrm = len > 0 ? nrm / len : glm::vec3(0.0f);
    }
    out->normals.push_back(nrm);
    out->uvs.push_back(T.empty() ? glm::vec2(0.0f) : glm::vec2(float(T[v * 2]), float(T[v * 2 + 1])));
  }
  const bool computeNormals = N.empty();
  for (size_t k = 0; k < tri.size(); k += 3) {
    out->indices.insert(out->indices.end(), {base + tri[k], base + tri[k + 1], base + tri[k + 2]});
    out->triangleMaterial.push_back(mat);
    if (computeNormals) {
      const glm::vec3 &a = out->positions[base + tri[k]], &b = out->positions[base + tri[k + 1]], &c = out->positions[base + tri[k + 2]];
      const glm::vec3 fn = glm::cross(b - a, c - a);
      for (int q = 0; q < 3; ++q) out->normals[base + tri[k + size_t(q)]] += fn;
    }
  }
  if (computeNormals)
    for (uint64_t v = 0; v < vcount; ++v) {
      glm::vec3& n2 = out->normals[base + v];
      const float len = glm::length(n2);
      n2 = len > 0 ? n2 / len : glm::vec3(0.0f, 1.0f, 0.0f);
    }
  return Status();
}

// EXT_mesh_gpu_instancing on a node: its mesh drawn once per instance, each at the node's world
// transform times the instance's TRANSLATION x ROTATION x SCALE (the extension's order; an absent
// attribute is the identity). Empty `out`: the node has no such extension. The accessors are
// checked like every other (types, component types, counts, byte ranges, finite values), the
// attributes' counts must agree, and the count is bounded by the triangle budget (each instance
// of a mesh costs at least one triangle) before anything is allocated.
Status readInstancing(Load& L, const tinygltf::Node& node, const std::string& what, std::vector<glm::mat4>* out) {
  out->clear();
  auto ext = node.extensions.find("EXT_mesh_gpu_instancing");
  if (ext == node.extensions.end()) return Status();
  const std::string w = what + ".extensions.EXT_mesh_gpu_instancing";
  if (!ext->second.IsObject() || !ext->second.Has("attributes") || !ext->second.Get("attributes").IsObject())
    return Status::error(w + ": 'attributes' must be an object");
  const tinygltf::Value& attrs = ext->second.Get("attributes");
  struct Attribute {
    const char* name;
    int type;
    std::vector<uint32_t> componentTypes;
    std::vector<double> values;
    bool present = false;
  };
  Attribute a[3] = {{"TRANSLATION", TINYGLTF_TYPE_VEC3, {TINYGLTF_COMPONENT_TYPE_FLOAT}, {}},
                    {"ROTATION", TINYGLTF_TYPE_VEC4, {TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_COMPONENT_TYPE_BYTE, TINYGLTF_COMPONENT_TYPE_SHORT}, {}},
                    {"SCALE", TINYGLTF_TYPE_VEC3, {TINYGLTF_COMPONENT_TYPE_FLOAT}, {}}};
  uint64_t count = 0;
  for (Attribute& at : a) {
    if (!attrs.Has(at.name)) continue;
    const tinygltf::Value& v = attrs.Get(at.name);
    // An accessor index (the JSON check bounded it to [0, 2^31 - 1]).
    if (!v.IsInt()) return Status::error(w + ".attributes." + at.name + ": not an accessor index");
    uint32_t nc = 0;
    uint64_t n = 0;
    CANOPY_TRY(L.reader.read(v.GetNumberAsInt(), {at.type}, at.componentTypes, L.opt.maxTriangles, &at.values, &nc, &n)
                   .context(w + ".attributes." + at.name));
    if (count && n != count)
      return Status::error(w + ".attributes." + at.name + ": " + std::to_string(n) + " values where the other attributes have " +
                           std::to_string(count));
    count = n;
    at.present = true;
  }
  if (count == 0) return Status::error(w + ": none of TRANSLATION, ROTATION, SCALE");
  if (count > L.opt.maxTriangles)
    return Status::error(w + ": " + std::to_string(count) + " instances exceed the model's limit of " + std::to_string(L.opt.maxTriangles) +
                         " triangles (GltfLoadOptions.maxTriangles)");
  out->resize(size_t(count), glm::mat4(1.0f));
  for (uint64_t i = 0; i < count; ++i) {
    glm::vec3 t(0.0f), sc(1.0f);
    glm::quat q(1.0f, 0.0f, 0.0f, 0.0f);
    if (a[0].present) t = glm::vec3(a[0].values[3 * i], a[0].values[3 * i + 1], a[0].values[3 * i + 2]);
    if (a[1].present) {
      const double* r = &a[1].values[4 * i];
      const double len = std::sqrt(r[0] * r[0] + r[1] * r[1] + r[2] * r[2] + r[3] * r[3]);
      if (!(len > 1e-6))
        return Status::error(w + ".attributes.ROTATION[" + std::to_string(i) + "]: not a unit quaternion (length " + std::to_string(len) + ")");
      q = glm::quat(float(r[3] / len), float(r[0] / len), float(r[1] / len), float(r[2] / len));  // glTF: x, y, z, w
    }
    if (a[2].present) sc = glm::vec3(a[2].values[3 * i], a[2].values[3 * i + 1], a[2].values[3 * i + 2]);
    (*out)[i] = glm::translate(glm::mat4(1.0f), t) * glm::mat4_cast(q) * glm::scale(glm::mat4(1.0f), sc);
  }
  return Status();
}

// The scene's hierarchy from `roots`, each node's meshes appended. Walked with an explicit stack:
// a chain of a million nodes is a valid tree and must not exhaust the call stack.
Status walkNodes(Load& L, const std::vector<int>& roots) {
  const tinygltf::Model& m = L.m;
  std::vector<uint8_t> visiting(m.nodes.size(), 0);
  struct Pending {
    int node;
    glm::mat4 parent;
    uint32_t plant;  // the ordinal of the scene root it hangs from (VegetationModel::trianglePlant)
  };
  std::vector<Pending> pending;
  auto visit = [&](int ni, const glm::mat4& parent, uint32_t plant) -> Status {
    const std::string what = "nodes[" + std::to_string(ni) + "]";
    if (ni < 0 || size_t(ni) >= m.nodes.size()) return Status::error(what + " does not exist");
    if (visiting[size_t(ni)]) return Status::error(what + " appears twice in the scene's hierarchy (cycle or shared child)");
    visiting[size_t(ni)] = 1;
    const tinygltf::Node& node = m.nodes[size_t(ni)];
    if (!node.matrix.empty() && node.matrix.size() != 16) return Status::error(what + ": matrix must have 16 numbers");
    const glm::mat4 world = parent * nodeMatrix(node);
    for (int k = 0; k < 16; ++k)
      if (!std::isfinite(glm::value_ptr(world)[k])) return Status::error(what + ": transform is not finite");
    if (node.mesh < 0 && node.extensions.count("EXT_mesh_gpu_instancing"))
      L.out->warnings.push_back(what + ".extensions.EXT_mesh_gpu_instancing: the node has no mesh (the extension instances nothing)");
    if (node.mesh >= 0) {
      if (size_t(node.mesh) >= m.meshes.size()) return Status::error(what + ": mesh " + std::to_string(node.mesh) + " does not exist");
      std::vector<glm::mat4> instances;
      CANOPY_TRY(readInstancing(L, node, what, &instances));
      // Each instance a copy in world space and a plant of its own (per-plant roots).
      const size_t copies = std::max<size_t>(instances.size(), 1);
      for (size_t k = 0; k < copies; ++k) {
        const glm::mat4 placed = instances.empty() ? world : world * instances[k];
        for (int e = 0; e < 16; ++e)
          if (!std::isfinite(glm::value_ptr(placed)[e]))
            return Status::error(what + ".extensions.EXT_mesh_gpu_instancing: instance " + std::to_string(k) + "'s transform is not finite");
        const glm::mat3 normalMatrix = glm::inverseTranspose(glm::mat3(placed));
        for (size_t pi = 0; pi < m.meshes[size_t(node.mesh)].primitives.size(); ++pi)
          CANOPY_TRY(appendPrimitive(L, node.mesh, pi, placed, normalMatrix));
        L.out->trianglePlant.resize(L.out->triangleMaterial.size(), instances.empty() ? plant : L.nextPlant++);
      }
    }
    for (auto c = node.children.rbegin(); c != node.children.rend(); ++c) pending.push_back({*c, world, plant});
    return Status();
  };
  L.nextPlant = uint32_t(roots.size());
  for (size_t r = roots.size(); r-- > 0;) pending.push_back({roots[r], glm::mat4(1.0f), uint32_t(r)});
  while (!pending.empty()) {
    const Pending p = pending.back();
    pending.pop_back();
    CANOPY_TRY(visit(p.node, p.parent, p.plant));
  }
  // Each scene root a plant, unless their bounds overlap on the ground (parts of one plant).
  L.out->mergeOverlappingPlants = true;
  return Status();
}

// The images decoded so far for each colour space (slot in out->images per glTF image, -1: not
// yet) and the pixel budget left.
struct ImageSlots {
  std::vector<int32_t> srgb, linear;
  uint64_t pixelsLeft = 0;
};

// A texture of material `what` (texture index `tex`, coordinate set `texCoord`) as a slot of
// out->images, decoded once per image and colour space (`linear`: normal maps; else sRGB). With
// `only`, decoded into it instead and not kept (a texture read once on the CPU: its slot stays -1).
Status decodeTexture(Load& L, ImageSlots& S, const std::string& what, int tex, int texCoord, const char* role,
                     bool linear, int32_t* slot, ModelImage* only = nullptr) {
  const tinygltf::Model& m = L.m;
  const GltfLoadOptions& opt = L.opt;
  VegetationModel* out = L.out;
  if (tex < 0) return Status();
  if (size_t(tex) >= m.textures.size()) return Status::error(what + ": " + role + " texture " + std::to_string(tex) + " does not exist");
  const int img = textureImage(m.textures[size_t(tex)]);  // EXT_texture_webp's source first
  if (img < 0) {  // glTF allows it (an extension may supply the image): drawn without this texture
    out->warnings.push_back(what + ": " + role + " textures[" + std::to_string(tex) + "] has no source image (not used)");
    return Status();
  }
  if (size_t(img) >= m.images.size())
    return Status::error(what + ": textures[" + std::to_string(tex) + "] names images[" + std::to_string(img) + "], which does not exist");
  if (texCoord != 0)
    out->warnings.push_back(what + ": " + role + " uses TEXCOORD_" + std::to_string(texCoord) + "; TEXCOORD_0 is used");
  if (!opt.decodeImages) return Status();
  std::vector<int32_t>& slots = linear ? S.linear : S.srgb;
  if (slots[size_t(img)] < 0 || only) {
    const std::string iw = "images[" + std::to_string(img) + "]";
    const tinygltf::Image& im = m.images[size_t(img)];
    const unsigned char* data = nullptr;
    uint64_t size = 0;
    if (im.bufferView >= 0) {
      uint32_t stride;
      const Status s = L.reader.view(im.bufferView, &data, &size, &stride);
      if (!s.ok()) return Status::error(iw + ": " + s.message());
    } else if (size_t(img) < L.images.encoded.size() && !L.images.encoded[size_t(img)].empty()) {
      data = L.images.encoded[size_t(img)].data();
      size = L.images.encoded[size_t(img)].size();
    } else {
      return Status::error(iw + " ('" + im.uri + "') could not be loaded" + (L.fs.lastError.empty() ? "" : ": " + L.fs.lastError));
    }
    ModelImage mi;
    if (isWebp(data, size)) {  // EXT_texture_webp: libwebp, after the same size and budget checks
      const Status s = decodeWebp(data, size, opt.maxImageDimension, &S.pixelsLeft, &mi.width, &mi.height, &mi.rgba);
      if (!s.ok()) return Status::error(iw + " ('" + im.uri + im.mimeType + "') " + s.message());
    } else {
      int w = 0, h = 0, comp = 0;
      if (size > uint64_t(std::numeric_limits<int>::max()) || !stbi_info_from_memory(data, int(size), &w, &h, &comp))
        return Status::error(iw + " ('" + im.uri + im.mimeType + "') does not decode: " + (stbi_failure_reason() ? stbi_failure_reason() : "unknown format"));
      if (w <= 0 || h <= 0 || uint32_t(w) > opt.maxImageDimension || uint32_t(h) > opt.maxImageDimension)
        return Status::error(iw + ": " + std::to_string(w) + "x" + std::to_string(h) + " exceeds " + std::to_string(opt.maxImageDimension) + " per side");
      const uint64_t pixels = uint64_t(w) * uint64_t(h);
      if (pixels > S.pixelsLeft)
        return Status::error(iw + ": " + std::to_string(w) + "x" + std::to_string(h) + " exceeds what is left of the " +
                    std::to_string(opt.maxImagePixels) + "-pixel budget of all images (GltfLoadOptions.maxImagePixels)");
      S.pixelsLeft -= pixels;
      unsigned char* px = stbi_load_from_memory(data, int(size), &w, &h, &comp, 4);
      if (!px) return Status::error(iw + " does not decode: " + (stbi_failure_reason() ? stbi_failure_reason() : "unknown error"));
      mi.width = uint32_t(w);
      mi.height = uint32_t(h);
      mi.rgba.assign(px, px + size_t(w) * h * 4);
      stbi_image_free(px);
    }
    mi.name = im.name.empty() ? im.uri : im.name;
    mi.linear = linear;
    if (only) {
      *only = std::move(mi);
      return Status();
    }
    slots[size_t(img)] = int32_t(out->images.size());
    out->images.push_back(std::move(mi));
  }
  *slot = slots[size_t(img)];
  return Status();
}

// Leaf transmission's factors: KHR_materials_diffuse_transmission (its textures in
// *diffuseTransmission for loadMaterial), else KHR_materials_transmission's factor.
Status transmissionFactors(const tinygltf::Material& src, const std::string& what, ModelMaterial* mm,
                           const tinygltf::Value** diffuseTransmission) {
  // A glTF factor: a number in [0, 1].
  auto factor = [&](const tinygltf::Value& ext, const char* extName, const char* key, float* out) -> Status {
    if (!ext.Has(key)) return Status();
    const tinygltf::Value& v = ext.Get(key);
    const double x = v.IsNumber() ? v.GetNumberAsDouble() : NAN;
    if (!(x >= 0.0 && x <= 1.0)) return Status::error(what + ": " + extName + "." + key + " must be a number in [0, 1]");
    *out = float(x);
    return Status();
  };
  *diffuseTransmission = nullptr;
  auto extension = src.extensions.find("KHR_materials_diffuse_transmission");
  if (extension != src.extensions.end() && extension->second.IsObject()) {
    const tinygltf::Value& ext = extension->second;
    *diffuseTransmission = &ext;
    mm->transmissionFactor = 0.0f;  // the extension's default
    Status s = factor(ext, "KHR_materials_diffuse_transmission", "diffuseTransmissionFactor", &mm->transmissionFactor);
    if (!s.ok()) return s;
    if (ext.Has("diffuseTransmissionColorFactor")) {
      const tinygltf::Value& c = ext.Get("diffuseTransmissionColorFactor");
      bool good = c.IsArray() && c.ArrayLen() == 3;
      for (int k = 0; good && k < 3; ++k) {
        const double x = c.Get(k).IsNumber() ? c.Get(k).GetNumberAsDouble() : NAN;
        good = x >= 0.0 && x <= 1.0;
        if (good) mm->transmissionColor[k] = float(x);
      }
      if (!good)
        return Status::error(what + ": KHR_materials_diffuse_transmission.diffuseTransmissionColorFactor must be 3 numbers in [0, 1]");
    }
  } else if ((extension = src.extensions.find("KHR_materials_transmission")) != src.extensions.end() &&
             extension->second.IsObject()) {
    mm->transmissionFactor = 0.0f;
    const Status s = factor(extension->second, "KHR_materials_transmission", "transmissionFactor", &mm->transmissionFactor);
    if (!s.ok()) return s;
  }
  // KHR_materials_volume: the leaf's thickness and its Beer-Lambert attenuation (Habel's
  // translucency). thicknessTexture is not read: the factor applies over the whole material.
  extension = src.extensions.find("KHR_materials_volume");
  if (extension != src.extensions.end() && extension->second.IsObject()) {
    const tinygltf::Value& ext = extension->second;
    // A finite number in [lo, 1e30] (`range` says which in the message).
    auto number = [&](const char* key, double lo, const char* range, float* out) -> Status {
      if (!ext.Has(key)) return Status();
      const tinygltf::Value& v = ext.Get(key);
      const double x = v.IsNumber() ? v.GetNumberAsDouble() : NAN;
      if (!(x >= lo && x <= 1e30)) return Status::error(what + ": KHR_materials_volume." + key + " must be a number " + range);
      *out = float(x);
      return Status();
    };
    mm->thicknessFactor = 0.0f;  // the extension's default
    CANOPY_TRY(number("thicknessFactor", 0.0, ">= 0", &mm->thicknessFactor));
    CANOPY_TRY(number("attenuationDistance", 1e-30, "> 0", &mm->attenuationDistance));
    if (ext.Has("attenuationColor")) {
      const tinygltf::Value& c = ext.Get("attenuationColor");
      bool good = c.IsArray() && c.ArrayLen() == 3;
      for (int k = 0; good && k < 3; ++k) {
        const double x = c.Get(k).IsNumber() ? c.Get(k).GetNumberAsDouble() : NAN;
        good = x >= 0.0 && x <= 1.0;
        if (good) mm->attenuationColor[k] = float(x);
      }
      if (!good) return Status::error(what + ": KHR_materials_volume.attenuationColor must be 3 numbers in [0, 1]");
    }
  }
  return Status();
}

// The leaf's gloss (docs/design.md "Layers: leaf shading"): glTF's roughness (roughnessFactor, default 1,
// times the mean green of metallicRoughnessTexture where a triangle uses the material) and
// KHR_materials_specular's factors (its textures are not read).
Status glossFactors(Load& L, ImageSlots& S, const tinygltf::Material& src, const std::string& what, bool used, ModelMaterial* mm) {
  const auto& pbr = src.pbrMetallicRoughness;
  if (!(pbr.roughnessFactor >= 0.0 && pbr.roughnessFactor <= 1.0))
    return Status::error(what + ": pbrMetallicRoughness.roughnessFactor must be a number in [0, 1]");
  mm->roughness = float(pbr.roughnessFactor);
  if (used && pbr.metallicRoughnessTexture.index >= 0) {
    ModelImage mr;
    int32_t unused = -1;
    CANOPY_TRY(decodeTexture(L, S, what, pbr.metallicRoughnessTexture.index, pbr.metallicRoughnessTexture.texCoord,
                             "metallic-roughness", true, &unused, &mr));
    double sum = 0;
    for (size_t p = 1; p < mr.rgba.size(); p += 4) sum += mr.rgba[p];
    if (!mr.rgba.empty()) mm->roughness *= float(sum / (double(mr.rgba.size() / 4) * 255.0));
  }
  const auto extension = src.extensions.find("KHR_materials_specular");
  if (extension == src.extensions.end() || !extension->second.IsObject()) return Status();
  const tinygltf::Value& ext = extension->second;
  double factor = 1.0, colour = 1.0;
  if (ext.Has("specularFactor")) {
    const tinygltf::Value& v = ext.Get("specularFactor");
    factor = v.IsNumber() ? v.GetNumberAsDouble() : NAN;
    if (!(factor >= 0.0 && factor <= 1.0)) return Status::error(what + ": KHR_materials_specular.specularFactor must be a number in [0, 1]");
  }
  if (ext.Has("specularColorFactor")) {
    const tinygltf::Value& c = ext.Get("specularColorFactor");
    bool good = c.IsArray() && c.ArrayLen() == 3;
    colour = 0.0;
    for (int k = 0; good && k < 3; ++k) {
      const double x = c.Get(k).IsNumber() ? c.Get(k).GetNumberAsDouble() : NAN;
      good = x >= 0.0 && x <= 1e6;
      colour = std::max(colour, x);
    }
    if (!good) return Status::error(what + ": KHR_materials_specular.specularColorFactor must be 3 non-negative numbers");
  }
  mm->specularFactor = float(std::min(factor * colour, 1.0));
  return Status();
}

// Material i: factors, alpha, transmission, and (when a triangle uses it) its textures decoded.
Status loadMaterial(Load& L, ImageSlots& S, size_t i, bool used, ModelMaterial* mm) {
  const tinygltf::Material& src = L.m.materials[i];
  const std::string what = "materials[" + std::to_string(i) + "]";
  mm->name = src.name;
  const auto& f = src.pbrMetallicRoughness.baseColorFactor;
  if (f.size() == 4) mm->baseColorFactor = glm::vec4(float(f[0]), float(f[1]), float(f[2]), float(f[3]));
  mm->alphaMode = src.alphaMode == "MASK" ? AlphaMode::Mask : src.alphaMode == "BLEND" ? AlphaMode::Blend : AlphaMode::Opaque;
  mm->alphaCutoff = float(src.alphaCutoff);
  mm->doubleSided = src.doubleSided;
  const tinygltf::Value* diffuseTransmission = nullptr;
  CANOPY_TRY(transmissionFactors(src, what, mm, &diffuseTransmission));
  CANOPY_TRY(glossFactors(L, S, src, what, used, mm));
  Status s;
  auto texture = [&](int tex, int texCoord, const char* role, bool linear, int32_t* slot) {
    return used ? decodeTexture(L, S, what, tex, texCoord, role, linear, slot) : Status();
  };
  const auto& pbr = src.pbrMetallicRoughness;
  if (!(s = texture(pbr.baseColorTexture.index, pbr.baseColorTexture.texCoord, "base colour", false, &mm->baseColorImage)).ok() ||
      !(s = texture(src.normalTexture.index, src.normalTexture.texCoord, "normal map", true, &mm->normalImage)).ok())
    return Status::error(s.message());
  if (mm->normalImage >= 0) {
    mm->normalScale = float(src.normalTexture.scale);
    if (!(std::abs(mm->normalScale) <= 100.0f))
      return Status::error(what + ": normalTexture.scale must be a finite number in [-100, 100]");
  }
  // KHR_materials_diffuse_transmission's textures: the factor in the alpha channel, the colour in RGB.
  if (diffuseTransmission) {
    for (const char* key : {"diffuseTransmissionTexture", "diffuseTransmissionColorTexture"}) {
      if (!diffuseTransmission->Has(key)) continue;
      const tinygltf::Value& info = diffuseTransmission->Get(key);
      const bool colour = std::string(key) == "diffuseTransmissionColorTexture";
      if (!info.IsObject() || !info.Has("index") || !info.Get("index").IsInt() || info.Get("index").GetNumberAsInt() < 0)
        return Status::error(what + ": KHR_materials_diffuse_transmission." + key + ".index must be a texture index");
      const int texCoord = info.Has("texCoord") && info.Get("texCoord").IsInt() ? info.Get("texCoord").GetNumberAsInt() : 0;
      if (!(s = texture(info.Get("index").GetNumberAsInt(), texCoord, key, false,
                        colour ? &mm->transmissionColorImage : &mm->transmissionImage)).ok())
        return Status::error(s.message());
    }
  }
  return Status();
}

// Materials (all of them keep their index; a default one is appended) and the images they use.
Status loadMaterials(Load& L) {
  const tinygltf::Model& m = L.m;
  ImageSlots S;
  S.srgb.assign(m.images.size(), -1);
  S.linear.assign(m.images.size(), -1);
  S.pixelsLeft = L.opt.maxImagePixels;
  std::vector<bool> materialUsedByTriangle(m.materials.size() + 1, false);
  for (uint32_t t : L.out->triangleMaterial) materialUsedByTriangle[t] = true;
  for (size_t i = 0; i < m.materials.size(); ++i) {
    ModelMaterial mm;
    CANOPY_TRY(loadMaterial(L, S, i, materialUsedByTriangle[i], &mm));
    L.out->materials.push_back(mm);
  }
  ModelMaterial fallback;
  fallback.name = "(default)";
  L.out->materials.push_back(fallback);
  return Status();
}

}  // namespace

// The loader behind loadGltf and loadGltfFromMemory: `bytes` is the model file, `fs` resolves
// its external files. Every refusal names the file.
static Status loadBytes(const std::string& path, const std::vector<unsigned char>& bytes, FsContext& fs,
                        const GltfLoadOptions& opt, VegetationModel* out) {
  const std::string file = "'" + path + "'";
  auto fail = [&](const Status& s) {
    *out = VegetationModel{};
    // Out of host memory keeps its code; every other refusal is the file's (InvalidArgument).
    return s.code() == Result::OutOfHostMemory ? Status::error(Result::OutOfHostMemory, file + ": " + s.message())
                                                : Status::error(file + ": " + s.message());
  };
  ImageContext images;
  tinygltf::Model m;
  GltfReadParts parts;
  std::vector<MeshoptView> meshopt;
  Status s = parseFile(bytes, fs, opt, &m, &images, &parts, &meshopt, &out->warnings);
  out->warnings.insert(out->warnings.end(), parts.warnings.begin(), parts.warnings.end());
  if (s.ok()) s = checkDocument(m, fs);
  // Compressed data decoded into plain buffers: everything after reads them as any file's.
  if (s.ok()) s = decodeMeshopt(m, meshopt);
  if (s.ok()) s = decodeDraco(m, opt, parts.dracoIndices);
  std::vector<int> roots;
  if (s.ok()) s = sceneRoots(m, out, &roots);
  Load L{m, opt, fs, images, out, GltfReader(m), parts};
  if (s.ok()) s = walkNodes(L, roots);
  if (s.ok()) s = loadMaterials(L);
  if (!s.ok()) return fail(s);
  if (!out->positions.empty()) {
    out->boundsMin = out->boundsMax = out->positions[0];
    for (const glm::vec3& p : out->positions) {
      out->boundsMin = glm::min(out->boundsMin, p);
      out->boundsMax = glm::max(out->boundsMax, p);
    }
  }
  out->path = path;
  return Status();
}

// Everything the loader calls that can throw (the standard library's allocations, nlohmann-json,
// tinygltf) stops here: the caller gets a Status, never an exception.
template <class F>
static Status guarded(const std::string& path, VegetationModel* out, F&& load) {
  Status s;
  try {
    s = load();
  } catch (const std::bad_alloc&) {
    s = Status::error(Result::OutOfHostMemory, "'" + path + "': out of host memory while loading");
  } catch (const std::exception& e) {
    s = Status::error(Result::InvalidModel, "'" + path + "': " + e.what());
  }
  if (!s.ok()) *out = VegetationModel{};
  return s;
}

Status loadGltf(const std::string& path, const GltfLoadOptions& opt, VegetationModel* out) {
  *out = VegetationModel{};
  return guarded(path, out, [&]() -> Status {
    std::vector<unsigned char> bytes;
    Status s = readFile(path, opt.maxFileBytes, &bytes);
    if (!s.ok()) return Status::error(s.code(), "'" + path + "': " + s.message());
    FsContext fs;
    const size_t slash = path.find_last_of('/');
    fs.baseDir = slash == std::string::npos ? "" : path.substr(0, slash);
    fs.maxBytes = opt.maxFileBytes;
    char resolved[PATH_MAX];
    if (!realpath(fs.baseDir.empty() ? "." : fs.baseDir.c_str(), resolved))
      return Status::error(Result::FileError, "'" + path + "': cannot resolve its folder");
    fs.realBase = resolved;
    return loadBytes(path, bytes, fs, opt, out);
  });
}

Status loadGltfFromMemory(const std::string& name, const std::vector<unsigned char>& bytes,
                          const std::map<std::string, std::vector<unsigned char>>& files, const GltfLoadOptions& opt,
                          VegetationModel* out) {
  *out = VegetationModel{};
  return guarded(name, out, [&]() -> Status {
    FsContext fs;
    fs.maxBytes = opt.maxFileBytes;
    fs.memory = &files;
    if (bytes.size() > opt.maxFileBytes)
      return Status::error("'" + name + "': file of " + std::to_string(bytes.size()) + " bytes exceeds the limit of " +
                           std::to_string(opt.maxFileBytes));
    return loadBytes(name, bytes, fs, opt, out);
  });
}

}  // namespace canopy
