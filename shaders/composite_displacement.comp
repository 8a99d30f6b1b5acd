#version 460
#extension GL_GOOGLE_include_directive : require
// Compute path: the warp grid of every layer as one image texel per corner, (d_i, previous d_i), so
// the composite kernel reads both with one hardware-filtered fetch per layer sample instead of
// eight buffer loads (docs/performance.md).
#include "shared/composite.h"

layout(local_size_x = COMPOSITE_DISP_GROUP) in;
layout(binding = 0, scalar) readonly buffer DispBuf { vec2 disp[]; };
layout(binding = 1, scalar) readonly buffer PrevBuf { vec2 prevDisp[]; };
layout(binding = 2, rgba32f) writeonly uniform image2DArray dispImage;
layout(push_constant, scalar) uniform Push { CompositePush pc; };

void main() {
  uint corners = pc.gridX * pc.gridY;
  uint id = gl_GlobalInvocationID.x, layer = gl_GlobalInvocationID.y;
  if (id >= corners || layer >= pc.layerCount) return;
  uint at = layer * corners + id;
  vec2 prev = (pc.flags & COMPOSITE_MOTION_VALID) != 0u ? prevDisp[at] : disp[at];
  imageStore(dispImage, ivec3(id % pc.gridX, id / pc.gridX, layer), vec4(disp[at], prev));
}
