#pragma once
// When the layers are re-sliced and how (docs/design.md "Layers: spread re-slicing"): the policy
// applied to each new view, a spread re-slice's phases (placing, drawing slices into the next set,
// the cross-fade), the slice sizing from measured frame times, and what the composite must
// recompute because of it.
#include <chrono>
#include <cstdint>
#include <string>
#include <vector>

#include "engine/camera.h"
#include "engine/status.h"
#include "render/layer_mesh.h"
#include "render/layer_placement.h"

namespace canopy {
struct Device;

enum class SpreadPhase : uint32_t { Idle = 0, Placing = 1, Drawing = 2, CrossFading = 3 };  // = LayerStats.spreadPhase

// docs/design.md "Layers: spread re-slicing".
// A spread re-slice whose visible set's estimated error passes this many times the thresholds
// (errorThresholdPixels, turnThresholdDegrees) is dropped for a re-slice at once.
constexpr float kSpreadBehind = 2.0f;
// A paced re-slice (LayerSettings.pacedReslices) is drawn over at most this many frames (its camera
// predicted that far: about half a second at 30 frames a second).
constexpr uint32_t kPacedMaxFrames = 16;
// A paced re-slice's last frame copies the new set in and recomputes the occupancy: on lavapipe at
// 1024x768 about a quarter of what drawing the 80K shrub's whole re-slice costs (35 of 140 ms;
// docs/lab/performance-notebook.md "Pacing: a moving camera's frames (issue 79)"). Frame intervals
// cannot measure it where the host does other work between frames (the benchmark's alternated
// contexts), and GPU timestamps read near zero on lavapipe: a constant.
constexpr double kPacedCopyCost = 0.25;

struct SpreadRebuild {
  SpreadPhase phase = SpreadPhase::Idle;
  PlacementJob job;
  uint32_t frames = 0;                 // frames since it started
  // What the re-slice draws, in order, once its placement is done: every chunk whole, or with
  // impostors the cut's foliage parts and then the rigid chunks (the cut is `impostors`).
  std::vector<ChunkPart> items;
  ImpostorDraws impostors;
  uint32_t cursorItem = 0, cursorTriangle = 0;  // the next triangle to draw: items[cursorItem], from its cursorTriangle-th
  std::vector<ChunkPart> slice;        // this frame's draws into the next set
  bool sliceClears = false;            // this frame's slice is the first: clear the next set (and draw the opaque impostors)
  bool sliceLast = false;              // this frame's slice is the last (and draws the fading impostors)
  bool united = false;                 // the frame after the last slice unites the occupancy (no fade)
  uint32_t fadeStep = 0;               // 1..crossFadeFrames during the cross-fade (the last copies)
  bool fadeCopy = false;               // this frame's step is the last: copy the next set
  // Asked at once but the mesh is streamed: placement in one frame, slices as large as the ring
  // segment allows, and the copy without a fade in the frame of the last slice.
  bool immediate = false;
  // A moving camera's paced re-slice (LayerSettings.pacedReslices): placement and the first slice in
  // its first frame, pacedSlices even slices (one a frame), the copy without a fade in the last.
  bool paced = false;
  uint32_t pacedSlices = 0, pacedSlice = 0;  // slices in all; the next one's index
  std::vector<double> pacedBounds;     // slice k draws the share [bounds[k], bounds[k + 1]) of every item
  std::vector<float> fadeWeights;      // this frame's LayerFadePush.weight per layer, then the
                                       // background; 0: not blended this frame
  std::vector<uint8_t> fadeMergeDepth; // per layer: its first blend, which takes the nearer depth
  std::vector<uint8_t> fadeOver;       // per image: this blend lays the new set over the old (the
                                       // fade's first half), else mixes towards it (the second)
  std::vector<LayerInfo> fadeFrom;     // the visible placement when the fade started
};

// Sizes the spread slices: frame intervals (between updateLayerView calls) of frames without layer
// work give the still baseline; a drawing frame's interval above it is what its triangles cost.
struct SliceRateControl {
  std::chrono::steady_clock::time_point lastUpdate{};
  bool haveLast = false;
  enum class Work { None, Placement, Slice, Other } lastWork = Work::Other;
  uint64_t lastTriangles = 0;
  double lastPlacementMs = 0;          // CPU placement time of a Placement frame (taken off its interval)
  std::vector<double> stillMs;         // the last few still intervals (ring)
  uint32_t stillNext = 0;
  std::vector<double> rateSamples;     // the last few slices' triangles / cost (ring)
  uint32_t rateNext = 0;
  double trianglesPerMs = 2000.0;      // start: a slow CPU device's rate (lavapipe draws ~2000-4000/ms)
};

struct ResliceScheduler {
  bool rebuildPending = false;
  bool haveView = false;
  bool settingsChanged = false;
  std::string forcedReason;     // re-slice at the next view update for this reason (requestReslice)
  bool forceImmediate = false;  // ... and at once
  bool slicePending = false;    // this frame draws spread.slice into the next set
  bool fadePending = false;     // this frame runs a cross-fade step
  // Which tiles hold foliage may have changed this frame (the composite's occupancy): a re-slice at
  // once and the frame after a cross-fade recompute it; the frame after a spread re-slice's last
  // slice has the next set's tiles united in (occupancyUniteNext), which covers the cross-fade.
  bool occupancyDirty = false;
  bool occupancyUniteNext = false;
  bool occupancyRecomputeNext = false;  // the last fade step asks the frame after it
  bool occupancyRecomputeNow = false;   // a streamed re-slice asked at once copied its set in this frame
  SpreadRebuild spread;
  SliceRateControl rate;
  LayerView lastRebuildView;  // the slice camera of the last re-slice (the guard band's widened view)
  // A moving camera outran a spread re-slice: the camera's re-slices are at once until it stops
  // (a frame at the previous frame's camera).
  bool outrun = false;
  LayerView lastFrameView;
  LayerView previousFrameView;  // the view update's before lastFrameView (the camera's last motion)
  uint32_t movingFrames = 0;  // consecutive view updates whose camera differs from the previous one's
  double lastErrorRatio = 0;  // the last frame's estimated error over its threshold (its growth a frame)
};

// What the scheduler reads and writes besides its own state (render/layers.cpp fills it from the
// vegetation): what a placement reads, the settings in force, the mesh (its chunks; a streamed
// mesh's ring, which the slices fill), the visible set a re-slice replaces, the statistics, the
// device (a streamed mesh's ring segment is its frame number's; null without a streamed mesh), the
// output the layers are for (their size less the guard band), whether re-slices may be spread, and
// a fixed slice size (tests; 0: measured).
struct ResliceParts {
  const PlacementInputs& placement;
  const LayerSettings& settings;
  LayerMesh& mesh;
  VisibleLayers& visible;
  LayerStats& stats;
  const Device* device;
  glm::uvec2 outputSize;
  bool spreadEnabled;
  uint32_t fixedSliceTriangles;
  bool pacedEnabled = false;  // a moving camera's re-slices may be paced (pacedEnabled())
};

// Whether re-slices may be spread over frames: a rebuild budget, and not with the id output
// (whose triangle ids need every draw whole).
bool spreadEnabled(const LayerSettings& settings, bool writeIds);
// Whether a moving camera's re-slices may be paced (LayerSettings.pacedReslices): not with the id
// output either. Either needs the second layer set.
bool pacedEnabled(const LayerSettings& settings, bool writeIds);

// Asks for a re-slice at the next view update, for `reason` (LayerStats.lastRebuildReason);
// `immediate`: at once rather than spread (an earlier request at once stays at once).
void requestReslice(ResliceScheduler& scheduler, const std::string& reason, bool immediate);

// The settings or the target size changed: `contentChanged`, what the layers hold differs (re-slice;
// a spread re-slice drawn with the old settings starts again); `targetsRecreated`, the images are
// new and empty (re-slice at once: nothing to fade from); `budgetChanged`, the slice rate measured
// for other slice sizes is dropped (a slice's cost is not linear in its triangles; the still
// baseline carries over).
void rescheduleAfterChange(ResliceScheduler& scheduler, bool contentChanged, bool targetsRecreated, bool budgetChanged);

// The re-slicing policy's verdict for a frame's camera `view` (whose slice camera is `slice`): why
// the layers are re-sliced now ("": they are not), and how. It tracks the camera's motion in the
// scheduler (moving frames, the error's growth, an outrun spread re-slice) but starts nothing.
struct ResliceDecision {
  std::string reason;
  bool atOnce = false;     // placed and drawn in this frame; else a spread re-slice starts
  bool immediate = false;  // asked at once: a spread re-slice (streamed mesh) then draws slices as large as the ring, no fade
  bool outrun = false;     // a spread re-slice fell, or would fall, behind the camera
  bool byCamera = false;   // caused by a moving camera whose motion is known (two frames or more; paced: one)
  // A paced re-slice (LayerSettings.pacedReslices): drawn over this many frames (at least 2), sliced
  // for the view the camera is predicted to have in the last, where it is shown; 0: not paced.
  uint32_t pacedFrames = 0;
};
ResliceDecision decideReslice(ResliceScheduler& scheduler, const ResliceParts& parts, const LayerView& view, const LayerView& slice);
// A re-slice for the slice camera `slice` starts (a decision's): the requests and changes it
// answers are settled, and the camera's error is measured from `slice` from now on.
void acceptReslice(ResliceScheduler& scheduler, const LayerView& slice);

// Applies the policy for the new view and advances a spread re-slice: *changed tells whether the
// next recorded layer passes change the visible layers (a re-slice at once, whose placement has
// been recomputed for `slice` into parts.visible, or a cross-fade step).
Status advanceReslice(ResliceScheduler& scheduler, const ResliceParts& parts, const LayerView& view, const LayerView& slice,
                      bool* changed);

}  // namespace canopy
