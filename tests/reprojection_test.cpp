// Reprojection of a layer between re-slices (render/reprojection.h): the slab plane's homography
// takes a pixel of the current camera to the slice camera's pixel of the same plane point; for a
// pure rotation it is exact at every depth (no re-slice needed); off the plane under translation the
// error is the parallax of the distance to the plane.
#include <cmath>
#include <cstdio>
#include <random>

#include <glm/glm.hpp>
#include <glm/gtc/matrix_transform.hpp>
#include <gtest/gtest.h>

#include "engine/camera.h"
#include "render/reprojection.h"
#include "tools/camera_paths.h"

namespace canopy {
namespace {

const glm::vec3 kMin(-1.0f, 0.0f, -1.0f), kMax(1.0f, 2.0f, 1.0f);
const glm::dvec2 kSize(1024, 768);

// Pixel (y down, centres at +0.5) and view depth of world point x seen by `v`.
glm::dvec2 pixelOf(const LayerView& v, const glm::dvec3& x, const glm::dvec2& size = kSize) {
  const glm::dvec4 c = glm::dmat4(v.proj) * glm::dmat4(v.view) * glm::dvec4(x, 1.0);
  return (glm::dvec2(c) / c.w + 1.0) * 0.5 * size;
}
double viewDepth(const LayerView& v, const glm::dvec3& x) { return -(glm::dmat4(v.view) * glm::dvec4(x, 1.0)).z; }
// The world point at view depth `depth` on the ray of pixel p of `v`.
glm::dvec3 pointAt(const LayerView& v, const glm::dvec2& p, double depth) {
  const glm::dvec2 ndc = p / kSize * 2.0 - 1.0;
  const glm::dmat4 inv = glm::inverse(glm::dmat4(v.proj) * glm::dmat4(v.view));
  const glm::dvec4 a = inv * glm::dvec4(ndc, 0.0, 1.0), b = inv * glm::dvec4(ndc, 1.0, 1.0);
  const glm::dvec3 x0 = glm::dvec3(a) / a.w, x1 = glm::dvec3(b) / b.w;
  const double d0 = viewDepth(v, x0), d1 = viewDepth(v, x1);
  return x0 + (x1 - x0) * ((depth - d0) / (d1 - d0));
}

LayerView along(CameraMotion m, uint32_t frame, float degrees = 0.25f, float radii = 0.005f) {
  CameraPath p;
  p.motion = m;
  p.degreesPerFrame = degrees;
  p.radiiPerFrame = radii;
  return cameraPathView(p, kMin, kMax, float(kSize.x / kSize.y), frame);
}

TEST(Reprojection, TheSlabPlaneMapsExactly) {
  const LayerView slice = along(CameraMotion::Still, 0);
  const double depth = viewDepth(slice, glm::dvec3(0.0, 1.0, 0.0));
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(0.1, 0.9);
  for (CameraMotion m : {CameraMotion::Orbit, CameraMotion::Dolly, CameraMotion::Strafe, CameraMotion::Turn, CameraMotion::Zoom}) {
    const LayerView current = along(m, 20);
    const glm::dmat3 h = layerHomography(slice, current, depth, kSize, kSize);
    for (int k = 0; k < 50; ++k) {
      const glm::dvec3 x = pointAt(slice, glm::dvec2(u(rng), u(rng)) * kSize, depth);
      const glm::dvec2 got = applyHomography(h, pixelOf(current, x)), want = pixelOf(slice, x);
      EXPECT_LT(glm::length(got - want), 1e-3) << cameraMotionName(m) << " point " << k;
      EXPECT_GT((h * glm::dvec3(pixelOf(current, x), 1.0)).z, 0.0) << cameraMotionName(m);
    }
  }
  // The same camera: the identity.
  const glm::dmat3 id = layerHomography(slice, slice, depth, kSize, kSize);
  EXPECT_LT(glm::length(applyHomography(id, glm::dvec2(100.5, 700.5)) - glm::dvec2(100.5, 700.5)), 1e-6);
  // A layer image twice the size: the same point at twice the pixel coordinates.
  const glm::dmat3 big = layerHomography(slice, slice, depth, kSize, 2.0 * kSize);
  EXPECT_LT(glm::length(applyHomography(big, glm::dvec2(100.5, 700.5)) - glm::dvec2(201.0, 1401.0)), 1e-6);
}

TEST(Reprojection, APureRotationIsExactAtEveryDepth) {
  const LayerView slice = along(CameraMotion::Turn, 0), current = along(CameraMotion::Turn, 16, 0.25f);  // 4 degrees
  const double plane = viewDepth(slice, glm::dvec3(0.0, 1.0, 0.0));
  const glm::dmat3 h = layerHomography(slice, current, plane, kSize, kSize);
  for (double depth : {0.6 * plane, plane, 1.4 * plane}) {
    const glm::dvec3 x = pointAt(slice, glm::dvec2(300.5, 400.5), depth);
    EXPECT_LT(glm::length(applyHomography(h, pixelOf(current, x)) - pixelOf(slice, x)), 1e-3) << depth;
  }
}

TEST(Reprojection, OffThePlaneTheErrorIsTheParallax) {
  // A translation: a point at the plane's depth + delta lands off by about the parallax
  // |t| f delta / z^2 (small motion), which grows with delta.
  const LayerView slice = along(CameraMotion::Strafe, 0), current = along(CameraMotion::Strafe, 10, 0.25f, 0.01f);
  const double plane = viewDepth(slice, glm::dvec3(0.0, 1.0, 0.0));
  const glm::dmat3 h = layerHomography(slice, current, plane, kSize, kSize);
  double last = 0.0;
  for (double delta : {0.0, 0.05, 0.1, 0.2}) {
    const glm::dvec3 x = pointAt(slice, 0.5 * kSize, plane + delta);
    const double err = glm::length(applyHomography(h, pixelOf(current, x)) - pixelOf(slice, x));
    if (delta == 0.0) EXPECT_LT(err, 1e-3);
    else EXPECT_GT(err, last);
    last = err;
  }
  const double moved = glm::length(viewPosition(current.view) - viewPosition(slice.view));
  const double focal = 0.5 * kSize.y * double(slice.proj[1][1]);
  EXPECT_NEAR(last, moved * std::fabs(focal) * 0.2 / (plane * (plane + 0.2)), 0.2 * last);
}

TEST(Reprojection, ClipToClipCarriesAWorldPoint) {
  const LayerView a = along(CameraMotion::Still, 0), b = along(CameraMotion::Orbit, 30);
  const glm::dvec3 x(0.2, 1.3, -0.4);
  const glm::dvec4 ca = glm::dmat4(a.proj) * glm::dmat4(a.view) * glm::dvec4(x, 1.0);
  const glm::dvec4 cb = glm::dmat4(b.proj) * glm::dmat4(b.view) * glm::dvec4(x, 1.0);
  const glm::dvec4 got = clipToClip(a, b) * (ca / ca.w);
  EXPECT_LT(glm::length(glm::dvec3(got) / got.w - glm::dvec3(cb) / cb.w), 1e-9);
}

// The policy's estimate (estimateReprojectionError) against the parallax in closed form: a strafe
// by t parallel to the image plane shifts a point at view depth z by f t / z pixels (f the focal
// length in pixels), so a point of the slab [zNear, zFar] shown on its plane at depth z_p is off by
// f t |1/z - 1/z_p| everywhere in the image; the estimate is its mean over the slab's depths (the
// same midpoints). A path strafing a fixed step per frame crosses a threshold at a frame known in
// advance.
TEST(Reprojection, TheEstimatedErrorIsTheStrafesParallaxAndCrossesTheThresholdWhereExpected) {
  const LayerView slice = along(CameraMotion::Still, 0);
  const double zp = viewDepth(slice, glm::dvec3(0.0, 1.0, 0.0));
  const std::vector<SlabRange> slabs = {{float(zp - 0.3), float(zp + 0.5), float(zp)}};
  const double f = 0.5 * kSize.y * double(slice.proj[1][1] < 0 ? -slice.proj[1][1] : slice.proj[1][1]);
  double perUnit = 0;
  for (int k = 0; k < kDepthSamples; ++k) perUnit += f * std::abs(1.0 / (zp - 0.3 + 0.8 * (k + 0.5) / kDepthSamples) - 1.0 / zp);
  perUnit /= kDepthSamples;
  const double step = 0.0005;  // world units a frame, along the view's right axis
  auto strafed = [&](int frame) {
    LayerView v = slice;
    v.view[3][0] -= float(step * frame);  // the eye moves +x in view space: the world moves -x
    return v;
  };
  const double threshold = 1.0;
  const int expected = int(std::floor(threshold / (perUnit * step))) + 1;  // first frame beyond
  ASSERT_GT(expected, 3);
  for (int k = 1; k <= expected + 2; ++k) {
    const ReprojectionError e = estimateReprojectionError(slice, strafed(k), slabs, kMin, kMax, kSize, kSize);
    EXPECT_NEAR(e.parallaxPx, perUnit * step * k, 1e-3 * perUnit * step * k) << "frame " << k;
    EXPECT_EQ(e.parallaxPx > threshold, k >= expected) << "frame " << k << ": " << e.parallaxPx << " px";
  }
}

TEST(Reprojection, APureRotationEstimatesNoErrorWhileTheVegetationStaysInTheImage) {
  const LayerView slice = along(CameraMotion::Still, 0);
  const double zp = viewDepth(slice, glm::dvec3(0.0, 1.0, 0.0));
  const std::vector<SlabRange> slabs = {{float(zp - 1.0), float(zp - 0.2), float(zp - 0.6)}, {float(zp - 0.2), float(zp + 1.0), float(zp + 0.4)}};
  for (uint32_t frame : {1u, 4u, 8u}) {
    const ReprojectionError e = estimateReprojectionError(slice, along(CameraMotion::Turn, frame), slabs, kMin, kMax, kSize, kSize);
    EXPECT_LT(e.parallaxPx, 1e-3) << "frame " << frame;
    EXPECT_LT(e.turnDegrees, 1e-3) << "the eye stays: the vegetation is seen from the same direction";
    EXPECT_LT(e.magnification, 1.02);
  }
  // A zoom keeps the eye too, but magnifies the layers' texels.
  const ReprojectionError z = estimateReprojectionError(slice, along(CameraMotion::Zoom, 20, 1.0f), slabs, kMin, kMax, kSize, kSize);
  EXPECT_LT(z.parallaxPx, 1e-3);
  EXPECT_NE(z.magnification, 1.0);
}

// The guard band (docs/design.md "Layers: guard band"): the slice camera widened by guardedView
// shows every world point at its output pixel plus the guard, so a still camera reads the layers at
// p + guard; content a turn brings in from beyond the output's edge is in the layer images until the
// turn leaves the guard band, and the policy's "content beyond the layers" says so.
TEST(Reprojection, TheGuardBandShowsTheOutputOffsetAndHoldsWhatATurnBringsIn) {
  const glm::uvec2 out(kSize), guard(96, 80), layer = out + 2u * guard;
  const LayerView v = along(CameraMotion::Orbit, 7);
  const LayerView g = guardedView(v, out, guard);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int k = 0; k < 64; ++k) {
    const glm::dvec3 x(u(rng), 1.0 + u(rng), u(rng));
    const glm::dvec2 d = pixelOf(g, x, glm::dvec2(layer)) - (pixelOf(v, x) + glm::dvec2(guard));
    EXPECT_LT(glm::length(d), 1e-3) << "point " << k;
  }
  EXPECT_TRUE(sameCamera(guardedView(v, out, glm::uvec2(0)), v)) << "no guard band: the camera itself";
  // A camera turned 20 degrees away from the vegetation (cut by the output's edge), then turning back
  // a degree a frame (content from beyond the edge comes into view): without a guard band the
  // policy sees content beyond the layers from the first degree; with one, the same error less the
  // band's width, so none for the first few degrees.
  const LayerView base = along(CameraMotion::Still, 0);
  auto turned = [&](float degrees) {
    LayerView t = base;
    t.view = glm::mat4(glm::rotate(glm::dmat4(1.0), glm::radians(double(degrees)), glm::dvec3(0, 1, 0))) * t.view;
    return t;
  };
  const LayerView slice = turned(20.0f), sliceGuarded = guardedView(slice, out, guard);
  const std::vector<SlabRange> slabs = {{4.0f, 5.0f, 4.5f}};
  int inBand = 0, beyondBand = 0;
  for (int k = 1; k <= 20; ++k) {
    const LayerView current = turned(20.0f - float(k));
    const ReprojectionError e0 = estimateReprojectionError(slice, current, slabs, kMin, kMax, kSize, kSize);
    const ReprojectionError eg = estimateReprojectionError(sliceGuarded, current, slabs, kMin, kMax, glm::dvec2(layer), kSize);
    EXPECT_LT(eg.parallaxPx, 1e-3);
    EXPECT_NEAR(eg.magnification, e0.magnification, 1e-3);
    EXPECT_NEAR(eg.outsidePx, std::max(0.0, e0.outsidePx - double(guard.x)), 1.0) << k << " degrees";
    EXPECT_GT(e0.outsidePx, 1.0) << k << " degrees";
    inBand += eg.outsidePx <= 1.0;
    beyondBand += eg.outsidePx > 1.0;
  }
  EXPECT_GE(inBand, 3) << "a turn of a few degrees stays within a 96-pixel band";
  EXPECT_GT(beyondBand, 0);
}

// The depth search (shared/composite.h compositeRayCrossing, float as on the GPU): a current pixel's
// ray meets a slice texel's depth where the slice camera saw that point, for every camera path
// that moves the eye (a pure rotation or zoom: the plane's own pixel, whatever the depth, which the
// short path shows without a search).
TEST(Reprojection, TheDepthSearchFindsAPointAtItsOwnDepth) {
  const LayerView slice = along(CameraMotion::Still, 0);
  const double mid = viewDepth(slice, glm::dvec3(0.0, 1.0, 0.0));
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(0.1, 0.9), dz(-1.0, 1.0);
  for (CameraMotion m : {CameraMotion::Orbit, CameraMotion::Dolly, CameraMotion::Strafe, CameraMotion::Turn, CameraMotion::Zoom}) {
    const LayerView current = along(m, 20);
    const gpu::CompositeView v = compositeView(slice, current, current, {float(mid)}, float(mid), kSize, kSize,
                                               {LayerSearch{float(mid - 1.0), float(mid + 1.0)}}, 16);
    if (m == CameraMotion::Turn || m == CameraMotion::Zoom) {  // the eye stays put: every depth lands on the plane's pixel
      EXPECT_EQ(v.search[0].z, 0.0f) << cameraMotionName(m) << " takes the plane alone (the short path)";
      continue;
    }
    EXPECT_GE(v.search[0].z, 2.0f) << cameraMotionName(m);
    const glm::dmat4 sliceVP = glm::dmat4(slice.proj) * glm::dmat4(slice.view);
    double worst = 0.0;
    int shortPath = 0;
    for (int k = 0; k < 200; ++k) {
      const glm::dvec3 x = pointAt(slice, glm::dvec2(u(rng), u(rng)) * kSize, mid + dz(rng));
      const glm::dvec4 c = sliceVP * glm::dvec4(x, 1.0);
      const float z = float(c.z / c.w);  // what the layer texel holds
      const glm::vec2 p(pixelOf(current, x));
      const glm::vec3 h = gpu::compositeHomogeneous(v.homography[0], v.homography[1], v.homography[2], p);
      const glm::vec2 plane = glm::vec2(h) / h.z;
      const gpu::CompositeRay ray = gpu::compositeRaySearch(gpu::compositeRayOrigin(v.currentToSlice, p, glm::vec2(kSize)),
                                                            v.currentToSlice[2], v.search[0], plane, glm::vec2(kSize));
      if (ray.steps == 0) {  // this pixel's range lands within the short path's bound of its plane point
        ++shortPath;
        EXPECT_LT(glm::length(glm::dvec2(plane) - pixelOf(slice, x)), kShortPathPx + 1e-3) << cameraMotionName(m);
        continue;
      }
      const glm::vec3 got = gpu::compositeRayCrossing(ray, ray.steps - 1, z, glm::vec2(kSize));
      ASSERT_GT(got.z, 0.0f) << cameraMotionName(m);
      worst = std::max(worst, glm::length(glm::dvec2(got.x, got.y) - pixelOf(slice, x)));
    }
    EXPECT_LT(worst, 0.02) << cameraMotionName(m) << ": layer pixels off the slice camera's";
    EXPECT_LT(shortPath, 100) << cameraMotionName(m) << ": most points searched";
    std::printf("  %s: the crossing at most %.4f layer pixels off (%d of 200 points on the short path)\n", cameraMotionName(m),
                worst, shortPath);
  }
}

// The depth search's length per layer (compositeView): a thin slab under a small motion since the
// slice lands within kShortPathPx of its plane and takes the homography alone (no samples); a
// thick slab under a large motion takes the full search (maxSteps samples); between them the
// samples grow with the parallax, two layer pixels apart.
TEST(Reprojection, AThinSlabUnderASmallMotionTakesTheShortPathAndAThickOneTheFullSearch) {
  const LayerView slice = along(CameraMotion::Still, 0);
  const double mid = viewDepth(slice, glm::dvec3(0.0, 1.0, 0.0));
  auto searchOf = [&](CameraMotion m, uint32_t frame, double halfThickness) {
    const LayerView current = along(m, frame);
    const gpu::CompositeView v = compositeView(slice, current, current, {float(mid)}, float(mid), kSize, kSize,
                                               {LayerSearch{float(mid - halfThickness), float(mid + halfThickness)}}, 16);
    return v.search[0];
  };
  for (CameraMotion m : {CameraMotion::Orbit, CameraMotion::Dolly, CameraMotion::Strafe}) {
    const glm::vec4 thin = searchOf(m, 1, 0.005), thick = searchOf(m, 60, 1.0);
    std::printf("  %s: a slab 0.01 deep one frame after the slice: %.0f samples; 2.0 deep 60 frames after: %.0f samples, "
                "reach %.1f layer px\n", cameraMotionName(m), double(thin.z), double(thick.z), double(thick.w));
    EXPECT_EQ(thin.z, 0.0f) << cameraMotionName(m) << ": the short path";
    EXPECT_EQ(thick.z, 16.0f) << cameraMotionName(m) << ": the full search";
    // Between them the samples never fall as the parallax grows (the slab thickens).
    float last = 0.0f;
    for (double h : {0.005, 0.02, 0.05, 0.1, 0.2, 0.5, 1.0}) {
      const float steps = searchOf(m, 20, h).z;
      EXPECT_GE(steps, last) << cameraMotionName(m) << " half thickness " << h;
      last = steps;
    }
  }
  // Whatever the thickness, a pure rotation or zoom is the plane's homography exactly: the short path.
  EXPECT_EQ(searchOf(CameraMotion::Turn, 60, 1.0).z, 0.0f);
  EXPECT_EQ(searchOf(CameraMotion::Zoom, 60, 1.0).z, 0.0f);
}

}  // namespace
}  // namespace canopy
