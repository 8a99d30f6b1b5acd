// The wind in the world (issue 66; docs/design.md "World wind"): the plane is the wind's and no
// camera's, a change eases in without a pop, the simulation's inflow is the wind's speed in domain
// units/s, and eq. 6's shrink along the view is bounded by a share of the height above the root.
#include <gtest/gtest.h>

#include <cmath>

#include "compute/dynamics.h"
#include "render/world_wind.h"
#include "shaders/shared/anim.h"

using namespace canopy;

namespace {
float angleBetween(glm::vec3 a, glm::vec3 b) { return std::acos(std::clamp(glm::dot(glm::normalize(a), glm::normalize(b)), -1.0f, 1.0f)); }
}  // namespace

TEST(WorldWind, ThePlaneIsTheWindsHorizontalAndSpansTheVegetation) {
  WorldWind w;
  const glm::vec3 lo(-0.4f, 0.0f, -0.3f), hi(0.4f, 1.0f, 0.3f);  // a 1 m shrub
  for (const glm::vec3 d : {glm::vec3(1, 0, 0), glm::vec3(0, 0, -1), glm::vec3(3, 0, 4)}) {
    const SimulationPlane p = worldWindPlane(w, glm::normalize(d), lo, hi);
    EXPECT_LT(angleBetween(toGlm(p.right), d), 1e-5f);
    EXPECT_NEAR(glm::dot(toGlm(p.up), glm::vec3(0, 1, 0)), 0.0f, 1e-6f) << "the plane's y axis is horizontal";
    EXPECT_NEAR(std::abs(glm::cross(toGlm(p.right), toGlm(p.up)).y), 1.0f, 1e-5f) << "a horizontal wind: the ground plane";
    EXPECT_FLOAT_EQ(p.tileSize, 4.0f) << "at least tileMetres";
    // Centred on the vegetation: its centre maps to the tile's middle.
    const glm::vec3 rel = 0.5f * (lo + hi) - toGlm(p.origin);
    EXPECT_NEAR(glm::dot(rel, toGlm(p.right)) / p.tileSize, 0.5f, 1e-5f);
    EXPECT_NEAR(glm::dot(rel, toGlm(p.up)) / p.tileSize, 0.5f, 1e-5f);
  }
  // A field wider than tileMetres: one tile over it; a world in centimetres: tileMetres in its units.
  EXPECT_FLOAT_EQ(worldWindPlane(w, glm::vec3(1, 0, 0), glm::vec3(-6, 0, -4), glm::vec3(6, 2, 4)).tileSize, 12.0f);
  w.unitsPerMetre = 100.0f;
  EXPECT_FLOAT_EQ(worldWindPlane(w, glm::vec3(1, 0, 0), 100.0f * lo, 100.0f * hi).tileSize, 400.0f);
  // The inflow: from the plane's left (toward +x, the wind), the wind's speed in tiles/s.
  const SimulationParams sp = worldWindSimulation(SimulationParams{}, w, worldWindPlane(w, glm::vec3(1, 0, 0), 100.0f * lo, 100.0f * hi), 3.0f);
  EXPECT_EQ(sp.wind.sides, uint32_t(kWindFromLeft));
  EXPECT_FLOAT_EQ(sp.wind.strength, 3.0f * 100.0f / 400.0f);
  EXPECT_FLOAT_EQ(sp.wind.modulation, w.gustIntensity);
  EXPECT_FLOAT_EQ(sp.wind.frequency, w.gustFrequency);
  EXPECT_FLOAT_EQ(sp.wind.gust, w.turbulence);
  EXPECT_FLOAT_EQ(sp.wind.baseline, 1.0f);
}

TEST(WorldWind, AChangeEasesInFromWhereTheWindStandsWithoutAPop) {
  WorldWindState s;
  WorldWind w;  // +X, 3 m/s, 2 s
  const float dt = 1.0f / 30.0f;
  stepWorldWind(s, w, dt);
  EXPECT_LT(angleBetween(s.direction, glm::vec3(1, 0, 0)), 1e-6f) << "the first wind at once";
  EXPECT_FLOAT_EQ(s.speed, 3.0f);
  w.direction = {0.0f, 0.0f, 5.0f};
  w.speed = 9.0f;
  // Smoothstep over 2 s: the fastest turn is 1.5 x (pi/2) / 2 rad/s, 0.039 rad a frame.
  glm::vec3 last = s.direction;
  float lastSpeed = s.speed, worst = 0.0f;
  for (int i = 1; i <= 60; ++i) {
    stepWorldWind(s, w, dt);
    worst = std::max(worst, angleBetween(last, s.direction));
    EXPECT_LE(std::abs(s.speed - lastSpeed), 1.5f * 6.0f / 2.0f * dt + 1e-4f);
    EXPECT_NEAR(s.direction.y, 0.0f, 1e-5f) << "turns about the vertical";
    last = s.direction;
    lastSpeed = s.speed;
    if (i == 30) {
      EXPECT_NEAR(angleBetween(s.direction, glm::vec3(1, 0, 0)), glm::radians(45.0f), glm::radians(1.0f)) << "half way at half time";
      EXPECT_NEAR(s.speed, 6.0f, 0.05f);
    }
  }
  EXPECT_LE(worst, 0.040f);
  EXPECT_LT(angleBetween(s.direction, glm::vec3(0, 0, 1)), 1e-4f) << "there after easeSeconds";
  EXPECT_FLOAT_EQ(s.speed, 9.0f);
  // Reversed mid-ease: it goes on from where it stands (no jump), about the vertical.
  w.direction = {-1.0f, 0.0f, 0.0f};
  for (int i = 0; i < 15; ++i) stepWorldWind(s, w, dt);
  const glm::vec3 mid = s.direction;
  w.direction = {0.0f, 0.0f, -1.0f};
  stepWorldWind(s, w, dt);
  EXPECT_LE(angleBetween(mid, s.direction), 0.040f);
  for (int i = 0; i < 90; ++i) stepWorldWind(s, w, dt);
  EXPECT_LT(angleBetween(s.direction, glm::vec3(0, 0, -1)), 1e-4f);
  // easeSeconds 0: at once.
  w.easeSeconds = 0.0f;
  w.direction = {1.0f, 0.0f, 0.0f};
  stepWorldWind(s, w, dt);
  EXPECT_LT(angleBetween(s.direction, glm::vec3(1, 0, 0)), 1e-5f);
}

// Seen along the wind, V is nearly all V_z: the paper's lambda_z |V_z| would pull a crown's top
// down by more than the crown; it is bounded by maxShrink of the height above the root.
TEST(WorldWind, TheShrinkAlongTheViewIsBoundedByAShareOfTheHeightAboveTheRoot) {
  gpu::AnimFrame f{};
  f.lambda = glm::vec4(300.0f, 300.0f, 150.0f, 1.0f / 30.0f);
  f.rigidity = 1.0f;
  f.maxShrink = 0.05f;
  gpu::AnimLayer layer{};
  layer.attenuation = 1.0f;
  layer.rootLineY = 200.0f;
  layer.height = 100.0f;
  for (float y : {100.0f, 150.0f, 190.0f, 200.0f, 230.0f}) {
    const float l = std::max(layer.rootLineY - y, 0.0f);
    const glm::vec2 d = gpu::displacementPixels(f, layer, y, glm::vec3(0.0f, 0.0f, 50.0f));
    EXPECT_NEAR(d.x, 0.0f, 1e-6f);
    EXPECT_LE(d.y, 0.05f * l + 1e-4f) << "row " << y;  // y down: the shrink pulls the top down
    EXPECT_GE(d.y, 0.0f);
  }
  // A small V_z stays the paper's term: (l/h) lambda_z |V_z| dt.
  const glm::vec2 small = gpu::displacementPixels(f, layer, 100.0f, glm::vec3(0.0f, 0.0f, 0.1f));
  EXPECT_NEAR(small.y, 1.0f * 150.0f * 0.1f / 30.0f, 1e-4f);
  // World wind: eq. 6 times the plant's height (a plant twice as tall on screen moves twice as far).
  f.heightRelative = 1u;
  f.lambda = glm::vec4(0.9f, 0.9f, 0.45f, 1.0f / 30.0f);
  // ...and the shrink is the lean's own foreshortening: a corner l above its root leaning e along
  // the view (the lean it shows seen across, k lambda_x |V_z|) shows l - sqrt(l^2 - e^2) shorter,
  // well under the paper's linear k lambda_z |V_z| for a breeze's lean.
  for (float vz : {0.3f, 1.0f, 2.0f}) {
    const float l = layer.rootLineY - 100.0f;
    const float k = (l / layer.height) * layer.height * f.lambda.w;  // R = l/h (rigidity 1), times h
    const float e = k * f.lambda.x * vz;
    const float want = std::min(l - std::sqrt(std::max(l * l - e * e, 0.0f)), 0.05f * l);
    const glm::vec2 d = gpu::displacementPixels(f, layer, 100.0f, glm::vec3(0.0f, 0.0f, vz));
    EXPECT_NEAR(d.y, want, 1e-3f * l) << "V_z " << vz;
    EXPECT_LT(d.y, k * f.lambda.z * vz) << "V_z " << vz << ": less than the paper's linear shrink";
  }
  const float a = gpu::displacementPixels(f, layer, 100.0f, glm::vec3(1.0f, 0.0f, 0.0f)).x;
  layer.height = 200.0f;
  layer.rootLineY = 300.0f;
  const float b = gpu::displacementPixels(f, layer, 100.0f, glm::vec3(1.0f, 0.0f, 0.0f)).x;
  EXPECT_NEAR(b, 2.0f * a, 1e-4f);
}
