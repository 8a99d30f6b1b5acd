#pragma once
// The parameter schema: every public parameter struct of <canopy/canopy_params.h> is declared by a list
// of its fields, one line each,
//
//   X(type, name, default, check, min, max, unit, doc)
//
// from which come the struct itself (type name = default), its operator==, its validation (the
// check over [min, max], the message naming the field with its range and unit: createCanopy and
// setCanopyParams run it when a value is given, not every frame), the ParamInfo table below (the
// demo's --help takes the range, unit and text of an option that mirrors a field from it) and
// docs/parameters.md (written from that table by `canopy-demo --param-table`; the docs check
// compares them). A field added to a list is compared, checked and documented with no other edit.
#include <array>
#include <cstddef>
#include <cstdint>

namespace canopy {

using Float4 = std::array<float, 4>;

// How a field's value is checked against [min, max].
enum class ParamCheck : uint32_t {
  Unchecked = 0,     // not checked here (a flag, a seed, a handle, or checked with other fields)
  Closed = 1,        // finite (integers: any), min <= v <= max; Float3/Float4: each component
  AboveMin = 2,      // finite, min < v <= max
  Enum = 3,          // an enumerator: min <= value <= max (the unit column names them)
  PowerOfTwo = 4,    // a power of two in [min, max]
  PowerOfTwoOrZero = 5,
  Finite = 6,        // finite (Float3: each component)
  Nested = 7,        // a parameter struct of its own: its list checks it
  Each = 8,          // a vector of a parameter struct: at most `max` elements, each checked
#ifndef None
  None = Unchecked,  // 0.8's name of Unchecked (X11 defines None)
#endif
};

// One field of the schema.
struct ParamInfo {
  const char* owner;        // the struct, e.g. "WindParams"
  const char* name;         // the field, e.g. "strength"
  const char* type;         // as declared, e.g. "float"
  const char* defaultText;  // the default as written in the list, e.g. "0.5f"
  ParamCheck check;
  double min, max;
  const char* unit;         // e.g. "domain units/s"; for an enum its enumerators
  const char* doc;          // one line: what the field does
};

// Every field of every parameter struct, struct by struct in declaration order.
const ParamInfo* paramSchema(size_t* count);
// The field "Struct.name" (e.g. "WindParams.strength"), or nullptr.
const ParamInfo* findParam(const char* qualifiedName);

}  // namespace canopy

// The struct's field from its list line.
#define CANOPY_PARAM_FIELD(type, name, def, check, lo, hi, unit, doc) type name = def;
#define CANOPY_PARAM_EQUAL(type, name, def, check, lo, hi, unit, doc) && a.name == b.name
// Declares `Struct` from LIST, with == and != over every field of the list.
#define CANOPY_PARAM_STRUCT(Struct, LIST)                                                           \
  struct Struct {                                                                                   \
    LIST(CANOPY_PARAM_FIELD)                                                                        \
  };                                                                                                \
  inline bool operator==(const Struct& a, const Struct& b) { return true LIST(CANOPY_PARAM_EQUAL); } \
  inline bool operator!=(const Struct& a, const Struct& b) { return !(a == b); }
