#pragma once
// Reprojection of the layers between re-slices (docs/design.md "Layers: reprojection"): a layer
// image holds a depth slab as the slice camera saw it; a pixel of the current camera reads it
// through the homography of the slab's plane (exact on the plane; off it, the error grows with
// the slab's thickness times the parallax between the two cameras).
#include <glm/glm.hpp>

#include "engine/camera.h"

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

}  // namespace canopy
