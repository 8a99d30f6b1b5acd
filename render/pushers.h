#pragma once
// Pushers (docs/design.md "Pushers"): the host's world-space spheres and capsules mapped onto the
// simulation plane every frame as motors of the fluid and sources of the bend field
// (shaders/shared/sim.h SimMotor), and the wind read back for the CPU (sampleCanopyWind).
#include <vector>

#include <canopy/canopy_params.h>

#include "engine/camera.h"
#include "engine/status.h"
#include "shaders/shared/sim.h"

namespace canopy {

// The default wind speed (WindParams.strength's default) a pusher's `bend` 1 stands for, domain units/s.
inline constexpr float kPusherBendUnit = 0.5f;

// The bend field's plane: the world's horizontal plane (glTF's +Y up), SIM_BEND_SCALE tiles a side
// centred under the simulation tile's centre, its first axis the plane's right made horizontal.
struct BendPlane {
  glm::vec3 origin{0.0f};  // world point at bend coordinate (0, 0); its y: the pushers' height (the layers' lookup)
  glm::vec3 x{1.0f, 0.0f, 0.0f}, z{0.0f, 0.0f, 1.0f};
  float tile = 1.0f;       // world units per tile unit (the simulation plane's tileSize)
};
BendPlane bendPlaneOf(const SimulationPlane& plane);

// Every pusher's fields (CanopyPusher's schema) and the count (at most kMaxPushers); the message
// names the pusher by index.
Status checkPushers(const std::vector<CanopyPusher>& pushers);

// What the last mapping did with the host's pushers.
struct PusherCounts {
  uint32_t mapped = 0;   // became motors of this step
  uint32_t outside = 0;  // their footprint misses the plane's bend domain (SIM_BEND_MIN .. + SIM_BEND_SCALE tiles)
  uint32_t behind = 0;   // wholly behind the camera
};
// One motor per pusher that can touch the vegetation: for the fluid its segment in plane
// coordinates (tile units) moved by whole tiles into the simulated tile (the plants read the field
// through fract()); for the bend field its segment on the ground plane (tile units).
// The height the layers look the bend field up at: the mean of the pushers' lower centres (y);
// `previous` when there are none (their trail springs back where they were).
float pusherHeight(const std::vector<CanopyPusher>& pushers, float previous);
void mapPushers(const std::vector<CanopyPusher>& pushers, const SimulationPlane& plane, const LayerView& camera,
                std::vector<gpu::SimMotor>* motors, PusherCounts* counts);

// The tiled wind (n*n vec2, domain units/s, row 0 at the bottom) at plane coordinates a (tile
// units): bilinear, periodic — what canopy_wind.glsl's canopyWindAt computes.
glm::vec2 sampleTiledWind(const float* field, uint32_t n, glm::vec2 a);
// The world vector of the wind at `p` through `plane` (the field is the same on every plane
// parallel to it; no component along its normal).
glm::vec3 windAtWorld(const float* field, uint32_t n, const SimulationPlane& plane, glm::vec3 p);

}  // namespace canopy
