#include "render/reslice_scheduler.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>

#include "engine/device.h"
#include "engine/timing.h"
#include "engine/transfer.h"
#include "render/layer_common.h"
#include "render/layers.h"
#include "render/reprojection.h"

namespace canopy {

namespace {
using Clock = std::chrono::steady_clock;
// Why the layers drawn from the slice camera `slice` no longer serve the camera `view` (docs/design.md
// "Layers: reprojection", the policy), or "" while the reprojection's estimated error stays within
// the settings (their pixel and degree thresholds times `scale`). The layer images reach beyond the
// output by the guard band, so content beyond the output is there until the view leaves the guard band.
// `ratio` (optional): the largest of the error's parts over its threshold (parallax and content
// beyond the layers over errorThresholdPixels, the turn over turnThresholdDegrees).
std::string reprojectionReason(const LayeredVegetation& lv, const LayerView& slice, const LayerView& view, float scale = 1.0f,
                               double* ratio = nullptr) {
  const LayerSettings& s = lv.settings;
  const float pixels = s.errorThresholdPixels * scale, degrees = s.turnThresholdDegrees * scale;
  std::vector<SlabRange> slabs;
  for (const LayerInfo& l : lv.visible.layers) slabs.push_back({l.slab.zNear, l.slab.zFar, l.slab.depth});
  const glm::dvec2 size(lv.targets.color.extent.width, lv.targets.color.extent.height);
  const ReprojectionError e = estimateReprojectionError(slice, view, slabs, lv.instances.boundsMin, lv.instances.boundsMax, size,
                                                        glm::dvec2(layerOutputSize(lv)),
                                                        lv.visible.extent.known ? &lv.visible.extent : nullptr);
  if (ratio)
    *ratio = std::max({e.parallaxPx / std::max(s.errorThresholdPixels, 1e-6f), e.outsidePx / std::max(s.errorThresholdPixels, 1e-6f),
                       e.turnDegrees / std::max(s.turnThresholdDegrees, 1e-6f)});
  // The message is built only for a re-slice (this runs every frame the camera moves).
  auto over = [&](double v, const char* what) {
    return "reprojection error " + (std::isfinite(v) ? std::to_string(v) : std::string("unbounded")) + " px (threshold " +
           std::to_string(pixels) + "): " + what;
  };
  if (e.parallaxPx > pixels) return over(e.parallaxPx, "parallax within the slabs");
  if (e.outsidePx > pixels) return over(e.outsidePx, "content beyond the layers");
  if (e.magnification > kMaxMagnification)
    return "layer texels magnified " + std::to_string(e.magnification) + "x (limit " + std::to_string(kMaxMagnification) + ")";
  if (e.turnDegrees > degrees)
    return "view direction to the vegetation turned " + std::to_string(e.turnDegrees) + " degrees (threshold " +
           std::to_string(degrees) + "): baked shading";
  return "";
}

// Triangles a spread slice draws: as many as the budget and the measured rate allow (at least 1024,
// so a re-slice always ends), or the fixed size a test asks for.
uint64_t sliceTriangles(const LayeredVegetation& lv) {
  return lv.desc.fixedSliceTriangles ? lv.desc.fixedSliceTriangles
                                     : std::max<uint64_t>(1024, uint64_t(lv.settings.rebuildBudgetMs * lv.reslice.rate.trianglesPerMs));
}

// Frames a spread re-slice of the whole mesh would take at the measured drawing rate: its placement,
// its slices, the frame that unites the occupancy and the copy (a set from another camera).
double spreadFrames(const LayeredVegetation& lv) {
  uint64_t triangles = 0;
  for (const MeshChunk& c : lv.mesh.chunks) triangles += c.triangleCount;
  return 3.0 + std::ceil(double(triangles) / double(sliceTriangles(lv)));
}

// The interval since the last view update tells what the last frame's layer work cost
// (SliceRateControl); a drawing frame's triangles over its cost above the still baseline update
// the rate (frame times are noisy: see below).
void updateSliceRate(LayeredVegetation& lv) {
  SliceRateControl& r = lv.reslice.rate;
  const auto now = Clock::now();
  if (r.haveLast) {
    const double ms = std::chrono::duration<double, std::milli>(now - r.lastUpdate).count();
    constexpr size_t kStill = 15;
    // A placement frame is a still frame plus its (timed) CPU placement: a baseline sample too, so
    // an orbiting camera that never stands still still has one.
    if (r.lastWork == SliceRateControl::Work::None || r.lastWork == SliceRateControl::Work::Placement) {
      const double still = r.lastWork == SliceRateControl::Work::None ? ms : std::max(ms - r.lastPlacementMs, 0.0);
      if (r.stillMs.size() < kStill) r.stillMs.push_back(still);
      else r.stillMs[r.stillNext++ % kStill] = still;
    } else if (r.lastWork == SliceRateControl::Work::Slice && r.stillMs.size() >= 3 && r.lastTriangles > 0) {
      // Cautious up, quick down: a slice is never believed to cost under a quarter of the budget
      // (a lucky fast frame would otherwise ask for a huge next slice), the estimate follows the
      // median of the last five slices by at most x1.2 up / x0.5 down a frame, and a slice that
      // cost over twice the budget halves it at once.
      const double budget = std::max<double>(lv.settings.rebuildBudgetMs, 1e-3);
      const double raw = ms - median(r.stillMs);
      const double measured = double(r.lastTriangles) / std::max(raw, 0.25 * budget);
      constexpr size_t kSamples = 5;
      if (r.rateSamples.size() < kSamples) r.rateSamples.push_back(measured);
      else r.rateSamples[r.rateNext++ % kSamples] = measured;
      r.trianglesPerMs *= std::clamp(median(r.rateSamples) / r.trianglesPerMs, 0.5, 1.2);
      if (raw > 2.0 * budget) r.trianglesPerMs = std::min(r.trianglesPerMs, 0.5 * double(r.lastTriangles) / budget);
    }
  }
  r.haveLast = true;
  r.lastUpdate = now;
  r.lastWork = SliceRateControl::Work::None;
  r.lastTriangles = 0;
}

// The next frame's draws of a spread re-slice: triangles from the cursor, as many as the budget
// and the measured rate allow (at least 1024, so it always ends); a streamed mesh also stops at
// what this frame's ring segment holds, and its parts are copied there now (the frame that reads
// them is the one being recorded: docs/design.md "Layers: mesh budget and staging ring").
void planSlice(LayeredVegetation& lv) {
  SpreadRebuild& sp = lv.reslice.spread;
  const uint64_t want = sp.immediate ? UINT64_MAX : sliceTriangles(lv);
  sp.slice.clear();
  sp.sliceClears = sp.cursorItem == 0 && sp.cursorTriangle == 0;
  MeshRing& r = lv.mesh.ring;
  uint64_t segment = 0, usedV = 0, usedI = 0, usedR = 0;
  if (lv.mesh.streamed) {
    const Device& d = *lv.device;
    segment = (d.anyFrame ? d.frameNumber : r.counter++) % r.segments;
  }
  uint64_t drawn = 0;
  while (sp.cursorItem < sp.items.size() && drawn < want) {
    const ChunkPart& item = sp.items[sp.cursorItem];
    const MeshChunk& c = lv.mesh.chunks[item.chunk];
    uint32_t count = uint32_t(std::min<uint64_t>(item.triangleCount - sp.cursorTriangle, want - drawn));
    ChunkPart part = item;  // its weight and level (a part of the impostor cut)
    part.firstTriangle = item.firstTriangle + sp.cursorTriangle;
    part.triangleCount = count;
    if (lv.mesh.streamed && count) {
      const uint64_t roots = roundUp(std::max<uint32_t>(c.rootCount, 1), r.rootAlignment);
      if (usedV + c.vertexCount > r.vertexCapacity || usedR + roots > r.rootCapacity || usedI + 3 > r.indexCapacity) break;
      part.triangleCount = count = uint32_t(std::min<uint64_t>(count, (r.indexCapacity - usedI) / 3));
      part.ringVertex = segment * r.vertexCapacity + usedV;
      part.ringIndex = segment * roundUp(r.indexCapacity * 2, 4) / 2 + usedI;
      part.ringRoot = segment * r.rootCapacity + usedR;
      auto* v = static_cast<gpu::LayerVertex*>(lv.mesh.vertices.allocation.mapped);
      auto* ix = static_cast<uint16_t*>(lv.mesh.indexBuffer.allocation.mapped);
      auto* rt = static_cast<gpu::LayerLeafRoot*>(lv.mesh.leafRoots.allocation.mapped);
      std::memcpy(v + part.ringVertex, lv.mesh.hostMesh.vertices.data() + c.firstVertex, size_t(c.vertexCount) * sizeof(gpu::LayerVertex));
      std::memcpy(ix + part.ringIndex, lv.mesh.hostMesh.indices.data() + c.firstIndex + 3ull * part.firstTriangle, size_t(count) * 6);
      std::memcpy(rt + part.ringRoot, lv.mesh.hostMesh.roots.data() + c.firstRoot, size_t(c.rootCount) * sizeof(gpu::LayerLeafRoot));
      usedV += c.vertexCount;
      usedI += 3ull * count;
      usedR += roots;
    }
    if (count) sp.slice.push_back(part);
    drawn += count;
    sp.cursorTriangle += count;
    if (sp.cursorTriangle >= item.triangleCount) {
      sp.cursorItem++;
      sp.cursorTriangle = 0;
    }
  }
  sp.sliceLast = sp.cursorItem >= sp.items.size();
  lv.reslice.slicePending = true;
  // A slice sized by the ring alone says nothing about the drawing rate the budget sizes.
  lv.reslice.rate.lastWork = sp.immediate ? SliceRateControl::Work::Other : SliceRateControl::Work::Slice;
  lv.reslice.rate.lastTriangles = drawn;
  lv.stats.lastSliceTriangles = drawn;
  lv.stats.maxSliceTriangles = std::max(lv.stats.maxSliceTriangles, drawn);
}

LayerInfo mixLayerInfo(const LayerInfo& a, const LayerInfo& b, float t) {
  LayerInfo m = b;
  m.slab.depth = glm::mix(a.slab.depth, b.slab.depth, t);
  m.slab.distance = glm::mix(a.slab.distance, b.slab.distance, t);
  m.top = glm::mix(a.top, b.top, t);
  m.rootLineY = glm::mix(a.rootLineY, b.rootLineY, t);
  m.height = glm::mix(a.height, b.height, t);
  m.drawnNear = std::min(a.drawnNear, b.drawnNear);  // both sets' texels are read
  m.drawnFar = std::max(a.drawnFar, b.drawnFar);
  return m;
}

// What a spread re-slice draws once its placement is done (SpreadRebuild.items): the impostor cut of
// its placement (docs/design.md "Impostors") — the cut's foliage parts, the impostors drawn with the
// first and last slices — or every foliage chunk, then the rigid chunks, each whole.
void planSpreadItems(LayeredVegetation& lv) {
  SpreadRebuild& sp = lv.reslice.spread;
  planImpostorCut(lv, sp.job.frame, sp.job.view, &sp.impostors);
  const bool cut = sp.impostors.cut.active;
  sp.items = cut ? sp.impostors.parts : std::vector<ChunkPart>{};
  for (uint32_t c = 0; c < lv.mesh.chunks.size(); ++c) {
    const MeshChunk& mc = lv.mesh.chunks[c];
    if ((!cut || !mc.foliage) && mc.triangleCount) sp.items.push_back(ChunkPart{c, 0, mc.triangleCount});
  }
}

// The frame of the last step (the copy of the next set): its placement becomes the visible one.
void finishSpread(LayeredVegetation& lv) {
  SpreadRebuild& sp = lv.reslice.spread;
  lv.stats.lastVisibleInstances = uint32_t(sp.job.depthRows.size());
  lv.visible.view = sp.job.view;
  lv.visible.runs = sp.job.runs;
  takeVertexBounds(lv.visible, sp.job);
  lv.visible.frame = sp.job.frame;
  lv.visible.layers = std::move(sp.job.layers);
  lv.visible.impostors = std::move(sp.impostors);
  lv.stats.spreadRebuilds++;
  lv.stats.lastSpreadFrames = sp.frames;
  lv.stats.crossFade = 1.0f;
  sp.phase = SpreadPhase::Idle;
  sp.job = PlacementJob{};
  sp.fadeFrom.clear();
}

// One frame of a spread re-slice: placement for up to the budget, then slices, then the fade.
Status advanceSpread(LayeredVegetation& lv) {
  SpreadRebuild& sp = lv.reslice.spread;
  sp.frames++;
  switch (sp.phase) {
    case SpreadPhase::Placing: {
      const auto deadline = Clock::now() + std::chrono::duration<double, std::milli>(lv.settings.rebuildBudgetMs);
      const auto deadlineTp = std::chrono::time_point_cast<Clock::duration>(deadline);
      bool done = false;
      const double before = sp.job.ms;
      CANOPY_TRY(advancePlacement(lv, sp.job, sp.immediate ? nullptr : &deadlineTp, &done));
      lv.reslice.rate.lastWork = SliceRateControl::Work::Placement;
      lv.reslice.rate.lastPlacementMs = sp.job.ms - before;
      if (done) {
        lv.stats.lastPlacementMs = sp.job.ms;
        planSpreadItems(lv);
        sp.phase = SpreadPhase::Drawing;
        // No visible placement of this layer count yet (the first view, or new layer images, of a
        // streamed mesh): the new one describes the visible images, still empty, until the copy.
        if (lv.visible.layers.size() != sp.job.layers.size()) {
          lv.visible.layers = sp.job.layers;
          lv.visible.view = sp.job.view;
          lv.visible.runs = sp.job.runs;
          takeVertexBounds(lv.visible, sp.job);
          lv.visible.frame = sp.job.frame;
        }
      }
      if (!done || !sp.immediate) break;
      [[fallthrough]];  // asked at once: the first slice in the placement's frame
    }
    case SpreadPhase::Drawing:
      planSlice(lv);
      if (!sp.sliceLast) break;
      if (!sp.immediate) {
        sp.phase = SpreadPhase::CrossFading;  // from the next frame
        break;
      }
      // Asked at once: the next set is copied in behind the last slice (the copy pass follows the
      // slice pass), without a fade, and the occupancy recomputed in this frame.
      sp.fadeCopy = true;
      lv.reslice.fadePending = true;
      lv.reslice.occupancyRecomputeNow = true;
      finishSpread(lv);
      break;
    case SpreadPhase::CrossFading: {
      lv.reslice.rate.lastWork = SliceRateControl::Work::Other;
      if (!sp.united) {  // the composite unites the next set's occupancy in; no blend this frame
        sp.united = true;
        lv.reslice.occupancyUniteNext = true;
        break;
      }
      // F frames: F - 1 blend frames, then a copy of the next set (depth included). Each frame blends
      // every other image (layers and background alternate), which halves a blend frame's cost. An
      // image blended H times lays the new set over the old in its first I = ceil(H / 2) blends
      // (weight 1 / (I + 1 - j) at its j-th: the new set's opaque texels are in whole after the I-th)
      // and mixes towards the new set in the rest (1 / (H + 1 - j): the old set's own texels fade
      // out). A leaf the new set draws in another layer is thus whole in one of the two layers in
      // every frame: the coverage never dips (docs/design.md, the cross-fade).
      // Sets drawn from two cameras are not blended texel by texel (their texels hold different
      // points): the composite shows the visible set reprojected to the current camera, and the next
      // set replaces it in one copy (docs/design.md "Layers: reprojection", the refresh).
      const uint32_t f = sameCamera(sp.job.view, lv.visible.view) ? lv.settings.crossFadeFrames : 1u, n = lv.settings.layout.count(), blends = f - 1;
      if (sp.fadeStep == 0) sp.fadeFrom = lv.visible.layers;
      sp.fadeStep++;
      sp.fadeCopy = sp.fadeStep >= f;
      sp.fadeWeights.assign(n + 1, 0.0f);
      sp.fadeMergeDepth.assign(n, 0);
      sp.fadeOver.assign(n + 1, 0);
      if (!sp.fadeCopy) {
        for (uint32_t i = 0; i <= n; ++i) {
          const bool alternate = blends >= 2;
          if (alternate && (sp.fadeStep + i) % 2 != 0) continue;
          const uint32_t h = !alternate ? blends : (i % 2 == 0 ? blends / 2 : (blends + 1) / 2);
          // Image i blends at frames k with k + i even: its j-th blend is at k = 2j - (i odd).
          const uint32_t j = !alternate ? sp.fadeStep : (sp.fadeStep + i % 2) / 2;
          const uint32_t jj = std::min(j, h), in = (h + 1) / 2;
          sp.fadeOver[i] = jj <= in;
          sp.fadeWeights[i] = jj <= in ? 1.0f / float(in + 1 - jj) : 1.0f / float(h + 1 - jj);
          if (i < n && j == 1) sp.fadeMergeDepth[i] = 1;
        }
      }
      const float share = float(sp.fadeStep) / float(f);
      lv.reslice.fadePending = true;
      lv.stats.crossFade = share;
      if (sp.fadeCopy) {
        lv.reslice.occupancyRecomputeNext = true;
        finishSpread(lv);
      } else {
        for (size_t i = 0; i < lv.visible.layers.size(); ++i) lv.visible.layers[i] = mixLayerInfo(sp.fadeFrom[i], sp.job.layers[i], share);
      }
      break;
    }
    case SpreadPhase::Idle: break;
  }
  return Status();
}

}  // namespace

void rescheduleAfterChange(LayeredVegetation& lv, bool contentChanged, bool targetsRecreated, bool budgetChanged) {
  ResliceScheduler& r = lv.reslice;
  if (budgetChanged) {
    r.rate.trianglesPerMs = SliceRateControl{}.trianglesPerMs;
    r.rate.rateSamples.clear();
  }
  r.settingsChanged = r.settingsChanged || contentChanged || targetsRecreated;
  if (targetsRecreated) {
    r.forceImmediate = true;
    r.spread = SpreadRebuild{};
  } else if (contentChanged && r.spread.phase != SpreadPhase::Idle) {
    r.spread = SpreadRebuild{};
  }
}

void requestReslice(LayeredVegetation& lv, const std::string& reason, bool immediate) {
  lv.reslice.forcedReason = reason;
  lv.reslice.forceImmediate = lv.reslice.forceImmediate || immediate;
}

Status updateLayerView(LayeredVegetation& lv, const LayerView& view, bool* changed) {
  lv.stats.viewUpdates++;
  updateSliceRate(lv);
  lv.reslice.rebuildPending = lv.reslice.slicePending = lv.reslice.fadePending = lv.reslice.occupancyUniteNext = lv.reslice.occupancyRecomputeNow = false;
  const bool recomputeOccupancy = lv.reslice.occupancyRecomputeNext;
  lv.reslice.occupancyRecomputeNext = false;
  std::string reason;
  const LayerSettings& s = lv.settings;
  bool forced = false, outrun = false, byCamera = false;
  // The layers are drawn from the slice camera: `view` widened by the guard band.
  const LayerView slice = sliceCameraFor(lv, view);
  const bool stillFrame = !lv.reslice.haveView || sameCamera(view, lv.reslice.lastFrameView);  // the first view counts as still
  lv.reslice.movingFrames = stillFrame ? 0 : lv.reslice.movingFrames + 1;
  if (stillFrame) lv.reslice.outrun = false;
  lv.reslice.lastFrameView = view;
  if (!lv.reslice.haveView) {
    reason = "first view";
  } else if (!lv.reslice.forcedReason.empty()) {
    reason = lv.reslice.forcedReason;
    forced = true;
  } else if (lv.reslice.settingsChanged) {
    reason = "settings changed";
    forced = true;
  } else if (s.policy == ReslicePolicy::EveryFrame) {
    reason = "every frame";
  } else {
    // Error-driven: the visible layers are shown reprojected until that shows (the newest set's
    // camera, which the visible set has once a spread re-slice ends).
    double ratio = 0.0;
    if (!sameCamera(slice, lv.reslice.lastRebuildView)) reason = reprojectionReason(lv, lv.reslice.lastRebuildView, view, 1.0f, &ratio);
    byCamera = !reason.empty();
    // A spread re-slice that would be outrun is not started: for a camera moving for more than a
    // frame (a single jump is not a pace), at the pace the error grew since the last frame (in
    // thresholds), would it pass kSpreadBehind before the new set is in?
    // (An unbounded error, a camera inside the vegetation's bounds, is outrun at once.)
    const double perFrame = std::isfinite(ratio) && std::isfinite(lv.reslice.lastErrorRatio) ? std::max(ratio - lv.reslice.lastErrorRatio, 0.0) : 0.0;
    lv.reslice.lastErrorRatio = ratio;
    if (byCamera && spreadEnabled(lv) && lv.reslice.spread.phase == SpreadPhase::Idle && lv.reslice.movingFrames >= 2) {
      if (!std::isfinite(ratio) || ratio + perFrame * spreadFrames(lv) > kSpreadBehind) {
        reason = "a spread re-slice would fall behind the camera: " + reason;
        outrun = true;
      }
    }
    // A spread re-slice shows the visible set, reprojected, until its copy. When a moving camera
    // outruns it (the visible set's error past kSpreadBehind x the thresholds) it is dropped for a
    // re-slice at once at this view: the error stays bounded (docs/design.md "Layers: spread re-slicing").
    if (lv.reslice.spread.phase != SpreadPhase::Idle && !sameCamera(slice, lv.visible.view)) {
      const std::string behind = reprojectionReason(lv, lv.visible.view, view, kSpreadBehind);
      if (!behind.empty()) {
        reason = "a spread re-slice fell behind the camera: " + behind;
        outrun = true;
      }
    }
  }
  // Once outrun, the camera's re-slices are at once while it keeps moving (a spread one would be
  // outrun again: each frame of a steady move adds to the error its slices take frames to remove).
  if (outrun) lv.reslice.outrun = true;
  const bool wantAtOnce = !lv.reslice.haveView || lv.reslice.forceImmediate || !spreadEnabled(lv) ||
                          s.policy == ReslicePolicy::EveryFrame || outrun || (byCamera && lv.reslice.outrun);
  // A streamed mesh cannot be drawn in one frame: "at once" becomes slices as large as the ring
  // allows, copied in without a fade (SpreadRebuild.immediate).
  const bool atOnce = wantAtOnce && !lv.mesh.streamed;
  const bool spreading = lv.reslice.spread.phase != SpreadPhase::Idle;
  // A spread re-slice runs to its end for its own view; the policy looks again afterwards (a forced
  // re-slice or new settings restart it).
  if (!reason.empty() && (atOnce || !spreading || forced)) {
    if (outrun) lv.stats.outrunSpreads++;
    lv.reslice.lastErrorRatio = 0.0;
    lv.reslice.haveView = true;
    lv.reslice.settingsChanged = false;
    lv.reslice.forcedReason.clear();
    lv.reslice.forceImmediate = false;
    lv.reslice.lastRebuildView = slice;
    lv.stats.rebuilds++;
    lv.stats.lastRebuildReason = reason;
    if (atOnce) {
      lv.reslice.spread = SpreadRebuild{};
      CANOPY_TRY(placeForView(lv, slice));
      lv.reslice.rebuildPending = true;
      lv.reslice.rate.lastWork = SliceRateControl::Work::Other;
      lv.stats.crossFade = 1.0f;
    } else {
      lv.reslice.spread = SpreadRebuild{};
      lv.reslice.spread.phase = SpreadPhase::Placing;
      lv.reslice.spread.immediate = wantAtOnce;
      lv.stats.maxSliceTriangles = 0;
      beginPlacement(lv, slice, lv.reslice.spread.job);
      lv.stats.crossFade = 0.0f;
    }
  }
  if (lv.reslice.spread.phase != SpreadPhase::Idle) CANOPY_TRY(advanceSpread(lv));
  lv.stats.spreadPhase = uint32_t(lv.reslice.spread.phase);
  lv.stats.trianglesPerMs = lv.reslice.rate.trianglesPerMs;
  *changed = lv.reslice.rebuildPending || lv.reslice.fadePending;
  // The composite's occupancy: recomputed after a re-slice at once and in the frame after a
  // cross-fade's copy; the frame after the last slice unites the next set's tiles in
  // (occupancyUniteNext), which covers every fade step (old and new both partly visible) without
  // a recompute in a fade frame. (Marking the views' whole footprint occupied instead was tried:
  // the composite then works through every footprint tile of every layer, 60-70 ms a fade frame
  // more at 80K faces on lavapipe.)
  lv.reslice.occupancyDirty = lv.reslice.rebuildPending || recomputeOccupancy || lv.reslice.occupancyRecomputeNow;
  return Status();
}

}  // namespace canopy
