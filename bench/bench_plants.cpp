// canopy-bench plants (issue 77; docs/performance.md "Real plants in wind"): real plants as a user
// brings them, each in a breeze and a gale, the 2D method beside the per-vertex baseline, drawn as
// canopy-demo draws them (its host, sky, camera and 2 s warm-up) and measured per frame:
//   attachment gap  for every leaf whose root sits on rigid geometry (within kAttachShare of its
//                   plant's height of a rigid triangle), how far on screen the root is drawn from
//                   where the rigid point it grows from is drawn, less the same offset at rest
//                   (pixels; p99 and max over leaves and frames)
//   sway            in the breeze, a pass of its own (--sway-frames, default 1800 at 320x240): the
//                   top third's horizontal centroid from its 5th to its 95th percentile
//   base            the 2D method: the largest drawn shift of a rigid vertex in the plant's bottom
//                   5 % (the CPU twin of rigid_follow_draw.glsl); the baseline (which draws no false
//                   colour): its bottom tenth's pixels' centroid against the windless frame's
//   bare rigid      rigid pixels inside the crown farther than 3 px from any foliage pixel, with the
//                   layers in false colour (CompositeDebugView::Layers), gale over still
// The 2D method's gap is computed from the frame's own displacement (read back): a leaf's root is
// shown where the inverse warp shows its layer texel, a rigid point where its triangle's displaced
// corners put it (shared/rigid.h; RigidMotion::Still: where it is). The baseline's from the CPU twin
// of its vertex shader (shared/bend.h bendPosition).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <memory>
#include <sstream>

#include "bench/bench.h"
#include "demo/demo_app.h"
#include "engine/device.h"
#include "engine/transfer.h"
#include "render/canopy_context.h"
#include "render/leaf_attach.h"
#include "render/material_split.h"
#include "render/plants.h"
#include "render/plant_sway.h"
#include "render/rigid_flex.h"
#include "render/rigid_refine.h"
#include "shared/rigid.h"

namespace canopy::bench {
namespace {

// One leaf whose root sits on a rigid triangle.
struct Attached {
  uint32_t leaf = 0;
  glm::vec3 root{0.0f};  // model space (one copy at the origin)
  glm::vec3 rigid{0.0f};
  uint32_t triangle = 0;
};

// What the CPU needs of a model to follow its leaves and rigid parts: the same split, roots and
// shares the context computed (the same functions on the same model and options).
struct PlantParts {
  std::vector<uint8_t> foliage;
  LeafRoots roots;
  std::vector<gpu::LayerLeafRoot> rigidAnchors;  // per vertex: anchor and share (render/rigid_flex.h)
  std::vector<glm::vec3> layerRoots;  // per leaf, the position its layer is decided by
  std::vector<Attached> attached;
  uint32_t leaves = 0;
  std::vector<PlantLevers> levers;         // per plant, its levers (render/plant_sway.h)
  std::vector<float> sway;                 // per plant, its sway scale with the world wind
  VegetationModel refined;                 // the model with its long rigid edges split, when it had any
  const VegetationModel* model = nullptr;  // the one measured: `refined` or the given
};

Status plantParts(const VegetationModel& given, const CanopyDesc& desc, PlantParts* out) {
  // The model as the context prepares it: its long rigid edges split (render/rigid_refine.h).
  MaterialSplit split;
  CANOPY_TRY(splitMaterials(given, desc.split, &split));
  out->model = &given;
  if (needsRigidRefinement(given, split.triangleFoliage)) {
    CANOPY_TRY(refineRigidParts(given, &split.triangleFoliage, &out->refined));
    out->model = &out->refined;
    CANOPY_TRY(splitMaterials(out->refined, desc.split, &split));
  }
  const VegetationModel& m = *out->model;
  out->foliage = split.triangleFoliage;
  CANOPY_TRY(computeLeafRoots(m, out->foliage, desc.roots, &out->roots));
  Plants plants;
  std::vector<uint32_t> trianglePlant;
  CANOPY_TRY(findPlants(m, out->roots, &plants, &trianglePlant));
  CANOPY_TRY(plantSwayScales(m, out->foliage, out->roots, trianglePlant, &plants));
  CANOPY_TRY(plantLevers(m, out->foliage, out->roots, trianglePlant, plants, &out->levers));
  out->sway = plants.sway;
  if (split.rigidTriangles) {
    CANOPY_TRY(rigidAnchors(m, out->foliage, out->roots, trianglePlant, &out->rigidAnchors));
    CANOPY_TRY(leafLayerRoots(m, out->foliage, out->roots, &out->layerRoots, &out->rigidAnchors));
  }
  out->leaves = out->roots.leafCount();
  const RigidGrid grid = buildRigidGrid(m, out->foliage, 0.0f);
  for (uint32_t l = 0; l < out->roots.leafCount(); ++l) {
    LeafAttachment at;
    const glm::vec3 r = m.positions[out->roots.leafRoot[l]];
    if (nearestRigidPoint(grid, r, &at)) out->attached.push_back({l, r, at.rigidPoint, at.triangle});
  }
  return Status();
}

// Barycentric coordinates of p (on the triangle) in (a, b, c).
glm::vec3 barycentric(const glm::vec3& p, const glm::vec3& a, const glm::vec3& b, const glm::vec3& c) {
  const glm::vec3 v0 = b - a, v1 = c - a, v2 = p - a;
  const float d00 = glm::dot(v0, v0), d01 = glm::dot(v0, v1), d11 = glm::dot(v1, v1), d20 = glm::dot(v2, v0), d21 = glm::dot(v2, v1);
  const float den = d00 * d11 - d01 * d01;
  if (!(std::abs(den) > 1e-30f)) return glm::vec3(1.0f, 0.0f, 0.0f);
  const float v = (d11 * d20 - d01 * d21) / den, w = (d00 * d21 - d01 * d20) / den;
  return glm::vec3(1.0f - v - w, v, w);
}

// A frame of the 2D method as the CPU sees it: the slice camera's frame block, the warp grid and
// every layer's displacement.
struct WarpFrame {
  gpu::LayerFrame layers{};
  gpu::AnimFrame anim{};
  std::vector<glm::vec2> disp;
  glm::vec2 size() const { return {anim.width, anim.height}; }
  glm::vec2 displacement(uint32_t layer, glm::vec2 p) const {
    const gpu::AnimGridSample s = gpu::animGridSample(anim.cellSize, anim.gridX, anim.gridY, size(), p);
    const size_t base = size_t(layer) * anim.gridX * anim.gridY;
    return gpu::animGridBlend(s, disp[base + s.i00], disp[base + s.i10], disp[base + s.i01], disp[base + s.i11]);
  }
  // Slice-camera layer pixel and view depth of world point w; false behind the camera.
  bool pixel(const glm::vec3& w, glm::vec2* p, float* z, glm::vec3* ndc = nullptr) const {
    const glm::vec4 c = layers.viewProj * glm::vec4(w, 1.0f);
    if (!(c.w > 1e-6f)) return false;
    const glm::vec3 n = glm::vec3(c) / c.w;
    *p = (glm::vec2(n) * 0.5f + 0.5f) * size();
    *z = glm::dot(layers.depthRow, glm::vec4(w, 1.0f));
    if (ndc) *ndc = n;
    return true;
  }
  uint32_t layerOf(float z) const { return std::min(gpu::layerOfDepth(layers, z), std::max(anim.layerCount, 1u) - 1u); }
  // Where the composite shows layer texel q of `layer`: s with s - d(s) = q (fixed point).
  glm::vec2 shown(uint32_t layer, glm::vec2 q) const {
    glm::vec2 s = q + displacement(layer, q);
    for (uint32_t k = 0; k < RIGID_SHOWN_STEPS; ++k) s = q + displacement(layer, s);
    return s;
  }
  // The world point the rigid draw moves vertex w to (rigid_follow_draw.glsl): its slice pixel
  // shown as the inverse warp shows it, by its share, unprojected at its own depth.
  glm::vec3 rigidWorld(const glm::vec3& w, float share, uint32_t layer) const {
    glm::vec2 p;
    float z;
    glm::vec3 ndc;
    if (!pixel(w, &p, &z, &ndc)) return w;
    const glm::vec3 n = gpu::rigidDisplacedNdc(ndc, share * (shown(layer, p) - p), size());
    const glm::vec4 q = anim.invViewProj * glm::vec4(n, 1.0f);
    return glm::vec3(q) / q.w;
  }
  // Where the rigid draw puts world point w of a vertex with share `share` (shared/rigid.h).
  glm::vec2 rigidShown(const glm::vec3& w, float share) const {
    glm::vec2 p;
    float z;
    if (!pixel(w, &p, &z)) return p;
    return p + share * displacement(layerOf(z), p);
  }
};

Status readWarp(Device& d, CanopyContext* ctx, WarpFrame* out) {
  out->layers = canopyLayers(ctx).visible.frame;
  const LayerDynamics& dyn = canopyDynamics(ctx);
  out->anim = dyn.current;
  out->disp.assign(size_t(out->anim.gridX) * out->anim.gridY * out->anim.layerCount, glm::vec2(0.0f));
  if (out->disp.empty()) return Status();
  return readbackBuffer(d, dyn.displacement, out->disp.data(), out->disp.size() * sizeof(glm::vec2),
                        rg::stateOf(rg::Use::ComputeStorageRead));
}

// The 2D method's gaps this frame, pixels (one per attached leaf).
void gaps2D(const VegetationModel& m, const PlantParts& parts, const WarpFrame& f, bool follows, std::vector<double>* out) {
  for (const Attached& a : parts.attached) {
    glm::vec2 pr, pg, pl;
    float zr, zg, zl;
    if (!f.pixel(a.root, &pr, &zr) || !f.pixel(a.rigid, &pg, &zg)) continue;
    // The leaf's layer: the depth of its layer root (the corner it grows from: render/leaf_attach.h).
    if (!parts.layerRoots.empty() && f.pixel(parts.layerRoots[a.leaf], &pl, &zl)) zr = zl;
    const glm::vec2 leaf = f.shown(f.layerOf(zr), pr);
    glm::vec2 rigid = pg;
    if (follows) {
      // The rigid point is drawn where its triangle's displaced corners put it: the rasterizer
      // interpolates them with perspective, so the same barycentric point of the displaced corners
      // in the world, projected.
      const uint32_t* tri = &m.indices[3 * size_t(a.triangle)];
      const glm::vec3 w = barycentric(a.rigid, m.positions[tri[0]], m.positions[tri[1]], m.positions[tri[2]]);
      glm::vec3 moved(0.0f);
      for (int k = 0; k < 3; ++k) {
        // Each corner follows the layer of its anchor's depth by its share (rigid_follow_draw.glsl).
        const bool anchored = !parts.rigidAnchors.empty();
        const float share = anchored ? gpu::layerRigidShare(parts.rigidAnchors[tri[k]].leaf) : 1.0f;
        glm::vec2 pa;
        float zk = 0.0f, za;
        glm::vec2 pk;
        f.pixel(m.positions[tri[k]], &pk, &zk);
        if (anchored && f.pixel(parts.rigidAnchors[tri[k]].position, &pa, &za)) zk = za;
        moved += w[k] * f.rigidWorld(m.positions[tri[k]], share, f.layerOf(zk));
      }
      float zm;
      if (!f.pixel(moved, &rigid, &zm)) continue;
    }
    out->push_back(glm::length((leaf - rigid) - (pr - pg)));
  }
}

// The 2D method's trunk base this frame: the largest on-screen shift of a rigid vertex within
// kFootShare of the model's height above its lowest point, drawn as rigid_follow_draw.glsl draws it
// (the CPU twin, shared/rigid.h) against where it stands; -1 without rigid parts.
double baseShift2D(const VegetationModel& m, const PlantParts& parts, const WarpFrame& f) {
  if (parts.rigidAnchors.size() != m.positions.size()) return -1.0;
  const float below = m.boundsMin.y + kFootShare * (m.boundsMax.y - m.boundsMin.y);
  double worst = 0.0;
  for (size_t t = 0; t < m.triangleCount(); ++t) {
    if (parts.foliage[t]) continue;
    for (int k = 0; k < 3; ++k) {
      const uint32_t v = m.indices[3 * t + size_t(k)];
      const glm::vec3 x = m.positions[v];
      glm::vec2 pa, pv, q;
      float za, zv, zq;
      if (x.y > below || !f.pixel(parts.rigidAnchors[v].position, &pa, &za) || !f.pixel(x, &pv, &zv)) continue;
      const float share = gpu::layerRigidShare(parts.rigidAnchors[v].leaf);
      if (f.pixel(f.rigidWorld(x, share, f.layerOf(za)), &q, &zq)) worst = std::max(worst, double(glm::length(q - pv)));
    }
  }
  return worst;
}

// The per-vertex baseline's gaps this frame: its vertex shader's bend (the CPU twin) of the root and
// of the rigid triangle's corners, both projected by the camera.
void gapsPerVertex(const VegetationModel& m, const PlantParts& parts, const CanopyContext* ctx, const glm::mat4& viewProj,
                   glm::vec2 size, std::vector<double>* out) {
  const gpu::BendFrame bf = ctx->perVertex.current;
  const bool hierarchy = (bf.flags & BEND_FLAG_HIERARCHY) != 0u && m.bend.size() == m.positions.size();
  auto bent = [&](uint32_t v, const glm::vec3& p, bool leaf, uint32_t leafIndex, const glm::vec3& root) {
    const gpu::BendVertex bv = hierarchy ? m.bend[v] : gpu::BendVertex{BEND_NO_BRANCH, 0};
    glm::vec3 n(0.0f, 1.0f, 0.0f);
    return gpu::bendPosition(bf, bendChainOf(m.branches, bv.branch), bv, leaf, root, leafIndex, p, bf.time, n);
  };
  auto project = [&](const glm::vec3& w) {
    const glm::vec4 c = viewProj * glm::vec4(w, 1.0f);
    return (glm::vec2(c) / std::max(c.w, 1e-6f) * 0.5f + 0.5f) * size;
  };
  for (const Attached& a : parts.attached) {
    const uint32_t rv = parts.roots.leafRoot[a.leaf];
    const glm::vec3 root = bent(rv, a.root, true, a.leaf, a.root);
    const uint32_t* tri = &m.indices[3 * size_t(a.triangle)];
    const glm::vec3 w = barycentric(a.rigid, m.positions[tri[0]], m.positions[tri[1]], m.positions[tri[2]]);
    glm::vec3 rigid(0.0f);
    for (int k = 0; k < 3; ++k) rigid += w[k] * bent(tri[k], m.positions[tri[k]], false, 0u, m.positions[tri[k]]);
    out->push_back(glm::length((project(root) - project(rigid)) - (project(a.root) - project(a.rigid))));
  }
}

double quantile(std::vector<double> v, double q) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  return v[std::min(v.size() - 1, size_t(std::floor(q * double(v.size()))))];
}

// Pixel classes of a frame of the demo's host (RGBA8 sRGB): the sky is its clear colour.
struct Pixels {
  uint32_t w = 0, h = 0;
  uint8_t sky[3] = {0, 0, 0};
  bool vegetation(const std::vector<uint8_t>& px, size_t i) const {
    for (int c = 0; c < 3; ++c)
      if (std::abs(int(px[4 * i + size_t(c)]) - int(sky[c])) > 2) return true;
    return false;
  }
  // With the layers in false colour: a fully saturated hue (one channel near 0, one bright).
  static bool falseColour(const std::vector<uint8_t>& px, size_t i) {
    const uint8_t* p = &px[4 * i];
    return std::min({p[0], p[1], p[2]}) <= 12 && std::max({p[0], p[1], p[2]}) >= 150;
  }
};

// The rows of the top third of the vegetation and the plant's bottom tenth in frame `px`.
struct Rows {
  uint32_t top = 0, topEnd = 0, baseBegin = 0, bottom = 0;
};
Rows rowsOf(const Pixels& P, const std::vector<uint8_t>& px) {
  uint32_t top = P.h, bottom = 0;
  for (uint32_t y = 0; y < P.h; ++y)
    for (uint32_t x = 0; x < P.w; ++x)
      if (P.vegetation(px, size_t(y) * P.w + x)) {
        top = std::min(top, y);
        bottom = std::max(bottom, y);
      }
  Rows r;
  if (top >= bottom) return r;
  r.top = top;
  r.topEnd = top + (bottom - top + 1) / 3;
  r.baseBegin = bottom - (bottom - top + 1) / 10;
  r.bottom = bottom + 1;
  return r;
}
double centroidX(const Pixels& P, const std::vector<uint8_t>& px, const Rows& r) {
  double sum = 0, n = 0;
  for (uint32_t y = r.top; y < r.topEnd; ++y)
    for (uint32_t x = 0; x < P.w; ++x)
      if (P.vegetation(px, size_t(y) * P.w + x)) {
        sum += x;
        n += 1;
      }
  return n > 0 ? sum / n : 0.0;
}
// The share of the base rows' vegetation pixels (in either frame) that differ by more than 8/255;
// `rigidOnly`: of the still frame's rigid pixels (layers in false colour), the trunk's base.
double baseChange(const Pixels& P, const std::vector<uint8_t>& a, const std::vector<uint8_t>& b, const Rows& r, bool rigidOnly = false) {
  double n = 0, changed = 0;
  for (uint32_t y = r.baseBegin; y < r.bottom; ++y)
    for (uint32_t x = 0; x < P.w; ++x) {
      const size_t i = size_t(y) * P.w + x;
      if (rigidOnly ? !P.vegetation(b, i) || Pixels::falseColour(b, i) : !P.vegetation(a, i) && !P.vegetation(b, i)) continue;
      n += 1;
      for (int c = 0; c < 3; ++c)
        if (std::abs(int(a[4 * i + size_t(c)]) - int(b[4 * i + size_t(c)])) > 8) {
          changed += 1;
          break;
        }
    }
  return n > 0 ? changed / n : 0.0;
}
// The horizontal centroid of the base rows' pixels: rigid ones (false-colour frames) or all the
// vegetation's; NAN without any.
double baseCentroid(const Pixels& P, const std::vector<uint8_t>& px, const Rows& r, bool rigidOnly) {
  double sum = 0, n = 0;
  for (uint32_t y = r.baseBegin; y < r.bottom; ++y)
    for (uint32_t x = 0; x < P.w; ++x) {
      const size_t i = size_t(y) * P.w + x;
      if (!P.vegetation(px, i) || (rigidOnly && Pixels::falseColour(px, i))) continue;
      sum += x;
      n += 1;
    }
  return n > 0 ? sum / n : NAN;
}

// Rigid pixels inside the foliage's bounding box farther than 3 px from any foliage pixel, with
// the layers in false colour.
double bareRigid(const Pixels& P, const std::vector<uint8_t>& px) {
  std::vector<uint8_t> foliage(size_t(P.w) * P.h, 0);
  uint32_t x0 = P.w, y0 = P.h, x1 = 0, y1 = 0;
  for (uint32_t y = 0; y < P.h; ++y)
    for (uint32_t x = 0; x < P.w; ++x)
      if (Pixels::falseColour(px, size_t(y) * P.w + x)) {
        foliage[size_t(y) * P.w + x] = 1;
        x0 = std::min(x0, x), y0 = std::min(y0, y), x1 = std::max(x1, x), y1 = std::max(y1, y);
      }
  if (x0 > x1) return 0.0;
  // Within 3 px (a 7 x 7 square) of a foliage pixel: separable dilation.
  std::vector<uint8_t> rows(foliage.size(), 0), near(foliage.size(), 0);
  for (uint32_t y = 0; y < P.h; ++y)
    for (uint32_t x = 0; x < P.w; ++x)
      for (int k = -3; k <= 3 && !rows[size_t(y) * P.w + x]; ++k) {
        const int xx = int(x) + k;
        if (xx >= 0 && xx < int(P.w) && foliage[size_t(y) * P.w + size_t(xx)]) rows[size_t(y) * P.w + x] = 1;
      }
  for (uint32_t y = 0; y < P.h; ++y)
    for (uint32_t x = 0; x < P.w; ++x)
      for (int k = -3; k <= 3 && !near[size_t(y) * P.w + x]; ++k) {
        const int yy = int(y) + k;
        if (yy >= 0 && yy < int(P.h) && rows[size_t(yy) * P.w + x]) near[size_t(y) * P.w + x] = 1;
      }
  double bare = 0;
  for (uint32_t y = y0; y <= y1; ++y)
    for (uint32_t x = x0; x <= x1; ++x) {
      const size_t i = size_t(y) * P.w + x;
      if (P.vegetation(px, i) && !foliage[i] && !near[i]) bare += 1;
    }
  return bare;
}

uint64_t gFrameNumber = 0;

// One run of the demo's frames (after its warm-up): `each` gets the frame's index, pixels and context.
Status runFrames(Device& d, const demo::Options& o, const VegetationModel& model,
                 const std::function<Status(uint32_t, const std::vector<uint8_t>&, CanopyContext*, const glm::mat4&)>& each) {
  demo::Host host;
  Status s = [&]() -> Status {
    CANOPY_TRY(demo::createHost(d, model, o, o.width, o.height, true, VK_FORMAT_UNDEFINED, &host));
    const demo::CameraRig rig = demo::defaultRig(o);
    const CameraPath path = demo::cameraPathOf(o, rig);
    std::vector<uint8_t> rgba;
    auto frame = [&](uint32_t i, bool keep) -> Status {
      CanopyFrame f;
      const LayerView view = cameraPathView(path, model.boundsMin, model.boundsMax, float(o.width) / float(o.height), i);
      f.camera = toCamera(view);
      f.dt = 1.0f / o.fps;
      f.frameNumber = ++gFrameNumber;
      CANOPY_TRY(submitAndWait(d, [&](VkCommandBuffer cmd) { return demo::recordHostFrame(host, cmd, f, nullptr, 0); }));
      if (!keep) return Status();
      demo::readPixels(host, 0, &rgba);
      return each(i, rgba, host.canopy, view.proj * view.view);
    };
    const uint32_t warmup = uint32_t(std::lround(double(o.warmupSeconds) * o.fps));
    for (uint32_t i = 0; i < warmup; ++i) CANOPY_TRY(frame(0, false));
    for (uint32_t i = 0; i < o.frames; ++i) CANOPY_TRY(frame(i, true));
    return Status();
  }();
  if (d.device) vkDeviceWaitIdle(d.device);
  demo::destroyHost(host);
  return s;
}

struct MethodResult {
  // centroid: the top third's centroid per frame of the sway pass; baseShift: the 2D method's
  // drawn foot (baseShift2D), the baseline's bottom tenth's pixels' centroid against at rest, px.
  std::vector<double> gaps, centroid, base, baseShift;
  double bare = 0;
  double gapP99() const { return quantile(gaps, 0.99); }
  double gapMax() const { return gaps.empty() ? 0.0 : *std::max_element(gaps.begin(), gaps.end()); }
  // The sway: the range of the top third's centroid between its 5th and 95th percentiles (a range's
  // ends are single frames; a gust's peak comes seconds apart: docs/performance.md "Real plants in wind").
  double sway() const { return centroid.size() < 2 ? 0.0 : quantile(centroid, 0.95) - quantile(centroid, 0.05); }
  double baseMax() const { return base.empty() ? 0.0 : *std::max_element(base.begin(), base.end()); }
  double baseShiftMax() const { return baseShift.empty() ? 0.0 : *std::max_element(baseShift.begin(), baseShift.end()); }
};

struct PlantRun {
  std::string plant, wind;
  float speed = 0;
  uint32_t leaves = 0, attached = 0;
  float height = 0, radius = 0;  // the model's bounds: height, half horizontal diagonal (the baseline's fallback trunk and crown)
  bool rigid = false;            // it has rigid parts (a trunk's base to hold)
  std::vector<PlantLevers> levers;
  std::vector<float> sway;
  MethodResult twoD, perVertex;
  double bareStill = 0;
  double bareRatio() const { return bareStill > 0 ? twoD.bare / bareStill : (twoD.bare > 0 ? INFINITY : 1.0); }
  double swayRatio() const { return perVertex.sway() > 0 ? twoD.sway() / perVertex.sway() : 0.0; }
};

// "tree:PATH" (a glTF plant) or a generated scene's name.
Status plantOptions(const std::string& plant, demo::Options* o, std::string* name) {
  if (plant.rfind("tree:", 0) == 0) {
    o->gltf = plant.substr(5);
    const size_t slash = o->gltf.find_last_of('/'), dot = o->gltf.find_last_of('.');
    const size_t b = slash == std::string::npos ? 0 : slash + 1;
    *name = o->gltf.substr(b, dot == std::string::npos || dot < b ? std::string::npos : dot - b);
    return Status();
  }
  *name = "generated " + plant;
  return parseSceneKind(plant, &o->scene);
}

// The windless frames of the 2D method: the rows measured, the base's reference, the bare rigid
// pixels at rest (with the layers in false colour).
struct StillFrames {
  Rows rows;
  std::vector<std::vector<uint8_t>> plain, layers;
  double bare = 0;
};

Status stillFrames(Device& d, const demo::Options& o, const VegetationModel& model, const Pixels& P, StillFrames* out) {
  out->plain.assign(o.frames, {});
  out->layers.assign(o.frames, {});
  demo::Options calm = o;
  calm.method = AnimationMode::Layers2D;
  calm.windSpeed = 0.0f;
  CANOPY_TRY(runFrames(d, calm, model, [&](uint32_t i, const std::vector<uint8_t>& px, CanopyContext*, const glm::mat4&) {
    out->plain[i] = px;
    return Status();
  }));
  out->rows = rowsOf(P, out->plain[0]);
  calm.debug = CompositeDebugView::Layers;
  return runFrames(d, calm, model, [&](uint32_t i, const std::vector<uint8_t>& px, CanopyContext*, const glm::mat4&) {
    out->bare += bareRigid(P, px);
    out->layers[i] = px;
    return Status();
  });
}

Pixels pixelsOf(const demo::Options& o) {
  Pixels P;
  P.w = o.width;
  P.h = o.height;
  const glm::vec3 sky = demo::skySrgb(o);
  for (int c = 0; c < 3; ++c) P.sky[c] = uint8_t(std::lround(sky[c] * 255.0f));
  return P;
}

// The sway pass (the breeze's, issue 77's bound): both methods at po.swayWidth x po.swayHeight over
// po.swayFrames frames (the top third's centroid each frame; the rows from a windless frame there).
Status measureSway(Device& d, const demo::Options& o, const VegetationModel& model, const PlantsOptions& po, PlantRun* r) {
  if (po.swayFrames == 0) return Status();
  demo::Options s = o;
  s.width = po.swayWidth;
  s.height = po.swayHeight;
  s.frames = 1;
  s.method = AnimationMode::Layers2D;
  s.windSpeed = 0.0f;
  const Pixels P = pixelsOf(s);
  Rows rows;
  CANOPY_TRY(runFrames(d, s, model, [&](uint32_t, const std::vector<uint8_t>& px, CanopyContext*, const glm::mat4&) {
    rows = rowsOf(P, px);
    return Status();
  }));
  s.frames = po.swayFrames;
  s.windSpeed = r->speed;
  for (AnimationMode method : {AnimationMode::Layers2D, AnimationMode::PerVertex}) {
    s.method = method;
    MethodResult& m = method == AnimationMode::Layers2D ? r->twoD : r->perVertex;
    CANOPY_TRY(runFrames(d, s, model, [&](uint32_t, const std::vector<uint8_t>& px, CanopyContext*, const glm::mat4&) {
      m.centroid.push_back(centroidX(P, px, rows));
      return Status();
    }));
  }
  return Status();
}

// One wind's gap, base and bare measures for both methods (po.frames frames at po.width x po.height).
Status measureWind(Device& d, const demo::Options& o, const VegetationModel& model, const PlantParts& parts, const StillFrames& still,
                   PlantRun* r) {
  const Pixels P = pixelsOf(o);
  for (AnimationMode method : {AnimationMode::Layers2D, AnimationMode::PerVertex}) {
    demo::Options run = o;
    run.windSpeed = r->speed;
    run.method = method;
    MethodResult& m = method == AnimationMode::Layers2D ? r->twoD : r->perVertex;
    CANOPY_TRY(runFrames(d, run, model, [&](uint32_t i, const std::vector<uint8_t>& px, CanopyContext* ctx, const glm::mat4& vp) {
      if (method == AnimationMode::PerVertex) {
        // The baseline's base: every pixel of the bottom tenth (it draws no false colours).
        m.base.push_back(baseChange(P, px, still.plain[i], still.rows));
        const double shift = std::abs(baseCentroid(P, px, still.rows, false) - baseCentroid(P, still.plain[i], still.rows, false));
        if (std::isfinite(shift)) m.baseShift.push_back(shift);
        gapsPerVertex(*parts.model, parts, ctx, vp, glm::vec2(o.width, o.height), &m.gaps);
        return Status();
      }
      WarpFrame f;
      CANOPY_TRY(readWarp(d, ctx, &f));
      gaps2D(*parts.model, parts, f, rigidFollows(canopyLayers(ctx)), &m.gaps);
      // RigidMotion::Still draws the wood where it stands: its foot does not move.
      const double foot = rigidFollows(canopyLayers(ctx)) ? baseShift2D(*parts.model, parts, f) : (parts.rigidAnchors.empty() ? -1.0 : 0.0);
      if (foot >= 0.0) m.baseShift.push_back(foot);
      return Status();
    }));
    if (method != AnimationMode::Layers2D) continue;
    run.debug = CompositeDebugView::Layers;
    CANOPY_TRY(runFrames(d, run, model, [&](uint32_t i, const std::vector<uint8_t>& px, CanopyContext*, const glm::mat4&) {
      m.bare += bareRigid(P, px);
      m.base.push_back(baseChange(P, px, still.layers[i], still.rows, true));
      return Status();
    }));
  }
  return Status();
}

Status measurePlant(Device& d, const PlantsOptions& po, const std::string& plant, std::vector<PlantRun>* runs) {
  demo::Options o;
  std::string name;
  CANOPY_TRY(plantOptions(plant, &o, &name));
  o.width = po.width;
  o.height = po.height;
  o.frames = po.frames;
  o.warmupSeconds = po.warmup;
  o.attachRoots = !po.before;
  o.rigidMotion = po.before ? RigidMotion::Still : RigidMotion::FollowFoliage;
  o.method = AnimationMode::PerVertex;  // the model with its hierarchy (a generated one): both methods
  VegetationModel model;
  std::string label;
  demo::SceneCopies copies;
  CANOPY_TRY(demo::loadScene(o, &model, &label, &copies));
  CanopyDesc desc;
  desc.split = o.split;
  desc.roots.attachRoots = o.attachRoots;
  PlantParts parts;
  CANOPY_TRY(plantParts(model, desc, &parts));
  StillFrames still;
  if (po.frames) CANOPY_TRY(stillFrames(d, o, model, pixelsOf(o), &still));
  for (const std::string& wind : po.winds) {
    PlantRun r;
    r.plant = name;
    r.wind = wind;
    r.speed = WorldWind{}.speed * (wind == "gale" ? po.galeFactor : 1.0f);
    r.leaves = parts.leaves;
    r.height = model.boundsMax.y - model.boundsMin.y;
    r.radius = 0.5f * glm::length(glm::vec2(model.boundsMax.x - model.boundsMin.x, model.boundsMax.z - model.boundsMin.z));
    r.attached = uint32_t(parts.attached.size());
    r.rigid = !parts.rigidAnchors.empty();
    r.levers = parts.levers;
    r.sway = parts.sway;
    r.bareStill = still.bare;
    if (po.frames) CANOPY_TRY(measureWind(d, o, model, parts, still, &r));
    if (wind == "breeze") CANOPY_TRY(measureSway(d, o, model, po, &r));  // the bound is the breeze's
    std::printf("%-26s %-6s %5u/%-6u | %6.2f %6.2f | %6.2f %6.2f | %5.1f %5.1f %5.2f | %5s %5.2f | %6.2f\n", name.c_str(),
                wind.c_str(), r.attached, r.leaves, r.twoD.gapP99(), r.twoD.gapMax(), r.perVertex.gapP99(), r.perVertex.gapMax(),
                r.twoD.sway(), r.perVertex.sway(), r.swayRatio(), r.rigid ? std::to_string(r.twoD.baseShiftMax()).substr(0, 5).c_str() : "n/a",
                r.perVertex.baseShiftMax(), r.bareRatio());
    std::fflush(stdout);
    runs->push_back(std::move(r));
  }
  return Status();
}

void writeJson(const std::string& path, const std::vector<PlantRun>& runs, const PlantsOptions& po) {
  std::ofstream f(path);
  f << "{\"size\": \"" << po.width << "x" << po.height << "\", \"frames\": " << po.frames << ", \"before\": " << (po.before ? "true" : "false")
    << ", \"runs\": [\n";
  for (size_t i = 0; i < runs.size(); ++i) {
    const PlantRun& r = runs[i];
    f << " {\"plant\": \"" << r.plant << "\", \"wind\": \"" << r.wind << "\", \"speed_mps\": " << r.speed << ", \"leaves\": " << r.leaves
      << ", \"attached\": " << r.attached << ", \"height\": " << r.height << ", \"radius\": " << r.radius;
    for (const auto& [key, m] : {std::pair<const char*, const MethodResult*>{"2d", &r.twoD}, {"pv", &r.perVertex}})
      f << ", \"" << key << "\": {\"gap_p99_px\": " << m->gapP99() << ", \"gap_max_px\": " << m->gapMax() << ", \"sway_px\": " << m->sway()
        << ", \"base_changed_max\": " << m->baseMax() << ", \"base_shift_max_px\": "
        << (m == &r.twoD && !r.rigid ? std::string("null") : std::to_string(m->baseShiftMax())) << "}";
    f << ", \"plants\": [";
    for (size_t p = 0; p < r.levers.size(); ++p)
      f << (p ? ", " : "") << "{\"trunk\": " << r.levers[p].trunk << ", \"branch\": " << r.levers[p].branch << ", \"leaf\": " << r.levers[p].leaf
        << ", \"sway_scale\": " << (p < r.sway.size() ? r.sway[p] : 1.0f) << "}";
    f << "]";
    f << ", \"sway_ratio\": " << r.swayRatio() << ", \"bare_rigid_2d\": " << r.twoD.bare << ", \"bare_rigid_still\": " << r.bareStill
      << ", \"bare_rigid_ratio\": " << r.bareRatio() << "}" << (i + 1 < runs.size() ? "," : "") << "\n";
  }
  f << "]}\n";
}

void writeTable(const std::string& path, const std::vector<PlantRun>& runs) {
  std::ofstream f(path);
  f << "| plant | wind | attached leaves | gap p99 / max, 2D | gap p99 / max, per-vertex | sway 2D / per-vertex (ratio) | base shift, 2D / "
       "per-vertex | bare rigid, gale / still |\n|---|---|---|---|---|---|---|---|\n";
  char line[512];
  for (const PlantRun& r : runs) {
    char sway[64] = "—";  // the sway pass is the breeze's
    if (!r.twoD.centroid.empty())
      std::snprintf(sway, sizeof sway, "%.1f / %.1f px (%.2f)", r.twoD.sway(), r.perVertex.sway(), r.swayRatio());
    std::snprintf(line, sizeof line, "| %s | %s | %u of %u | %.2f / %.2f px | %.2f / %.2f px | %s | %s / %.2f px | %s |\n",
                  r.plant.c_str(), r.wind.c_str(), r.attached, r.leaves, r.twoD.gapP99(), r.twoD.gapMax(), r.perVertex.gapP99(),
                  r.perVertex.gapMax(), sway,
                  r.rigid ? std::to_string(r.twoD.baseShiftMax()).substr(0, 4).c_str() : "n/a", r.perVertex.baseShiftMax(),
                  r.wind == "gale" ? (std::to_string(r.bareRatio()).substr(0, 4)).c_str() : "-");
    f << line;
  }
}

}  // namespace

int runPlantsBench(Device& d, const PlantsOptions& po) {
  std::printf("\nReal plants in wind (%ux%u, %u frames after a %.0f s warm-up, canopy-demo's camera; %s). Gap: a leaf's root against\n"
              "the rigid point it grows from on screen, less the same at rest (px); sway: the top third's centroid, 5th to 95th\n"
              "percentile over %u frames at %ux%u in the breeze (px); base: the largest shift of a rigid vertex in the bottom 5 %% of the plant as\n"
              "drawn (px; n/a: no rigid part; per-vertex: its bottom tenth's pixels' centroid); bare: rigid pixels in the crown > 3 px\n"
              "from foliage, gale / still.\n",
              po.width, po.height, po.frames, double(po.warmup), po.before ? "before issue 77: still background, paper roots" : "as shipped",
              po.swayFrames, po.swayWidth, po.swayHeight);
  std::printf("%-26s %-6s %-12s | %-13s | %-13s | %-17s | %-11s | %s\n", "plant", "wind", "attached", "2D gap p99/max",
              "pv gap p99/max", "sway 2D/pv ratio", "base px 2D/pv", "bare");
  std::vector<PlantRun> runs;
  for (const std::string& p : po.plants) {
    if (p.rfind("tree:", 0) == 0 && !std::ifstream(p.substr(5)).good()) {
      std::printf("%-26s skipped: %s is absent\n", p.substr(5).c_str(), p.substr(5).c_str());
      continue;
    }
    const Status s = measurePlant(d, po, p, &runs);
    if (!s.ok()) {
      std::fprintf(stderr, "canopy-bench plants: %s: %s\n", p.c_str(), s.message().c_str());
      return 1;
    }
  }
  if (!po.json.empty()) {
    writeJson(po.json, runs, po);
    std::printf("wrote %s\n", po.json.c_str());
  }
  if (!po.table.empty()) {
    writeTable(po.table, runs);
    std::printf("wrote %s\n", po.table.c_str());
  }
  if (!po.check) return 0;
  // Issue 77's bounds: the gap's p99 <= 1 px in a breeze and <= 2 px in a gale; the sway within
  // [0.67, 1.5] of the baseline's (real plants: not a generated one); bare rigid pixels gale / still
  // <= 1.3; the trunk's base still (its centroid within 0.5 px of the windless frame's).
  int bad = 0;
  for (const PlantRun& r : runs) {
    const double gapBound = r.wind == "gale" ? 2.0 : 1.0;
    if (r.attached && r.twoD.gapP99() > gapBound) {
      std::printf("check: %s %s: gap p99 %.2f px > %.1f\n", r.plant.c_str(), r.wind.c_str(), r.twoD.gapP99(), gapBound);
      ++bad;
    }
    if (r.rigid && r.twoD.baseShiftMax() > 0.5) {
      std::printf("check: %s %s: the trunk's base moved %.2f px > 0.5\n", r.plant.c_str(), r.wind.c_str(), r.twoD.baseShiftMax());
      ++bad;
    }
    if (po.swayFrames && r.wind == "breeze" && r.plant.rfind("generated", 0) != 0 && (r.swayRatio() < 0.67 || r.swayRatio() > 1.5)) {
      std::printf("check: %s breeze: sway 2D / per-vertex %.2f outside [0.67, 1.5]\n", r.plant.c_str(), r.swayRatio());
      ++bad;
    }
    if (r.wind == "gale" && r.bareRatio() > 1.3) {
      std::printf("check: %s gale: bare rigid pixels %.2f x the still frame's > 1.3\n", r.plant.c_str(), r.bareRatio());
      ++bad;
    }
  }
  std::printf(bad ? "plants: %d checks outside issue 77's bounds\n" : "plants: every run within issue 77's bounds (%d)\n",
              bad ? bad : int(runs.size()));
  return bad ? 1 : 0;
}

}  // namespace canopy::bench
