#pragma once
// Procedural vegetation scenes: the paper's five test scenes (Figure 1: shrub, tree crown, grass
// field, underwater vegetation, a large vegetation field) as VegetationModels, so the demo, the
// benchmark and the tests need no asset, and `canopy-scene` can write them as .glb.
//
// Every scene has separate rigid materials (bark, kelp stem, ground, rock: OPAQUE) and foliage
// materials (leaf, grass, kelp blade: MASK with a procedurally drawn alpha-masked texture), every
// leaf is its own connected component (its own vertices, root vertex = smallest (u, v) at its
// attachment), and the result depends only on the description (same seed, same bytes, whatever
// the thread count). Branching structure comes from a bracketed L-system interpreted by a 3D
// turtle with PUSH/POP ([ and ]), as in ../shared/seeds/002 section 3 (ABOP's turtle).
//
// Face budget: the rigid parts are generated first (L-system depth chosen so they stay within
// about a fifth of the request), the leaves fill the rest, so the total is within one leaf's
// faces (<= 12) of the request. Leaves are written in parallel straight into the final arrays;
// memory is about 80 bytes per face (50M faces: about 4 GB).
#include <cstdint>
#include <functional>
#include <string>

#include "engine/status.h"
#include "render/model.h"

namespace canopy {

enum class SceneKind : uint32_t { Shrub = 0, TreeCrown = 1, GrassField = 2, Kelp = 3, Field = 4 };
inline constexpr uint32_t kSceneKindCount = 5;

struct SceneDesc {
  SceneKind kind = SceneKind::Shrub;
  uint64_t faces = 80000;     // total triangles wanted, [kMinSceneFaces, kMaxSceneFaces]
  uint32_t seed = 1;          // any value; the same seed gives the same model
  uint32_t textureSize = 128; // leaf texture side, pixels: a power of two in [16, 2048]
  uint32_t threads = 0;       // worker threads for the leaves; 0: all hardware threads
  // Also the branch hierarchy for the per-vertex wind baseline (VegetationModel::bend and
  // ::branches, 8 bytes a vertex): from the L-system's brackets for plants; grass blades and kelp
  // ribbons get the leaf level only, ground and rock stay still.
  bool hierarchy = false;
  // Also the bounding-box hierarchy of the foliage (VegetationModel::boxParent, ::triangleBox, 4
  // bytes a face; seed 002 section 3): box 0 bounds the scene, each plant has a box under it and
  // every PUSH of its L-system opens a box under the enclosing one, closed by its POP; a leaf card
  // belongs to the box open where it is attached; grass and kelp blades to their patch's box.
  bool boxes = false;
};
inline constexpr uint64_t kMinSceneFaces = 2000;
inline constexpr uint64_t kMaxSceneFaces = 200'000'000;

struct SceneStats {
  uint64_t faces = 0;        // triangles generated (= model.triangleCount())
  uint64_t rigidFaces = 0;   // bark / stems / ground / rock
  uint64_t leafFaces = 0;
  uint64_t leaves = 0;       // connected foliage components
  uint32_t plants = 0;       // plants placed (trees, shrubs, kelp stems; grass counts as one patch)
  uint32_t lsystemIterations = 0;  // derivation depth of the (largest) L-system plant, 0 for none
  uint64_t pushes = 0;       // PUSH modules ([) interpreted over all L-system plants
};

// Called from the calling thread while leaves are generated: (stage, done, total).
using SceneProgress = Progress;

// "shrub", "tree", "grass", "kelp", "field" (also "tree-crown", "grass-field", "underwater").
Status parseSceneKind(const std::string& text, SceneKind* out);
const char* sceneName(SceneKind kind);
// Checks the ranges above; the error names the parameter and its allowed range.
Status validateSceneDesc(const SceneDesc& desc);

// Generates the scene. On failure `out` is left empty.
Status generateScene(const SceneDesc& desc, VegetationModel* out, SceneStats* stats = nullptr,
                     const SceneProgress& progress = {});

// A hash of everything in a model (geometry, materials, images): equal hashes, equal models.
uint64_t modelHash(const VegetationModel& model);

}  // namespace canopy
