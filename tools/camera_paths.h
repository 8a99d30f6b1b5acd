#pragma once
// The camera paths of canopy-demo and canopy-bench (docs/design.md "Moving camera: paths and the
// world-lock measure"): the ways a game's camera moves past vegetation, each a pure function of the
// frame number, so the same path can be rendered twice (re-sliced every frame as the reference, and
// by the re-slicing policy) and compared frame by frame.
#include <cstdint>
#include <string>

#include <glm/glm.hpp>

#include "engine/camera.h"
#include "engine/status.h"

namespace canopy {

enum class CameraMotion {
  Still,   // the start view, every frame
  Orbit,   // around the vegetation's centre: yaw by degreesPerFrame
  Dolly,   // towards the centre by radiiPerFrame, back when 1.2 radii away (a ping-pong)
  Strafe,  // sideways along the view's right axis by radiiPerFrame, within ±1 radius (ping-pong)
  Turn,    // a pure rotation: the eye stays, the view turns by degreesPerFrame within ±amplitudeDegrees
  Zoom,    // the field of view changes by degreesPerFrame within ±amplitudeDegrees of the start
  Walk,    // first person: eye height, forward by radiiPerFrame, looking around within ±amplitudeDegrees
};

// "still", "orbit", "dolly", "strafe", "turn", "zoom", "walk"; the error lists them.
Status parseCameraMotion(const std::string& name, CameraMotion* out);
const char* cameraMotionName(CameraMotion m);

struct CameraPath {
  CameraMotion motion = CameraMotion::Still;
  float degreesPerFrame = 0.25f;  // orbit and turn: yaw; zoom: field of view; walk: looking around
  float radiiPerFrame = 0.005f;   // dolly, strafe, walk: the vegetation's bounding radius per frame
  float amplitudeDegrees = 5.0f;  // turn, zoom, walk: the swing either side of the start
  // The start view (orbitView's parameters): yaw and pitch in degrees, vertical field of view in
  // degrees, distance as a multiple of the one that fits the bounding sphere.
  float yaw = 20.0f, pitch = 10.0f, fovY = 40.0f, distanceScale = 0.8f;
};

// The view at `frame` (0 = the start view) for vegetation in the box [bmin, bmax].
LayerView cameraPathView(const CameraPath& path, const glm::vec3& bmin, const glm::vec3& bmax, float aspect, uint32_t frame);

// A triangle wave of amplitude `a` that starts at 0 rising with slope `rate` per unit of t
// (0, a, 0, -a, 0, ...): the swing of the ping-pong paths. a <= 0: t * rate.
float pingPong(float t, float rate, float a);

}  // namespace canopy
