#pragma once
// Small writers for inspecting GPU results: PNG (via stb_image_write) and NumPy .npy arrays.
#include <cstdint>
#include <string>
#include <vector>

#include "engine/status.h"

namespace canopy {

// 8-bit RGBA, rows top to bottom.
Status writePng(const std::string& path, uint32_t width, uint32_t height, const std::vector<uint8_t>& rgba);
// The same PNG in memory (e.g. to embed it in a .glb).
Status encodePng(uint32_t width, uint32_t height, const std::vector<uint8_t>& rgba, std::vector<uint8_t>* png);
// Reads any PNG as 8-bit RGBA, rows top to bottom; the error names the file.
Status readPng(const std::string& path, uint32_t* width, uint32_t* height, std::vector<uint8_t>* rgba);
// float32 array of the given shape, C order (e.g. {N, N, 2}).
Status writeNpy(const std::string& path, const std::vector<float>& data, const std::vector<uint32_t>& shape);

// A 2D vector field (n*n vec2, row 0 at the bottom) as colour: hue = direction, brightness =
// magnitude / scale (scale <= 0: the field's largest magnitude). Rows flipped so +y is up; each
// cell becomes zoom x zoom pixels.
std::vector<uint8_t> vectorFieldToRgba(const std::vector<float>& field, uint32_t n, float scale, uint32_t zoom);

}  // namespace canopy
