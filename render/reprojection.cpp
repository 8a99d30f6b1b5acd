#include "render/reprojection.h"

#include <algorithm>
#include <cmath>

namespace canopy {
namespace {
// The depth search's samples are this many layer pixels apart along a pixel's ray (the kernel's
// own per-pixel count uses the same, shared/composite.h).
constexpr double kSearchSpacingPx = COMPOSITE_SEARCH_SPACING_PX;
glm::dmat4 viewProj(const LayerView& v) { return glm::dmat4(v.proj) * glm::dmat4(v.view); }

// The world point shown at pixel s of camera v at view depth z (a point on the pixel's ray).
glm::dvec3 pointAtDepth(const LayerView& v, const glm::dmat4& inverseViewProj, const glm::dvec2& s, double z, const glm::dvec2& size) {
  const glm::dvec2 ndc = s / size * 2.0 - 1.0;
  const glm::dvec4 a4 = inverseViewProj * glm::dvec4(ndc, 0.0, 1.0), b4 = inverseViewProj * glm::dvec4(ndc, 1.0, 1.0);
  const glm::dvec3 a = glm::dvec3(a4) / a4.w, b = glm::dvec3(b4) / b4.w;
  const glm::dmat4 vv(v.view);
  const glm::dvec3 row(-vv[0][2], -vv[1][2], -vv[2][2]);
  const double za = glm::dot(row, a) - vv[3][2], zb = glm::dot(row, b) - vv[3][2];
  const double t = std::abs(zb - za) > 1e-12 ? (z - za) / (zb - za) : 0.0;
  return a + t * (b - a);
}

// Pixel of world point x in camera `viewProjection`'s image; w <= 0: behind the camera.
glm::dvec3 pixelOf(const glm::dmat4& viewProjection, const glm::dvec3& x, const glm::dvec2& size) {
  const glm::dvec4 c = viewProjection * glm::dvec4(x, 1.0);
  return glm::dvec3((glm::dvec2(c) / c.w + 1.0) * 0.5 * size, c.w);
}
}  // namespace

glm::dmat3 layerHomography(const LayerView& slice, const LayerView& current, double depth, const glm::dvec2& outSize,
                           const glm::dvec2& layerSize) {
  // Current clip -> world: the ray of NDC (u, v) is the line through A = M (u, v, 0, 1) and the
  // eye B = M (0, 0, 1, 0) (homogeneous); it meets the plane pi . X = 0 at A - B (pi . A) / (pi . B).
  const glm::dmat4 m = glm::inverse(viewProj(current));
  const glm::dmat4 sv(slice.view);
  // View depth of world X is -(view X).z: the plane -(row 2 of the view) . X = depth.
  const glm::dvec4 pi(-sv[0][2], -sv[1][2], -sv[2][2], -sv[3][2] - depth);
  const glm::dvec4 b = m[2];
  const double pb = glm::dot(pi, b);
  // L = (I - b pi^T / (pi . b)) M, then the slice camera's clip.
  glm::dmat4 outer(0.0);
  for (int c = 0; c < 4; ++c) outer[c] = b * (pi[c] / pb);
  const glm::dmat4 toSlice = viewProj(slice) * (glm::dmat4(1.0) - outer) * m;
  // Columns u, v, 1 (NDC z = 0, w = 1) and rows x, y, w of the slice clip.
  glm::dmat3 ndc;
  const int cols[3] = {0, 1, 3}, rows[3] = {0, 1, 3};
  for (int c = 0; c < 3; ++c)
    for (int r = 0; r < 3; ++r) ndc[c][r] = toSlice[cols[c]][rows[r]];
  // Pixel -> NDC on the way in (u = 2x / W - 1), NDC -> pixel on the way out (x = (u + 1) W / 2).
  const glm::dmat3 in(2.0 / outSize.x, 0, 0, 0, 2.0 / outSize.y, 0, -1, -1, 1);
  const glm::dmat3 out(0.5 * layerSize.x, 0, 0, 0, 0.5 * layerSize.y, 0, 0.5 * layerSize.x, 0.5 * layerSize.y, 1);
  glm::dmat3 h = out * ndc * in;
  // Scale so that w is positive where the plane is in front of the current camera: the image of
  // the current image's centre.
  const glm::dvec3 c = h * glm::dvec3(0.5 * outSize.x, 0.5 * outSize.y, 1.0);
  if (c.z < 0) h = -h;
  return h;
}

glm::dmat4 clipToClip(const LayerView& from, const LayerView& to) { return viewProj(to) * glm::inverse(viewProj(from)); }

glm::dvec2 applyHomography(const glm::dmat3& h, const glm::dvec2& p) {
  const glm::dvec3 q = h * glm::dvec3(p, 1.0);
  return glm::dvec2(q) / q.z;
}

bool sameCamera(const LayerView& a, const LayerView& b) { return a.view == b.view && a.proj == b.proj; }

LayerView guardedView(const LayerView& view, glm::uvec2 outSize, glm::uvec2 guard) {
  if (guard == glm::uvec2(0)) return view;
  LayerView v = view;
  // Row r of the projection scaled: clip x' = sx clip x, so NDC x' (layer) = NDC x (output) * out / layer.
  const glm::vec2 scale = glm::vec2(outSize) / glm::vec2(outSize + 2u * guard);
  for (int c = 0; c < 4; ++c) {
    v.proj[c][0] *= scale.x;
    v.proj[c][1] *= scale.y;
  }
  return v;
}

gpu::CompositeView compositeView(const LayerView& slice, const LayerView& current, const LayerView& previous,
                                 const std::vector<float>& layerDepths, float backgroundDepth, const glm::dvec2& outSize,
                                 const glm::dvec2& layerSize, const std::vector<LayerSearch>& search, uint32_t maxSteps,
                                 const LayerSearch& backgroundSearch) {
  gpu::CompositeView v{};
  v.sliceToCurrent = glm::mat4(clipToClip(slice, current));
  v.sliceToPrevious = glm::mat4(clipToClip(slice, previous));
  v.currentToSlice = glm::mat4(clipToClip(current, slice));
  // The search's samples: kSearchSpacingPx apart along the longest stretch a pixel's ray crosses
  // between the range's two planes (at the output's corners and centre: the stretch is the parallax,
  // smooth over the image), two at least (the ends), maxSteps at most. The reach the classification
  // widens its boxes by gets a quarter more and a pixel, for pixels between those five.
  auto searchOf = [&](const LayerSearch& l, double planeDepth) -> glm::vec4 {
    if (maxSteps == 0 || !(l.zNear > 0 && l.zFar >= l.zNear && std::isfinite(l.zFar))) return glm::vec4(0.0f);
    const glm::dmat3 hn = layerHomography(slice, current, l.zNear, outSize, layerSize);
    const glm::dmat3 hf = layerHomography(slice, current, l.zFar, outSize, layerSize);
    const glm::dmat3 hp = layerHomography(slice, current, planeDepth, outSize, layerSize);
    double stretch = 0, reach = 0;
    for (int k = 0; k < 5; ++k) {
      const glm::dvec2 p = k < 4 ? glm::dvec2((k & 1) ? outSize.x : 0.0, (k & 2) ? outSize.y : 0.0) : 0.5 * outSize;
      const glm::dvec3 n = hn * glm::dvec3(p, 1.0), f = hf * glm::dvec3(p, 1.0), c = hp * glm::dvec3(p, 1.0);
      if (n.z <= 0 || f.z <= 0 || c.z <= 0) return glm::vec4(0.0f);  // the planes cross behind a camera: the plane alone
      const glm::dvec2 a = glm::dvec2(n) / n.z, b = glm::dvec2(f) / f.z, m = glm::dvec2(c) / c.z;
      stretch = std::max(stretch, glm::length(a - b));
      reach = std::max({reach, glm::length(a - m), glm::length(b - m)});
    }
    if (!std::isfinite(stretch) || !std::isfinite(reach)) return glm::vec4(0.0f);
    // The short path: every texel of the range lands within kShortPathPx of its plane's mapping (a
    // thin slab, a small motion since the slice, a pure rotation): the homography alone.
    if (reach < kShortPathPx) return glm::vec4(0.0f);
    // A stretch within one spacing: one sample at the range's middle and its secant step (the
    // iterative inverse warp's first iteration); longer ones a sample every spacing, the ends included.
    const double steps = stretch <= kSearchSpacingPx ? 1.0 : std::min<double>(maxSteps, std::ceil(stretch / kSearchSpacingPx) + 1.0);
    // The ends as the slice camera's NDC depths (what its layer texels hold).
    const glm::dmat4 proj(slice.proj);
    const glm::dvec4 cn = proj * glm::dvec4(0.0, 0.0, -double(l.zNear), 1.0), cf = proj * glm::dvec4(0.0, 0.0, -double(l.zFar), 1.0);
    return glm::vec4(float(cn.z / cn.w), float(cf.z / cf.w), float(steps), float(1.25 * reach + 1.0));
  };
  for (size_t i = 0; i < search.size() && i < CANOPY_MAX_LAYERS; ++i)
    v.search[i] = searchOf(search[i], i < layerDepths.size() ? layerDepths[i] : 0.5 * (search[i].zNear + search[i].zFar));
  v.search[COMPOSITE_VIEW_BACKGROUND] = searchOf(backgroundSearch, backgroundDepth);
  for (uint32_t i = 0; i <= CANOPY_MAX_LAYERS; ++i) {
    const bool background = i == COMPOSITE_VIEW_BACKGROUND;
    if (!background && i >= layerDepths.size()) continue;  // no such layer: never read
    glm::dmat3 h = layerHomography(slice, current, background ? backgroundDepth : layerDepths[i], outSize, layerSize);
    // Scaled so that w is about 1 near the image (float precision), its sign kept.
    const double w = std::abs((h * glm::dvec3(0.5 * outSize, 1.0)).z);
    if (w > 0 && std::isfinite(w)) h /= w;
    for (int r = 0; r < 3; ++r) v.homography[3 * i + r] = glm::vec4(float(h[0][r]), float(h[1][r]), float(h[2][r]), 0.0f);
  }
  return v;
}

ReprojectionError estimateReprojectionError(const LayerView& slice, const LayerView& current, const std::vector<SlabRange>& slabs,
                                            const glm::vec3& boundsMin, const glm::vec3& boundsMax, const glm::dvec2& size,
                                            const glm::dvec2& outSize, const PixelExtent* drawn) {
  ReprojectionError e;
  const glm::dmat4 sliceVP = viewProj(slice), currentVP = viewProj(current), sliceInv = glm::inverse(sliceVP);
  // The vegetation's footprint in the slice camera's image (its bounding box's corners).
  glm::dvec2 lo(1e300), hi(-1e300);
  bool behind = false;
  for (int k = 0; k < 8; ++k) {
    const glm::dvec3 x((k & 1) ? boundsMax.x : boundsMin.x, (k & 2) ? boundsMax.y : boundsMin.y, (k & 4) ? boundsMax.z : boundsMin.z);
    const glm::dvec3 p = pixelOf(sliceVP, x, size);
    if (p.z <= 0) behind = true;
    lo = glm::min(lo, glm::dvec2(p));
    hi = glm::max(hi, glm::dvec2(p));
  }
  if (behind) {  // the camera is inside the bounds: the whole image
    lo = glm::dvec2(0.0);
    hi = size;
  }
  if (drawn && drawn->known) {  // the vertices' own extent, inside the box's
    lo = glm::dvec2(drawn->lo);
    hi = glm::dvec2(drawn->hi);
  }
  const glm::dvec2 clo = glm::clamp(lo, glm::dvec2(0.0), size), chi = glm::clamp(hi, glm::dvec2(0.0), size);
  // Parallax: a 3 x 3 grid of slice pixels over the footprint; at each, the mean distance between
  // where a point of the slab (uniform in depth over its range: kDepthSamples midpoints) is seen
  // from the current camera and where its plane's mapping shows it; the largest over the grid and
  // the slabs.
  for (const SlabRange& slab : slabs)
    for (int gy = 0; gy < 3; ++gy)
      for (int gx = 0; gx < 3; ++gx) {
        const glm::dvec2 s = clo + (chi - clo) * glm::dvec2(0.5 * gx, 0.5 * gy);
        const glm::dvec3 onPlane = pixelOf(currentVP, pointAtDepth(slice, sliceInv, s, slab.depth, size), outSize);
        double sum = 0;
        for (int k = 0; k < kDepthSamples; ++k) {
          const double z = slab.zNear + (slab.zFar - slab.zNear) * (k + 0.5) / kDepthSamples;
          const glm::dvec3 off = pixelOf(currentVP, pointAtDepth(slice, sliceInv, s, z, size), outSize);
          sum += onPlane.z > 0 && off.z > 0 ? glm::length(glm::dvec2(off) - glm::dvec2(onPlane)) : INFINITY;
        }
        e.parallaxPx = std::max(e.parallaxPx, sum / kDepthSamples);
      }
  // Content beyond the slice image: the current image's corners on the middle slab's plane, in
  // slice pixels, intersected with the footprint, against the slice image.
  const double mid = slabs.empty() ? 0.0 : 0.5 * (slabs.front().depth + slabs.back().depth);
  const glm::dmat3 h = layerHomography(slice, current, mid, outSize, size);
  glm::dvec2 nlo(1e300), nhi(-1e300);
  bool wrapped = false;
  for (int k = 0; k < 4; ++k) {
    const glm::dvec3 q = h * glm::dvec3((k & 1) ? outSize.x : 0.0, (k & 2) ? outSize.y : 0.0, 1.0);
    if (q.z <= 0) wrapped = true;
    nlo = glm::min(nlo, glm::dvec2(q) / q.z);
    nhi = glm::max(nhi, glm::dvec2(q) / q.z);
  }
  if (wrapped) {
    nlo = lo;
    nhi = hi;
  }
  nlo = glm::max(nlo, lo);
  nhi = glm::min(nhi, hi);
  if (nlo.x < nhi.x && nlo.y < nhi.y)
    e.outsidePx = std::max({0.0, -nlo.x, -nlo.y, nhi.x - size.x, nhi.y - size.y});
  // Magnification: the homography's Jacobian at the image centre (layer texels per current pixel).
  const glm::dvec2 c0 = 0.5 * outSize;
  const glm::dvec2 m0 = applyHomography(h, c0), mx = applyHomography(h, c0 + glm::dvec2(1, 0)), my = applyHomography(h, c0 + glm::dvec2(0, 1));
  const double det = std::abs((mx.x - m0.x) * (my.y - m0.y) - (mx.y - m0.y) * (my.x - m0.x));
  if (!wrapped && det > 0 && std::isfinite(det)) e.magnification = 1.0 / std::sqrt(det);
  // Shading: the eyes' directions to the centre.
  const glm::dvec3 centre = 0.5 * (glm::dvec3(boundsMin) + glm::dvec3(boundsMax));
  const glm::dvec3 a = glm::normalize(centre - glm::dvec3(viewPosition(slice.view)));
  const glm::dvec3 b = glm::normalize(centre - glm::dvec3(viewPosition(current.view)));
  e.turnDegrees = glm::degrees(std::acos(std::clamp(glm::dot(a, b), -1.0, 1.0)));
  return e;
}

}  // namespace canopy
