#pragma once
// The wind in the world (docs/design.md "World wind"): CanopyParams.wind eased toward its latest
// value, the simulation plane it defines (horizontal through the vegetation, its x axis along the
// wind, fixed in the world) and the simulation's inflow derived from it.
#include <canopy/canopy_params.h>

#include "engine/camera.h"

namespace canopy {

// The wind as it stands while a change eases in: from where it stood when the change was given to
// the target, along the shortest arc, with a smoothstep in time over the target's easeSeconds.
struct WorldWindState {
  bool started = false;
  WorldWind target;
  glm::vec3 fromDirection{1.0f, 0.0f, 0.0f}, toDirection{1.0f, 0.0f, 0.0f}, direction{1.0f, 0.0f, 0.0f};
  float fromSpeed = 0.0f, speed = 0.0f;  // m/s
  float elapsed = 0.0f;                  // s since the change
};

// A unit direction from a host's vector (the world's +X when it has no length).
glm::vec3 windDirectionOf(const Float3& v);
// Takes `target` (a change restarts the ease from where the wind stands; the first call starts
// there at once), then advances the ease by dt seconds.
void stepWorldWind(WorldWindState& s, const WorldWind& target, float dt);
// The simulation plane of a wind blowing along `direction` over vegetation within [boundsMin,
// boundsMax]: centred on the bounds' centre, right = the direction, up = the horizontal across it
// (a horizontal wind: the ground plane), one tile over the vegetation's horizontal extent and at
// least tileMetres * unitsPerMetre a side.
SimulationPlane worldWindPlane(const WorldWind& wind, const glm::vec3& direction, const glm::vec3& boundsMin, const glm::vec3& boundsMax);
// `base` with the inflow of the wind as it stands: from the plane's left side (toward its +x, the
// wind's direction) at speed * unitsPerMetre / tileSize domain units/s (the field's patterns travel
// at the wind's speed), swelling by gustIntensity at gustFrequency, noise by turbulence
// (WindParams' speed profile; its gustScale, gustSpeed and seed kept).
SimulationParams worldWindSimulation(const SimulationParams& base, const WorldWind& wind, const SimulationPlane& plane, float speed);

}  // namespace canopy
