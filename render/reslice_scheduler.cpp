#include "render/reslice_scheduler.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>

#include "engine/device.h"
#include "engine/timing.h"
#include "engine/transfer.h"
#include "render/layer_common.h"
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
std::string reprojectionReason(const ResliceParts& p, const LayerView& slice, const LayerView& view, float scale = 1.0f,
                               double* ratio = nullptr) {
  const LayerSettings& s = p.settings;
  const float pixels = s.errorThresholdPixels * scale, degrees = s.turnThresholdDegrees * scale;
  std::vector<SlabRange> slabs;
  for (const LayerInfo& l : p.visible.layers) slabs.push_back({l.slab.zNear, l.slab.zFar, l.slab.depth});
  const glm::dvec2 size(p.placement.width, p.placement.height);
  const ReprojectionError e = estimateReprojectionError(slice, view, slabs, p.placement.instances->boundsMin,
                                                        p.placement.instances->boundsMax, size, glm::dvec2(p.outputSize),
                                                        p.visible.extent.known ? &p.visible.extent : nullptr);
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
uint64_t sliceTriangles(const ResliceScheduler& r, const ResliceParts& p) {
  return p.fixedSliceTriangles ? p.fixedSliceTriangles
                                     : std::max<uint64_t>(1024, uint64_t(p.settings.rebuildBudgetMs * r.rate.trianglesPerMs));
}

// Frames a spread re-slice of the whole mesh would take at the measured drawing rate: its placement,
// its slices, the frame that unites the occupancy and the copy (a set from another camera).
double spreadFrames(const ResliceScheduler& r, const ResliceParts& p) {
  uint64_t triangles = 0;
  for (const MeshChunk& c : p.mesh.chunks) triangles += c.triangleCount;
  return 3.0 + std::ceil(double(triangles) / double(sliceTriangles(r, p)));
}

// The interval since the last view update tells what the last frame's layer work cost
// (SliceRateControl); a drawing frame's triangles over its cost above the still baseline update
// the rate (frame times are noisy: see below).
void updateSliceRate(ResliceScheduler& rs, const LayerSettings& settings) {
  SliceRateControl& r = rs.rate;
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
      const double budget = std::max<double>(settings.rebuildBudgetMs, 1e-3);
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

// The shares of a paced re-slice's D slices, as cumulative bounds (D + 1, from 0 to 1): even, but
// the last frame, which also copies the set in and recomputes the occupancy, draws w of a share,
// with w chosen so that it costs what the others do: (1 - c(D - 1)) / (1 + c), c the copy's cost
// against a whole re-slice's drawing (kPacedCopyCost), at least 0.
std::vector<double> pacedShares(uint32_t slices) {
  const uint32_t n = std::max<uint32_t>(slices, 1);
  const double c = kPacedCopyCost, last = n < 2 ? 1.0 : std::clamp((1.0 - c * double(n - 1)) / (1.0 + c), 0.0, 1.0);
  std::vector<double> bounds(n + 1, 0.0);
  const double total = double(n - 1) + last;
  for (uint32_t i = 0; i < n; ++i) bounds[i + 1] = bounds[i] + (i + 1 < n ? 1.0 : last) / total;
  bounds[n] = 1.0;
  return bounds;
}

// The next frame's draws of a spread re-slice: triangles from the cursor, as many as the budget
// and the measured rate allow (at least 1024, so it always ends); a streamed mesh also stops at
// what this frame's ring segment holds, and its parts are copied there now (the frame that reads
// them is the one being recorded: docs/design.md "Layers: mesh budget and staging ring").
void planSlice(ResliceScheduler& r, const ResliceParts& p) {
  SpreadRebuild& sp = r.spread;
  sp.slice.clear();
  if (sp.paced) {
    // Slice k of D draws the k-th D-th of every item (not D runs of the item list in turn), so each
    // slice holds the same share of leaves and wood: the slices' fragments, not only their
    // triangles, are even (in turn, the leaves' and the trunk's slices differed 3x in fragments).
    // The shares were set at the start (pacedShares): the last frame draws less.
    const uint32_t k = sp.pacedSlice, n = std::max<uint32_t>(sp.pacedSlices, 1);
    auto bound = [&](uint32_t count, uint32_t j) {
      return j >= n ? count : uint32_t(std::floor(double(count) * (j < sp.pacedBounds.size() ? sp.pacedBounds[j] : double(j) / n)));
    };
    uint64_t drawn = 0;
    for (const ChunkPart& item : sp.items) {
      const uint32_t from = bound(item.triangleCount, k), to = bound(item.triangleCount, k + 1);
      if (to <= from) continue;
      ChunkPart part = item;
      part.firstTriangle = item.firstTriangle + from;
      part.triangleCount = to - from;
      sp.slice.push_back(part);
      drawn += to - from;
    }
    sp.sliceClears = k == 0;
    sp.sliceLast = k + 1 >= n;
    sp.pacedSlice++;
    r.slicePending = true;
    r.rate.lastWork = SliceRateControl::Work::Other;  // sized by the camera's pace, not the budget
    p.stats.lastSliceTriangles = drawn;
    p.stats.maxSliceTriangles = std::max(p.stats.maxSliceTriangles, drawn);
    return;
  }
  const uint64_t want = sp.immediate ? UINT64_MAX : sliceTriangles(r, p);
  sp.sliceClears = sp.cursorItem == 0 && sp.cursorTriangle == 0;
  MeshRing& ring = p.mesh.ring;
  uint64_t segment = 0, usedV = 0, usedI = 0, usedR = 0;
  if (p.mesh.streamed) {
    const Device& d = *p.device;
    segment = (d.anyFrame ? d.frameNumber : ring.counter++) % ring.segments;
  }
  uint64_t drawn = 0;
  while (sp.cursorItem < sp.items.size() && drawn < want) {
    const ChunkPart& item = sp.items[sp.cursorItem];
    const MeshChunk& c = p.mesh.chunks[item.chunk];
    uint32_t count = uint32_t(std::min<uint64_t>(item.triangleCount - sp.cursorTriangle, want - drawn));
    ChunkPart part = item;  // its weight and level (a part of the impostor cut)
    part.firstTriangle = item.firstTriangle + sp.cursorTriangle;
    part.triangleCount = count;
    if (p.mesh.streamed && count) {
      const uint64_t roots = roundUp(std::max<uint32_t>(c.tableEntries(), 1), ring.rootAlignment);
      if (usedV + c.vertexCount > ring.vertexCapacity || usedR + roots > ring.rootCapacity || usedI + 3 > ring.indexCapacity) break;
      part.triangleCount = count = uint32_t(std::min<uint64_t>(count, (ring.indexCapacity - usedI) / 3));
      part.ringVertex = segment * ring.vertexCapacity + usedV;
      part.ringIndex = segment * roundUp(ring.indexCapacity * 2, 4) / 2 + usedI;
      part.ringRoot = segment * ring.rootCapacity + usedR;
      auto* v = static_cast<gpu::LayerVertex*>(p.mesh.vertices.allocation.mapped);
      auto* ix = static_cast<uint16_t*>(p.mesh.indexBuffer.allocation.mapped);
      auto* rt = static_cast<gpu::LayerLeafRoot*>(p.mesh.leafRoots.allocation.mapped);
      std::memcpy(v + part.ringVertex, p.mesh.hostMesh.vertices.data() + c.firstVertex, size_t(c.vertexCount) * sizeof(gpu::LayerVertex));
      std::memcpy(ix + part.ringIndex, p.mesh.hostMesh.indices.data() + c.firstIndex + 3ull * part.firstTriangle, size_t(count) * 6);
      std::memcpy(rt + part.ringRoot, p.mesh.hostMesh.roots.data() + c.firstRoot, size_t(c.tableEntries()) * sizeof(gpu::LayerLeafRoot));
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
  r.slicePending = true;
  // A slice sized by the ring alone says nothing about the drawing rate the budget sizes.
  r.rate.lastWork = sp.immediate ? SliceRateControl::Work::Other : SliceRateControl::Work::Slice;
  r.rate.lastTriangles = drawn;
  p.stats.lastSliceTriangles = drawn;
  p.stats.maxSliceTriangles = std::max(p.stats.maxSliceTriangles, drawn);
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
void planSpreadItems(ResliceScheduler& r, const ResliceParts& p) {
  SpreadRebuild& sp = r.spread;
  planImpostorCut(p.placement, sp.job.frame, sp.job.view, sp.job.runs, &sp.impostors, p.stats);
  const bool cut = sp.impostors.cut.active;
  sp.items = cut ? sp.impostors.parts : std::vector<ChunkPart>{};
  const bool carry = carriesWood(p.mesh, p.settings, cut);
  for (uint32_t c = 0; c < p.mesh.chunks.size(); ++c) {
    const MeshChunk& mc = p.mesh.chunks[c];
    // Rigid chunks only into a background (drawn every frame otherwise: render/rigid_follow.h),
    // or with the foliage where they are carried into the layers (render/layer_mesh.h carriesWood).
    if ((drawnWithFoliage(mc, carry) ? !cut : drawsBackground(p.mesh, p.settings)) && mc.triangleCount)
      sp.items.push_back(ChunkPart{c, 0, mc.triangleCount});
  }
}

// The frame of the last step (the copy of the next set): its placement becomes the visible one.
void finishSpread(ResliceScheduler& r, const ResliceParts& p) {
  SpreadRebuild& sp = r.spread;
  p.stats.lastVisibleInstances = uint32_t(sp.job.depthRows.size());
  p.stats.lastVisibleSpecies = visibleSpecies(sp.job);
  p.visible.view = sp.job.view;
  p.visible.runs = sp.job.runs;
  takeVertexBounds(p.visible, sp.job);
  p.visible.frame = sp.job.frame;
  p.visible.layers = std::move(sp.job.layers);
  p.visible.impostors = std::move(sp.impostors);
  p.stats.spreadRebuilds++;
  p.stats.lastSpreadFrames = sp.frames;
  p.stats.crossFade = 1.0f;
  sp.phase = SpreadPhase::Idle;
  sp.job = PlacementJob{};
  sp.fadeFrom.clear();
}

// One frame of a spread re-slice: placement for up to the budget, then slices, then the fade.
Status advanceSpread(ResliceScheduler& r, const ResliceParts& p) {
  SpreadRebuild& sp = r.spread;
  sp.frames++;
  switch (sp.phase) {
    case SpreadPhase::Placing: {
      const auto deadline = Clock::now() + std::chrono::duration<double, std::milli>(p.settings.rebuildBudgetMs);
      const auto deadlineTp = std::chrono::time_point_cast<Clock::duration>(deadline);
      bool done = false;
      const double before = sp.job.ms;
      CANOPY_TRY(advancePlacement(p.placement, sp.job, sp.immediate || sp.paced ? nullptr : &deadlineTp, &done));
      r.rate.lastWork = SliceRateControl::Work::Placement;
      r.rate.lastPlacementMs = sp.job.ms - before;
      if (done) {
        p.stats.lastPlacementMs = sp.job.ms;
        planSpreadItems(r, p);
        sp.phase = SpreadPhase::Drawing;
        // No visible placement of this layer count yet (the first view, or new layer images, of a
        // streamed mesh): the new one describes the visible images, still empty, until the copy.
        if (p.visible.layers.size() != sp.job.layers.size()) {
          p.visible.layers = sp.job.layers;
          p.visible.view = sp.job.view;
          p.visible.runs = sp.job.runs;
          takeVertexBounds(p.visible, sp.job);
          p.visible.frame = sp.job.frame;
        }
      }
      if (!done || !(sp.immediate || sp.paced)) break;
      [[fallthrough]];  // asked at once or paced: the first slice in the placement's frame
    }
    case SpreadPhase::Drawing:
      planSlice(r, p);
      if (!sp.sliceLast) break;
      if (!sp.immediate && !sp.paced) {
        sp.phase = SpreadPhase::CrossFading;  // from the next frame
        break;
      }
      // Asked at once, or paced (sliced for this frame's view): the next set is copied in behind the
      // last slice (the copy pass follows the slice pass), without a fade, and the occupancy
      // recomputed in this frame.
      if (sp.paced) p.stats.pacedRebuilds++;
      sp.fadeCopy = true;
      r.fadePending = true;
      r.occupancyRecomputeNow = true;
      finishSpread(r, p);
      break;
    case SpreadPhase::CrossFading: {
      r.rate.lastWork = SliceRateControl::Work::Other;
      if (!sp.united) {  // the composite unites the next set's occupancy in; no blend this frame
        sp.united = true;
        r.occupancyUniteNext = true;
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
      const uint32_t f = sameCamera(sp.job.view, p.visible.view) ? p.settings.crossFadeFrames : 1u, n = p.settings.layout.count(), blends = f - 1;
      if (sp.fadeStep == 0) sp.fadeFrom = p.visible.layers;
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
      r.fadePending = true;
      p.stats.crossFade = share;
      if (sp.fadeCopy) {
        r.occupancyRecomputeNext = true;
        finishSpread(r, p);
      } else {
        for (size_t i = 0; i < p.visible.layers.size(); ++i) p.visible.layers[i] = mixLayerInfo(sp.fadeFrom[i], sp.job.layers[i], share);
      }
      break;
    }
    case SpreadPhase::Idle: break;
  }
  return Status();
}

}  // namespace

void rescheduleAfterChange(ResliceScheduler& r, bool contentChanged, bool targetsRecreated, bool budgetChanged) {
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

void requestReslice(ResliceScheduler& r, const std::string& reason, bool immediate) {
  r.forcedReason = reason;
  r.forceImmediate = r.forceImmediate || immediate;
}

bool spreadEnabled(const LayerSettings& settings, bool writeIds) { return settings.rebuildBudgetMs > 0 && !writeIds; }
bool pacedEnabled(const LayerSettings& settings, bool writeIds) { return settings.pacedReslices && !writeIds; }

ResliceDecision decideReslice(ResliceScheduler& r, const ResliceParts& p, const LayerView& view, const LayerView& slice) {
  ResliceDecision d;
  std::string reason;
  const LayerSettings& s = p.settings;
  bool forced = false, outrun = false, byCamera = false;
  const bool stillFrame = !r.haveView || sameCamera(view, r.lastFrameView);  // the first view counts as still
  r.movingFrames = stillFrame ? 0 : r.movingFrames + 1;
  if (stillFrame) r.outrun = false;
  r.previousFrameView = r.lastFrameView;
  r.lastFrameView = view;
  if (!r.haveView) {
    reason = "first view";
  } else if (!r.forcedReason.empty()) {
    reason = r.forcedReason;
    forced = true;
  } else if (r.settingsChanged) {
    reason = "settings changed";
    forced = true;
  } else if (s.policy == ReslicePolicy::EveryFrame) {
    reason = "every frame";
  } else {
    // Error-driven: the visible layers are shown reprojected until that shows (the newest set's
    // camera, which the visible set has once a spread re-slice ends).
    double ratio = 0.0;
    if (!sameCamera(slice, r.lastRebuildView)) reason = reprojectionReason(p, r.lastRebuildView, view, 1.0f, &ratio);
    byCamera = !reason.empty();
    // A spread re-slice that would be outrun is not started: for a camera moving for more than a
    // frame (a single jump is not a pace), at the pace the error grew since the last frame (in
    // thresholds), would it pass kSpreadBehind before the new set is in?
    // (An unbounded error, a camera inside the vegetation's bounds, is outrun at once.)
    const double perFrame = std::isfinite(ratio) && std::isfinite(r.lastErrorRatio) ? std::max(ratio - r.lastErrorRatio, 0.0) : 0.0;
    // Paced (LayerSettings.pacedReslices; issue 79): a moving camera (its last motion known) starts the
    // next set D frames before its error would pass the thresholds (at this frame's pace, in
    // thresholds a frame: the change since the last frame, either way, as a set sliced ahead is
    // approached), drawn in D even slices and shown in the D-th frame, sliced for the view predicted
    // there. Every frame of a steady move then draws a D-th of a re-slice instead of one frame in D
    // drawing all of it. An error over the thresholds already is the policy's re-slice at once.
    const double pace = std::isfinite(ratio) && std::isfinite(r.lastErrorRatio) ? std::fabs(ratio - r.lastErrorRatio) : 0.0;
    r.lastErrorRatio = ratio;
    if (p.pacedEnabled && !p.mesh.streamed && r.movingFrames >= 1 && r.spread.phase == SpreadPhase::Idle && std::isfinite(ratio) &&
        pace > 1e-6) {
      const double left = (1.0 - ratio) / pace;  // frames until the visible set's error passes the thresholds
      // The visible set is shown up to the frame before the new one's (D - 2 frames on from this
      // one), so D - 2 <= left; past the thresholds already: the policy's re-slice at once.
      if (left >= 0.0 && left + 2.0 < double(kPacedMaxFrames)) {
        d.pacedFrames = uint32_t(std::clamp(std::floor(left) + 2.0, 2.0, double(kPacedMaxFrames)));
        if (reason.empty()) reason = "paced: the error passes the thresholds in " + std::to_string(d.pacedFrames) + " frames";
        byCamera = true;
      }
    }
    if (d.pacedFrames == 0 && byCamera && p.spreadEnabled && r.spread.phase == SpreadPhase::Idle && r.movingFrames >= 2) {
      if (!std::isfinite(ratio) || ratio + perFrame * spreadFrames(r, p) > kSpreadBehind) {
        reason = "a spread re-slice would fall behind the camera: " + reason;
        outrun = true;
      }
    }
    // A spread re-slice shows the visible set, reprojected, until its copy. When a moving camera
    // outruns it (the visible set's error past kSpreadBehind x the thresholds) it is dropped for a
    // re-slice at once at this view: the error stays bounded (docs/design.md "Layers: spread re-slicing").
    if (r.spread.phase != SpreadPhase::Idle && !sameCamera(slice, p.visible.view)) {
      const std::string behind = reprojectionReason(p, p.visible.view, view, kSpreadBehind);
      if (!behind.empty()) {
        reason = "a spread re-slice fell behind the camera: " + behind;
        outrun = true;
      }
    }
  }
  // Once outrun, the camera's re-slices are at once while it keeps moving (a spread one would be
  // outrun again: each frame of a steady move adds to the error its slices take frames to remove).
  if (outrun) r.outrun = true;
  const bool wantAtOnce = d.pacedFrames == 0 && (!r.haveView || r.forceImmediate || !p.spreadEnabled ||
                                                 s.policy == ReslicePolicy::EveryFrame || outrun || (byCamera && r.outrun));
  // A streamed mesh cannot be drawn in one frame: "at once" becomes slices as large as the ring
  // allows, copied in without a fade (SpreadRebuild.immediate).
  d.atOnce = wantAtOnce && !p.mesh.streamed;
  d.immediate = wantAtOnce;
  d.outrun = outrun;
  d.byCamera = byCamera && (r.movingFrames >= 2 || d.pacedFrames > 0);
  // A spread re-slice runs to its end for its own view; the policy looks again afterwards (a forced
  // re-slice or new settings restart it).
  const bool spreading = r.spread.phase != SpreadPhase::Idle;
  if (!reason.empty() && (d.atOnce || !spreading || forced)) d.reason = std::move(reason);
  return d;
}

void acceptReslice(ResliceScheduler& r, const LayerView& slice) {
  r.lastErrorRatio = 0.0;
  r.haveView = true;
  r.settingsChanged = false;
  r.forcedReason.clear();
  r.forceImmediate = false;
  r.lastRebuildView = slice;
}

Status advanceReslice(ResliceScheduler& r, const ResliceParts& p, const LayerView& view, const LayerView& slice, bool* changed) {
  p.stats.viewUpdates++;
  updateSliceRate(r, p.settings);
  r.rebuildPending = r.slicePending = r.fadePending = r.occupancyUniteNext = r.occupancyRecomputeNow = false;
  const bool recomputeOccupancy = r.occupancyRecomputeNext;
  r.occupancyRecomputeNext = false;
  const ResliceDecision d = decideReslice(r, p, view, slice);
  if (!d.reason.empty()) {
    if (d.outrun) p.stats.outrunSpreads++;
    // A moving camera's re-slice at once, sliced for where the camera will be predictFrames frames
    // on (its last frame's motion D repeated: view' = D^k view): the error falls to zero as the
    // camera arrives there before it grows again, so the next re-slice comes later (issue 79;
    // docs/lab/performance-notebook.md "Pacing: a moving camera's frames (issue 79)").
    // A paced re-slice is sliced for the view of the frame it is shown in, pacedFrames - 1 on.
    LayerView predicted = slice;
    const uint32_t ahead = d.pacedFrames > 1 ? d.pacedFrames - 1 : d.atOnce && d.byCamera ? p.settings.predictFrames : 0;
    if (ahead > 0 && d.byCamera) {
      const glm::mat4 step = r.lastFrameView.view * glm::inverse(r.previousFrameView.view);
      for (uint32_t k = 0; k < ahead; ++k) predicted.view = step * predicted.view;
    }
    acceptReslice(r, predicted);
    p.stats.rebuilds++;
    p.stats.lastRebuildReason = d.reason;
    r.spread = SpreadRebuild{};
    if (d.atOnce) {
      CANOPY_TRY(placeForView(p.placement, predicted, p.visible, p.stats));
      r.rebuildPending = true;
      r.rate.lastWork = SliceRateControl::Work::Other;
      p.stats.crossFade = 1.0f;
    } else {
      r.spread.phase = SpreadPhase::Placing;
      r.spread.immediate = d.immediate;
      r.spread.paced = d.pacedFrames > 1;
      r.spread.pacedSlices = d.pacedFrames;
      if (r.spread.paced) r.spread.pacedBounds = pacedShares(d.pacedFrames);
      p.stats.maxSliceTriangles = 0;
      beginPlacement(p.placement, predicted, r.spread.job);
      p.stats.crossFade = 0.0f;
    }
  }
  if (r.spread.phase != SpreadPhase::Idle) CANOPY_TRY(advanceSpread(r, p));
  p.stats.spreadPhase = uint32_t(r.spread.phase);
  p.stats.trianglesPerMs = r.rate.trianglesPerMs;
  *changed = r.rebuildPending || r.fadePending;
  // The composite's occupancy: recomputed after a re-slice at once and in the frame after a
  // cross-fade's copy; the frame after the last slice unites the next set's tiles in
  // (occupancyUniteNext), which covers every fade step (old and new both partly visible) without
  // a recompute in a fade frame. (Marking the views' whole footprint occupied instead was tried:
  // the composite then works through every footprint tile of every layer, 60-70 ms a fade frame
  // more at 80K faces on lavapipe.)
  r.occupancyDirty = r.rebuildPending || recomputeOccupancy || r.occupancyRecomputeNow;
  return Status();
}

}  // namespace canopy
