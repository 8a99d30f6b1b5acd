// The camera paths of the demo and the benchmark (tools/camera_paths.h): each moves the way its
// name says and no other way, starts at the still view, and stays within its stated swing.
#include <cmath>

#include <glm/glm.hpp>
#include <gtest/gtest.h>

#include "tools/camera_paths.h"

namespace canopy {
namespace {

const glm::vec3 kMin(-1.0f, 0.0f, -1.0f), kMax(1.0f, 2.0f, 1.0f);
const glm::vec3 kCentre = 0.5f * (kMin + kMax);

LayerView at(CameraMotion m, uint32_t frame, float degrees = 0.25f, float radii = 0.005f) {
  CameraPath p;
  p.motion = m;
  p.degreesPerFrame = degrees;
  p.radiiPerFrame = radii;
  return cameraPathView(p, kMin, kMax, 4.0f / 3.0f, frame);
}

// Angle between two directions (atan2 of |a x b| and a . b, in double: acos loses precision near 0).
float angleDegrees(const glm::vec3& a, const glm::vec3& b) {
  const glm::dvec3 x(a), y(b);
  return float(glm::degrees(std::atan2(glm::length(glm::cross(x, y)), glm::dot(x, y))));
}
// Angle between two gazes at the same pitch whose yaws differ by `yaw` degrees.
float gazeAngle(float yaw, float pitch) {
  const double p = glm::radians(double(pitch)), c = std::cos(p) * std::cos(p) * std::cos(glm::radians(double(yaw))) +
                                                   std::sin(p) * std::sin(p);
  return float(glm::degrees(std::acos(std::clamp(c, -1.0, 1.0))));
}

TEST(CameraPaths, EveryPathStartsAtTheStillViewAndNamesParse) {
  const LayerView still = at(CameraMotion::Still, 0);
  const LayerView orbit = orbitView(kMin, kMax, 20.0f, 10.0f, 40.0f, 4.0f / 3.0f, 0.8f);
  for (int c = 0; c < 4; ++c)
    for (int r = 0; r < 4; ++r) {
      EXPECT_NEAR(still.view[c][r], orbit.view[c][r], 1e-5f);
      EXPECT_NEAR(still.proj[c][r], orbit.proj[c][r], 1e-5f);
    }
  for (CameraMotion m : {CameraMotion::Orbit, CameraMotion::Dolly, CameraMotion::Strafe, CameraMotion::Turn, CameraMotion::Zoom}) {
    const LayerView v = at(m, 0);
    EXPECT_LT(glm::length(viewPosition(v.view) - viewPosition(still.view)), 1e-4f) << cameraMotionName(m);
    EXPECT_LT(angleDegrees(viewForward(v.view), viewForward(still.view)), 0.01f) << cameraMotionName(m);
    CameraMotion back;
    ASSERT_TRUE(parseCameraMotion(cameraMotionName(m), &back).ok());
    EXPECT_EQ(back, m);
  }
  CameraMotion m;
  const Status s = parseCameraMotion("spin", &m);
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.message().find("'spin' is not one of still, orbit, dolly, strafe, turn, zoom, walk"), std::string::npos)
      << s.message();
}

TEST(CameraPaths, EachPathMovesAsItsNameSays) {
  const LayerView s = at(CameraMotion::Still, 0);
  const glm::vec3 eye0 = viewPosition(s.view);
  const float d0 = glm::length(eye0 - kCentre);
  // Orbit: same distance, looking at the centre, turned by 0.25 degrees a frame.
  const LayerView o = at(CameraMotion::Orbit, 40);
  EXPECT_NEAR(glm::length(viewPosition(o.view) - kCentre), d0, 1e-4f * d0);
  EXPECT_NEAR(angleDegrees(eye0 - kCentre, viewPosition(o.view) - kCentre), gazeAngle(10.0f, 10.0f), 0.01f);
  // Turn: a pure rotation (the eye stays), 0.25 degrees a frame up to the 5 degree swing, then back.
  for (uint32_t f : {4u, 20u, 40u, 60u}) {
    const LayerView t = at(CameraMotion::Turn, f);
    EXPECT_LT(glm::length(viewPosition(t.view) - eye0), 1e-4f * d0) << f;
    const float expected = f <= 20 ? 0.25f * float(f) : (f <= 60 ? 10.0f - 0.25f * float(f) : 0.0f);
    EXPECT_NEAR(angleDegrees(viewForward(t.view), viewForward(s.view)), gazeAngle(expected, 10.0f), 0.01f) << f;
    EXPECT_EQ(t.proj, s.proj) << f;
  }
  // Dolly: along the line to the centre, closer by 0.005 radii a frame, never nearer than 1.2 radii.
  const float radius = 0.5f * glm::length(kMax - kMin);
  const LayerView d = at(CameraMotion::Dolly, 30);
  EXPECT_NEAR(glm::length(viewPosition(d.view) - kCentre), d0 - 30 * 0.005f * radius, 1e-3f * d0);
  EXPECT_LT(angleDegrees(viewPosition(d.view) - kCentre, eye0 - kCentre), 0.01f);
  for (uint32_t f = 0; f < 4000; f += 97)
    EXPECT_GE(glm::length(viewPosition(at(CameraMotion::Dolly, f, 0.25f, 0.05f).view) - kCentre), 1.2f * radius - 1e-4f);
  // Strafe: the eye moves along the view's right axis; the gaze keeps its direction.
  const LayerView st = at(CameraMotion::Strafe, 50);
  const glm::vec3 moved = viewPosition(st.view) - eye0;
  EXPECT_NEAR(glm::length(moved), 50 * 0.005f * radius, 1e-3f * radius);
  EXPECT_NEAR(glm::dot(glm::normalize(moved), viewForward(s.view)), 0.0f, 1e-4f);
  EXPECT_LT(angleDegrees(viewForward(st.view), viewForward(s.view)), 0.01f);
  // Zoom: only the field of view changes (the projection's y scale is cot(fov / 2)).
  const LayerView z = at(CameraMotion::Zoom, 8);
  EXPECT_EQ(z.view, s.view);
  EXPECT_NEAR(2.0f * glm::degrees(std::atan(1.0f / std::fabs(z.proj[1][1]))), 42.0f, 1e-3f);
}

TEST(CameraPaths, WalkCrossesTheBoxAtEyeHeight) {
  for (uint32_t f = 0; f < 2000; f += 50) {
    const glm::vec3 eye = viewPosition(at(CameraMotion::Walk, f, 0.5f, 0.01f).view);
    EXPECT_NEAR(eye.y, kMin.y + (kMax.y - kMin.y) / 6.0f, 1e-4f);
    EXPECT_GE(eye.z, kMin.z - 1e-4f);
    EXPECT_LE(eye.z, kMax.z + 1e-4f);
  }
  EXPECT_LT(viewPosition(at(CameraMotion::Walk, 10, 0.5f, 0.01f).view).z, kMax.z);
}

TEST(CameraPaths, PingPongIsATriangleWave) {
  EXPECT_FLOAT_EQ(pingPong(0, 1, 5), 0);
  EXPECT_FLOAT_EQ(pingPong(3, 1, 5), 3);
  EXPECT_FLOAT_EQ(pingPong(7, 1, 5), 3);
  EXPECT_FLOAT_EQ(pingPong(13, 1, 5), -3);
  EXPECT_FLOAT_EQ(pingPong(20, 1, 5), 0);
  EXPECT_FLOAT_EQ(pingPong(4, 2, 0), 8);
}

}  // namespace
}  // namespace canopy
