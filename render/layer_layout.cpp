#include "render/layer_layout.h"

#include <algorithm>
#include <cmath>

namespace canopy {
namespace {

// Reads an unsigned decimal at `pos`; false when there is none or it exceeds `maxValue`.
bool readUint(std::string_view s, size_t* pos, uint32_t maxValue, uint32_t* out) {
  size_t p = *pos;
  uint64_t v = 0;
  while (p < s.size() && s[p] >= '0' && s[p] <= '9') {
    v = v * 10 + uint64_t(s[p] - '0');
    if (v > maxValue) return false;
    ++p;
  }
  if (p == *pos) return false;
  *pos = p;
  *out = uint32_t(v);
  return true;
}

}  // namespace

Status parseLayerLayout(std::string_view text, LayerLayout* out) {
  const std::string quoted = "layer layout '" + std::string(text) + "'";
  const std::string expect = ": expected N or N(near-mid-far), e.g. 5(3-1-1), with 1 <= N <= " +
                             std::to_string(kMaxLayers) + " and near+mid+far = N";
  size_t p = 0;
  uint32_t total = 0;
  if (!readUint(text, &p, 1000, &total)) return Status::error(quoted + expect);
  LayerLayout l;
  if (p == text.size()) {
    l.region[0] = total;
    l.region[1] = l.region[2] = 0;
  } else {
    if (text[p] != '(') return Status::error(quoted + expect);
    ++p;
    for (int r = 0; r < 3; ++r) {
      if (!readUint(text, &p, 1000, &l.region[r])) return Status::error(quoted + expect);
      const char want = r < 2 ? '-' : ')';
      if (p >= text.size() || text[p] != want) return Status::error(quoted + expect);
      ++p;
    }
    if (p != text.size()) return Status::error(quoted + ": unexpected text after ')'" + expect);
    if (l.count() != total)
      return Status::error(quoted + ": the regions hold " + std::to_string(l.count()) + " layers, not " +
                           std::to_string(total));
  }
  if (total < 1 || total > kMaxLayers)
    return Status::error(quoted + ": " + std::to_string(total) + " layers is outside 1.." + std::to_string(kMaxLayers));
  *out = l;
  return Status();
}

std::string toString(const LayerLayout& l) {
  return std::to_string(l.count()) + "(" + std::to_string(l.region[0]) + "-" + std::to_string(l.region[1]) + "-" +
         std::to_string(l.region[2]) + ")";
}

Status validateRegionSplit(const RegionSplit& s) {
  if (!std::isfinite(s.nearEnd) || !std::isfinite(s.farStart))
    return Status::error("region split: distances must be finite");
  if (s.absolute) {
    if (s.nearEnd < 0 || s.farStart < s.nearEnd)
      return Status::error("region split: need 0 <= nearEnd <= farStart (world units), got " +
                           std::to_string(s.nearEnd) + ", " + std::to_string(s.farStart));
  } else if (s.nearEnd < 0 || s.farStart < s.nearEnd || s.farStart > 1) {
    return Status::error("region split: need 0 <= nearEnd <= farStart <= 1 (fractions of the depth range), got " +
                         std::to_string(s.nearEnd) + ", " + std::to_string(s.farStart));
  }
  return Status();
}

Status placeLayers(const LayerLayout& layout, const RegionSplit& split, float zMin, float zMax,
                   std::vector<LayerSlab>* slabs, std::vector<float>* boundaries) {
  if (layout.count() < 1 || layout.count() > kMaxLayers)
    return Status::error("layer layout " + toString(layout) + ": 1.." + std::to_string(kMaxLayers) + " layers");
  CANOPY_TRY(validateRegionSplit(split));
  if (!std::isfinite(zMin) || !std::isfinite(zMax) || zMax < zMin)
    return Status::error("layer placement: bad depth range [" + std::to_string(zMin) + ", " + std::to_string(zMax) + "]");
  const float range = zMax - zMin;
  float r1, r2;
  if (split.absolute) {
    r1 = std::clamp(split.nearEnd, zMin, zMax);
    r2 = std::clamp(split.farStart, zMin, zMax);
  } else {
    r1 = zMin + split.nearEnd * range;
    r2 = zMin + split.farStart * range;
  }
  const float edge[4] = {zMin, r1, r2, zMax};
  // Non-empty regions take over their empty neighbours' intervals.
  float start[3], end[3];
  int prev = -1;
  for (int r = 0; r < 3; ++r) {
    if (!layout.region[r]) continue;
    if (prev < 0) {
      start[r] = zMin;
    } else if (r == prev + 1) {
      start[r] = edge[r];
    } else {  // one empty region between prev and r: split it at its middle
      start[r] = 0.5f * (edge[prev + 1] + edge[r]);
    }
    if (prev >= 0) end[prev] = start[r];
    prev = r;
  }
  end[prev] = zMax;
  slabs->clear();
  boundaries->clear();
  for (int r = 0; r < 3; ++r) {
    const uint32_t n = layout.region[r];
    for (uint32_t k = 0; k < n; ++k) {
      LayerSlab s;
      s.zNear = start[r] + (end[r] - start[r]) * float(k) / float(n);
      s.zFar = k + 1 == n ? end[r] : start[r] + (end[r] - start[r]) * float(k + 1) / float(n);
      s.depth = 0.5f * (s.zNear + s.zFar);
      slabs->push_back(s);
      boundaries->push_back(s.zNear);
    }
  }
  boundaries->push_back(zMax);
  for (LayerSlab& s : *slabs) s.distance = s.depth - (*slabs)[0].depth;
  return Status();
}

}  // namespace canopy
