#pragma once
// canopy-demo --measure-foliage W S: the picture in wind, frame by frame (tools/foliage_measure.h).
#include <string>

namespace canopy::demo {

// Each frame_NNNN.png of `wind` against `still`'s, one line each, then the least coverage and
// sharpness. Exit 1 when a folder has no frames, a frame is missing or unreadable, or sizes differ.
int measureFoliageFolders(const std::string& wind, const std::string& still);

}  // namespace canopy::demo
