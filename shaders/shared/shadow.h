// The vegetation's shadow (issue 54; docs/design.md "Shadows"): the foliage mesh drawn into the
// host's depth image from the light, each leaf displaced by the displacement its own layer has on
// screen, taken back into the world at the leaf's depth in the slice camera's image plane, so the
// caster sways as the leaves the camera shows. Read by shaders/shadow.vert.
#ifndef CANOPY_SHARED_SHADOW_H
#define CANOPY_SHARED_SHADOW_H
#include "interop.h"

CANOPY_NAMESPACE_BEGIN

struct ShadowFrame {
  mat4 lightViewProj;  // world -> the light's Vulkan clip space (the host's: orthographic or perspective)
  uint displace;       // 1: leaves displaced by their layer's warp; 0: the still mesh
  uint displaceRigid;  // 1: rigid parts too, by their share (RigidMotion::FollowFoliage; shared/rigid.h)
  uint pad1;
  uint pad2;
};
CANOPY_SIZE_CHECK(ShadowFrame, 80)

CANOPY_NAMESPACE_END
#endif
