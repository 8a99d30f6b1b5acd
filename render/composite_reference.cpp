#include "render/composite_reference.h"

#include <algorithm>
#include <cmath>

namespace canopy {
namespace {

struct Texels {
  const CompositeReferenceInputs& in;
  uint32_t w, h;  // the layer images
  glm::vec4 color(uint32_t layer, int x, int y) const {
    if (x < 0 || y < 0 || x >= int(w) || y >= int(h)) return glm::vec4(0.0f);
    return in.layerColor[(size_t(layer) * h + y) * w + x];
  }
  float depth(uint32_t layer, int x, int y) const {
    if (x < 0 || y < 0 || x >= int(w) || y >= int(h)) return 1.0f;
    return in.layerDepth[(size_t(layer) * h + y) * w + x];
  }
  // The depth search's depth at layer pixel q of a layer read at texel scale `scale` (half
  // resolution): the nearest of the bilinear footprint's texels, or the nearest texel's; the
  // background's (layer COMPOSITE_VIEW_BACKGROUND) at its nearest texel.
  float depthAt(uint32_t layer, const glm::vec2& q, float scale, bool bilinear) const {
    if (layer == COMPOSITE_VIEW_BACKGROUND) {
      const int x = int(std::floor(q.x)), y = int(std::floor(q.y));
      if (q.x < 0.0f || q.y < 0.0f || x >= int(w) || y >= int(h)) return 1.0f;
      return in.backgroundDepth[size_t(y) * w + x];
    }
    const glm::vec2 t = q * scale;
    if (!bilinear) return depth(layer, int(std::floor(t.x)), int(std::floor(t.y)));
    const int x0 = int(std::floor(t.x - 0.5f)), y0 = int(std::floor(t.y - 0.5f));
    return std::min(std::min(depth(layer, x0, y0), depth(layer, x0 + 1, y0)), std::min(depth(layer, x0, y0 + 1), depth(layer, x0 + 1, y0 + 1)));
  }
};

glm::vec2 displacementAt(const std::vector<glm::vec2>& d, uint32_t base, const gpu::GridSample& g) {
  return gpu::blendCorners(g, d[base + g.i00], d[base + g.i10], d[base + g.i01], d[base + g.i11]);
}

// Plane i's homogeneous layer pixel under p (shared/composite.h, CompositeView).
glm::vec3 planePoint(const gpu::CompositeView& v, uint32_t i, const glm::vec2& p) {
  return gpu::compositeHomogeneous(v.homography[3 * i], v.homography[3 * i + 1], v.homography[3 * i + 2], p);
}

}  // namespace

void compositeReference(const gpu::CompositePush& pc, const CompositeReferenceInputs& in, CompositeReferenceOutputs* out) {
  const uint32_t w = in.width, h = in.height, n = in.layers;
  const uint32_t lw = in.layerWidth ? in.layerWidth : w, lh = in.layerHeight ? in.layerHeight : h;
  const Texels tex{in, lw, lh};
  const glm::vec2 origin(pc.originX, pc.originY), outSize{float(w), float(h)};
  const bool bilinear = (pc.flags & COMPOSITE_BILINEAR) != 0;
  const uint32_t corners = pc.gridX * pc.gridY;
  out->color.assign(size_t(w) * h, glm::vec4(0.0f));
  out->depth.assign(size_t(w) * h, 1.0f);
  out->motion.assign(size_t(w) * h, glm::vec2(0.0f));
  out->vegetationFront.assign(size_t(w) * h, 0);
  for (uint32_t y = 0; y < h; ++y)
    for (uint32_t x = 0; x < w; ++x) {
      const size_t pix = size_t(y) * w + x;
      const glm::vec2 p(float(x) + 0.5f, float(y) + 0.5f);
      const float sceneRaw = (pc.flags & COMPOSITE_SCENE_DEPTH) ? in.sceneDepth[pix] : gpu::compositeStandardDepth(pc.flags, 1.0f);
      const float sceneZ = (pc.flags & COMPOSITE_SCENE_DEPTH) ? gpu::compositeStandardDepth(pc.flags, sceneRaw) : 1.0f;
      glm::vec4 bg(0.0f);
      float bgZ = 1.0f;
      const bool reproject = (pc.flags & COMPOSITE_REPROJECT) != 0;
      const glm::vec2 size{float(lw), float(lh)};
      const glm::vec4 rayA = reproject ? gpu::compositeRayOrigin(in.view.currentToSlice, p, outSize) : glm::vec4(0.0f);
      const glm::vec4 rayB = in.view.currentToSlice[2];
      // The depth search of layer i (or the background), as composite_search.glsl: false where
      // nothing is found; *s the plane's point on entry, the layer pixel shown on return, *z the
      // slice depth shown there (the found sample's; the plane's point's without a search).
      auto depthSearch = [&](uint32_t i, const glm::vec2& d, glm::vec2* s, float* z) {
        const gpu::CompositeRay ray = gpu::compositeRaySearch(rayA, rayB, in.view.search[i], *s, size);
        const float scale = i == COMPOSITE_VIEW_BACKGROUND ? 1.0f : gpu::layerTexelScale(pc.halfResolution, i);
        *z = 1.0f;
        if (ray.steps == 0) {
          *z = tex.depthAt(i, *s - d, scale, bilinear);
          return *z < 1.0f;
        }
        for (uint32_t k = 0; k < ray.steps; ++k) {
          const glm::vec4 x = gpu::compositeRaySample(ray, k, size);
          const float zt = x.w > 0.0f ? tex.depthAt(i, glm::vec2(x) - d, scale, bilinear) : 1.0f;
          const glm::vec3 c = gpu::compositeRayCrossing(ray, k, zt, size);
          if (zt < 1.0f && c.z > 0.0f) {
            *s = glm::vec2(c);
            *z = zt;
            return true;
          }
        }
        return false;
      };
      if ((pc.flags & COMPOSITE_BACKGROUND) && !in.backgroundColor.empty()) {
        int bx = int(std::floor(float(x) + 0.5f + origin.x)), by = int(std::floor(float(y) + 0.5f + origin.y));  // a jitter makes origin fractional
        bool inside = true;
        float searched = 1.0f;  // the search's depth (reprojected)
        if (reproject) {
          const glm::vec3 hp = planePoint(in.view, COMPOSITE_VIEW_BACKGROUND, p);
          glm::vec2 s = glm::vec2(hp) / hp.z;
          inside = hp.z > 0.0f && depthSearch(COMPOSITE_VIEW_BACKGROUND, glm::vec2(0.0f), &s, &searched);
          bx = int(std::floor(s.x));
          by = int(std::floor(s.y));
          inside = inside && s.x >= 0.0f && s.y >= 0.0f && s.x < size.x && s.y < size.y;
        }
        if (inside) {
          const size_t b = size_t(by) * lw + size_t(bx);
          bg = in.backgroundColor[b];
          bgZ = bg.a > 0.0f ? in.backgroundDepth[b] : 1.0f;
          if (reproject && bg.a > 0.0f)
            bgZ = gpu::compositeClipDepth(gpu::compositeClipOf(in.view.sliceToCurrent, glm::vec2(bx, by) + 0.5f, searched, size));
        }
      }
      if (bgZ >= sceneZ) {
        bg = glm::vec4(0.0f);
        bgZ = 1.0f;
      }
      const float opaqueZ = std::min(sceneZ, bgZ);
      glm::vec2 s = p + origin;  // the layer pixel under p (the slice camera's)
      gpu::GridSample g = gpu::gridSample(pc, s);
      glm::vec4 acc(0.0f);
      float frontZ = 1.0f;
      bool front = false;
      glm::vec2 motion(0.0f);
      for (uint32_t i = 0; i < n; ++i) {
        if (reproject) {
          const glm::vec3 hp = planePoint(in.view, i, p);
          if (hp.z <= 0.0f) continue;
          s = glm::vec2(hp) / hp.z;
          g = gpu::gridSample(pc, s);
        }
        const glm::vec2 d = displacementAt(in.displacement, i * corners, g);
        float searched = 1.0f;
        if (reproject && !depthSearch(i, d, &s, &searched)) continue;
        glm::vec2 q = s - d;
        // Texel space: centres at integer + 0.5; a layer at half resolution holds pixel q at q / 2.
        if (bilinear) q = gpu::compositeSharpPoint(q, pc.sharpness);  // the warp's sharp filter (composite.h)
        const glm::vec2 tq = q * gpu::layerTexelScale(pc.halfResolution, i);
        const glm::vec2 t = tq - 0.5f;
        const int x0 = int(std::floor(t.x)), y0 = int(std::floor(t.y));
        const float fx = t.x - float(x0), fy = t.y - float(y0);
        glm::vec4 c;
        float z;
        if (bilinear) {
          c = (tex.color(i, x0, y0) * (1 - fx) + tex.color(i, x0 + 1, y0) * fx) * (1 - fy) +
              (tex.color(i, x0, y0 + 1) * (1 - fx) + tex.color(i, x0 + 1, y0 + 1) * fx) * fy;
          z = std::min(std::min(tex.depth(i, x0, y0), tex.depth(i, x0 + 1, y0)),
                       std::min(tex.depth(i, x0, y0 + 1), tex.depth(i, x0 + 1, y0 + 1)));
        } else {
          const int xn = int(std::floor(tq.x)), yn = int(std::floor(tq.y));
          c = tex.color(i, xn, yn);
          z = tex.depth(i, xn, yn);
        }
        if (reproject) z = searched;  // the depth the search found
        if (c.a < COMPOSITE_MIN_ALPHA) continue;
        if (bilinear && c.a < 1.0f - COMPOSITE_EDGE_TOLERANCE) {  // an edge: cut at 1/2 (composite.h)
          c = gpu::compositeSharpenEdge(c, glm::vec4(tex.color(i, x0, y0).a, tex.color(i, x0 + 1, y0).a, tex.color(i, x0, y0 + 1).a,
                                                     tex.color(i, x0 + 1, y0 + 1).a));
          if (c.a < COMPOSITE_MIN_ALPHA) continue;
        }
        const float zSlice = z;
        glm::vec4 clip(0.0f);
        if (reproject) {
          clip = gpu::compositeClipOf(in.view.sliceToCurrent, s, z, size);
          z = gpu::compositeClipDepth(clip);
        }
        if (z >= opaqueZ) continue;
        acc = gpu::underPremultiplied(acc, c);
        if (!front && c.a >= pc.depthAlpha) {
          front = true;
          frontZ = z;
          if (pc.flags & COMPOSITE_MOTION_VALID) {
            const glm::vec2 dPrev = displacementAt(in.previous, i * corners, g);
            motion = reproject ? gpu::compositeClipPixel(clip, outSize) -
                                     gpu::compositeClipPixel(gpu::compositeClipOf(in.view.sliceToPrevious, s - d + dPrev, zSlice, size), outSize)
                               : d - dPrev;
          }
        }
        if ((pc.flags & COMPOSITE_EARLY_EXIT) && acc.a >= COMPOSITE_OPAQUE) break;
      }
      acc = gpu::underPremultiplied(acc, bg);
      const glm::vec4 scene = in.sceneColor.empty() ? glm::vec4(0.0f) : in.sceneColor[pix];
      // The pipeline's premultiplied blend of the exposed vegetation colour.
      out->color[pix] = glm::vec4(glm::vec3(acc) * pc.exposure, acc.a) + (1.0f - acc.a) * scene;
      const float vegZ = std::min(frontZ, bgZ);
      out->depth[pix] = vegZ < sceneZ ? gpu::compositeStandardDepth(pc.flags, vegZ) : sceneRaw;
      const bool vegFront = front && frontZ < bgZ;
      out->vegetationFront[pix] = vegFront;
      if (vegFront) out->motion[pix] = motion;
    }
}

}  // namespace canopy
