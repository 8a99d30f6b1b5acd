// The parameter schema's table and checks, both expanded from the field lists of
// <canopy/canopy_params.h> (canopy_schema.h explains the list form; docs/design.md "Parameters").
#include <cmath>
#include <cstring>
#include <sstream>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include <canopy/canopy_params.h>

#include "engine/status.h"
#include "render/param_schema.h"

namespace canopy {
namespace {

// Every struct with a field list, with the list that declares it.
#define CANOPY_PARAM_LISTS(S)                              \
  S(WindParams, CANOPY_WIND_PARAMS)                        \
  S(Motor, CANOPY_MOTOR_PARAMS)                            \
  S(FluidParams, CANOPY_FLUID_PARAMS)                      \
  S(WaveParams, CANOPY_WAVE_PARAMS)                        \
  S(PushParams, CANOPY_PUSH_PARAMS)                        \
  S(SimulationParams, CANOPY_SIMULATION_PARAMS)            \
  S(SimulationDesc, CANOPY_SIMULATION_DESC)                \
  S(RegionSplit, CANOPY_REGION_SPLIT)                      \
  S(ImpostorSettings, CANOPY_IMPOSTOR_SETTINGS)            \
  S(ImpostorDesc, CANOPY_IMPOSTOR_DESC)                    \
  S(LayerSettings, CANOPY_LAYER_SETTINGS)                  \
  S(DynamicsParams, CANOPY_DYNAMICS_PARAMS)                \
  S(CompositeParams, CANOPY_COMPOSITE_PARAMS)              \
  S(SimulationPlane, CANOPY_SIMULATION_PLANE)              \
  S(CanopyPusher, CANOPY_PUSHER_PARAMS)                    \
  S(PerVertexParams, CANOPY_PER_VERTEX_PARAMS)             \
  S(WorldWind, CANOPY_WORLD_WIND)                          \
  S(CanopyParams, CANOPY_PARAMS)                           \
  S(CanopyDesc, CANOPY_DESC)

std::string unitText(ParamCheck check, const char* unit) {
  if (!unit || !*unit) return std::string();
  return check == ParamCheck::Enum ? std::string(": one of ") + unit : std::string(" (") + unit + ")";
}

Status refuse(const std::string& path, const std::string& value, ParamCheck check, double lo, double hi, const char* unit) {
  const std::string range = formatParamNumber(lo) + ", " + formatParamNumber(hi) + "]";
  std::string why;
  switch (check) {
    case ParamCheck::AboveMin: why = "is outside (" + range; break;
    case ParamCheck::PowerOfTwo: why = "is not a power of two in [" + range; break;
    case ParamCheck::PowerOfTwoOrZero: why = "is neither 0 nor a power of two in [" + range; break;
    case ParamCheck::Finite: why = "is not finite"; break;
    default: why = "is outside [" + range; break;
  }
  return Status::error(path + " = " + value + " " + why + unitText(check, unit));
}

Status checkReal(const std::string& path, double v, ParamCheck c, double lo, double hi, const char* unit) {
  bool ok = std::isfinite(v);
  if (c == ParamCheck::Closed) ok = ok && v >= lo && v <= hi;
  if (c == ParamCheck::AboveMin) ok = ok && v > lo && v <= hi;
  return ok ? Status() : refuse(path, formatParamNumber(v), c, lo, hi, unit);
}

Status checkInteger(const std::string& path, uint64_t v, ParamCheck c, double lo, double hi, const char* unit) {
  const bool inRange = double(v) >= lo && double(v) <= hi;
  const bool pow2 = v != 0 && (v & (v - 1)) == 0;
  bool ok = inRange;
  if (c == ParamCheck::PowerOfTwo) ok = inRange && pow2;
  if (c == ParamCheck::PowerOfTwoOrZero) ok = v == 0 || (inRange && pow2);
  return ok ? Status() : refuse(path, std::to_string(v), c, lo, hi, unit);
}

template <class T>
struct IsVector : std::false_type {};
template <class T>
struct IsVector<std::vector<T>> : std::true_type {};
template <class T, class = void>
struct HasParams : std::false_type {};
template <class T>
struct HasParams<T, std::void_t<decltype(checkParams(std::declval<const T&>(), std::string()))>> : std::true_type {};

// One field, by its type and its line's check (None: nothing here).
template <class T>
Status checkValue(const std::string& path, const T& v, ParamCheck c, double lo, double hi, const char* unit) {
  if (c == ParamCheck::None) return Status();
  if constexpr (std::is_floating_point_v<T>) {
    // The bounds in the field's own precision: 1.7f is in [1.2, 1.7] as the header writes it.
    return checkReal(path, double(v), c, double(T(lo)), double(T(hi)), unit);
  } else if constexpr (std::is_enum_v<T>) {
    // A negative underlying value wraps to a huge one: outside every enumerator range.
    return checkInteger(path, uint64_t(std::underlying_type_t<T>(v)), c, lo, hi, unit);
  } else if constexpr (std::is_integral_v<T> && !std::is_same_v<T, bool>) {
    return checkInteger(path, uint64_t(v), c, lo, hi, unit);
  } else if constexpr (std::is_same_v<T, Float3>) {
    CANOPY_TRY(checkValue(path + ".x", v.x, c, lo, hi, unit));
    CANOPY_TRY(checkValue(path + ".y", v.y, c, lo, hi, unit));
    return checkValue(path + ".z", v.z, c, lo, hi, unit);
  } else if constexpr (std::is_same_v<T, Float4>) {
    for (size_t i = 0; i < v.size(); ++i) CANOPY_TRY(checkValue(path + "[" + std::to_string(i) + "]", v[i], c, lo, hi, unit));
    return Status();
  } else if constexpr (std::is_same_v<T, std::vector<CanopyInstance>>) {
    return Status();  // each transform is checked where it is used (render/layer_instances.cpp)
  } else if constexpr (IsVector<T>::value) {
    if (double(v.size()) > hi)
      return Status::error(path + ": " + std::to_string(v.size()) + " given, at most " + formatParamNumber(hi));
    for (size_t i = 0; i < v.size(); ++i) CANOPY_TRY(checkParams(v[i], path + "[" + std::to_string(i) + "]."));
    return Status();
  } else if constexpr (HasParams<T>::value) {
    return checkParams(v, path + ".");  // Nested
  } else {
    return Status::error(path + ": the schema has no check of this field's type");  // a list line asks for one
  }
}

}  // namespace

#define CANOPY_CHECK_LINE(type, name, def, check, lo, hi, unit, doc) \
  CANOPY_TRY(checkValue(prefix + #name, p.name, ParamCheck::check, double(lo), double(hi), unit));
#define CANOPY_DEFINE_CHECK(Struct, LIST)                              \
  Status checkParams(const Struct& p, const std::string& prefix) {     \
    LIST(CANOPY_CHECK_LINE)                                            \
    return Status();                                                   \
  }
CANOPY_PARAM_LISTS(CANOPY_DEFINE_CHECK)

namespace {
std::vector<ParamInfo> buildSchema() {
  std::vector<ParamInfo> out;
  const char* owner = nullptr;
#define CANOPY_INFO_LINE(type, name, def, check, lo, hi, unit, doc) \
  out.push_back({owner, #name, #type, #def, ParamCheck::check, double(lo), double(hi), unit, doc});
#define CANOPY_INFO_STRUCT(Struct, LIST) \
  owner = #Struct;                       \
  LIST(CANOPY_INFO_LINE)
  CANOPY_PARAM_LISTS(CANOPY_INFO_STRUCT)
  return out;
}
}  // namespace

const ParamInfo* paramSchema(size_t* count) {
  static const std::vector<ParamInfo> table = buildSchema();  // immutable once built
  if (count) *count = table.size();
  return table.data();
}

const ParamInfo* findParam(const char* qualifiedName) {
  if (!qualifiedName) return nullptr;
  size_t n = 0;
  const ParamInfo* t = paramSchema(&n);
  for (size_t i = 0; i < n; ++i) {
    const size_t ownerLength = std::strlen(t[i].owner);
    if (std::strncmp(qualifiedName, t[i].owner, ownerLength) == 0 && qualifiedName[ownerLength] == '.' &&
        std::strcmp(qualifiedName + ownerLength + 1, t[i].name) == 0)
      return &t[i];
  }
  return nullptr;
}

std::string formatParamNumber(double v) {
  std::ostringstream o;
  if (std::isfinite(v) && v == std::floor(v) && std::fabs(v) < 9007199254740992.0) o.precision(17);
  o << v;
  return o.str();
}

}  // namespace canopy
