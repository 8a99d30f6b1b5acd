#pragma once
// The picture in wind, measured as a player sees it (issues 66, 67; docs/performance.md "The wind
// from every side"): a frame with wind against the same frame (camera, time) without it. Images
// are 8-bit RGBA, rows top to bottom. Foliage is what a viewer reads as green: green above red and
// above blue by more than 15 levels (the issues' measure; the sky, the ground and the trunks are not).
#include <cstdint>
#include <vector>

namespace canopy {

struct FoliageMeasure {
  uint64_t windPixels = 0;   // foliage pixels of the frame with wind
  uint64_t stillPixels = 0;  // ... and without
  double coverage = 1.0;     // windPixels / stillPixels (1 when both are empty, inf when only the still one is)
  // The crown's top third: the rows of the still frame's foliage, top third of them; the centroid x
  // of each frame's foliage pixels there, pixels (NaN when it has none).
  double windTopX = 0.0, stillTopX = 0.0;
  double offsetPx = 0.0;     // windTopX - stillTopX: how far the wind moved the crown sideways
  uint32_t heightPx = 0;     // the still frame's foliage rows, first to last
  // Mean luminance gradient (|forward differences| in x and y, Rec. 709 luma of the 8-bit values)
  // over each frame's own foliage pixels, wind / still: below 1, the wind blurred the leaves.
  double sharpness = 1.0;
};

// True where (r, g, b) reads as foliage.
inline bool isFoliage(uint8_t r, uint8_t g, uint8_t b) { return int(g) > int(r) + 15 && int(g) > int(b) + 15; }

// `wind` against `still` (same size, width x height RGBA).
FoliageMeasure measureFoliage(const std::vector<uint8_t>& wind, const std::vector<uint8_t>& still, uint32_t width,
                              uint32_t height);

}  // namespace canopy
