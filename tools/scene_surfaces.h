#pragma once
// The generated scenes' surfaces (tools/scene_generator.cpp): their materials (bark, leaves, grass,
// ground, kelp and rock, the foliage ones alpha-masked with a procedural texture drawn here) and the
// rigid geometry appended straight to the model (branches, ground, rocks).
#include <cstdint>

#include <glm/glm.hpp>

#include "render/model.h"

namespace canopy::scenegen {

enum MaterialSlot : uint32_t { kBark, kLeaf, kGrass, kGround, kKelpStem, kKelpBlade, kRock, kSlotCount };

// The slots above (and the loader's default material last), textures `textureSize` texels square.
void setMaterials(VegetationModel& m, uint32_t textureSize, uint64_t seed);
// Drops the materials (and images) no triangle uses, renumbering the rest.
void compactMaterials(VegetationModel& m);
// A value in [0, 1) per (x, y, seed), the same on every machine.
float hashNoise(uint32_t x, uint32_t y, uint64_t seed);

void pushVertex(VegetationModel& m, const glm::vec3& p, const glm::vec3& n, const glm::vec2& uv);
// Two triangles a b c, c d a of `material`.
void pushQuad(VegetationModel& m, uint32_t material, uint32_t a, uint32_t b, uint32_t c, uint32_t d);
// A truncated cone from a (radius ra) to b (radius rb) around the frame (side0, side1): 2 `sides`
// triangles, no caps (the ends are hidden in the parent branch or under the leaves).
void addCylinder(VegetationModel& m, uint32_t material, const glm::vec3& a, const glm::vec3& b, float ra, float rb,
                 const glm::vec3& side0, const glm::vec3& side1, uint32_t sides);
// A ground grid of n x n cells over [lo, hi] at height y, facing up.
void addGround(VegetationModel& m, uint32_t material, glm::vec2 lo, glm::vec2 hi, float y, uint32_t n);
// A lumpy dome (the kelp's rock): `rings` x `sides` quads.
void addRock(VegetationModel& m, uint32_t material, const glm::vec3& c, float radius, uint32_t rings, uint32_t sides,
             uint64_t seed);

}  // namespace canopy::scenegen
