// The translucency light sheet (issue 36; the seed's Figure 5 layout, seed 004 section III.C): one
// leaf with a relief (a midrib, lateral veins and the bulges between them, as a normal map) seen
// from its unlit side with the light behind it, from steep to grazing, drawn through Canopy's layers
// with Habel's translucency (top row) and the diffuse BTDF (bottom row), written as one PNG.
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "bench/bench.h"
#include "bench/bench_host.h"
#include "engine/camera.h"
#include "engine/device.h"
#include "engine/transfer.h"
#include "tools/image_io.h"

namespace canopy::bench {
namespace {

// The leaf: a quad with an elliptic outline (alpha mask), its relief as a height field turned into
// a tangent-space normal map.
VegetationModel reliefLeaf() {
  VegetationModel m;
  m.materials.resize(2);
  ModelMaterial& leaf = m.materials[0];
  leaf.name = "leaf";
  leaf.baseColorFactor = glm::vec4(1.0f);
  leaf.alphaMode = AlphaMode::Mask;
  leaf.transmissionFactor = 0.8f;
  leaf.transmissionColor = glm::vec3(0.55f, 0.9f, 0.2f);
  leaf.baseColorImage = 0;
  leaf.normalImage = 1;
  leaf.normalScale = 1.0f;
  m.materials[1].name = "default";
  const uint32_t N = 256;
  ModelImage colour, normals;
  colour.name = "leaf colour";
  normals.name = "leaf relief";
  normals.linear = true;
  colour.width = colour.height = normals.width = normals.height = N;
  colour.rgba.resize(size_t(N) * N * 4);
  normals.rgba.resize(size_t(N) * N * 4);
  auto height = [](float u, float v) {
    const float x = u - 0.5f, y = v - 0.5f;
    const float midrib = 0.02f * std::exp(-x * x / 0.0003f);
    // Lateral veins leaving the midrib at about 40 degrees, every 0.1 along it.
    const float along = y - 0.8f * std::abs(x);
    const float ph = along / 0.1f - std::floor(along / 0.1f) - 0.5f;
    const float vein = 0.008f * std::exp(-ph * ph / 0.004f);
    const float bulge = 0.006f * std::sin(3.14159265f * (ph + 0.5f)) * std::sin(3.14159265f * std::min(std::abs(x) * 2.0f, 1.0f));
    return midrib + vein + bulge;
  };
  for (uint32_t j = 0; j < N; ++j)
    for (uint32_t i = 0; i < N; ++i) {
      const float u = (float(i) + 0.5f) / float(N), v = (float(j) + 0.5f) / float(N), e = 1.0f / float(N);
      const float dx = (height(u + e, v) - height(u - e, v)) / (2.0f * e), dy = (height(u, v + e) - height(u, v - e)) / (2.0f * e);
      const glm::vec3 n = glm::normalize(glm::vec3(-dx, -dy, 1.0f));
      uint8_t* p = &normals.rgba[(size_t(j) * N + i) * 4];
      for (int k = 0; k < 3; ++k) p[k] = uint8_t(std::lround((n[k] * 0.5f + 0.5f) * 255.0f));
      p[3] = 255;
      const float ex = (u - 0.5f) / 0.42f, ey = (v - 0.5f) / 0.48f;
      uint8_t* c = &colour.rgba[(size_t(j) * N + i) * 4];
      c[0] = 70, c[1] = 130, c[2] = 40;
      c[3] = ex * ex + ey * ey <= 1.0f ? 255 : 0;
    }
  m.images = {colour, normals};
  // The front (+z normal) faces the camera; the light comes from behind.
  const glm::vec3 p[4] = {{-1, -1.2f, 0}, {1, -1.2f, 0}, {1, 1.2f, 0}, {-1, 1.2f, 0}};
  const glm::vec2 uv[4] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
  for (int i = 0; i < 4; ++i) {
    m.positions.push_back(p[i]);
    m.normals.push_back({0, 0, 1});
    m.uvs.push_back(uv[i]);
  }
  m.indices = {0, 1, 2, 2, 3, 0};
  m.triangleMaterial = {0, 0};
  m.boundsMin = glm::vec3(-1, -1.2f, 0);
  m.boundsMax = glm::vec3(1, 1.2f, 0);
  return m;
}

}  // namespace

int runLeafSheet(Device& d, const std::string& outPath) {
  const uint32_t tile = 200;
  const float elevations[] = {80.0f, 55.0f, 35.0f, 20.0f, 8.0f};
  const uint32_t cols = 5, rows = 2;
  std::vector<uint8_t> sheet(size_t(tile) * cols * tile * rows * 4, 255);
  const VegetationModel leaf = reliefLeaf();
  std::printf("\nTranslucency light sheet: the leaf's unlit side, light behind it at");
  for (float e : elevations) std::printf(" %.0f", double(e));
  std::printf(" degrees above its plane; top Habel's translucency, bottom the diffuse BTDF\n");
  for (uint32_t row = 0; row < rows; ++row)
    for (uint32_t col = 0; col < cols; ++col) {
      CanopyDesc desc;
      desc.width = desc.height = tile;
      CanopyContext* ctx = nullptr;
      HostTargets host;
      rg::RenderGraph graph;
      Status s = createCanopy(d, leaf, desc, &ctx);
      std::vector<uint8_t> px(size_t(tile) * tile * 4);
      if (s.ok()) {
        CanopyParams p = canopyParams(ctx);
        p.windMode = WindMode::PlaneSides;  // the wind as the plane's sides (domain units/s)
        p.simulation.wind.strength = 0.0f;
        p.layers.translucencyModel = row == 0 ? TranslucencyModel::Habel : TranslucencyModel::DiffuseBtdf;
        const float e = elevations[col] * 3.14159265f / 180.0f;
        p.layers.lightDirection = {-std::cos(e), 0.0f, -std::sin(e)};
        p.layers.ambient = 0.1f;
        s = setCanopyParams(ctx, p);
      }
      if (s.ok()) s = createHostTargets(d, tile, tile, VK_FORMAT_R8G8B8A8_UNORM, &host);
      if (s.ok()) s = buildHostGraph(d, ctx, host, true, rg::stateOf(rg::Use::ColorAttachmentReadWrite), &graph);
      for (int frame = 0; frame < 2 && s.ok(); ++frame) {
        CanopyFrame f;
        f.camera = toCamera(orbitView(leaf.boundsMin, leaf.boundsMax, 0.0f, 0.0f, 40.0f, 1.0f, 0.9f));
        f.dt = 1.0f / 30.0f;
        s = beginCanopyFrame(ctx, f);
        if (s.ok()) s = submitAndWait(d, [&](VkCommandBuffer cmd) { return graph.record(cmd, nullptr); });
      }
      if (s.ok()) s = readbackImage(d, host.color, 0, 4, px.data(), rg::stateOf(rg::Use::ColorAttachmentReadWrite));
      graph.release(d);
      destroyHostTargets(d, host);
      destroyCanopy(ctx);
      if (!s.ok()) {
        std::fprintf(stderr, "canopy-bench: leaf sheet: %s\n", s.message().c_str());
        return 1;
      }
      for (uint32_t y = 0; y < tile; ++y)
        for (uint32_t x = 0; x < tile; ++x)
          for (int k = 0; k < 4; ++k)
            sheet[((size_t(row) * tile + y) * tile * cols + size_t(col) * tile + x) * 4 + size_t(k)] =
                k == 3 ? 255 : px[(size_t(y) * tile + x) * 4 + size_t(k)];
    }
  const Status w = writePng(outPath, tile * cols, tile * rows, sheet);
  if (!w.ok()) {
    std::fprintf(stderr, "canopy-bench: %s\n", w.message().c_str());
    return 1;
  }
  std::printf("wrote %s (%ux%u)\n", outPath.c_str(), tile * cols, tile * rows);
  return 0;
}

}  // namespace canopy::bench
