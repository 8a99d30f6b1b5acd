#version 460
#extension GL_GOOGLE_include_directive : require
// Copies the host's depth into a buffer the composite can read while the host's depth image is
// its depth attachment (reading an attachment being written would be a feedback loop).
#include "shared/composite.h"

layout(local_size_x = COMPOSITE_SCENE_GROUP) in;
layout(binding = 0) uniform sampler2D hostDepth;
layout(binding = 1, scalar) writeonly buffer SceneBuf { float sceneDepth[]; };
layout(push_constant, scalar) uniform Push { CompositePush pc; };

void main() {
  uint w = uint(pc.width), h = uint(pc.height);
  uint id = gl_GlobalInvocationID.x;
  if (id >= w * h) return;
  sceneDepth[id] = texelFetch(hostDepth, ivec2(id % w, id / w), 0).r;
}
