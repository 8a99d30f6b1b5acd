#include "render/part_split.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <unordered_map>

#include "render/plants.h"

namespace canopy {
namespace {

uint32_t findRoot(std::vector<uint32_t>& parent, uint32_t x) {
  while (parent[x] != x) x = parent[x] = parent[parent[x]];
  return x;
}

// The eigenvalues of a symmetric 3 x 3 matrix, largest first (the trigonometric closed form).
glm::vec3 eigenvalues(const glm::dmat3& a) {
  const double p1 = a[0][1] * a[0][1] + a[0][2] * a[0][2] + a[1][2] * a[1][2];
  const double q = (a[0][0] + a[1][1] + a[2][2]) / 3.0;
  if (p1 <= 1e-30 * std::max(1.0, q * q)) {
    float e[3] = {float(a[0][0]), float(a[1][1]), float(a[2][2])};
    std::sort(e, e + 3, std::greater<float>());
    return glm::vec3(e[0], e[1], e[2]);
  }
  const double p2 = (a[0][0] - q) * (a[0][0] - q) + (a[1][1] - q) * (a[1][1] - q) + (a[2][2] - q) * (a[2][2] - q) + 2.0 * p1;
  const double p = std::sqrt(p2 / 6.0);
  const glm::dmat3 b = (a - q * glm::dmat3(1.0)) * (1.0 / p);
  const double r = std::clamp(glm::determinant(b) / 2.0, -1.0, 1.0);
  const double phi = std::acos(r) / 3.0;
  const double e1 = q + 2.0 * p * std::cos(phi), e3 = q + 2.0 * p * std::cos(phi + 2.0943951023931953);
  return glm::vec3(float(e1), float(3.0 * q - e1 - e3), float(e3));
}

float srgbToLinear(float c) { return c <= 0.04045f ? c / 12.92f : std::pow((c + 0.055f) / 1.055f, 2.4f); }

// One part's accumulated features.
struct Part {
  uint32_t material = 0, triangles = 0;
  double n = 0;
  glm::dvec3 sum{0.0};
  glm::dmat3 outer{0.0};
  float minY = INFINITY;
  float footY = 0.0f, height = 0.0f;  // its plant's lowest point and height (render/plants.h)
  glm::dvec3 colour{0.0};  // linear, summed over samples
  double samples = 0, cutout = 0;
};

}  // namespace

Status splitParts(const VegetationModel& m, const std::vector<uint8_t>& materialFoliage, const std::vector<uint8_t>& byParts,
                  std::vector<uint8_t>* out, std::vector<PartReport>* reports) {
  const size_t nt = m.triangleCount(), nv = m.positions.size(), nm = m.materials.size();
  if (materialFoliage.size() != nm || byParts.size() != nm || m.triangleMaterial.size() != nt)
    return Status::error("part split: per-material or per-triangle arrays disagree with the model");
  out->assign(nt, 0);
  reports->clear();
  bool any = false;
  for (size_t t = 0; t < nt; ++t) {
    const uint32_t mat = m.triangleMaterial[t];
    (*out)[t] = materialFoliage[mat];
    any = any || byParts[mat];
  }
  if (!any) return Status();
  PlantGroups groups;
  CANOPY_TRY(groupPlants(m, &groups));
  // Parts: connected triangles of one classified material, through shared indices and equal positions.
  std::vector<uint32_t> parent(nv);
  for (size_t v = 0; v < nv; ++v) parent[v] = uint32_t(v);
  std::vector<int32_t> vertexMaterial(nv, -1);
  auto unite = [&](uint32_t a, uint32_t b) {
    a = findRoot(parent, a);
    b = findRoot(parent, b);
    if (a != b) parent[std::max(a, b)] = std::min(a, b);
  };
  for (size_t t = 0; t < nt; ++t) {
    const uint32_t mat = m.triangleMaterial[t];
    if (!byParts[mat]) continue;
    const uint32_t* tri = &m.indices[3 * t];
    for (int k = 0; k < 3; ++k) vertexMaterial[tri[k]] = int32_t(mat);
    unite(tri[0], tri[1]);
    unite(tri[1], tri[2]);
  }
  {
    // Equal positions of the same material weld (exporters split vertices along UV seams).
    std::unordered_map<std::string, uint32_t> seen;
    seen.reserve(nv);
    std::string key(sizeof(glm::vec3) + sizeof(int32_t), '\0');
    for (size_t v = 0; v < nv; ++v) {
      if (vertexMaterial[v] < 0) continue;
      std::memcpy(&key[0], &m.positions[v], sizeof(glm::vec3));
      std::memcpy(&key[sizeof(glm::vec3)], &vertexMaterial[v], sizeof(int32_t));
      const auto [it, inserted] = seen.emplace(key, uint32_t(v));
      if (!inserted) unite(uint32_t(v), it->second);
    }
  }
  std::unordered_map<uint32_t, Part> parts;
  std::vector<uint32_t> stamp(nv, 0xffffffffu);
  auto sample = [&](const ModelMaterial& mat, glm::vec2 uv, Part& p) {
    glm::vec4 c = mat.baseColorFactor;
    if (mat.baseColorImage >= 0 && size_t(mat.baseColorImage) < m.images.size()) {
      const ModelImage& img = m.images[size_t(mat.baseColorImage)];
      if (img.width && img.height && img.rgba.size() >= size_t(img.width) * img.height * 4) {
        const float u = uv.x - std::floor(uv.x), v = uv.y - std::floor(uv.y);
        const size_t x = std::min<size_t>(img.width - 1, size_t(u * float(img.width)));
        const size_t y = std::min<size_t>(img.height - 1, size_t(v * float(img.height)));
        const uint8_t* px = &img.rgba[(y * img.width + x) * 4];
        c *= glm::vec4(srgbToLinear(px[0] / 255.0f), srgbToLinear(px[1] / 255.0f), srgbToLinear(px[2] / 255.0f), px[3] / 255.0f);
      }
    }
    p.colour += glm::dvec3(c);
    p.samples += 1;
    const float cutoff = mat.alphaMode == AlphaMode::Mask ? mat.alphaCutoff : mat.alphaMode == AlphaMode::Blend ? 0.5f : -1.0f;
    p.cutout += c.a < cutoff;
  };
  for (size_t t = 0; t < nt; ++t) {
    const uint32_t mat = m.triangleMaterial[t];
    if (!byParts[mat]) continue;
    const uint32_t* tri = &m.indices[3 * t];
    const uint32_t id = findRoot(parent, tri[0]);
    Part& p = parts[id];
    if (p.triangles == 0) {  // its plant: the group of its first triangle, the whole model's if none
      const uint32_t g = t < groups.triangle.size() ? groups.triangle[t] : kNoPlant;
      const bool own = g != kNoPlant && groups.lo[g].y <= groups.hi[g].y;
      p.footY = own ? groups.lo[g].y : m.boundsMin.y;
      p.height = std::max(own ? groups.hi[g].y - groups.lo[g].y : m.boundsMax.y - m.boundsMin.y, 1e-12f);
    }
    p.material = mat;
    p.triangles++;
    glm::vec2 mid(0.0f);
    for (int k = 0; k < 3; ++k) {
      const uint32_t v = tri[k];
      mid += m.uvs[v] / 3.0f;
      sample(m.materials[mat], m.uvs[v], p);
      if (stamp[v] == id) continue;
      stamp[v] = id;
      const glm::dvec3 x(m.positions[v]);
      p.n += 1;
      p.sum += x;
      p.outer += glm::outerProduct(x, x);
      p.minY = std::min(p.minY, m.positions[v].y);
    }
    sample(m.materials[mat], mid, p);
  }
  std::unordered_map<uint32_t, uint8_t> rigidPart;
  for (auto& [id, p] : parts) {
    const glm::dvec3 mean = p.sum / std::max(p.n, 1.0);
    const glm::vec3 e = eigenvalues(p.outer / std::max(p.n, 1.0) - glm::outerProduct(mean, mean));
    const float elongation = std::sqrt(std::max(e.x, 0.0f) / std::max(e.y, 1e-30f));
    const float round = std::sqrt(std::max(e.z, 0.0f) / std::max(e.y, 1e-30f));
    const glm::vec3 c = glm::vec3(p.colour / std::max(p.samples, 1.0));
    // Hue and saturation of the mean colour (HSV on the linear values).
    const float hi = std::max({c.r, c.g, c.b}), lo = std::min({c.r, c.g, c.b});
    const float sat = hi > 0.0f ? (hi - lo) / hi : 0.0f;
    float hue = 0.0f;
    if (hi > lo) {
      if (hi == c.r) hue = 60.0f * std::fmod((c.g - c.b) / (hi - lo) + 6.0f, 6.0f);
      else if (hi == c.g) hue = 60.0f * ((c.b - c.r) / (hi - lo) + 2.0f);
      else hue = 60.0f * ((c.r - c.g) / (hi - lo) + 4.0f);
    }
    const bool cutout = p.cutout >= 0.1 * p.samples;
    const bool green = sat >= 0.2f && hue >= 65.0f && hue <= 170.0f;
    const bool thin = elongation >= 2.5f, foot = p.minY <= p.footY + 0.02f * p.height, solid = round >= 0.3f;
    const bool rigid = !cutout && !green && solid && (thin || foot);
    rigidPart[id] = rigid;
    char why[200];
    std::snprintf(why, sizeof why, "%s, colour hue %.0f sat %.2f%s, elongation %.1f, round %.2f%s", cutout ? "cut-out texels" : "no cut-out texels",
                  double(hue), double(sat), green ? " (green)" : "", double(elongation), double(round), foot ? ", at the plant's foot" : "");
    reports->push_back({p.material, p.triangles, rigid, why});
  }
  for (size_t t = 0; t < nt; ++t) {
    const uint32_t mat = m.triangleMaterial[t];
    if (byParts[mat]) (*out)[t] = rigidPart[findRoot(parent, m.indices[3 * t])] ? 0 : 1;
  }
  std::sort(reports->begin(), reports->end(), [](const PartReport& a, const PartReport& b) {
    return a.material != b.material ? a.material < b.material : a.triangles > b.triangles;
  });
  return Status();
}

}  // namespace canopy
