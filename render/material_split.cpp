#include "render/material_split.h"

#include <algorithm>
#include <cctype>

namespace canopy {
namespace {

std::string lower(std::string s) {
  for (char& c : s) c = char(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

bool containsAny(const std::string& name, std::initializer_list<const char*> words) {
  for (const char* w : words)
    if (name.find(w) != std::string::npos) return true;
  return false;
}

// Resolves one override entry to a material index.
Status resolve(const VegetationModel& m, const std::string& entry, uint32_t* index) {
  if (!entry.empty() && entry[0] == '#') {
    const std::string digits = entry.substr(1);
    if (digits.empty() || digits.size() > 9 || !std::all_of(digits.begin(), digits.end(), ::isdigit))
      return Status::error("material override '" + entry + "': expected #N with N a material index");
    const unsigned long v = std::stoul(digits);
    if (v >= m.materials.size())
      return Status::error("material override '" + entry + "': index out of range (the model has " +
                           std::to_string(m.materials.size()) + " materials, #0..#" +
                           std::to_string(m.materials.size() - 1) + ")");
    *index = uint32_t(v);
    return Status();
  }
  for (uint32_t i = 0; i < m.materials.size(); ++i)
    if (lower(m.materials[i].name) == lower(entry)) {
      *index = i;
      return Status();
    }
  std::string names;
  for (uint32_t i = 0; i < m.materials.size(); ++i)
    names.append(i ? ", '" : "'").append(m.materials[i].name).append("'");
  return Status::error("material override '" + entry + "' names no material of " + m.path + " (materials: " + names +
                       ")");
}

}  // namespace

Status splitMaterials(const VegetationModel& m, const MaterialSplitOptions& o, MaterialSplit* out) {
  *out = MaterialSplit{};
  const size_t n = m.materials.size();
  bool anyCutout = false;
  for (const ModelMaterial& mat : m.materials) anyCutout |= mat.alphaMode != AlphaMode::Opaque;
  out->role.resize(n);
  out->reason.resize(n);
  for (size_t i = 0; i < n; ++i) {
    const ModelMaterial& mat = m.materials[i];
    const std::string name = lower(mat.name);
    if (containsAny(name, {"bark", "trunk", "branch", "wood", "stem", "twig", "stalk"})) {
      out->role[i] = MaterialRole::Rigid;
      out->reason[i] = "name looks like bark/wood";
    } else if (containsAny(name, {"leaf", "leaves", "foliage", "needle", "grass", "frond", "flower", "petal",
                                  "blossom", "fern", "kelp", "moss"})) {
      out->role[i] = MaterialRole::Foliage;
      out->reason[i] = "name looks like leaves";
    } else if (mat.alphaMode != AlphaMode::Opaque) {
      out->role[i] = MaterialRole::Foliage;
      out->reason[i] = mat.alphaMode == AlphaMode::Mask ? "alphaMode MASK" : "alphaMode BLEND";
    } else if (anyCutout) {
      out->role[i] = MaterialRole::Rigid;
      out->reason[i] = "OPAQUE beside cut-out materials";
    } else {
      out->role[i] = MaterialRole::Foliage;
      out->reason[i] = "OPAQUE in an all-opaque model";
    }
  }
  // The roles rules (3) and (5) gave are hints: their materials are split part by part.
  std::vector<uint8_t> byParts(n, 0);
  for (size_t i = 0; i < n; ++i)
    byParts[i] = out->role[i] == MaterialRole::Foliage && (m.materials[i].alphaMode != AlphaMode::Opaque || !anyCutout) &&
                 out->reason[i] != "name looks like leaves";
  std::vector<int> forced(n, -1);
  for (int pass = 0; pass < 2; ++pass)
    for (const std::string& e : pass == 0 ? o.rigid : o.foliage) {
      uint32_t idx = 0;
      CANOPY_TRY(resolve(m, e, &idx));
      const int want = pass == 0 ? int(MaterialRole::Rigid) : int(MaterialRole::Foliage);
      if (forced[idx] != -1 && forced[idx] != want)
        return Status::error("material '" + m.materials[idx].name + "' (#" + std::to_string(idx) +
                             ") is listed as both rigid and foliage");
      forced[idx] = want;
      out->role[idx] = MaterialRole(want);
      out->reason[idx] = "user override";
      byParts[idx] = 0;
    }
  for (uint32_t mat : m.triangleMaterial)
    if (mat >= n) return Status::error(m.path + ": a triangle names material " + std::to_string(mat) + " of " + std::to_string(n));
  std::vector<uint8_t> materialFoliage(n);
  for (size_t i = 0; i < n; ++i) materialFoliage[i] = out->role[i] == MaterialRole::Foliage;
  CANOPY_TRY(splitParts(m, materialFoliage, byParts, &out->triangleFoliage, &out->parts));
  for (uint8_t f : out->triangleFoliage) (f ? out->foliageTriangles : out->rigidTriangles)++;
  return Status();
}

}  // namespace canopy
