#version 460
#extension GL_GOOGLE_include_directive : require
// Impostors, single pass, with some layers at half resolution (layers_half.vert's counterpart).
#extension GL_ARB_shader_viewport_layer_array : require
out gl_PerVertex {
  vec4 gl_Position;
  float gl_ClipDistance[2];
};
#define CANOPY_VERTEX
#include "layers_impostor_common.glsl"
#define LAYER_HALF_CLIP_FIRST 0
#include "layers_half.glsl"

void main() {
  uint layer = impostorVertex();
  gl_Layer = int(layer);
  layerHalfResolution(layerTexelScale(f.halfResolution, layer) < 1.0);
}
