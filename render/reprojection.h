#pragma once
// Reprojection of the layers between re-slices (docs/design.md "Layers: reprojection"): a layer
// image holds a depth slab as the slice camera saw it; a pixel of the current camera reads it
// through the homography of the slab's plane (exact on the plane; off it, the error grows with
// the slab's thickness times the parallax between the two cameras).
#include <vector>
#include <glm/glm.hpp>

#include "engine/camera.h"
#include "shared/composite.h"

namespace canopy {

// The homography taking a pixel of the current camera's image (`outSize`, pixel centres at +0.5,
// y down) to the pixel of the slice camera's layer image (`layerSize`) that shows the same point
// of the plane at view depth `depth` (world units) of the slice camera. Homogeneous: the third
// coordinate of H * (x, y, 1) is > 0 where the plane point is in front of both cameras.
glm::dmat3 layerHomography(const LayerView& slice, const LayerView& current, double depth, const glm::dvec2& outSize,
                           const glm::dvec2& layerSize);

// Clip coordinates of camera `from` to clip coordinates of camera `to` for the same world point
// (the slice camera's depth to the current camera's, the current camera's to the previous frame's).
glm::dmat4 clipToClip(const LayerView& from, const LayerView& to);

// A pixel through a homography (the point at infinity maps to a huge value; check w with the
// homogeneous product when it matters).
glm::dvec2 applyHomography(const glm::dmat3& h, const glm::dvec2& p);

// Whether two cameras are the same, bit for bit (then the composite reads layer pixel = pixel).
bool sameCamera(const LayerView& a, const LayerView& b);

// Layer i's depth search (shared/composite.h compositeRaySearch): the slice camera's view depths
// between which the layer's texels lie (its vertices' range, widened a little; a reversed or
// unknown range searches nothing).
struct LayerSearch {
  float zNear = 0, zFar = 0;
};
// The composite's view block: layer i's plane at slice-camera view depth `layerDepths[i]`, the
// rigid background's at `backgroundDepth`; the output of `outSize` pixels, the layer images of
// `layerSize` (the slice camera's, guard band included). `search` (one per layer, or empty) and
// `maxSteps` (CompositeParams.depthSearchSteps; 0: the planes alone): the depth search's most
// samples per layer over the image, a sample every two layer pixels the ray crosses between the
// range's ends, at most maxSteps, none where the range lands within kShortPathPx of the plane (the
// short path) — each pixel then takes what its own ray needs (shared/composite.h compositeRaySearch);
// `backgroundSearch` the rigid background's (its vertices' depths).
gpu::CompositeView compositeView(const LayerView& slice, const LayerView& current, const LayerView& previous,
                                 const std::vector<float>& layerDepths, float backgroundDepth, const glm::dvec2& outSize,
                                 const glm::dvec2& layerSize, const std::vector<LayerSearch>& search = {},
                                 uint32_t maxSteps = 0, const LayerSearch& backgroundSearch = {});

// The reprojection's estimated screen error (pixels of the current camera) of showing layers drawn
// from `slice` from `current` (docs/design.md "Layers: reprojection", the policy):
struct ReprojectionError {
  double parallaxPx = 0;   // how far a point of a slab (uniform over its depth range) lands off its
                           // plane's mapping, on average; the largest over the image and the slabs
  double outsidePx = 0;    // how far the current view needs content beyond the slice camera's image
                           // (the layer images, guard band included)
  double magnification = 1;  // current pixels per layer texel at the image centre (> 1: zoomed in, blurred)
  double turnDegrees = 0;  // the angle between the two eyes' directions to the vegetation's centre
                           // (view-dependent shading baked into the layers: the specular lobe)
};
// Where a layer set's vertices project in its slice camera, pixels, unclipped (known: every vertex
// was in front of the camera).
struct PixelExtent {
  glm::vec2 lo{0.0f}, hi{0.0f};
  bool known = false;
};

// A layer whose every texel lands within this many layer pixels of its plane's mapping is shown by
// the plane's homography alone, without the depth search (compositeView; docs/design.md "Layers:
// reprojection", the short path).
constexpr double kShortPathPx = COMPOSITE_SHORT_PATH_PX;
// Depths averaged over a slab's range by estimateReprojectionError (midpoints).
constexpr int kDepthSamples = 8;
// Zooming in beyond this many current pixels per layer texel re-slices (the reprojected layers blur).
constexpr double kMaxMagnification = 1.1;
struct SlabRange {
  float zNear = 0, zFar = 0, depth = 0;  // slice-camera view depths
};
// `slice` and `sliceSize`: the slice camera and its layer images (guard band included);
// `current` and `outSize`: the camera shown and its output. `drawn`: the set's vertex extent in
// slice pixels (null: the bounding box's projection, which a rounded crown overstates).
ReprojectionError estimateReprojectionError(const LayerView& slice, const LayerView& current, const std::vector<SlabRange>& slabs,
                                            const glm::vec3& boundsMin, const glm::vec3& boundsMax, const glm::dvec2& sliceSize,
                                            const glm::dvec2& outSize, const PixelExtent* drawn = nullptr);

// The slice camera for `view` with a guard band (docs/design.md "Layers: guard band"): the same
// camera, its clip x and y scaled by out / (out + 2 guard), so the layer images of out + 2 guard
// pixels show the output's view at the same scale, offset by the guard (layer pixel = output
// pixel + guard). No guard: `view` itself, bit for bit.
LayerView guardedView(const LayerView& view, glm::uvec2 outSize, glm::uvec2 guard);

}  // namespace canopy
