// Scene files (readCanopyScene, parseCanopyScene; docs/scene-files.md): species, explicit copies
// and seeded scatters in JSON. The file is untrusted input like a glTF (docs/design.md "Errors and
// hostile input"): the nesting is measured before parsing, every key is known, every value checked
// for its type and range (finite numbers only), counts are capped before anything is allocated
// from them, and each refusal names the file and the JSON pointer of the offending value.
#include <canopy/canopy.h>

#include <sys/stat.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <initializer_list>
#include <map>
#include <string>

#include <glm/glm.hpp>
#include <glm/gtc/matrix_transform.hpp>
#include <nlohmann/json.hpp>

#include "engine/camera.h"
#include "engine/files.h"
#include "engine/status.h"
#include "render/gltf_json_checks.h"

namespace canopy {
namespace {
using nlohmann::json;

constexpr uint32_t kMaxDepth = 16;       // the format nests 4 deep
constexpr double kMaxCoordinate = 1e6;   // world units, each coordinate of a position or centre
constexpr double kMinScale = 0.001, kMaxScale = 1000.0;  // a float transform stays invertible
constexpr size_t kMaxNameLength = 64;
const char* const kGeneratedKinds[] = {"shrub", "tree", "grass", "kelp", "field"};

// A JSON pointer's reference token (RFC 6901: '~' and '/' escaped).
std::string token(const std::string& key) {
  std::string t;
  for (char c : key) t += c == '~' ? std::string("~0") : c == '/' ? std::string("~1") : std::string(1, c);
  return t;
}

// The value at `at` (a JSON pointer) read and checked; the first refusal is kept with its pointer.
class SceneReader {
 public:
  std::string pointer, problem;

  bool fail(const std::string& at, const std::string& what) {
    if (problem.empty()) {
      pointer = at.empty() ? "/" : at;
      problem = what;
    }
    return false;
  }
  // An object whose keys are all in `allowed`; `required` of them present.
  bool object(const json& o, const std::string& at, std::initializer_list<const char*> allowed,
              std::initializer_list<const char*> required = {}) {
    if (!o.is_object()) return fail(at, "expected an object, got " + typeOf(o));
    for (auto it = o.begin(); it != o.end(); ++it) {
      bool known = false;
      for (const char* k : allowed) known = known || it.key() == k;
      if (!known) {
        std::string keys;
        for (const char* k : allowed) keys += std::string(keys.empty() ? "" : ", ") + k;
        return fail(at + "/" + token(it.key()), "unknown key (expected one of: " + keys + ")");
      }
    }
    for (const char* k : required)
      if (!o.contains(k)) return fail(at + "/" + k, "missing (required)");
    return true;
  }
  // o[key] as a finite number in [lo, hi] ((lo, hi] when `openLow`); absent: *out is left alone.
  bool number(const json& o, const std::string& at, const char* key, double lo, double hi, bool openLow, double* out) {
    auto it = o.find(key);
    if (it == o.end()) return true;
    return value(*it, at + "/" + key, lo, hi, openLow, out);
  }
  bool value(const json& v, const std::string& at, double lo, double hi, bool openLow, double* out) {
    const std::string range = std::string(openLow ? "(" : "[") + num(lo) + ", " + num(hi) + "]";
    if (!v.is_number()) return fail(at, "expected a number in " + range + ", got " + typeOf(v));
    const double d = v.get<double>();
    if (!std::isfinite(d) || d < lo || d > hi || (openLow && d == lo))
      return fail(at, "expected a number in " + range + ", got " + v.dump());
    *out = d;
    return true;
  }
  // o[key] as an integer in [lo, hi].
  bool integer(const json& o, const std::string& at, const char* key, uint64_t lo, uint64_t hi, uint64_t* out) {
    auto it = o.find(key);
    if (it == o.end()) return true;
    const std::string where = at + "/" + key;
    const std::string range = "an integer in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]";
    uint64_t v = 0;
    if (it->is_number_unsigned()) v = it->get<uint64_t>();
    else if (it->is_number_integer() && it->get<int64_t>() >= 0) v = uint64_t(it->get<int64_t>());
    else return fail(where, "expected " + range + ", got " + it->dump());
    if (v < lo || v > hi) return fail(where, "expected " + range + ", got " + it->dump());
    *out = v;
    return true;
  }
  bool string(const json& o, const std::string& at, const char* key, size_t maxLength, std::string* out) {
    auto it = o.find(key);
    if (it == o.end()) return true;
    if (!it->is_string()) return fail(at + "/" + key, "expected a string, got " + typeOf(*it));
    const std::string s = it->get<std::string>();
    if (s.empty() || s.size() > maxLength)
      return fail(at + "/" + key, "expected 1.." + std::to_string(maxLength) + " characters, got " + std::to_string(s.size()));
    for (char c : s)
      if (c == '\0') return fail(at + "/" + key, "contains a NUL character");
    *out = s;
    return true;
  }
  // o[key] as `n` numbers, each in [lo, hi].
  bool numbers(const json& o, const std::string& at, const char* key, size_t n, double lo, double hi, bool openLow, double* out) {
    auto it = o.find(key);
    if (it == o.end()) return true;
    const std::string where = at + "/" + key;
    if (!it->is_array() || it->size() != n)
      return fail(where, "expected an array of " + std::to_string(n) + " numbers, got " + typeOf(*it) +
                             (it->is_array() ? " of " + std::to_string(it->size()) : ""));
    for (size_t i = 0; i < n; ++i)
      if (!value((*it)[i], where + "/" + std::to_string(i), lo, hi, openLow, &out[i])) return false;
    return true;
  }
  // An array at o[key] of at most `cap` elements (absent: empty).
  const json* array(const json& o, const std::string& at, const char* key, size_t cap) {
    auto it = o.find(key);
    if (it == o.end()) return nullptr;
    if (!it->is_array()) {
      fail(at + "/" + key, "expected an array, got " + typeOf(*it));
      return nullptr;
    }
    if (it->size() > cap) {
      fail(at + "/" + key, std::to_string(it->size()) + " entries, more than the cap of " + std::to_string(cap));
      return nullptr;
    }
    return &*it;
  }

 private:
  static std::string typeOf(const json& v) {
    if (v.is_array()) return "an array";
    if (v.is_object()) return "an object";
    if (v.is_string()) return "a string";
    if (v.is_boolean()) return "a boolean";
    if (v.is_null()) return "null";
    return "the number " + v.dump();
  }
  static std::string num(double d) {
    char b[32];
    std::snprintf(b, sizeof b, "%g", d);
    return b;
  }
};

// A copy's transform: translation, then the yaw about +Y (degrees), then a uniform scale.
CanopyInstance placed(const glm::dvec3& position, double yawDegrees, double scale, const glm::dvec3& tint, double windPhase) {
  glm::mat4 m = glm::translate(glm::mat4(1.0f), glm::vec3(position));
  m = glm::rotate(m, glm::radians(float(yawDegrees)), glm::vec3(0.0f, 1.0f, 0.0f));
  m = glm::scale(m, glm::vec3(float(scale)));
  CanopyInstance c;
  c.transform = toFloat4x4(m);
  c.tint = {float(tint.x), float(tint.y), float(tint.z)};
  c.windPhase = float(windPhase);
  return c;
}

// splitmix64: the scatter's numbers, the same on every machine for a seed.
struct Random {
  uint64_t state;
  double next() {
    uint64_t z = (state += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    z ^= z >> 31;
    return double(z >> 11) * (1.0 / 9007199254740992.0);  // [0, 1)
  }
};

bool readSpecies(SceneReader& r, const json& doc, const std::string& folder, CanopyScene* out, std::map<std::string, uint32_t>* index) {
  const json* list = r.array(doc, "", "species", kMaxSceneSpecies);
  if (!list) return r.problem.empty() ? r.fail("/species", "missing (required: at least one species)") : false;
  if (list->empty()) return r.fail("/species", "empty (at least one species)");
  out->species.reserve(list->size());
  for (size_t i = 0; i < list->size(); ++i) {
    const json& s = (*list)[i];
    const std::string at = "/species/" + std::to_string(i);
    if (!r.object(s, at, {"name", "gltf", "generated", "faces", "seed", "flexibility", "responseSpeed", "anchor"}, {"name"}))
      return false;
    CanopySceneSpecies sp;
    double flexibility = 1.0, speed = 1.0;
    uint64_t faces = 0, seed = 1;
    if (!r.string(s, at, "name", kMaxNameLength, &sp.name) || !r.string(s, at, "gltf", 4096, &sp.gltf) ||
        !r.string(s, at, "generated", kMaxNameLength, &sp.generated) || !r.integer(s, at, "faces", 2000, 200000000, &faces) ||
        !r.integer(s, at, "seed", 0, UINT32_MAX, &seed) || !r.number(s, at, "flexibility", 0.0, 4.0, false, &flexibility) ||
        !r.number(s, at, "responseSpeed", 0.25, 4.0, false, &speed))
      return false;
    std::string anchor = "file";
    if (!r.string(s, at, "anchor", kMaxNameLength, &anchor)) return false;
    if (anchor != "file" && anchor != "base") return r.fail(at + "/anchor", "expected \"file\" or \"base\", got '" + anchor + "'");
    sp.anchorBase = anchor == "base";
    if (sp.gltf.empty() == sp.generated.empty())
      return r.fail(at, "needs exactly one of \"gltf\" (a file) and \"generated\" (a generated plant)");
    if (!sp.gltf.empty() && (s.contains("faces") || s.contains("seed")))
      return r.fail(at + (s.contains("faces") ? "/faces" : "/seed"), "only a generated species has faces and a seed");
    if (!sp.generated.empty()) {
      bool known = false;
      for (const char* k : kGeneratedKinds) known = known || sp.generated == k;
      if (!known) return r.fail(at + "/generated", "unknown plant '" + sp.generated + "' (expected shrub, tree, grass, kelp or field)");
    }
    if (!sp.gltf.empty() && sp.gltf[0] != '/' && !folder.empty()) sp.gltf = folder + "/" + sp.gltf;
    sp.faces = faces;
    sp.seed = uint32_t(seed);
    sp.flexibility = float(flexibility);
    sp.responseSpeed = float(speed);
    if (!index->emplace(sp.name, uint32_t(i)).second) return r.fail(at + "/name", "'" + sp.name + "' names a species twice");
    out->species.push_back(std::move(sp));
  }
  return true;
}

// The species a copy names, by name.
bool speciesOf(SceneReader& r, const json& o, const std::string& at, const std::map<std::string, uint32_t>& index, uint32_t* out) {
  std::string name;
  if (!r.string(o, at, "species", kMaxNameLength, &name)) return false;
  auto it = index.find(name);
  if (it == index.end()) return r.fail(at + "/species", "'" + name + "' is not a species of this file");
  *out = it->second;
  return true;
}

bool readInstances(SceneReader& r, const json& doc, const std::map<std::string, uint32_t>& index, CanopyScene* out) {
  const json* list = r.array(doc, "", "instances", kMaxSceneInstances);
  if (!list) return r.problem.empty();
  out->instances.reserve(list->size());
  for (size_t i = 0; i < list->size(); ++i) {
    const json& o = (*list)[i];
    const std::string at = "/instances/" + std::to_string(i);
    if (!r.object(o, at, {"species", "position", "yawDegrees", "scale", "tint", "windPhase"}, {"species", "position"})) return false;
    CanopySceneInstance c;
    glm::dvec3 position(0.0), tint(1.0);
    double yaw = 0.0, scale = 1.0, phase = 0.0;
    if (!speciesOf(r, o, at, index, &c.species) || !r.numbers(o, at, "position", 3, -kMaxCoordinate, kMaxCoordinate, false, &position.x) ||
        !r.number(o, at, "yawDegrees", -3600.0, 3600.0, false, &yaw) || !r.number(o, at, "scale", kMinScale, kMaxScale, false, &scale) ||
        !r.numbers(o, at, "tint", 3, 0.0, 16.0, false, &tint.x) || !r.number(o, at, "windPhase", -3600.0, 3600.0, false, &phase))
      return false;
    c.placement = placed(position, yaw, scale, tint, phase);
    out->instances.push_back(c);
  }
  return true;
}

// Each scatter's copies, uniform over its disc (area), each turned by a random yaw and scaled by
// a random factor in its range; the seed fixes them.
bool readScatters(SceneReader& r, const json& doc, const std::map<std::string, uint32_t>& index, CanopyScene* out) {
  const json* list = r.array(doc, "", "scatter", kMaxSceneInstances);
  if (!list) return r.problem.empty();
  for (size_t i = 0; i < list->size(); ++i) {
    const json& o = (*list)[i];
    const std::string at = "/scatter/" + std::to_string(i);
    if (!r.object(o, at, {"species", "count", "center", "radius", "seed", "scale", "tint"}, {"species", "count", "radius"})) return false;
    uint32_t species = 0;
    uint64_t count = 0, seed = 1;
    glm::dvec3 center(0.0), tint(1.0);
    double radius = 0.0, scale[2] = {1.0, 1.0};
    if (!speciesOf(r, o, at, index, &species) || !r.integer(o, at, "count", 1, kMaxSceneInstances, &count) ||
        !r.numbers(o, at, "center", 3, -kMaxCoordinate, kMaxCoordinate, false, &center.x) ||
        !r.number(o, at, "radius", 0.0, kMaxCoordinate, true, &radius) || !r.integer(o, at, "seed", 0, UINT32_MAX, &seed) ||
        !r.numbers(o, at, "scale", 2, kMinScale, kMaxScale, false, scale) || !r.numbers(o, at, "tint", 3, 0.0, 16.0, false, &tint.x))
      return false;
    if (scale[0] > scale[1]) return r.fail(at + "/scale", "expected [low, high] with low <= high");
    // The cap holds for the whole file, checked before the copies are made.
    if (count > kMaxSceneInstances - out->instances.size())
      return r.fail(at + "/count", std::to_string(count) + " more copies after " + std::to_string(out->instances.size()) +
                                       " pass the file's cap of " + std::to_string(kMaxSceneInstances) + " instances");
    Random rng{seed * 0x2545F4914F6CDD1Dull + i};
    for (uint64_t k = 0; k < count; ++k) {
      const double angle = 2.0 * M_PI * rng.next(), dist = radius * std::sqrt(rng.next());
      const double yaw = 360.0 * rng.next(), s = scale[0] + (scale[1] - scale[0]) * rng.next();
      CanopySceneInstance c;
      c.species = species;
      c.placement = placed(center + glm::dvec3(dist * std::cos(angle), 0.0, dist * std::sin(angle)), yaw, s, tint, 0.0);
      out->instances.push_back(c);
    }
  }
  return true;
}

Status parse(const std::string& name, const std::string& text, const std::string& folder, CanopyScene* out) {
  const std::string file = "'" + name + "'";
  if (text.size() > kMaxSceneFileBytes)
    return Status::error(file + ": " + std::to_string(text.size()) + " bytes, more than the cap of " + std::to_string(kMaxSceneFileBytes));
  if (!checkJsonDepth(reinterpret_cast<const unsigned char*>(text.data()), text.size(), kMaxDepth).ok())
    return Status::error(file + ": the JSON nests deeper than " + std::to_string(kMaxDepth) + " levels (a scene file needs 4)");
  json doc;
  try {
    doc = json::parse(text);
  } catch (const json::exception& e) {
    return Status::error(file + ": not JSON: " + e.what());
  }
  SceneReader r;
  std::map<std::string, uint32_t> index;
  out->path = name;
  const bool ok = r.object(doc, "", {"species", "instances", "scatter"}, {"species"}) && readSpecies(r, doc, folder, out, &index) &&
                  readInstances(r, doc, index, out) && readScatters(r, doc, index, out);
  if (!ok) return Status::error(file + ": " + r.pointer + ": " + r.problem);
  if (out->instances.empty()) return Status::error(file + ": no instances and no scatter: the scene places nothing");
  return Status();
}

}  // namespace

Status parseCanopyScene(const std::string& name, const std::string& text, const std::string& folder, CanopyScene* out) {
  *out = CanopyScene{};
  const Status s = guardApi("parseCanopyScene", [&] { return parse(name, text, folder, out); });
  if (!s.ok()) *out = CanopyScene{};
  return s;
}

Status readCanopyScene(const std::string& path, CanopyScene* out) {
  *out = CanopyScene{};
  const Status s = guardApi("readCanopyScene", [&]() -> Status {
    std::vector<unsigned char> bytes;
    FileReadOptions o;
    o.maxBytes = kMaxSceneFileBytes;
    Status r = readWholeFile(path, o, &bytes);
    if (!r.ok()) return Status::error(r.code(), "'" + path + "': " + r.message());
    const size_t slash = path.find_last_of('/');
    const std::string folder = slash == std::string::npos ? "" : path.substr(0, slash);
    CANOPY_TRY(parse(path, std::string(reinterpret_cast<const char*>(bytes.data()), bytes.size()), folder, out));
    // Each glTF a regular file now (loadModel reads it later and names what is wrong inside).
    for (size_t i = 0; i < out->species.size(); ++i) {
      const std::string& g = out->species[i].gltf;
      if (g.empty()) continue;
      OpenedFile f;
      FileReadOptions fo;
      fo.maxBytes = UINT64_MAX;
      r = openFileForRead(g, fo, &f);
      if (!r.ok())
        return Status::error(Result::FileError, "'" + path + "': /species/" + std::to_string(i) + "/gltf: '" + g + "': " + r.message());
    }
    return Status();
  });
  if (!s.ok()) *out = CanopyScene{};
  return s;
}

Status sceneCopies(const CanopyScene& scene, const std::vector<Float3>& boundsMin, const std::vector<Float3>& boundsMax,
                   std::vector<CanopyInstance>* out) {
  out->clear();
  if (boundsMin.size() != scene.species.size() || boundsMax.size() != scene.species.size())
    return Status::error(Result::InvalidArgument, scene.path + ": " + std::to_string(boundsMin.size()) + " models for " +
                                                      std::to_string(scene.species.size()) + " species");
  out->reserve(scene.instances.size());
  for (const CanopySceneInstance& si : scene.instances) {
    if (si.species >= scene.species.size())
      return Status::error(Result::InvalidArgument, scene.path + ": a copy names species " + std::to_string(si.species));
    CanopyInstance c = si.placement;
    c.species = si.species;
    if (scene.species[si.species].anchorBase) {
      // The base's centre to the origin first: x and z the bounds' middle, y their bottom.
      const glm::vec3 lo = toGlm(boundsMin[si.species]), hi = toGlm(boundsMax[si.species]);
      const glm::vec3 base(0.5f * (lo.x + hi.x), lo.y, 0.5f * (lo.z + hi.z));
      c.transform = toFloat4x4(toGlm(c.transform) * glm::translate(glm::mat4(1.0f), -base));
    }
    out->push_back(c);
  }
  return Status();
}

}  // namespace canopy
