// Depth-sliced layer rasterization (paper 3.2) on the device, under the validation helper:
// whole leaves per layer (read back by leaf and triangle id), the per-triangle slicing that cuts
// them, single pass == per-layer fallback pixel for pixel, automatic fallback selection, alpha
// cutoff, the rigid background, and the re-slicing policy.
#include "render/rigid_refine.h"
#include "tests/layers_test_fixture.h"

using namespace canopy;
using namespace canopy::test::layers;

TEST_F(LayersTest, EveryLeafLandsWholeInTheLayerOfItsRoot) {
  const VegetationModel m = straddlingLeaves(12, 8, true);
  LayeredVegetation lv;
  Status s = createLayeredVegetation(dev, m, smallDesc(), &lv);
  ASSERT_TRUE(s.ok()) << s.message();
  EXPECT_TRUE(lv.pipelines.singlePass) << "lavapipe has shaderOutputLayer: the single pass is expected";
  ASSERT_TRUE(renderOnce(dev, lv, frontView()).ok());
  const uint32_t leaves = 12 * 8;
  EXPECT_EQ(lv.stats.leafCount, leaves);
  const uint32_t straddlers = countStraddlers(lv);
  EXPECT_GE(straddlers, leaves / 4) << "the test mesh must put many leaves across layer boundaries";
  Coverage c = readCoverage(lv);
  EXPECT_EQ(c.layersOfLeaf.size(), leaves) << "every leaf is visible in some layer";
  EXPECT_EQ(c.layersOfTriangle.size(), 2u * leaves) << "every foliage triangle is visible in some layer";
  std::vector<uint32_t> perLayer(lv.settings.layout.count(), 0);
  const std::map<uint32_t, glm::vec3> rootOf = rootPositions(lv);
  for (auto& [leaf, layers] : c.layersOfLeaf) {
    ASSERT_EQ(layers.size(), 1u) << "leaf " << leaf << " is cut across " << layers.size() << " layers";
    const float rootDepth = glm::dot(lv.visible.frame.depthRow, glm::vec4(rootOf.at(leaf), 1.0f));
    EXPECT_EQ(*layers.begin(), gpu::layerOfDepth(lv.visible.frame, rootDepth)) << "leaf " << leaf;
    perLayer[*layers.begin()]++;
  }
  for (auto& [tri, layers] : c.layersOfTriangle) EXPECT_EQ(layers.size(), 1u) << "triangle " << tri;
  for (uint32_t l = 0; l < perLayer.size(); ++l) {
    EXPECT_GT(perLayer[l], 0u) << "layer " << l << " is empty";
    EXPECT_EQ(perLayer[l], lv.visible.layers[l].leaves) << "the CPU placement statistics disagree in layer " << l;
  }
  destroyLayeredVegetation(lv);
}

TEST_F(LayersTest, PerTriangleSlicingCutsTheSameLeaves) {
  const VegetationModel m = straddlingLeaves(12, 8, false);
  LayeredVegetationDesc d = smallDesc();
  d.settings.slice = SliceMode::Geometry;
  LayeredVegetation lv;
  ASSERT_TRUE(createLayeredVegetation(dev, m, d, &lv).ok());
  EXPECT_FALSE(lv.pipelines.singlePass);
  ASSERT_TRUE(renderOnce(dev, lv, frontView()).ok());
  Coverage c = readCoverage(lv);
  uint32_t cut = 0, cutTriangles = 0;
  for (auto& [leaf, layers] : c.layersOfLeaf) cut += layers.size() > 1;
  for (auto& [tri, layers] : c.layersOfTriangle) cutTriangles += layers.size() > 1;
  // The near/far planes on the fragments' own depth split straddling leaves (and triangles).
  EXPECT_GE(cut, 12u * 8u / 4u) << "the simple segmentation should cut many of these leaves";
  EXPECT_GT(cutTriangles, 0u);
  destroyLayeredVegetation(lv);
}

namespace {
// The models two draw ways are compared on: the leaf grid, the generated shrub when asked (alpha-
// masked leaves, rigid branches) and the shared real plant when the assets are there (a note
// otherwise); false when a model could not be made.
bool comparisonModels(bool shrub, std::vector<std::pair<std::string, VegetationModel>>* models) {
  models->push_back({"leaves", straddlingLeaves(12, 8, true)});
  if (shrub) {
    SceneDesc sd;
    sd.kind = SceneKind::Shrub;
    sd.faces = 20000;
    sd.seed = 5;
    sd.textureSize = 32;
    VegetationModel m;
    if (!generateScene(sd, &m).ok()) return false;
    models->push_back({"shrub", std::move(m)});
  }
  const std::string plant = kAssets + "/DiffuseTransmissionPlant/DiffuseTransmissionPlant.gltf";
  if (!std::filesystem::exists(plant)) {
    std::printf("[ note ] shared assets absent: the real-model part of this test is skipped\n");
    return true;
  }
  VegetationModel m;
  if (!loadGltf(plant, {}, &m).ok()) return false;
  models->push_back({"plant", std::move(m)});
  return true;
}
}  // namespace

TEST_F(LayersTest, SinglePassEqualsPerLayerDrawsPixelForPixel) {
  std::vector<std::pair<std::string, VegetationModel>> models;
  ASSERT_TRUE(comparisonModels(false, &models));
  for (auto& [name, m] : models) {
    LayeredVegetationDesc a = smallDesc();
    a.settings.draw = LayerDrawMode::SinglePass;
    LayeredVegetationDesc b = a;
    b.settings.draw = LayerDrawMode::PerLayer;
    LayeredVegetation x, y;
    ASSERT_TRUE(createLayeredVegetation(dev, m, a, &x).ok());
    ASSERT_TRUE(createLayeredVegetation(dev, m, b, &y).ok());
    ASSERT_TRUE(x.pipelines.singlePass);
    ASSERT_FALSE(y.pipelines.singlePass);
    const LayerView view = name == "leaves" ? frontView() : orbitView(m.boundsMin, m.boundsMax, 30, 15, 40, float(kW) / kH, 0.8f);
    ASSERT_TRUE(renderOnce(dev, x, view).ok());
    ASSERT_TRUE(renderOnce(dev, y, view).ok());
    size_t covered = 0;
    for (uint32_t l = 0; l < x.settings.layout.count(); ++l) {
      std::vector<glm::vec4> c;
      ASSERT_TRUE(readLayerColor(x, l, &c).ok());
      for (const glm::vec4& p : c) covered += p.a > 0;
    }
    EXPECT_GT(covered, size_t(kW) * kH / 50) << name << ": the comparison must cover a real image";
    expectSameLayers(x, y, name);
    destroyLayeredVegetation(x);
    destroyLayeredVegetation(y);
  }
}

// Shading once (docs/design.md "Layers: shading once") changes which fragments are shaded, not
// the layers: the depth pre-pass and the EQUAL shading give the plain draw's images on both draw
// paths, for the leaf grid, the generated shrub (alpha-masked leaves, rigid branches) and a real
// plant. Colour and depth by a metric (edges of coplanar leaves may resolve a tie the other way).
TEST_F(LayersTest, ShadingOnceEqualsShadingEveryFragment) {
  std::vector<std::pair<std::string, VegetationModel>> models;
  ASSERT_TRUE(comparisonModels(true, &models));
  for (auto& [name, m] : models) {
    for (LayerDrawMode mode : {LayerDrawMode::SinglePass, LayerDrawMode::PerLayer}) {
      const std::string what = "shade_once_" + name + (mode == LayerDrawMode::SinglePass ? "_single_pass" : "_per_layer");
      SCOPED_TRACE(what);
      LayeredVegetationDesc a = smallDesc();
      a.writeIds = false;  // the id output is drawn the plain way
      a.settings.draw = mode;
      LayeredVegetationDesc b = a;
      a.settings.shadeOnce = true;
      b.settings.shadeOnce = false;
      LayeredVegetation x, y;
      ASSERT_TRUE(createLayeredVegetation(dev, m, a, &x).ok());
      ASSERT_TRUE(createLayeredVegetation(dev, m, b, &y).ok());
      ASSERT_NE(mode == LayerDrawMode::SinglePass ? x.pipelines.shaded.layeredOnce.shade.pipeline : x.pipelines.shaded.perLayerOnce.shade.pipeline,
                VK_NULL_HANDLE);
      const LayerView view = name == "leaves" ? frontView() : orbitView(m.boundsMin, m.boundsMax, 30, 15, 40, float(kW) / kH, 0.8f);
      ASSERT_TRUE(renderOnce(dev, x, view).ok());
      ASSERT_TRUE(renderOnce(dev, y, view).ok());
      size_t covered = 0;
      for (uint32_t l = 0; l < x.settings.layout.count(); ++l) {
        std::vector<glm::vec4> ca, cb;
        std::vector<float> da, db;
        ASSERT_TRUE(readLayerColor(x, l, &ca).ok());
        ASSERT_TRUE(readLayerColor(y, l, &cb).ok());
        ASSERT_TRUE(readLayerDepth(x, l, &da).ok());
        ASSERT_TRUE(readLayerDepth(y, l, &db).ok());
        for (const glm::vec4& p : cb) covered += p.a > 0;
        std::vector<glm::vec4> va(da.size()), vb(db.size());
        for (size_t i = 0; i < da.size(); ++i) va[i] = glm::vec4(da[i]), vb[i] = glm::vec4(db[i]);
        expectClose(ca, cb, 2e-3f, 0.002, what + "_colour_layer" + std::to_string(l));
        expectClose(va, vb, 1e-6f, 0.002, what + "_depth_layer" + std::to_string(l));
      }
      EXPECT_GT(covered, size_t(kW) * kH / 50) << "the comparison must cover a real image";
      if (x.mesh.hasRigid) {
        std::vector<glm::vec4> ca, cb;
        std::vector<float> da, db;
        ASSERT_TRUE(readBackground(x, &ca, &da).ok());
        ASSERT_TRUE(readBackground(y, &cb, &db).ok());
        expectClose(ca, cb, 2e-3f, 0.002, what + "_background");
      }
      destroyLayeredVegetation(x);
      destroyLayeredVegetation(y);
    }
  }
}

TEST_F(LayersWithoutGlLayerTest, FallbackIsChosenAutomaticallyAndKeepsLeavesWhole) {
  ASSERT_FALSE(dev.shaderOutputLayer);
  const VegetationModel m = straddlingLeaves(8, 6, false);
  LayeredVegetation lv;
  ASSERT_TRUE(createLayeredVegetation(dev, m, smallDesc("3(1-1-1)"), &lv).ok());
  EXPECT_FALSE(lv.pipelines.singlePass) << "Auto must pick one draw per layer without shaderOutputLayer";
  EXPECT_FALSE(lv.pipelines.shaded.layered.pipeline) << "no gl_Layer pipeline may be created on such a device";
  ASSERT_TRUE(renderOnce(dev, lv, frontView()).ok());
  Coverage c = readCoverage(lv);
  EXPECT_EQ(c.layersOfLeaf.size(), 48u);
  for (auto& [leaf, layers] : c.layersOfLeaf) EXPECT_EQ(layers.size(), 1u) << "leaf " << leaf;
  LayeredVegetationDesc forced = smallDesc();
  forced.settings.draw = LayerDrawMode::SinglePass;
  LayeredVegetation bad;
  Status s = createLayeredVegetation(dev, m, forced, &bad);
  EXPECT_FALSE(s.ok());
  EXPECT_NE(s.message().find("shaderOutputLayer"), std::string::npos) << s.message();
  destroyLayeredVegetation(lv);
}

TEST_F(LayersTest, AlphaCutoffAndRigidBackground) {
  VegetationModel m = straddlingLeaves(1, 1, true);
  // Replace the leaf by a flat, camera-facing quad with a texture: left texel alpha 0.3, right 1.
  for (size_t v = 0; v < 4; ++v) m.positions[v].z = 1.0f;
  m.materials[0].alphaMode = AlphaMode::Mask;
  m.materials[0].alphaCutoff = 0.5f;
  m.materials[0].baseColorImage = 0;
  ModelImage img;
  img.name = "half";
  img.width = 2;
  img.height = 1;
  img.rgba = {255, 255, 255, 77, 255, 255, 255, 255};
  m.images.push_back(img);
  for (size_t v = 0; v < 4; ++v) m.uvs[v] = glm::vec2(m.uvs[v].x * 0.5f + 0.25f, m.uvs[v].y);  // texel centres
  LayeredVegetationDesc d = smallDesc("1");
  LayeredVegetation lv;
  ASSERT_TRUE(createLayeredVegetation(dev, m, d, &lv).ok());
  // The rigid quad as refined for the displacement it follows (render/rigid_refine.h): its two
  // triangles split until no edge is longer than kRigidEdgeShare of the model's height, a pass
  // quartering each triangle, at most kRigidRefinePasses passes.
  EXPECT_GT(lv.stats.rigidTriangles, 2u);
  EXPECT_LE(lv.stats.rigidTriangles, 2u << (2 * kRigidRefinePasses));
  ASSERT_TRUE(renderOnce(dev, lv, frontView()).ok());
  std::vector<glm::vec4> c;
  ASSERT_TRUE(readLayerColor(lv, 0, &c).ok());
  // Linear filtering between the texel centres (u = 0.25 and 0.75) crosses the cutoff at
  // u = 0.25 + 0.5 (0.5 - a) / (1 - a) with a = 77/255: everything left of it must be cut away.
  const glm::mat4 vp = lv.visible.frame.viewProj;
  auto screenX = [&](glm::vec3 p) {
    glm::vec4 q = vp * glm::vec4(p, 1.0f);
    return (q.x / q.w * 0.5f + 0.5f) * float(kW);
  };
  const float a = 77.0f / 255.0f, cross = (0.5f - a) / (1.0f - a);
  const float xl = screenX(m.positions[0]), xr = screenX(m.positions[1]), xm = xl + cross * (xr - xl);
  size_t left = 0, right = 0;
  for (uint32_t y = 0; y < kH; ++y)
    for (uint32_t x = 0; x < kW; ++x) {
      const glm::vec4 p = c[size_t(y) * kW + x];
      if (p.a <= 0) continue;
      EXPECT_FLOAT_EQ(p.a, 1.0f) << "masked leaves are opaque where kept";
      const float cx = float(x) + 0.5f;
      if (cx < xm - 1) ++left;
      else if (cx > xm + 1) ++right;
    }
  EXPECT_EQ(left, 0u) << "texels below alphaCutoff were drawn";
  EXPECT_GT(right, 100u);
  EXPECT_GT(xm - xl, 10.0f) << "the cut-away part must be wide enough to see";
  std::vector<glm::vec4> bg;
  std::vector<float> bgDepth;
  ASSERT_TRUE(readBackground(lv, &bg, &bgDepth).ok());
  size_t bark = 0;
  for (size_t i = 0; i < bg.size(); ++i)
    if (bg[i].a > 0) {
      ++bark;
      EXPECT_LT(bgDepth[i], 1.0f);
    }
  EXPECT_GT(bark, 500u) << "the rigid quad must be in the background";
  destroyLayeredVegetation(lv);
}

// Issue 16: chunks of at most 3 vertices put every triangle in a chunk of its own, so each leaf
// quad is split by a chunk border (and its root sits in two chunk tables). Leaves stay whole in
// the layer of their root, the ids are those of the default chunking, and the images differ only
// where the per-chunk quantisation moves an edge by a fraction of a pixel.
TEST_F(LayersTest, ChunkBordersInsideLeavesCutNoLeaf) {
  const VegetationModel m = straddlingLeaves(12, 8, true);
  for (LayerDrawMode mode : {LayerDrawMode::SinglePass, LayerDrawMode::PerLayer}) {
    const std::string what = mode == LayerDrawMode::SinglePass ? "single_pass" : "per_layer";
    LayeredVegetationDesc a = smallDesc();
    a.settings.draw = mode;
    LayeredVegetationDesc b = a;
    b.maxChunkVertices = 3;
    LayeredVegetation x, y;
    ASSERT_TRUE(createLayeredVegetation(dev, m, a, &x).ok());
    Status s = createLayeredVegetation(dev, m, b, &y);
    ASSERT_TRUE(s.ok()) << s.message();
    EXPECT_LE(x.mesh.chunks.size(), 2u) << "default chunking: one foliage and one rigid chunk";
    // One triangle per chunk: the 2 x 12 x 8 leaf triangles and the rigid quad's as refined
    // (render/rigid_refine.h).
    EXPECT_EQ(y.mesh.chunks.size(), size_t(2 * 12 * 8) + y.stats.rigidTriangles) << "one triangle per chunk";
    EXPECT_EQ(y.stats.meshChunks, y.mesh.chunks.size());
    ASSERT_TRUE(renderOnce(dev, x, frontView()).ok());
    ASSERT_TRUE(renderOnce(dev, y, frontView()).ok());
    Coverage c = readCoverage(y);
    EXPECT_EQ(c.layersOfLeaf.size(), 12u * 8u) << what;
    const std::map<uint32_t, glm::vec3> rootOf = rootPositions(y);
    for (auto& [leaf, layers] : c.layersOfLeaf) {
      ASSERT_EQ(layers.size(), 1u) << what << ": leaf " << leaf << " is cut across " << layers.size() << " layers";
      const float rootDepth = glm::dot(y.visible.frame.depthRow, glm::vec4(rootOf.at(leaf), 1.0f));
      EXPECT_EQ(*layers.begin(), gpu::layerOfDepth(y.visible.frame, rootDepth)) << what << ": leaf " << leaf;
    }
    Coverage cx = readCoverage(x);
    EXPECT_EQ(c.layersOfLeaf, cx.layersOfLeaf) << what << ": leaves land in other layers than with one chunk";
    for (uint32_t l = 0; l < x.settings.layout.count(); ++l) {
      std::vector<glm::vec4> ca, cb;
      ASSERT_TRUE(readLayerColor(x, l, &ca).ok());
      ASSERT_TRUE(readLayerColor(y, l, &cb).ok());
      expectClose(ca, cb, 0.02f, 0.005, what + "_chunks_layer" + std::to_string(l));
    }
    destroyLayeredVegetation(x);
    destroyLayeredVegetation(y);
  }
}

TEST_F(LayersTest, ReslicingFollowsThePolicy) {
  const VegetationModel m = straddlingLeaves(4, 3, false);
  LayeredVegetationDesc d = smallDesc("3(1-1-1)");
  d.settings.errorThresholdPixels = 1.0f;
  d.settings.turnThresholdDegrees = 2.0f;
  LayeredVegetation lv;
  ASSERT_TRUE(createLayeredVegetation(dev, m, d, &lv).ok());
  bool rebuild = false;
  LayerView v = frontView();
  ASSERT_TRUE(updateLayerView(lv, v, &rebuild).ok());
  EXPECT_TRUE(rebuild);
  ASSERT_TRUE(updateLayerView(lv, v, &rebuild).ok());
  EXPECT_FALSE(rebuild) << "a still camera must not rebuild";
  const float radius = 0.5f * glm::length(m.boundsMax - m.boundsMin);
  // Issue 34: re-slices driven by the reprojection's estimated error, not by fixed angles.
  LayerView small = v;
  small.view[3][0] += 0.001f * radius;  // a strafe whose parallax stays far below a pixel
  ASSERT_TRUE(updateLayerView(lv, small, &rebuild).ok());
  EXPECT_FALSE(rebuild) << lv.stats.lastRebuildReason;
  LayerView moved = v;
  moved.view[3][0] += 0.5f * radius;  // the slabs' parallax: pixels
  ASSERT_TRUE(updateLayerView(lv, moved, &rebuild).ok());
  EXPECT_TRUE(rebuild);
  EXPECT_NE(lv.stats.lastRebuildReason.find("parallax"), std::string::npos) << lv.stats.lastRebuildReason;
  LayerView turned = moved;  // a pure rotation (the eye stays): no parallax, the vegetation in view
  turned.view = glm::rotate(glm::mat4(1.0f), glm::radians(-1.0f), glm::vec3(0, 1, 0)) * moved.view;
  ASSERT_TRUE(updateLayerView(lv, turned, &rebuild).ok());
  EXPECT_FALSE(rebuild) << "a pure rotation is reprojected exactly: " << lv.stats.lastRebuildReason;
  LayerView orbited = turned;  // the eye moves around the vegetation: the baked shading's angle
  orbited.view = turned.view * glm::rotate(glm::mat4(1.0f), glm::radians(3.0f), glm::vec3(0, 1, 0));
  ASSERT_TRUE(updateLayerView(lv, orbited, &rebuild).ok());
  EXPECT_TRUE(rebuild);
  LayerView zoomed = orbited;  // 40 to 30 degrees: layer texels magnified 1.35x
  zoomed.proj = perspectiveVulkan(glm::radians(30.0f), float(kW) / kH, 1.0f, 30.0f);
  ASSERT_TRUE(updateLayerView(lv, zoomed, &rebuild).ok());
  EXPECT_TRUE(rebuild);
  EXPECT_NE(lv.stats.lastRebuildReason.find("magnified"), std::string::npos) << lv.stats.lastRebuildReason;
  EXPECT_EQ(lv.stats.rebuilds, 4u);
  EXPECT_EQ(lv.stats.viewUpdates, 7u);
  LayerSettings every = lv.settings;
  every.policy = ReslicePolicy::EveryFrame;
  ASSERT_TRUE(setLayerSettings(lv, every).ok());
  for (int i = 0; i < 3; ++i) {
    ASSERT_TRUE(updateLayerView(lv, zoomed, &rebuild).ok());
    EXPECT_TRUE(rebuild);
  }
  EXPECT_EQ(lv.stats.rebuilds, 7u);
  // A new layer count recreates the images; the next frame rebuilds with it.
  LayerSettings five = every;
  ASSERT_TRUE(parseLayerLayout("5(3-1-1)", &five.layout).ok());
  five.policy = ReslicePolicy::OnViewChange;
  ASSERT_TRUE(setLayerSettings(lv, five).ok());
  EXPECT_EQ(lv.targets.color.layers, 5u);
  ASSERT_TRUE(renderOnce(dev, lv, zoomed).ok());
  EXPECT_EQ(lv.stats.lastRebuildReason, "settings changed");
  LayerSettings bad = five;
  bad.ambient = 2.0f;
  Status s = setLayerSettings(lv, bad);
  EXPECT_NE(s.message().find("ambient"), std::string::npos) << s.message();
  destroyLayeredVegetation(lv);
}

// Issue 16: a re-slice spread over frames (slices of 7 triangles through chunks of at most 16
// vertices, so slices end inside chunks and chunk borders fall inside leaves) leaves exactly the
// layers a re-slice at once draws, for both draw paths; until its cross-fade the visible layers
// and their placement stay the old ones; the cross-fade starts the frame after the frame that
// unites the occupancy, which follows the last slice, and lasts crossFadeFrames frames, each
// visible layer moving towards the new one by the step's weight.
TEST_F(LayersTest, SpreadReslicingEqualsReslicingAtOnce) {
  const VegetationModel m = straddlingLeaves(12, 8, true);
  constexpr uint32_t kSlice = 7, kFade = 5;
  for (LayerDrawMode mode : {LayerDrawMode::SinglePass, LayerDrawMode::PerLayer}) {
    const std::string what = mode == LayerDrawMode::SinglePass ? "spread_single_pass" : "spread_per_layer";
    LayeredVegetationDesc d = smallDesc();
    d.writeIds = false;
    d.settings.draw = mode;
    d.maxChunkVertices = 16;
    d.fixedSliceTriangles = kSlice;
    d.settings.rebuildBudgetMs = 2.0f;
    d.settings.crossFadeFrames = kFade;
    LayeredVegetationDesc once = d;
    once.settings.rebuildBudgetMs = 0.0f;
    LayeredVegetation x, y;
    ASSERT_TRUE(createLayeredVegetation(dev, m, d, &x).ok());
    ASSERT_TRUE(createLayeredVegetation(dev, m, once, &y).ok());
    ASSERT_NE(x.targets.next.color.image, VkImage(VK_NULL_HANDLE)) << "spread re-slicing draws into a second layer set";
    EXPECT_EQ(y.targets.next.color.image, VkImage(VK_NULL_HANDLE));
    auto run = std::make_unique<LayerFrames>(dev, x);
    ASSERT_TRUE(run->init().ok());
    const bool& changed = run->changed;
    auto frame = [&](const LayerView& v) { return run->frame(v); };
    const uint32_t n = x.settings.layout.count();
    auto readAll = [&](LayeredVegetation& lv, std::vector<std::vector<glm::vec4>>* c) {
      c->resize(n);
      for (uint32_t l = 0; l < n; ++l) ASSERT_TRUE(readLayerColor(lv, l, &(*c)[l]).ok());
    };
    // The first view is drawn at once.
    const LayerView a = frontView();
    ASSERT_TRUE(frame(a).ok());
    EXPECT_TRUE(changed);
    EXPECT_EQ(x.stats.spreadPhase, 0u);
    std::vector<std::vector<glm::vec4>> oldColor, newColor, mid;
    readAll(x, &oldColor);
    const std::vector<LayerInfo> oldLayers = x.visible.layers;
    // A light change (the same camera, so the new set fades in; sets drawn from two cameras are
    // swapped in one copy): placement, slices, the occupancy frame, the fade.
    const LayerView b = a;
    LayerSettings lit = x.settings;
    lit.lightDirection = Float3{-0.6f, 0.5f, 0.4f};
    ASSERT_TRUE(setLayerSettings(x, lit).ok());
    LayerSettings litOnce = y.settings;
    litOnce.lightDirection = lit.lightDirection;
    ASSERT_TRUE(setLayerSettings(y, litOnce).ok());
    ASSERT_TRUE(renderOnce(dev, y, b).ok());
    readAll(y, &newColor);
    uint64_t triangles = 0;
    for (const MeshChunk& c : x.mesh.chunks) triangles += c.triangleCount;
    const uint32_t slices = uint32_t((triangles + kSlice - 1) / kSlice);
    ASSERT_GT(slices, 20u);
    ASSERT_TRUE(frame(b).ok());  // placement (the mesh is small: done in this frame)
    EXPECT_FALSE(changed);
    EXPECT_EQ(x.stats.spreadPhase, uint32_t(SpreadPhase::Drawing)) << "placement done, drawing from the next frame";
    for (uint32_t i = 0; i < slices; ++i) {
      ASSERT_TRUE(frame(b).ok());
      EXPECT_FALSE(changed) << what << ": slice " << i << " changed the visible layers";
      EXPECT_TRUE(x.reslice.slicePending);
      EXPECT_LE(x.stats.lastSliceTriangles, kSlice);
      if (i == slices / 2) {
        // Halfway: the visible layers and their placement are the old ones.
        readAll(x, &mid);
        for (uint32_t l = 0; l < n; ++l) expectClose(mid[l], oldColor[l], 0.0f, 0.0, what + "_halfway_layer" + std::to_string(l));
        for (uint32_t l = 0; l < n; ++l) EXPECT_EQ(x.visible.layers[l].slab.depth, oldLayers[l].slab.depth);
      }
    }
    EXPECT_EQ(x.stats.spreadPhase, uint32_t(SpreadPhase::CrossFading)) << what << ": the last slice was drawn";
    ASSERT_TRUE(frame(b).ok());  // unites the occupancy, no fade yet
    EXPECT_FALSE(changed);
    EXPECT_TRUE(x.reslice.occupancyUniteNext);
    EXPECT_EQ(x.stats.crossFade, 0.0f);
    for (uint32_t k = 1; k <= kFade; ++k) {
      ASSERT_TRUE(frame(b).ok());
      EXPECT_TRUE(changed) << what << ": fade step " << k;
      EXPECT_FLOAT_EQ(x.stats.crossFade, float(k) / float(kFade));
      if (k < kFade) {
        EXPECT_EQ(x.stats.spreadPhase, uint32_t(SpreadPhase::CrossFading));
        // Layer info moves linearly with the share.
        const float t = float(k) / float(kFade);
        EXPECT_NEAR(x.visible.layers[0].slab.depth, glm::mix(oldLayers[0].slab.depth, y.visible.layers[0].slab.depth, t), 1e-4f);
      }
      if (k == 2) {
        // Image i has had j = floor((k + (i odd)) / 2) of its H blends (H = blends of its parity):
        // the first I = ceil(H / 2) lay the new set over the old with weight 1 / (I + 1 - b), the
        // rest mix towards it with 1 / (H + 1 - b); up to half-float rounding.
        readAll(x, &mid);
        for (uint32_t l = 0; l < n; ++l) {
          const uint32_t blends = kFade - 1, h = l % 2 == 0 ? blends / 2 : (blends + 1) / 2, j = (k + l % 2) / 2, in = (h + 1) / 2;
          std::vector<glm::vec4> expect = oldColor[l];
          for (uint32_t b = 1; b <= j; ++b)
            for (size_t p = 0; p < expect.size(); ++p) {
              const glm::vec4 nc = newColor[l][p];
              expect[p] = b <= in ? nc / float(in + 1 - b) + expect[p] * (1.0f - nc.a / float(in + 1 - b))
                                  : glm::mix(expect[p], nc, 1.0f / float(h + 1 - b));
            }
          expectClose(mid[l], expect, 4e-3f, 0.0, what + "_fade_layer" + std::to_string(l));
        }
      }
    }
    EXPECT_EQ(x.stats.spreadPhase, 0u);
    EXPECT_EQ(x.stats.spreadRebuilds, 1u);
    EXPECT_EQ(x.stats.lastSpreadFrames, 1 + slices + 1 + kFade);
    ASSERT_TRUE(frame(b).ok());
    EXPECT_FALSE(changed);
    EXPECT_TRUE(x.reslice.occupancyDirty) << "the frame after the fade recomputes the occupancy";
    // Exactly the layers drawn at once: colour and depth of every layer, and the background.
    expectSameLayers(x, y, what);
    std::vector<glm::vec4> bx, by;
    std::vector<float> zx, zy;
    ASSERT_TRUE(readBackground(x, &bx, &zx).ok());
    ASSERT_TRUE(readBackground(y, &by, &zy).ok());
    expectClose(bx, by, 0.0f, 0.0, what + "_background");
    expectIdentical(zx, zy, 1, what + "_background_depth");
    for (uint32_t l = 0; l < n; ++l) {
      EXPECT_EQ(x.visible.layers[l].slab.depth, y.visible.layers[l].slab.depth);
      EXPECT_EQ(x.visible.layers[l].leaves, y.visible.layers[l].leaves);
      EXPECT_EQ(x.visible.layers[l].triangles, y.visible.layers[l].triangles);
    }
    run.reset();
    destroyLayeredVegetation(x);
    destroyLayeredVegetation(y);
  }
}

// The policy with spreading on: a camera cut, a new layer count and the EveryFrame policy
// re-slice at once; a turn while a spread re-slice runs waits for it; bad values are refused.
// Spread re-slicing in slices of 4 triangles (many frames a re-slice) on a small model.
Status createSlowSpread(Device& dev, const VegetationModel& m, LayeredVegetation* lv) {
  LayeredVegetationDesc d = smallDesc();
  d.writeIds = false;
  d.fixedSliceTriangles = 4;
  d.settings.rebuildBudgetMs = 1.0f;
  return createLayeredVegetation(dev, m, d, lv);
}

TEST_F(LayersTest, SpreadReslicingFollowsThePolicy) {
  const VegetationModel m = straddlingLeaves(6, 4, false);
  LayeredVegetation lv;
  ASSERT_TRUE(createSlowSpread(dev, m, &lv).ok());
  bool changed = false;
  const LayerView a = frontView();
  ASSERT_TRUE(updateLayerView(lv, a, &changed).ok());
  EXPECT_TRUE(changed) << "first view: at once";
  LayerView b = a;
  b.view = a.view * glm::rotate(glm::mat4(1.0f), glm::radians(3.0f), glm::vec3(0, 1, 0));  // an orbit
  ASSERT_TRUE(updateLayerView(lv, b, &changed).ok());
  EXPECT_FALSE(changed);
  EXPECT_NE(lv.stats.spreadPhase, 0u);
  EXPECT_EQ(lv.stats.rebuilds, 2u);
  LayerView c = b;
  c.view = b.view * glm::rotate(glm::mat4(1.0f), glm::radians(0.3f), glm::vec3(0, 1, 0));
  ASSERT_TRUE(updateLayerView(lv, c, &changed).ok());
  EXPECT_EQ(lv.stats.rebuilds, 2u) << "a turn during a spread re-slice waits for it";
  EXPECT_NE(lv.stats.spreadPhase, 0u);
  // ... unless the camera outruns it: the visible set's error past twice the thresholds (here the
  // view direction turned 7.3 degrees from the visible set's, twice 2 degrees) re-slices at once.
  c.view = c.view * glm::rotate(glm::mat4(1.0f), glm::radians(4.0f), glm::vec3(0, 1, 0));
  ASSERT_TRUE(updateLayerView(lv, c, &changed).ok());
  EXPECT_TRUE(changed);
  EXPECT_EQ(lv.stats.rebuilds, 3u);
  EXPECT_EQ(lv.stats.spreadPhase, 0u);
  EXPECT_EQ(lv.stats.outrunSpreads, 1u);
  EXPECT_NE(lv.stats.lastRebuildReason.find("a spread re-slice fell behind the camera"), std::string::npos)
      << lv.stats.lastRebuildReason;
  // A camera that keeps moving re-slices at once from then on (a spread one would be outrun again).
  c.view = c.view * glm::rotate(glm::mat4(1.0f), glm::radians(4.5f), glm::vec3(0, 1, 0));
  ASSERT_TRUE(updateLayerView(lv, c, &changed).ok());
  EXPECT_TRUE(changed);
  EXPECT_EQ(lv.stats.rebuilds, 4u);
  EXPECT_EQ(lv.stats.spreadPhase, 0u);
  // Standing still ends that; the next move spreads again.
  ASSERT_TRUE(updateLayerView(lv, c, &changed).ok());
  EXPECT_FALSE(lv.reslice.outrun);
  LayerView e = c;
  e.view = c.view * glm::rotate(glm::mat4(1.0f), glm::radians(3.0f), glm::vec3(0, 1, 0));
  ASSERT_TRUE(updateLayerView(lv, e, &changed).ok());
  EXPECT_FALSE(changed);
  EXPECT_NE(lv.stats.spreadPhase, 0u) << lv.stats.lastRebuildReason;
  EXPECT_EQ(lv.stats.rebuilds, 5u);
  lv.reslice.forcedReason = "camera cut";
  lv.reslice.forceImmediate = true;
  ASSERT_TRUE(updateLayerView(lv, c, &changed).ok());
  EXPECT_TRUE(changed);
  EXPECT_TRUE(lv.reslice.rebuildPending);
  EXPECT_EQ(lv.stats.spreadPhase, 0u) << "a camera cut re-slices at once and ends the spread one";
  EXPECT_EQ(lv.stats.lastRebuildReason, "camera cut");
  LayerSettings slower = lv.settings;
  slower.crossFadeFrames = 12;
  slower.rebuildBudgetMs = 3.0f;
  ASSERT_TRUE(setLayerSettings(lv, slower).ok());
  const uint64_t rebuilds = lv.stats.rebuilds;
  ASSERT_TRUE(updateLayerView(lv, c, &changed).ok());
  EXPECT_FALSE(changed);
  EXPECT_EQ(lv.stats.rebuilds, rebuilds) << "a new budget or fade length changes no layer: no re-slice";
  LayerSettings every = lv.settings;
  every.policy = ReslicePolicy::EveryFrame;
  ASSERT_TRUE(setLayerSettings(lv, every).ok());
  for (int i = 0; i < 2; ++i) {
    ASSERT_TRUE(updateLayerView(lv, c, &changed).ok());
    EXPECT_TRUE(changed && lv.reslice.rebuildPending) << "EveryFrame re-slices at once";
  }
  LayerSettings three = lv.settings;
  three.policy = ReslicePolicy::OnViewChange;
  ASSERT_TRUE(parseLayerLayout("3(1-1-1)", &three.layout).ok());
  bool recreated = false;
  ASSERT_TRUE(setLayerSettings(lv, three, &recreated).ok());
  EXPECT_TRUE(recreated);
  EXPECT_EQ(lv.targets.next.color.layers, 3u);
  ASSERT_TRUE(updateLayerView(lv, c, &changed).ok());
  EXPECT_TRUE(changed && lv.reslice.rebuildPending) << "new layer images: nothing to fade from";
  LayerSettings off = three;
  off.rebuildBudgetMs = 0.0f;
  ASSERT_TRUE(setLayerSettings(lv, off, &recreated).ok());
  EXPECT_TRUE(recreated);
  EXPECT_EQ(lv.targets.next.color.image, VkImage(VK_NULL_HANDLE)) << "no second set without spreading";
  LayerSettings bad = three;
  bad.rebuildBudgetMs = -1.0f;
  Status s = setLayerSettings(lv, bad);
  EXPECT_NE(s.message().find("rebuildBudgetMs"), std::string::npos) << s.message();
  EXPECT_NE(s.message().find("[0, 1000]"), std::string::npos) << s.message();
  bad = three;
  bad.crossFadeFrames = 0;
  s = setLayerSettings(lv, bad);
  EXPECT_NE(s.message().find("crossFadeFrames"), std::string::npos) << s.message();
  destroyLayeredVegetation(lv);
}

// A camera that keeps moving (issue 34): the first re-slice it causes is not spread when, at the
// pace its error grows, the spread one would fall behind (slices of 4 triangles take many frames);
// the error at that re-slice is the threshold's, not more.
TEST_F(LayersTest, ASteadilyMovingCameraIsNotOutrunByASpreadReslice) {
  const VegetationModel m = straddlingLeaves(6, 4, false);
  LayeredVegetation lv;
  ASSERT_TRUE(createSlowSpread(dev, m, &lv).ok());
  bool changed = false;
  LayerView v = frontView();
  ASSERT_TRUE(updateLayerView(lv, v, &changed).ok());
  int frame = 0;
  for (; frame < 200 && lv.stats.rebuilds == 1; ++frame) {
    v.view = v.view * glm::rotate(glm::mat4(1.0f), glm::radians(0.2f), glm::vec3(0, 1, 0));  // an orbit
    ASSERT_TRUE(updateLayerView(lv, v, &changed).ok());
  }
  ASSERT_EQ(lv.stats.rebuilds, 2u) << "the orbit re-slices within 200 frames";
  EXPECT_TRUE(changed && lv.reslice.rebuildPending) << "at once, frame " << frame;
  EXPECT_EQ(lv.stats.spreadPhase, 0u);
  EXPECT_EQ(lv.stats.outrunSpreads, 1u);
  EXPECT_NE(lv.stats.lastRebuildReason.find("a spread re-slice would fall behind the camera"), std::string::npos)
      << lv.stats.lastRebuildReason;
  std::printf("re-sliced at once after %d frames of 0.2 degrees: %s\n", frame, lv.stats.lastRebuildReason.c_str());
  destroyLayeredVegetation(lv);
}

// LayerSettings.predictFrames (issue 79): a moving camera's re-slice at once slices for its view a
// frame on (the last frame's motion repeated), so an orbit re-slices less often; off, the slice
// camera is the current view.
TEST_F(LayersTest, APredictedResliceSlicesAheadAndComesLessOften) {
  const VegetationModel m = straddlingLeaves(6, 4, false);
  uint64_t rebuilds[2] = {0, 0};
  for (uint32_t predict = 0; predict < 2; ++predict) {
    LayeredVegetationDesc d = smallDesc();
    d.writeIds = false;
    d.settings.predictFrames = predict;
    LayeredVegetation lv;
    ASSERT_TRUE(createLayeredVegetation(dev, m, d, &lv).ok());
    bool changed = false;
    LayerView v = frontView();
    ASSERT_TRUE(updateLayerView(lv, v, &changed).ok());
    const glm::mat4 step = glm::rotate(glm::mat4(1.0f), glm::radians(0.5f), glm::vec3(0, 1, 0));
    bool checked = false;
    for (int frame = 0; frame < 240; ++frame) {
      const uint64_t before = lv.stats.rebuilds;
      v.view = v.view * step;  // an orbit
      ASSERT_TRUE(updateLayerView(lv, v, &changed).ok());
      if (lv.stats.rebuilds == before || checked) continue;
      // The slice camera of this re-slice: the current view, or one step of the orbit on.
      const glm::mat4 expected = predict ? v.view * step : v.view;
      float off = 0.0f;
      for (int c = 0; c < 4; ++c) off = std::max(off, glm::length(lv.visible.view.view[c] - expected[c]));
      EXPECT_LT(off, 1e-4f) << "predictFrames " << predict;
      checked = true;
    }
    EXPECT_TRUE(checked) << "the orbit re-slices";
    rebuilds[predict] = lv.stats.rebuilds;
    destroyLayeredVegetation(lv);
  }
  std::printf("re-slices over 240 frames of a 0.5-degree orbit: %llu at the current view, %llu a frame ahead\n",
              (unsigned long long)rebuilds[0], (unsigned long long)rebuilds[1]);
  EXPECT_LT(rebuilds[1], rebuilds[0]);
}
