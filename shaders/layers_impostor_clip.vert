#version 460
#extension GL_GOOGLE_include_directive : require
// Impostors, one draw per layer (devices without shaderOutputLayer): a box outside the target
// layer is clipped whole, decided by the same layerOfDepth() as the single pass.
out gl_PerVertex {
  vec4 gl_Position;
  float gl_ClipDistance[3];
};
#define CANOPY_VERTEX
#include "layers_impostor_common.glsl"
#define LAYER_HALF_CLIP_FIRST 1
#include "layers_half.glsl"

void main() {
  uint layer = impostorVertex();
  gl_ClipDistance[0] = (pc.passKind != LAYER_PASS_ONE_LAYER || layer == pc.targetLayer) ? 1.0 : -1.0;
  layerHalfResolution(pc.passKind == LAYER_PASS_ONE_LAYER && layerTexelScale(f.halfResolution, pc.targetLayer) < 1.0);
}
