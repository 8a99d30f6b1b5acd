#include "compute/dynamics_reference.h"

#include <algorithm>
#include <cmath>

namespace canopy {

glm::vec2 sampleTiledReference(const glm::vec2* field, uint32_t n, glm::vec2 a) {
  const glm::vec2 x = (a - glm::floor(a)) * float(n) - 0.5f;
  const glm::vec2 fl = glm::floor(x), t = x - fl;
  auto wrap = [n](int i) { return uint32_t((i % int(n) + int(n)) % int(n)); };
  const uint32_t i0 = wrap(int(fl.x)), i1 = wrap(int(fl.x) + 1), j0 = wrap(int(fl.y)), j1 = wrap(int(fl.y) + 1);
  const glm::vec2 b = glm::mix(field[j0 * n + i0], field[j0 * n + i1], t.x);
  const glm::vec2 c = glm::mix(field[j1 * n + i0], field[j1 * n + i1], t.x);
  return glm::mix(b, c, t.y);
}

glm::vec2 cornerSimCoord(const gpu::AnimFrame& f, uint32_t layer, uint32_t gx, uint32_t gy, float depth) {
  const glm::vec2 pixel = glm::min(glm::vec2(float(gx), float(gy)) * f.cellSize, glm::vec2(f.width, f.height));
  const glm::vec2 ndc = pixel / glm::vec2(f.width, f.height) * 2.0f - 1.0f;
  const glm::vec4 h0 = f.invViewProj * glm::vec4(ndc, 0, 1), h1 = f.invViewProj * glm::vec4(ndc, 1, 1);
  const glm::vec3 p0 = glm::vec3(h0) / h0.w, p1 = glm::vec3(h1) / h1.w;
  const float d0 = glm::dot(f.depthRow, glm::vec4(p0, 1)), d1 = glm::dot(f.depthRow, glm::vec4(p1, 1));
  const glm::vec3 world = p0 + (p1 - p0) * (((depth > 0.0f ? depth : f.layers[layer].depth) - d0) / (d1 - d0));
  const glm::vec3 rel = world - glm::vec3(f.simOrigin);
  return glm::vec2(glm::dot(rel, glm::vec3(f.simRight)), glm::dot(rel, glm::vec3(f.simUp))) / f.simOrigin.w;
}

std::vector<glm::vec2> referenceDisplacement(const gpu::AnimFrame& f, const std::vector<glm::vec2>& tiled,
                                             const std::vector<glm::vec2>& ring, const std::vector<float>& times,
                                             const std::vector<glm::vec4>& plantRects) {
  const uint32_t corners = f.gridX * f.gridY, nn = f.n * f.n;
  std::vector<glm::vec2> out(size_t(corners) * f.layerCount);
  // History bounds: the newest and oldest slot by time.
  const auto [lo, hi] = std::minmax_element(times.begin(), times.begin() + f.ringSize);
  auto history = [&](glm::vec2 a, float tau) {
    tau = std::clamp(tau, *lo, *hi);
    // Latest slot at or before tau, earliest at or after it.
    float before = *lo, after = *hi;
    uint32_t sb = uint32_t(lo - times.begin()), sa = uint32_t(hi - times.begin());
    for (uint32_t s = 0; s < f.ringSize; ++s) {
      if (times[s] <= tau && times[s] >= before) before = times[s], sb = s;
      if (times[s] >= tau && times[s] <= after) after = times[s], sa = s;
    }
    const float w = after > before ? (tau - before) / (after - before) : 0.0f;
    return glm::mix(sampleTiledReference(&ring[size_t(sb) * nn], f.n, a), sampleTiledReference(&ring[size_t(sa) * nn], f.n, a), w);
  };
  for (uint32_t layer = 0; layer < f.layerCount; ++layer)
    for (uint32_t id = 0; id < corners; ++id) {
      const uint32_t gx = id % f.gridX, gy = id / f.gridX;
      const glm::vec2 pixel = glm::min(glm::vec2(float(gx), float(gy)) * f.cellSize, glm::vec2(f.width, f.height));
      gpu::AnimLayer rooted = f.layers[layer];
      glm::vec2 response(1.0f);
      float sampleDepth = 0.0f;  // the layer's
      float bestD = 3.0e38f, bestA = 3.0e38f;
      const uint32_t k = ANIM_RECT_VEC4S;
      for (uint32_t j = rooted.firstPlant; j < rooted.firstPlant + rooted.plantCount && k * j + 2 < plantRects.size(); ++j) {
        const glm::vec4 r = plantRects[k * j], place = plantRects[k * j + 2];  // sample depth, wood only
        if (gpu::plantRectBetter(r, place.y, pixel, bestD, bestA)) {
          bestD = gpu::plantRectDistance2(r, pixel);
          bestA = gpu::plantRectRank(r, place.y);
          const glm::vec4 species = plantRects[k * j + 1];
          rooted = species.z > 0.0f ? gpu::withPlantRoot(f.layers[layer], r, species.w) : f.layers[layer];
          response = glm::vec2(species);
          sampleDepth = place.x;
        }
      }
      const glm::vec2 a = cornerSimCoord(f, layer, gx, gy, sampleDepth);
      const glm::vec2 vs = sampleTiledReference(tiled.data(), f.n, a);
      const glm::vec3 v0 = gpu::simToView(f, vs);
      glm::vec3 vi = v0;
      if (layer > 0) {
        const float gamma = gpu::speciesDelay(f.maxDelay, gpu::layerDelay(f.maxDelay, f.layers[layer], v0.z), response.y);
        vi = f.delayMode == ANIM_DELAY_EXACT ? gpu::simToView(f, history(a, f.time - gamma))
                                             : gpu::simToView(f, sampleTiledReference(tiled.data(), f.n, gpu::approximateLookup(f, a, gamma, vs)));
      }
      out[size_t(layer) * corners + id] = response.x * gpu::displacementPixels(f, rooted, pixel.y, vi);
    }
  return boundStretchReference(f, out);
}

std::vector<glm::vec2> boundStretchReference(const gpu::AnimFrame& f, const std::vector<glm::vec2>& raw) {
  // The largest L-Lipschitz magnitude under |d| in the grid's L1 metric, by brute force over every
  // corner pair (the shaders separate it into a column and a row pass; the two are equal).
  if (f.maxStretch <= 0.0f) return raw;
  std::vector<glm::vec2> out(raw.size());
  const uint32_t corners = f.gridX * f.gridY;
  const float step = f.maxStretch * f.cellSize;
  for (uint32_t layer = 0; layer < f.layerCount; ++layer)
    for (uint32_t id = 0; id < corners; ++id) {
      const int gx = int(id % f.gridX), gy = int(id / f.gridX);
      float m = 3.0e38f;
      for (uint32_t n = 0; n < corners; ++n) {
        const int nx = int(n % f.gridX), ny = int(n / f.gridX);
        m = std::min(m, glm::length(raw[size_t(layer) * corners + n]) + step * float(std::abs(nx - gx) + std::abs(ny - gy)));
      }
      out[size_t(layer) * corners + id] = gpu::stretchBounded(raw[size_t(layer) * corners + id], m);
    }
  return out;
}

}  // namespace canopy
