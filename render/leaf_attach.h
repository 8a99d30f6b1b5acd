#pragma once
// Where each leaf meets the rigid parts (docs/design.md "Rigid parts in wind"): for every leaf the
// vertex of it nearest to a rigid triangle and the nearest point of that triangle. A leaf whose
// nearest rigid point lies within the attachment distance grows from it: its root is taken there
// (render/leaf_roots.h), so it goes into the layer of the depth where it meets its branch, and the
// attachment-gap measure (canopy-bench attach) follows the two points on screen.
//
// Cost: the rigid triangles in a uniform grid of cells about the attachment distance (or the
// rigid triangles' median size, if larger), then one grid lookup per foliage vertex: linear in the
// mesh for meshes whose triangles are of similar size.
#include <cstdint>
#include <unordered_map>
#include <vector>

#include <glm/glm.hpp>

#include "engine/status.h"
#include "render/leaf_roots.h"
#include "render/model.h"
#include "shared/layers.h"

namespace canopy {

// A leaf meets the rigid parts when a vertex of it lies within this share of its plant's height of a
// rigid triangle (the height, which turning a copy about the vertical keeps, not the box's diagonal).
inline constexpr float kAttachShare = 0.014f;

struct LeafAttachment {
  uint32_t vertex = kNoLeaf;  // the leaf's vertex nearest the rigid parts (model index); kNoLeaf: not attached
  glm::vec3 rigidPoint{0.0f}; // the nearest point of the rigid triangles to it
  uint32_t triangle = 0;      // the rigid triangle holding it (model index)
  float distance = INFINITY;  // between the two, model units
};

// The rigid triangles in a uniform grid, for nearest-point queries within `reach`.
struct RigidGrid {
  const VegetationModel* model = nullptr;
  float reach = 0.0f, cell = 1.0f;  // the largest reach
  std::vector<float> reachOf;        // per triangle, its reach
  glm::vec3 origin{0.0f};
  std::unordered_map<uint64_t, std::vector<uint32_t>> cells;
};
// `reach` <= 0: kAttachShare of the height of each rigid triangle's plant
// (render/plants.h plantSizeOfTriangles). The grid points into `model`.
RigidGrid buildRigidGrid(const VegetationModel& model, const std::vector<uint8_t>& foliage, float reach);
// The rigid point nearest p within the grid's reach, or false.
bool nearestRigidPoint(const RigidGrid& grid, const glm::vec3& p, LeafAttachment* out);

// The attachment of every leaf of `roots` (leafOfVertex, leafRoot) to the triangles that are not
// foliage (`foliage` per triangle), within `maxDistance` model units (<= 0: kAttachShare of the
// rigid triangle's plant's height); leaves farther from every rigid triangle are not attached.
Status findLeafAttachments(const VegetationModel& model, const std::vector<uint8_t>& foliage, const LeafRoots& roots,
                           float maxDistance, std::vector<LeafAttachment>* out);

// The position each leaf's layer is decided by (docs/design.md "Rigid parts in wind"): for a leaf
// whose root lies within the attachment reach of a rigid triangle, the corner of that triangle
// nearest the point it grows from, whose layer the branch takes too (the rigid draw puts a vertex
// in the layer of its own depth), so the two move as one even where the leaf's own root lies across
// a slab's boundary, and every leaf hanging from that corner shares its layer; for the others their
// root vertex. Per leaf of `roots`.
// With `anchors` (per model vertex: render/rigid_flex.h rigidAnchors), the corner's anchor: the point
// whose depth picks the layer the rigid draw moves that corner with.
Status leafLayerRoots(const VegetationModel& model, const std::vector<uint8_t>& foliage, const LeafRoots& roots,
                      std::vector<glm::vec3>* out, const std::vector<gpu::LayerLeafRoot>* anchors = nullptr);

// The closest point of triangle (a, b, c) to p (Ericson, Real-Time Collision Detection 5.1.5).
glm::vec3 closestPointOnTriangle(const glm::vec3& p, const glm::vec3& a, const glm::vec3& b, const glm::vec3& c);

}  // namespace canopy
