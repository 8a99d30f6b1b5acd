// The vegetation's shadow (issue 54; docs/design.md "Shadows"): recordCanopyShadow into a host
// depth image from an orthographic light. With the wind off the map is the still foliage's depth
// from the light (a CPU rasteriser with the same alpha test as the reference); with the wind on the
// shadow's centroid moves in step with the crown's on screen, by the world amplitude the screen
// implies; D32 and D16 maps, standard and reverse-Z, the host's states honoured (validation and
// synchronization validation on: any message fails the test).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include <glm/gtc/matrix_transform.hpp>

#include "tests/gpu_test.h"
#include "tests/test_host.h"
#include "tools/scene_generator.h"

using namespace canopy;
using canopy::test::GpuTest;
using canopy::test::Host;

namespace {

class ShadowTest : public GpuTest {
 protected:
  uint64_t frameNumber = 0;
};

VegetationModel shrub() {
  SceneDesc sd;
  sd.kind = SceneKind::Shrub;
  sd.faces = 8000;
  sd.seed = 5;
  sd.textureSize = 64;
  VegetationModel m;
  EXPECT_TRUE(generateScene(sd, &m).ok());
  return m;
}

// A spot light above and aside, a perspective cone around the model (Vulkan clip: depth 0 near).
glm::mat4 spotViewProj(const VegetationModel& m) {
  const glm::vec3 c = 0.5f * (m.boundsMin + m.boundsMax);
  const float r = 0.5f * glm::length(m.boundsMax - m.boundsMin);
  const glm::vec3 dir = glm::normalize(glm::vec3(0.3f, -1.0f, -0.4f));
  return perspectiveVulkan(glm::radians(50.0f), 1.0f, 0.5f * r, 5.0f * r) * glm::lookAt(c - dir * (2.5f * r), c, glm::vec3(0, 0, 1));
}

// A sun from above and aside, an orthographic box around the model (Vulkan clip: depth 0 near).
glm::mat4 sunViewProj(const VegetationModel& m, bool reverseZ) {
  const glm::vec3 c = 0.5f * (m.boundsMin + m.boundsMax);
  const float r = 0.5f * glm::length(m.boundsMax - m.boundsMin);
  const glm::vec3 dir = glm::normalize(glm::vec3(-0.45f, -1.0f, -0.3f));
  const glm::mat4 view = glm::lookAt(c - dir * (2.0f * r), c, glm::vec3(0, 0, 1));
  glm::mat4 proj = glm::orthoRH_ZO(-1.1f * r, 1.1f * r, -1.1f * r, 1.1f * r, 0.5f * r, 3.5f * r);
  if (reverseZ) {
    glm::mat4 mirror(1.0f);  // z' = 1 - z
    mirror[2][2] = -1.0f;
    mirror[3][2] = 1.0f;
    proj = mirror * proj;
  }
  return proj * view;
}

// The host's shadow map: a depth image it samples later (here: reads back).
struct ShadowMap {
  Image image;
  VkFormat format = VK_FORMAT_D32_SFLOAT;
  uint32_t size = 256;
  bool reverseZ = false;
  bool first = true;
  Status create(Device& d) {
    ImageDesc i;
    i.format = format;
    i.width = i.height = size;
    i.usage = VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT | VK_IMAGE_USAGE_SAMPLED_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT;
    return createImage(d, i, &image, "test: shadow map");
  }
  CanopyShadowInputs inputs(const glm::mat4& light) {
    CanopyShadowInputs in;
    const rg::State src = rg::stateOf(rg::Use::TransferSrc);
    in.depth = canopyImage(image.image, image.view, VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT | VK_IMAGE_USAGE_SAMPLED_BIT |
                                                        VK_IMAGE_USAGE_TRANSFER_SRC_BIT,
                           format, first ? rg::State{} : src, src);
    first = false;
    in.width = in.height = size;
    in.lightViewProj = toFloat4x4(light);
    in.reverseZ = reverseZ;
    return in;
  }
  // Depth as float in [0, 1].
  Status read(Device& d, std::vector<float>* z) {
    const size_t n = size_t(size) * size;
    z->resize(n);
    const rg::State src = rg::stateOf(rg::Use::TransferSrc);
    if (format == VK_FORMAT_D16_UNORM) {
      std::vector<uint16_t> v(n);
      CANOPY_TRY(readbackImage(d, image, 0, 2, v.data(), src));
      for (size_t i = 0; i < n; ++i) (*z)[i] = v[i] / 65535.0f;
      return Status();
    }
    return readbackImage(d, image, 0, 4, z->data(), src);
  }
};

// The reference: the still model rasterised on the CPU from the light, pixel centres, the
// material's alpha (bilinear, repeat, like the layers' sampler) against its cutoff.
std::vector<float> rasterise(const VegetationModel& m, const glm::mat4& light, uint32_t size, bool reverseZ) {
  std::vector<float> z(size_t(size) * size, reverseZ ? 0.0f : 1.0f);
  auto alphaAt = [&](const ModelMaterial& mat, glm::vec2 uv) {
    float a = mat.baseColorFactor.a;
    if (mat.baseColorImage < 0) return a;
    const ModelImage& img = m.images[size_t(mat.baseColorImage)];
    const float x = uv.x * img.width - 0.5f, y = uv.y * img.height - 0.5f;
    const int x0 = int(std::floor(x)), y0 = int(std::floor(y));
    const float fx = x - x0, fy = y - y0;
    auto texel = [&](int xi, int yi) {
      xi = ((xi % int(img.width)) + int(img.width)) % int(img.width);
      yi = ((yi % int(img.height)) + int(img.height)) % int(img.height);
      return img.rgba[(size_t(yi) * img.width + size_t(xi)) * 4 + 3] / 255.0f;
    };
    const float t = (texel(x0, y0) * (1 - fx) + texel(x0 + 1, y0) * fx) * (1 - fy) + (texel(x0, y0 + 1) * (1 - fx) + texel(x0 + 1, y0 + 1) * fx) * fy;
    return a * t;
  };
  for (size_t t = 0; t < m.triangleCount(); ++t) {
    const ModelMaterial& mat = m.materials[m.triangleMaterial[t]];
    glm::vec3 p[3];
    glm::vec2 uv[3];
    for (int k = 0; k < 3; ++k) {
      const uint32_t v = m.indices[3 * t + size_t(k)];
      const glm::vec4 c = light * glm::vec4(m.positions[v], 1.0f);
      p[k] = glm::vec3((glm::vec2(c) / c.w * 0.5f + 0.5f) * float(size), c.z / c.w);
      uv[k] = m.uvs.empty() ? glm::vec2(0.0f) : m.uvs[v];
    }
    const float area = (p[1].x - p[0].x) * (p[2].y - p[0].y) - (p[2].x - p[0].x) * (p[1].y - p[0].y);
    if (std::abs(area) < 1e-12f) continue;
    const int x0 = std::max(0, int(std::floor(std::min({p[0].x, p[1].x, p[2].x})))),
              x1 = std::min(int(size) - 1, int(std::ceil(std::max({p[0].x, p[1].x, p[2].x})))),
              y0 = std::max(0, int(std::floor(std::min({p[0].y, p[1].y, p[2].y})))),
              y1 = std::min(int(size) - 1, int(std::ceil(std::max({p[0].y, p[1].y, p[2].y}))));
    for (int y = y0; y <= y1; ++y)
      for (int x = x0; x <= x1; ++x) {
        const glm::vec2 q(x + 0.5f, y + 0.5f);
        const float w0 = ((p[1].x - q.x) * (p[2].y - q.y) - (p[2].x - q.x) * (p[1].y - q.y)) / area;
        const float w1 = ((p[2].x - q.x) * (p[0].y - q.y) - (p[0].x - q.x) * (p[2].y - q.y)) / area;
        const float w2 = 1.0f - w0 - w1;
        if (w0 < 0 || w1 < 0 || w2 < 0) continue;
        if (mat.alphaMode != AlphaMode::Opaque) {
          const float a = alphaAt(mat, w0 * uv[0] + w1 * uv[1] + w2 * uv[2]);
          if ((mat.alphaMode == AlphaMode::Mask && a < mat.alphaCutoff) || (mat.alphaMode == AlphaMode::Blend && a < 0.5f)) continue;
        }
        const float d = w0 * p[0].z + w1 * p[1].z + w2 * p[2].z;
        float& o = z[size_t(y) * size + size_t(x)];
        if (reverseZ ? d > o : d < o) o = d;
      }
  }
  return z;
}

bool covered(float z, bool reverseZ) { return reverseZ ? z > 0.0f : z < 1.0f; }

struct Coverage {
  double iou = 0, farOff = 0;  // farOff: share of the pixels both cover whose depths differ by more than 1e-3
  uint64_t either = 0;
};
Coverage compare(const std::vector<float>& a, const std::vector<float>& b, bool reverseZ) {
  Coverage c;
  uint64_t both = 0, off = 0;
  for (size_t i = 0; i < a.size(); ++i) {
    const bool ia = covered(a[i], reverseZ), ib = covered(b[i], reverseZ);
    both += ia && ib;
    c.either += ia || ib;
    off += ia && ib && std::abs(a[i] - b[i]) > 1e-3f;
  }
  c.iou = c.either ? double(both) / double(c.either) : 1.0;
  c.farOff = both ? double(off) / double(both) : 0.0;
  return c;
}

// Context on `m` with the wind's strength `wind`, a host of 160x120 looking at it.
struct Scene {
  Host host;
  CanopyContext* ctx = nullptr;
  LayerView view;
  Status create(Device& dev, const VegetationModel& m, float wind) {
    host.w = 160;
    host.h = 120;
    CANOPY_TRY(canopy::test::createHostContext(dev, host, {SpeciesModel{&m}}, {}, wind, false, &ctx));
    view = orbitView(m.boundsMin, m.boundsMax, 0.0f, 10.0f, 40.0f, 160.0f / 120.0f, 1.0f);
    return Status();
  }
  void destroy() {
    (void)host.finish();
    destroyCanopy(ctx);
    host.destroy();
  }
};

TEST_F(ShadowTest, WithTheWindOffTheMapIsTheStillFoliagesDepthFromTheLight) {
  const VegetationModel m = shrub();
  // The sun in both formats and conventions, then a spot light (perspective, D32).
  struct Case {
    VkFormat format;
    bool reverseZ, spot;
  };
  for (const Case& k : {Case{VK_FORMAT_D32_SFLOAT, false, false}, Case{VK_FORMAT_D32_SFLOAT, true, false}, Case{VK_FORMAT_D16_UNORM, false, false},
                        Case{VK_FORMAT_D16_UNORM, true, false}, Case{VK_FORMAT_D32_SFLOAT, false, true}}) {
      const VkFormat format = k.format;
      const bool reverseZ = k.reverseZ;
      SCOPED_TRACE(std::string(format == VK_FORMAT_D16_UNORM ? "D16" : "D32") + (reverseZ ? " reverse-Z" : "") + (k.spot ? " spot" : ""));
      Scene s;
      ASSERT_TRUE(s.create(dev, m, 0.0f).ok());
      ShadowMap map;
      map.format = format;
      map.reverseZ = reverseZ;
      ASSERT_TRUE(map.create(dev).ok());
      const glm::mat4 light = k.spot ? spotViewProj(m) : sunViewProj(m, reverseZ);
      bool updated = false;
      s.host.recordAfter = [&](VkCommandBuffer cmd) { return recordCanopyShadow(s.ctx, cmd, map.inputs(light), &updated); };
      for (int f = 0; f < 3; ++f) ASSERT_TRUE(s.host.frame(++frameNumber, {s.ctx}, s.view, 1.0f / 30.0f).ok());
      EXPECT_TRUE(updated);
      std::vector<float> z;
      ASSERT_TRUE(map.read(dev, &z).ok());
      const std::vector<float> ref = rasterise(m, light, map.size, reverseZ);
      const Coverage c = compare(z, ref, reverseZ);
      std::printf("wind off, %s%s: coverage IoU %.4f over %llu px; where both cover, %.2f %% of depths off by > 1e-3\n",
                  format == VK_FORMAT_D16_UNORM ? "D16" : "D32", reverseZ ? ", reverse-Z" : k.spot ? ", spot light" : "", c.iou,
                  (unsigned long long)c.either, 100.0 * c.farOff);
      EXPECT_GT(c.either, 2000u) << "the shrub covers part of the map";
      EXPECT_GE(c.iou, 0.98);
      // The spot light's depth is hyperbolic: the same leaves' depths differ more there (the UVs the
      // reference interpolates affinely decide a few alpha edges otherwise).
      EXPECT_LE(c.farOff, k.spot ? 0.02 : 0.01) << "the nearest leaf's depth, as the reference finds it";
      s.destroy();
      destroyImage(dev, map.image);
    }
}

// Pearson correlation of two series.
double correlation(const std::vector<double>& a, const std::vector<double>& b) {
  const size_t n = std::min(a.size(), b.size());
  double ma = 0, mb = 0;
  for (size_t i = 0; i < n; ++i) ma += a[i] / n, mb += b[i] / n;
  double sab = 0, saa = 0, sbb = 0;
  for (size_t i = 0; i < n; ++i) {
    sab += (a[i] - ma) * (b[i] - mb);
    saa += (a[i] - ma) * (a[i] - ma);
    sbb += (b[i] - mb) * (b[i] - mb);
  }
  return sab / std::sqrt(std::max(saa * sbb, 1e-30));
}
double stddev(const std::vector<double>& a) {
  double m = 0, s = 0;
  for (double v : a) m += v / a.size();
  for (double v : a) s += (v - m) * (v - m) / a.size();
  return std::sqrt(s);
}

TEST_F(ShadowTest, WithTheWindOnTheShadowSwaysInStepWithTheCrownOnScreen) {
  const VegetationModel m = shrub();
  Scene s;
  ASSERT_TRUE(s.create(dev, m, 2.0f).ok());
  // This wind (2 domain units/s through the plane's sides, 160x120) leans the shrub's top by more
  // than DynamicsParams.maxStretch of its height above the root: the stretch bound would hold the
  // lean at its cap and the sway measured here with it (1.39 px s.d. unbounded, 0.07 with 0.4;
  // docs/design.md "Layers: the warp's stretch"). The shadow's step with the crown is what is tested.
  CanopyParams unbounded = canopyParams(s.ctx);
  unbounded.dynamics.maxStretch = 0.0f;
  ASSERT_TRUE(setCanopyParams(s.ctx, unbounded).ok());
  ShadowMap map;
  ASSERT_TRUE(map.create(dev).ok());
  const glm::mat4 light = sunViewProj(m, false);
  s.host.recordAfter = [&](VkCommandBuffer cmd) { return recordCanopyShadow(s.ctx, cmd, map.inputs(light)); };
  // The camera's right, and the shadow map's direction it moves along (light pixels per world unit).
  const glm::vec3 right = glm::vec3(glm::inverse(s.view.view)[0]);
  const glm::vec3 c = 0.5f * (m.boundsMin + m.boundsMax);
  auto lightPixel = [&](glm::vec3 p) {
    const glm::vec4 q = light * glm::vec4(p, 1.0f);
    return (glm::vec2(q) / q.w * 0.5f + 0.5f) * float(map.size);
  };
  const glm::vec2 along = lightPixel(c + right) - lightPixel(c);  // light pixels per world unit of `right`
  const glm::vec2 axis = glm::normalize(along);
  const float depth = -(s.view.view * glm::vec4(c, 1.0f)).z;
  const float worldPerPixel = depth / (std::abs(s.view.proj[0][0]) * 0.5f * float(s.host.w));  // at the crown's depth
  std::vector<double> screen, shadow;
  const int frames = 90;
  for (int f = 0; f < frames; ++f) {
    ASSERT_TRUE(s.host.frame(++frameNumber, {s.ctx}, s.view, 1.0f / 30.0f).ok());
    std::vector<glm::vec4> rgba;
    std::vector<float> z, zs;
    ASSERT_TRUE(s.host.read(&rgba, &z).ok());
    ASSERT_TRUE(map.read(dev, &zs).ok());
    if (f < 20) continue;  // the wind rising from rest
    double sx = 0, n = 0;
    for (uint32_t y = 0; y < s.host.h; ++y)
      for (uint32_t x = 0; x < s.host.w; ++x)
        if (z[size_t(y) * s.host.w + x] < 1.0f) sx += x, n += 1;
    double lx = 0, ln = 0;
    for (uint32_t y = 0; y < map.size; ++y)
      for (uint32_t x = 0; x < map.size; ++x)
        if (zs[size_t(y) * map.size + x] < 1.0f) lx += glm::dot(glm::vec2(x + 0.5f, y + 0.5f), axis), ln += 1;
    screen.push_back(n ? sx / n : 0.0);
    shadow.push_back(ln ? lx / ln : 0.0);
  }
  const double r = correlation(screen, shadow);
  // The world amplitude the screen implies, along `right`, in light pixels.
  const double expected = stddev(screen) * worldPerPixel * glm::length(along), measured = stddev(shadow);
  std::printf("wind on, %d frames: crown centroid on screen sways %.2f px (s.d.), the shadow's %.2f light px against %.2f implied "
              "(ratio %.2f); correlation %.3f\n",
              frames - 20, stddev(screen), measured, expected, measured / std::max(expected, 1e-9), r);
  EXPECT_GT(stddev(screen), 0.3) << "the wind sways the crown on screen";
  EXPECT_GE(r, 0.8);
  EXPECT_GT(measured / expected, 0.5);
  EXPECT_LT(measured / expected, 2.0);
  s.destroy();
  destroyImage(dev, map.image);
}

TEST_F(ShadowTest, BadInputsAreRefusedByNameAndUpdatesFollowTheInterval) {
  const VegetationModel m = shrub();
  Scene s;
  ASSERT_TRUE(s.create(dev, m, 1.0f).ok());
  ShadowMap map;
  ASSERT_TRUE(map.create(dev).ok());
  const glm::mat4 light = sunViewProj(m, false);
  VkCommandBuffer none = VK_NULL_HANDLE;
  // Before the first frame: nothing to follow.
  Status st = recordCanopyShadow(s.ctx, reinterpret_cast<VkCommandBuffer>(uintptr_t(1)), map.inputs(light));
  EXPECT_NE(st.message().find("record a frame first"), std::string::npos) << st.message();
  map.first = true;
  st = recordCanopyShadow(s.ctx, none, map.inputs(light));
  EXPECT_NE(st.message().find("null command buffer"), std::string::npos) << st.message();
  CanopyShadowInputs bad = map.inputs(light);
  bad.depth.format = VK_FORMAT_R8G8B8A8_UNORM;
  st = recordCanopyShadow(s.ctx, reinterpret_cast<VkCommandBuffer>(uintptr_t(1)), bad);
  EXPECT_NE(st.message().find("CanopyShadowInputs.depth.format"), std::string::npos) << st.message();
  bad = map.inputs(light);
  bad.depth.usage = VK_IMAGE_USAGE_SAMPLED_BIT;
  st = recordCanopyShadow(s.ctx, reinterpret_cast<VkCommandBuffer>(uintptr_t(1)), bad);
  EXPECT_NE(st.message().find("DEPTH_STENCIL_ATTACHMENT"), std::string::npos) << st.message();
  bad = map.inputs(light);
  bad.lightViewProj.m[5] = NAN;
  st = recordCanopyShadow(s.ctx, reinterpret_cast<VkCommandBuffer>(uintptr_t(1)), bad);
  EXPECT_NE(st.message().find("lightViewProj"), std::string::npos) << st.message();
  bad = map.inputs(light);
  bad.updateInterval = 0;
  st = recordCanopyShadow(s.ctx, reinterpret_cast<VkCommandBuffer>(uintptr_t(1)), bad);
  EXPECT_NE(st.message().find("updateInterval = 0"), std::string::npos) << st.message();
  bad = map.inputs(light);
  bad.cascade = 8;
  st = recordCanopyShadow(s.ctx, reinterpret_cast<VkCommandBuffer>(uintptr_t(1)), bad);
  EXPECT_NE(st.message().find("cascade = 8"), std::string::npos) << st.message();
  bad = map.inputs(light);
  bad.width = 0;
  st = recordCanopyShadow(s.ctx, reinterpret_cast<VkCommandBuffer>(uintptr_t(1)), bad);
  EXPECT_NE(st.message().find("width x height"), std::string::npos) << st.message();
  // Every third call of cascade 2 draws; the others keep the map (only its state moves).
  map.first = true;
  std::vector<int> drawn;
  s.host.recordAfter = [&](VkCommandBuffer cmd) {
    CanopyShadowInputs in = map.inputs(light);
    in.cascade = 2;
    in.updateInterval = 3;
    bool updated = false;
    CANOPY_TRY(recordCanopyShadow(s.ctx, cmd, in, &updated));
    drawn.push_back(updated ? 1 : 0);
    return Status();
  };
  for (int f = 0; f < 7; ++f) ASSERT_TRUE(s.host.frame(++frameNumber, {s.ctx}, s.view, 1.0f / 30.0f).ok());
  EXPECT_EQ(drawn, (std::vector<int>{1, 0, 0, 1, 0, 0, 1}));
  EXPECT_EQ(canopyStats(s.ctx).shadowUpdates, 3u);
  EXPECT_EQ(canopyStats(s.ctx).shadowSkips, 4u);
  std::vector<float> z;
  ASSERT_TRUE(map.read(dev, &z).ok());
  uint64_t n = 0;
  for (float v : z) n += v < 1.0f;
  EXPECT_GT(n, 2000u) << "the map kept between updates holds the shrub";
  s.destroy();
  destroyImage(dev, map.image);
}

}  // namespace
