#include "render/reprojection.h"

namespace canopy {
namespace {
glm::dmat4 viewProj(const LayerView& v) { return glm::dmat4(v.proj) * glm::dmat4(v.view); }
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

}  // namespace canopy
