#include "render/gltf_compressed.h"

#include <cmath>
#include <cstring>
#include <limits>
#include <memory>

#include <draco/compression/decode.h>
#include <meshoptimizer.h>
#include <nlohmann/json.hpp>
#include <webp/decode.h>

#include <canopy/canopy_params.h>

#include "render/gltf_accessors.h"

namespace canopy {
namespace {

using json = nlohmann::json;

const json* child(const json& o, const char* key) {
  if (!o.is_object()) return nullptr;
  auto it = o.find(key);
  return it == o.end() ? nullptr : &*it;
}

// A non-negative integer field, else an error naming it.
Status uintField(const json& o, const char* key, const std::string& what, uint64_t* out, bool required = true) {
  const json* v = child(o, key);
  if (!v) {
    if (required) return Status::error(what + "." + key + " is missing");
    return Status();
  }
  if (!v->is_number_unsigned() && !(v->is_number_integer() && v->get<int64_t>() >= 0))
    return Status::error(what + "." + key + " must be a non-negative integer");
  *out = v->get<uint64_t>();
  return Status();
}

// The stand-in for a fallback buffer: one byte, so tinygltf loads nothing of the file for it.
const char* kStandIn = "data:application/octet-stream;base64,AA==";

// Meshopt decodes at most this many bytes per compressed byte (the vertex codec's densest block
// is a 2-bit header per 16 bytes: 64 to 1; the index codecs less), plus a block's worth.
constexpr uint64_t kMeshoptExpansion = 128, kMeshoptSlack = 65536;

}  // namespace

Status prepareMeshopt(json& doc, const GltfLoadOptions& opt, std::vector<MeshoptView>* views) {
  views->clear();
  if (!doc.is_object()) return Status();
  json* bv = doc.contains("bufferViews") ? &doc["bufferViews"] : nullptr;
  json* buffers = doc.contains("buffers") ? &doc["buffers"] : nullptr;
  if (!bv || !bv->is_array()) return Status();
  const size_t bufferCount = buffers && buffers->is_array() ? buffers->size() : 0;
  for (size_t i = 0; i < bv->size(); ++i) {
    json& v = (*bv)[i];
    const json* ext = child(v, "extensions");
    const json* mo = ext ? child(*ext, "EXT_meshopt_compression") : nullptr;
    if (!mo) continue;
    const std::string what = "bufferViews[" + std::to_string(i) + "].extensions.EXT_meshopt_compression";
    if (!mo->is_object()) return Status::error(what + " must be an object");
    uint64_t buffer = 0, offset = 0, length = 0, stride = 0, count = 0;
    CANOPY_TRY(uintField(*mo, "buffer", what, &buffer));
    CANOPY_TRY(uintField(*mo, "byteOffset", what, &offset, false));
    CANOPY_TRY(uintField(*mo, "byteLength", what, &length));
    CANOPY_TRY(uintField(*mo, "byteStride", what, &stride));
    CANOPY_TRY(uintField(*mo, "count", what, &count));
    if (buffer >= bufferCount) return Status::error(what + ".buffer = " + std::to_string(buffer) + " does not exist");
    MeshoptView m;
    m.view = int(i);
    const json* mode = child(*mo, "mode");
    const std::string modeName = mode && mode->is_string() ? mode->get<std::string>() : "";
    if (modeName == "ATTRIBUTES") m.mode = 0;
    else if (modeName == "TRIANGLES") m.mode = 1;
    else if (modeName == "INDICES") m.mode = 2;
    else return Status::error(what + ".mode must be \"ATTRIBUTES\", \"TRIANGLES\" or \"INDICES\"");
    const json* filter = child(*mo, "filter");
    const std::string filterName = filter && filter->is_string() ? filter->get<std::string>() : filter ? "?" : "NONE";
    if (filterName == "NONE") m.filter = 0;
    else if (filterName == "OCTAHEDRAL") m.filter = 1;
    else if (filterName == "QUATERNION") m.filter = 2;
    else if (filterName == "EXPONENTIAL") m.filter = 3;
    else return Status::error(what + ".filter must be \"NONE\", \"OCTAHEDRAL\", \"QUATERNION\" or \"EXPONENTIAL\"");
    // The codecs' own limits (meshoptimizer.h) and the loader's budgets, before anything is allocated.
    if (m.mode == 0 && (stride == 0 || stride > 256 || stride % 4 != 0))
      return Status::error(what + ".byteStride = " + std::to_string(stride) + ": ATTRIBUTES needs a multiple of 4 in [4, 256]");
    if (m.mode != 0 && stride != 2 && stride != 4)
      return Status::error(what + ".byteStride = " + std::to_string(stride) + ": " + modeName + " needs 2 or 4");
    if (m.mode == 1 && count % 3 != 0) return Status::error(what + ".count = " + std::to_string(count) + ": TRIANGLES needs a multiple of 3");
    if (m.filter == 1 && stride != 4 && stride != 8) return Status::error(what + ": the OCTAHEDRAL filter needs byteStride 4 or 8");
    if (m.filter == 2 && stride != 8) return Status::error(what + ": the QUATERNION filter needs byteStride 8");
    if (m.filter != 0 && m.mode != 0) return Status::error(what + ": a filter applies to ATTRIBUTES only");
    const uint64_t limit = m.mode == 0 ? opt.maxVertices : (opt.maxTriangles > (UINT64_MAX - 2) / 3 ? UINT64_MAX : opt.maxTriangles * 3 + 2);
    if (count > limit)
      return Status::error(what + ".count = " + std::to_string(count) + " exceeds the loader's budget (" +
                           (m.mode == 0 ? "GltfLoadOptions.maxVertices" : "3 x GltfLoadOptions.maxTriangles") + ")");
    const uint64_t decoded = count * stride;
    if (decoded > kMeshoptExpansion * length + kMeshoptSlack || decoded > opt.maxFileBytes)
      return Status::error(what + ": " + std::to_string(count) + " x " + std::to_string(stride) + " bytes cannot come from " +
                           std::to_string(length) + " compressed bytes");
    m.count = count;
    m.stride = uint32_t(stride);
    views->push_back(m);
    // The view now names the compressed bytes; decodeMeshopt gives it the decoded ones.
    v["buffer"] = buffer;
    v["byteOffset"] = offset;
    v["byteLength"] = length;
    v.erase("byteStride");
  }
  // Fallback buffers hold no data (the decoder fills the views); a uri, if any, is not read.
  for (size_t i = 0; i < bufferCount; ++i) {
    json& b = (*buffers)[i];
    const json* ext = child(b, "extensions");
    const json* mo = ext ? child(*ext, "EXT_meshopt_compression") : nullptr;
    const json* fallback = mo ? child(*mo, "fallback") : nullptr;
    if (fallback && fallback->is_boolean() && fallback->get<bool>()) b = json{{"byteLength", 1}, {"uri", kStandIn}};
  }
  return Status();
}

Status decodeMeshopt(tinygltf::Model& m, const std::vector<MeshoptView>& views) {
  GltfReader reader(m);
  for (const MeshoptView& mv : views) {
    const std::string what = "bufferViews[" + std::to_string(mv.view) + "].extensions.EXT_meshopt_compression";
    const unsigned char* src = nullptr;
    uint64_t size = 0;
    uint32_t stride = 0;
    CANOPY_TRY(reader.view(mv.view, &src, &size, &stride).context(what));
    tinygltf::Buffer out;
    out.data.resize(size_t(mv.count * mv.stride));
    int rc = 0;
    if (mv.mode == 0) rc = meshopt_decodeVertexBuffer(out.data.data(), size_t(mv.count), mv.stride, src, size_t(size));
    else if (mv.mode == 1) rc = meshopt_decodeIndexBuffer(out.data.data(), size_t(mv.count), mv.stride, src, size_t(size));
    else rc = meshopt_decodeIndexSequence(out.data.data(), size_t(mv.count), mv.stride, src, size_t(size));
    if (rc != 0) return Status::error(what + ": the compressed data does not decode (meshoptimizer error " + std::to_string(rc) + ")");
    if (mv.filter == 1) meshopt_decodeFilterOct(out.data.data(), size_t(mv.count), mv.stride);
    else if (mv.filter == 2) meshopt_decodeFilterQuat(out.data.data(), size_t(mv.count), mv.stride);
    else if (mv.filter == 3) meshopt_decodeFilterExp(out.data.data(), size_t(mv.count), mv.stride);
    m.buffers.push_back(std::move(out));
    tinygltf::BufferView& v = m.bufferViews[size_t(mv.view)];
    v.buffer = int(m.buffers.size() - 1);
    v.byteOffset = 0;
    v.byteLength = size_t(mv.count * mv.stride);
    v.byteStride = mv.mode == 0 ? mv.stride : 0;
  }
  return Status();
}

Status decodeDraco(tinygltf::Model& m, const GltfLoadOptions& opt, const std::map<std::pair<int, int>, int>& indices) {
  GltfReader reader(m);
  for (size_t mi = 0; mi < m.meshes.size(); ++mi)
    for (size_t pi = 0; pi < m.meshes[mi].primitives.size(); ++pi) {
      tinygltf::Primitive& pr = m.meshes[mi].primitives[pi];
      auto it = pr.extensions.find("KHR_draco_mesh_compression");
      if (it == pr.extensions.end()) continue;
      const std::string what = "meshes[" + std::to_string(mi) + "].primitives[" + std::to_string(pi) + "].extensions.KHR_draco_mesh_compression";
      const tinygltf::Value& ext = it->second;
      const tinygltf::Value& viewValue = ext.Get("bufferView");
      const tinygltf::Value& attrs = ext.Get("attributes");
      if (!viewValue.IsInt() || viewValue.Get<int>() < 0 || !attrs.IsObject())
        return Status::error(what + " needs a bufferView index and an attributes object");
      const unsigned char* src = nullptr;
      uint64_t size = 0;
      uint32_t stride = 0;
      CANOPY_TRY(reader.view(viewValue.Get<int>(), &src, &size, &stride).context(what + ".bufferView"));
      if (size > uint64_t(std::numeric_limits<int64_t>::max())) return Status::error(what + ": the bufferView is too large");
      draco::DecoderBuffer buffer;
      buffer.Init(reinterpret_cast<const char*>(src), size_t(size));
      auto type = draco::Decoder::GetEncodedGeometryType(&buffer);
      if (!type.ok() || type.value() != draco::TRIANGULAR_MESH)
        return Status::error(what + ": the bufferView is not a Draco triangle mesh" + (type.ok() ? "" : " (" + type.status().error_msg_string() + ")"));
      draco::Decoder decoder;
      auto decoded = decoder.DecodeMeshFromBuffer(&buffer);
      if (!decoded.ok()) return Status::error(what + ": Draco cannot decode it: " + decoded.status().error_msg_string());
      const std::unique_ptr<draco::Mesh> mesh = std::move(decoded).value();
      const uint64_t points = mesh->num_points(), faces = mesh->num_faces();
      if (points > opt.maxVertices || faces > opt.maxTriangles)
        return Status::error(what + ": " + std::to_string(points) + " vertices, " + std::to_string(faces) +
                             " triangles exceed the loader's budget (GltfLoadOptions.maxVertices, maxTriangles)");
      // Each attribute the extension names: its accessor given a float buffer of the decoded values.
      for (const std::string& name : attrs.Keys()) {
        const tinygltf::Value& id = attrs.Get(name);
        auto acc = pr.attributes.find(name);
        if (acc == pr.attributes.end()) continue;  // glTF: only the primitive's own attributes are read
        if (!id.IsInt()) return Status::error(what + ".attributes." + name + " must be an attribute id");
        const draco::PointAttribute* pa = mesh->GetAttributeByUniqueId(uint32_t(id.Get<int>()));
        if (!pa) return Status::error(what + ".attributes." + name + " = " + std::to_string(id.Get<int>()) + " is not in the Draco data");
        if (acc->second < 0 || size_t(acc->second) >= m.accessors.size())
          return Status::error(what + ": the primitive's " + name + " accessor does not exist");
        tinygltf::Accessor& a = m.accessors[size_t(acc->second)];
        const uint32_t n = componentCount(a.type);
        if (n == 0 || n > 4) return Status::error(what + ": accessor " + std::to_string(acc->second) + " (" + name + ") has an unknown type");
        if (a.count != points)
          return Status::error(what + ": accessor " + std::to_string(acc->second) + " (" + name + ") counts " + std::to_string(a.count) +
                               ", the Draco data " + std::to_string(points));
        tinygltf::Buffer out;
        out.data.resize(size_t(points * n * 4));
        std::vector<float> value(n);
        for (uint64_t p = 0; p < points; ++p) {
          if (!pa->ConvertValue<float>(pa->mapped_index(draco::PointIndex(uint32_t(p))), int8_t(n), value.data()))
            return Status::error(what + ".attributes." + name + ": Draco cannot give its values as " + std::to_string(n) + " floats");
          std::memcpy(out.data.data() + size_t(p * n * 4), value.data(), n * 4);
        }
        m.buffers.push_back(std::move(out));
        tinygltf::BufferView v;
        v.buffer = int(m.buffers.size() - 1);
        v.byteLength = size_t(points * n * 4);
        m.bufferViews.push_back(v);
        a.bufferView = int(m.bufferViews.size() - 1);
        a.byteOffset = 0;
        a.componentType = TINYGLTF_COMPONENT_TYPE_FLOAT;
        a.normalized = false;
        a.sparse.isSparse = false;
      }
      // The triangles, as 32-bit indices.
      if (auto taken = indices.find({int(mi), int(pi)}); taken != indices.end()) pr.indices = taken->second;
      if (pr.indices < 0 || size_t(pr.indices) >= m.accessors.size()) return Status::error(what + ": the primitive has no indices accessor");
      tinygltf::Accessor& ia = m.accessors[size_t(pr.indices)];
      if (ia.count != faces * 3)
        return Status::error(what + ": the indices accessor counts " + std::to_string(ia.count) + ", the Draco data " + std::to_string(faces * 3));
      tinygltf::Buffer out;
      out.data.resize(size_t(faces * 12));
      for (uint64_t f = 0; f < faces; ++f) {
        const draco::Mesh::Face& face = mesh->face(draco::FaceIndex(uint32_t(f)));
        for (int k = 0; k < 3; ++k) {
          const uint32_t index = face[k].value();
          std::memcpy(out.data.data() + size_t(f * 12 + uint64_t(k) * 4), &index, 4);
        }
      }
      m.buffers.push_back(std::move(out));
      tinygltf::BufferView v;
      v.buffer = int(m.buffers.size() - 1);
      v.byteLength = size_t(faces * 12);
      m.bufferViews.push_back(v);
      ia.bufferView = int(m.bufferViews.size() - 1);
      ia.byteOffset = 0;
      ia.componentType = TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT;
      ia.sparse.isSparse = false;
    }
  return Status();
}

int textureImage(const tinygltf::Texture& t) {
  auto it = t.extensions.find("EXT_texture_webp");
  if (it != t.extensions.end() && it->second.Get("source").IsInt()) return it->second.Get("source").Get<int>();
  return t.source;
}

bool isWebp(const unsigned char* data, uint64_t size) {
  return size >= 12 && std::memcmp(data, "RIFF", 4) == 0 && std::memcmp(data + 8, "WEBP", 4) == 0;
}

Status decodeWebp(const unsigned char* data, uint64_t size, uint32_t maxDimension, uint64_t* pixelsLeft, uint32_t* width,
                  uint32_t* height, std::vector<unsigned char>* rgba) {
  int w = 0, h = 0;
  if (size > uint64_t(std::numeric_limits<int>::max()) || !WebPGetInfo(data, size_t(size), &w, &h))
    return Status::error("is not a WebP image libwebp can read");
  if (w <= 0 || h <= 0 || uint32_t(w) > maxDimension || uint32_t(h) > maxDimension)
    return Status::error(std::to_string(w) + "x" + std::to_string(h) + " exceeds " + std::to_string(maxDimension) + " per side");
  const uint64_t pixels = uint64_t(w) * uint64_t(h);
  if (pixels > *pixelsLeft)
    return Status::error(std::to_string(w) + "x" + std::to_string(h) + " exceeds what is left of the pixel budget of all images "
                         "(GltfLoadOptions.maxImagePixels)");
  rgba->resize(size_t(pixels * 4));
  if (!WebPDecodeRGBAInto(data, size_t(size), rgba->data(), rgba->size(), w * 4))
    return Status::error("does not decode (libwebp)");
  *pixelsLeft -= pixels;
  *width = uint32_t(w);
  *height = uint32_t(h);
  return Status();
}

Status textureTransform(const tinygltf::ExtensionMap& extensions, const std::string& what, TextureTransform* out) {
  *out = TextureTransform{};
  auto it = extensions.find("KHR_texture_transform");
  if (it == extensions.end()) return Status();
  const tinygltf::Value& e = it->second;
  const std::string w = what + ".extensions.KHR_texture_transform";
  if (!e.IsObject()) return Status::error(w + " must be an object");
  auto pair = [&](const char* key, double dflt, double* a, double* b) -> Status {
    *a = *b = dflt;
    const tinygltf::Value& v = e.Get(key);
    if (v.Type() == tinygltf::NULL_TYPE) return Status();
    if (!v.IsArray() || v.ArrayLen() != 2 || !v.Get(0).IsNumber() || !v.Get(1).IsNumber())
      return Status::error(w + "." + key + " must be 2 numbers");
    *a = v.Get(0).GetNumberAsDouble();
    *b = v.Get(1).GetNumberAsDouble();
    if (!std::isfinite(*a) || !std::isfinite(*b) || std::abs(*a) > 1e6 || std::abs(*b) > 1e6)
      return Status::error(w + "." + key + " must be finite numbers within +-1e6");
    return Status();
  };
  double ox, oy, sx, sy, r = 0;
  CANOPY_TRY(pair("offset", 0.0, &ox, &oy));
  CANOPY_TRY(pair("scale", 1.0, &sx, &sy));
  const tinygltf::Value& rv = e.Get("rotation");
  if (rv.Type() != tinygltf::NULL_TYPE) {
    if (!rv.IsNumber() || !std::isfinite(rv.GetNumberAsDouble()) || std::abs(rv.GetNumberAsDouble()) > 1e6)
      return Status::error(w + ".rotation must be a finite number (radians)");
    r = rv.GetNumberAsDouble();
  }
  const tinygltf::Value& tc = e.Get("texCoord");
  if (tc.Type() != tinygltf::NULL_TYPE) {
    if (!tc.IsInt() || tc.Get<int>() < 0) return Status::error(w + ".texCoord must be a non-negative integer");
    out->texCoord = tc.Get<int>();
  }
  // glTF's matrix: translation x rotation x scale, the rotation [cos sin; -sin cos] (counter-clockwise in UV).
  const double c = std::cos(r), s = std::sin(r);
  out->m[0] = c * sx;
  out->m[1] = s * sy;
  out->m[2] = ox;
  out->m[3] = -s * sx;
  out->m[4] = c * sy;
  out->m[5] = oy;
  out->identity = ox == 0 && oy == 0 && sx == 1 && sy == 1 && r == 0;
  return Status();
}

}  // namespace canopy
