// A struct using every member type the interop rules allow, read back field by field by
// shaders/interop_probe.comp to prove C++ and GLSL agree on the layout.
#ifndef CANOPY_INTEROP_PROBE_H
#define CANOPY_INTEROP_PROBE_H
#include "shared/interop.h"

CANOPY_NAMESPACE_BEGIN
struct InteropProbe {
  float a;
  vec3 b;
  uint c;
  vec2 d;
  ivec4 e;
  mat4 m;
};
CANOPY_SIZE_CHECK(InteropProbe, 108)
CANOPY_NAMESPACE_END
#endif
