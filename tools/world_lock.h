#pragma once
// How far a frame drawn by Canopy's re-slicing policy is from the same frame drawn with a re-slice
// every frame (docs/design.md "Moving camera: paths and the world-lock measure"): the measure of
// layers that stay locked to the world while the camera moves. Images are 8-bit RGBA, rows top to
// bottom; a pixel is covered (the vegetation drew it) where its colour differs from the host's
// clear colour by more than 1 level.
#include <cstdint>
#include <vector>

namespace canopy {

struct WorldLockError {
  double coverageIoU = 1.0;       // |A ∩ B| / |A ∪ B| of the covered pixels (1 when both are empty)
  double silhouetteMeanPx = 0.0;  // mean distance from each silhouette pixel to the other image's silhouette, both ways
  double silhouetteP99Px = 0.0;   // its 99th percentile
  double centroidPx = 0.0;        // distance between the covered pixels' centroids
  double colourMean = 0.0;        // mean |RGB difference| over the covered pixels of either image, 8-bit levels
  uint64_t coveredA = 0, coveredB = 0;
};

// Covered pixels of `rgba` (1 = covered).
std::vector<uint8_t> coverageMask(const std::vector<uint8_t>& rgba, uint32_t width, uint32_t height, const uint8_t clear[3]);

// `a` against the reference `b` (same size). A silhouette pixel is a covered pixel with an
// uncovered 4-neighbour; when one image has a silhouette and the other none, every distance is the
// image's diagonal.
WorldLockError compareFrames(const std::vector<uint8_t>& a, const std::vector<uint8_t>& b, uint32_t width, uint32_t height,
                             const uint8_t clear[3]);
// The same measure over given coverage masks (1 = covered; e.g. where Canopy wrote the host's depth,
// its alpha >= depthAlpha rule, which leaves out the faint resampling halo a colour threshold counts);
// colour from the two RGBA8 frames.
WorldLockError compareMasks(const std::vector<uint8_t>& maskA, const std::vector<uint8_t>& maskB, const std::vector<uint8_t>& a,
                            const std::vector<uint8_t>& b, uint32_t width, uint32_t height);

}  // namespace canopy
