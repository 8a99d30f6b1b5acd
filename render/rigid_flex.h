#pragma once
// How far each rigid vertex follows the foliage's displacement (docs/design.md "Rigid parts in
// wind"), found once per model. The paper draws trunks and branches as a still background; a real
// tree carries branches inside its crown, and those must move with the leaves they hold while the
// trunk's base stands. A rigid vertex of a plant follows fully from the crown's base up (the height
// most of the plant's leaves grow above) and not at all in the plant's foot band (render/plants.h
// kFootShare of its height), with a smoothstep between, so the trunk bends like a clamped beam: still and level at the ground, joining the
// crown's motion smoothly. Rigid parts of no plant with leaves (the ground, a rock) stay still.
//
// Which foliage layer a rigid vertex follows is decided by its anchor's depth, not its own: the
// mean of the rigid vertices within kAnchorShare of its plant's height of it, the middle
// of the wood around it, so the front and the back of a trunk, which lie on either side of a slab's
// boundary as often as not, follow one layer and the trunk is not torn across its thickness.
#include <cstdint>
#include <vector>

#include "engine/status.h"
#include "render/leaf_roots.h"
#include "render/model.h"
#include "shared/layers.h"

namespace canopy {

// The crown's base of a plant: this share of its leaves' roots lie below it (a few low leaves, a
// sprig at the trunk's foot, do not pull the crown down to the ground), or its lowest leaf that grows
// from the rigid parts (render/leaf_attach.h) if lower: the wood follows in full where leaves hang.
inline constexpr float kCrownBaseQuantile = 0.05f;
// A rigid vertex's anchor is the mean of the rigid vertices this share of its plant's height around
// it (render/plants.h plantSizeOfTriangles; the height, which turning a copy keeps).
inline constexpr float kAnchorShare = 0.07f;

// Per model vertex, 0 (still) .. LAYER_RIGID_FULL (follows the foliage) for the vertices of rigid
// triangles (the others LAYER_RIGID_FULL, unused). `trianglePlant`: per triangle its plant
// (findPlants), `foliage` per triangle, `roots` the leaves' roots. Up is the model's +y (glTF).
Status rigidFlexibility(const VegetationModel& model, const std::vector<uint8_t>& foliage, const LeafRoots& roots,
                        const std::vector<uint32_t>& trianglePlant, std::vector<uint16_t>* out);

// Per model vertex, a rigid vertex's root-table entry (shared/layers.h LAYER_CHUNK_RIGID): its
// anchor and its share (rigidFlexibility); the vertices of no rigid triangle get their own position.
Status rigidAnchors(const VegetationModel& model, const std::vector<uint8_t>& foliage, const LeafRoots& roots,
                    const std::vector<uint32_t>& trianglePlant, std::vector<gpu::LayerLeafRoot>* out);

}  // namespace canopy
