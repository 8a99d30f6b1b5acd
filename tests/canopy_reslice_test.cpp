// The façade with a moving camera (issues 34, 16, 44): reprojected layers against layers drawn at
// the new camera, the depth search, spread re-slicing and its cross-fade, and a mesh streamed
// within the device budget, each against the CPU reference or the world-lock measure.
#include "tests/canopy_test_fixture.h"

using namespace canopy;
using namespace canopy::test::facade;

// Issue 34: a layer set drawn at camera A and shown at camera B (reprojected, no re-slice) against
// the set drawn at B, wind off, by the world-lock measure (tools/world_lock.h): a pure rotation is
// exact up to resampling and does not re-slice under the default policy; a small orbit and a small
// dolly stay within their slabs' parallax; a turn that brings in foliage from beyond the output's
// edge finds it in the guard band (no re-slice) and matches as well as the same turn mid-image
// (the resampling's error grows with the turn: the image's local scale changes towards its edges).
// Bounds: measured on lavapipe (depth-coverage IoU 0.972, 0.954, 0.989, 0.960, 0.956; silhouette
// mean 0.27, 0.41, 0.22, 0.49, 0.44 px), then rounded outwards (docs/lab/performance-notebook.md "Moving camera: reprojected, re-sliced by its error").
TEST_F(CanopyTest, ReprojectedLayersMatchLayersDrawnAtTheNewCamera) {
  const uint32_t w = 160, h = 120;
  const VkFormat fmt = VK_FORMAT_R16G16B16A16_SFLOAT;
  const VegetationModel model = makeLeafCloud(4000, 3, true);
  const LayerView a = cameraFor(model, w, h, 20.0f);
  struct Case {
    const char* name;
    LayerView a, b;
    bool defaultPolicy;  // the default thresholds (else none: the set drawn at A is kept)
    double minIoU, maxSilhouettePx;
  };
  auto turned = [&](float degrees) {
    LayerView t = a;
    t.view = glm::rotate(glm::mat4(1.0f), glm::radians(degrees), glm::vec3(0, 1, 0)) * a.view;
    return t;
  };
  LayerView rotation = turned(2.0f), orbit = cameraFor(model, w, h, 21.0f), dolly = a;
  // The guard band (16 x 16 px here): a camera turned 24 degrees away, so the output's left edge
  // cuts the crown, then 4 degrees back: what comes into view was drawn in the guard band.
  const LayerView edgeA = turned(24.0f), edgeB = turned(20.0f);
  const glm::vec3 centre = 0.5f * (model.boundsMin + model.boundsMax);
  const glm::vec3 eye = viewPosition(a.view);
  dolly.view = glm::translate(a.view, 0.02f * (eye - centre));  // 2 % of the distance closer
  const Case cases[] = {{"pure rotation 2 degrees", a, rotation, true, 0.96, 0.4},
                        {"pure rotation 4 degrees", a, turned(4.0f), true, 0.95, 0.5},
                        {"orbit 1 degree", a, orbit, false, 0.97, 0.4},
                        {"dolly 2 %", a, dolly, false, 0.94, 0.7},
                        {"a turn within the guard band", edgeA, edgeB, true, 0.95, 0.5}};
  {
    // Without a guard band the same turn needs content beyond the layers: a re-slice.
    CanopyDesc d = smallDesc(w, h, fmt);
    d.guardBand = 0.0f;
    CanopyContext* none = nullptr;
    ASSERT_TRUE(createCanopy(dev, model, d, &none).ok());
    CanopyParams p = canopyParams(none);
    p.layers.rebuildBudgetMs = 0.0f;
    ASSERT_TRUE(setCanopyParams(none, p).ok());
    Host host;
    ASSERT_TRUE(host.create(dev, w, h, fmt).ok());
    CanopyFrame f;
    f.camera = toCamera(edgeA);
    ASSERT_TRUE(host.frame(none, f).ok());
    const uint64_t rebuilds = canopyStats(none).layers.rebuilds;
    f.camera = toCamera(edgeB);
    ASSERT_TRUE(host.frame(none, f).ok());
    EXPECT_EQ(canopyStats(none).layers.rebuilds, rebuilds + 1);
    EXPECT_NE(canopyStats(none).layers.lastRebuildReason.find("content beyond the layers"), std::string::npos)
        << canopyStats(none).layers.lastRebuildReason;
    host.destroy();
    destroyCanopy(none);
  }
  const uint8_t sky[3] = {uint8_t(std::lround(kSky.r * 255)), uint8_t(std::lround(kSky.g * 255)), uint8_t(std::lround(kSky.b * 255))};
  auto rgba8 = [](const std::vector<glm::vec4>& c) {
    std::vector<uint8_t> out(c.size() * 4);
    for (size_t i = 0; i < c.size(); ++i)
      for (int k = 0; k < 4; ++k) out[4 * i + k] = uint8_t(std::lround(std::clamp(c[i][k], 0.0f, 1.0f) * 255.0f));
    return out;
  };
  // The reference re-slices at every frame, so what it draws at B does not depend on what came
  // before: one context serves every case (contexts are the test's cost under the sanitizers).
  CanopyContext* fresh = nullptr;
  ASSERT_TRUE(createCanopy(dev, model, smallDesc(w, h, fmt), &fresh).ok());
  Host hostFresh;
  ASSERT_TRUE(hostFresh.create(dev, w, h, fmt).ok());
  for (const Case& k : cases) {
    SCOPED_TRACE(k.name);
    CanopyContext* held = nullptr;
    ASSERT_TRUE(createCanopy(dev, model, smallDesc(w, h, fmt), &held).ok());
    CanopyParams p = canopyParams(held);
    p.windMode = WindMode::PlaneSides;  // the wind as the plane's sides (domain units/s)
    p.simulation.wind.strength = 0.0f;
    p.layers.rebuildBudgetMs = 0.0f;
    if (!k.defaultPolicy) {
      p.layers.errorThresholdPixels = 1000.0f;
      p.layers.turnThresholdDegrees = 180.0f;
    }
    ASSERT_TRUE(setCanopyParams(held, p).ok());
    p.layers.policy = ReslicePolicy::EveryFrame;
    ASSERT_TRUE(setCanopyParams(fresh, p).ok());
    Host hostHeld;
    ASSERT_TRUE(hostHeld.create(dev, w, h, fmt).ok());
    CanopyFrame f;
    f.camera = toCamera(k.a);
    ASSERT_TRUE(hostHeld.frame(held, f).ok());
    ASSERT_TRUE(hostFresh.frame(fresh, f).ok());
    EXPECT_EQ(canopyStats(held).layers.guardX, 16u);
    EXPECT_EQ(canopyStats(held).layers.layerWidth, w + 32u);
    const uint64_t rebuilds = canopyStats(held).layers.rebuilds;
    f.camera = toCamera(k.b);
    ASSERT_TRUE(hostHeld.frame(held, f).ok());
    ASSERT_TRUE(hostFresh.frame(fresh, f).ok());
    EXPECT_EQ(canopyStats(held).layers.rebuilds, rebuilds) << "re-sliced: " << canopyStats(held).layers.lastRebuildReason;
    EXPECT_NE(canopyCompositor(held).push.flags & COMPOSITE_REPROJECT, 0u);
    std::vector<glm::vec4> ch, cf;
    std::vector<float> zh, zf;
    ASSERT_TRUE(hostHeld.read(&ch, &zh).ok());
    ASSERT_TRUE(hostFresh.read(&cf, &zf).ok());
    // Coverage where Canopy wrote the host's depth (a layer's alpha >= depthAlpha), and in colour
    // (any pixel more than 1 level off the sky): the reprojection's resampling cuts alpha-tested
    // edges at 1/2 (compositeSharpenEdge), so no faint halo widens the colour coverage.
    std::vector<uint8_t> mh(zh.size()), mf(zf.size());
    for (size_t i = 0; i < zh.size(); ++i) mh[i] = zh[i] < 1.0f, mf[i] = zf[i] < 1.0f;
    const WorldLockError e = compareMasks(mh, mf, rgba8(ch), rgba8(cf), w, h);
    const WorldLockError c = compareFrames(rgba8(ch), rgba8(cf), w, h, sky);
    std::printf("  %s: depth coverage IoU %.4f, silhouette mean %.3f px, p99 %.2f px, centroid %.3f px, colour %.2f levels; "
                "colour coverage (> 1 level) IoU %.4f, silhouette mean %.3f px\n",
                k.name, e.coverageIoU, e.silhouetteMeanPx, e.silhouetteP99Px, e.centroidPx, e.colourMean, c.coverageIoU,
                c.silhouetteMeanPx);
    EXPECT_GT(e.coveredB, 500u) << "the vegetation is in view";
    EXPECT_GE(e.coverageIoU, k.minIoU);
    EXPECT_LE(e.silhouetteMeanPx, k.maxSilhouettePx);
    EXPECT_GE(c.coverageIoU, k.minIoU) << "colour coverage";
    EXPECT_LE(c.silhouetteMeanPx, k.maxSilhouettePx) << "colour coverage";
    // The depth written for the host follows the reprojected layers: where both frames hold
    // foliage, the depths agree up to the two placements' differences (the set drawn at B slices
    // the leaves by B's view depths), the same for every case: no offset of the whole.
    std::vector<float> dz;
    for (size_t i = 0; i < zh.size(); ++i)
      if (zh[i] < 1.0f && zf[i] < 1.0f) dz.push_back(std::abs(zh[i] - zf[i]));
    ASSERT_GT(dz.size(), 500u);
    std::sort(dz.begin(), dz.end());
    EXPECT_LE(dz[dz.size() / 2], 0.005f) << "median depth difference";
    EXPECT_LE(dz[dz.size() * 9 / 10], 0.05f) << "90th percentile depth difference";
    hostHeld.destroy();
    destroyCanopy(held);
  }
  hostFresh.destroy();
  destroyCanopy(fresh);
}

// Issue 34, the depth search (docs/design.md "Layers: reprojection", per-texel depth): an orbit of
// 8 degrees shown without a re-slice, on both composite paths, is the CPU reference's search of
// the layers and the trunk (wind on: the warp composed with it); against layers drawn at the new
// camera it keeps the leaves where they belong better than the planes alone
// (CompositeParams.depthSearchSteps = 0).
TEST_F(CanopyTest, TheDepthSearchShowsEachTexelWhereItsDepthPutsIt) {
  struct Run {
    std::vector<glm::vec4> color;
    std::vector<float> depth;
    CompositeReferenceOutputs ref;
    gpu::CompositeView view{};
  };
  // Frames at camera a, then one at b, shown reprojected (the policy's thresholds lifted); the
  // compute path's tile lists from the classification unless `classify` is cleared.
  bool classify = true;
  auto run = [&](const VegetationModel& model, uint32_t w, uint32_t h, const LayerView& a, const LayerView& b, CompositePath path,
                 uint32_t steps, float wind, ReslicePolicy policy, bool reference, Run* out) {
    CanopyContext* ctx = nullptr;
    ASSERT_TRUE(createCanopy(dev, model, smallDesc(w, h, VK_FORMAT_R16G16B16A16_SFLOAT), &ctx).ok());
    CanopyParams p = canopyParams(ctx);
    p.composite.skipEmptyTiles = classify;
    p.windMode = WindMode::PlaneSides;  // the wind as the plane's sides (domain units/s)
    p.simulation.wind.strength = wind;
    p.composite.path = path;
    p.composite.depthSearchSteps = steps;
    p.layers.policy = policy;
    p.layers.rebuildBudgetMs = 0.0f;
    p.layers.errorThresholdPixels = 1000.0f;
    p.layers.turnThresholdDegrees = 180.0f;
    Host host;
    Status s = setCanopyParams(ctx, p);
    if (s.ok()) s = host.create(dev, w, h, VK_FORMAT_R16G16B16A16_SFLOAT);
    CanopyFrame f;
    f.camera = toCamera(a);
    for (int i = 0; i < 3 && s.ok(); ++i) s = host.frame(ctx, f);
    const uint64_t rebuilds = canopyStats(ctx).layers.rebuilds;
    f.camera = toCamera(b);
    if (s.ok()) s = host.frame(ctx, f);
    if (policy != ReslicePolicy::EveryFrame) EXPECT_EQ(canopyStats(ctx).layers.rebuilds, rebuilds);
    if (s.ok()) s = host.read(&out->color, &out->depth);
    float maxDisplacement = 0.0f;
    if (s.ok() && reference) {
      s = referenceFrame(dev, ctx, w, h, &out->ref, &maxDisplacement);
      EXPECT_GT(maxDisplacement, 0.1f) << "the wind warps the layers";
    }
    out->view = canopyCompositor(ctx).view;
    EXPECT_TRUE(s.ok()) << s.message();
    if (host.dev) host.destroy();
    destroyCanopy(ctx);
  };
  {
    const uint32_t w = 128, h = 96;
    const VegetationModel model = makeLeafCloud(4000, 3, true);
    const LayerView a = cameraFor(model, w, h, 20.0f), b = cameraFor(model, w, h, 28.0f);
    for (CompositePath path : {CompositePath::Compute, CompositePath::Fragment}) {
      SCOPED_TRACE(path == CompositePath::Compute ? "compute path" : "fragment path");
      Run r;
      run(model, w, h, a, b, path, 16, 1.0f, ReslicePolicy::OnViewChange, true, &r);
      if (HasFailure()) return;
      // Searched: one sample and its secant step where the slab's ray spans at most two layer pixels.
      for (uint32_t i = 0; i < 5; ++i) EXPECT_GE(r.view.search[i].z, 1.0f) << "layer " << i << " searched";
      EXPECT_GE(r.view.search[COMPOSITE_VIEW_BACKGROUND].z, 1.0f) << "the trunk searched";
      expectNearReference(r.color, r.depth, r.ref, "an 8 degree orbit, reprojected with the depth search");
      if (path != CompositePath::Compute) continue;
      // The classification's boxes (each tile's corners through the homographies, grown to the
      // search's ray ends, asked of the occupancy's 2-pixel cells) drop no layer a pixel reads:
      // the image of every tile listing every layer, pixel for pixel.
      Run all;
      classify = false;
      run(model, w, h, a, b, path, 16, 1.0f, ReslicePolicy::OnViewChange, false, &all);
      classify = true;
      if (HasFailure()) return;
      size_t differ = 0, covered = 0;
      for (size_t i = 0; i < all.color.size(); ++i) {
        differ += all.color[i] != r.color[i] || all.depth[i] != r.depth[i];
        covered += all.depth[i] < 1.0f;
      }
      EXPECT_GT(covered, all.depth.size() / 20) << "the leaves must cover pixels for the comparison to mean anything";
      EXPECT_EQ(differ, 0u) << "a reprojected frame's tile lists dropped a layer";
    }
  }
  auto mask = [](const std::vector<float>& z) {
    std::vector<uint8_t> m(z.size());
    for (size_t i = 0; i < z.size(); ++i) m[i] = z[i] < 1.0f;
    return m;
  };
  auto rgba8 = [](const std::vector<glm::vec4>& c) {
    std::vector<uint8_t> out(c.size() * 4);
    for (size_t i = 0; i < c.size(); ++i)
      for (int k = 0; k < 4; ++k) out[4 * i + k] = uint8_t(std::lround(std::clamp(c[i][k], 0.0f, 1.0f) * 255.0f));
    return out;
  };
  // Against layers drawn at the new camera (wind off): a sparse cloud of large leaves, each slab's
  // leaves far apart in depth, orbited 10 degrees, and the generated shrub orbited 6 degrees.
  SceneDesc sd;
  sd.faces = 20000;
  VegetationModel shrub;
  ASSERT_TRUE(generateScene(sd, &shrub).ok());
  const VegetationModel cloud = makeLeafCloud(60, 7, false);
  struct Config {
    const char* name;
    const VegetationModel* model;
    uint32_t w, h;
    float degrees, minIoUGain, maxSilhouetteRatio;
  };
  const Config configs[] = {{"60 large leaves, 10 degrees", &cloud, 256, 192, 10.0f, 0.03f, 0.6f},
                            {"20K-face shrub, 6 degrees", &shrub, 320, 240, 6.0f, 0.015f, 0.85f}};
  for (const Config& c : configs) {
    SCOPED_TRACE(c.name);
    const LayerView a = cameraFor(*c.model, c.w, c.h, 20.0f), b = cameraFor(*c.model, c.w, c.h, 20.0f + c.degrees);
    Run search, plane, fresh;
    run(*c.model, c.w, c.h, a, b, CompositePath::Compute, 16, 0.0f, ReslicePolicy::OnViewChange, false, &search);
    run(*c.model, c.w, c.h, a, b, CompositePath::Compute, 0, 0.0f, ReslicePolicy::OnViewChange, false, &plane);
    run(*c.model, c.w, c.h, a, b, CompositePath::Compute, 16, 0.0f, ReslicePolicy::EveryFrame, false, &fresh);
    if (HasFailure()) return;
    for (uint32_t i = 0; i < 5; ++i) EXPECT_EQ(plane.view.search[i].z, 0.0f) << "layer " << i << ": the plane alone";
    const WorldLockError es = compareMasks(mask(search.depth), mask(fresh.depth), rgba8(search.color), rgba8(fresh.color), c.w, c.h);
    const WorldLockError ep = compareMasks(mask(plane.depth), mask(fresh.depth), rgba8(plane.color), rgba8(fresh.color), c.w, c.h);
    std::printf("  %s, against layers drawn at the new camera: depth search IoU %.4f, silhouette mean %.3f px, centroid %.3f px; "
                "planes alone IoU %.4f, silhouette mean %.3f px, centroid %.3f px\n",
                c.name, es.coverageIoU, es.silhouetteMeanPx, es.centroidPx, ep.coverageIoU, ep.silhouetteMeanPx, ep.centroidPx);
    EXPECT_GT(es.coveredB, 500u) << "the vegetation is in view";
    EXPECT_GE(es.coverageIoU, ep.coverageIoU + c.minIoUGain);
    EXPECT_LE(es.silhouetteMeanPx, c.maxSilhouetteRatio * ep.silhouetteMeanPx);
  }
}

// Issue 16, through the public API: a re-slice spread over frames while the wind keeps animating
// the old layers; every frame, during the slices and the cross-fade, is the CPU reference's
// composite of the layers then visible. Issue 34: a turn of the camera is then re-sliced the same
// way while the old set is shown reprojected to the new camera (the CPU reference reprojects too),
// and the new set, drawn from another camera, replaces it in one copy (no texel blend of two
// cameras' images). requestCanopyRebuild and a camera cut re-slice at once.
TEST_F(CanopyTest, SpreadReslicingKeepsAnimatingAsTheCpuReferenceDoes) {
  const uint32_t w = 128, h = 96;
  const VegetationModel model = makeLeafCloud(4000, 3, true);
  CanopyContext* ctx = nullptr;
  Status s = createCanopy(dev, model, smallDesc(w, h, VK_FORMAT_R16G16B16A16_SFLOAT), &ctx);
  ASSERT_TRUE(s.ok()) << s.message();
  CanopyParams p = canopyParams(ctx);
  p.windMode = WindMode::PlaneSides;  // the wind as the plane's sides (domain units/s)
  p.simulation.wind.strength = 2.0f;
  p.dynamics.cellSize = 8;
  p.layers.rebuildBudgetMs = 0.5f;
  p.layers.crossFadeFrames = 4;
  const uint64_t gen = canopyStats(ctx).resourceGeneration;
  ASSERT_TRUE(setCanopyParams(ctx, p).ok());
  EXPECT_EQ(canopyStats(ctx).resourceGeneration, gen + 1) << "the second layer set is new";
  Host host;
  ASSERT_TRUE(host.create(dev, w, h, VK_FORMAT_R16G16B16A16_SFLOAT).ok());
  CanopyFrame f;
  f.camera = toCamera(cameraFor(model, w, h, 20.0f));
  for (int i = 0; i < 3; ++i) ASSERT_TRUE(host.frame(ctx, f).ok());
  auto checkReference = [&](const std::string& when) {
    std::vector<glm::vec4> color;
    std::vector<float> depth;
    CompositeReferenceOutputs ref;
    float maxDisp = 0;
    ASSERT_TRUE(host.read(&color, &depth).ok());
    ASSERT_TRUE(referenceFrame(dev, ctx, w, h, &ref, &maxDisp).ok());
    EXPECT_GT(maxDisp, 0.5f) << when << ": the wind moves the layers";
    expectNearReference(color, depth, ref, when);
  };
  ASSERT_TRUE(requestCanopyRebuild(ctx, false).ok());
  ASSERT_TRUE(host.frame(ctx, f).ok());
  CanopyStats st = canopyStats(ctx);
  EXPECT_FALSE(st.layersRebuilt);
  EXPECT_NE(st.layers.spreadPhase, 0u);
  int frames = 1, fadeFrames = 0;
  bool checkedSlices = false, checkedFade = false;
  while (canopyStats(ctx).layers.spreadRebuilds == 0 && frames < 10000) {
    ASSERT_TRUE(host.frame(ctx, f).ok());
    ++frames;
    st = canopyStats(ctx);
    fadeFrames += st.layersRebuilt;
    if (st.layers.spreadPhase == 2 && !checkedSlices) {
      checkReference("while drawing slices");
      checkedSlices = true;
    }
    if (st.layers.spreadPhase == 3 && st.layers.crossFade == 0.5f) {
      checkReference("halfway through the cross-fade");
      checkedFade = true;
    }
  }
  EXPECT_TRUE(checkedSlices && checkedFade);
  EXPECT_EQ(st.layers.spreadRebuilds, 1u);
  EXPECT_EQ(fadeFrames, 4) << "the visible layers change only in the cross-fade's frames";
  EXPECT_EQ(st.layers.lastSpreadFrames, uint32_t(frames));
  ASSERT_TRUE(host.frame(ctx, f).ok());
  checkReference("after the cross-fade");
  // A turn: the old set reprojected while the new one is drawn, then one copy.
  f.camera = toCamera(cameraFor(model, w, h, 24.0f));
  ASSERT_TRUE(host.frame(ctx, f).ok());
  st = canopyStats(ctx);
  EXPECT_NE(st.layers.spreadPhase, 0u) << st.layers.lastRebuildReason;
  checkReference("the turned camera's first frame, reprojected");
  EXPECT_NE(canopyCompositor(ctx).push.flags & COMPOSITE_REPROJECT, 0u);
  int copies = 0;
  checkedSlices = false;
  for (int i = 0; canopyStats(ctx).layers.spreadRebuilds == 1 && i < 10000; ++i) {
    ASSERT_TRUE(host.frame(ctx, f).ok());
    st = canopyStats(ctx);
    copies += st.layersRebuilt;
    if (st.layers.spreadPhase == 2 && !checkedSlices) {
      checkReference("while drawing the turned camera's slices, reprojected");
      checkedSlices = true;
    }
  }
  EXPECT_TRUE(checkedSlices);
  EXPECT_EQ(st.layers.spreadRebuilds, 2u);
  EXPECT_EQ(copies, 1) << "sets drawn from two cameras are swapped in one copy";
  ASSERT_TRUE(host.frame(ctx, f).ok());
  EXPECT_EQ(canopyCompositor(ctx).push.flags & COMPOSITE_REPROJECT, 0u) << "the new set is the camera's own";
  checkReference("after the turned camera's set is in");
  // Forced re-slices.
  ASSERT_TRUE(requestCanopyRebuild(ctx, true).ok());
  ASSERT_TRUE(host.frame(ctx, f).ok());
  st = canopyStats(ctx);
  EXPECT_TRUE(st.layersRebuilt);
  EXPECT_EQ(st.layers.lastRebuildReason, "requested at once");
  EXPECT_EQ(st.layers.spreadPhase, 0u);
  ASSERT_TRUE(requestCanopyRebuild(ctx, false).ok());
  ASSERT_TRUE(host.frame(ctx, f).ok());
  st = canopyStats(ctx);
  EXPECT_FALSE(st.layersRebuilt);
  EXPECT_EQ(st.layers.lastRebuildReason, "requested");
  EXPECT_NE(st.layers.spreadPhase, 0u);
  f.cameraCut = true;
  ASSERT_TRUE(host.frame(ctx, f).ok());
  st = canopyStats(ctx);
  EXPECT_TRUE(st.layersRebuilt);
  EXPECT_EQ(st.layers.spreadPhase, 0u) << "a camera cut re-slices at once";
  EXPECT_FALSE(requestCanopyRebuild(nullptr, true).ok());
  p.layers.crossFadeFrames = 500;
  s = setCanopyParams(ctx, p);
  EXPECT_NE(s.message().find("crossFadeFrames"), std::string::npos) << s.message();
  host.destroy();
  destroyCanopy(ctx);
}

// Issue 34: a cross-fade at one camera never lowers the coverage below the smaller set's. A layout
// of the same layer count moves leaves between layers; each layer's depth takes the nearer of the
// two sets' at its first blend, so the new copy of a moved leaf passes the composite's depth test
// (without it, covered pixels fell to 80 % here), and the new set is laid over the old before the
// old set's own texels fade out, so the leaf is whole in one of its two layers in every frame (a
// plain mix composed 1 - s (1 - s) there). Bounds: covered pixels (alpha >= 1/2) and summed alpha
// each >= 99 % of the smaller set's (half-float rounding and partial edge texels).
TEST_F(CanopyTest, CrossFadeNeverLowersCoverageBelowTheSmallerSet) {
  const uint32_t w = 128, h = 96;
  const VegetationModel model = makeLeafCloud(600, 3, true);
  CanopyContext* ctx = nullptr;
  Status s = createCanopy(dev, model, smallDesc(w, h, VK_FORMAT_R16G16B16A16_SFLOAT), &ctx);
  ASSERT_TRUE(s.ok()) << s.message();
  CanopyParams p = canopyParams(ctx);
  p.windMode = WindMode::PlaneSides;  // the wind as the plane's sides (domain units/s)
  p.simulation.wind.strength = 0.0f;
  p.layers.rebuildBudgetMs = 0.5f;
  p.layers.crossFadeFrames = 8;
  ASSERT_TRUE(parseLayerLayout("5(3-1-1)", &p.layers.layout).ok());
  ASSERT_TRUE(setCanopyParams(ctx, p).ok());
  Host host;
  host.clear = glm::vec4(0.0f);
  ASSERT_TRUE(host.create(dev, w, h, VK_FORMAT_R16G16B16A16_SFLOAT).ok());
  CanopyFrame f;
  f.camera = toCamera(cameraFor(model, w, h, 20.0f));
  struct Coverage {
    double covered = 0, alpha = 0;
  };
  auto coverage = [&](Coverage* c) {
    std::vector<glm::vec4> color;
    std::vector<float> depth;
    ASSERT_TRUE(host.read(&color, &depth).ok());
    *c = Coverage{};
    for (const glm::vec4& v : color) {
      c->covered += v.a >= 0.5f ? 1.0 : 0.0;
      c->alpha += v.a;
    }
  };
  for (int i = 0; i < 3; ++i) ASSERT_TRUE(host.frame(ctx, f).ok());
  Coverage before, after, lowest;
  coverage(&before);
  ASSERT_GT(before.covered, 300.0);
  std::vector<glm::vec4> oldColor, newColor;
  std::vector<float> z;
  ASSERT_TRUE(host.read(&oldColor, &z).ok());
  lowest = before;
  ASSERT_TRUE(parseLayerLayout("5(1-1-3)", &p.layers.layout).ok());
  ASSERT_TRUE(setCanopyParams(ctx, p).ok());
  int fadeFrames = 0;
  for (int i = 0; i < 10000; ++i) {
    ASSERT_TRUE(host.frame(ctx, f).ok());
    const CanopyStats st = canopyStats(ctx);
    Coverage c;
    coverage(&c);
    fadeFrames += st.layers.spreadPhase == 3 && st.layers.crossFade > 0.0f && st.layers.crossFade < 1.0f;
    lowest.covered = std::min(lowest.covered, c.covered);
    lowest.alpha = std::min(lowest.alpha, c.alpha);
    if (st.layers.spreadPhase == 0) break;
  }
  EXPECT_EQ(fadeFrames, 7) << "crossFadeFrames - 1 blend frames, then the copy";
  ASSERT_TRUE(host.frame(ctx, f).ok());
  coverage(&after);
  ASSERT_TRUE(host.read(&newColor, &z).ok());
  float changed = 0;
  for (size_t i = 0; i < oldColor.size(); ++i) changed = std::max(changed, maxDiff(oldColor[i], newColor[i]));
  EXPECT_GT(changed, 0.05f) << "the new layout changes the picture (leaves moved between layers)";
  const double smallerCovered = std::min(before.covered, after.covered), smallerAlpha = std::min(before.alpha, after.alpha);
  EXPECT_GE(lowest.covered, 0.99 * smallerCovered) << "covered pixels: before " << before.covered << ", after " << after.covered;
  EXPECT_GE(lowest.alpha, 0.99 * smallerAlpha) << "summed alpha: before " << before.alpha << ", after " << after.alpha;
  host.destroy();
  destroyCanopy(ctx);
}

// issue 16: through the public API, a mesh over CanopyDesc.deviceMemoryBudget stays in host memory
// and is streamed through the staging ring; once the first re-slice is complete the frames equal
// the resident mesh's (no wind: the static composite), and Canopy's allocator never held more than
// the budget for the streamed context.
TEST_F(CanopyTest, StreamedMeshWithinTheDeviceBudget) {
  const uint32_t w = 128, h = 96;
  SceneDesc sd;
  sd.kind = SceneKind::Shrub;
  sd.faces = 300000;
  sd.seed = 2;
  sd.textureSize = 32;
  VegetationModel model;
  ASSERT_TRUE(generateScene(sd, &model).ok());
  CanopyDesc rd = smallDesc(w, h, VK_FORMAT_R16G16B16A16_SFLOAT);
  rd.deviceMemoryBudget = 0;
  rd.params.windMode = WindMode::PlaneSides;  // the wind as the plane's sides (domain units/s)
  rd.params.simulation.wind.strength = 0.0f;
  rd.params.layers.rebuildBudgetMs = 1.0f;  // both layer sets, as the budget plans for
  const uint64_t before = dev.allocator->liveBytes;
  CanopyContext* resident = nullptr;
  Status s = createCanopy(dev, model, rd, &resident);
  ASSERT_TRUE(s.ok()) << s.message();
  const uint64_t residentBytes = dev.allocator->liveBytes - before;
  const CanopyStats rs = canopyStats(resident);
  EXPECT_TRUE(rs.layers.meshResident);
  const LayeredVegetation& rl = canopyLayers(resident);
  const uint64_t mesh = rs.layers.meshBytes;
  const uint64_t other =
      residentBytes - (rl.mesh.vertices.allocation.size + rl.mesh.indexBuffer.allocation.size + rl.mesh.leafRoots.allocation.size);
  CanopyDesc sdsc = rd;
  sdsc.params.layers.rebuildBudgetMs = 0.0f;
  sdsc.deviceMemoryBudget = other + mesh / 2;
  sdsc.meshStagingRingBytes = 1 << 20;
  Host host;
  ASSERT_TRUE(host.create(dev, w, h, VK_FORMAT_R16G16B16A16_SFLOAT).ok());
  CanopyFrame f;
  f.camera = toCamera(cameraFor(model, w, h, 20.0f));
  uint64_t frameNumber = 0;
  for (int i = 0; i < 3; ++i) {
    f.frameNumber = ++frameNumber;
    ASSERT_TRUE(host.frame(resident, f).ok());
  }
  std::vector<glm::vec4> colorR, colorS;
  std::vector<float> depthR, depthS;
  ASSERT_TRUE(host.read(&colorR, &depthR).ok());
  // The streamed context's peak, from its creation to its last frame (before any readback: the
  // test's own staging buffers are not the context's).
  const uint64_t start = dev.allocator->liveBytes;
  dev.allocator->peakLiveBytes = start;
  CanopyContext* streamed = nullptr;
  s = createCanopy(dev, model, sdsc, &streamed);
  ASSERT_TRUE(s.ok()) << s.message();
  const CanopyStats ss = canopyStats(streamed);
  EXPECT_FALSE(ss.layers.meshResident);
  EXPECT_GT(ss.layers.meshRingBytes, 0u);
  EXPECT_LT(ss.layers.meshRingBytes, mesh);
  uint32_t frames = 0;
  while (canopyStats(streamed).layers.spreadRebuilds == 0) {
    f.frameNumber = ++frameNumber;
    ++frames;
    const Status fs = host.frame(streamed, f);
    ASSERT_TRUE(fs.ok()) << fs.message();
    ASSERT_LT(frames, 1000u);
  }
  EXPECT_GT(frames, 2u) << "the ring holds less than the mesh: several frames";
  f.frameNumber = ++frameNumber;
  ASSERT_TRUE(host.frame(streamed, f).ok());
  EXPECT_LE(dev.allocator->peakLiveBytes - start, sdsc.deviceMemoryBudget)
      << "peak " << dev.allocator->peakLiveBytes - start << " bytes, budget " << sdsc.deviceMemoryBudget;
  ASSERT_TRUE(host.read(&colorS, &depthS).ok());
  size_t off = 0, depthOff = 0, covered = 0;
  for (size_t i = 0; i < colorR.size(); ++i) {
    off += maxDiff(colorR[i], colorS[i]) > 1.0f / 255.0f;
    depthOff += depthR[i] != depthS[i];
    covered += depthS[i] < 1.0f;
  }
  EXPECT_EQ(off, 0u) << "pixels of the streamed mesh's frame more than 1/255 off the resident mesh's";
  EXPECT_EQ(depthOff, 0u);
  EXPECT_GT(covered, colorS.size() / 20) << "the vegetation covers part of the image";
  CompositeReferenceOutputs ref;
  float maxDisp = 0.0f;
  ASSERT_TRUE(referenceFrame(dev, streamed, w, h, &ref, &maxDisp).ok());
  expectNearReference(colorS, depthS, ref, "streamed mesh");
  host.destroy();
  destroyCanopy(streamed);
  destroyCanopy(resident);
  // The ring's range, and a budget the compositor alone exceeds, are refused naming the parameter.
  CanopyDesc bad = sdsc;
  bad.meshStagingRingBytes = 1000;
  CanopyContext* none = nullptr;
  s = createCanopy(dev, model, bad, &none);
  EXPECT_NE(s.message().find("meshStagingRingBytes"), std::string::npos) << s.message();
  bad = sdsc;
  bad.deviceMemoryBudget = 4096;
  s = createCanopy(dev, model, bad, &none);
  EXPECT_NE(s.message().find("deviceMemoryBudget"), std::string::npos) << s.message();
  EXPECT_EQ(none, nullptr);
}
