#include "render/gltf_json_checks.h"

#include <cstring>
#include <string>

#include <nlohmann/json.hpp>

namespace canopy {
namespace {

// tinygltf reads indices, counts and offsets into int and size_t without a range check: 2^64-4
// becomes the index -4 (read as "no bufferView": silent zeros) and an image's bufferView offset
// past its buffer becomes an out-of-range pointer. Every such field Canopy depends on is checked
// on the JSON first: a non-negative integer in its range, and an image's bufferView inside the
// byteLength its buffer declares (which tinygltf then enforces on the loaded bytes).
class JsonCheck {
 public:
  Status run(nlohmann::json& doc) {
    if (!doc.is_object()) return Status();  // tinygltf reports what is wrong with the document
    const int64_t kIndex = 0x7fffffff;
    const int64_t kSize = int64_t(1) << 53;  // exact in a double; far beyond any file
    each(doc, "accessors", [&](const nlohmann::json& a) {
      field(a, "bufferView", kIndex);
      field(a, "byteOffset", kSize);
      field(a, "count", kSize, 1);
      field(a, "componentType", kIndex);
      if (const nlohmann::json* sp = child(a, "sparse")) {
        path_.push_back(".sparse");
        field(*sp, "count", kIndex, 1);
        for (const char* part : {"indices", "values"})
          if (const nlohmann::json* x = child(*sp, part)) {
            path_.push_back(std::string(".") + part);
            field(*x, "bufferView", kIndex);
            field(*x, "byteOffset", kSize);
            field(*x, "componentType", kIndex);
            path_.pop_back();
          }
        path_.pop_back();
      }
    });
    each(doc, "bufferViews", [&](const nlohmann::json& v) {
      field(v, "buffer", kIndex);
      field(v, "byteOffset", kSize);
      field(v, "byteLength", kSize, 1);
      field(v, "byteStride", 252, 4);
    });
    each(doc, "buffers", [&](const nlohmann::json& b) { field(b, "byteLength", kSize, 1); });
    each(doc, "images", [&](const nlohmann::json& im) { field(im, "bufferView", kIndex); });
    each(doc, "textures", [&](const nlohmann::json& t) {
      field(t, "source", kIndex);
      field(t, "sampler", kIndex);
    });
    each(doc, "materials", [&](const nlohmann::json& m) {
      const nlohmann::json* pbr = child(m, "pbrMetallicRoughness");
      const nlohmann::json* tex = pbr ? child(*pbr, "baseColorTexture") : nullptr;
      if (tex) {
        path_.push_back(".pbrMetallicRoughness.baseColorTexture");
        field(*tex, "index", kIndex);
        field(*tex, "texCoord", kIndex);
        path_.pop_back();
      }
    });
    each(doc, "meshes", [&](const nlohmann::json& mesh) {
      const nlohmann::json* prims = child(mesh, "primitives");
      if (!prims || !prims->is_array()) return;
      for (size_t j = 0; j < prims->size(); ++j) {
        path_.push_back(".primitives[" + std::to_string(j) + "]");
        const nlohmann::json& pr = (*prims)[j];
        field(pr, "indices", kIndex);
        field(pr, "material", kIndex);
        field(pr, "mode", 6);
        if (const nlohmann::json* attrs = child(pr, "attributes"); attrs && attrs->is_object())
          for (auto it = attrs->begin(); it != attrs->end(); ++it) field(*attrs, it.key().c_str(), kIndex);
        path_.pop_back();
      }
    });
    each(doc, "nodes", [&](const nlohmann::json& n) {
      field(n, "mesh", kIndex);
      elements(n, "children", kIndex);
      // EXT_mesh_gpu_instancing's attributes are accessor indices like a primitive's.
      const nlohmann::json* ext = child(n, "extensions");
      const nlohmann::json* inst = ext ? child(*ext, "EXT_mesh_gpu_instancing") : nullptr;
      if (const nlohmann::json* attrs = inst ? child(*inst, "attributes") : nullptr; attrs && attrs->is_object()) {
        path_.push_back(".extensions.EXT_mesh_gpu_instancing.attributes");
        for (auto it = attrs->begin(); it != attrs->end(); ++it) field(*attrs, it.key().c_str(), kIndex);
        path_.pop_back();
      }
    });
    each(doc, "scenes", [&](const nlohmann::json& sc) { elements(sc, "nodes", kIndex); });
    field(doc, "scene", kIndex);
    if (!error_.empty()) return Status::error(error_);
    // An image's bytes inside the byteLength its buffer declares.
    const nlohmann::json* images = child(doc, "images");
    const nlohmann::json* views = child(doc, "bufferViews");
    const nlohmann::json* buffers = child(doc, "buffers");
    if (images && images->is_array() && views && views->is_array() && buffers && buffers->is_array())
      for (size_t i = 0; i < images->size(); ++i) {
        const nlohmann::json* bv = child((*images)[i], "bufferView");
        if (!bv || bv->get<int64_t>() >= int64_t(views->size())) continue;  // tinygltf names a missing view
        const nlohmann::json& view = (*views)[size_t(bv->get<int64_t>())];
        const nlohmann::json* b = child(view, "buffer");
        if (!b || b->get<int64_t>() >= int64_t(buffers->size())) continue;
        const nlohmann::json* declared = child((*buffers)[size_t(b->get<int64_t>())], "byteLength");
        const nlohmann::json* off = child(view, "byteOffset");
        const nlohmann::json* len = child(view, "byteLength");
        const uint64_t o = off ? off->get<uint64_t>() : 0, l = len ? len->get<uint64_t>() : 0;
        const uint64_t size = declared ? declared->get<uint64_t>() : 0;
        if (!rangeFits(o, l, size))
          return Status::error("images[" + std::to_string(i) + "]: bufferViews[" + std::to_string(bv->get<int64_t>()) +
                               "] (byteOffset " + std::to_string(o) + ", byteLength " + std::to_string(l) +
                               ") does not fit the " + std::to_string(size) + " bytes its buffer declares");
      }
    return Status();
  }

 private:
  static const nlohmann::json* child(const nlohmann::json& o, const char* key) {
    if (!o.is_object()) return nullptr;
    auto it = o.find(key);
    return it == o.end() ? nullptr : &*it;
  }
  template <class F>
  void each(const nlohmann::json& doc, const char* key, F&& f) {
    const nlohmann::json* arr = child(doc, key);
    if (!arr || !arr->is_array()) return;
    for (size_t i = 0; i < arr->size() && error_.empty(); ++i) {
      path_ = {std::string(key) + "[" + std::to_string(i) + "]"};
      f((*arr)[i]);
    }
    path_.clear();
  }
  std::string where(const char* key) const {
    std::string p;
    for (const std::string& s : path_) p += s;
    return p.empty() ? key : p + "." + key;
  }
  bool check(const nlohmann::json& v, const std::string& name, int64_t hi, int64_t lo) {
    if (!error_.empty()) return false;
    bool ok = false;
    if (v.is_number_unsigned()) ok = v.get<uint64_t>() <= uint64_t(hi) && int64_t(v.get<uint64_t>()) >= lo;
    else if (v.is_number_integer()) ok = v.get<int64_t>() >= lo && v.get<int64_t>() <= hi;
    else if (v.is_number_float()) {
      const double d = v.get<double>();
      ok = std::isfinite(d) && d == std::floor(d) && d >= double(lo) && d <= double(hi);
      // JSON has one number type: 1.0 and 1e0 are the integer 1 (the glTF validator's
      // integer_written_as_float), which tinygltf refuses. Written back as an integer in the
      // caller's own (mutable) document.
      if (ok) const_cast<nlohmann::json&>(v) = int64_t(d);
    }
    if (!ok)
      error_ = name + " = " + v.dump() + " is not an integer in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]";
    return ok;
  }
  void field(const nlohmann::json& o, const char* key, int64_t hi, int64_t lo = 0) {
    if (const nlohmann::json* v = child(o, key)) check(*v, where(key), hi, lo);
  }
  void elements(const nlohmann::json& o, const char* key, int64_t hi) {
    const nlohmann::json* arr = child(o, key);
    if (!arr || !arr->is_array()) return;
    for (size_t i = 0; i < arr->size() && error_.empty(); ++i)
      check((*arr)[i], where(key) + "[" + std::to_string(i) + "]", hi, 0);
  }
  std::vector<std::string> path_;
  std::string error_;
};

}  // namespace

// GLB framing checked before tinygltf sees it: header, chunk lengths inside the file.
Status checkGlb(const std::vector<unsigned char>& d) {
  auto u32 = [&](size_t o) { uint32_t v; std::memcpy(&v, d.data() + o, 4); return v; };
  if (d.size() < 20) return Status::error("GLB: " + std::to_string(d.size()) + " bytes, shorter than a header and one chunk");
  if (u32(4) != 2) return Status::error("GLB: version " + std::to_string(u32(4)) + " (only 2 is supported)");
  if (u32(8) > d.size()) return Status::error("GLB: header length " + std::to_string(u32(8)) + " exceeds the file's " + std::to_string(d.size()) + " bytes (truncated)");
  if (u32(8) < 20) return Status::error("GLB: header length " + std::to_string(u32(8)) + " is too small");
  const uint64_t total = u32(8);
  uint64_t off = 12;
  int chunk = 0, binChunks = 0;
  while (off < total) {
    if (off + 8 > total) return Status::error("GLB: chunk " + std::to_string(chunk) + " header is truncated");
    const uint64_t len = u32(size_t(off)), type = u32(size_t(off + 4));
    if (off + 8 + len > total)
      return Status::error("GLB: chunk " + std::to_string(chunk) + " of " + std::to_string(len) + " bytes runs past the end of the file (truncated)");
    if (len % 4 != 0) return Status::error("GLB: chunk " + std::to_string(chunk) + " length " + std::to_string(len) + " is not a multiple of 4");
    if (chunk == 0 && type != 0x4E4F534Au) return Status::error("GLB: the first chunk is not JSON");
    if (chunk > 0 && type == 0x4E4F534Au) return Status::error("GLB: chunk " + std::to_string(chunk) + " is a second JSON chunk");
    if (type == 0x004E4942u && ++binChunks > 1) return Status::error("GLB: chunk " + std::to_string(chunk) + " is a second BIN chunk");
    off += 8 + len;
    ++chunk;
  }
  return Status();
}

// tinygltf converts `extras` and `extensions` into its Value type recursively: a file nested
// thousands deep overflows the stack. The nesting is measured on the bytes first (strings and
// their escapes skipped), without recursion.
Status checkJsonDepth(const unsigned char* p, size_t n, uint32_t maxDepth) {
  uint64_t depth = 0;
  bool inString = false;
  for (size_t i = 0; i < n; ++i) {
    const unsigned char c = p[i];
    if (inString) {
      if (c == '\\') ++i;
      else if (c == '"') inString = false;
    } else if (c == '"') {
      inString = true;
    } else if (c == '[' || c == '{') {
      if (++depth > maxDepth)
        return Status::error("JSON nesting deeper than " + std::to_string(maxDepth) + " levels at byte " + std::to_string(i) +
                             " (GltfLoadOptions.maxJsonDepth)");
    } else if ((c == ']' || c == '}') && depth > 0) {
      --depth;
    }
  }
  return Status();
}


Status checkGltfJsonFields(nlohmann::json& doc) { return JsonCheck().run(doc); }

}  // namespace canopy
