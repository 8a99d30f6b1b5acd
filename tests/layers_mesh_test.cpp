// Layers from a streamed mesh and their shading (issues 38, 36): a mesh streamed through the
// staging ring within the device budget against the resident one, the budget's refusals, and leaf
// shading (Habel's translucency, normal maps, transmission textures) against the CPU evaluation.
#include "tests/layers_test_fixture.h"

using namespace canopy;
using namespace canopy::test::layers;

namespace {

// A view of the whole model from in front of it (+Z), at three radii.
LayerView viewOfModel(const VegetationModel& m, uint32_t w, uint32_t h) {
  const glm::vec3 c = 0.5f * (m.boundsMin + m.boundsMax);
  const float r = std::max(0.5f * glm::length(m.boundsMax - m.boundsMin), 1e-3f);
  LayerView v;
  v.view = glm::lookAt(c + glm::vec3(0.0f, 0.2f * r, 3.0f * r), c, glm::vec3(0, 1, 0));
  v.proj = perspectiveVulkan(glm::radians(45.0f), float(w) / float(h), 0.5f * r, 6.0f * r);
  return v;
}

// Bytes of the three mesh buffers (resident: the mesh; streamed: the rings).
uint64_t meshBufferBytes(const LayeredVegetation& lv) {
  return lv.mesh.vertices.allocation.size + lv.mesh.indexBuffer.allocation.size + lv.mesh.leafRoots.allocation.size;
}

}  // namespace

// issue 16: a mesh over the device-memory budget stays in host memory and reaches the GPU through
// the staging ring, a slice a frame. The layers equal those of the resident mesh pixel for pixel
// (both draw paths; chunks small enough that chunk borders fall inside leaves' neighbourhoods), for
// a re-slice asked at once (the first view: slices as large as the ring allows, copied in without a
// fade) and for a spread one; and the allocator's own counters stay within the budget.
TEST_F(LayersTest, StreamedMeshEqualsResidentMeshWithinTheBudget) {
  struct Case {
    std::string name;
    VegetationModel model;
    uint32_t width, height, chunkVertices;
    const char* layout;
  };
  std::vector<Case> cases;
  cases.push_back({"grid", straddlingLeaves(12, 8, true), kW, kH, 16, "5(3-1-1)"});
  {
    SceneDesc sd;
    sd.kind = SceneKind::Shrub;
    sd.faces = 80000;
    sd.seed = 5;
    sd.textureSize = 32;
    VegetationModel shrub;
    ASSERT_TRUE(generateScene(sd, &shrub).ok());
    cases.push_back({"shrub", std::move(shrub), 96, 72, 2048, "3(1-1-1)"});
  }
  for (Case& k : cases) {
    for (LayerDrawMode mode : {LayerDrawMode::SinglePass, LayerDrawMode::PerLayer}) {
      const std::string what = "streamed_" + k.name + (mode == LayerDrawMode::SinglePass ? "_single_pass" : "_per_layer");
      SCOPED_TRACE(what);
      LayeredVegetationDesc d;
      d.width = k.width;
      d.height = k.height;
      ASSERT_TRUE(parseLayerLayout(k.layout, &d.settings.layout).ok());
      d.settings.draw = mode;
      d.settings.rigidMotion = RigidMotion::Still;  // a streamed mesh draws its background: the resident one too
      d.maxChunkVertices = k.chunkVertices;
      // The resident reference, with both layer sets (what the budget plans for).
      LayeredVegetationDesc rd = d;
      rd.settings.rebuildBudgetMs = 2.0f;
      const uint64_t before = dev.allocator->liveBytes;
      LayeredVegetation y;
      ASSERT_TRUE(createLayeredVegetation(dev, k.model, rd, &y).ok());
      ASSERT_TRUE(y.stats.meshResident);
      const uint64_t residentBytes = dev.allocator->liveBytes - before;
      const uint64_t mesh = y.stats.meshBytes;
      // Budget: everything but the mesh, plus half the mesh; the ring gets a quarter of the mesh.
      const uint64_t otherBytes = residentBytes - meshBufferBytes(y);
      d.deviceMemoryBudget = otherBytes + mesh / 2;
      d.stagingRingBytes = mesh / 4;
      if (k.name == "shrub") {
        // The mesh several times what is left for it.
        EXPECT_GT(mesh, 3 * (d.deviceMemoryBudget - otherBytes) / 2);
      }
      const LayerView a = viewOfModel(k.model, k.width, k.height);
      ASSERT_TRUE(renderOnce(dev, y, a).ok());
      dev.allocator->peakLiveBytes = dev.allocator->liveBytes;  // this test's peak from here
      const uint64_t start = dev.allocator->liveBytes;
      LayeredVegetation x;
      Status made = createLayeredVegetation(dev, k.model, d, &x);
      ASSERT_TRUE(made.ok()) << made.message();
      EXPECT_FALSE(x.stats.meshResident);
      EXPECT_TRUE(x.mesh.streamed);
      EXPECT_GT(x.stats.meshRingBytes, 0u);
      EXPECT_LT(x.stats.meshRingBytes, mesh) << "the ring is smaller than the mesh";
      EXPECT_EQ(x.stats.meshBytes, mesh);
      EXPECT_EQ(meshBufferBytes(x) >= x.stats.meshRingBytes, true);
      auto run = std::make_unique<LayerFrames>(dev, x);
      ASSERT_TRUE(run->init().ok());
      const bool& changed = run->changed;
      auto frame = [&](const LayerView& v) { return run->frame(v); };
      // The first view, asked at once: slices until the whole mesh is drawn, the copy with the last.
      uint32_t frames = 0;
      uint64_t drawn = 0;
      do {
        ASSERT_TRUE(frame(a).ok());
        ++frames;
        drawn += x.stats.lastSliceTriangles;
        if (x.stats.spreadRebuilds == 0) EXPECT_FALSE(changed) << "frame " << frames << " changed the visible layers early";
        ASSERT_LT(frames, 100000u);
      } while (x.stats.spreadRebuilds == 0);
      EXPECT_TRUE(changed) << "the last slice's frame copies the new layers in";
      EXPECT_TRUE(x.reslice.occupancyDirty) << "and recomputes the occupancy in that frame";
      EXPECT_GT(frames, 2u) << "the ring holds less than the mesh: several slices";
      EXPECT_EQ(drawn, y.stats.foliageTriangles + y.stats.rigidTriangles);
      EXPECT_EQ(x.stats.lastSpreadFrames, frames);
      // Canopy's allocator: the streamed object never held more than its budget (checked before
      // the readbacks, whose staging buffers are the test's).
      EXPECT_LE(dev.allocator->peakLiveBytes - start, d.deviceMemoryBudget)
          << "peak " << dev.allocator->peakLiveBytes - start << " bytes, budget " << d.deviceMemoryBudget;
      expectSameLayers(x, y, what + "_at_once");
      std::vector<glm::vec4> bx, by;
      std::vector<float> zx, zy;
      ASSERT_TRUE(readBackground(x, &bx, &zx).ok());
      ASSERT_TRUE(readBackground(y, &by, &zy).ok());
      expectClose(bx, by, 0.0f, 0.0, what + "_background", k.width);
      expectIdentical(zx, zy, 1, what + "_background_depth", k.width);
      for (uint32_t l = 0; l < x.settings.layout.count(); ++l) EXPECT_EQ(x.visible.layers[l].slab.depth, y.visible.layers[l].slab.depth);
      // A spread re-slice (a 3-degree orbit with a budget): the same layers once it is done.
      LayerSettings s = x.settings;
      s.rebuildBudgetMs = 2.0f;
      s.crossFadeFrames = 3;
      bool recreated = true;
      ASSERT_TRUE(setLayerSettings(x, s, &recreated).ok());
      EXPECT_FALSE(recreated) << "a streamed mesh has the second set already";
      LayerView b = a;
      b.view = a.view * glm::rotate(glm::mat4(1.0f), glm::radians(3.0f), glm::vec3(0, 1, 0));
      dev.allocator->peakLiveBytes = dev.allocator->liveBytes;
      frames = 0;
      do {
        ASSERT_TRUE(frame(b).ok());
        ++frames;
        ASSERT_LT(frames, 100000u);
      } while (x.stats.spreadRebuilds == 1);
      EXPECT_GT(x.stats.lastSpreadFrames, 3u);
      EXPECT_LE(dev.allocator->peakLiveBytes - start, d.deviceMemoryBudget);
      y.reslice.forceImmediate = true;  // the reference at once (it has spreading on for its second set)
      ASSERT_TRUE(renderOnce(dev, y, b).ok());
      expectSameLayers(x, y, what + "_spread");
      run.reset();
      destroyLayeredVegetation(x);
      destroyLayeredVegetation(y);
    }
  }
}

// A budget the ring cannot fit in, and the id output over the budget, are refused naming the budget.
TEST_F(LayersTest, MeshBudgetRefusals) {
  const VegetationModel m = straddlingLeaves(12, 8, true);
  LayeredVegetationDesc d = smallDesc();
  d.writeIds = false;
  d.deviceMemoryBudget = 1 << 20;  // less than the layer images
  LayeredVegetation lv;
  Status s = createLayeredVegetation(dev, m, d, &lv);
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.message().find("deviceMemoryBudget 1.0 MiB"), std::string::npos) << s.message();
  EXPECT_NE(s.message().find("raise the budget"), std::string::npos) << s.message();
  d.writeIds = true;
  s = createLayeredVegetation(dev, m, d, &lv);
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.message().find("id output"), std::string::npos) << s.message();
  d.writeIds = false;
  d.deviceMemoryBudget = 0;
  d.stagingRingBytes = 0;
  s = createLayeredVegetation(dev, m, d, &lv);
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.message().find("stagingRingBytes"), std::string::npos) << s.message();
}

// Leaf shading (issue 17, seed 004 section III; shared/leaf_shading.h): one large leaf quad seen
// head-on through an orthographic camera, lit from several directions, against the CPU evaluation
// of the same terms. Tolerance: 2e-3 relative plus 1e-3 (the R16G16B16A16_SFLOAT layer's rounding).
namespace {

VegetationModel oneLeaf(glm::vec3 normal) {
  VegetationModel m = straddlingLeaves(1, 1, false);
  const glm::vec3 p[4] = {{-2, -2, 0}, {2, -2, 0}, {2, 2, 0}, {-2, 2, 0}};
  for (size_t v = 0; v < 4; ++v) {
    m.positions[v] = p[v];
    m.normals[v] = normal;
  }
  m.boundsMin = glm::vec3(-2, -2, 0);
  m.boundsMax = glm::vec3(2, 2, 0);
  return m;
}

LayerView orthoFront() {
  LayerView v;
  v.view = glm::mat4(1.0f);
  v.view[3][2] = -10.0f;  // camera at z = +10 looking down -Z
  v.proj = glm::orthoRH_ZO(-4.0f, 4.0f, -3.0f, 3.0f, 1.0f, 30.0f);
  v.proj[1][1] *= -1.0f;  // Vulkan: y down
  return v;
}

// Draws `m` with `d` seen through orthoFront(): layer 0's centre pixel and the first vertex's normal
// as the vertex shader decodes it.
Status shadeCentre(Device& dev, const VegetationModel& m, const LayeredVegetationDesc& d, glm::vec4* pixel,
                   glm::vec3* normal = nullptr) {
  LayeredVegetation lv;
  Status s = createLayeredVegetation(dev, m, d, &lv);
  std::vector<glm::vec4> c;
  if (s.ok()) s = renderOnce(dev, lv, orthoFront());
  if (s.ok()) s = readLayerColor(lv, 0, &c);
  if (s.ok()) *pixel = c[(kH / 2) * kW + kW / 2];
  if (s.ok() && normal) *normal = decodeNormal(lv.mesh.hostMesh.vertices[0]);
  destroyLayeredVegetation(lv);
  return s;
}

}  // namespace

TEST_F(LayersTest, LeafShadingMatchesTheCpuEvaluation) {
  struct Case {
    const char* what;
    glm::vec3 normal, light;
    float ior, roughness, transmission;  // transmission: LayerSettings.leafTransmission
  };
  const Case cases[] = {
      {"front lit from above", {0, 0, 1}, {0.3f, 0.5f, 0.8f}, 1.45f, 0.25f, 0.35f},
      {"front near the mirror direction, glossy", {0, 0, 1}, {0.15f, 0.0f, 1.0f}, 1.7f, 0.078f, 0.35f},
      {"front near the mirror direction, rough", {0, 0, 1}, {0.15f, 0.0f, 1.0f}, 1.2f, 0.5f, 0.35f},
      {"front at a grazing light", {0, 0, 1}, {0.95f, 0.0f, 0.2f}, 1.45f, 0.3f, 0.0f},
      {"tilted leaf, front lit", {0, 0.6f, 0.8f}, {0.0f, -0.2f, 1.0f}, 1.45f, 0.15f, 0.5f},
      {"front seen, light behind: transmission", {0, 0, 1}, {0.2f, 0.3f, -0.9f}, 1.45f, 0.25f, 0.6f},
      {"back seen, light in front of it: diffuse only", {0, 0, -1}, {0.3f, 0.4f, 0.8f}, 1.45f, 0.25f, 0.35f},
      {"back seen, light behind it: transmission", {0, 0, -1}, {-0.3f, 0.1f, -0.9f}, 1.45f, 0.25f, 0.8f},
  };
  for (TranslucencyModel model : {TranslucencyModel::Habel, TranslucencyModel::DiffuseBtdf})
  for (const Case& k : cases) {
    SCOPED_TRACE(model == TranslucencyModel::Habel ? "Habel's translucency" : "diffuse BTDF");
    const VegetationModel m = oneLeaf(glm::normalize(k.normal));
    LayeredVegetationDesc d = smallDesc("1");
    d.settings.translucencyModel = model;
    d.settings.leafOpticalDepth = 0.4f;
    d.settings.lightDirection = {k.light.x, k.light.y, k.light.z};
    d.settings.lightColor = {1.5f, 1.2f, 1.0f};
    d.settings.ambient = 0.2f;
    d.settings.leafRefractiveIndex = k.ior;
    d.settings.leafRoughness = k.roughness;
    d.settings.leafTransmission = k.transmission;
    glm::vec4 got;
    glm::vec3 n;  // the CPU side: the same decoded normal the vertex shader reads, the viewer +Z
    const Status s = shadeCentre(dev, m, d, &got, &n);
    ASSERT_TRUE(s.ok()) << s.message();
    const glm::vec3 v(0, 0, 1), l = glm::normalize(k.light);
    const bool front = glm::dot(n, v) >= 0.0f;
    if (!front) n = -n;
    const glm::vec3 base = glm::vec3(m.materials[0].baseColorFactor);
    const glm::vec3 want =
        model == TranslucencyModel::Habel
            ? gpu::leafShadeHabel(base, n, n, front, v, l, glm::vec3(1.5f, 1.2f, 1.0f), 0.2f, k.ior, k.roughness, 1.0f, k.transmission,
                                  gpu::leafTransmissionTint(base), glm::vec3(0.4f))
            : gpu::leafShade(base, n, front, v, l, glm::vec3(1.5f, 1.2f, 1.0f), 0.2f, k.ior, k.roughness, 1.0f, k.transmission,
                             gpu::leafTransmissionTint(base));
    EXPECT_NEAR(got.a, 1.0f, 1e-3f) << k.what;
    for (int i = 0; i < 3; ++i)
      EXPECT_NEAR(got[i], want[i], 2e-3f * std::max(1.0f, want[i]) + 1e-3f) << k.what << ", channel " << i;
  }
}

TEST_F(LayersTest, ABacklitLeafGlowsOnItsUnlitSideAndOutOfRangeLeafParametersAreRefused) {
  const VegetationModel m = oneLeaf({0, 0, 1});
  auto centre = [&](bool translucency, float transmission, glm::vec4* out) {
    LayeredVegetationDesc d = smallDesc("1");
    d.settings.lightDirection = {0.1f, 0.2f, -1.0f};  // behind the leaf, seen from the front
    d.settings.translucency = translucency;
    d.settings.leafTransmission = transmission;
    const Status s = shadeCentre(dev, m, d, out);
    ASSERT_TRUE(s.ok()) << s.message();
  };
  glm::vec4 on, off;
  centre(true, 0.5f, &on);
  centre(false, 0.5f, &off);
  const glm::vec3 base = glm::vec3(m.materials[0].baseColorFactor);
  // Without translucency the unlit side has the ambient term only.
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(off[i], base[i] * 0.35f, 2e-3f) << "channel " << i;
  EXPECT_GT(on.g, 1.5f * off.g) << "the backlit leaf must glow";
  // The measured ranges of Habel's section III.B, refused with the range.
  LayerSettings s;
  s.leafRefractiveIndex = 1.1f;
  Status st = validateLayerSettings(s);
  EXPECT_FALSE(st.ok());
  EXPECT_NE(st.message().find("leafRefractiveIndex = 1.1"), std::string::npos) << st.message();
  EXPECT_NE(st.message().find("[1.2, 1.7]"), std::string::npos) << st.message();
  s = LayerSettings{};
  s.leafRoughness = 0.6f;
  st = validateLayerSettings(s);
  EXPECT_FALSE(st.ok());
  EXPECT_NE(st.message().find("[0.078, 0.5]"), std::string::npos) << st.message();
  s = LayerSettings{};
  s.leafRoughness = NAN;
  EXPECT_FALSE(validateLayerSettings(s).ok());
  s = LayerSettings{};
  s.leafTransmission = -0.1f;
  EXPECT_FALSE(validateLayerSettings(s).ok());
}

// Normal maps and the transmission textures (issue 17): a 1x1 normal map tilting the normal
// towards +u and +v, and a transmission factor texture of alpha 0.5, against the CPU evaluation with the
// tilted normal (t = +x along +u, b = n x t, as the shader builds them) and the halved factor.
TEST_F(LayersTest, NormalMapsAndTransmissionTexturesEnterTheShading) {
  VegetationModel m = oneLeaf({0, 0, 1});
  const uint8_t enc[4] = {204, 166, 220, 255};  // about (0.6, 0.3, 0.73) in unit range
  ModelImage normals;
  normals.name = "normal map";
  normals.width = normals.height = 1;
  normals.rgba.assign(enc, enc + 4);
  normals.linear = true;
  ModelImage thickness;
  thickness.name = "transmission factor";
  thickness.width = thickness.height = 1;
  thickness.rgba = {255, 255, 255, 128};
  m.images = {normals, thickness};
  m.materials[0].normalImage = 0;
  m.materials[0].normalScale = 1.0f;
  m.materials[0].transmissionImage = 1;
  m.materials[0].transmissionFactor = 0.8f;
  m.materials[0].transmissionColor = glm::vec3(0.9f, 1.0f, 0.5f);
  const glm::vec3 mapped = glm::vec3(enc[0], enc[1], enc[2]) / 255.0f * 2.0f - 1.0f;
  const glm::vec3 tilted = glm::normalize(mapped.x * glm::vec3(1, 0, 0) + mapped.y * glm::vec3(0, 1, 0) + mapped.z * glm::vec3(0, 0, 1));
  const glm::vec3 base = glm::vec3(m.materials[0].baseColorFactor);
  struct Case {
    const char* what;
    glm::vec3 light;
  };
  for (const Case& k : {Case{"front lit from +x+y: the tilted normal catches more light", {0.7f, 0.5f, 0.6f}},
                        Case{"backlit: the factor texture halves the transmission", {0.2f, 0.1f, -1.0f}}}) {
    LayeredVegetationDesc d = smallDesc("1");
    d.settings.lightDirection = {k.light.x, k.light.y, k.light.z};
    d.settings.ambient = 0.2f;
    d.settings.translucencyModel = TranslucencyModel::DiffuseBtdf;  // Habel's: LayersTest.HabelsTranslucency*
    glm::vec4 got;
    const Status s = shadeCentre(dev, m, d, &got);
    ASSERT_TRUE(s.ok()) << s.message();
    const float t = 0.8f * 128.0f / 255.0f;
    const glm::vec3 want = gpu::leafShade(base, tilted, true, glm::vec3(0, 0, 1), glm::normalize(k.light), glm::vec3(1.0f), 0.2f,
                                          1.45f, 0.25f, 1.0f, t, glm::vec3(0.9f, 1.0f, 0.5f));
    const glm::vec3 flat = gpu::leafShade(base, glm::vec3(0, 0, 1), true, glm::vec3(0, 0, 1), glm::normalize(k.light), glm::vec3(1.0f),
                                          0.2f, 1.45f, 0.25f, 1.0f, t, glm::vec3(0.9f, 1.0f, 0.5f));
    for (int i = 0; i < 3; ++i)
      EXPECT_NEAR(got[i], want[i], 3e-3f * std::max(1.0f, want[i]) + 2e-3f) << k.what << ", channel " << i;
    EXPECT_GT(std::abs(want.g - flat.g), 0.02f) << k.what << ": the case must tell a mapped normal from the flat one";
  }
  // A material naming an image the model does not have is refused, not read out of bounds.
  m.materials[0].normalImage = 7;
  LayeredVegetation bad;
  Status s = createLayeredVegetation(dev, m, smallDesc("1"), &bad);
  EXPECT_FALSE(s.ok());
  EXPECT_NE(s.message().find("names image 7 of 2"), std::string::npos) << s.message();
}

// The layer draws' fragment shader is specialised for what the model and the settings can meet
// (docs/lab/performance-notebook.md "Specialised shading"): a settings change that changes it switches to
// pipelines made for the new settings, keeps the old ones, and a switch back reuses them; each
// switch shades as the CPU evaluation of the model in force.
TEST_F(LayersTest, SpecialisedShadingFollowsTheModelAndTheSettings) {
  const glm::vec3 light = glm::normalize(glm::vec3(0.2f, 0.3f, -0.9f));  // behind the leaf: transmission
  const VegetationModel plain = oneLeaf({0, 0, 1});
  VegetationModel mapped = plain;
  ModelImage normals;
  normals.name = "normal map";
  normals.width = normals.height = 1;
  normals.rgba = {128, 128, 255, 255};
  normals.linear = true;
  mapped.images = {normals};
  mapped.materials[0].normalImage = 0;
  mapped.materials[0].normalScale = 1.0f;
  LayeredVegetationDesc d = smallDesc("1");
  d.settings.lightDirection = {light.x, light.y, light.z};
  d.settings.ambient = 0.2f;
  d.settings.leafOpticalDepth = 0.4f;
  {
    LayeredVegetation lv;
    ASSERT_TRUE(createLayeredVegetation(dev, mapped, d, &lv).ok());
    EXPECT_EQ(lv.pipelines.shaded.features, LAYER_FEATURE_HABEL | LAYER_FEATURE_NORMAL_MAP);
    destroyLayeredVegetation(lv);
  }
  LayeredVegetation lv;
  ASSERT_TRUE(createLayeredVegetation(dev, plain, d, &lv).ok());
  EXPECT_EQ(lv.pipelines.shaded.features, LAYER_FEATURE_HABEL) << "no texture, no level colours: only Habel's model is compiled";
  const VkPipeline habelPipeline = lv.pipelines.shaded.layered.pipeline ? lv.pipelines.shaded.layered.pipeline : lv.pipelines.shaded.perLayer.pipeline;
  const glm::vec3 base = glm::vec3(plain.materials[0].baseColorFactor);
  const float t = d.settings.leafTransmission;
  const glm::vec3 tint = gpu::leafTransmissionTint(base);
  auto expectCentre = [&](const glm::vec3& want, const char* what) {
    std::vector<glm::vec4> c;
    Status s = renderOnce(dev, lv, orthoFront());
    if (s.ok()) s = readLayerColor(lv, 0, &c);
    ASSERT_TRUE(s.ok()) << s.message();
    const glm::vec4 got = c[(kH / 2) * kW + kW / 2];
    for (int i = 0; i < 3; ++i) EXPECT_NEAR(got[i], want[i], 3e-3f * std::max(1.0f, want[i]) + 2e-3f) << what << ", channel " << i;
  };
  const glm::vec3 habel = gpu::leafShadeHabel(base, glm::vec3(0, 0, 1), glm::vec3(0, 0, 1), true, glm::vec3(0, 0, 1), light, glm::vec3(1.0f),
                                              0.2f, 1.45f, 0.25f, 1.0f, t, tint, glm::vec3(0.4f));
  const glm::vec3 diffuse = gpu::leafShade(base, glm::vec3(0, 0, 1), true, glm::vec3(0, 0, 1), light, glm::vec3(1.0f), 0.2f, 1.45f, 0.25f,
                                           1.0f, t, tint);
  ASSERT_GT(glm::length(habel - diffuse), 0.01f) << "the case must tell the two models apart";
  expectCentre(habel, "Habel's model");
  LayerSettings s = d.settings;
  s.translucencyModel = TranslucencyModel::DiffuseBtdf;
  ASSERT_TRUE(setLayerSettings(lv, s).ok());
  EXPECT_EQ(lv.pipelines.shaded.features, LAYER_FEATURE_DIFFUSE_BTDF);
  EXPECT_EQ(lv.pipelines.otherShading.size(), 1u) << "Habel's pipelines kept: a frame in flight may use them";
  expectCentre(diffuse, "the diffuse BTDF");
  s.translucencyModel = TranslucencyModel::Habel;
  ASSERT_TRUE(setLayerSettings(lv, s).ok());
  EXPECT_EQ(lv.pipelines.shaded.features, LAYER_FEATURE_HABEL);
  EXPECT_EQ(lv.pipelines.otherShading.size(), 1u) << "switched back: the kept pipelines, none made";
  EXPECT_EQ(lv.pipelines.shaded.layered.pipeline ? lv.pipelines.shaded.layered.pipeline : lv.pipelines.shaded.perLayer.pipeline, habelPipeline);
  expectCentre(habel, "Habel's model again");
  destroyLayeredVegetation(lv);
}

// Habel's translucency (seed 004 III.C) against the CPU evaluation on a backlit leaf with a normal
// map and a KHR_materials_volume thickness: the light-facing side's relief and its Fresnel entry,
// its self-shadowing at grazing light and Beer-Lambert through the thickness. The relief's effect
// grows from steep to grazing light (seed Figure 5); the thickness darkens and tints.
TEST_F(LayersTest, HabelsTranslucencyMatchesTheCpuEvaluation) {
  VegetationModel m = oneLeaf({0, 0, 1});
  const uint8_t enc[4] = {204, 166, 220, 255};  // about (0.6, 0.3, 0.73): a facet of a vein's flank
  ModelImage normals;
  normals.name = "normal map";
  normals.width = normals.height = 1;
  normals.rgba.assign(enc, enc + 4);
  normals.linear = true;
  m.images = {normals};
  m.materials[0].normalImage = 0;
  m.materials[0].normalScale = 1.0f;
  m.materials[0].transmissionFactor = 0.7f;
  m.materials[0].transmissionColor = glm::vec3(0.8f, 1.0f, 0.4f);
  m.materials[0].thicknessFactor = 0.002f;  // 2 mm (KHR_materials_volume)
  m.materials[0].attenuationDistance = 0.004f;
  m.materials[0].attenuationColor = glm::vec3(0.5f, 0.9f, 0.3f);
  const glm::vec3 tau = 0.002f * -glm::log(glm::vec3(0.5f, 0.9f, 0.3f)) / 0.004f;
  const glm::vec3 mapped = glm::vec3(enc[0], enc[1], enc[2]) / 255.0f * 2.0f - 1.0f;
  const glm::vec3 tilted = glm::normalize(mapped);
  const glm::vec3 base = glm::vec3(m.materials[0].baseColorFactor);
  float reliefSteep = 0, reliefGrazing = 0;
  for (float elevation : {80.0f, 45.0f, 20.0f, 8.0f}) {
    // The light behind the leaf (seen from +z, its front), from steep to grazing.
    const float e = glm::radians(elevation);
    const glm::vec3 l(-std::cos(e), 0.0f, -std::sin(e));
    LayeredVegetationDesc d = smallDesc("1");
    d.settings.lightDirection = {l.x, l.y, l.z};
    d.settings.ambient = 0.2f;
    glm::vec4 got;
    const Status s = shadeCentre(dev, m, d, &got);
    ASSERT_TRUE(s.ok()) << s.message();
    const glm::vec3 want = gpu::leafShadeHabel(base, tilted, glm::vec3(0, 0, 1), true, glm::vec3(0, 0, 1), l, glm::vec3(1.0f), 0.2f,
                                               1.45f, 0.25f, 1.0f, 0.7f, glm::vec3(0.8f, 1.0f, 0.4f), tau);
    const glm::vec3 flat = gpu::leafShadeHabel(base, glm::vec3(0, 0, 1), glm::vec3(0, 0, 1), true, glm::vec3(0, 0, 1), l, glm::vec3(1.0f),
                                               0.2f, 1.45f, 0.25f, 1.0f, 0.7f, glm::vec3(0.8f, 1.0f, 0.4f), tau);
    const glm::vec3 btdf = gpu::leafShade(base, tilted, true, glm::vec3(0, 0, 1), l, glm::vec3(1.0f), 0.2f, 1.45f, 0.25f, 1.0f, 0.7f,
                                          glm::vec3(0.8f, 1.0f, 0.4f));
    std::printf("light %2.0f deg above the leaf's plane: Habel (%.4f %.4f %.4f), flat relief (%.4f %.4f %.4f), diffuse BTDF (%.4f %.4f %.4f)\n",
                elevation, want.r, want.g, want.b, flat.r, flat.g, flat.b, btdf.r, btdf.g, btdf.b);
    for (int i = 0; i < 3; ++i)
      EXPECT_NEAR(got[i], want[i], 3e-3f * std::max(1.0f, want[i]) + 2e-3f) << elevation << " deg, channel " << i;
    const float ambient = 0.2f * base.g;
    const float relief = std::abs((want.g - ambient) / std::max(flat.g - ambient, 1e-6f) - 1.0f);
    if (elevation == 80.0f) reliefSteep = relief;
    if (elevation == 8.0f) reliefGrazing = relief;
    // Beer-Lambert: the red and blue channels (attenuated more) fall below what the colour alone gives.
    EXPECT_LT((want.b - 0.2f * base.b) / 0.4f, (want.g - 0.2f * base.g) / 1.0f) << elevation;
  }
  EXPECT_GT(reliefGrazing, 2.0f * reliefSteep) << "the relief shows at grazing light, not at steep light";
}

// Habel's translucency on the shared plant with a thickness added (KHR_materials_volume's values
// set on its foliage materials): the backlit leaves transmit less; the diffuse BTDF ignores the
// thickness.
TEST_F(LayersTest, ThePlantWithAThicknessAddedTransmitsLess) {
  const std::string path = kAssets + "/DiffuseTransmissionPlant/DiffuseTransmissionPlant.gltf";
  if (!std::filesystem::exists(path)) GTEST_SKIP() << "shared assets folder absent (" << kAssets << "): skipped";
  VegetationModel plain;
  ASSERT_TRUE(loadGltf(path, {}, &plain).ok());
  VegetationModel thick = plain;
  for (ModelMaterial& mat : thick.materials)
    if (mat.transmissionFactor > 0.0f) {
      mat.thicknessFactor = 0.002f;
      mat.attenuationDistance = 0.002f;
      mat.attenuationColor = glm::vec3(0.3f, 0.8f, 0.2f);
    }
  const LayerView view = orbitView(plain.boundsMin, plain.boundsMax, 0.0f, 10.0f, 40.0f, float(kW) / float(kH), 1.0f);
  // Mean colour of layer 0's covered texels, the light behind the plant.
  auto mean = [&](const VegetationModel& m, TranslucencyModel model) {
    LayeredVegetationDesc d = smallDesc("1");
    d.settings.lightDirection = {0.2f, 0.4f, -1.0f};
    d.settings.translucencyModel = model;
    d.settings.leafTransmission = 0.8f;
    LayeredVegetation lv;
    Status s = createLayeredVegetation(dev, m, d, &lv);
    std::vector<glm::vec4> c;
    if (s.ok()) s = renderOnce(dev, lv, view);
    if (s.ok()) s = readLayerColor(lv, 0, &c);
    EXPECT_TRUE(s.ok()) << s.message();
    destroyLayeredVegetation(lv);
    glm::dvec3 sum(0.0);
    size_t n = 0;
    for (const glm::vec4& p : c)
      if (p.a > 0.5f) sum += glm::dvec3(p) / double(p.a), ++n;
    EXPECT_GT(n, 1000u);
    return glm::vec3(sum / double(std::max<size_t>(n, 1)));
  };
  const glm::vec3 a = mean(plain, TranslucencyModel::Habel), b = mean(thick, TranslucencyModel::Habel);
  const glm::vec3 c = mean(plain, TranslucencyModel::DiffuseBtdf), e = mean(thick, TranslucencyModel::DiffuseBtdf);
  std::printf("backlit plant, mean leaf colour: Habel (%.4f %.4f %.4f) -> with thickness (%.4f %.4f %.4f); diffuse BTDF (%.4f %.4f %.4f) -> (%.4f %.4f %.4f)\n",
              a.r, a.g, a.b, b.r, b.g, b.b, c.r, c.g, c.b, e.r, e.g, e.b);
  // The file's transmission colour texture passes mostly red: the glow, and so what the thickness
  // takes away, is in the channels the leaves transmit; no channel gains.
  for (int k = 0; k < 3; ++k) {
    EXPECT_LE(b[k], a[k] + 1e-5f) << "channel " << k << ": the thickness absorbs";
    EXPECT_NEAR(e[k], c[k], 1e-4f) << "channel " << k << ": the BTDF has no thickness";
  }
  EXPECT_LT(b.r + b.g + b.b, a.r + a.g + a.b - 0.003f) << "the backlit plant transmits less through a thickness";
}
