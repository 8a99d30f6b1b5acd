#include "tools/scene_generator.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <new>
#include <thread>

#include "engine/hash.h"
#include "tools/scene_surfaces.h"

namespace canopy {
namespace {

using namespace scenegen;

constexpr float kPi = 3.14159265358979f;

// splitmix64: one independent stream per leaf, so the output does not depend on the thread count.
struct Rng {
  uint64_t s;
  explicit Rng(uint64_t seed) : s(seed) {}
  uint64_t next() {
    uint64_t z = (s += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
  }
  float uniform() { return float(next() >> 40) * (1.0f / 16777216.0f); }  // [0, 1)
  float range(float a, float b) { return a + (b - a) * uniform(); }
  glm::vec3 inBall() {
    for (;;) {
      const glm::vec3 p(range(-1, 1), range(-1, 1), range(-1, 1));
      if (glm::dot(p, p) <= 1.0f) return p;
    }
  }
  glm::vec3 onSphere() {
    for (;;) {
      const glm::vec3 p = inBall();
      const float l = glm::length(p);
      if (l > 1e-3f) return p / l;
    }
  }
};

glm::vec3 rotateAbout(const glm::vec3& v, const glm::vec3& axis, float angle) {
  const float c = std::cos(angle), s = std::sin(angle);
  return v * c + glm::cross(axis, v) * s + axis * glm::dot(axis, v) * (1.0f - c);
}

glm::vec3 anyPerpendicular(const glm::vec3& v) {
  const glm::vec3 a = std::abs(v.y) < 0.9f ? glm::vec3(0, 1, 0) : glm::vec3(1, 0, 0);
  return glm::normalize(glm::cross(v, a));
}

// ---------------------------------------------------------------------------------------------
// Foliage batches: planned first (counts, sizes, attachment points), written in parallel later.

enum class LeafShape : uint8_t { Card, Blade, Ribbon };
constexpr uint32_t kBladeSegments = 3, kRibbonSegments = 6;

uint32_t verticesPerLeaf(LeafShape s) {
  return s == LeafShape::Card ? 4 : 2 * ((s == LeafShape::Blade ? kBladeSegments : kRibbonSegments) + 1);
}
uint32_t facesPerLeaf(LeafShape s) {
  return s == LeafShape::Card ? 2 : 2 * (s == LeafShape::Blade ? kBladeSegments : kRibbonSegments);
}

struct Attach {
  glm::vec3 pos, dir;
  float size;  // local scale: the length of the internode it sits on
  // Where it sits in the branch hierarchy (per-vertex baseline): the L-system branch and the arc
  // length along it; BEND_LEAF_ONLY where there is none (kelp stems).
  uint32_t branch = BEND_LEAF_ONLY;
  float arc = 0.0f;
  gpu::BendVertex bend{BEND_LEAF_ONLY, 0};  // filled by finishHierarchy
  uint32_t box = 0;  // the innermost box open where it was attached (SceneDesc::boxes)
};

// The branch hierarchy the turtle builds (shared/bend.h; docs/design.md "Per-vertex wind
// baseline"): each PUSH that starts a branch at bracket depth < BEND_LEVELS opens a table branch;
// deeper brackets stay part of their depth-3 branch, carried at the arc where they leave it.
struct BranchBuild {
  glm::vec3 origin{0.0f}, tip{0.0f}, dir0{0.0f, 1.0f, 0.0f};
  float length = 0.0f;     // arc length drawn along it (turtle units)
  float attachArc = 0.0f;  // arc along the parent where it starts
  uint32_t parent = BEND_NO_PARENT, level = 0;
};
// Two rings of a cylinder: `ringVertices` vertices at arc0, then as many at arc1, on `branch`.
struct RigidRun {
  uint32_t firstVertex, ringVertices, branch;
  float arc0, arc1;
};
struct HierarchyBuild {
  std::vector<BranchBuild> branches;
  std::vector<RigidRun> runs;
};

struct LeafBatch {
  LeafShape shape = LeafShape::Card;
  uint32_t material = 0;
  std::vector<Attach> attach;  // Card, Ribbon
  glm::vec3 centre{0.0f};      // Card: crown centre (leaves face outward)
  float spread = 1.0f;         // Card: cluster radius in units of Attach::size
  float length = 0, width = 0; // leaf size, world units
  glm::vec2 lo{0}, hi{0};      // Blade: root area (x, z)
  float ground = 0;            // Blade: root height
  glm::vec3 flow{1, 0, 0};     // Ribbon: the current's direction
  uint64_t count = 0, seed = 0;
  uint64_t firstVertex = 0, firstIndex = 0, firstTriangle = 0;
  uint32_t box = 0;            // Blade, Ribbon: the batch's box (SceneDesc::boxes)
  uint32_t plant = kNoPlant;   // VegetationModel::trianglePlant of its leaves
};

struct Plan {
  VegetationModel model;  // materials + rigid geometry
  std::vector<LeafBatch> batches;
  HierarchyBuild hierarchy;
  std::vector<uint32_t> boxParent{0xffffffffu};  // box 0: the scene
  SceneStats stats;
  std::vector<uint32_t> rigidPlant;  // plant of each rigid triangle so far (VegetationModel::trianglePlant)
};

// The rigid triangles added since the last call belong to `plant` (kNoPlant: the ground, a rock).
void markRigid(Plan& p, uint32_t plant) { p.rigidPlant.resize(p.model.triangleMaterial.size(), plant); }

// ---------------------------------------------------------------------------------------------
// L-system: bracketed string rewriting, then a 3D turtle (ABOP chapter 1.5 symbols).
//   F draw an internode   T draw a trunk segment (never rewritten)   L leaf cluster here
//   + - yaw   & ^ pitch   / \ roll   [ PUSH (branch level + 1)   ] POP
struct LSystem {
  std::string axiom;
  std::string rules[128];
};

// One rewriting step: every symbol with a production is replaced, the others are kept.
std::string rewrite(const LSystem& ls, const std::string& s) {
  std::string next;
  next.reserve(s.size() * 3);
  for (char c : s) {
    const std::string& r = ls.rules[uint8_t(c) & 127];
    if (r.empty()) next += c;
    else next += r;
  }
  return next;
}

// A branching bush (after ABOP Figure 1.25): each apex A splits into three branches rolled
// around the parent by 112.5 and 157.5 degrees, each an internode F carrying a leaf cluster L.
// ABOP's internode elongation (F -> S/////F) is left out: it makes the oldest stems bare and
// very long, where a dense shrub or crown wants its foliage spread through the whole volume.
LSystem bushSystem(const char* axiom) {
  LSystem ls;
  ls.axiom = axiom;
  ls.rules[uint8_t('A')] = "[&FLA]/////[&FLA]///////[&FLA]";
  return ls;
}

struct PlantShape {
  float angle = 22.5f;        // degrees per + - & ^ / \ (jittered by +-jitter)
  float jitter = 0.25f;
  float length = 0.25f;       // internode at level 0, world units
  float lengthDecay = 0.85f;  // per branch level
  float radius = 0.03f;       // at level 0
  float radiusDecay = 0.62f;
  float trunkLength = 0.0f, trunkRadius = 0.0f;  // T segments
  float tropism = 0.12f;      // upward bend per internode
  uint32_t leafMinLevel = 1;  // leaf clusters only on branches this deep or deeper
  uint32_t sides = 5;
};

struct Placement {
  glm::vec3 origin{0.0f};
  float scale = 1.0f, yaw = 0.0f;
  glm::vec3 apply(const glm::vec3& p) const {
    const float c = std::cos(yaw), s = std::sin(yaw);
    return origin + scale * glm::vec3(c * p.x + s * p.z, p.y, -s * p.x + c * p.z);
  }
  glm::vec3 direction(const glm::vec3& d) const {
    const float c = std::cos(yaw), s = std::sin(yaw);
    return glm::vec3(c * d.x + s * d.z, d.y, -s * d.x + c * d.z);
  }
};

uint64_t countDrawn(const std::string& s, uint32_t* trunk) {
  uint64_t f = 0;
  *trunk = 0;
  for (char c : s) {
    f += c == 'F';
    *trunk += c == 'T';
  }
  return f;
}

// Picks the deepest derivation (at most 7 steps) whose wood stays within `rigidBudget` faces.
std::string deriveWithin(const LSystem& ls, uint64_t rigidBudget, PlantShape* shape, uint32_t* iterations) {
  std::string best = rewrite(ls, ls.axiom);
  *iterations = 1;
  uint32_t trunk = 0;
  for (uint32_t n = 2; n <= 7; ++n) {
    std::string s = rewrite(ls, best);
    if ((countDrawn(s, &trunk) + trunk) * 2 * shape->sides > rigidBudget) break;
    best.swap(s);
    *iterations = n;
  }
  if ((countDrawn(best, &trunk) + trunk) * 2 * shape->sides > rigidBudget) shape->sides = 3;
  return best;
}

struct TurtleState {
  glm::vec3 pos, h, l, u;
  uint32_t level;
  uint32_t branch = 0;  // table branch (HierarchyBuild) the turtle draws on
  float arc = 0.0f;     // arc length along it
  bool deep = false;    // past BEND_LEVELS: the arc stays where this subtree leaves `branch`
};

// Interprets `s`: wood into the model, leaf clusters into `attach`.
void interpret(const std::string& s, const PlantShape& shape, const Placement& place, uint64_t seed, VegetationModel& m,
               std::vector<Attach>& attach, HierarchyBuild& hier, std::vector<uint32_t>& boxParent, uint64_t* pushes) {
  Rng rng(seed);
  // Lluch et al. section 3: the plant's box, then a box per PUSH under the innermost open one.
  boxParent.push_back(0);
  std::vector<uint32_t> openBoxes{uint32_t(boxParent.size() - 1)};
  TurtleState t{glm::vec3(0.0f), {0, 1, 0}, {-1, 0, 0}, {0, 0, 1}, 0};
  auto openBranch = [&](uint32_t parent, uint32_t level, float attachArc) {
    BranchBuild b;
    b.origin = b.tip = place.apply(t.pos);
    b.dir0 = place.direction(t.h);
    b.parent = parent;
    b.level = level;
    b.attachArc = attachArc;
    hier.branches.push_back(b);
    return uint32_t(hier.branches.size() - 1);
  };
  t.branch = openBranch(BEND_NO_PARENT, 0, 0.0f);  // the trunk (zero length for plants without T)
  std::vector<TurtleState> stack;
  const float delta = shape.angle * kPi / 180.0f;
  auto turn = [&](glm::vec3& a, glm::vec3& b, const glm::vec3& axis, float sign) {
    const float ang = sign * delta * (1.0f + shape.jitter * rng.range(-1, 1));
    a = rotateAbout(a, axis, ang);
    b = rotateAbout(b, axis, ang);
  };
  for (char c : s) {
    switch (c) {
      case 'F':
      case 'T': {
        const bool trunk = c == 'T';
        const float len = trunk ? shape.trunkLength : shape.length * std::pow(shape.lengthDecay, float(t.level)) *
                                                          rng.range(0.85f, 1.15f);
        const float r0 = trunk ? shape.trunkRadius : shape.radius * std::pow(shape.radiusDecay, float(t.level));
        const float r1 = trunk ? r0 * 0.95f : r0 * 0.85f;
        const glm::vec3 end = t.pos + t.h * len;
        const uint32_t first = uint32_t(m.positions.size());
        addCylinder(m, kBark, place.apply(t.pos), place.apply(end), r0 * place.scale, r1 * place.scale,
                    place.direction(t.l), place.direction(t.u), shape.sides);
        const float a1 = t.deep ? t.arc : t.arc + len;
        hier.runs.push_back({first, shape.sides + 1, t.branch, t.arc, a1});
        if (!t.deep) {
          t.arc = a1;
          BranchBuild& b = hier.branches[t.branch];
          if (a1 >= b.length) {
            b.length = a1;
            b.tip = place.apply(end);
          }
        }
        t.pos = end;
        if (!trunk && shape.tropism > 0) {  // bend toward +Y, keep the frame orthonormal
          const glm::vec3 h = glm::normalize(t.h + shape.tropism * glm::vec3(0, 1, 0));
          if (glm::length(glm::cross(h, t.l)) > 1e-3f) {
            t.h = h;
            t.l = glm::normalize(t.l - glm::dot(t.l, h) * h);
            t.u = glm::cross(t.h, t.l);
          }
        }
        break;
      }
      case 'L':
      case 'A':
        if (t.level >= shape.leafMinLevel)
          attach.push_back({place.apply(t.pos), place.direction(t.h),
                            shape.length * std::pow(shape.lengthDecay, float(t.level)) * place.scale, t.branch, t.arc,
                            gpu::BendVertex{BEND_LEAF_ONLY, 0}, openBoxes.back()});
        break;
      case '+': turn(t.h, t.l, t.u, 1.0f); break;
      case '-': turn(t.h, t.l, t.u, -1.0f); break;
      case '&': turn(t.h, t.u, t.l, 1.0f); break;
      case '^': turn(t.h, t.u, t.l, -1.0f); break;
      case '/': turn(t.l, t.u, t.h, 1.0f); break;
      case '\\': turn(t.l, t.u, t.h, -1.0f); break;
      case '[':
        stack.push_back(t);
        t.level++;
        boxParent.push_back(openBoxes.back());
        openBoxes.push_back(uint32_t(boxParent.size() - 1));
        ++*pushes;
        if (!t.deep && t.level < BEND_LEVELS) {
          t.branch = openBranch(t.branch, t.level, t.arc);
          t.arc = 0.0f;
        } else {
          t.deep = true;
        }
        break;
      case ']':
        if (!stack.empty()) {
          t = stack.back();
          stack.pop_back();
          openBoxes.pop_back();
        }
        break;
      default: break;
    }
  }
}

// Leaf size for `count` cards over the clusters: the leaves' total area is `coverage` times the
// crown's cross-section (depth complexity ~coverage), whatever the count.
void sizeCards(LeafBatch& b, float coverage, float aspect) {
  glm::vec3 lo(1e30f), hi(-1e30f);
  for (const Attach& a : b.attach) {
    lo = glm::min(lo, a.pos);
    hi = glm::max(hi, a.pos);
  }
  b.centre = 0.5f * (lo + hi);
  float r = 0.0f;
  for (const Attach& a : b.attach) r = std::max(r, glm::length(a.pos - b.centre) + a.size * b.spread);
  r = std::max(r, 1e-3f);
  const float area = coverage * kPi * r * r / float(std::max<uint64_t>(b.count, 1));
  b.length = std::min(0.5f * r, std::sqrt(area / (aspect * 0.7f)));  // the outline fills ~70% of the card
  b.width = aspect * b.length;
}

// One L-system plant with `faces` faces: wood, then leaf cards filling the rest.
void planPlant(Plan& p, SceneKind kind, uint64_t faces, const Placement& place, uint64_t seed) {
  PlantShape shape;
  LSystem ls;
  if (kind == SceneKind::TreeCrown) {
    ls = bushSystem("TTTT/A");
    shape.angle = 34.0f;
    shape.length = 0.9f;
    shape.lengthDecay = 0.74f;
    shape.radius = 0.09f;
    shape.radiusDecay = 0.6f;
    shape.trunkLength = 0.5f;
    shape.trunkRadius = 0.14f;
    shape.tropism = 0.18f;
    shape.leafMinLevel = 2;
  } else {
    ls = bushSystem("[&&FA]///////[&FA]///////[&&FA]///////[&FA]");  // four stems from the ground
    shape.angle = 30.0f;
    shape.length = 0.4f;
    shape.lengthDecay = 0.8f;
    shape.tropism = 0.3f;
    shape.jitter = 0.15f;
    shape.radius = 0.025f;
    shape.leafMinLevel = 1;
  }
  uint32_t iterations = 0;
  const std::string s = deriveWithin(ls, faces / 5, &shape, &iterations);
  p.stats.lsystemIterations = std::max(p.stats.lsystemIterations, iterations);
  const size_t rigidBefore = p.model.triangleMaterial.size();
  LeafBatch b;
  interpret(s, shape, place, seed, p.model, b.attach, p.hierarchy, p.boxParent, &p.stats.pushes);
  const uint64_t rigid = p.model.triangleMaterial.size() - rigidBefore;
  if (b.attach.empty())
    b.attach.push_back({place.apply({0, shape.length, 0}), {0, 1, 0}, shape.length * place.scale, BEND_LEAF_ONLY, 0.0f,
                        gpu::BendVertex{BEND_LEAF_ONLY, 0}, uint32_t(p.boxParent.size() - 1)});
  b.shape = LeafShape::Card;
  b.material = kLeaf;
  b.spread = kind == SceneKind::TreeCrown ? 0.9f : 0.7f;
  b.count = faces > rigid ? (faces - rigid) / facesPerLeaf(b.shape) : 1;
  b.count = std::max<uint64_t>(b.count, 1);
  b.seed = mix64(seed ^ 0x1eafull);
  sizeCards(b, kind == SceneKind::TreeCrown ? 5.0f : 6.0f, 0.55f);
  markRigid(p, p.stats.plants);
  b.plant = p.stats.plants;
  p.batches.push_back(std::move(b));
  p.stats.plants++;
}

// A patch of grass blades over [lo, hi] on y = 0 with `faces` faces.
void planGrass(Plan& p, uint64_t faces, glm::vec2 lo, glm::vec2 hi, float height, uint64_t seed, uint32_t plant) {
  LeafBatch b;
  b.plant = plant;
  b.shape = LeafShape::Blade;
  b.material = kGrass;
  b.lo = lo;
  b.hi = hi;
  b.length = height;
  b.count = std::max<uint64_t>(1, faces / facesPerLeaf(b.shape));
  // Total blade area ~3x the ground (the blade's outline fills ~55% of its quad strip).
  const float area = (hi.x - lo.x) * (hi.y - lo.y);
  b.width = std::clamp(3.0f * area / (float(b.count) * height * 0.55f), 0.0005f, 0.12f);
  b.seed = mix64(seed ^ 0x67a55ull);
  p.batches.push_back(std::move(b));
}

// Underwater vegetation: a rock, stems swaying up from it, ribbon blades along the stems.
void planKelp(Plan& p, uint64_t faces, uint64_t seed) {
  Rng rng(seed);
  addRock(p.model, kRock, {0, 0, 0}, 0.7f, 5, 14, seed);
  const uint32_t stems = uint32_t(std::clamp<uint64_t>(faces / 20000, 6, 40));
  const uint32_t segments = 12, sides = faces < 20000 ? 3 : 5;
  LeafBatch b;
  b.shape = LeafShape::Ribbon;
  b.material = kKelpBlade;
  for (uint32_t k = 0; k < stems; ++k) {
    const float a = rng.range(0, 2 * kPi), r = 0.45f * std::sqrt(rng.uniform());
    glm::vec3 pos(r * std::cos(a), 0.3f, r * std::sin(a));
    glm::vec3 h = glm::normalize(glm::vec3(rng.range(-0.3f, 0.3f), 1.0f, rng.range(-0.3f, 0.3f)));
    const float height = rng.range(1.6f, 2.6f), seg = height / float(segments);
    const float phase = rng.range(0, 2 * kPi), sway = rng.range(0.15f, 0.35f);
    for (uint32_t i = 0; i < segments; ++i) {
      // The turtle's heading swings slowly (a stem drifting in the current).
      glm::vec3 next = glm::normalize(h + glm::vec3(sway * std::sin(phase + 0.7f * float(i)), 0.0f,
                                                    0.5f * sway * std::cos(phase + 0.5f * float(i))) * 0.3f);
      const glm::vec3 end = pos + next * seg;
      const float radius = 0.018f * (1.0f - 0.6f * float(i) / float(segments));
      const glm::vec3 s0 = anyPerpendicular(next), s1 = glm::cross(next, s0);
      addCylinder(p.model, kKelpStem, pos, end, radius, radius * 0.95f, s0, s1, sides);
      if (i >= 1)
        for (int side = -1; side <= 1; side += 2) {
          const glm::vec3 out = glm::normalize(float(side) * s0 * std::cos(float(i)) + float(side) * s1 * std::sin(float(i)));
          b.attach.push_back({end, glm::normalize(out + next * 0.8f), seg});
        }
      pos = end;
      h = next;
    }
    p.stats.plants++;
  }
  const uint64_t rigid = p.model.triangleMaterial.size();
  b.count = std::max<uint64_t>(1, (faces > rigid ? faces - rigid : 0) / facesPerLeaf(b.shape));
  b.length = 0.35f;
  // Blade area ~10x the plants' silhouette (about 2.4 x 2.4 world units): kelp is a thick tangle.
  b.width = std::clamp(10.0f * 2.4f * 2.4f / (float(b.count) * b.length * 0.5f), 0.002f, 0.12f);
  b.seed = mix64(seed ^ 0xce1bull);
  markRigid(p, 0);  // the rock and its stems: one plant, as its blades are one batch
  b.plant = 0;
  p.batches.push_back(std::move(b));
}

// The large vegetation field: ground, trees, shrubs and grass over 16 x 16 world units.
void planField(Plan& p, uint64_t faces, uint64_t seed, uint32_t* lsysIterations) {
  const float half = 8.0f;
  const uint32_t groundCells = uint32_t(std::clamp<double>(std::sqrt(double(faces) * 0.005 / 2.0), 1.0, 32.0));
  addGround(p.model, kGround, {-half, -half}, {half, half}, 0.0f, groundCells);
  markRigid(p, kNoPlant);
  Rng rng(seed);
  const uint32_t trees = 3 + uint32_t(std::min<uint64_t>(12, faces / 4'000'000)), shrubs = 2 * trees;
  std::vector<glm::vec3> placed;  // x, z, radius
  auto place = [&](float radius) {
    glm::vec2 best(0.0f);
    float bestGap = -1e30f;
    for (int attempt = 0; attempt < 40; ++attempt) {  // best of 40 candidates: spread out, deterministic
      const glm::vec2 c(rng.range(-half + radius, half - radius), rng.range(-half + radius, half - radius));
      float gap = 1e30f;
      for (const glm::vec3& q : placed) gap = std::min(gap, glm::length(c - glm::vec2(q.x, q.y)) - q.z - radius);
      if (gap > bestGap) {
        bestGap = gap;
        best = c;
      }
      if (gap > 0.5f) break;
    }
    placed.push_back({best.x, best.y, radius});
    return best;
  };
  const uint64_t rigid = p.model.triangleMaterial.size();
  const uint64_t rest = faces > rigid ? faces - rigid : 0;
  for (uint32_t i = 0; i < trees + shrubs; ++i) {
    const bool tree = i < trees;
    const float scale = tree ? rng.range(1.4f, 2.0f) : rng.range(0.9f, 1.5f);
    const glm::vec2 c = place(tree ? 2.2f * scale : 0.8f * scale);
    Placement pl{{c.x, 0.0f, c.y}, scale, rng.range(0, 2 * kPi)};
    const uint64_t budget = tree ? uint64_t(0.35 * double(rest) / trees) : uint64_t(0.25 * double(rest) / shrubs);
    planPlant(p, tree ? SceneKind::TreeCrown : SceneKind::Shrub, budget, pl, mix64(seed + 1 + i));
  }
  const uint64_t used = p.model.triangleMaterial.size();
  uint64_t leafFaces = 0;
  for (const LeafBatch& b : p.batches) leafFaces += b.count * facesPerLeaf(b.shape);
  const uint64_t sofar = used + leafFaces;
  planGrass(p, faces > sofar ? faces - sofar : facesPerLeaf(LeafShape::Blade), {-half, -half}, {half, half}, 0.3f,
            mix64(seed ^ 0xf1e1dull), p.stats.plants);
  p.stats.plants++;
  *lsysIterations = p.stats.lsystemIterations;
}

// ---------------------------------------------------------------------------------------------
// The branch hierarchy as the model carries it (shared/bend.h).

// Habel's w of a point `arc` along `branch`: its coordinate on that branch, then, up the chain,
// the coordinate at which each ancestor carries the branch below it.
uint32_t packW(const HierarchyBuild& h, uint32_t branch, float arc) {
  uint32_t w = 0;
  for (uint32_t b = branch; b != BEND_NO_PARENT;) {
    const BranchBuild& B = h.branches[b];
    const float x = B.length > 0.0f ? std::clamp(arc / B.length, 0.0f, 1.0f) : 0.0f;
    w |= uint32_t(std::lround(x * 255.0f)) << (8 * B.level);
    arc = B.attachArc;
    b = B.parent;
  }
  return w;
}

// The branch table, the rigid vertices' bend records (others: BEND_LEAF_ONLY) and the attachments'.
void finishHierarchy(Plan& p) {
  VegetationModel& m = p.model;
  const HierarchyBuild& h = p.hierarchy;
  m.branches.clear();
  for (const BranchBuild& b : h.branches) {
    const glm::vec3 chord = b.tip - b.origin;
    const glm::vec3 axis = glm::length(chord) > 1e-6f ? glm::normalize(chord) : glm::normalize(b.dir0);
    m.branches.push_back(gpu::BendBranch{b.origin, b.parent, axis, b.level});
  }
  m.bend.assign(m.positions.size(), gpu::BendVertex{BEND_LEAF_ONLY, 0});
  for (const RigidRun& r : h.runs)
    for (uint32_t ring = 0; ring < 2; ++ring) {
      const gpu::BendVertex v{r.branch, packW(h, r.branch, ring ? r.arc1 : r.arc0)};
      std::fill(m.bend.begin() + r.firstVertex + ring * r.ringVertices,
                m.bend.begin() + r.firstVertex + (ring + 1) * r.ringVertices, v);
    }
  for (LeafBatch& b : p.batches)
    for (Attach& a : b.attach)
      if (a.branch != BEND_LEAF_ONLY) a.bend = gpu::BendVertex{a.branch, packW(h, a.branch, a.arc)};
}

// ---------------------------------------------------------------------------------------------
// Writing leaves.

struct Arrays {
  glm::vec3* pos;
  glm::vec3* nrm;
  glm::vec2* uv;
  uint32_t* idx;
  uint32_t* mat;
  gpu::BendVertex* bend;  // null: no hierarchy asked for
  uint32_t* box;          // per triangle; null: no boxes asked for
  uint32_t* plant;        // per triangle (VegetationModel::trianglePlant)
};

// A grass patch is kGrassCells x kGrassCells plants (eq. 7 per plant: a blade bends about its own
// cell's front, not the whole field's); a blade's plant is its root's cell.
constexpr uint32_t kGrassCells = 4;

void writeCard(const LeafBatch& b, uint64_t j, Rng& rng, glm::vec3* P, glm::vec3* N, glm::vec2* T) {
  const Attach& a = b.attach[j % b.attach.size()];
  const glm::vec3 base = a.pos + rng.inBall() * (b.spread * a.size);
  glm::vec3 out = base - b.centre;
  out = glm::length(out) > 1e-5f ? glm::normalize(out) : a.dir;
  glm::vec3 axis = a.dir * 0.5f + out * 0.7f + rng.onSphere() * 0.7f;
  axis = glm::length(axis) > 1e-4f ? glm::normalize(axis) : out;
  glm::vec3 n = out + glm::vec3(0, 0.6f, 0) + rng.onSphere() * 0.6f;
  n -= glm::dot(n, axis) * axis;
  n = glm::length(n) > 1e-4f ? glm::normalize(n) : anyPerpendicular(axis);
  const glm::vec3 side = glm::cross(axis, n);
  const float k = rng.range(0.75f, 1.25f), L = b.length * k, W = 0.5f * b.width * k;
  P[0] = base - side * W;
  P[1] = base + side * W;
  P[2] = base + side * W + axis * L;
  P[3] = base - side * W + axis * L;
  for (int i = 0; i < 4; ++i) N[i] = n;
  T[0] = {0, 0};  // the root vertex: smallest (u, v), at the attachment
  T[1] = {1, 0};
  T[2] = {1, 1};
  T[3] = {0, 1};
}

// A strip of `segs` quads along centre(t) with half width w(t), uv (0|1, t).
template <typename Centre, typename Width>
void writeStrip(uint32_t segs, const glm::vec3& side, Centre centre, Width width, glm::vec3* P, glm::vec3* N,
                glm::vec2* T) {
  for (uint32_t k = 0; k <= segs; ++k) {
    const float t = float(k) / float(segs);
    const glm::vec3 c = centre(t);
    const glm::vec3 tangent = centre(std::min(1.0f, t + 0.05f)) - centre(std::max(0.0f, t - 0.05f));
    glm::vec3 n = glm::cross(side, tangent);
    n = glm::length(n) > 1e-9f ? glm::normalize(n) : anyPerpendicular(side);
    const float w = width(t);
    P[2 * k] = c - side * w;
    P[2 * k + 1] = c + side * w;
    N[2 * k] = N[2 * k + 1] = n;
    T[2 * k] = {0, t};
    T[2 * k + 1] = {1, t};
  }
}

void writeBlade(const LeafBatch& b, Rng& rng, glm::vec3* P, glm::vec3* N, glm::vec2* T) {
  const glm::vec3 root(rng.range(b.lo.x, b.hi.x), b.ground, rng.range(b.lo.y, b.hi.y));
  const float h = b.length * rng.range(0.6f, 1.3f), bend = rng.range(0.1f, 0.5f) * h;
  const float lean = rng.range(0, 2 * kPi), facing = rng.range(0, 2 * kPi);
  const glm::vec3 leanDir(std::cos(lean), 0, std::sin(lean)), side(std::cos(facing), 0, std::sin(facing));
  const float w = 0.5f * b.width * rng.range(0.7f, 1.3f);
  writeStrip(
      kBladeSegments, side, [&](float t) { return root + glm::vec3(0, h * t, 0) + leanDir * (bend * t * t); },
      [&](float t) { return w * (1.0f - 0.8f * t); }, P, N, T);
}

void writeRibbon(const LeafBatch& b, uint64_t j, Rng& rng, glm::vec3* P, glm::vec3* N, glm::vec2* T) {
  const Attach& a = b.attach[j % b.attach.size()];
  const glm::vec3 root = a.pos + rng.inBall() * (0.3f * a.size);
  const glm::vec3 d0 = glm::normalize(a.dir + rng.onSphere() * 0.4f);
  const glm::vec3 drift = glm::normalize(glm::vec3(0, 0.8f, 0) + b.flow * 0.6f + rng.onSphere() * 0.3f);
  const float L = b.length * rng.range(0.6f, 1.4f), w = 0.5f * b.width * rng.range(0.7f, 1.3f);
  const float wave = rng.range(0.02f, 0.06f), phase = rng.range(0, 2 * kPi);
  glm::vec3 side = glm::cross(d0, drift);
  side = glm::length(side) > 1e-4f ? glm::normalize(side) : anyPerpendicular(d0);
  writeStrip(
      kRibbonSegments, side,
      [&](float t) {
        // Leaves the stem along d0 and bends toward the drift direction (buoyancy + current).
        return root + L * (d0 * t * (1.0f - 0.5f * t) + drift * 0.5f * t * t) + side * (wave * std::sin(phase + 9.0f * t) * t);
      },
      [&](float t) { return w * (0.35f + 0.65f * std::sin(kPi * std::min(1.0f, 0.2f + t * 0.9f))); }, P, N, T);
}

void writeLeaves(const LeafBatch& b, uint64_t first, uint64_t last, const Arrays& out) {
  const uint32_t nv = verticesPerLeaf(b.shape), nf = facesPerLeaf(b.shape);
  for (uint64_t j = first; j < last; ++j) {
    Rng rng(mix64(b.seed + j * 0x9e3779b97f4a7c15ull));
    const uint64_t v0 = b.firstVertex + j * nv;
    glm::vec3* P = out.pos + v0;
    glm::vec3* N = out.nrm + v0;
    glm::vec2* T = out.uv + v0;
    if (b.shape == LeafShape::Card) writeCard(b, j, rng, P, N, T);
    else if (b.shape == LeafShape::Blade) writeBlade(b, rng, P, N, T);
    else writeRibbon(b, j, rng, P, N, T);
    // A card rides its twig rigidly (it turns about its own root in the leaf level); blades and
    // ribbons have only the leaf level.
    if (out.bend)
      std::fill(out.bend + v0, out.bend + v0 + nv,
                b.shape == LeafShape::Card ? b.attach[j % b.attach.size()].bend : gpu::BendVertex{BEND_LEAF_ONLY, 0});
    uint32_t* I = out.idx + b.firstIndex + j * nf * 3;
    const uint32_t base = uint32_t(v0);
    if (b.shape == LeafShape::Card) {
      const uint32_t q[6] = {0, 1, 2, 2, 3, 0};
      for (int i = 0; i < 6; ++i) I[i] = base + q[i];
    } else {
      for (uint32_t k = 0; k < nf / 2; ++k) {
        const uint32_t q[6] = {2 * k, 2 * k + 1, 2 * k + 3, 2 * k + 3, 2 * k + 2, 2 * k};
        for (int i = 0; i < 6; ++i) I[6 * k + i] = base + q[i];
      }
    }
    std::fill(out.mat + b.firstTriangle + j * nf, out.mat + b.firstTriangle + (j + 1) * nf, b.material);
    uint32_t plant = b.plant;
    if (b.shape == LeafShape::Blade && plant != kNoPlant) {
      const glm::vec2 t = (glm::vec2(P[0].x, P[0].z) - b.lo) / glm::max(b.hi - b.lo, glm::vec2(1e-6f));
      const uint32_t cx = std::min(uint32_t(std::max(t.x, 0.0f) * kGrassCells), kGrassCells - 1);
      const uint32_t cz = std::min(uint32_t(std::max(t.y, 0.0f) * kGrassCells), kGrassCells - 1);
      plant += cz * kGrassCells + cx;
    }
    std::fill(out.plant + b.firstTriangle + j * nf, out.plant + b.firstTriangle + (j + 1) * nf, plant);
    if (out.box)
      std::fill(out.box + b.firstTriangle + j * nf, out.box + b.firstTriangle + (j + 1) * nf,
                b.shape == LeafShape::Card ? b.attach[j % b.attach.size()].box : b.box);
  }
}

}  // namespace

Status parseSceneKind(const std::string& text, SceneKind* out) {
  struct Name {
    const char* text;
    SceneKind kind;
  };
  static const Name names[] = {{"shrub", SceneKind::Shrub},      {"tree", SceneKind::TreeCrown},
                               {"tree-crown", SceneKind::TreeCrown}, {"grass", SceneKind::GrassField},
                               {"grass-field", SceneKind::GrassField}, {"kelp", SceneKind::Kelp},
                               {"underwater", SceneKind::Kelp},  {"field", SceneKind::Field}};
  for (const Name& n : names)
    if (text == n.text) {
      *out = n.kind;
      return Status();
    }
  return Status::error("scene '" + text + "' is not one of shrub, tree, grass, kelp, field");
}

const char* sceneName(SceneKind kind) {
  switch (kind) {
    case SceneKind::Shrub: return "shrub";
    case SceneKind::TreeCrown: return "tree";
    case SceneKind::GrassField: return "grass";
    case SceneKind::Kelp: return "kelp";
    case SceneKind::Field: return "field";
  }
  return "?";
}

Status validateSceneDesc(const SceneDesc& d) {
  if (uint32_t(d.kind) >= kSceneKindCount) return Status::error("scene kind " + std::to_string(uint32_t(d.kind)) + " is not 0..4");
  if (d.faces < kMinSceneFaces || d.faces > kMaxSceneFaces)
    return Status::error("scene faces " + std::to_string(d.faces) + " is outside [" + std::to_string(kMinSceneFaces) + ", " +
                         std::to_string(kMaxSceneFaces) + "]");
  if (d.textureSize < 16 || d.textureSize > 2048 || (d.textureSize & (d.textureSize - 1)))
    return Status::error("scene textureSize " + std::to_string(d.textureSize) + " is not a power of two in [16, 2048]");
  if (d.threads > 1024) return Status::error("scene threads " + std::to_string(d.threads) + " is outside [0, 1024]");
  return Status();
}

Status generateScene(const SceneDesc& desc, VegetationModel* out, SceneStats* statsOut, const SceneProgress& progress) {
  *out = VegetationModel();
  CANOPY_TRY(validateSceneDesc(desc));
  try {
    Plan p;
    const uint64_t seed = mix64(uint64_t(desc.seed) * 0x2545f4914f6cdd1dull + uint64_t(desc.kind) + 1);
    setMaterials(p.model, desc.textureSize, seed);
    uint32_t iterations = 0;
    switch (desc.kind) {
      case SceneKind::Shrub:
      case SceneKind::TreeCrown: planPlant(p, desc.kind, desc.faces, Placement{}, seed); break;
      case SceneKind::GrassField:
        addGround(p.model, kGround, {-2.5f, -2.5f}, {2.5f, 2.5f}, 0.0f, 8);
        markRigid(p, kNoPlant);
        planGrass(p, desc.faces - p.model.triangleMaterial.size(), {-2.5f, -2.5f}, {2.5f, 2.5f}, 0.35f, seed, 0);
        p.stats.plants = 1;
        break;
      case SceneKind::Kelp: planKelp(p, desc.faces, seed); break;
      case SceneKind::Field: planField(p, desc.faces, seed, &iterations); break;
    }
    // Layout: rigid geometry first, then each batch's leaves at fixed offsets.
    VegetationModel& m = p.model;
    if (desc.hierarchy) finishHierarchy(p);
    const uint64_t rigidVertices = m.positions.size(), rigidTriangles = m.triangleMaterial.size();
    uint64_t vertices = rigidVertices, triangles = rigidTriangles, leaves = 0;
    for (LeafBatch& b : p.batches) {
      b.firstVertex = vertices;
      b.firstTriangle = triangles;
      b.firstIndex = triangles * 3;
      vertices += b.count * verticesPerLeaf(b.shape);
      triangles += b.count * facesPerLeaf(b.shape);
      leaves += b.count;
    }
    if (vertices >= 0xffffffffull)
      return Status::error("scene: " + std::to_string(vertices) + " vertices do not fit 32-bit indices; ask for fewer faces");
    m.positions.resize(vertices);
    m.normals.resize(vertices);
    m.uvs.resize(vertices);
    m.indices.resize(triangles * 3);
    m.triangleMaterial.resize(triangles);
    // Each triangle's plant: rigid parts as marked, each batch's leaves its plant's.
    p.rigidPlant.resize(rigidTriangles, kNoPlant);
    m.trianglePlant = std::move(p.rigidPlant);
    m.trianglePlant.resize(triangles, kNoPlant);  // the leaves': writeLeaves
    if (desc.hierarchy) m.bend.resize(vertices);
    if (desc.boxes) {
      // Cards take their attachment's box; a blade or ribbon batch gets one box under the scene's.
      for (LeafBatch& b : p.batches)
        if (b.shape != LeafShape::Card) {
          p.boxParent.push_back(0);
          b.box = uint32_t(p.boxParent.size() - 1);
        }
      m.triangleBox.assign(triangles, 0xffffffffu);
      m.boxParent = p.boxParent;
    }
    const Arrays arrays{m.positions.data(), m.normals.data(), m.uvs.data(), m.indices.data(), m.triangleMaterial.data(),
                        desc.hierarchy ? m.bend.data() : nullptr, desc.boxes ? m.triangleBox.data() : nullptr,
                        m.trianglePlant.data()};

    // Jobs of up to 64K leaves, taken by the workers in order; each leaf has its own random stream.
    struct Job {
      uint32_t batch;
      uint64_t first, last;
    };
    std::vector<Job> jobs;
    for (uint32_t i = 0; i < p.batches.size(); ++i)
      for (uint64_t f = 0; f < p.batches[i].count; f += 65536) jobs.push_back({i, f, std::min(p.batches[i].count, f + 65536)});
    std::atomic<size_t> nextJob{0};
    std::atomic<uint64_t> done{0};
    auto worker = [&]() {
      for (size_t j; (j = nextJob.fetch_add(1)) < jobs.size();) {
        writeLeaves(p.batches[jobs[j].batch], jobs[j].first, jobs[j].last, arrays);
        done += jobs[j].last - jobs[j].first;
      }
    };
    const uint32_t threads = std::max(1u, std::min<uint32_t>(desc.threads ? desc.threads : std::thread::hardware_concurrency(),
                                                            uint32_t(std::max<size_t>(1, jobs.size()))));
    std::vector<std::thread> pool;
    for (uint32_t t = 1; t < threads; ++t) pool.emplace_back(worker);
    if (progress) {
      // The calling thread reports while the workers write (and works too once they are few).
      while (done.load() < leaves && nextJob.load() < jobs.size() && !pool.empty()) {
        progress("leaves", done.load(), leaves);
        std::this_thread::sleep_for(std::chrono::milliseconds(200));
      }
    }
    worker();
    for (std::thread& t : pool) t.join();
    if (progress) progress("leaves", leaves, leaves);

    m.boundsMin = glm::vec3(1e30f);
    m.boundsMax = glm::vec3(-1e30f);
    for (const glm::vec3& v : m.positions) {
      m.boundsMin = glm::min(m.boundsMin, v);
      m.boundsMax = glm::max(m.boundsMax, v);
    }
    compactMaterials(m);
    // The per-vertex baseline bends these plants through their own hierarchy (SceneDesc.hierarchy
    // builds it on request): the default sway's calibration (render/plant_sway.h).
    m.ownHierarchy = true;
    p.stats.faces = triangles;
    p.stats.rigidFaces = rigidTriangles;
    p.stats.leafFaces = triangles - rigidTriangles;
    p.stats.leaves = leaves;
    if (iterations) p.stats.lsystemIterations = iterations;
    *out = std::move(m);
    if (statsOut) *statsOut = p.stats;
    return Status();
  } catch (const std::bad_alloc&) {
    *out = VegetationModel();
    return Status::error("scene: not enough memory for " + std::to_string(desc.faces) + " faces (about " +
                         std::to_string(desc.faces * 80 >> 20) + " MiB needed)");
  } catch (const std::system_error& e) {
    *out = VegetationModel();
    return Status::error(std::string("scene: cannot start worker threads: ") + e.what());
  }
}

uint64_t modelHash(const VegetationModel& m) {
  uint64_t h = 0x9e3779b97f4a7c15ull;
  h = hashBytes(h, m.positions.data(), m.positions.size() * sizeof(glm::vec3));
  h = hashBytes(h, m.normals.data(), m.normals.size() * sizeof(glm::vec3));
  h = hashBytes(h, m.uvs.data(), m.uvs.size() * sizeof(glm::vec2));
  h = hashBytes(h, m.indices.data(), m.indices.size() * sizeof(uint32_t));
  h = hashBytes(h, m.triangleMaterial.data(), m.triangleMaterial.size() * sizeof(uint32_t));
  for (const ModelMaterial& mat : m.materials) {
    h = hashBytes(h, mat.name.data(), mat.name.size());
    const float f[5] = {mat.baseColorFactor.r, mat.baseColorFactor.g, mat.baseColorFactor.b, mat.baseColorFactor.a,
                        mat.alphaCutoff};
    const int32_t i[3] = {mat.baseColorImage, int32_t(mat.alphaMode), int32_t(mat.doubleSided)};
    h = hashBytes(h, f, sizeof(f));
    h = hashBytes(h, i, sizeof(i));
  }
  for (const ModelImage& img : m.images) {
    const uint32_t wh[2] = {img.width, img.height};
    h = hashBytes(h, wh, sizeof(wh));
    h = hashBytes(h, img.rgba.data(), img.rgba.size());
  }
  // The hierarchy only where there is one: models without keep their hashes.
  if (!m.bend.empty()) h = hashBytes(h, m.bend.data(), m.bend.size() * sizeof(gpu::BendVertex));
  if (!m.branches.empty()) h = hashBytes(h, m.branches.data(), m.branches.size() * sizeof(gpu::BendBranch));
  if (!m.boxParent.empty()) h = hashBytes(h, m.boxParent.data(), m.boxParent.size() * sizeof(uint32_t));
  if (!m.triangleBox.empty()) h = hashBytes(h, m.triangleBox.data(), m.triangleBox.size() * sizeof(uint32_t));
  return h;
}

}  // namespace canopy
