#include "tools/image_io.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cerrno>
#include <cstring>

#define STB_IMAGE_WRITE_IMPLEMENTATION
#include <stb/stb_image_write.h>
// A private PNG-only decoder (render/gltf_loader.cpp has its own, also private).
#define STB_IMAGE_STATIC
#define STB_IMAGE_IMPLEMENTATION
#define STBI_ONLY_PNG
#include <stb/stb_image.h>

namespace canopy {

namespace {
// An opaque image is encoded as RGB: a quarter fewer bytes to compress (the demo writes many
// frames; docs/ keeps a few); readers get alpha = 255 back either way.
struct PngPixels {
  std::vector<uint8_t> rgb;  // filled only for an opaque image
  const uint8_t* data = nullptr;
  int channels = 4;
};
PngPixels pngPixels(const std::vector<uint8_t>& rgba) {
  PngPixels p;
  p.data = rgba.data();
  for (size_t i = 3; i < rgba.size(); i += 4)
    if (rgba[i] != 255) return p;
  p.rgb.resize(rgba.size() / 4 * 3);
  for (size_t i = 0, j = 0; i < rgba.size(); i += 4, j += 3) std::memcpy(&p.rgb[j], &rgba[i], 3);
  p.data = p.rgb.data();
  p.channels = 3;
  return p;
}
}  // namespace

Status writePng(const std::string& path, uint32_t w, uint32_t h, const std::vector<uint8_t>& rgba) {
  if (w == 0 || h == 0 || rgba.size() != size_t(w) * h * 4)
    return Status::error("writePng '" + path + "': " + std::to_string(rgba.size()) + " bytes for " + std::to_string(w) + "x" +
                         std::to_string(h) + " RGBA");
  const PngPixels p = pngPixels(rgba);
  if (!stbi_write_png(path.c_str(), int(w), int(h), p.channels, p.data, int(w) * p.channels))
    return Status::error("cannot write PNG '" + path + "'");
  return Status();
}

Status encodePng(uint32_t w, uint32_t h, const std::vector<uint8_t>& rgba, std::vector<uint8_t>* png) {
  png->clear();
  if (w == 0 || h == 0 || rgba.size() != size_t(w) * h * 4)
    return Status::error("encodePng: " + std::to_string(rgba.size()) + " bytes for " + std::to_string(w) + "x" +
                         std::to_string(h) + " RGBA");
  auto append = [](void* ctx, void* data, int size) {
    auto* out = static_cast<std::vector<uint8_t>*>(ctx);
    out->insert(out->end(), static_cast<uint8_t*>(data), static_cast<uint8_t*>(data) + size);
  };
  const PngPixels p = pngPixels(rgba);
  if (!stbi_write_png_to_func(append, png, int(w), int(h), p.channels, p.data, int(w) * p.channels))
    return Status::error("encodePng: the encoder failed");
  return Status();
}

Status readPng(const std::string& path, uint32_t* width, uint32_t* height, std::vector<uint8_t>* rgba) {
  int w = 0, h = 0, comp = 0;
  stbi_uc* px = stbi_load(path.c_str(), &w, &h, &comp, 4);
  if (!px) return Status::error(path + ": cannot read PNG (" + std::string(stbi_failure_reason()) + ")");
  *width = uint32_t(w);
  *height = uint32_t(h);
  rgba->assign(px, px + size_t(w) * size_t(h) * 4);
  stbi_image_free(px);
  return Status();
}

Status writeNpy(const std::string& path, const std::vector<float>& data, const std::vector<uint32_t>& shape) {
  size_t count = 1;
  std::string dims;
  for (uint32_t d : shape) {
    count *= d;
    dims += std::to_string(d) + ", ";
  }
  if (shape.size() > 1) dims.resize(dims.size() - 2);
  if (count != data.size())
    return Status::error("writeNpy '" + path + "': shape holds " + std::to_string(count) + " values, " +
                         std::to_string(data.size()) + " given");
  std::string header = "{'descr': '<f4', 'fortran_order': False, 'shape': (" + dims + "), }";
  // Magic (6) + version (2) + length (2) + header + '\n', padded to a multiple of 64.
  const size_t total = (10 + header.size() + 1 + 63) / 64 * 64;
  header.append(total - 10 - header.size() - 1, ' ');
  header += '\n';
  FILE* f = std::fopen(path.c_str(), "wb");
  if (!f) return Status::error("cannot create '" + path + "': " + std::strerror(errno));
  const unsigned char magic[8] = {0x93, 'N', 'U', 'M', 'P', 'Y', 1, 0};
  const uint16_t len = uint16_t(header.size());
  const unsigned char lenBytes[2] = {uint8_t(len & 0xff), uint8_t(len >> 8)};
  bool ok = std::fwrite(magic, 1, 8, f) == 8 && std::fwrite(lenBytes, 1, 2, f) == 2 &&
            std::fwrite(header.data(), 1, header.size(), f) == header.size() &&
            std::fwrite(data.data(), sizeof(float), data.size(), f) == data.size();
  ok = (std::fclose(f) == 0) && ok;
  if (!ok) return Status::error("error writing '" + path + "'");
  return Status();
}

std::vector<uint8_t> vectorFieldToRgba(const std::vector<float>& field, uint32_t n, float scale, uint32_t zoom) {
  zoom = std::max(1u, zoom);
  if (scale <= 0) {
    for (size_t c = 0; c + 1 < field.size(); c += 2) scale = std::max(scale, std::hypot(field[c], field[c + 1]));
    if (scale <= 0) scale = 1;
  }
  const uint32_t W = n * zoom;
  std::vector<uint8_t> img(size_t(W) * W * 4);
  for (uint32_t y = 0; y < W; ++y)
    for (uint32_t x = 0; x < W; ++x) {
      const uint32_t i = x / zoom, j = n - 1 - y / zoom;  // row 0 of the field at the bottom
      const float u = field[2 * (size_t(j) * n + i)], v = field[2 * (size_t(j) * n + i) + 1];
      const float val = std::min(1.0f, std::hypot(u, v) / scale);
      float hue = std::atan2(v, u) / 6.2831853f;
      hue = (hue - std::floor(hue)) * 6.0f;
      const int k = int(hue) % 6;
      const float fr = hue - std::floor(hue);
      float r, g, b;  // HSV with s = 1
      switch (k) {
        case 0: r = 1, g = fr, b = 0; break;
        case 1: r = 1 - fr, g = 1, b = 0; break;
        case 2: r = 0, g = 1, b = fr; break;
        case 3: r = 0, g = 1 - fr, b = 1; break;
        case 4: r = fr, g = 0, b = 1; break;
        default: r = 1, g = 0, b = 1 - fr; break;
      }
      uint8_t* p = &img[(size_t(y) * W + x) * 4];
      p[0] = uint8_t(255 * r * val + 0.5f);
      p[1] = uint8_t(255 * g * val + 0.5f);
      p[2] = uint8_t(255 * b * val + 0.5f);
      p[3] = 255;
    }
  return img;
}

}  // namespace canopy
