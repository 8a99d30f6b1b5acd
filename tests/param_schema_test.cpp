// The parameter schema (<canopy/canopy_schema.h>, docs/parameters.md): the field lists that declare
// the public parameter structs also give their equality, their checks, the table and the demo's
// help. These tests walk the same lists: every default passes its own check, every checked field
// refuses a value outside its range naming the field and the range, equality sees every field, and
// docs/parameters.md is the table the schema prints.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <iterator>
#include <limits>
#include <string>
#include <type_traits>
#include <typeinfo>
#include <vector>

#include <canopy/canopy.h>

#include "tools/param_table.h"

using namespace canopy;

namespace {

template <class T>
struct IsVector : std::false_type {};
template <class T>
struct IsVector<std::vector<T>> : std::true_type {};

// A value outside a field's allowed values (false: none for this type and check).
template <class T>
bool breakValue(T& v, ParamCheck check, double lo, double hi) {
  if (check == ParamCheck::None || check == ParamCheck::Nested || check == ParamCheck::Each) return false;
  if constexpr (std::is_floating_point_v<T>) {
    v = check == ParamCheck::Finite ? std::numeric_limits<T>::infinity() : T(hi + std::fabs(hi) + 1.0);
    if (check == ParamCheck::AboveMin) v = T(lo);  // the open end
    return true;
  } else if constexpr (std::is_enum_v<T>) {
    v = T(std::underlying_type_t<T>(hi) + 1);
    return true;
  } else if constexpr (std::is_integral_v<T> && !std::is_same_v<T, bool>) {
    if (check == ParamCheck::PowerOfTwo || check == ParamCheck::PowerOfTwoOrZero) {
      v = T(lo) + 1;  // not a power of two (every such lower bound is one)
      return true;
    }
    if (hi >= double(std::numeric_limits<T>::max())) {
      if (lo <= 0) return false;
      v = T(lo) - 1;
      return true;
    }
    v = T(hi) + 1;
    return true;
  } else if constexpr (std::is_same_v<T, Float3>) {
    v.y = std::numeric_limits<float>::quiet_NaN();
    return true;
  } else if constexpr (std::is_same_v<T, Float4>) {
    v[2] = std::numeric_limits<float>::quiet_NaN();
    return true;
  } else {
    return false;
  }
}

// A value different from the default, whatever the check (equality must see it).
template <class T>
void changeValue(T& v) {
  if constexpr (std::is_same_v<T, bool>) v = !v;
  else if constexpr (std::is_floating_point_v<T>) v = v + T(1);
  else if constexpr (std::is_enum_v<T>) v = T(std::underlying_type_t<T>(v) + 1);
  else if constexpr (std::is_integral_v<T>) v = v + 1;
  else if constexpr (std::is_pointer_v<T>) v = reinterpret_cast<T>(uintptr_t(16));
  else if constexpr (std::is_same_v<T, Float3>) v.z += 1.0f;
  else if constexpr (std::is_same_v<T, Float4>) v[3] += 1.0f;
  else if constexpr (IsVector<T>::value) v.emplace_back();
  else if constexpr (std::is_same_v<T, LayerLayout>) v.region[2] += 1;
  else if constexpr (std::is_same_v<T, WindParams>) v.strength += 1.0f;
  else if constexpr (std::is_same_v<T, FluidParams>) v.iterations += 1;
  else if constexpr (std::is_same_v<T, WaveParams>) v.gain += 1.0f;
  else if constexpr (std::is_same_v<T, PushParams>) v.damping += 1.0f;
  else if constexpr (std::is_same_v<T, RegionSplit>) v.absolute = !v.absolute;
  else if constexpr (std::is_same_v<T, ImpostorSettings>) v.band += 1.0f;
  else if constexpr (std::is_same_v<T, PerVertexParams>) v.seed += 1;
  else if constexpr (std::is_same_v<T, LayerSettings>) v.ambient += 0.5f;
  else if constexpr (std::is_same_v<T, SimulationParams>) v.motors.emplace_back();
  else if constexpr (std::is_same_v<T, DynamicsParams>) v.vd += 1.0f;
  else if constexpr (std::is_same_v<T, CompositeParams>) v.bilinear = !v.bilinear;
  else if constexpr (std::is_same_v<T, SimulationPlane>) v.tileSize += 1.0f;
  else if constexpr (std::is_same_v<T, WorldWind>) v.speed += 1.0f;
  else static_assert(std::is_void_v<T>, "a parameter field type the test cannot change");
}

struct Refusal {
  std::string field, message;
  bool refused;
};

// Per list line: break the field in a default struct and check it (through the struct's own
// checkParams), and change it and compare.
#define BREAK_LINE(type, name, def, check, lo, hi, unit, doc)                                          \
  {                                                                                                    \
    Struct s{};                                                                                        \
    if (breakValue(s.name, ParamCheck::check, double(lo), double(hi))) {                               \
      const Status st = checkParams(s);                                                                \
      refusals->push_back({#name, st.message(), !st.ok()});                                            \
    }                                                                                                  \
  }
#define CHANGE_LINE(type, name, def, check, lo, hi, unit, doc) \
  {                                                            \
    Struct s{};                                                \
    changeValue(s.name);                                       \
    if (s == Struct{}) unseen->push_back(#name);               \
  }

}  // namespace

namespace {
template <class Struct>
std::vector<Refusal> refusalsOf();
template <class Struct>
std::vector<std::string> unseenBy();

#define DEFINE_CASES(S, LIST)                                 \
  template <>                                                 \
  std::vector<Refusal> refusalsOf<S>() {                      \
    using Struct = S;                                         \
    std::vector<Refusal> out, *refusals = &out;               \
    LIST(BREAK_LINE)                                          \
    return out;                                               \
  }                                                           \
  template <>                                                 \
  std::vector<std::string> unseenBy<S>() {                    \
    using Struct = S;                                         \
    std::vector<std::string> out, *unseen = &out;             \
    LIST(CHANGE_LINE)                                         \
    return out;                                               \
  }
DEFINE_CASES(WindParams, CANOPY_WIND_PARAMS)
DEFINE_CASES(Motor, CANOPY_MOTOR_PARAMS)
DEFINE_CASES(FluidParams, CANOPY_FLUID_PARAMS)
DEFINE_CASES(WaveParams, CANOPY_WAVE_PARAMS)
DEFINE_CASES(PushParams, CANOPY_PUSH_PARAMS)
DEFINE_CASES(SimulationParams, CANOPY_SIMULATION_PARAMS)
DEFINE_CASES(SimulationDesc, CANOPY_SIMULATION_DESC)
DEFINE_CASES(RegionSplit, CANOPY_REGION_SPLIT)
DEFINE_CASES(ImpostorSettings, CANOPY_IMPOSTOR_SETTINGS)
DEFINE_CASES(ImpostorDesc, CANOPY_IMPOSTOR_DESC)
DEFINE_CASES(LayerSettings, CANOPY_LAYER_SETTINGS)
DEFINE_CASES(DynamicsParams, CANOPY_DYNAMICS_PARAMS)
DEFINE_CASES(CompositeParams, CANOPY_COMPOSITE_PARAMS)
DEFINE_CASES(SimulationPlane, CANOPY_SIMULATION_PLANE)
DEFINE_CASES(CanopyPusher, CANOPY_PUSHER_PARAMS)
DEFINE_CASES(PerVertexParams, CANOPY_PER_VERTEX_PARAMS)
DEFINE_CASES(WorldWind, CANOPY_WORLD_WIND)
DEFINE_CASES(CanopyParams, CANOPY_PARAMS)

template <class... S>
void forEachStruct(void (*fn)(const char*, std::vector<Refusal>, std::vector<std::string>)) {
  (fn(typeid(S).name(), refusalsOf<S>(), unseenBy<S>()), ...);
}

}  // namespace

TEST(ParamSchema, DefaultsPassTheirOwnChecks) {
  for (const Status& s : {checkParams(CanopyParams{}), checkParams(CanopyDesc{}), checkParams(ImpostorDesc{}),
                          checkParams(SimulationPlane{}), checkParams(Motor{}), checkParams(CanopyPusher{})})
    EXPECT_TRUE(s.ok()) << s.message();
}

// Every field whose line checks it refuses a value outside its allowed values (NaN, inf, one past
// the range, the open end, a non-power of two, one past the last enumerator), naming the field.
TEST(ParamSchema, EveryCheckedFieldRefusesAValueOutsideItsRange) {
  size_t checked = 0;
  forEachStruct<WindParams, Motor, FluidParams, WaveParams, PushParams, SimulationParams, SimulationDesc, RegionSplit, ImpostorSettings,
                ImpostorDesc, LayerSettings, DynamicsParams, CompositeParams, SimulationPlane, CanopyPusher, PerVertexParams, WorldWind, CanopyParams>(
      [](const char* type, std::vector<Refusal> refusals, std::vector<std::string>) {
        for (const Refusal& r : refusals) {
          EXPECT_TRUE(r.refused) << type << "." << r.field << " accepted a value outside its range";
          EXPECT_NE(r.message.find("." + r.field), std::string::npos) << r.message;
        }
      });
  for (const Refusal& r : refusalsOf<LayerSettings>()) checked += r.refused;
  EXPECT_GE(checked, 12u);
  // The message carries the range and the unit.
  WindParams w;
  w.strength = 2000.0f;
  EXPECT_EQ(checkParams(w, "CanopyParams.simulation.wind.").message(),
            "CanopyParams.simulation.wind.strength = 2000 is outside [0, 1000] (domain units/s)");
  SimulationDesc d;
  d.gridSize = 48;
  EXPECT_EQ(checkParams(d).message(), "SimulationDesc.gridSize = 48 is not a power of two in [4, 1024] (cells)");
  CompositeParams c;
  c.debugView = CompositeDebugView(7);
  EXPECT_EQ(checkParams(c).message(), "CompositeParams.debugView = 7 is outside [0, 3]: one of Off | Layers | Velocity | Grid");
  SimulationParams sp;
  sp.motors.resize(kMaxMotors + 1);
  EXPECT_EQ(checkParams(sp).message(), "SimulationParams.motors: 9 given, at most 8");
  sp.motors.resize(2);
  sp.motors[1].radius = 0.0f;
  EXPECT_EQ(checkParams(sp).message(), "SimulationParams.motors[1].radius = 0 is outside (0, 100] (domain units)");
}

// The generated operator== compares every field of every list (LayerSettings had a hand-written
// one over 17 fields that a new field could silently miss).
TEST(ParamSchema, EqualitySeesEveryField) {
  forEachStruct<WindParams, Motor, FluidParams, WaveParams, PushParams, SimulationParams, SimulationDesc, RegionSplit, ImpostorSettings,
                ImpostorDesc, LayerSettings, DynamicsParams, CompositeParams, SimulationPlane, CanopyPusher, PerVertexParams, WorldWind, CanopyParams>(
      [](const char* type, std::vector<Refusal>, std::vector<std::string> unseen) {
        for (const std::string& f : unseen) ADD_FAILURE() << type << "::operator== does not see " << f;
      });
}

TEST(ParamSchema, TableNamesEveryFieldOnce) {
  size_t n = 0;
  const ParamInfo* t = paramSchema(&n);
  EXPECT_GT(n, 100u);
  for (size_t i = 0; i < n; ++i) {
    const std::string q = std::string(t[i].owner) + "." + t[i].name;
    EXPECT_EQ(findParam(q.c_str()), &t[i]) << q;
    EXPECT_NE(std::string(t[i].doc), "") << q << " has no text";
  }
  const ParamInfo* s = findParam("WindParams.strength");
  ASSERT_NE(s, nullptr);
  EXPECT_EQ(s->min, 0.0);
  EXPECT_EQ(s->max, 1000.0);
  EXPECT_STREQ(s->unit, "domain units/s");
  EXPECT_STREQ(s->defaultText, "0.5f");
  EXPECT_EQ(findParam("WindParams.nothing"), nullptr);
  EXPECT_EQ(findParam("Wind.strength"), nullptr);
}

TEST(ParamSchema, DocsTableMatchesTheSchema) {
  const std::string path = std::string(CANOPY_SOURCE_DIR) + "/docs/parameters.md";
  std::ifstream f(path);
  ASSERT_TRUE(f.good()) << path << " is missing: canopy-demo --param-table > docs/parameters.md";
  const std::string text((std::istreambuf_iterator<char>(f)), {});
  EXPECT_EQ(text, paramTableMarkdown()) << path << " differs from the schema: canopy-demo --param-table > docs/parameters.md";
}
