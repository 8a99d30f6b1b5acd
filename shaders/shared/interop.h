// One definition for every struct C++ and GLSL exchange (NRD style). A shared header includes
// this file, then declares plain structs between CANOPY_NAMESPACE_BEGIN/END. GLSL reads them with
// the scalar block layout (GL_EXT_scalar_block_layout, core in Vulkan 1.2), whose offsets are the
// C++ ones for the allowed member types: float, int, uint, glm vecN/ivecN/uvecN and mat4 (no
// bool, no double). CANOPY_SIZE_CHECK pins each struct's size on the C++ side, and
// tests/interop_test.cpp reads every field back from a shader, so a drift cannot go unnoticed.
#ifndef CANOPY_INTEROP_H
#define CANOPY_INTEROP_H

#ifdef __cplusplus
#include <cmath>
#include <cstdint>
#include <glm/glm.hpp>
// Shared inline functions use GLSL built-ins; on the C++ side they resolve to std:: and glm::.
#define CANOPY_NAMESPACE_BEGIN                                                          \
  namespace canopy::gpu {                                                              \
  using glm::vec2; using glm::vec3; using glm::vec4; using glm::ivec2; using glm::ivec4; \
  using glm::uvec2; using glm::uvec4; using glm::mat4; using uint = uint32_t;            \
  using std::sin; using std::cos; using std::abs; using std::floor; using std::sqrt; using std::pow; \
  using glm::fract; using glm::mix; using glm::clamp; using glm::smoothstep; using glm::min; using glm::max; \
  using glm::normalize; using glm::dot; using std::exp; using std::acos; using std::asin;
#define CANOPY_NAMESPACE_END }
#define CANOPY_SIZE_CHECK(T, bytes) \
  static_assert(sizeof(T) == (bytes), #T ": size differs from its GLSL scalar-layout size");
#define CANOPY_INLINE inline
// A shared function's in-out parameter: a reference in C++, `inout` in GLSL.
#define CANOPY_INOUT(T) T&
#else
#extension GL_EXT_scalar_block_layout : require
#define CANOPY_NAMESPACE_BEGIN
#define CANOPY_NAMESPACE_END
#define CANOPY_SIZE_CHECK(T, bytes)
#define CANOPY_INLINE
#define CANOPY_INOUT(T) inout T
#endif

#endif
