#pragma once
// canopy-demo --measure-foliage W S: the picture in wind, frame by frame (tools/foliage_measure.h).
#include <cstdint>
#include <string>
#include <vector>

namespace canopy::demo {

// Each frame_NNNN.png of `wind` against `still`'s, one line each, then the least coverage and
// sharpness. Exit 1 when a folder has no frames, a frame is missing or unreadable, or sizes differ.
int measureFoliageFolders(const std::string& wind, const std::string& still);

// Frame n of two output folders (frame_NNNN.png), the same size: 0 read, 1 neither folder has it
// (the end), 2 an error (one missing, unreadable, sizes differ), printed to stderr.
int readFramePair(const std::string& a, const std::string& b, uint32_t n, uint32_t* width, uint32_t* height,
                  std::vector<uint8_t>* pixelsA, std::vector<uint8_t>* pixelsB);

}  // namespace canopy::demo
