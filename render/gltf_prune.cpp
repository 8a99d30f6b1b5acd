#include "render/gltf_prune.h"

#include <cctype>
#include <cstdlib>
#include <cstring>
#include <set>

#include <nlohmann/json.hpp>

namespace canopy {
namespace {

using nlohmann::json;

const json* child(const json& o, const char* key) {
  if (!o.is_object()) return nullptr;
  auto it = o.find(key);
  return it == o.end() ? nullptr : &*it;
}

// A non-negative integer below `size` (the JSON check bounded every index already; an index past
// its array is left to the loader, which names it).
bool indexIn(const json* v, size_t size, size_t* out) {
  if (!v || !v->is_number_integer()) return false;
  const int64_t i = v->get<int64_t>();
  if (i < 0 || uint64_t(i) >= size) return false;
  *out = size_t(i);
  return true;
}

size_t count(const json& doc, const char* key) {
  const json* a = child(doc, key);
  return a && a->is_array() ? a->size() : 0;
}

bool isTriangleMode(const json& primitive) {
  const json* mode = child(primitive, "mode");
  if (!mode) return true;  // glTF: 4, triangles
  if (!mode->is_number_integer()) return true;  // the loader names a bad mode
  const int64_t m = mode->get<int64_t>();
  return m == 4 || m == 5 || m == 6;
}

const char* modeName(int64_t m) {
  switch (m) {
    case 0: return "points";
    case 1: return "lines";
    case 2: return "a line loop";
    case 3: return "a line strip";
  }
  return "not a triangle primitive";
}

// RFC 2397: data:[<mediatype>][;base64],<data>. The payload's bytes: base64 decoded, or the
// percent-encoded text as it stands. False: not a data URI Canopy can read.
bool decodeDataUri(const std::string& uri, std::vector<unsigned char>* out, bool* wasBase64) {
  const size_t comma = uri.find(',');
  if (uri.compare(0, 5, "data:") != 0 || comma == std::string::npos) return false;
  const std::string meta = uri.substr(5, comma - 5);
  *wasBase64 = meta.size() >= 7 && meta.compare(meta.size() - 7, 7, ";base64") == 0;
  const std::string payload = uri.substr(comma + 1);
  out->clear();
  if (*wasBase64) {  // tinygltf decodes these itself: only the alphabet and the length are checked here
    size_t n = 0;
    for (char ch : payload) {
      if (std::isalnum(static_cast<unsigned char>(ch)) || ch == '+' || ch == '/' || ch == '=') ++n;
      else if (!std::isspace(static_cast<unsigned char>(ch))) return false;
    }
    return n % 4 == 0;
  }
  for (size_t i = 0; i < payload.size(); ++i) {
    if (payload[i] == '%') {
      if (i + 2 >= payload.size()) return false;
      const std::string hex = payload.substr(i + 1, 2);
      char* end = nullptr;
      const long v = std::strtol(hex.c_str(), &end, 16);
      if (!end || *end) return false;
      out->push_back(uint8_t(v));
      i += 2;
    } else {
      out->push_back(uint8_t(payload[i]));
    }
  }
  return true;
}

std::string base64(const std::vector<unsigned char>& b) {
  static const char* k = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string s;
  s.reserve((b.size() + 2) / 3 * 4);
  for (size_t i = 0; i < b.size(); i += 3) {
    const uint32_t v = uint32_t(b[i]) << 16 | (i + 1 < b.size() ? uint32_t(b[i + 1]) << 8 : 0) | (i + 2 < b.size() ? b[i + 2] : 0);
    s += k[(v >> 18) & 63];
    s += k[(v >> 12) & 63];
    s += i + 1 < b.size() ? k[(v >> 6) & 63] : '=';
    s += i + 2 < b.size() ? k[v & 63] : '=';
  }
  return s;
}

// A URI with a scheme other than data: (http:, https:, file:, ...): never fetched.
bool isRemote(const std::string& uri) {
  const size_t colon = uri.find(':');
  if (colon == std::string::npos || colon < 2) return false;  // "C:" is a drive, refused as absolute later
  for (size_t i = 0; i < colon; ++i)
    if (!std::isalnum(static_cast<unsigned char>(uri[i])) && uri[i] != '+' && uri[i] != '-' && uri[i] != '.') return false;
  return uri.compare(0, 5, "data:") != 0;
}

// The textures a material names: every "index" of an object under a key ending in "Texture"
// (pbrMetallicRoughness.baseColorTexture, normalTexture, the extensions' textures).
void materialTextures(const json& v, const std::string& key, std::set<size_t>* out, size_t textures) {
  if (v.is_object()) {
    if (key.size() >= 7 && key.compare(key.size() - 7, 7, "Texture") == 0) {
      size_t t;
      if (indexIn(child(v, "index"), textures, &t)) out->insert(t);
    }
    for (auto it = v.begin(); it != v.end(); ++it) materialTextures(*it, it.key(), out, textures);
  } else if (v.is_array()) {
    for (const json& e : v) materialTextures(e, key, out, textures);
  }
}

// The images no drawn material reads become a one-byte stub (kept encoded, never decoded); a read
// image's data: URI is checked (RFC 2397) and made base64 for tinygltf.
Status keepReadImages(json& doc, const std::set<size_t>& imageUsed) {
  const size_t images = count(doc, "images");
  for (size_t i = 0; i < images; ++i) {
    json& im = doc["images"][i];
    if (!imageUsed.count(i)) {
      im = json{{"uri", "data:image/png;base64,AA=="}};
      continue;
    }
    const json* uri = child(im, "uri");
    if (!uri || !uri->is_string()) continue;  // a bufferView image, or tinygltf names what is missing
    const std::string u = uri->get<std::string>();
    if (u.compare(0, 5, "data:") != 0) continue;
    std::vector<unsigned char> bytes;
    bool wasBase64 = false;
    if (!decodeDataUri(u, &bytes, &wasBase64))
      return Status::error("images[" + std::to_string(i) + "]: the data: URI is not data:[<mediatype>][;base64],<data> (RFC 2397)");
    if (!wasBase64) im["uri"] = "data:image/png;base64," + base64(bytes);
  }
  return Status();
}

// The buffers the model reads checked (Canopy's messages), their data: URIs made base64 for
// tinygltf; the others a one-byte stub.
Status keepReadBuffers(json& doc, bool glb, uint64_t binBytes, const std::vector<bool>& bufferUsed) {
  const size_t buffers = bufferUsed.size();
  for (size_t b = 0; b < buffers; ++b) {
    json& buf = doc["buffers"][b];
    const std::string what = "buffers[" + std::to_string(b) + "]";
    if (!bufferUsed[b]) {
      buf = json{{"byteLength", 1}, {"uri", "data:application/octet-stream;base64,AA=="}};
      continue;
    }
    const json* uri = child(buf, "uri");
    const json* len = child(buf, "byteLength");
    const uint64_t declared = len && len->is_number_unsigned() ? len->get<uint64_t>() : 0;
    if (!uri) {
      if (!glb)
        return Status::error(what + " has no 'uri': in a .gltf every buffer the model reads names its data (a file or a data: URI)");
      if (b != 0) return Status::error(what + " has no 'uri': only a .glb's first buffer is its BIN chunk");
      if (binBytes == 0) return Status::error(what + " has no 'uri' and the .glb has no BIN chunk");
      if (declared > binBytes)
        return Status::error(what + ": byteLength " + std::to_string(declared) + " is more than the .glb's BIN chunk (" +
                             std::to_string(binBytes) + " bytes)");
      continue;
    }
    if (!uri->is_string()) return Status::error(what + ": 'uri' is not a string");
    const std::string u = uri->get<std::string>();
    if (u.empty()) return Status::error(what + ": 'uri' is empty");
    if (u.compare(0, 5, "data:") == 0) {
      std::vector<unsigned char> bytes;
      bool wasBase64 = false;
      if (!decodeDataUri(u, &bytes, &wasBase64))
        return Status::error(what + ": the data: URI is not data:[<mediatype>][;base64],<data> (RFC 2397)");
      if (wasBase64) {
        // tinygltf reads base64 only under the octet-stream and gltf-buffer media types.
        buf["uri"] = "data:application/octet-stream;base64," + u.substr(u.find(',') + 1);
      } else {
        if (bytes.size() < declared)
          return Status::error(what + ": the data: URI holds " + std::to_string(bytes.size()) + " bytes, byteLength says " +
                               std::to_string(declared));
        buf["uri"] = "data:application/octet-stream;base64," + base64(bytes);
      }
      continue;
    }
    if (isRemote(u))
      return Status::error(what + ": uri '" + u + "' is remote; Canopy reads only files beside the model and never fetches one");
  }
  return Status();
}

}  // namespace

Status keepReadParts(json& doc, bool glb, uint64_t binBytes, GltfReadParts* out) {
  if (!doc.is_object()) return Status();  // tinygltf names what is wrong with the document
  const size_t nodes = count(doc, "nodes"), meshes = count(doc, "meshes"), accessors = count(doc, "accessors"),
               views = count(doc, "bufferViews"), buffers = count(doc, "buffers"), materials = count(doc, "materials"),
               textures = count(doc, "textures"), images = count(doc, "images");
  // The scene's nodes, as the loader walks them (render/gltf_loader.cpp sceneRoots).
  std::vector<size_t> stack;
  if (count(doc, "scenes") > 0) {
    size_t sc = 0;
    if (const json* s = child(doc, "scene"); s && !indexIn(s, count(doc, "scenes"), &sc)) return Status();  // the loader refuses it
    if (const json* roots = child(doc["scenes"][sc], "nodes"); roots && roots->is_array())
      for (const json& r : *roots) {
        size_t n;
        if (indexIn(&r, nodes, &n)) stack.push_back(n);
      }
  } else {
    std::vector<bool> isChild(nodes, false);
    for (size_t i = 0; i < nodes; ++i)
      if (const json* c = child(doc["nodes"][i], "children"); c && c->is_array())
        for (const json& e : *c) {
          size_t n;
          if (indexIn(&e, nodes, &n)) isChild[n] = true;
        }
    for (size_t i = 0; i < nodes; ++i)
      if (!isChild[i]) stack.push_back(i);
  }
  std::vector<const json*> dracoViews;
  std::vector<bool> nodeSeen(nodes, false), meshUsed(meshes, false), accessorUsed(accessors, false), viewUsed(views, false),
      bufferUsed(buffers, false), materialUsed(materials, false);
  auto useAccessor = [&](const json* v) {
    size_t a;
    if (indexIn(v, accessors, &a)) accessorUsed[a] = true;
  };
  while (!stack.empty()) {
    const size_t n = stack.back();
    stack.pop_back();
    if (nodeSeen[n]) continue;  // the loader refuses a node reached twice
    nodeSeen[n] = true;
    const json& node = doc["nodes"][n];
    size_t mesh;
    if (indexIn(child(node, "mesh"), meshes, &mesh)) {
      meshUsed[mesh] = true;
      const json* ext = child(node, "extensions");
      const json* inst = ext ? child(*ext, "EXT_mesh_gpu_instancing") : nullptr;
      if (const json* attrs = inst ? child(*inst, "attributes") : nullptr; attrs && attrs->is_object())
        for (auto it = attrs->begin(); it != attrs->end(); ++it) useAccessor(&*it);
    }
    if (const json* c = child(node, "children"); c && c->is_array())
      for (const json& e : *c) {
        size_t k;
        if (indexIn(&e, nodes, &k)) stack.push_back(k);
      }
  }
  // The meshes' primitives: triangles are read; points and lines are left out with a warning;
  // a mesh no node shows keeps no primitive (glTF: not displayed).
  for (size_t mi = 0; mi < meshes; ++mi) {
    json& mesh = doc["meshes"][mi];
    json* prims = mesh.is_object() && mesh.contains("primitives") ? &mesh["primitives"] : nullptr;
    if (!prims || !prims->is_array()) continue;
    if (!meshUsed[mi]) {
      *prims = json::array();
      continue;
    }
    for (size_t pi = 0; pi < prims->size(); ++pi) {
      json& pr = (*prims)[pi];
      if (!pr.is_object()) continue;
      const std::string where = "meshes[" + std::to_string(mi) + "].primitives[" + std::to_string(pi) + "]";
      if (!isTriangleMode(pr)) {
        const int64_t m = pr["mode"].get<int64_t>();
        out->warnings.push_back(where + ": mode " + std::to_string(m) + " (" + modeName(m) + ") is not drawn as triangles (skipped)");
        const json mode = pr["mode"];
        pr = json{{"attributes", json::object()}, {"mode", mode}};
        continue;
      }
      pr.erase("targets");  // morph targets: not read
      // KHR_draco_mesh_compression: its accessors have no bufferView until the loader decodes the
      // extension's (render/gltf_compressed.h), indices included.
      const json* prExt = child(pr, "extensions");
      const json* draco = prExt ? child(*prExt, "KHR_draco_mesh_compression") : nullptr;
      if (draco) dracoViews.push_back(child(*draco, "bufferView"));
      if (const json* attrs = child(pr, "attributes"); attrs && attrs->is_object())
        for (const char* a : {"POSITION", "NORMAL", "TEXCOORD_0"}) useAccessor(child(*attrs, a));
      size_t mat;
      if (indexIn(child(pr, "material"), materials, &mat)) materialUsed[mat] = true;
      size_t ia;
      if (indexIn(child(pr, "indices"), accessors, &ia)) {
        accessorUsed[ia] = true;
        if (draco && !child(doc["accessors"][ia], "bufferView")) {  // decoded by the loader
          out->dracoIndices[{int(mi), int(pi)}] = int(ia);
          pr.erase("indices");
        } else if (!child(doc["accessors"][ia], "bufferView")) {  // zeros (and a sparse part): read by the loader
          out->indicesWithoutView[{int(mi), int(pi)}] = int(ia);
          pr.erase("indices");
        }
      }
    }
  }
  // Materials -> textures -> images.
  std::set<size_t> textureUsed, imageUsed;
  for (size_t i = 0; i < materials; ++i)
    if (materialUsed[i]) materialTextures(doc["materials"][i], "", &textureUsed, textures);
  for (size_t t : textureUsed) {
    size_t img;
    if (indexIn(child(doc["textures"][t], "source"), images, &img)) imageUsed.insert(img);
    const json* ext = child(doc["textures"][t], "extensions");
    if (const json* webp = ext ? child(*ext, "EXT_texture_webp") : nullptr; webp && indexIn(child(*webp, "source"), images, &img))
      imageUsed.insert(img);
  }
  auto useView = [&](const json* v) {
    size_t b;
    if (indexIn(v, views, &b)) viewUsed[b] = true;
  };
  for (size_t img : imageUsed) useView(child(doc["images"][img], "bufferView"));
  for (const json* v : dracoViews) useView(v);
  CANOPY_TRY(keepReadImages(doc, imageUsed));
  // Accessors -> bufferViews -> buffers; the others become a stub tinygltf parses and nothing reads.
  for (size_t a = 0; a < accessors; ++a) {
    json& acc = doc["accessors"][a];
    if (!accessorUsed[a]) {
      acc = json{{"componentType", 5126}, {"count", 1}, {"type", "SCALAR"}};
      continue;
    }
    useView(child(acc, "bufferView"));
    if (const json* sp = child(acc, "sparse"))
      for (const char* part : {"indices", "values"})
        if (const json* x = child(*sp, part)) useView(child(*x, "bufferView"));
  }
  for (size_t v = 0; v < views; ++v) {
    size_t b;
    if (viewUsed[v] && indexIn(child(doc["bufferViews"][v], "buffer"), buffers, &b)) bufferUsed[b] = true;
  }
  doc.erase("animations");  // they and skins name accessors; the vegetation reads neither
  doc.erase("skins");
  return keepReadBuffers(doc, glb, binBytes, bufferUsed);
}

}  // namespace canopy
